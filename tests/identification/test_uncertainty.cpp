// Standard errors, intervals and their coverage (lm).
#include "identification/identifier.h"
#include "estimation/statistics.h"
#include "test_support.h"

#include <random>

using namespace armsim;
using namespace armsim::test;

namespace {

constexpr double kQuantileTol = 1e-6;   // against tabulated Student-t / normal quantiles (6 digits)
constexpr double kSeTol = 0.01;         // relative: Ceres covariance vs the test's own (J^T J)^-1
constexpr double kJacobianStep = 1e-7;  // relative step of the test's own central differences

}  // namespace

TEST(Statistics, StudentTQuantilesMatchTables) {
    // Abramowitz & Stegun Table 26.10 / any t table, two-sided 95 %.
    EXPECT_NEAR(calcStudentTQuantile(0.975, 1), 12.706205, kQuantileTol * 12.7);
    EXPECT_NEAR(calcStudentTQuantile(0.975, 3), 3.182446, kQuantileTol * 3.2);
    EXPECT_NEAR(calcStudentTQuantile(0.975, 10), 2.228139, kQuantileTol * 2.2);
    EXPECT_NEAR(calcStudentTQuantile(0.025, 10), -2.228139, kQuantileTol * 2.2);
    EXPECT_NEAR(calcNormalQuantile(0.975), 1.959964, kQuantileTol * 2);
    EXPECT_NEAR(calcStudentTCdf(0.0, 4), 0.5, 1e-15);
}

// Chi-square tail probabilities against table values (Abramowitz & Stegun 26.4) and the closed forms
// for 2 degrees of freedom, P = exp(-x/2), and for 1, P = erfc(sqrt(x/2)).
TEST(Statistics, ChiSquareSurvivalMatchesTablesAndClosedForms) {
    constexpr double kTableTol = 2e-5;  // the table's critical values have 3-4 decimals
    EXPECT_NEAR(calcChiSquareSurvival(3.841459, 1), 0.05, kTableTol);
    EXPECT_NEAR(calcChiSquareSurvival(18.307038, 10), 0.05, kTableTol);
    EXPECT_NEAR(calcChiSquareSurvival(2.558212, 10), 0.99, kTableTol);
    EXPECT_NEAR(calcChiSquareSurvival(124.342, 100), 0.05, kTableTol);
    for (double x : {0.1, 1.0, 5.0, 30.0}) {
        EXPECT_NEAR(calcChiSquareSurvival(x, 2), std::exp(-x / 2), 1e-13 * std::max(1.0, std::exp(-x / 2))) << x;
        EXPECT_NEAR(calcChiSquareSurvival(x, 1), std::erfc(std::sqrt(x / 2)), 1e-12) << x;
    }
    EXPECT_EQ(calcChiSquareSurvival(0, 3), 1.0);
}

TEST(Uncertainty, AsManyPointsAsUnknownsNeedAGivenNoiseLevel) {
    const ObservationSet data = makeSyntheticData(makeTruth(), {0.375, 0.40});
    const IdentificationReport r = identify(makeProblem(data), SteadyForceModel());
    ASSERT_TRUE(r.isConverged()) << r.message;
    EXPECT_FALSE(r.hasUncertainty);
    EXPECT_NE(r.uncertaintyNote.find("n = p"), std::string::npos) << r.uncertaintyNote;
    EXPECT_TRUE(std::isnan(r.parameters[0].standardError));

    // With a given force sd: se_j = sd sqrt((J^T J)^-1_jj); J from the test's own central differences.
    constexpr double sd = 5.0;   // N
    IdentificationOptions o;
    o.forceSd = sd;
    const IdentificationReport s = identify(makeProblem(data), SteadyForceModel(), o);
    ASSERT_TRUE(s.hasUncertainty) << s.uncertaintyNote;
    MuscleParameters p = s.muscle;
    double J[2][2];
    for (int j = 0; j < 2; ++j) {
        const double x = j == 0 ? p.mass : p.optimalTendonLength, h = kJacobianStep * x;
        MuscleParameters plus = p, minus = p;
        (j == 0 ? plus.mass : plus.optimalTendonLength) = x + h;
        (j == 0 ? minus.mass : minus.optimalTendonLength) = x - h;
        const auto yp = SteadyForceModel().calcForces(plus, data.points);
        const auto ym = SteadyForceModel().calcForces(minus, data.points);
        for (int k = 0; k < 2; ++k) J[k][j] = (yp[k] - ym[k]) / (2 * h);
    }
    // (J^T J)^-1 = J^-1 J^-T for square J.
    const double det = J[0][0] * J[1][1] - J[0][1] * J[1][0];
    const double inv[2][2] = {{J[1][1] / det, -J[0][1] / det}, {-J[1][0] / det, J[0][0] / det}};
    for (int j = 0; j < 2; ++j) {
        const double se = sd * std::sqrt(inv[j][0] * inv[j][0] + inv[j][1] * inv[j][1]);
        EXPECT_NEAR(s.parameters[j].standardError / se, 1.0, kSeTol) << j;
        EXPECT_NEAR(s.parameters[j].ciUpper - s.parameters[j].value, calcNormalQuantile(0.975) * se, kSeTol * 2 * se);
    }
    EXPECT_NEAR(s.correlation[0][1], s.correlation[1][0], 1e-12);
    EXPECT_LE(std::abs(s.correlation[0][1]), 1.0);
}

namespace {

struct Coverage {
    int mass = 0, tendon = 0, fits = 0;
};

/// Fits kRepetitions noisy copies of the five-angle data; counts intervals that hold the truth.
/// noise(force, rng) returns a noisy force.
template <class Noise>
Coverage measureCoverage(int repetitions, const IdentificationOptions& options, Noise noise) {
    const ObservationSet clean = makeSyntheticData(makeTruth(), thesisAnglePaths());
    std::mt19937_64 rng(20090601);
    Coverage c;
    for (int rep = 0; rep < repetitions; ++rep) {
        ObservationSet noisy = clean;
        for (Observation& o : noisy.points) o.force = noise(o.force, rng);
        const IdentificationReport r = identify(makeProblem(noisy), SteadyForceModel(), options);
        if (!r.isConverged() || !r.hasUncertainty) continue;
        ++c.fits;
        EXPECT_EQ(r.degreesOfFreedom, 3);
        c.mass += r.parameters[0].ciLower <= kTrueMass && kTrueMass <= r.parameters[0].ciUpper;
        c.tendon += r.parameters[1].ciLower <= kTrueTendonLength && kTrueTendonLength <= r.parameters[1].ciUpper;
    }
    return c;
}

// 200 repetitions; the coverage count of a 95 % interval is Binomial(200, 0.95): mean 190, sd
// sqrt(200 * 0.95 * 0.05) = 3.08. We accept 190 +/- 3 sd, i.e. [181, 199].
constexpr int kRepetitions = 200;
constexpr int kCoverLow = 181, kCoverHigh = 199;
constexpr double kNoise = 0.02;   // 2 %

void expectCoverage(const Coverage& c, const std::string& what) {
    EXPECT_EQ(c.fits, kRepetitions) << what;
    EXPECT_GE(c.mass, kCoverLow) << what << " mass coverage " << c.mass << "/" << kRepetitions;
    EXPECT_LE(c.mass, kCoverHigh) << what << " mass coverage " << c.mass << "/" << kRepetitions;
    EXPECT_GE(c.tendon, kCoverLow) << what << " L0T coverage " << c.tendon << "/" << kRepetitions;
    EXPECT_LE(c.tendon, kCoverHigh) << what << " L0T coverage " << c.tendon << "/" << kRepetitions;
    std::printf("%s: 95 %% intervals cover the truth in %d (mass) and %d (L0T) of %d repetitions\n", what.c_str(),
                c.mass, c.tendon, kRepetitions);
}

}  // namespace

TEST(Uncertainty, IntervalsCoverTheTruthAboutNinetyFivePercentOfTheTimeWithRelativeNoise) {
    // 2 % of each force (the five forces span 5..592 N), fitted with the relative noise model.
    IdentificationOptions o;
    o.noise = NoiseModel::Relative;
    std::normal_distribution<double> normal(0.0, 1.0);
    expectCoverage(measureCoverage(kRepetitions, o, [&](double f, std::mt19937_64& rng) {
                       return f * (1.0 + kNoise * normal(rng));
                   }),
                   "relative noise");
}

TEST(Uncertainty, IntervalsCoverTheTruthAboutNinetyFivePercentOfTheTimeWithAbsoluteNoise) {
    // sd = 2 % of the largest force (592 N): 11.8 N on every force, fitted with the absolute model.
    constexpr double kSd = kNoise * 592.37;
    std::normal_distribution<double> normal(0.0, 1.0);
    expectCoverage(measureCoverage(kRepetitions, IdentificationOptions(), [&](double f, std::mt19937_64& rng) {
                       return std::max(0.0, f + kSd * normal(rng));
                   }),
                   "absolute noise");
}

TEST(Uncertainty, UnweightedFitOfProportionalNoiseMisstatesTheIntervals) {
    // The reason for the relative model: with 2 % of each force and equal weights, the pooled s^2
    // misstates the per-parameter errors, and the mass interval undercovers.
    std::normal_distribution<double> normal(0.0, 1.0);
    const Coverage c = measureCoverage(kRepetitions, IdentificationOptions(), [&](double f, std::mt19937_64& rng) {
        return f * (1.0 + kNoise * normal(rng));
    });
    EXPECT_LT(c.mass, kCoverLow);
}

namespace {
/// A forward model in which the tendon length has no effect: F = 1800 N/kg * M.
class MassOnlyModel : public ForceModel {
public:
    std::vector<double> calcForces(const MuscleParameters& p, const std::vector<Observation>& obs) const override {
        return std::vector<double>(obs.size(), 1800.0 * p.mass);
    }
    std::string getName() const override { return "mass-only"; }
};
}  // namespace

TEST(Uncertainty, AnUnidentifiableUnknownGetsNoIntervals) {
    ObservationSet data = makeSyntheticData(makeTruth(), thesisAnglePaths());
    for (Observation& o : data.points) o.force = 1800.0 * kTrueMass;
    const IdentificationReport r = identify(makeProblem(data), MassOnlyModel());
    EXPECT_NEAR(r.parameters[0].value, kTrueMass, 1e-9);
    EXPECT_FALSE(r.hasUncertainty);
    EXPECT_NE(r.uncertaintyNote.find("rank deficient"), std::string::npos) << r.uncertaintyNote;
}

// Validation of the thesis identifiers against a known truth: a tiny run recovers the thesis truth and
// writes one row per method and noise level.
#include "basics/errors.h"
#include "muscles/muscle_file.h"
#include "identification/torque_identification.h"
#include "studies/study.h"
#include "studies/torque_validation.h"
#include "studies/validation.h"
#include "tests/identification/test_support.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <random>

using namespace armsim;
using namespace armsim::test;

namespace {

constexpr double kRecoveryTol = 1e-3;  // relative: "within 0.1 %" of the truth

}  // namespace

TEST(Validation, TinyRunRecoversTheThesisTruthAndWritesOneRowPerMethodAndNoiseLevel) {
    const ArmSetup setup = ArmSetup::loadDefault();
    const MuscleParameters base = setup.calcBicepsParameters();
    ValidationSettings s;
    s.seeds = 0;
    s.noiseLevels = {0.0, 0.02};
    s.methods = {Method::LevenbergMarquardt};
    const std::vector<ValidationRow> rows = runValidation(setup.arm, base, s);
    ASSERT_EQ(rows.size(), 2u);
    EXPECT_EQ(rows[0].truth, "thesis");
    EXPECT_LT(std::abs(rows[0].massError), kRecoveryTol) << rows[0].mass;
    EXPECT_LT(std::abs(rows[0].tendonLengthError), kRecoveryTol) << rows[0].tendonLength;
    EXPECT_GT(std::abs(rows[1].massError), std::abs(rows[0].massError));  // noise moves the estimate
    EXPECT_NE(rows[1].massCovered, -1);                                    // lm with n > p has intervals
    const std::string csv = formatValidationCsv(rows);
    EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 3);
    EXPECT_NE(formatValidationTable(rows).find("lm"), std::string::npos);
    s.noiseLevels = {0.6};
    EXPECT_THROW(runValidation(setup.arm, base, s), InputError);
}

// The README's `validate --seeds 3` (issue 32): the third random truth of seed 1 has a tendon so long
// that it pulls nothing at the most flexed angle, which relative noise cannot measure; it is drawn again
// (the first two keep their values), and every truth is identified at 0 % noise within 1 % by the
// steady model (0.7 % low on the faithful model's data: the tare hides the passive force, README).
TEST(Validation, ARandomTruthThatPullsNothingIsDrawnAgain) {
    constexpr double kSteadyTol = 0.01;
    const ArmSetup setup = ArmSetup::loadDefault();
    const MuscleParameters base = setup.calcBicepsParameters();
    ValidationSettings s;
    s.seeds = 3;
    s.noiseLevels = {0.0};
    s.methods = {Method::LevenbergMarquardt};
    s.model = ValidationModel::Steady;
    const std::vector<ValidationRow> rows = runValidation(setup.arm, base, s);
    ASSERT_EQ(rows.size(), 4u);
    s.seeds = 2;
    const std::vector<ValidationRow> two = runValidation(setup.arm, base, s);
    for (std::size_t k = 0; k < rows.size(); ++k) {
        EXPECT_LT(std::abs(rows[k].massError), kSteadyTol) << rows[k].truth;
        EXPECT_LT(std::abs(rows[k].tendonLengthError), kSteadyTol) << rows[k].truth;
        if (k < two.size()) { EXPECT_EQ(rows[k].trueMass, two[k].trueMass) << rows[k].truth; }  // kept
    }
}

// Out of family (issue 31): subjects come from the truth population, the identifiers use the prior.
// With the prior equal to the truth the run is the in-family run; a stronger truth makes the same people
// 1.26x heavier while the identifiers' answers are computed against the default prior.
TEST(Validation, OutOfFamilyDrawsFromTheTruthAndIdentifiesWithThePrior) {
    const Population prior = loadDefaultPopulation();
    Population truth = prior;
    truth.strengthMeanScale = 1.26;
    ElbowValidationSettings v;
    v.subjects = 2;
    v.noiseLevels = {0.02};
    v.activationSd = 0;
    v.jobs = 2;
    const std::vector<ElbowValidationRow> inFamily = runElbowValidation(prior, v);
    const std::vector<ElbowValidationRow> same = runElbowValidation(prior, prior, v);
    const std::vector<ElbowValidationRow> stronger = runElbowValidation(truth, prior, v);
    ASSERT_EQ(inFamily.size(), same.size());
    ASSERT_EQ(inFamily.size(), stronger.size());
    for (std::size_t k = 0; k < inFamily.size(); ++k) {
        EXPECT_EQ(same[k].estimate.mass, inFamily[k].estimate.mass);   // bitwise: the same computation
        EXPECT_NEAR(stronger[k].trueMass, 1.26 * inFamily[k].trueMass, 1e-12);
        const VirtualSubject person = drawSubject(truth, v.seed, stronger[k].subject);
        EXPECT_EQ(stronger[k].trueMass, person.setup.muscles[person.setup.primary].params.mass);
    }
    Population other = prior;
    other.base.primary = other.base.findMuscle("BRA");
    try {
        runElbowValidation(other, prior, v);
        FAIL() << "a truth whose primary muscle is not the prior's was accepted";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("'BRA'"), std::string::npos) << e.what();
    }
}

// The summary's standard errors against closed forms: errors +x and -x alternate, so the bias is 0 with
// SE = sample sd / sqrt(n); every squared error is x^2, so the RMSE is x with SE 0; coverage 3 of 4 has
// SE sqrt(0.75 0.25 / 4).
TEST(Validation, SummaryStandardErrorsMatchClosedForms) {
    constexpr double kExact = 1e-12;
    const double x = 0.1;
    std::vector<ElbowValidationRow> rows;
    for (int k = 0; k < 4; ++k) {
        ElbowValidationRow r;
        r.subject = k;
        r.method = "m";
        r.massError = k % 2 ? -x : x;
        r.tendonError = 0.002 * k;
        r.massCovered = k < 3;
        r.estimate.mass = 1, r.estimate.massLower = 0.9, r.estimate.massUpper = 1.1;
        rows.push_back(r);
    }
    const std::vector<ElbowValidationSummary> s = summarizeElbowValidation(rows);
    ASSERT_EQ(s.size(), 1u);
    EXPECT_NEAR(s[0].massBias, 0, kExact);
    EXPECT_NEAR(s[0].massBiasSe, std::sqrt(4 * x * x / 3 / 4), kExact);   // sample sd / sqrt(n)
    EXPECT_NEAR(s[0].massRmse, x, kExact);
    EXPECT_NEAR(s[0].massRmseSe, 0, kExact);
    EXPECT_NEAR(s[0].massCoverage, 0.75, kExact);
    EXPECT_NEAR(s[0].massCoverageSe, std::sqrt(0.75 * 0.25 / 4), kExact);
    // tendon errors 0, 2, 4, 6 mm: mean 3 mm, sample sd sqrt(20/3) mm
    EXPECT_NEAR(s[0].tendonBiasSe, 0.001 * std::sqrt(20.0 / 3 / 4), kExact);
    const std::string csv = formatElbowValidationSummaryCsv(s);
    EXPECT_NE(csv.find("mass_rmse_se_pct"), std::string::npos);
}

// The summary is accumulated row by row (a study of millions of subjects keeps no rows); its standard
// errors (Welford updates) equal the two-pass sums over stored errors, on 1000 seeded random rows.
TEST(Validation, SummaryAccumulatedRowByRowEqualsTheTwoPassFormulas) {
    constexpr double kTwoPassTol = 1e-10;  // relative: rounding of one pass against two
    std::mt19937_64 rng(7);
    std::normal_distribution<double> mass(0.05, 0.1), tendon(0.003, 0.004);
    std::vector<ElbowValidationRow> rows;
    std::vector<double> m, t;
    for (int k = 0; k < 1000; ++k) {
        ElbowValidationRow r;
        r.subject = k;
        r.method = "m";
        r.massError = mass(rng), r.tendonError = tendon(rng);
        m.push_back(r.massError), t.push_back(r.tendonError);
        rows.push_back(r);
    }
    const std::vector<ElbowValidationSummary> s = summarizeElbowValidation(rows);
    ASSERT_EQ(s.size(), 1u);
    auto twoPass = [](const std::vector<double>& e, double& biasSe, double& rmseSe) {
        const double n = double(e.size());
        double mean = 0, ms = 0;
        for (double x : e) mean += x / n, ms += x * x / n;
        double v = 0, v2 = 0;
        for (double x : e) v += (x - mean) * (x - mean), v2 += (x * x - ms) * (x * x - ms);
        biasSe = std::sqrt(v / (n - 1) / n);
        rmseSe = std::sqrt(v2 / (n - 1) / n) / (2 * std::sqrt(ms));
    };
    double mb = 0, mr = 0, tb = 0, tr = 0;
    twoPass(m, mb, mr);
    twoPass(t, tb, tr);
    EXPECT_NEAR(s[0].massBiasSe, mb, kTwoPassTol * mb);
    EXPECT_NEAR(s[0].massRmseSe, mr, kTwoPassTol * mr);
    EXPECT_NEAR(s[0].tendonBiasSe, tb, kTwoPassTol * tb);
    EXPECT_NEAR(s[0].tendonRmseSe, tr, kTwoPassTol * tr);
}

// Issue 31: out of family (specific tension 20 % higher than the prior's), the recommended protocol's
// channels (ultrasound volume and fascicle, EMG, anthropometry) cut the biceps mass RMSE of the
// torque-only synergist fit on the same subjects and data, and the channels fit estimates F0 (the
// torque-only fits do too, through their free specific tension). Fails if the channels are ignored.
TEST(Validation, ChannelsOfTheRecommendedProtocolBeatTorqueAloneOutOfFamily) {
    constexpr double kRatioBound = 0.7;   // measured 0.42 at 20 subjects (README table)
    const Population prior = loadDefaultPopulation();
    const Population truth = loadPopulation(findAsset("subjects/mismatch/specific_tension.yaml"));
    ElbowValidationSettings v;
    v.subjects = 10;
    v.noiseLevels = {0.02};
    v.activationSd = 0.02;
    v.jobs = 2;
    v.protocol = readTorqueProtocol(findAsset("protocols/recommended.yaml"));
    const std::vector<ElbowValidationSummary> s = summarizeElbowValidation(runElbowValidation(truth, prior, v));
    auto find = [&](const std::string& method) {
        auto it = std::find_if(s.begin(), s.end(), [&](const ElbowValidationSummary& x) { return x.method == method; });
        EXPECT_NE(it, s.end()) << method;
        return *it;
    };
    const ElbowValidationSummary channels = find("channels"), torque = find("synergist");
    EXPECT_EQ(channels.converged, v.subjects);
    EXPECT_LT(channels.massRmse, kRatioBound * torque.massRmse)
        << "channels " << channels.massRmse << " vs torque only " << torque.massRmse;
    EXPECT_TRUE(std::isfinite(channels.maxForceRmse));
}

// The population draws every muscle's lengths, slow fraction and mass on its own; the identifier shares
// or holds them, and its intervals add what that costs (consider parameters). In family, with the
// two-axis protocol, the F0 and L0T errors over their 95 % half-widths / 1.96 then spread with sd near 1:
// measured on these 12 subjects 0.92 (F0) and 0.87 (L0T); the Laplace intervals alone gave 1.41 and 0.96
// (on 100 subjects of the recommended protocol: 0.96 and 0.98 with, F0 coverage 0.97 against 0.93).
TEST(Validation, ChannelIntervalsCoverWhatThePopulationVariesAndTheFitShares) {
    constexpr double kMaxZSd = 1.15, kMinZSd = 0.6;  // sd of 12 z-scores: about +/- 0.2 by chance
    const Population prior = loadDefaultPopulation();
    ElbowValidationSettings v;
    v.subjects = 12;
    v.noiseLevels = {0.02};
    v.activationSd = 0;  // no synergist-va: not what this test checks
    v.jobs = 2;
    v.protocol = readTorqueProtocol(findAsset("protocols/two_axis.yaml"));
    std::vector<double> zf, zt;
    for (const ElbowValidationRow& r : runElbowValidation(prior, prior, v)) {
        if (r.method != "channels") continue;
        const MuscleEstimate& e = r.estimate;
        ASSERT_TRUE(std::isfinite(e.maxForceLower)) << "subject " << r.subject;
        zf.push_back(std::log(e.maxForce / r.trueMaxForce) / (std::log(e.maxForceUpper / e.maxForceLower) / (2 * 1.96)));
        zt.push_back((e.tendonLength - r.trueTendonLength) / ((e.tendonUpper - e.tendonLower) / (2 * 1.96)));
    }
    ASSERT_EQ(zf.size(), 12u);
    auto sd = [](const std::vector<double>& z) {
        double m = 0, v = 0;
        for (double x : z) m += x / double(z.size());
        for (double x : z) v += (x - m) * (x - m) / double(z.size());
        return std::sqrt(v);
    };
    EXPECT_LE(sd(zf), kMaxZSd) << "F0 intervals too narrow";
    EXPECT_GE(sd(zf), kMinZSd) << "F0 intervals too wide";
    EXPECT_LE(sd(zt), kMaxZSd) << "L0T intervals too narrow";
    EXPECT_GE(sd(zt), kMinZSd) << "L0T intervals too wide";
}

// The prior's check (ChannelFit "prior", SynergistModel::calcPriorCheck): for people of the prior's own
// population its p-values are uniform (mean 1/2; over 100 subjects of the recommended protocol, 2 % below
// 0.05 and quartiles 0.27 / 0.54 / 0.79), and it flags people whose muscles follow other equations (the
// Thelen 2003 truth: 100 of 100 flagged; their L0T coverage is 0.32, README).
TEST(Validation, PriorCheckIsUniformInFamilyAndFlagsPeopleOfAnotherMuscleModel) {
    constexpr int kInFamily = 30;
    constexpr double kMeanTol = 0.16;       // 3 sd of the mean of 30 uniforms (0.053)
    constexpr int kMaxFlaggedInFamily = 5;  // P(>= 6 of 30 | 5 %) < 0.003
    constexpr int kHill = 8;
    constexpr int kMinFlaggedHill = 6;
    const Population prior = loadDefaultPopulation();
    ElbowValidationSettings v;
    v.subjects = kInFamily;
    v.noiseLevels = {0.02};
    v.activationSd = 0;
    v.jobs = 2;
    v.protocol = readTorqueProtocol(findAsset("protocols/recommended.yaml"));
    auto checks = [](const std::vector<ElbowValidationRow>& rows) {
        std::vector<double> p;
        for (const ElbowValidationRow& r : rows)
            if (r.method == "channels") p.push_back(r.priorCheckP);
        return p;
    };
    const std::vector<double> p = checks(runElbowValidation(prior, prior, v));
    ASSERT_EQ(int(p.size()), kInFamily);
    double mean = 0;
    int flagged = 0;
    for (double x : p) {
        ASSERT_TRUE(std::isfinite(x));
        mean += x / kInFamily;
        flagged += x < 0.05;
    }
    EXPECT_NEAR(mean, 0.5, kMeanTol);
    EXPECT_LE(flagged, kMaxFlaggedInFamily);

    v.subjects = kHill;
    const std::vector<double> h = checks(runElbowValidation(loadPopulation(findAsset("subjects/mismatch/hill_muscles.yaml")), prior, v));
    ASSERT_EQ(int(h.size()), kHill);
    EXPECT_GE(std::count_if(h.begin(), h.end(), [](double x) { return x < 0.05; }), kMinFlaggedHill);
}

// One subject alone (the main job's out-of-family person) gives that subject's rows of the whole
// validation, bit for bit, and its clean data with noise added are what the rows were fitted to.
TEST(Validation, OneSubjectAloneEqualsItsRowsOfTheWholeValidation) {
    const Population prior = loadDefaultPopulation();
    ElbowValidationSettings v;
    v.subjects = 2;
    v.noiseLevels = {0.02};
    v.activationSd = 0;
    v.protocol.conditions = TorqueProtocol::makeFlexionMvcs({30, 90, 135}, 2);
    const std::vector<ElbowValidationRow> all = runElbowValidation(prior, prior, v);
    const ElbowValidationSubject one = runElbowValidationSubject(prior, prior, v, 1);
    std::vector<ElbowValidationRow> second;
    for (const ElbowValidationRow& r : all)
        if (r.subject == 1) second.push_back(r);
    ASSERT_EQ(one.rows.size(), second.size());
    for (std::size_t k = 0; k < second.size(); ++k) {
        EXPECT_EQ(one.rows[k].method, second[k].method);
        EXPECT_EQ(one.rows[k].estimate.mass, second[k].estimate.mass);
        EXPECT_EQ(one.rows[k].trueMass, second[k].trueMass);
    }
    EXPECT_EQ(one.torque.size(), 6u);
    EXPECT_TRUE(one.channels.empty());
    EXPECT_EQ(one.subject.index, 1);
}

namespace {

/// A field's name must end in its unit as the house spells units in column names.
template <class T>
std::vector<std::string> findUnitlessNames(const FieldTable<T>& table) {
    static const std::map<std::string, std::string> suffix = {
        {"kg", "_kg"}, {"m", "_m"}, {"mm", "_mm"}, {"N", "_N"}, {"N m", "_Nm"}, {"s", "_s"}, {"%", "_pct"},
        {"N/m^2", "_N_per_m2"}};
    std::vector<std::string> bad;
    for (const Field<T>& f : table.getFields()) {
        if (f.unit.empty() || f.unit == "1") continue;
        const auto it = suffix.find(f.unit);
        const bool ok = it != suffix.end() && f.name.size() > it->second.size() &&
                        f.name.compare(f.name.size() - it->second.size(), it->second.size(), it->second) == 0;
        if (!ok) bad.push_back(f.name + " [" + f.unit + "]");
    }
    return bad;
}

}  // namespace

// Every result table's columns carry their units in their names (the house's naming rule), and each
// table's header is what its CSV writer writes.
TEST(ResultFields, EveryColumnWithAUnitEndsInIt) {
    EXPECT_EQ(findUnitlessNames(getStudyResultFields()), std::vector<std::string>{});
    EXPECT_EQ(findUnitlessNames(getValidationFields()), std::vector<std::string>{});
    EXPECT_EQ(findUnitlessNames(getElbowValidationFields()), std::vector<std::string>{});
    EXPECT_EQ(findUnitlessNames(getElbowValidationSummaryFields()), std::vector<std::string>{});
    EXPECT_EQ(findUnitlessNames(getTorqueEstimateFields()), std::vector<std::string>{});
    EXPECT_EQ(findUnitlessNames(getChannelFitFields()), std::vector<std::string>{});
    EXPECT_EQ(formatElbowValidationCsv({}), getElbowValidationFields().getHeader() + "\n");
    EXPECT_EQ(getStudyResultsHeader(), getStudyResultFields().getHeader());
}

// Virtual-subject populations: reproducible draws, the stated distributions, valid people, and
// population files read strictly.
#include "basics/errors.h"
#include "experiments/population.h"
#include "model/geometry.h"
#include "model/muscle_arm.h"
#include "model/mvc_curve.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>

using namespace armsim;

namespace {

const Population& population() {
    static const Population p = loadDefaultPopulation();
    return p;
}

std::string writeTemp(const std::string& name, const std::string& text) {
    const auto path = std::filesystem::temp_directory_path() / name;
    std::ofstream(path) << text;
    return path.string();
}

std::string errorOf(const std::string& text) {
    try {
        loadPopulation(writeTemp("armsim_population_test.yaml", text));
    } catch (const InputError& e) {
        return e.what();
    }
    return "";
}

}  // namespace

TEST(Population, ADrawDependsOnlyOnSeedAndIndex) {
    const VirtualSubject a = drawSubject(population(), 7, 3);
    for (int i = 0; i < 5; ++i) drawSubject(population(), 7, i);  // other draws in between change nothing
    const VirtualSubject b = drawSubject(population(), 7, 3);
    EXPECT_EQ(a.massScale, b.massScale);
    EXPECT_EQ(a.tendonLengthScale, b.tendonLengthScale);
    EXPECT_EQ(a.setup.effort.voluntaryActivation, b.setup.effort.voluntaryActivation);
    EXPECT_NE(a.massScale, drawSubject(population(), 7, 4).massScale);
    EXPECT_NE(a.massScale, drawSubject(population(), 8, 3).massScale);
    // The draw is applied to the model: mass = base mass x scale.
    for (int m = 0; m < a.setup.getNumMuscles(); ++m)
        EXPECT_DOUBLE_EQ(a.setup.muscles[m].params.mass, population().base.muscles[m].params.mass * a.massScale[m]);
}

// Sample moments of 4000 people against the distributions the file states (tolerances: about four
// standard errors of each statistic).
TEST(Population, DrawsFollowTheStatedDistributions) {
    constexpr int kPeople = 4000;
    const Population& p = population();
    double s0 = 0, s00 = 0, s1 = 0, s11 = 0, s01 = 0, t = 0, tt = 0, va = 0, vaMin = 1, vaMax = 0;
    for (int i = 0; i < kPeople; ++i) {
        const VirtualSubject v = drawSubject(p, 11, i);
        const double a = std::log(v.massScale[0]), b = std::log(v.massScale[4]);
        s0 += a, s00 += a * a, s1 += b, s11 += b * b, s01 += a * b;
        t += v.tendonLengthScale[2], tt += v.tendonLengthScale[2] * v.tendonLengthScale[2];
        const double u = v.setup.effort.voluntaryActivation;
        va += u, vaMin = std::min(vaMin, u), vaMax = std::max(vaMax, u);
    }
    const double n = kPeople;
    const double m0 = s0 / n, m1 = s1 / n, var0 = s00 / n - m0 * m0, var1 = s11 / n - m1 * m1;
    const double total = p.strengthSubjectSd * p.strengthSubjectSd + p.strengthMuscleSd * p.strengthMuscleSd;
    EXPECT_NEAR(m0, 0.0, 4 * std::sqrt(total / n));
    EXPECT_NEAR(std::sqrt(var0), std::sqrt(total), 0.05 * std::sqrt(total));
    EXPECT_NEAR(std::sqrt(var1), std::sqrt(total), 0.05 * std::sqrt(total));
    // Two muscles of one person share the person's level: correlation subject_sd^2 / total.
    const double correlation = (s01 / n - m0 * m1) / std::sqrt(var0 * var1);
    EXPECT_NEAR(correlation, p.strengthSubjectSd * p.strengthSubjectSd / total, 0.04);
    const double tm = t / n, tsd = std::sqrt(tt / n - tm * tm);
    EXPECT_NEAR(tm, 1.0, 4 * p.tendonLengthSd / std::sqrt(n));
    EXPECT_NEAR(tsd, 0.9866 * p.tendonLengthSd, 0.05 * p.tendonLengthSd);  // N(0,1) cut at 3 sd: sd 0.9866
    EXPECT_GE(vaMin, p.voluntaryActivation.min);
    EXPECT_LE(vaMax, p.voluntaryActivation.max);
    EXPECT_NEAR(va / n, 0.5 * (p.voluntaryActivation.min + p.voluntaryActivation.max), 0.004);
}

// Every drawn person is a valid model with a steady maximal effort at every angle of the range: a
// flexion torque above 10 N m up to 90 deg and still flexing at 130 deg (the twin's flexors are short
// there: README, "The anatomical twin").
TEST(Population, DrawnPeopleAreValidModelsWithAnMvcAcrossTheRange) {
    const std::vector<double> flexion = {10, 45, 90, 130};
    for (int i = 0; i < 20; ++i) {
        const VirtualSubject v = drawSubject(population(), 1, i);
        for (int m = 0; m < v.setup.getNumMuscles(); ++m) EXPECT_NO_THROW(v.setup.calcMuscleParameters(m)) << i;
        const SteadyMvcCurve c = calcSteadyMvcCurve(v.setup, MuscleGroup::Flexor, v.setup.effort, flexion);
        for (std::size_t a = 0; a < flexion.size(); ++a)
            EXPECT_GT(c.totalTorque[a], flexion[a] <= 90 ? 10.0 : 1.0) << "subject " << i << " at " << flexion[a];
    }
}

TEST(Population, BadFilesNameTheFileLineAndField) {
    const std::string good = "name: x\nmodel: elbow\n";
    EXPECT_EQ(errorOf(good), "");
    std::string e = errorOf(good + "strength:\n  subject_sd: -0.1\n");
    EXPECT_NE(e.find("armsim_population_test.yaml:3"), std::string::npos) << e;
    EXPECT_NE(e.find("strength.subject_sd"), std::string::npos) << e;
    EXPECT_NE(e.find("-0.1"), std::string::npos) << e;
    e = errorOf(good + "voluntary_activation: {min: 0.9, max: 0.8}\n");
    EXPECT_NE(e.find("voluntary_activation.max"), std::string::npos) << e;
    e = errorOf(good + "transducer_nosie: 0.02\n");
    EXPECT_NE(e.find("transducer_nosie"), std::string::npos) << e;
    e = errorOf("name: x\nmodel: elbw\n");
    EXPECT_NE(e.find(":2"), std::string::npos) << e;
    EXPECT_NE(e.find("elbw"), std::string::npos) << e;
}

// Issue 31: means and person-level scales. Each mismatch field moves exactly what it names; the new
// person-level draws come from their own stream, so masses and lengths are those of the same people
// without them.
TEST(Population, MeanScalesAndPersonLevelScalesMoveWhatTheyName) {
    constexpr double kExact = 1e-12;   // relative: scaling is exact arithmetic
    Population base = population();
    base.specificTensionSd = base.geometryScaleSd = 0;  // the reference: no person-level scales
    Population p = base;
    p.strengthMeanScale = 1.26;
    p.slowFractionMeanShift = 0.1;
    p.specificTensionMeanScale = 1.2;
    p.specificTensionSd = 0.16;
    p.geometryMeanScale = 1.15;
    p.geometryScaleSd = 0.05;
    ArmGeometry g0(base.base);
    g0.setElbowAngle(elbowAngleFromFlexion(degToRad(90)));
    double sigmaLog = 0;
    constexpr int kPeople = 400;
    for (int i = 0; i < kPeople; ++i) {
        const VirtualSubject a = drawSubject(base, 3, i), b = drawSubject(p, 3, i);
        for (int m = 0; m < a.setup.getNumMuscles(); ++m) {
            EXPECT_NEAR(b.massScale[m], 1.26 * a.massScale[m], kExact * b.massScale[m]);
            EXPECT_EQ(b.tendonLengthScale[m], a.tendonLengthScale[m]);
            const MuscleParameters &pa = a.setup.muscles[m].params, &pb = b.setup.muscles[m].params;
            EXPECT_NEAR(pb.coefficients.sigma, b.specificTensionScale * pa.coefficients.sigma, kExact * pb.coefficients.sigma);
            EXPECT_NEAR(pb.optimalFascicleLength, b.geometryScale * pa.optimalFascicleLength, kExact);
            EXPECT_NEAR(pb.maxPathLength, b.geometryScale * pa.maxPathLength, kExact);
            EXPECT_NEAR(pb.slowFraction, std::clamp(pa.slowFraction + 0.1, 0.05, 0.95), kExact);
        }
        sigmaLog += std::log(b.specificTensionScale / 1.2);
        if (i < 3) {  // moment arms scale with the person's size (path geometry, virtual work)
            ArmGeometry g(b.setup);
            g.setElbowAngle(elbowAngleFromFlexion(degToRad(90)));
            for (int m = 0; m < g.getNumMuscles(); ++m)
                EXPECT_NEAR(g.calcMomentArm(m), b.geometryScale * g0.calcMomentArm(m), 1e-9) << m;
        }
    }
    // The sigma scale is ln-normal around its median 1.2 (mean of ln within 4 standard errors).
    EXPECT_NEAR(sigmaLog / kPeople, 0.0, 4 * 0.16 / std::sqrt(double(kPeople)));
    EXPECT_NE(errorOf("name: x\nmodel: elbow\ngeometry: {mean_scale: 3}\n").find("geometry.mean_scale"), std::string::npos);
}

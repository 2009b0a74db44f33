// Reading and validating force files; input errors of identify().
#include "basics/errors.h"
#include "identification/identifier.h"
#include "test_support.h"

#include <fstream>

using namespace armsim;
using namespace armsim::test;

namespace {

constexpr double kPathTol = 1e-12;   // m, exact arithmetic of the closed form

std::string writeCsv(const std::string& name, const std::string& text) {
    const std::string path = tempPath(name).string();
    std::ofstream(path) << text;
    return path;
}

/// Expects InputError whose message contains every fragment.
template <class F>
void expectInputError(F&& f, const std::vector<std::string>& fragments) {
    try {
        f();
        ADD_FAILURE() << "no InputError thrown";
    } catch (const InputError& e) {
        for (const std::string& s : fragments) EXPECT_NE(std::string(e.what()).find(s), std::string::npos) << e.what();
    }
}

}  // namespace

TEST(ThesisGeometry, PathLengthIsTheLawOfCosines) {
    // P(90) = sqrt(A^2 + B^2) = sqrt(0.1405); P(180) = A + B; P(0) = A - B.
    EXPECT_NEAR(calcThesisPathLength(kPi / 2), std::sqrt(0.37 * 0.37 + 0.06 * 0.06), kPathTol);
    EXPECT_NEAR(calcThesisPathLength(kPi), 0.43, kPathTol);
    EXPECT_NEAR(calcThesisPathLength(0), 0.31, kPathTol);
}

TEST(ReadObservations, ReadsPathAndAngleFilesInSI) {
    const std::string cm = writeCsv("cm.csv", "# comment\npath_cm,force_N,activation,trial\n41,600,1,1\n37.5,458,0.5,1\n");
    const ObservationSet a = readObservations(cm);
    ASSERT_EQ(a.points.size(), 2u);
    EXPECT_NEAR(a.points[0].pathLength, 0.41, kPathTol);
    EXPECT_EQ(a.points[0].force, 600);
    EXPECT_EQ(a.points[1].activation, 0.5);
    EXPECT_EQ(a.points[1].line, 4);

    const std::string deg = writeCsv("deg.csv", "angle_deg,force_N\n90,500\n150,450\n");
    const ObservationSet b = readObservations(deg);
    EXPECT_NEAR(b.points[0].pathLength, calcThesisPathLength(kPi / 2), kPathTol);
    EXPECT_NEAR(b.points[1].angle, 150 * kPi / 180, kPathTol);
    EXPECT_EQ(b.points[0].activation, 1.0);

    ObservationOptions injected;
    injected.pathFromAngle = [](double theta) { return 0.30 + 0.05 * theta; };
    const ObservationSet c = readObservations(deg, injected);
    EXPECT_NEAR(c.points[0].pathLength, 0.30 + 0.05 * kPi / 2, kPathTol);
    std::filesystem::remove(cm);
    std::filesystem::remove(deg);
}

TEST(ReadObservations, ShippedThesisFilesHoldTheThesisForces) {
    const ObservationSet m = readObservations(std::string(ARMSIM_ASSET_DIR) + "/measured/thesis_measured.csv");
    ASSERT_EQ(m.points.size(), 2u);
    EXPECT_NEAR(m.points[0].pathLength, 0.41, kPathTol);   // thesis 7.2.5: 600 N at 41 cm
    EXPECT_EQ(m.points[0].force, 600);
    EXPECT_NEAR(m.points[1].pathLength, 0.375, kPathTol);  // 458 N at 37.5 cm
    EXPECT_EQ(m.points[1].force, 458);
    const ObservationSet s = readObservations(std::string(ARMSIM_ASSET_DIR) + "/measured/thesis_synthetic.csv");
    ASSERT_EQ(s.points.size(), 2u);
    EXPECT_EQ(s.points[0].force, 596);                      // Table 7.2: 596 N at 40 cm
    EXPECT_EQ(s.points[1].force, 448);                      // 448 N at 37.5 cm
}

TEST(ReadObservations, BadValuesNameFileLineAndValue) {
    struct Case {
        const char* name;
        const char* text;
        std::vector<std::string> fragments;
    };
    const Case cases[] = {
        {"nan.csv", "path_cm,force_N\n40,596\n37.5,nan\n", {"nan.csv:3", "force_N", "nan"}},
        {"neg.csv", "path_cm,force_N\n40,-5\n", {"neg.csv:2", "force_N", "-5"}},
        {"act.csv", "path_cm,force_N,activation\n40,596,1.2\n", {"act.csv:2", "activation", "1.2", "[0, 1]"}},
        {"dup.csv", "path_cm,force_N\n40,596\n37.5,448\n40,590\n", {"dup.csv:4", "the same point as", "dup.csv:2 (path 0.4 m"}},
        {"ang.csv", "angle_deg,force_N\n200,500\n", {"ang.csv:2", "angle_deg", "200"}},
        {"col.csv", "path_cm,force_N,weight\n40,596,1\n", {"col.csv", "unknown column 'weight'"}},
        {"two.csv", "path_cm,angle_deg,force_N\n40,90,596\n", {"two.csv", "exactly one of"}},
        {"trial.csv", "path_cm,force_N,trial\n40,596,1.5\n", {"trial.csv:2", "trial", "1.5", "integer"}},
    };
    for (const Case& c : cases) {
        const std::string path = writeCsv(c.name, c.text);
        expectInputError([&] { readObservations(path); }, c.fragments);
        std::filesystem::remove(path);
    }
}

TEST(ReadObservations, RepeatedTrialsAreNotDuplicates) {
    const std::string path = writeCsv("trials.csv", "path_cm,force_N,trial\n40,596,1\n40,590,2\n");
    const ObservationSet s = readObservations(path);
    EXPECT_EQ(s.points.size(), 2u);
    EXPECT_EQ(s.countDistinctPoints(), 1);
    std::filesystem::remove(path);
}

TEST(IdentifyInput, FewerDistinctPointsThanUnknownsIsAnError) {
    const std::string path = writeCsv("one.csv", "path_cm,force_N,trial\n40,596,1\n40,590,2\n");
    IdentificationProblem pr = makeProblem(readObservations(path));
    expectInputError([&] { identify(pr, SteadyForceModel()); }, {"one.csv", "1 distinct", "2 unknowns"});
    std::filesystem::remove(path);
}

TEST(IdentifyInput, InMemoryBadDataAndBadMethodFitAreErrors) {
    const MuscleParameters truth = makeTruth();
    ObservationSet nan = makeSyntheticData(truth, {0.375, 0.40}, "memory");
    nan.points[1].force = std::nan("");
    expectInputError([&] { identify(makeProblem(nan), SteadyForceModel()); }, {"memory (point 2)", "force_N"});

    const ObservationSet beyond = makeSyntheticData(truth, {0.375, 0.40}, "memory");
    ObservationSet far = beyond;
    far.points[1].pathLength = 0.45;   // P_max = 0.43 m
    expectInputError([&] { identify(makeProblem(far), SteadyForceModel()); }, {"0.45", "max_path_length"});

    IdentificationOptions fp;
    fp.method = Method::FalsePosition;
    expectInputError([&] { identify(makeProblem(beyond), SteadyForceModel(), fp); }, {"false-position", "exactly one"});
    IdentificationOptions standard;
    standard.method = Method::IlcStandard;
    expectInputError([&] { identify(makeProblem(beyond), SteadyForceModel(), standard); }, {"ilc-standard", "2 observations"});
    IdentificationOptions bad;
    bad.lambda = 1.5;
    EXPECT_THROW(identify(makeProblem(beyond), SteadyForceModel(), bad), FieldError);
    expectInputError([] { parseMethodName("newton"); }, {"newton", "ilc-sign-search", "lm"});
    expectInputError([] { parseParameterName("weight"); }, {"weight", "optimal_tendon_length"});
}

TEST(Unknowns, ParameterMapRoundTripsAndScalesToOrderOne) {
    const ParameterMap map(loadBiceps(), makeUnknowns({"mass", "optimal_tendon_length", "optimal_fascicle_length",
                                                       "slow_fraction", "max_path_length"}));
    const std::vector<double> x = {0.30, 0.25, 0.15, 0.4, 0.44};
    const MuscleParameters p = map.toMuscle(x);
    EXPECT_EQ(p.mass, 0.30);
    EXPECT_EQ(p.optimalTendonLength, 0.25);
    EXPECT_EQ(p.optimalFascicleLength, 0.15);
    EXPECT_EQ(p.slowFraction, 0.4);
    EXPECT_EQ(p.maxPathLength, 0.44);
    EXPECT_EQ(map.fromMuscle(p), x);
    for (double z : map.toScaled(map.getStart())) EXPECT_DOUBLE_EQ(z, 1.0);  // scale = start by default
    Unknown u = makeUnknown(ParameterId::Mass);
    u.start = 2.0;   // outside 0.05..1 kg
    EXPECT_THROW(ParameterMap(loadBiceps(), {u}), FieldError);
}

// Synthetic data sets start from these points: one per angle, in order, the path from the angle.
TEST(Observations, AnglePointsCarryTheAngleAndItsPath) {
    const ObservationSet s = makeAnglePoints({150, 90}, calcThesisPathLength);
    ASSERT_EQ(s.points.size(), 2u);
    EXPECT_EQ(s.points[0].angle, degToRad(150));
    EXPECT_EQ(s.points[1].pathLength, calcThesisPathLength(degToRad(90)));
    EXPECT_NEAR(s.points[1].pathLength, 0.3748, 1e-4);  // thesis 6.1.2: "37.5 cm" at 90 deg
    EXPECT_EQ(s.points[0].activation, 1.0);
}

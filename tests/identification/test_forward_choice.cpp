// The pieces the command and the Python module share: identifyAndRecheck (the forward model chosen by
// name, then the two re-checks), observations and torque data from tables in memory, the torque
// identifiers run together and their residual check.
#include "basics/errors.h"
#include "basics/table.h"
#include "identification/torque_identification.h"
#include "identification/forward_choice.h"
#include "estimation/statistics.h"
#include "model/geometry.h"
#include "muscles/muscle_file.h"
#include "test_support.h"

#include <cmath>

using namespace armsim;

namespace {

constexpr double kSame = 0;           // the same computation: bit-identical
constexpr double kChiTol = 1e-12;     // closed-form chi-square sum

IdentificationProblem makeFiveAngleProblem(const ArmSetup& setup) {
    IdentificationProblem pr;
    pr.base = setup.calcBicepsParameters();
    Table t({"angle_deg", "force_N"});
    const std::vector<double> deg = {45, 60, 90, 120, 150}, factor = {1.01, 0.99, 1.02, 0.985, 1.0};
    std::vector<Observation> points;
    for (double d : deg) {
        Observation o;
        o.pathLength = calcBicepsPathLength(setup.arm.originDistance, setup.arm.insertionDistance, degToRad(d));
        points.push_back(o);
    }
    const std::vector<double> f = SteadyForceModel().calcForces(pr.base, points);
    for (std::size_t k = 0; k < deg.size(); ++k) t.appendRow({deg[k], f[k] * factor[k]});
    ObservationOptions oo;
    oo.pathFromAngle = makeArmPathFromAngle(setup.arm);
    pr.data = makeObservations(t, "data", oo);
    return pr;
}

}  // namespace

TEST(ForwardChoice, SteadyChoiceIsIdentifyPlusTwoRechecks) {
    const ArmSetup setup = loadModel("thesis");
    const IdentificationProblem pr = makeFiveAngleProblem(setup);
    const IdentificationReport direct = identify(pr, SteadyForceModel());
    std::string iterationModel = "unset";
    const IdentificationReport r = identifyAndRecheck(pr, {}, setup.arm, {}, &iterationModel);
    EXPECT_TRUE(iterationModel.empty());
    ASSERT_EQ(r.parameters.size(), 2u);
    EXPECT_NEAR(r.parameters[0].value, direct.parameters[0].value, kSame);
    EXPECT_NEAR(r.parameters[1].value, direct.parameters[1].value, kSame);
    ASSERT_EQ(r.checks.size(), 2u);
    EXPECT_EQ(r.checks[0].model, "steady");
    EXPECT_EQ(r.checks[1].model, "faithful");
    EXPECT_NE(r.checks[1].note.find("1000 Hz"), std::string::npos) << r.checks[1].note;  // the reference protocol
    // the steady re-check at the estimate reproduces the run's own residuals
    for (std::size_t k = 0; k < r.residuals.size(); ++k) EXPECT_NEAR(r.checks[0].residuals[k], r.residuals[k], 1e-9);
}

TEST(ForwardChoice, FaithfulChoiceNamesItsIterationModelAndBadChoicesAreRefused) {
    const ArmSetup setup = loadModel("thesis");
    ForwardModelChoice c;
    c.model = "corrected";
    c.holdDuration = 1.5;
    EXPECT_EQ(c.makeIterationOptions().protocol.averagingWindow, 0.5);  // a third of the hold
    EXPECT_EQ(c.makeReferenceOptions().protocol.sampleRate, FaithfulProtocol::makeReference().sampleRate);
    std::string iterationModel;
    const IdentificationReport r = identifyAndRecheck(makeFiveAngleProblem(setup), {}, setup.arm, c, &iterationModel);
    EXPECT_NE(iterationModel.find("faithful"), std::string::npos) << iterationModel;
    EXPECT_NE(r.forceModel.find("corrected"), std::string::npos) << r.forceModel;
    c.model = "exact";
    EXPECT_THROW(c.validate(), InputError);
    c.model = "faithful";
    c.holdDuration = -1;
    EXPECT_THROW(identifyAndRecheck(makeFiveAngleProblem(setup), {}, setup.arm, c), InputError);
}

TEST(ForwardChoice, FaithfulIsWarmStartedFromTheSteadyEstimateUnlessAskedNotTo) {
    const ArmSetup setup = loadModel("thesis");
    const IdentificationProblem pr = makeFiveAngleProblem(setup);
    ForwardModelChoice c;
    c.model = "faithful";
    c.holdDuration = 1.5;
    const IdentificationReport warm = identifyAndRecheck(pr, {}, setup.arm, c);
    c.warmStart = false;
    const IdentificationReport cold = identifyAndRecheck(pr, {}, setup.arm, c);
    EXPECT_NE(warm.message.find("started from the steady-model lm estimate"), std::string::npos) << warm.message;
    EXPECT_EQ(cold.message.find("steady-model"), std::string::npos) << cold.message;
    ASSERT_TRUE(warm.isConverged() && cold.isConverged()) << warm.message << " / " << cold.message;
    // both reach the faithful model's least-squares point, within its parameter tolerance (1e-5 scaled)
    for (int j = 0; j < 2; ++j)
        EXPECT_NEAR(warm.parameters[j].value, cold.parameters[j].value, 1e-3 * warm.parameters[j].value) << j;
    EXPECT_LT(warm.forwardEvaluations, cold.forwardEvaluations);  // the point of the warm start
}

TEST(TablesInMemory, RowsAreNamedByNumberWhenTheyHaveNoLine) {
    Table t({"angle_deg", "force_N"});
    t.appendRow({90, 300});
    t.appendRow({200, 400});
    ObservationOptions oo;
    try {
        makeObservations(t, "data", oo);
        ADD_FAILURE() << "no InputError";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("data row 2: column 'angle_deg' = 200"), std::string::npos) << e.what();
    }
    Table torque({"flexion_deg", "torque_Nm"});
    torque.appendRow({90, 40});
    torque.appendRow({90, -5});
    try {
        makeTorqueData(torque, "data");
        ADD_FAILURE() << "no InputError";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("data row 2: column 'torque_Nm' = -5"), std::string::npos) << e.what();
    }
}

TEST(TorqueIdentification, RunsThesisOnlyWithMvcsAtTwoAnglesAndChecksResidualsInClosedForm) {
    const Population prior = loadDefaultPopulation();
    std::vector<TorqueObservation> data = readTorqueData(findAsset("measured/thesis_mvc_torque.csv"));
    TorqueIdentificationOptions o;
    o.activation = 0.95;
    const std::vector<MuscleEstimate> all = identifyTorqueData(prior, data, o);
    ASSERT_EQ(all.size(), 3u);
    EXPECT_EQ(all[0].method, "thesis");
    EXPECT_EQ(all[2].method, "synergist-va");

    // the residual check by hand: sd_k = noise max(|torque_k|, 1), thesis dof = n - 2
    const double noise = 0.03;
    double chi = 0;
    int n = 0;
    for (std::size_t k = 0; k < data.size(); ++k)
        if (std::isfinite(all[0].predictedTorque[k])) {
            chi += std::pow((all[0].predictedTorque[k] - data[k].torque) / (noise * std::max(std::abs(data[k].torque), 1.0)), 2);
            ++n;
        }
    const TorqueResidualCheck c = checkTorqueResiduals(data, all[0], noise);
    EXPECT_EQ(c.n, n);
    EXPECT_EQ(c.dof, n - all[0].numParameters);
    EXPECT_NEAR(c.chiSquare, chi, kChiTol * chi);
    EXPECT_EQ(c.p, calcChiSquareSurvival(c.chiSquare, c.dof));
    EXPECT_EQ(checkTorqueResiduals(data, all[1], noise).dof, int(data.size()));  // MAP fits: no subtraction
    // Every method gives an estimate on these data (synergist-va's fit once stopped where a finite-difference
    // probe had no steady state), with a prediction per trial.
    for (const MuscleEstimate& e : all) {
        EXPECT_TRUE(std::isfinite(e.mass)) << e.method << ": " << e.message;
        EXPECT_EQ(e.predictedTorque.size(), data.size()) << e.method;
    }
    // A failed fit (no predictions) has no residual check, not a perfect one.
    MuscleEstimate failed;
    failed.method = "synergist";
    failed.predictedTorque.assign(data.size(), NAN);
    const TorqueResidualCheck none = checkTorqueResiduals(data, failed, noise);
    EXPECT_EQ(none.n, 0);
    EXPECT_TRUE(std::isnan(none.p));
    EXPECT_TRUE(std::isnan(none.rms));

    // one angle only: the thesis method is skipped and says why
    std::vector<TorqueObservation> oneAngle;
    for (const TorqueObservation& d : data)
        if (d.flexionDeg == data[0].flexionDeg) oneAngle.push_back(d);
    std::string skipped;
    const std::vector<MuscleEstimate> some = identifyTorqueData(prior, oneAngle, {}, &skipped);
    ASSERT_EQ(some.size(), 1u);
    EXPECT_EQ(some[0].method, "synergist");
    EXPECT_NE(skipped.find("thesis method: skipped"), std::string::npos) << skipped;
    o.noiseLevel = 0.9;
    EXPECT_THROW(identifyTorqueData(prior, data, o), InputError);
}

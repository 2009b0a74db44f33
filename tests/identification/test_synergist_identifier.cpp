// The synergist-aware identifier: the tared steady torque two ways, and the thesis and synergist-aware
// identifiers on a seeded population with the elbow as truth.
#include "basics/errors.h"
#include "basics/parallel.h"
#include "muscles/muscle_file.h"
#include "identification/torque_identification.h"
#include "model/geometry.h"
#include "model/mvc_curve.h"
#include "model/trial.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <array>
#include <cmath>
#include <cstdio>
#include <random>

using namespace armsim;

namespace {

const Population& population() {
    static const Population p = loadDefaultPopulation();
    return p;
}

// The integrated, tared MVC trial of v at each angle (3 s hold, last 0.2 s) against `steady`.
void expectTrialsMatch(const VirtualSubject& v, const std::vector<double>& flexion, const std::vector<double>& steady,
                       double relTol) {
    for (std::size_t a = 0; a < flexion.size(); ++a) {
        IsometricTrialSettings s;
        s.elbowAngle = degToRad(180 - flexion[a]);
        s.activation = v.setup.effort.voluntaryActivation;
        s.antagonistActivation = v.setup.effort.coContraction;
        s.averagingWindow = 0.2;
        const double trial = runIsometricTrial(v.setup, s).summary.meanMuscleTorque;
        EXPECT_NEAR(trial, steady[a], relTol * std::abs(steady[a])) << v.setup.name << " at " << flexion[a] << " deg";
    }
}

}  // namespace

// The identifier's prediction two ways: the steady MVC curves of model/ (active minus relaxed), and
// the time-integrated, tared MVC trial at the end of a 3 s hold.
TEST(ElbowIdentification, TaredSteadyTorqueEqualsTheMvcCurvesAndTheIntegratedTrial) {
    constexpr double kTrialRelTol = 0.01;  // slow activation dynamics: the 3 s plateau is within 1 %
    const VirtualSubject v = drawSubject(population(), 3, 2);
    const std::vector<double> flexion = {30, 90, 135};
    const std::vector<double> t = calcTaredSteadyTorque(v.setup, v.setup.effort, flexion);
    const SteadyMvcCurve active = calcSteadyMvcCurve(v.setup, MuscleGroup::Flexor, v.setup.effort, flexion);
    const SteadyMvcCurve relaxed = calcSteadyMvcCurve(v.setup, MuscleGroup::Flexor, SubjectEffort{0, 0}, flexion);
    for (std::size_t a = 0; a < flexion.size(); ++a)
        EXPECT_NEAR(t[a], active.totalTorque[a] - relaxed.totalTorque[a], 1e-9 * std::abs(t[a]));
    expectTrialsMatch(v, flexion, t, kTrialRelTol);
}

// Issue 11: with the elbow as truth (20 seeded subjects, five angles x 3 efforts, 2 % transducer
// noise), the synergist-aware identifier's biceps mass bias is within 10 % and its tendon-length
// RMSE within 15 mm, while the thesis method is off by more than +50 % (the flexors' torque lands on
// the biceps). Leaving the synergists out of the identifier's model breaks the bias bound: the
// test fails if the synergists are dropped.
TEST(ElbowIdentification, SynergistAwareIdentifierMeetsItsBiasBoundWhereTheThesisMethodFails) {
    constexpr int kSubjects = 20;
    constexpr double kMassBiasBound = 0.10, kTendonRmseBound = 0.015;
    constexpr int kMinCovered = 15;  // of 20: a 95 % interval may miss ~1; mismatch the prior lacks costs more
    TorqueProtocol protocol;
    protocol.holdDuration = 2.0;
    std::vector<std::vector<TorqueObservation>> data(kSubjects);
    std::vector<VirtualSubject> subjects(kSubjects);
    runParallel(kSubjects, 2, [&](int s) {
        subjects[s] = drawSubject(population(), 1, s);
        data[s] = synthesizeTorqueData(subjects[s], protocol, 1);
    });
    SynergistOptions dropped;
    dropped.includeSynergists = false;
    std::vector<std::array<MuscleEstimate, 4>> estimates(kSubjects);
    runParallel(kSubjects, 2, [&](int s) {
        SynergistOptions withVa;
        withVa.measuredActivation = measureVoluntaryActivation(data[s], withVa.activationSd, unsigned(s));
        estimates[s] = {identifySynergistAware(population(), data[s]), identifyThesisMethod(population().base, data[s]),
                        identifySynergistAware(population(), data[s], dropped),
                        identifySynergistAware(population(), data[s], withVa)};
    });
    double bias[4] = {0, 0, 0, 0}, massSq[4] = {0, 0, 0, 0}, tendonSq = 0;
    int converged = 0, covered = 0;
    for (int s = 0; s < kSubjects; ++s) {
        const MuscleParameters& truth = subjects[s].setup.biceps();
        const auto& e = estimates[s];
        for (int m = 0; m < 4; ++m) {
            bias[m] += (e[m].mass / truth.mass - 1) / kSubjects;
            massSq[m] += std::pow(e[m].mass / truth.mass - 1, 2) / kSubjects;
        }
        tendonSq += std::pow(e[0].tendonLength - truth.optimalTendonLength, 2) / kSubjects;
        converged += e[0].converged;
        if (!e[0].converged) {
            std::printf("subject %d: %s; mass %g tendon %g;", s, e[0].message.c_str(), e[0].mass, e[0].tendonLength);
            for (std::size_t k = 0; k < e[0].nuisance.size(); ++k) std::printf(" %s %g", e[0].nuisanceNames[k].c_str(), e[0].nuisance[k]);
            std::printf("\n");
        }
        covered += truth.mass >= e[0].massLower && truth.mass <= e[0].massUpper;
    }
    std::printf("mass bias: synergist-aware %+.1f %%, thesis %+.1f %%, synergists dropped %+.1f %%, with measured "
                "activation %+.1f %%; mass RMSE %.1f %% / %.1f %% with measured activation; tendon RMSE %.1f mm; "
                "mass coverage %d/%d\n",
                100 * bias[0], 100 * bias[1], 100 * bias[2], 100 * bias[3], 100 * std::sqrt(massSq[0]),
                100 * std::sqrt(massSq[3]), 1000 * std::sqrt(tendonSq), covered, kSubjects);
    EXPECT_EQ(converged, kSubjects);
    EXPECT_LE(std::abs(bias[0]), kMassBiasBound);
    EXPECT_LE(std::sqrt(tendonSq), kTendonRmseBound);
    EXPECT_GT(bias[1], 0.5);
    EXPECT_GT(std::abs(bias[2]), kMassBiasBound);  // the ablation fails the bound the full model meets
    EXPECT_GE(covered, kMinCovered);
    // A measured activation removes the activation-strength confound: a smaller mass RMSE.
    EXPECT_LT(massSq[3], massSq[0]);
}

// A population whose effort is exactly known (zero-width ranges: VA = 1, no co-contraction) holds
// those values fixed in the fit instead of probing outside [0, 1].
TEST(ElbowIdentification, ZeroWidthEffortRangesAreHeldFixed) {
    Population known = population();
    known.voluntaryActivation = {1.0, 1.0};
    known.coContraction = {0.0, 0.0};
    TorqueProtocol protocol;
    protocol.holdDuration = 1.5;
    protocol.averagingWindow = 0.5;
    const VirtualSubject v = drawSubject(known, 4, 0);
    const std::vector<TorqueObservation> data = synthesizeTorqueData(v, protocol, 4, 2);
    const MuscleEstimate e = identifySynergistAware(known, data);
    ASSERT_TRUE(std::isfinite(e.mass)) << e.message;
    EXPECT_TRUE(e.converged) << e.message;
    EXPECT_NEAR(e.nuisance[0], 1.0, 1e-5);  // voluntary_activation, within the probe margin
    EXPECT_NEAR(e.nuisance[1], 0.0, 1e-5);  // co_contraction
    EXPECT_LT(e.massLower, e.mass);
    EXPECT_GT(e.massUpper, e.mass);
}

// Issue 31: the channels fit recovers a known person from data its own model predicts (every
// channel, 1 % errors), reports F0 = sigma M / (rho L0) at the estimate, and judges each channel on
// its own: one fascicle image moved by 10 sd makes that channel a misfit, named with its angle, while
// the others stay consistent with their noise.
TEST(ElbowIdentification, ChannelsRecoverAKnownPersonAndJudgeEachChannel) {
    constexpr double kRelSd = 0.01;              // every measurement's relative sd
    constexpr double kMassTol = 0.03;            // relative: prior pull with 1 % data
    constexpr double kTendonTol = 0.003;         // m
    const Population& prior = population();
    ASSERT_GT(prior.specificTensionSd, 0);       // sigma and size are free
    ASSERT_GT(prior.geometryScaleSd, 0);
    const ArmSetup& base = prior.base;
    const std::string head = base.muscles[base.primary].params.name;
    std::vector<TorqueCondition> conditions;
    std::vector<ChannelObservation> channels;
    for (double q : {30.0, 90.0, 135.0}) {
        conditions.push_back({q, MuscleGroup::Flexor, 1.0, 1});
        for (double level : {0.0, 1.0}) {
            ChannelObservation o;
            o.channel = "fascicle_length";
            o.muscle = head;
            o.flexionDeg = q;
            o.level = level;
            channels.push_back(o);
        }
        ChannelObservation e;
        e.channel = "emg";
        e.muscle = base.muscles[base.surfaceEmg.back()].params.name;
        e.flexionDeg = q;
        e.level = 1;
        channels.push_back(e);
    }
    for (int m : base.getBicepsHeads()) {
        ChannelObservation v;
        v.channel = "volume";
        v.muscle = base.muscles[m].params.name;
        channels.push_back(v);
    }
    ChannelObservation arm;
    arm.channel = "upper_arm_length";
    channels.push_back(arm);
    for (ChannelObservation& o : channels) o.sd = 1;  // placeholders for the model's construction
    SynergistOptions options;
    options.channels = channels;
    const SynergistModel model(prior, options, conditions);
    std::vector<double> x = model.getPriorMean();
    const int im = model.getMassIndex();
    x[im] += 0.2;
    x[SynergistModel::getTendonIndex()] += 0.04;
    x[SynergistModel::getSpecificTensionIndex()] += 0.1;
    x[SynergistModel::getSizeIndex()] += 0.03;
    std::vector<double> torques, predicted;
    model.calcPredictions(x.data(), torques, predicted);
    std::vector<TorqueObservation> data;
    for (std::size_t k = 0; k < conditions.size(); ++k) {
        TorqueObservation t;
        t.flexionDeg = conditions[k].flexionDeg;
        t.torque = torques[k];
        data.push_back(t);
    }
    for (std::size_t k = 0; k < channels.size(); ++k) {
        options.channels[k].value = predicted[k];
        options.channels[k].sd = kRelSd * std::abs(predicted[k]);
    }
    options.noiseLevel = kRelSd;
    const MuscleEstimate e = identifySynergistAware(prior, data, options);
    ASSERT_TRUE(e.converged) << e.message;
    EXPECT_EQ(e.method, "channels");
    const MuscleParameters truth = model.makeMuscles(x.data())[base.primary].params;
    EXPECT_NEAR(e.mass / truth.mass - 1, 0, kMassTol);
    EXPECT_NEAR(e.tendonLength, truth.optimalTendonLength, kTendonTol);
    EXPECT_LT(e.massLower, truth.mass);
    EXPECT_GT(e.massUpper, truth.mass);
    const double f0 = truth.coefficients.sigma * truth.mass / (truth.coefficients.density * truth.optimalFascicleLength);
    EXPECT_NEAR(e.maxForce / f0 - 1, 0, 2 * kMassTol);
    ASSERT_EQ(e.channelFits.size(), 5u);  // torque, fascicle_length, emg, volume, upper_arm_length
    for (const ChannelFit& f : e.channelFits) EXPECT_GT(f.p, 0.05) << f.channel;

    // One image 10 sd off: its channel is the misfit and names the angle.
    options.channels[3].value += 10 * options.channels[3].sd;  // 90 deg at rest (after 30 deg: rest, MVC, EMG)
    const MuscleEstimate bad = identifySynergistAware(prior, data, options);
    for (const ChannelFit& f : bad.channelFits) {
        if (f.channel == "fascicle_length") {
            EXPECT_LT(f.p, 0.05);
            EXPECT_NE(f.worst.find("90 deg"), std::string::npos) << f.worst;
            EXPECT_NE(f.worst.find("rest"), std::string::npos) << f.worst;
        }
    }
}

// The twin (ten muscles, forearm locked at its posture): the identifier's steady prediction against
// the integrated, tared trial, as for the elbow above, and the fascicle at rest and at the plateau.
TEST(ElbowIdentification, TwinTaredSteadyTorqueEqualsTheIntegratedTrial) {
    constexpr double kTrialRelTol = 0.01;  // as the elbow's: slow activation dynamics over a 3 s hold
    const Population& p = population();   // the twin's: its forearm rotates
    ASSERT_TRUE(p.base.arm.forearmRotation.enabled);
    const VirtualSubject v = drawSubject(p, 3, 2);
    const std::vector<double> flexion = {30, 90, 135};
    expectTrialsMatch(v, flexion, calcTaredSteadyTorque(v.setup, v.setup.effort, flexion), kTrialRelTol);
}

// Torque in several forearm postures (issue 31): the identifier's steady prediction for conditions at
// rotation -90, the model's posture (NaN) and +90 deg, on a prior whose model is the person (x = 0 with
// the person's effort), against the integrated trial locked at each posture. The postures differ by more
// than the tolerance (the biceps' moment arm changes with the radius), so ignoring the posture fails.
TEST(ElbowIdentification, PostureConditionsPredictTheTrialInEachPosture) {
    constexpr double kTrialRelTol = 0.01;   // as above: slow activation dynamics over a 3 s hold
    Population p = population();
    p.base = loadModel("twin");
    const VirtualSubject v = drawSubject(p, 3, 2);
    Population person = p;
    person.base = v.setup;
    std::vector<TorqueCondition> conditions;
    for (double rotation : {-90.0, double(NAN), 90.0}) {
        TorqueCondition c{90, MuscleGroup::Flexor, 1.0, 1};
        c.rotationDeg = rotation;
        conditions.push_back(c);
    }
    const SynergistModel model(person, SynergistOptions{}, conditions);
    std::vector<double> x(std::size_t(model.getNumParameters()), 0.0);
    x[SynergistModel::getActivationIndex()] = v.setup.effort.voluntaryActivation;
    x[SynergistModel::getActivationIndex() + 1] = v.setup.effort.coContraction;
    x[SynergistModel::getSpecificTensionIndex()] = x[SynergistModel::getSizeIndex()] = 0;
    const std::vector<double> predicted = model.calcTorques(x.data());
    ASSERT_EQ(predicted.size(), 3u);
    // a posture differs from neutral by more than the tolerance (this person: supinated by 4.4 %)
    EXPECT_GT(std::max(std::abs(predicted[0] / predicted[1] - 1), std::abs(predicted[2] / predicted[1] - 1)), 3 * kTrialRelTol);
    for (std::size_t k = 0; k < conditions.size(); ++k) {
        IsometricTrialSettings s;
        s.elbowAngle = degToRad(90);
        s.forearmRotationDeg = conditions[k].rotationDeg;
        s.activation = v.setup.effort.voluntaryActivation;
        s.antagonistActivation = v.setup.effort.coContraction;
        s.averagingWindow = 0.2;
        const double trial = runIsometricTrial(v.setup, s).summary.meanMuscleTorque;
        EXPECT_NEAR(trial, predicted[k], kTrialRelTol * std::abs(predicted[k])) << "rotation " << conditions[k].rotationDeg;
    }
    // A posture on a model without a forearm rotation (the elbow) is refused, by the identifier and by the trial.
    const Population elbow = loadPopulation(findAsset("subjects/elbow_population.yaml"));
    EXPECT_THROW(SynergistModel(elbow, SynergistOptions{}, conditions), armsim::InputError);
    IsometricTrialSettings s;
    s.forearmRotationDeg = -90;
    EXPECT_THROW(runIsometricTrial(elbow.base, s), armsim::InputError);
}

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

#include <algorithm>
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
// test fails if the synergists are dropped. A measured voluntary activation must reach the fit.
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
    // A measured activation reaches the fit: the fitted activation lies closer to the person's. (Its
    // mass RMSE is no smaller on the twin, where the person's specific tension, not the activation, is
    // what torque cannot separate from mass: README, 200 subjects, 14.0 % without and 14.4 % with it;
    // 13.6 % both ways at fmax 2.)
    double vaSq[2] = {0, 0};
    for (int s = 0; s < kSubjects; ++s)
        for (int m = 0; m < 2; ++m) {
            const MuscleEstimate& e = estimates[s][m == 0 ? 0 : 3];
            const auto it = std::find(e.nuisanceNames.begin(), e.nuisanceNames.end(), "voluntary_activation");
            ASSERT_NE(it, e.nuisanceNames.end());
            const double va = e.nuisance[std::size_t(it - e.nuisanceNames.begin())];
            vaSq[m] += std::pow(va - subjects[s].setup.effort.voluntaryActivation, 2) / kSubjects;
        }
    std::printf("fitted voluntary activation RMSE: %.3f without the measurement, %.3f with it\n", std::sqrt(vaSq[0]),
                std::sqrt(vaSq[1]));
    // Expected ratio about 0.45-0.5: the measurement's sd 0.02 combined with what the torque and the prior's
    // uniform 0.85-1 (sd 0.043) give (RMSE 0.041 on the twin calibrated 2026-11-27); 20 subjects put about
    // 16 % on each RMSE (measured 0.60). A measurement that does not reach the fit gives about 1.
    constexpr double kVaRmseRatio = 0.7;
    EXPECT_LT(std::sqrt(vaSq[1]), kVaRmseRatio * std::sqrt(vaSq[0]));
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
        conditions.push_back({q, Effort::Flexion, 1.0, 1});
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
    ASSERT_EQ(e.channelFits.size(), 6u);  // torque, fascicle_length, emg, volume, upper_arm_length, prior
    EXPECT_EQ(e.channelFits.back().channel, "prior");
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
        TorqueCondition c{90, Effort::Flexion, 1.0, 1};
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

// The two-axis transducer (issue 31): the identifier's steady prediction of both axes, for a flexion
// MVC in the model's posture, a supination MVC pronated and a pronation MVC supinated, against the
// integrated trial's tared torques about the elbow and the forearm axis (as above: prior = the person).
TEST(ElbowIdentification, TwoAxisConditionsPredictBothAxesOfTheTrial) {
    constexpr double kTrialRelTol = 0.01;   // as above: slow activation dynamics over a 3 s hold
    Population p = population();
    const VirtualSubject v = drawSubject(p, 3, 2);
    Population person = p;
    person.base = v.setup;
    ASSERT_TRUE(v.setup.arm.forearmRotation.enabled);
    std::vector<TorqueCondition> conditions = {{90, Effort::Flexion, 1.0, 1}, {90, Effort::Supination, 1.0, 1},
                                               {60, Effort::Pronation, 1.0, 1}};
    conditions[1].rotationDeg = -60;
    conditions[2].rotationDeg = 30;
    const SynergistModel model(person, SynergistOptions{}, conditions);
    std::vector<double> x(std::size_t(model.getNumParameters()), 0.0);
    x[SynergistModel::getActivationIndex()] = v.setup.effort.voluntaryActivation;
    x[SynergistModel::getActivationIndex() + 1] = v.setup.effort.coContraction;
    std::vector<double> torque, forearm, channels;
    model.calcPredictions(x.data(), torque, forearm, channels);
    ASSERT_EQ(forearm.size(), 3u);
    EXPECT_GT(forearm[0], 0.5);   // N m: in a flexion MVC the biceps out-supinates the pronator teres
    EXPECT_GT(forearm[1], 5.0);   // a supination effort supinates
    EXPECT_LT(forearm[2], -5.0);  // a pronation effort pronates
    for (std::size_t k = 0; k < conditions.size(); ++k) {
        IsometricTrialSettings s;
        s.elbowAngle = degToRad(180 - conditions[k].flexionDeg);
        s.forearmRotationDeg = conditions[k].rotationDeg;
        s.effort = conditions[k].effort;
        s.activation = v.setup.effort.voluntaryActivation;
        s.antagonistActivation = v.setup.effort.coContraction;
        s.averagingWindow = 0.2;
        const IsometricSummary trial = runIsometricTrial(v.setup, s).summary;
        const double scale = std::max(std::abs(torque[k]), std::abs(forearm[k]));
        EXPECT_NEAR(trial.meanMuscleTorque, torque[k], kTrialRelTol * scale) << getEffortName(conditions[k].effort);
        EXPECT_NEAR(trial.meanForearmTorque, forearm[k], kTrialRelTol * scale) << getEffortName(conditions[k].effort);
    }
}

// The prediction cache (SteadyCurveCache) is exact: along a fit-like sequence of points (central
// probes of every parameter, a repeated point, a step of all of them, muscle deviations), predictions
// with one cache equal the predictions without it bit for bit, in three postures and both axes; and it
// does its work: a mass probe solves nothing, a biceps tendon probe only the biceps heads.
TEST(ElbowIdentification, CachedPredictionsEqualUncachedOnesBitForBit) {
    constexpr double kStep = 1e-6;   // a numeric Jacobian's relative probe
    const Population& prior = population();
    std::vector<TorqueCondition> conditions = {{30, Effort::Flexion, 1.0, 1}, {90, Effort::Flexion, 1.0, 1},
                                               {90, Effort::Extension, 1.0, 1}, {90, Effort::Supination, 1.0, 1},
                                               {120, Effort::Flexion, 0.5, 1}};
    conditions[3].rotationDeg = -60;
    conditions[4].rotationDeg = 45;
    const SynergistModel model(prior, SynergistOptions{}, conditions);
    const int n = model.getNumParameters();
    std::vector<std::vector<double>> points{model.getPriorMean()};
    for (int j = 0; j < n; ++j)
        for (double sign : {1.0, -1.0}) {
            std::vector<double> x = model.getPriorMean();
            x[j] += sign * kStep;
            points.push_back(x);
        }
    points.push_back(model.getPriorMean());
    std::vector<double> step = model.getPriorMean();
    for (int j = 0; j < n; ++j) step[j] = std::clamp(step[j] + 0.01 * (j % 3 - 1), model.getLower()[j], model.getUpper()[j]);
    points.push_back(step);
    SynergistModel::PredictionCache cache;
    auto expectSame = [&](const std::vector<double>& x, const std::vector<SynergistModel::MuscleDeviation>* d) {
        std::vector<double> t0, f0, c0, t1, f1, c1;
        model.calcPredictions(x.data(), d, t0, f0, c0);
        model.calcPredictions(x.data(), d, t1, f1, c1, &cache);
        ASSERT_EQ(t0.size(), t1.size());
        for (std::size_t k = 0; k < t0.size(); ++k) {
            EXPECT_EQ(t0[k], t1[k]) << "condition " << k;   // bit for bit
            EXPECT_EQ(f0[k], f1[k]) << "condition " << k;
        }
    };
    for (const auto& x : points) expectSame(x, nullptr);
    std::vector<SynergistModel::MuscleDeviation> deviations(prior.base.muscles.size());
    deviations[prior.base.primary].lnTendon = 0.02;
    deviations.back().lnMass = -0.1;
    expectSame(step, &deviations);
    expectSame(step, nullptr);
    EXPECT_GT(cache.relaxed.getNumReused(), 0);

    // What one probe solves: the states of the curves at the points, counted.
    auto solvedBy = [&](int j) {
        SynergistModel::PredictionCache c;
        std::vector<double> t, f, ch, x = model.getPriorMean();
        model.calcPredictions(x.data(), nullptr, t, f, ch, &c);
        auto count = [&] {
            long s = c.relaxed.getNumSolved();
            for (const SteadyCurveCache& a : c.active) s += a.getNumSolved();
            return s;
        };
        const long before = count();
        x[j] += kStep;
        model.calcPredictions(x.data(), nullptr, t, f, ch, &c);
        return count() - before;
    };
    const long poses = 4, curves = 5;   // (30, 90, 120 deg; rotations 0, -60, 45): 4 poses; relaxed + 4 kinds
    EXPECT_EQ(solvedBy(model.getMassIndex()), 0);
    EXPECT_EQ(solvedBy(SynergistModel::getTendonIndex()), long(prior.base.getBicepsHeads().size()) * poses * curves);
    EXPECT_EQ(solvedBy(SynergistModel::getSizeIndex()), long(prior.base.muscles.size()) * poses * curves);
}

// The predictions' Jacobian through the steady states (implicit function theorem and the chain rule
// through x's scales) against central differences of the predictions, over every parameter: both axes
// of flexion, extension, supination and submaximal efforts in three postures, and every channel kind;
// the slow-fraction shifts free (their columns are differenced inside, the rest analytic).
TEST(ElbowIdentification, PredictionJacobianEqualsDifferencesOfPredictions) {
    constexpr double kStep = 1e-6;   // central differences, on x (ln scales and activations)
    constexpr double kTol = 2e-5;    // of the row's largest derivative: differences of 1e-13-bracketed solves
    const Population& prior = population();
    const ArmSetup& base = prior.base;
    std::vector<TorqueCondition> conditions = {{30, Effort::Flexion, 1.0, 1}, {90, Effort::Flexion, 1.0, 1},
                                               {90, Effort::Extension, 1.0, 1}, {90, Effort::Supination, 1.0, 1},
                                               {120, Effort::Flexion, 0.5, 1}, {60, Effort::Pronation, 1.0, 1}};
    conditions[3].rotationDeg = -60;
    conditions[4].rotationDeg = 45;
    SynergistOptions options;
    options.freeSlowFraction = true;
    const std::string head = base.muscles[base.primary].params.name;
    for (double level : {0.0, 1.0}) {
        ChannelObservation o;
        o.channel = "fascicle_length";
        o.muscle = head;
        o.flexionDeg = 90;
        o.level = level;
        options.channels.push_back(o);
    }
    ChannelObservation emg, volume, arm;
    emg.channel = "emg";
    emg.muscle = base.muscles[base.surfaceEmg.back()].params.name;
    emg.flexionDeg = 90;
    emg.level = 1;
    volume.channel = "volume";
    volume.muscle = head;
    arm.channel = "upper_arm_length";
    for (const ChannelObservation& o : {emg, volume, arm}) options.channels.push_back(o);
    for (ChannelObservation& o : options.channels) o.sd = 1;
    const SynergistModel model(prior, options, conditions);
    const int n = model.getNumParameters();
    std::vector<double> x = model.getPriorMean();
    for (int j = 0; j < n; ++j)   // away from the prior's mean, inside the bounds
        if (model.getLower()[j] < model.getUpper()[j])
            x[j] = std::clamp(x[j] + 0.03 * ((j * 7) % 5 - 2), model.getLower()[j] + 1e-3, model.getUpper()[j] - 1e-3);
    std::vector<double> t, f, c, dt, df, dc;
    SynergistModel::PredictionCache cache;
    model.calcPredictionJacobian(x.data(), t, f, c, dt, df, dc, &cache);
    std::vector<double> t0, f0, c0;
    model.calcPredictions(x.data(), nullptr, t0, f0, c0);
    ASSERT_EQ(t, t0);   // the same values as calcPredictions
    ASSERT_EQ(f, f0);
    ASSERT_EQ(c, c0);
    const std::size_t nc = t.size(), nk = c.size();
    std::vector<std::vector<double>> fd(2 * nc + nk, std::vector<double>(n));
    for (int j = 0; j < n; ++j) {
        std::vector<double> xp = x, xm = x, tp, fp, cp, tm, fm, cm;
        xp[j] += kStep;
        xm[j] -= kStep;
        model.calcPredictions(xp.data(), nullptr, tp, fp, cp);
        model.calcPredictions(xm.data(), nullptr, tm, fm, cm);
        for (std::size_t k = 0; k < nc; ++k) {
            fd[k][j] = (tp[k] - tm[k]) / (2 * kStep);
            fd[nc + k][j] = (fp[k] - fm[k]) / (2 * kStep);
        }
        for (std::size_t k = 0; k < nk; ++k) fd[2 * nc + k][j] = (cp[k] - cm[k]) / (2 * kStep);
    }
    const std::vector<std::string> names = model.getParameterNames();
    int nonzero = 0;
    for (std::size_t r = 0; r < fd.size(); ++r) {
        const double* row = r < nc ? &dt[r * n] : r < 2 * nc ? &df[(r - nc) * n] : &dc[(r - 2 * nc) * n];
        double largest = 1e-9;
        for (int j = 0; j < n; ++j) largest = std::max(largest, std::abs(fd[r][j]));
        for (int j = 0; j < n; ++j) {
            EXPECT_NEAR(row[j], fd[r][j], kTol * largest) << "row " << r << ", d / d " << names[j];
            nonzero += row[j] != 0;
        }
    }
    EXPECT_GT(nonzero, int(fd.size()) * 3);   // not an empty matrix
}

// The forearm axis identifies: torque data of both axes made by the identifier's own model at a known x
// (biceps long head 20 % heavier, supinator 15 % stronger than the prior's mean; no noise, 2 % assumed)
// are fitted within their noise, with the mass inside its interval and the supinator's scale moved from
// the prior's mean toward the truth; each axis is judged as its own channel, and one supination
// reading 10 sd off is named. The rotators' scale is held at the prior's mean without forearm readings
// (the torque-only fit of before), and a rotation effort without its forearm torque is refused.
TEST(ElbowIdentification, ForearmAxisDataRecoverAKnownPerson) {
    constexpr double kNoise = 0.02;
    const Population& prior = population();
    std::vector<TorqueCondition> conditions;
    for (double q : {30.0, 60.0, 90.0, 120.0, 135.0}) conditions.push_back({q, Effort::Flexion, 1.0, 1});
    for (double rotation : {-60.0, 0.0, 60.0}) {
        TorqueCondition s{90, Effort::Supination, 1.0, 1}, p{90, Effort::Pronation, 1.0, 1};
        s.rotationDeg = p.rotationDeg = rotation;
        conditions.push_back(s);
        conditions.push_back(p);
    }
    const SynergistModel model(prior, SynergistOptions{}, conditions);
    std::vector<double> x = model.getPriorMean();
    x[model.getMassIndex()] += 0.2;
    const int sup = model.findMassIndex(prior.base.findMuscle("SUP"));
    ASSERT_GE(sup, model.getFirstRotatorIndex());
    x[sup] += std::log(1.15);
    std::vector<double> torque, forearm, channels;
    model.calcPredictions(x.data(), torque, forearm, channels);
    std::vector<TorqueObservation> data;
    for (std::size_t k = 0; k < conditions.size(); ++k) {
        TorqueObservation t;
        t.flexionDeg = conditions[k].flexionDeg;
        t.effort = conditions[k].effort;
        t.rotationDeg = conditions[k].rotationDeg;
        t.torque = torque[k];
        t.forearmTorque = forearm[k];
        data.push_back(t);
    }
    SynergistOptions options;
    options.noiseLevel = kNoise;
    const MuscleEstimate e = identifySynergistAware(prior, data, options);
    ASSERT_TRUE(e.converged) << e.message;
    const MuscleParameters truth = model.makeMuscles(x.data())[prior.base.primary].params;
    EXPECT_LT(e.massLower, truth.mass);
    EXPECT_GT(e.massUpper, truth.mass);
    const auto it = std::find(e.nuisanceNames.begin(), e.nuisanceNames.end(), "SUP_mass_scale");
    ASSERT_NE(it, e.nuisanceNames.end());
    // From 1 toward 1.15: the prior holds it back (at 90 deg flexion the supinator gives about a fifth
    // of the supination torque, 376 N x 7.7 mm neutral, the biceps most of the rest); measured a third of
    // the way in ln (1.047), so at least a quarter. Without forearm readings it stays at exactly 1 (below).
    constexpr double kMinShareOfTheWay = 0.25;
    EXPECT_GT(std::log(e.nuisance[it - e.nuisanceNames.begin()]), kMinShareOfTheWay * std::log(1.15));
    ASSERT_EQ(e.channelFits.size(), 3u);  // torque, forearm_torque, prior
    EXPECT_EQ(e.channelFits[1].channel, "forearm_torque");
    EXPECT_EQ(e.channelFits[1].n, int(conditions.size()));
    for (const ChannelFit& f : e.channelFits) EXPECT_GT(f.p, 0.05) << f.channel;

    // One supination reading 10 sd off: the forearm channel misfits and names the effort and posture.
    std::vector<TorqueObservation> bad = data;
    bad[5].forearmTorque += 10 * kNoise * bad[5].getLoad();
    const MuscleEstimate b = identifySynergistAware(prior, bad, options);
    ASSERT_EQ(b.channelFits.size(), 3u);
    EXPECT_LT(b.channelFits[1].p, 0.05);
    EXPECT_NE(b.channelFits[1].worst.find("supination MVC at 90 deg, forearm at -60 deg"), std::string::npos)
        << b.channelFits[1].worst;

    // Without forearm readings the rotators stay at the prior's mean; a rotation effort needs its reading.
    std::vector<TorqueObservation> flexionOnly(data.begin(), data.begin() + 5);
    for (TorqueObservation& t : flexionOnly) t.forearmTorque = NAN;
    const MuscleEstimate f = identifySynergistAware(prior, flexionOnly, options);
    EXPECT_EQ(std::find(f.nuisanceNames.begin(), f.nuisanceNames.end(), "SUP_mass_scale"), f.nuisanceNames.end());
    std::vector<TorqueObservation> unread = data;
    unread[5].forearmTorque = NAN;
    EXPECT_THROW(identifySynergistAware(prior, unread, options), armsim::InputError);
}

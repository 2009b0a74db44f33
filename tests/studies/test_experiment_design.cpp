// Experiment design (issue 11): the predicted posterior width checked against a second method (the
// spread of actual MAP estimates when the identifier's own model is the truth), information that only
// grows with trials, and a greedy design that does at least as well as the reference it is compared to.
#include "basics/errors.h"
#include "basics/parallel.h"
#include "basics/portable_random.h"
#include "muscles/muscle_file.h"
#include "experiments/channels.h"
#include "studies/experiment_design.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

using namespace armsim;

namespace {

// The default population with an effort that varies only through the transducer (trial CV 0), so the
// design's noise model sigma = hypot(transducer, cv) is the noise the data get.
Population makePrior() {
    Population p = loadDefaultPopulation();
    p.trialCv = 0;
    p.transducerNoise = 0.02;
    return p;
}

}  // namespace

// Second method: draw x from the identifier's prior, synthesize the protocol's torques with the
// identifier's own model plus 2 % noise, fit with the MAP identifier (noise level given), and compare
// the RMS error of ln M over the draws with the predicted posterior sd (same draws). With 40 draws the
// RMS has a sampling spread of ~11 %; the Laplace approximation of a nonlinear model adds some: a 30 %
// tolerance. The MAP intervals must also cover the truth in most draws.
TEST(ExperimentDesign, PredictedWidthMatchesTheSpreadOfMapEstimatesOnTheModelsOwnData) {
    constexpr int kDraws = 40;
    constexpr double kRatioTol = 0.30;
    constexpr int kMinCovered = 34;  // of 40 at a nominal 95 %: P(fewer) < 1 % for a true 95 % interval
    const Population prior = makePrior();
    TorqueProtocol protocol;  // the thesis's five flexion MVCs x 3
    DesignSettings settings;
    settings.draws = kDraws;
    settings.activationSd = 0;
    settings.seed = 3;
    const ProtocolPrediction predicted = predictProtocol(prior, protocol, settings);

    const SynergistModel model(prior, SynergistOptions{}, protocol.conditions);
    const std::vector<std::vector<double>> xs = drawFromPrior(model, settings.seed, kDraws);
    const int im = model.getMassIndex();
    std::vector<double> error(kDraws, NAN);
    std::vector<int> covered(kDraws, 0);
    runParallel(kDraws, 2, [&](int d) {
        const std::vector<double> clean = model.calcTorques(xs[d].data());
        PortableRandom rng{17u, unsigned(d)};
        std::vector<TorqueObservation> data;
        for (std::size_t c = 0; c < protocol.conditions.size(); ++c)
            for (int r = 0; r < protocol.conditions[c].repetitions; ++r) {
                TorqueObservation o;
                o.flexionDeg = protocol.conditions[c].flexionDeg;
                o.repetition = r;
                o.torque = clean[c] * (1 + prior.transducerNoise * rng.drawNormal());
                data.push_back(o);
            }
        SynergistOptions options;
        options.noiseLevel = prior.transducerNoise;
        const MuscleEstimate e = identifySynergistAware(prior, data, options);
        const double trueMass = prior.base.biceps().mass * std::exp(xs[d][im]);
        error[d] = std::log(e.mass / trueMass);
        covered[d] = trueMass >= e.massLower && trueMass <= e.massUpper;
    });
    double ss = 0;
    int n = 0, hits = 0;
    for (int d = 0; d < kDraws; ++d) {
        ASSERT_TRUE(std::isfinite(error[d])) << "draw " << d;
        ss += error[d] * error[d];
        ++n;
        hits += covered[d];
    }
    const double rms = std::sqrt(ss / n);
    std::printf("ln M: predicted posterior sd %.2f %%, RMS error of the MAP estimates %.2f %% over %d draws; "
                "95 %% intervals covered %d/%d\n",
                100 * predicted.massSd, 100 * rms, n, hits, n);
    EXPECT_NEAR(rms / predicted.massSd, 1.0, kRatioTol);
    EXPECT_GE(hits, kMinCovered);
    EXPECT_LT(predicted.massSd, predicted.priorMassSd);  // the data inform M
}

// The widened prediction against a second method: persons drawn from the population itself (each muscle
// its own tendon, fascicle, slow fraction and mass, which the identifier's fit shares or holds) through
// the recommended protocol (every channel), fitted with the population as prior. The RMS error of L0T over
// 100 persons must not exceed the design's width with the consider parameters (tendonSdConsidered, what
// the identifier's intervals report): intervals at least as wide as the errors; and it must lie well
// above the narrower width of the fit's own model. The same for the primary's F0 (maxForceSdConsidered:
// ln sigma + ln M - ln L0), whose prediction is what the README's F0 floor rests on. A known conservative bias, bounded here, not hidden:
// with transducer noise only, the twin at fmax 3 gives 13.2 mm against 17.1 mm predicted (ratio 0.77;
// 11.6 against 12.7 mm, 0.91, at fmax 2) and 7.8 mm own. The widened variance is linear in what the fit
// holds, 72 % of it the pronator teres' own tendon and fascicle (one person of the recommended protocol).
// With the population's 5 % trial variability the prediction and validation agree (README: 10.7 mm
// predicted, 10.2 mm obtained in family). RMS over 100 persons: sampling sd about 7 %.
TEST(ExperimentDesign, WidenedWidthBoundsTheSpreadOfEstimatesOfPeopleTheFitSimplifies) {
    constexpr int kPeople = 100;
    constexpr double kMaxRatio = 1.15;          // not narrower than the spread: 2 sampling sds
    constexpr double kMinRatio = 0.65;          // the known conservative bias (0.77) plus 2 sampling sds
    constexpr double kAboveOwnModel = 1.2;      // measured 1.69: the own model's prediction is too narrow
    constexpr double kForceMaxRatio = 1.15;     // F0: not narrower than the spread (2 sampling sds)
    constexpr double kForceMinRatio = 0.65;     // and not conservative beyond what L0T is
    const Population prior = makePrior();
    const TorqueProtocol protocol = readTorqueProtocol(findAsset("protocols/recommended.yaml"));
    DesignSettings settings;
    settings.draws = 32;
    settings.activationSd = 0.02;
    const ProtocolPrediction predicted = predictProtocol(prior, protocol, settings);
    ASSERT_TRUE(std::isfinite(predicted.tendonSdConsidered));

    std::vector<double> error(kPeople, NAN), massError(kPeople, NAN), forceError(kPeople, NAN);
    runParallel(kPeople, 2, [&](int k) {
        const VirtualSubject v = drawSubject(prior, 7, k);
        const std::vector<TorqueObservation> data = synthesizeTorqueData(v, protocol, 100 + unsigned(k), 1);
        SynergistOptions options;
        options.noiseLevel = prior.transducerNoise;
        options.channels = synthesizeChannelData(v, protocol, data, 100 + unsigned(k));
        options.emgCrosstalk = protocol.channelNoise.emgCrosstalk;
        options.measuredActivation = measureVoluntaryActivation(data, settings.activationSd, 100 + unsigned(k));
        const MuscleEstimate e = identifySynergistAware(prior, data, options);
        if (!e.converged) return;
        error[k] = e.tendonLength - v.setup.biceps().optimalTendonLength;
        massError[k] = std::log(e.mass / v.setup.biceps().mass);
        const MuscleParameters& q = v.setup.biceps();
        forceError[k] = std::log(e.maxForce / (q.coefficients.sigma * q.mass / (q.coefficients.density * q.optimalFascicleLength)));
    });
    double ss = 0, sm = 0, sf = 0;
    int n = 0;
    for (int k = 0; k < kPeople; ++k)
        if (std::isfinite(error[k]))
            ss += error[k] * error[k], sm += massError[k] * massError[k], sf += forceError[k] * forceError[k], ++n;
    ASSERT_GE(n, kPeople - 3);
    const double rms = std::sqrt(ss / n);
    std::printf("recommended protocol, %d persons of the population: L0T RMS error %.2f mm, predicted %.2f mm with the "
                "consider parameters, %.2f mm without; ln M RMS %.2f %%, predicted %.2f %% / %.2f %%\n",
                n, 1000 * rms, 1000 * predicted.tendonSdConsidered, 1000 * predicted.tendonSd, 100 * std::sqrt(sm / n),
                100 * predicted.massSdConsidered, 100 * predicted.massSd);
    const double rmsForce = std::sqrt(sf / n);
    std::printf("ln F0 RMS %.2f %%, predicted %.2f %% with the consider parameters, %.2f %% without (prior %.2f %%)\n",
                100 * rmsForce, 100 * predicted.maxForceSdConsidered, 100 * predicted.maxForceSd,
                100 * predicted.priorMaxForceSd);
    EXPECT_LE(rmsForce / predicted.maxForceSdConsidered, kForceMaxRatio);
    EXPECT_GE(rmsForce / predicted.maxForceSdConsidered, kForceMinRatio);
    EXPECT_LT(predicted.maxForceSd, predicted.priorMaxForceSd);  // the data inform F0
    EXPECT_LE(rms / predicted.tendonSdConsidered, kMaxRatio);
    EXPECT_GE(rms / predicted.tendonSdConsidered, kMinRatio);
    EXPECT_GT(rms / predicted.tendonSd, kAboveOwnModel);
}

// Information only adds to the fit's own model: its Laplace widths shrink (never grow) as repetitions
// are added, and the greedy design on them falls step by step and ends at or below the thesis protocol's
// (whose conditions are all candidates) with the same budget. With the widened widths (the default
// criterion) more torque-only trials can widen them; that design stops where no block narrows them.
TEST(ExperimentDesign, WidthsShrinkWithTrialsAndTheDesignBeatsTheThesisProtocol) {
    const Population prior = makePrior();
    DesignSettings settings;
    settings.draws = 8;
    settings.ownModelCriterion = true;
    TorqueProtocol thesis;
    thesis.name = "thesis";
    double last = INFINITY;
    for (int repetitions : {1, 3, 9}) {
        TorqueProtocol p = thesis;
        for (TorqueCondition& c : p.conditions) c.repetitions = repetitions;
        const ProtocolPrediction q = predictProtocol(prior, p, settings);
        EXPECT_LT(q.criterion, last) << repetitions;
        last = q.criterion;
    }
    const DesignResult d = designProtocol(prior, settings, thesis);
    ASSERT_EQ(d.steps.size(), 5u);
    for (std::size_t k = 1; k < d.steps.size(); ++k) EXPECT_LE(d.steps[k].criterion, d.steps[k - 1].criterion);
    EXPECT_EQ(d.protocol.getNumTrials(), settings.trials);
    EXPECT_LE(d.predicted.criterion, d.reference.criterion);
    EXPECT_NEAR(d.predicted.criterion, d.steps.back().criterion, 1e-12);
    EXPECT_EQ(d.reference.trials, 15);
    settings.ownModelCriterion = false;
    const DesignResult w = designProtocol(prior, settings, thesis);
    ASSERT_FALSE(w.steps.empty());
    for (std::size_t k = 1; k < w.steps.size(); ++k) EXPECT_LT(w.steps[k].criterion, w.steps[k - 1].criterion);
    EXPECT_LE(w.protocol.getNumTrials(), settings.trials);
    EXPECT_NEAR(w.predicted.criterion, w.steps.back().criterion, 1e-12);
}

// Freed slow-fibre fractions are informed by submaximal efforts: with the identifier's own model as
// truth (biceps F_slow shifted by +0.10, everything else at the prior mean) and noise-free data at 1 %
// assumed noise, the MAP estimate moves from the prior mean (0) at least a third of the way to the
// truth without overshooting it, and the mass stays within 10 % (the shift trades off against
// strength and fascicle length, and the prior sd 0.08 shrinks it). Held fixed (the
// default), the shift is not a parameter.
TEST(ExperimentDesign, FreedSlowFractionsAreInformedBySubmaximalEfforts) {
    constexpr double kMinShift = 0.10 / 3, kMaxShift = 0.10 + 0.01, kMassTol = 0.10;
    const Population prior = makePrior();
    SynergistOptions options;
    options.freeSlowFraction = true;
    options.noiseLevel = 0.01;
    std::vector<TorqueCondition> conditions;
    for (double q : {30.0, 75.0, 120.0}) conditions.push_back({q, Effort::Flexion, 1.0, 3});
    for (double q : {15.0, 45.0, 75.0, 105.0, 135.0}) conditions.push_back({q, Effort::Flexion, 0.3, 3});
    const SynergistModel model(prior, options, conditions);
    const std::vector<std::string> names = model.getParameterNames();
    auto index = [&](const std::string& n) { return int(std::find(names.begin(), names.end(), n) - names.begin()); };
    std::vector<double> x = model.getPriorMean();
    x[index("biceps_slow_fraction_shift")] = 0.10;
    const std::vector<double> clean = model.calcTorques(x.data());
    std::vector<TorqueObservation> data;
    for (std::size_t c = 0; c < conditions.size(); ++c)
        for (int r = 0; r < 2; ++r) {
            TorqueObservation o;
            o.flexionDeg = conditions[c].flexionDeg;
            o.level = conditions[c].level;
            o.repetition = r;
            o.torque = clean[c];
            data.push_back(o);
        }
    const MuscleEstimate e = identifySynergistAware(prior, data, options);
    auto nuisance = [&](const std::string& n) {
        const auto it = std::find(e.nuisanceNames.begin(), e.nuisanceNames.end(), n);
        return it == e.nuisanceNames.end() ? NAN : e.nuisance[it - e.nuisanceNames.begin()];
    };
    EXPECT_GE(nuisance("biceps_slow_fraction_shift"), kMinShift) << e.message;
    EXPECT_LE(nuisance("biceps_slow_fraction_shift"), kMaxShift) << e.message;
    EXPECT_NEAR(e.mass / prior.base.biceps().mass, 1.0, kMassTol);
    options.freeSlowFraction = false;
    const MuscleEstimate fixed = identifySynergistAware(prior, data, options);
    EXPECT_TRUE(std::find(fixed.nuisanceNames.begin(), fixed.nuisanceNames.end(), "biceps_slow_fraction_shift") ==
                fixed.nuisanceNames.end());
}

// Forearm postures as candidates (issue 31): with postures allowed the design reads both transducer axes
// and may pick flexion MVCs in other postures and supination or pronation MVCs. Minimising the fit's own
// Laplace widths it buys flexion MVCs in other postures whose information the population's per-muscle
// variation takes back (its widened L0T width is far above its own); minimising the widened widths (the
// default) it ends narrower in the widths the identifier reports. Its protocol predicts alike when read
// back (both axes, postures and all), and a model whose forearm does not rotate is refused.
TEST(ExperimentDesign, PosturesAreCandidatesAndTheWidenedCriterionIsNotFooledByThem) {
    constexpr double kSame = 1e-9;
    const Population prior = makePrior();
    DesignSettings settings;
    settings.draws = 8;
    settings.flexionDeg = {30, 90, 135};
    settings.postures = {-60, 60};
    settings.budgetMinutes = 100;
    TorqueProtocol thesis;
    const DesignResult widened = designChannelProtocol(prior, settings, thesis);
    settings.ownModelCriterion = true;
    const DesignResult own = designChannelProtocol(prior, settings, thesis);
    EXPECT_TRUE(widened.protocol.forearmTorque);
    EXPECT_TRUE(std::any_of(own.protocol.conditions.begin(), own.protocol.conditions.end(),
                            [](const TorqueCondition& c) { return !std::isnan(c.rotationDeg); }));
    std::printf("postures allowed: widened widths of the design by the widened criterion %.2f %% / %.2f mm, by the "
                "own-model criterion %.2f %% / %.2f mm (its own widths %.2f %% / %.2f mm)\n",
                100 * widened.predicted.massSdConsidered, 1000 * widened.predicted.tendonSdConsidered,
                100 * own.predicted.massSdConsidered, 1000 * own.predicted.tendonSdConsidered, 100 * own.predicted.massSd,
                1000 * own.predicted.tendonSd);
    EXPECT_GT(own.predicted.tendonSdConsidered, 1.3 * own.predicted.tendonSd);   // the trap
    EXPECT_LT(widened.predicted.tendonSdConsidered, own.predicted.tendonSdConsidered);
    settings.ownModelCriterion = false;
    const ProtocolPrediction again = predictProtocol(prior, widened.protocol, settings);
    EXPECT_NEAR(again.tendonSdConsidered, widened.predicted.tendonSdConsidered, kSame * widened.predicted.tendonSdConsidered);
    EXPECT_NEAR(again.massSd, widened.predicted.massSd, kSame * widened.predicted.massSd);
    EXPECT_THROW(designChannelProtocol(loadPopulation(findAsset("subjects/elbow_population.yaml")), settings, thesis),
                 InputError);
}

// Issue 31, design across channels: the picks' minutes add up to the written protocol's lab minutes
// (counted a second way, LabCosts::calcMinutes) within the budget; predicting the written protocol
// reproduces the design's own prediction (rows built from the protocol file's fields instead of the
// candidates); channels shrink the predicted mass width below the torque-only reference; a budget that
// fits no MVC block is refused.
TEST(ExperimentDesign, ChannelDesignStaysWithinItsBudgetAndItsProtocolPredictsAlike) {
    constexpr double kSame = 1e-9;  // relative: the same posterior computed from the same rows
    const Population prior = makePrior();
    DesignSettings settings;
    settings.draws = 4;
    settings.flexionDeg = {30, 90, 135};
    settings.budgetMinutes = 70;
    TorqueProtocol thesis;
    const DesignResult d = designChannelProtocol(prior, settings, thesis);
    double minutes = 0;
    for (const DesignStep& s : d.steps) minutes += s.minutes;
    EXPECT_LE(minutes, settings.budgetMinutes);
    EXPECT_NEAR(minutes, settings.costs.calcMinutes(d.protocol), 1e-9);
    EXPECT_TRUE(d.protocol.hasChannels());
    const ProtocolPrediction again = predictProtocol(prior, d.protocol, settings);
    EXPECT_NEAR(again.massSd, d.predicted.massSd, kSame * d.predicted.massSd);
    EXPECT_NEAR(again.tendonSd, d.predicted.tendonSd, kSame * d.predicted.tendonSd);
    EXPECT_LT(d.predicted.massSd, d.reference.massSd);
    // The protocol reads back as written.
    const TorqueProtocol back = readTorqueProtocol([&] {
        const std::string path = ::testing::TempDir() + "armsim_channel_design.yaml";
        std::FILE* f = std::fopen(path.c_str(), "w");
        const std::string text = formatTorqueProtocol(d.protocol);
        std::fwrite(text.data(), 1, text.size(), f);
        std::fclose(f);
        return path;
    }());
    EXPECT_EQ(back.volumeScan, d.protocol.volumeScan);
    EXPECT_EQ(back.anthropometry, d.protocol.anthropometry);
    settings.budgetMinutes = 5;
    EXPECT_THROW(designChannelProtocol(prior, settings, thesis), InputError);
    // A budget for thousands of trials: no condition gets more repetitions than a protocol may hold
    // (100; the design used to pick 1,827 of one and fail after its work), and the protocol validates.
    settings.budgetMinutes = 10000;
    const DesignResult large = designChannelProtocol(prior, settings, thesis);
    for (const TorqueCondition& c : large.protocol.conditions) EXPECT_LE(c.repetitions, 100);
    EXPECT_NO_THROW(large.protocol.validate());
}

// The two-axis protocol (issue 31): the recommended protocol's rows plus the forearm axis and supination
// efforts. The design predicts it narrower in ln M and L0T than the recommended protocol on the twin's
// prior (measured 2026-11-26: 7.4 % / 8.0 mm against 7.7 % / 8.5 mm; the validation obtained 7.9 % /
// 9.6 mm against 8.0 % / 10.6 mm, README), and the rotators' scales are informed only with the forearm
// axis (their posterior sd below the prior's).
TEST(ExperimentDesign, TwoAxisProtocolIsPredictedNarrowerThanTheRecommended) {
    const Population prior = loadDefaultPopulation();
    DesignSettings settings;
    const ProtocolPrediction one = predictProtocol(prior, readTorqueProtocol(findAsset("protocols/recommended.yaml")), settings);
    const ProtocolPrediction two = predictProtocol(prior, readTorqueProtocol(findAsset("protocols/two_axis.yaml")), settings);
    std::printf("recommended: %.2f %% / %.2f mm; two_axis: %.2f %% / %.2f mm\n", 100 * one.massSd, 1000 * one.tendonSd,
                100 * two.massSd, 1000 * two.tendonSd);
    EXPECT_LT(two.massSd, one.massSd);
    EXPECT_LT(two.tendonSd, one.tendonSd);
    const auto sup = std::find(two.parameterNames.begin(), two.parameterNames.end(), "ln_SUP_mass_scale");
    ASSERT_NE(sup, two.parameterNames.end());
    const std::size_t j = std::size_t(sup - two.parameterNames.begin());
    EXPECT_LT(two.posteriorSd[j], 0.9 * one.posteriorSd[j]);  // recommended: held, its sd the prior's
}

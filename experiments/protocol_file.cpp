#include "basics/files.h"
#include "basics/format.h"
#include "basics/numbers.h"
#include "basics/param_node.h"
#include "experiments/protocol.h"
#include "experiments/protocol_run.h"
#include "model/geometry.h"
#include "muscles/muscle_file.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>

namespace fs = std::filesystem;

namespace armsim {

namespace {

// ---- Reading --------------------------------------------------------------------------------------

std::vector<double> readRange(const ParamNode& parent, const std::string& key, const Bound& bound) {
    const ParamNode r = parent.child(key);
    const double from = r.getNumber("from", bound), to = r.getNumber("to", bound);
    const double step = r.getNumber("step", Bound::positive(bound.unit));
    r.finish();
    if (to < from)
        throw InputError(r.where("to") + ": field " + describeField(r.path("to")) + " = " + formatNumber(to) + " is below 'from' = " +
                         formatNumber(from) + ": expected from <= to");
    if (to > from && step > to - from)   // one value: the sweep's other end would be dropped unseen
        throw InputError(r.where("step") + ": field " + describeField(r.path("step")) + " = " + formatNumber(step) +
                         " is longer than the range " + formatNumber(from) + " to " + formatNumber(to) +
                         ": expected at most " + formatNumber(to - from) + " (from = to sweeps one value)");
    std::vector<double> v;
    for (int k = 0;; ++k) {
        const double x = from + k * step;
        if (x > to + 1e-9 * std::max(1.0, std::abs(to))) break;
        v.push_back(std::min(x, to));
        if (v.size() > 10000)
            throw InputError(r.where("step") + ": field " + describeField(r.path("step")) + " = " + formatNumber(step) +
                             " over " + formatNumber(from) + " to " + formatNumber(to) + " gives " +
                             formatNumber(std::floor((to - from) / step) + 1) + " values: expected at most 10000 (a longer step)");
    }
    return v;
}

std::vector<double> requireNonEmpty(const ParamNode& n, const std::string& key, std::vector<double> v,
                                    const char* what) {
    if (v.empty())
        throw InputError(n.where(key) + ": field " + describeField(n.path(key)) + " is empty: expected at least one " + what);
    // A value twice would be one condition run twice under one name (its trial files overwritten).
    for (std::size_t i = 0; i < v.size(); ++i)
        for (std::size_t j = 0; j < i; ++j)
            if (v[i] == v[j])
                throw InputError(n.where(key) + ": field " + describeField(n.path(key) + "[" + std::to_string(i) + "]") +
                                 " = " + formatNumber(v[i]) + " is also entry " + std::to_string(j + 1) +
                                 ": expected each " + what + " once (repeat conditions with `repetitions:`)");
    return v;
}

/// Maps EmgAcquisitionSettings' field names to the protocol's keys.
std::string acquisitionKey(const std::string& field) {
    static const std::map<std::string, std::string> keys = {
        {"gain", "gain"},
        {"outputRate", "output_rate"},
        {"bandHigh", "band_high"},
        {"bandLow", "band_low"},
        {"bandOrder", "band_order"},
        {"mainsFrequency", "mains_frequency"},
        {"notchQuality", "notch_quality"},
        {"antiAliasCutoff", "anti_alias_cutoff"},
        {"antiAliasOrder", "anti_alias_order"},
        {"mainsAmplitude", "mains_amplitude"},
        {"electrodeNoiseRms", "electrode_noise_rms"}};
    const auto it = keys.find(field);
    return it == keys.end() ? field : it->second;
}

void readEmg(const ParamNode& n, Protocol& p) {
    const Bound any = Bound::any();
    SurfaceEmgSettings& e = p.emg;
    EmgAcquisitionSettings& a = e.acquisition;
    p.emgEnabled = n.getBool("enabled", true);
    e.internalRate = n.getNumber("internal_rate", Bound::positive("Hz"), e.internalRate);
    e.isiCv = n.getNumber("isi_cv", any, e.isiCv);
    e.trainsPerUnit = n.getInt("trains_per_unit", 1, 1000, e.trainsPerUnit);
    e.muapAmplitude = n.getNumber("muap_amplitude", any, e.muapAmplitude);
    e.muapWidthSlow = n.getNumber("muap_width_slow", any, e.muapWidthSlow);
    e.muapWidthFast = n.getNumber("muap_width_fast", any, e.muapWidthFast);
    p.emgRmsWindow = n.getNumber("rms_window", Bound::positive("s"), p.emgRmsWindow);
    a.gain = n.getNumber("gain", any, a.gain);
    a.bandLow = n.getNumber("band_low", any, a.bandLow);
    a.bandHigh = n.getNumber("band_high", any, a.bandHigh);
    a.bandOrder = n.getInt("band_order", 1, 10, a.bandOrder);
    a.notch = n.getBool("notch", a.notch);
    a.notchQuality = n.getNumber("notch_quality", any, a.notchQuality);
    a.mainsFrequency = n.getNumber("mains_frequency", any, a.mainsFrequency);
    a.mainsAmplitude = n.getNumber("mains_amplitude", any, a.mainsAmplitude);
    a.electrodeNoiseRms = n.getNumber("electrode_noise_rms", any, a.electrodeNoiseRms);
    a.antiAliasCutoff = n.getNumber("anti_alias_cutoff", any, a.antiAliasCutoff);
    a.antiAliasOrder = n.getInt("anti_alias_order", 1, 20, a.antiAliasOrder);
    a.zeroPhase = n.getBool("zero_phase", a.zeroPhase);
    a.outputRate = p.trial.sampleRate;  // the EMG is sampled with the other channels
    n.finish();
    if (!p.emgEnabled) return;   // no EMG is made: its filters need not suit the sample rate
    try {
        e.validate();
    } catch (const FieldError& err) {
        if (err.getField() == "outputRate")
            throw InputError(n.where() + ": the EMG output rate is trial.sample_rate = " + fmt::format("{:g}", a.outputRate) +
                             " Hz: " + err.getDetail());
        std::string detail = err.getDetail();
        const std::string key = acquisitionKey(err.getField());
        const double value = key == "band_high" ? a.bandHigh
                             : key == "anti_alias_cutoff" ? a.antiAliasCutoff
                             : key == "mains_frequency" ? a.mainsFrequency
                                                        : kNaN;
        if (value >= a.outputRate / 2)   // past Nyquist: the sample rate, not the frequency, may be what to change
            detail += fmt::format(" (frequencies stay below half of trial.sample_rate = {:g} Hz: the EMG is sampled "
                                  "with the other channels; raise sample_rate or lower the frequency)", a.outputRate);
        n.throwLocated(FieldError(n.path(key), detail));
    }
}

IsometricTrialSettings readTrialTemplate(const ParamNode& n, const ArmParameters& arm) {
    IsometricTrialSettings s;
    s.restDuration = n.getNumber("rest", Bound::positive("s"), s.restDuration);
    s.riseTime = n.getNumber("rise", Bound::nonNegative("s"), s.riseTime);
    s.holdDuration = n.getNumber("hold", Bound::positive("s"), s.holdDuration);
    s.sampleRate = n.getNumber("sample_rate", Bound::positive("Hz"), s.sampleRate);
    s.averagingWindow = n.getNumber("averaging_window", Bound::positive("s"), std::min(s.averagingWindow, s.holdDuration));
    s.integration.accuracy = n.getNumber("accuracy", bounds::kTrialAccuracy, s.integration.accuracy);
    n.finish();
    s.elbowAngle = degToRad(0.5 * (arm.minElbowAngleDeg + arm.maxElbowAngleDeg));
    n.rethrowWithLocation([&] { s.validate(arm); });
    return s;
}

}  // namespace

namespace {

// The protocol's `subject` section (model, arm and muscle files resolved against the protocol's folder,
// effort overrides) and the subject it names, loaded.
ArmSetup readProtocolSubjectSection(const ParamNode& root, Protocol& p) {
    if (root.has("subject")) {
        const ParamNode s = root.child("subject");
        p.model = s.getString("model", p.model);
        p.armFile = s.getString("arm", p.armFile);
        p.muscleFile = s.getString("muscle", p.muscleFile);
        const Bound any = Bound::any();
        if (s.has("voluntary_activation")) p.voluntaryActivation = s.getNumber("voluntary_activation", any);
        if (s.has("co_contraction")) p.coContraction = s.getNumber("co_contraction", any);
        if (s.has("trial_cv")) p.trialCv = s.getNumber("trial_cv", any);
        if (s.has("fatigue")) p.fatigue = s.getNumber("fatigue", any);
        s.finish();
    }
    auto resolve = [&](const std::string& key, const std::string& file) {
        const std::string relative = root.getDirectory().empty() ? file : root.getDirectory() + "/" + file;
        if (doesPathExist(relative)) return relative;
        try {
            return findAsset(file);
        } catch (const InputError& e) {
            throw InputError(root.where("subject") + ": field 'subject." + key + "': " + e.what());
        }
    };
    if (!p.armFile.empty()) p.armFile = resolve("arm", p.armFile);
    if (!p.muscleFile.empty()) p.muscleFile = resolve("muscle", p.muscleFile);
    if (p.model.find('/') != std::string::npos || p.model.find(".yaml") != std::string::npos)
        p.model = resolve("model", p.model);
    ArmSetup subject;
    try {
        subject = loadProtocolSubject(p);
    } catch (const InputError& e) {
        throw InputError(root.where("subject") + ": subject: " + e.what());
    }
    return subject;
}

// The `sensors` section (transducer noise, EMG) and the EMG chain checked against the sample rate.
void readProtocolSensors(const ParamNode& root, Protocol& p, bool armTrials) {
    if (armTrials && root.has("sensors")) {
        const ParamNode s = root.child("sensors");
        if (s.has("transducer")) {
            const ParamNode t = s.child("transducer");
            // A strap transducer reads to about 1 N (the thesis's: 50 kgf full scale, 5.3.2); 50 N of noise,
            // a tenth of that scale, is a value in other units (mN, or kgf read as N).
            p.transducerNoiseRms = t.getNumber("noise_rms", Bound::closed(0, 50, "N"), 0.0);
            t.finish();
        }
        p.emg.acquisition.outputRate = p.trial.sampleRate;
        if (s.has("emg")) {
            const ParamNode emg = s.child("emg");
            readEmg(emg, p);
            if (!p.emgEnabled && p.kind == ProtocolKind::Submaximal)   // its levels are EMG feedback: no EMG, no level
                throw InputError(emg.where("enabled") + ": field 'sensors.emg.enabled' = false: a submaximal protocol holds "
                                 "each level by EMG feedback: expected EMG enabled (or kind: mvc)");
        }
        s.finish();
    }
    p.emg.acquisition.outputRate = p.trial.sampleRate;
    if (armTrials && p.emgEnabled) {
        try {
            p.emg.validate();
        } catch (const FieldError& e) {
            throw InputError(root.where("trial") + ": trial.sample_rate does not suit the EMG defaults: " + e.what());
        }
    }
}

// The whole run's size: every trial's samples (and their CSV, .sto and EMG) are kept and written.
void checkProtocolSize(const std::string& path, const Protocol& p) {
    if (detail::getProtocolKindSpec(p.kind).armTrials) {
        const double trials = double(p.elbowAngles.size()) * std::max<std::size_t>(1, p.levels.size()) * p.repetitions;
        const double perTrial = double(calcNumSamples(p.trial.getDuration(), p.trial.sampleRate));
        const double rows = trials * perTrial;
        if (rows > 1e8)
            throw InputError(path + ": " + formatNumber(trials) + " trials x " + formatNumber(perTrial) + " samples = " + formatNumber(rows) +
                             " samples in the run: expected at most 1e+08 (fewer repetitions, a shorter hold or a lower "
                             "sample rate)");
    }
}

}  // namespace

Protocol readProtocol(const std::string& path) {
    Protocol p;
    p.sourcePath = path;
    p.sourceText = readFileText(path);
    const ParamNode root = ParamNode::loadString(p.sourceText, path);
    p.name = root.getString("name");
    if (p.name.empty() || p.name.find_first_of("/\\ \t") != std::string::npos)
        throw InputError(root.where("name") + ": field 'name' = '" + p.name +
                         "': expected a non-empty name without spaces or slashes");
    p.description = root.getString("description", "");
    root.getString("kind");  // required
    std::vector<std::string> kindNames;
    for (const detail::ProtocolKindSpec& k : detail::getProtocolKindSpecs()) kindNames.push_back(k.name);
    const std::string kindName = root.getChoice("kind", kindNames, kindNames.front());
    const detail::ProtocolKindSpec* kind = nullptr;
    for (const detail::ProtocolKindSpec& k : detail::getProtocolKindSpecs())
        if (kindName == k.name) kind = &k;
    p.kind = kind->kind;
    const bool armTrials = kind->armTrials;

    const ArmSetup subject = readProtocolSubjectSection(root, p);
    const ArmParameters& arm = subject.arm;
    const double pMax = subject.calcBicepsParameters().maxPathLength;

    if (armTrials) {
        const double seed = root.getNumber("seed", Bound::closed(0, 9007199254740992.0));
        if (seed != std::floor(seed))
            throw InputError(root.where("seed") + ": field 'seed' = " + fmt::format("{:g}", seed) + ": expected a whole number");
        p.seed = std::uint64_t(seed);
        p.randomOrder = root.getChoice("order", {"random", "listed"}, "random") == "random";
        p.repetitions = root.getInt("repetitions", 1, 1000, 1);
        p.interTrialRest = root.getNumber("inter_trial_rest", Bound::nonNegative("s"), 0.0);
        p.trial = root.has("trial") ? readTrialTemplate(root.child("trial"), arm) : p.trial;
    }

    const ParamNode c = root.child("conditions");
    kind->readConditions(c, p, arm, pMax);
    c.finish();
    readProtocolSensors(root, p, armTrials);
    root.finish();
    checkProtocolSize(path, p);
    return p;
}

ArmSetup loadProtocolSubject(const Protocol& protocol) {
    ArmSetup s = loadModel(protocol.model);
    if (!protocol.armFile.empty()) s.arm = loadArmParameters(findAsset(protocol.armFile));
    if (!protocol.muscleFile.empty()) {
        const std::string name = s.biceps().name;
        s.biceps() = loadMuscleParameters(findAsset(protocol.muscleFile));
        s.biceps().name = name;
        s.muscles[s.primary].maxPathFromRange = true;
    }
    if (protocol.voluntaryActivation) s.effort.voluntaryActivation = *protocol.voluntaryActivation;
    if (protocol.coContraction) s.effort.coContraction = *protocol.coContraction;
    if (protocol.trialCv) s.effort.trialCv = *protocol.trialCv;
    if (protocol.fatigue) s.effort.fatigue = *protocol.fatigue;
    resolveMaxPathLengths(s);
    s.validate();
    return s;
}

namespace detail {

namespace {

// The elbow angles a kind's trials may use: the moment arm vanishes at full extension, so efforts there
// have no measurable force.
Bound getTrialAngleBound(const ArmParameters& arm) {
    return {arm.minElbowAngleDeg, arm.maxElbowAngleDeg, false, true, "deg, the subject's elbow range"};
}

std::vector<double> toRadians(std::vector<double> v) {
    for (double& a : v) a = degToRad(a);
    return v;
}

}  // namespace

void readMvcConditions(const ParamNode& c, Protocol& p, const ArmParameters& arm, double) {
    p.elbowAngles = toRadians(
        requireNonEmpty(c, "elbow_angles_deg", c.getNumbers("elbow_angles_deg", getTrialAngleBound(arm)), "angle"));
    p.levels = {1.0};
}

void readSubmaximalConditions(const ParamNode& c, Protocol& p, const ArmParameters& arm, double) {
    p.elbowAngles = toRadians(
        requireNonEmpty(c, "elbow_angles_deg", c.getNumbers("elbow_angles_deg", getTrialAngleBound(arm)), "angle"));
    std::vector<double> pct =
        requireNonEmpty(c, "levels_pct_mvc", c.getNumbers("levels_pct_mvc", {0, 100, true, false, "% MVC"}), "level");
    if (std::find(pct.begin(), pct.end(), 100.0) == pct.end()) {
        const bool fractions = std::all_of(pct.begin(), pct.end(), [](double l) { return l <= 1; });
        std::string percent;   // what fractions would have meant
        for (double l : pct) percent += (percent.empty() ? "" : ", ") + formatNumber(100 * l, 6);
        throw InputError(c.where("levels_pct_mvc") + ": field 'conditions.levels_pct_mvc' lacks 100: the 100 % "
                         "MVC trials are the reference of the other levels and of the EMG normalisation" +
                         (fractions ? std::string("; every level is at most 1 % MVC: fractions? expected percent of MVC ([") +
                                          percent + "])"
                                    : std::string()));
    }
    for (double l : pct) p.levels.push_back(l / 100.0);
}

void readForceLengthConditions(const ParamNode& c, Protocol& p, const ArmParameters& arm, double pMax) {
    if (c.has("elbow_angle_range_deg"))
        p.elbowAngles = toRadians(readRange(c, "elbow_angle_range_deg", getTrialAngleBound(arm)));
    p.maxPathLength = c.getNumber("max_path_length", bounds::kPathLength, 0.0);
    const double limit = p.maxPathLength > 0 ? p.maxPathLength : pMax;
    if (c.has("path_range"))
        p.pathLengths = readRange(c, "path_range", {0, limit, true, false,
                                                   p.maxPathLength > 0 ? "m, up to max_path_length"
                                                                       : "m, up to the muscle's P_max"});
    p.levels = {1.0};
    if (p.elbowAngles.empty() && p.pathLengths.empty())
        throw InputError(c.where() + ": field 'conditions' has no trials: expected elbow_angle_range_deg "
                         "and/or path_range");
}

void readCompositionConditions(const ParamNode& c, Protocol& p, const ArmParameters&, double pMax) {
    const ParamNode su = c.child("slow_units"), fu = c.child("fast_units");
    p.slowUnitsFrom = su.getInt("from", 0, 100);
    p.slowUnitsTo = su.getInt("to", p.slowUnitsFrom, 100);
    p.fastUnitsFrom = fu.getInt("from", 0, 100);
    p.fastUnitsTo = fu.getInt("to", p.fastUnitsFrom, 100);
    su.finish();
    fu.finish();
    if (p.slowUnitsTo == 0 && p.fastUnitsTo == 0)   // a grid's 0 + 0 corner is its passive reference, not a grid
        throw InputError(c.where("fast_units") + ": fields 'conditions.slow_units' and 'conditions.fast_units' both end at 0: "
                         "the grid's one cell has no motor unit (passive force only): expected units in some cell");
    p.compositionActivation = c.getNumber("activation", Bound::closed(0, 1), p.compositionActivation);
    p.compositionPath = c.getNumber("path_length", {0, pMax, true, false, "m, up to the muscle's P_max"},
                                    p.compositionPath);
}

}  // namespace detail

}  // namespace armsim

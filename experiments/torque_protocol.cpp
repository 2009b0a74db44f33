#include "experiments/torque_protocol.h"

#include "experiments/channels.h"

#include "basics/files.h"
#include "basics/param_node.h"
#include "basics/plot.h"
#include "basics/portable_random.h"
#include "basics/table.h"
#include "basics/parallel.h"
#include "model/geometry.h"
#include "model/osim_arm.h"
#include "model/osim_forward.h"
#include "model/osim_trial.h"
#include "model/trial.h"
#include "muscles/muscle_file.h"

#include <algorithm>
#include <iterator>
#include <map>
#include <set>
#include <tuple>

namespace armsim {

namespace {

std::string conditionField(std::size_t k, const char* key) {
    return "conditions[" + std::to_string(k) + "]." + key;
}

ConditionKey conditionKey(double flexionDeg, Effort effort, double level, double rotationDeg) {
    return {flexionDeg, int(effort), level, std::isnan(rotationDeg) ? INFINITY : rotationDeg};
}

}  // namespace

int getEffortCode(Effort e) {
    switch (e) {
        case Effort::Flexion: return 1;
        case Effort::Extension: return -1;
        case Effort::Supination: return 2;
        case Effort::Pronation: return -2;
    }
    return 0;
}

std::vector<TorqueCondition> TorqueProtocol::makeFlexionMvcs(const std::vector<double>& flexionDeg, int repetitions) {
    std::vector<TorqueCondition> out;
    for (double q : flexionDeg) out.push_back({q, Effort::Flexion, 1.0, repetitions});
    return out;
}

int TorqueProtocol::getNumTrials() const {
    int n = 0;
    for (const TorqueCondition& c : conditions) n += c.repetitions;
    return n;
}

bool TorqueProtocol::usesEmg() const {
    return std::any_of(conditions.begin(), conditions.end(), [](const TorqueCondition& c) { return c.level < 1; });
}

bool TorqueProtocol::readsForearmTorque() const {
    return forearmTorque ||
           std::any_of(conditions.begin(), conditions.end(), [](const TorqueCondition& c) { return isForearmEffort(c.effort); });
}

bool TorqueProtocol::hasChannels() const {
    return !volumeScan.empty() || anthropometry ||
           std::any_of(conditions.begin(), conditions.end(), [](const TorqueCondition& c) { return c.ultrasound || c.emg; });
}

bool TorqueProtocol::usesOsimModel() const { return population.empty() && isOsimModel(model); }

namespace {

// What an OpenSim model's protocol cannot have: the channels, the forearm axis and postures need an
// armsim model's muscles and forearm.
void checkOsimProtocol(const TorqueProtocol& p) {
    const std::string why = "an OpenSim model's protocol reads the torque about its coordinate alone";
    for (std::size_t k = 0; k < p.conditions.size(); ++k) {
        const TorqueCondition& c = p.conditions[k];
        if (isForearmEffort(c.effort))
            throw FieldError(conditionField(k, "effort"), std::string("= ") + getEffortName(c.effort) + ": " + why +
                                                              ": expected flexion (the positive direction) or extension");
        if (!std::isnan(c.rotationDeg))
            throw FieldError(conditionField(k, "rotation_deg"), why + ": expected no forearm posture");
        if (c.ultrasound || c.emg)
            throw FieldError(conditionField(k, "channels"), why + ": expected torque only");
        checkField(conditionField(k, "flexion_deg"), c.flexionDeg, Bound::closed(-3600, 3600, "deg, the coordinate's value"));
    }
    if (!p.volumeScan.empty() || p.anthropometry || p.forearmTorque)
        throw FieldError("measurements", why + ": expected no volume scan, anthropometry or forearm torque");
}

}  // namespace

void TorqueProtocol::validate() const {
    if (conditions.empty()) throw FieldError("conditions", "is empty: expected at least one condition");
    const bool osim = usesOsimModel();
    if (!coordinate.empty() && !osim)
        throw FieldError("subject.coordinate", "= '" + coordinate + "': only an OpenSim model (subject.model: NAME.osim) has coordinates to name");
    if (osim) checkOsimProtocol(*this);
    std::set<ConditionKey> seen;
    for (std::size_t k = 0; k < conditions.size(); ++k) {
        const TorqueCondition& c = conditions[k];
        if (!osim) checkField(conditionField(k, "flexion_deg"), c.flexionDeg, Bound::closed(0, 180, "deg, 0 = extended"));
        checkField(conditionField(k, "level"), c.level, Bound{0, 1, true, false, "fraction of maximal"});
        checkField(conditionField(k, "repetitions"), c.repetitions, Bound::closed(1, 100));
        if (isForearmEffort(c.effort) && (c.ultrasound || c.emg))
            throw FieldError(conditionField(k, "channels"),
                             std::string("a ") + getEffortName(c.effort) +
                                 " effort is read by the transducer alone: expected ultrasound and EMG in flexion "
                                 "or extension efforts only");
        if (!std::isnan(c.rotationDeg)) {
            checkField(conditionField(k, "rotation_deg"), c.rotationDeg, Bound::closed(-180, 180, "deg, + = supination"));
            if (c.ultrasound || c.emg)
                throw FieldError(conditionField(k, "channels"),
                                 "ultrasound and EMG are read at the model's forearm posture only: expected torque "
                                 "alone with rotation_deg (or no rotation_deg)");
        }
        if (!seen.insert(conditionKey(c.flexionDeg, c.effort, c.level, c.rotationDeg)).second)
            throw FieldError(conditionField(k, "flexion_deg"),
                             "the same condition (angle, effort, level, posture) is listed twice: expected each "
                             "once (raise its repetitions instead)");
    }
    std::vector<double> angles;
    for (const TorqueCondition& c : conditions) angles.push_back(c.flexionDeg);
    if (const std::size_t k = findFirstFractional(angles); k < angles.size())
        checkDegreesNotRadians(conditionField(k, "flexion_deg"), angles);
    std::vector<double> rotations;    // the postures given (NaN: the model's own)
    std::vector<std::size_t> givenAt; // their conditions
    for (std::size_t k = 0; k < conditions.size(); ++k)
        if (std::isfinite(conditions[k].rotationDeg)) rotations.push_back(conditions[k].rotationDeg), givenAt.push_back(k);
    if (const std::size_t k = findFirstFractional(rotations); k < rotations.size())
        checkDegreesNotRadians(conditionField(givenAt[k], "rotation_deg"), rotations);
    checkField("trial.rest", restDuration, Bound::positive("s"));
    checkField("trial.hold", holdDuration, Bound::positive("s"));
    checkField("trial.averaging_window", averagingWindow, {0, holdDuration, true, false, "s, within the hold"});
    checkField("trial.sample_rate", sampleRate, Bound::positive("Hz"));
    checkField("subject.transducer_noise", transducerNoise, Bound::closed(0, 0.5));
    checkField("subject.index", subjectIndex, Bound::closed(0, 1e6));
    for (std::size_t k = 0; k < volumeScan.size(); ++k)
        if (std::find(volumeScan.begin(), volumeScan.begin() + long(k), volumeScan[k]) != volumeScan.begin() + long(k))
            throw FieldError("measurements.volume_scan[" + std::to_string(k) + "]",
                             "'" + volumeScan[k] + "' is listed twice: expected each muscle once");
    const ChannelNoise& n = channelNoise;
    // Lower bounds: the finest sd a channel file may give (experiments/channels.h), so what a protocol
    // writes reads back (an EMG sd is emg x max(|value|, kEmgFloor); an upper arm is under 1 m long).
    checkField("channel_noise.fascicle_length", n.fascicleLength, Bound{kMinChannelSdRelative, 0.5, false, true, "relative sd"});
    checkField("channel_noise.volume", n.volume, Bound{kMinChannelSdRelative, 0.5, false, true, "relative sd"});
    checkField("channel_noise.emg", n.emg, Bound{kMinChannelSdEmg / kEmgFloor, 1, false, true, "relative sd"});
    checkField("channel_noise.emg_crosstalk", n.emgCrosstalk, Bound::closed(0, 0.5));
    checkField("channel_noise.upper_arm_length", n.upperArmLength, Bound{kMinChannelSdRelative, 0.1, false, true, "m"});
}

std::string describeConditions(const TorqueProtocol& protocol) {
    using Key = std::tuple<int, double, int, int>;  // effort, level, repetitions, channels in first-seen order
    std::vector<Key> groups;
    std::map<Key, std::string> angles;
    for (const TorqueCondition& c : protocol.conditions) {
        const Key key = std::make_tuple(int(c.effort), c.level, c.repetitions, (c.ultrasound ? 1 : 0) + (c.emg ? 2 : 0));
        if (!angles.count(key)) groups.push_back(key);
        std::string& a = angles[key];
        a += (a.empty() ? "" : ", ") + formatNumber(c.flexionDeg);
    }
    std::string out;
    for (const auto& key : groups) {
        const auto [effort, level, repetitions, channels] = key;
        out += (out.empty() ? "" : "; ") + std::string(getEffortName(Effort(effort))) + " " +
               (level == 1 ? std::string("MVC") : formatNumber(100 * level) + " %") + " at " + angles[key] +
               " deg x " + std::to_string(repetitions);
        if (channels) out += std::string(" with ") + (channels & 1 ? "ultrasound" : "") + (channels == 3 ? " and " : "") +
                             (channels & 2 ? "EMG" : "");
    }
    if (!protocol.volumeScan.empty()) out += "; volume scan of " + formatList(protocol.volumeScan);
    if (protocol.anthropometry) out += "; anthropometry";
    if (protocol.readsForearmTorque()) out += "; forearm torque read";
    return out;
}

namespace {
OsimModel loadOsimProtocolModel(const TorqueProtocol& protocol);
}  // namespace

TorqueProtocol readTorqueProtocol(const std::string& path) {
    const ParamNode root = ParamNode::loadFile(path);
    TorqueProtocol p;
    p.source = path;
    p.name = root.getString("name");
    p.description = root.getString("description", "");
    root.getChoice("kind", {"torque"}, "torque");
    p.seed = unsigned(root.getInt("seed", 0, 2147483647, int(p.seed)));
    if (root.has("trial")) {
        const ParamNode t = root.child("trial");
        p.restDuration = t.getNumber("rest", Bound::positive("s"), p.restDuration);
        p.holdDuration = t.getNumber("hold", Bound::positive("s"), p.holdDuration);
        p.averagingWindow = t.getNumber("averaging_window", Bound::positive("s"), p.averagingWindow);
        p.sampleRate = t.getNumber("sample_rate", Bound::positive("Hz"), p.sampleRate);
        t.finish();
    }
    if (root.has("subject")) {
        const ParamNode s = root.child("subject");
        if (s.has("population") && s.has("model"))
            throw InputError(s.where() + ": 'subject' names both a population and a model: expected one of them");
        if (s.has("population")) {
            p.population = s.findFile("population", "population file", findAsset("subjects"));
            p.subjectIndex = s.getInt("index", 0, 1000000, 0);
        } else {
            p.model = s.getString("model", p.model);
            if (isOsimModel(p.model) && (p.model.find('/') != std::string::npos ||
                                         (p.model.size() > 5 && p.model.compare(p.model.size() - 5, 5, ".osim") == 0))) {
                // A file next to the protocol, or as given.
                const std::string relative = root.getDirectory().empty() ? p.model : root.getDirectory() + "/" + p.model;
                if (doesPathExist(relative)) p.model = relative;
            }
            p.coordinate = s.getString("coordinate", "");
            p.transducerNoise = s.getNumber("transducer_noise", Bound::closed(0, 0.5), p.transducerNoise);
        }
        s.finish();
    }
    if (root.has("measurements")) {
        const ParamNode m = root.child("measurements");
        if (m.has("volume_scan")) {
            p.volumeScan = m.getStrings("volume_scan");
            p.volumeScanWhere = m.where("volume_scan");
        }
        p.anthropometry = m.getBool("anthropometry", false);
        p.forearmTorque = m.getBool("forearm_torque", false);
        m.finish();
    }
    if (root.has("channel_noise")) {
        const ParamNode n = root.child("channel_noise");
        ChannelNoise& c = p.channelNoise;
        c.fascicleLength = n.getNumber("fascicle_length", Bound{0, 0.5, true, true, "relative sd"}, c.fascicleLength);
        c.volume = n.getNumber("volume", Bound{0, 0.5, true, true, "relative sd"}, c.volume);
        c.emg = n.getNumber("emg", Bound{0, 1, true, true, "relative sd"}, c.emg);
        c.emgCrosstalk = n.getNumber("emg_crosstalk", Bound::closed(0, 0.5), c.emgCrosstalk);
        c.upperArmLength = n.getNumber("upper_arm_length", Bound{0, 0.1, true, true, "m"}, c.upperArmLength);
        n.finish();
    }
    p.conditions.clear();
    for (const ParamNode& c : root.children("conditions")) {
        TorqueCondition tc;
        tc.flexionDeg = c.getNumber("flexion_deg", Bound::any());   // validate(): the range the subject's model has
        tc.effort = parseEffortName(c.getChoice("effort", {"flexion", "extension", "supination", "pronation"}, "flexion"));
        tc.level = c.getNumber("level", Bound{0, 1, true, false, "fraction of maximal"}, 1.0);
        tc.repetitions = c.getInt("repetitions", 1, 100, 1);
        if (c.has("rotation_deg")) tc.rotationDeg = c.getNumber("rotation_deg", Bound::closed(-180, 180, "deg, + = supination"));
        if (c.has("channels")) {
            const std::vector<std::string> channels = c.getStrings("channels");
            for (std::size_t i = 0; i < channels.size(); ++i) {
                const std::string& name = channels[i];
                if (std::find(channels.begin(), channels.begin() + long(i), name) != channels.begin() + long(i))
                    throw InputError(c.where("channels") + ": field " + describeField(c.path("channels")) + " lists '" + name +
                                     "' twice: expected each channel once");
                if (name == "ultrasound") tc.ultrasound = true;
                else if (name == "emg") tc.emg = true;
                else if (name != "torque")
                    throw InputError(c.where("channels") + ": field " + describeField(c.path("channels")) + " = '" + name +
                                     "': expected torque, ultrasound or emg");
            }
            if (std::find(channels.begin(), channels.end(), "torque") == channels.end())
                throw InputError(c.where("channels") + ": field " + describeField(c.path("channels")) +
                                 " leaves out torque: expected every effort to be read by the transducer (list torque)");
        }
        c.finish();
        p.conditions.push_back(tc);
    }
    root.finish();
    root.rethrowWithLocation([&] { p.validate(); });
    if (p.usesOsimModel()) root.rethrowWithLocation([&] { loadOsimProtocolModel(p); });
    return p;
}

std::string formatTorqueProtocol(const TorqueProtocol& p) {
    p.validate();
    std::string out = "name: " + p.name + "\nkind: torque\n";
    if (!p.description.empty()) out += "description: \"" + p.description + "\"\n";
    out += "seed: " + std::to_string(p.seed) + "\n";
    out += "trial:\n  rest: " + formatNumber(p.restDuration) + "              # s, relaxed; transducer tared at its start\n" +
           "  hold: " + formatNumber(p.holdDuration) + "              # s\n" +
           "  averaging_window: " + formatNumber(p.averagingWindow) + "  # s, end of the hold\n" +
           "  sample_rate: " + formatNumber(p.sampleRate) + "      # Hz\n";
    out += "subject:             # who `armsim protocol` runs it on\n";
    if (!p.population.empty())
        out += "  population: " + p.population + "\n  index: " + std::to_string(p.subjectIndex) + "\n";
    else
        out += "  model: " + p.model + "\n" + (p.coordinate.empty() ? "" : "  coordinate: " + p.coordinate + "\n") +
               "  transducer_noise: " + formatNumber(p.transducerNoise) + "\n";
    if (p.hasChannels() || p.forearmTorque) {
        std::string names;
        for (const std::string& v : p.volumeScan) names += (names.empty() ? "" : ", ") + v;
        out += "measurements: {volume_scan: [" + names + "]" +
               ", anthropometry: " + (p.anthropometry ? "true" : "false") +
               (p.forearmTorque ? ", forearm_torque: true" : "") + "}\n";
    }
    if (p.hasChannels()) {
        const ChannelNoise& n = p.channelNoise;
        out += "channel_noise: {fascicle_length: " + formatNumber(n.fascicleLength) + ", volume: " + formatNumber(n.volume) +
               ", emg: " + formatNumber(n.emg) + ", emg_crosstalk: " + formatNumber(n.emgCrosstalk) +
               ", upper_arm_length: " + formatNumber(n.upperArmLength) + "}  # relative sd; upper_arm_length in m\n";
    }
    out += "conditions:          # flexion_deg: 0 = extended; level: fraction of maximal (< 1: EMG feedback)\n";
    for (const TorqueCondition& c : p.conditions) {
        out += "  - {effort: " + std::string(getEffortName(c.effort)) + ", flexion_deg: " + formatNumber(c.flexionDeg) +
               ", level: " + formatNumber(c.level) + ", repetitions: " + std::to_string(c.repetitions);
        if (!std::isnan(c.rotationDeg)) out += ", rotation_deg: " + formatNumber(c.rotationDeg);
        if (c.ultrasound || c.emg)
            out += std::string(", channels: [torque") + (c.ultrasound ? ", ultrasound" : "") + (c.emg ? ", emg" : "") + "]";
        out += "}\n";
    }
    return out;
}

bool isTorqueProtocolFile(const std::string& path) {
    const ParamNode root = ParamNode::loadFile(path);
    return root.has("kind") && root.getString("kind") == "torque";
}

VirtualSubject loadTorqueProtocolSubject(const TorqueProtocol& protocol) {
    if (!protocol.population.empty())
        return drawSubject(loadPopulation(protocol.population), protocol.seed, protocol.subjectIndex);
    VirtualSubject v;
    v.seed = protocol.seed;
    v.setup = loadModel(protocol.model);
    v.transducerNoise = protocol.transducerNoise;
    v.massScale.assign(v.setup.muscles.size(), 1.0);
    v.tendonLengthScale = v.fascicleLengthScale = v.massScale;
    return v;
}

std::string formatPosture(double rotationDeg) { return std::isnan(rotationDeg) ? "-" : formatNumber(rotationDeg); }

ConditionKey getConditionKey(const TorqueObservation& o) {
    return conditionKey(o.flexionDeg, o.effort, o.level, o.rotationDeg);
}

bool isSameCondition(const TorqueObservation& a, const TorqueObservation& b) {
    return getConditionKey(a) == getConditionKey(b);
}

bool hasPostures(const std::vector<TorqueObservation>& data) {
    return std::any_of(data.begin(), data.end(), [](const TorqueObservation& o) { return !std::isnan(o.rotationDeg); });
}

std::vector<TorqueObservation> synthesizeTorqueData(const VirtualSubject& subject, const TorqueProtocol& protocol,
                                                    unsigned noiseSeed, int jobs, const std::function<void(int, int)>& progress) {
    protocol.validate();
    for (std::size_t k = 0; k < protocol.conditions.size(); ++k)   // an OpenSim protocol's angles are its coordinate's
        checkField(conditionField(k, "flexion_deg"), protocol.conditions[k].flexionDeg, Bound::closed(0, 180, "deg, 0 = extended"));
    PortableRandom rng{noiseSeed, subject.seed, unsigned(subject.index)};
    // The forearm axis's noise from a stream of its own: the flexion axis's draws stay what they were.
    PortableRandom forearmRng{noiseSeed, subject.seed, unsigned(subject.index), 2u};
    const bool forearm = protocol.readsForearmTorque();
    if (forearm && !subject.setup.arm.forearmRotation.enabled)
        throw InputError(protocol.describe() + " reads the forearm axis (a rotation effort or measurements." +
                         "forearm_torque), but model '" + subject.setup.name + "' has no forearm rotation");
    for (std::size_t k = 0; k < protocol.conditions.size(); ++k) {   // an effort no muscle of the model makes reads 0
        const Effort effort = protocol.conditions[k].effort;
        if (isForearmEffort(effort)) continue;   // its agonists depend on the pose (the trial checks them)
        const bool made = std::any_of(subject.setup.muscles.begin(), subject.setup.muscles.end(),
                                      [&](const MuscleSpec& m) { return isAgonistOf(effort, m.group, 0.0); });
        if (!made)
            throw FieldError(conditionField(k, "effort"), std::string("= ") + getEffortName(effort) + ": model '" +
                                                              subject.setup.name + "' has no muscle that makes it (expected an "
                                                              "effort of the model's muscles)");
    }
    const SubjectEffort& e = subject.setup.effort;
    int maxRepetitions = 0;
    for (const TorqueCondition& c : protocol.conditions) maxRepetitions = std::max(maxRepetitions, c.repetitions);
    std::vector<IsometricTrialSettings> trials;
    std::vector<TorqueObservation> data;
    for (int r = 0; r < maxRepetitions; ++r)
        for (const TorqueCondition& c : protocol.conditions) {
            if (r >= c.repetitions) continue;
            IsometricTrialSettings s;
            s.elbowAngle = elbowAngleFromFlexion(degToRad(c.flexionDeg));
            s.forearmRotationDeg = c.rotationDeg;
            s.activation = std::clamp(c.level * e.voluntaryActivation * (1 + e.trialCv * rng.drawNormal()), 0.0, 1.0);
            s.antagonistActivation = c.level * e.coContraction;
            s.effort = c.effort;
            s.restDuration = protocol.restDuration;
            s.holdDuration = protocol.holdDuration;
            s.averagingWindow = protocol.averagingWindow;
            s.sampleRate = protocol.sampleRate;
            trials.push_back(s);
            TorqueObservation o;
            o.flexionDeg = c.flexionDeg;
            o.rotationDeg = c.rotationDeg;
            o.effort = c.effort;
            o.level = c.level;
            o.repetition = r;
            o.activation = s.activation;
            o.antagonistActivation = s.antagonistActivation;
            o.noiseDraw = rng.drawNormal();
            if (forearm) o.forearmNoiseDraw = forearmRng.drawNormal();
            data.push_back(o);
        }
    const std::vector<IsometricTrialResult> results = runIsometricTrials(subject.setup, trials, jobs, progress);
    for (std::size_t k = 0; k < data.size(); ++k) {
        data[k].cleanTorque = results[k].summary.meanMuscleTorque;
        if (forearm) data[k].cleanForearmTorque = results[k].summary.meanForearmTorque;
        data[k].restFascicleLength = results[k].summary.restFascicleLength;
        data[k].fascicleLength = results[k].summary.meanFascicleLength;
    }
    return setTransducerNoise(std::move(data), subject.transducerNoise);
}

namespace {

// Condition c of an OpenSim protocol as an isometric trial.
OsimIsometricTrialSettings makeOsimTrial(const TorqueProtocol& protocol, const TorqueCondition& c) {
    OsimIsometricTrialSettings s;
    s.coordinate = protocol.coordinate;
    s.angleDeg = c.flexionDeg;
    s.direction = c.effort == Effort::Extension ? -1 : 1;
    s.activation = c.level;
    s.restDuration = protocol.restDuration;
    s.holdDuration = protocol.holdDuration;
    s.averagingWindow = protocol.averagingWindow;
    s.sampleRate = protocol.sampleRate;
    return s;
}

// Every condition's trial checked on the model before any runs: FieldErrors named as the protocol's
// fields (subject.coordinate, conditions[k].flexion_deg).
OsimModel loadOsimProtocolModel(const TorqueProtocol& protocol) {
    OsimModel model;
    try {
        model = readOsimFile(findOsimModelFile(protocol.model, "subject.model"));
    } catch (const InputError& e) {
        throw FieldError("subject.model", std::string("= '") + protocol.model + "': " + e.what());
    }
    const OsimArm arm(model);
    for (std::size_t k = 0; k < protocol.conditions.size(); ++k) {
        try {
            makeOsimTrial(protocol, protocol.conditions[k]).validate(arm);
        } catch (const SampleCountError& e) {
            throw FieldError("trial.sample_rate", "= " + formatNumber(e.getSampleRate()) + " Hz over trial.rest + trial.hold = " +
                                                      formatNumber(e.getDuration()) + " s " + e.getDetail());
        } catch (const FieldError& e) {
            if (e.getField() == "coordinate") throw FieldError("subject.coordinate", e.getDetail());
            if (e.getField() == "angle_deg")
                throw FieldError(conditionField(k, "flexion_deg"), e.getDetail() + " (the range of coordinate " +
                                                                       (protocol.coordinate.empty() ? "of the model" : protocol.coordinate) + ")");
            throw;
        }
    }
    return model;
}

}  // namespace

std::vector<TorqueObservation> synthesizeOsimTorqueData(const TorqueProtocol& protocol, unsigned noiseSeed, int jobs) {
    protocol.validate();
    if (!protocol.usesOsimModel())
        throw InputError(protocol.describe() + ": subject.model = '" + protocol.model + "' is not an OpenSim model");
    const OsimModel model = loadOsimProtocolModel(protocol);
    PortableRandom rng{noiseSeed, 0u, 0u};
    int maxRepetitions = 0;
    for (const TorqueCondition& c : protocol.conditions) maxRepetitions = std::max(maxRepetitions, c.repetitions);
    std::vector<OsimIsometricTrialSettings> trials;
    std::vector<TorqueObservation> data;
    for (int r = 0; r < maxRepetitions; ++r)   // repetition-major, as synthesizeTorqueData
        for (const TorqueCondition& c : protocol.conditions) {
            if (r >= c.repetitions) continue;
            trials.push_back(makeOsimTrial(protocol, c));
            TorqueObservation o;
            o.flexionDeg = c.flexionDeg;
            o.effort = c.effort;
            o.level = c.level;
            o.repetition = r;
            o.activation = c.level;
            o.antagonistActivation = 0;
            o.noiseDraw = rng.drawNormal();
            data.push_back(o);
        }
    std::vector<double> torques(trials.size());
    runParallel(int(trials.size()), jobs,
                [&](int k) { torques[k] = runOsimIsometricTrial(model, trials[k]).summary.meanTaredTorque; });
    for (std::size_t k = 0; k < data.size(); ++k) data[k].cleanTorque = torques[k];
    return setTransducerNoise(std::move(data), protocol.transducerNoise);
}

TorqueProtocolRun runTorqueProtocol(const TorqueProtocol& protocol, int jobs, const std::function<void(int, int)>& progress) {
    TorqueProtocolRun run;
    if (protocol.usesOsimModel()) {
        run.subject = "OpenSim model " + protocol.model +
                      (protocol.coordinate.empty() ? std::string() : ", coordinate " + protocol.coordinate);
        run.data = synthesizeOsimTorqueData(protocol, protocol.seed, jobs);
        return run;
    }
    run.subject = protocol.population.empty() ? "model " + protocol.model
                                              : protocol.population + " person " + std::to_string(protocol.subjectIndex);
    const VirtualSubject subject = loadTorqueProtocolSubject(protocol);
    run.data = synthesizeTorqueData(subject, protocol, protocol.seed, jobs, progress);
    if (protocol.hasChannels()) run.channels = synthesizeChannelData(subject, protocol, run.data, protocol.seed);
    return run;
}

std::vector<TorqueObservation> setTransducerNoise(std::vector<TorqueObservation> data, double sd) {
    checkField("transducer noise", sd, Bound{0, 0.5, false, true, "relative sd"});
    for (TorqueObservation& o : data) {
        if (!std::isfinite(o.cleanForearmTorque)) {  // one axis
            o.torque = o.cleanTorque * (1 + sd * o.noiseDraw);
            continue;
        }
        const double load = std::hypot(o.cleanTorque, o.cleanForearmTorque);
        o.torque = o.cleanTorque + sd * load * o.noiseDraw;
        o.forearmTorque = o.cleanForearmTorque + sd * load * o.forearmNoiseDraw;
    }
    return data;
}

std::string formatTorqueData(const std::vector<TorqueObservation>& data, bool truth) {
    const bool postures = hasPostures(data);
    const bool forearm = std::any_of(data.begin(), data.end(), [](const TorqueObservation& o) {
        return std::isfinite(o.forearmTorque) || std::isfinite(o.cleanForearmTorque);
    });
    std::string out = std::string("# tared elbow torque per trial; flexion_deg: 0 = extended; effort: 1 = flexion, -1 = extension") +
                      (forearm ? ", 2 = supination, -2 = pronation" : "") + ";\n# level: drive as a fraction of maximal; torque_Nm: + = flexion";
    out += postures ? "; rotation_deg: forearm posture, + = supination, NaN = the model's" : "";
    out += forearm ? ";\n# forearm_torque_Nm: the transducer's forearm axis, + = supination\n" : "\n";
    out += "flexion_deg,effort,level,repetition,torque_Nm";
    out += postures ? ",rotation_deg" : "";
    out += forearm ? ",forearm_torque_Nm" : "";
    out += truth ? ",activation,clean_torque_Nm" : "";
    out += truth && forearm ? ",clean_forearm_torque_Nm\n" : "\n";
    auto number = [](double v) { return std::isnan(v) ? std::string("NaN") : formatNumber(v); };
    for (const TorqueObservation& o : data) {
        out += formatNumber(o.flexionDeg) + "," + std::to_string(getEffortCode(o.effort)) + "," +
               formatNumber(o.level) + "," + std::to_string(o.repetition) + "," + formatNumber(o.torque);
        if (postures) out += "," + number(o.rotationDeg);
        if (forearm) out += "," + number(o.forearmTorque);
        if (truth) out += "," + formatNumber(o.activation) + "," + formatNumber(o.cleanTorque);
        if (truth && forearm) out += "," + number(o.cleanForearmTorque);
        out += "\n";
    }
    return out;
}

namespace {

// Each row's first line, by condition and torques (rows without repetition numbers).
using RowLines = std::map<std::tuple<ConditionKey, double, double>, int>;

// Without repetition numbers, a row equal to an earlier one is more likely pasted twice than a second
// trial reading the same torque to the last digit (force data refuse it alike).
void checkRowOnce(RowLines& firstLine, const ConditionKey& key, const TorqueObservation& o, const std::string& at) {
    const double forearm = std::isnan(o.forearmTorque) ? -INFINITY : o.forearmTorque;   // NaN would not order
    const auto [earlier, fresh] = firstLine.emplace(std::make_tuple(key, o.torque, forearm), o.line);
    if (!fresh)
        throw InputError(at + ": the same row as line " + std::to_string(earlier->second) + " (" + getEffortName(o.effort) +
                         " at " + formatNumber(o.flexionDeg) + " deg, torque " + formatNumber(o.torque) +
                         " N m): expected each trial once (repeated trials that read the same torque: give them a "
                         "repetition column)");
}

// Slips of unit a row-by-row bound cannot see, refused for the file as a whole: angles in radians, and
// torques in kN m (every maximal effort under 0.5 N m; the weakest elbow MVCs measured are several N m).
void checkTorqueDataUnits(const std::vector<TorqueObservation>& data, const std::string& path) {
    std::vector<double> angles;
    for (const TorqueObservation& o : data)
        if (std::find(angles.begin(), angles.end(), o.flexionDeg) == angles.end()) angles.push_back(o.flexionDeg);
    try {
        checkDegreesNotRadians("flexion_deg", angles);
    } catch (const FieldError& e) {
        throw InputError(path + ": column 'flexion_deg' " + e.getDetail());
    }
    constexpr double kMinMaximalTorque = 0.5;   // N m
    double largest = -1;
    for (const TorqueObservation& o : data)
        if (o.level == 1) largest = std::max(largest, isForearmEffort(o.effort) ? std::abs(o.forearmTorque) : std::abs(o.torque));
    if (largest >= 0 && largest < kMinMaximalTorque)
        throw InputError(path + ": every maximal effort's torque is under " + formatNumber(kMinMaximalTorque) +
                         " N m (the largest is " + formatNumber(largest) + "): expected N m (a value in kN m is 1000 "
                         "times too small; the weakest elbow MVCs are several N m)");
}

}  // namespace

std::vector<TorqueObservation> readTorqueData(const std::string& path) {
    return makeTorqueData(Table::readCsv(path), path);
}

std::vector<TorqueObservation> makeTorqueData(const Table& t, const std::string& path) {
    static const std::set<std::string> known = {"flexion_deg", "effort", "level", "repetition", "torque_Nm",
                                                "rotation_deg", "forearm_torque_Nm", "activation", "clean_torque_Nm",
                                                "clean_forearm_torque_Nm"};
    for (const std::string& c : t.getColumnNames())
        if (!known.count(c))
            throw InputError(path + ": unknown column '" + c +
                             "': expected flexion_deg, torque_Nm and optionally effort, level, repetition, rotation_deg, "
                             "forearm_torque_Nm (activation, clean_torque_Nm, clean_forearm_torque_Nm: truth of "
                             "synthetic data, ignored)");
    for (const char* c : {"flexion_deg", "torque_Nm"})
        if (!t.hasColumn(c)) throw InputError(path + ": missing column '" + std::string(c) + "'");
    if (t.getNumRows() == 0) throw InputError(path + ": no data rows");
    if (t.getNumRows() > kMaxTorqueRows)
        throw InputError(path + ": " + std::to_string(t.getNumRows()) + " data rows: expected at most " +
                         std::to_string(kMaxTorqueRows) + " (one row per trial; a lab's protocol has tens to hundreds)");
    std::vector<TorqueObservation> data;
    std::map<ConditionKey, int> count;
    std::set<std::pair<ConditionKey, int>> seen;
    RowLines firstLine;   // rows without repetition numbers
    for (int r = 0; r < t.getNumRows(); ++r) {
        const std::string at = t.describeRow(path, r);
        auto fail = [&](const std::string& column, double v, const std::string& expected) {
            throw InputError(at + ": column '" + column + "' = " + formatNumber(v) + ": expected " + expected);
        };
        TorqueObservation o;
        o.line = t.getSourceLine(r);
        o.flexionDeg = t.get(r, "flexion_deg");
        if (!std::isfinite(o.flexionDeg) || o.flexionDeg < 0 || o.flexionDeg > 180)
            fail("flexion_deg", o.flexionDeg, "in [0, 180] (0 = extended)");
        o.torque = t.get(r, "torque_Nm");
        // A person's elbow: the strongest flexion MVCs are about 150 N m; 1000 N m bounds any arm, and
        // keeps a value in the wrong unit (N mm) from reaching the fit as an impossible force.
        const Bound kElbowTorque{-1000, 1000, false, false, "N m"};
        if (!kElbowTorque.contains(o.torque)) fail("torque_Nm", o.torque, kElbowTorque.describe());
        if (t.hasColumn("effort")) {
            const double e = t.get(r, "effort");
            const Effort* found = std::find_if(std::begin(kEfforts), std::end(kEfforts),
                                               [&](Effort k) { return getEffortCode(k) == e; });
            if (found == std::end(kEfforts))
                fail("effort", e, "1 (flexion), -1 (extension), 2 (supination) or -2 (pronation)");
            o.effort = *found;
        }
        if (t.hasColumn("level")) {
            o.level = t.get(r, "level");
            if (!(o.level > 0 && o.level <= 1)) fail("level", o.level, "in (0, 1] (fraction of maximal)");
        }
        if (t.hasColumn("rotation_deg")) {
            o.rotationDeg = t.get(r, "rotation_deg");   // NaN = the model's posture
            if (std::isinf(o.rotationDeg) || std::abs(o.rotationDeg) > 180)
                fail("rotation_deg", o.rotationDeg, "in [-180, 180] (+ = supination) or NaN (the model's posture)");
        }
        if (t.hasColumn("forearm_torque_Nm")) {
            o.forearmTorque = t.get(r, "forearm_torque_Nm");  // NaN: not read in this trial
            if (std::isinf(o.forearmTorque) || std::abs(o.forearmTorque) > kElbowTorque.hi)
                fail("forearm_torque_Nm", o.forearmTorque, "in [-1000, 1000] (N m) or NaN (not read)");
        }
        if (isForearmEffort(o.effort) && !std::isfinite(o.forearmTorque))
            throw InputError(at + ": a " + getEffortName(o.effort) + " effort without its forearm torque: expected a "
                             "column forearm_torque_Nm with a finite value (+ = supination)");
        const ConditionKey key = getConditionKey(o);
        if (!t.hasColumn("repetition")) checkRowOnce(firstLine, key, o, at);
        if (t.hasColumn("repetition")) {
            const double v = t.get(r, "repetition");
            if (!std::isfinite(v) || v != std::floor(v) || v < 0 || v > 1e6) fail("repetition", v, "an integer in [0, 1000000]");
            o.repetition = int(v);
        } else {
            o.repetition = count[key];
        }
        ++count[key];
        if (!seen.insert({key, o.repetition}).second)
            throw InputError(at + ": repetition " + std::to_string(o.repetition) + " of " + getEffortName(o.effort) +
                             " at " + formatNumber(o.flexionDeg) + " deg, level " + formatNumber(o.level) +
                             (std::isnan(o.rotationDeg) ? std::string() : ", rotation " + formatNumber(o.rotationDeg) + " deg") +
                             " appears earlier: expected each trial once");
        if (o.effort == Effort::Flexion && o.torque < 0)
            fail("torque_Nm", o.torque, ">= 0 for a flexion effort (+ = flexion; a tared transducer)");
        if (o.effort == Effort::Extension && o.torque > 0)
            fail("torque_Nm", o.torque, "<= 0 for an extension effort (+ = flexion; a tared transducer)");
        if (o.effort == Effort::Supination && o.forearmTorque < 0)
            fail("forearm_torque_Nm", o.forearmTorque, ">= 0 for a supination effort (+ = supination; a tared transducer)");
        if (o.effort == Effort::Pronation && o.forearmTorque > 0)
            fail("forearm_torque_Nm", o.forearmTorque, "<= 0 for a pronation effort (+ = supination; a tared transducer)");
        data.push_back(o);
    }
    if (std::none_of(data.begin(), data.end(), [](const TorqueObservation& o) {
            return o.torque != 0 || (std::isfinite(o.forearmTorque) && o.forearmTorque != 0);
        }))
        throw InputError(path + ": column 'torque_Nm' (and forearm_torque_Nm) is 0 in every row: expected the tared "
                                "torques measured (nothing to fit)");
    checkTorqueDataUnits(data, path);
    return data;
}

void writeTorquePlot(const std::string& path, const std::vector<TorqueObservation>& data, const std::string& title) {
    PlotSpec plot;
    plot.title = title;
    plot.xLabel = "elbow flexion (deg, 0 = extended)";
    const bool rotation = std::any_of(data.begin(), data.end(), [](const TorqueObservation& o) { return isForearmEffort(o.effort); });
    plot.yLabel = rotation ? "tared torque about the effort's axis (N m, + = flexion, supination)" : "tared torque (N m, + = flexion)";
    std::vector<std::pair<int, double>> kinds;
    for (const TorqueObservation& o : data) {
        const std::pair<int, double> k{int(o.effort), o.level};
        auto it = std::find(kinds.begin(), kinds.end(), k);
        if (it == kinds.end()) {
            kinds.push_back(k);
            plot.series.push_back({std::string(getEffortName(o.effort)) +
                                       (o.level == 1 ? " MVC" : " " + formatNumber(100 * o.level) + " %"),
                                   {}, {}, true, int(kinds.size() - 1) % 8});
            it = kinds.end() - 1;
        }
        PlotSeries& series = plot.series[it - kinds.begin()];
        series.x.push_back(o.flexionDeg);
        series.y.push_back(o.getEffortTorque());
    }
    writePlotPng(path, plot);
}

std::vector<std::string> writeTorqueProtocolRun(const std::string& dir, const TorqueProtocol& protocol,
                                                const std::vector<TorqueObservation>& data,
                                                const std::vector<ChannelObservation>& channels) {
    std::vector<std::string> paths = {dir + "/torque_data.csv", dir + "/protocol.yaml", dir + "/torque_angle.png"};
    writeFileAtomically(paths[0], formatTorqueData(data, true));
    writeFileAtomically(paths[1], formatTorqueProtocol(protocol));
    writeTorquePlot(paths[2], data, "Protocol " + protocol.name + ": tared torque per trial");
    if (!channels.empty()) {
        paths.push_back(dir + "/channel_data.csv");
        writeFileAtomically(paths.back(), formatChannelData(channels, true));
        for (const std::string& p : writeChannelPlots(dir, channels, "Protocol " + protocol.name)) paths.push_back(p);
    }
    return paths;
}

}  // namespace armsim

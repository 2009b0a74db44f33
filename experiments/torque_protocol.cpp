#include "experiments/torque_protocol.h"

#include "experiments/channels.h"

#include "basics/files.h"
#include "basics/param_node.h"
#include "basics/plot.h"
#include "basics/portable_random.h"
#include "basics/table.h"
#include "model/geometry.h"
#include "model/trial.h"
#include "muscles/muscle_file.h"

#include <algorithm>
#include <map>
#include <set>
#include <tuple>

namespace armsim {

namespace {

std::string conditionField(std::size_t k, const char* key) {
    return "conditions[" + std::to_string(k) + "]." + key;
}

ConditionKey conditionKey(double flexionDeg, MuscleGroup effort, double level, double rotationDeg) {
    return {flexionDeg, int(effort), level, std::isnan(rotationDeg) ? INFINITY : rotationDeg};
}

}  // namespace

const char* getEffortName(MuscleGroup effort) { return effort == MuscleGroup::Flexor ? "flexion" : "extension"; }

std::vector<TorqueCondition> TorqueProtocol::makeFlexionMvcs(const std::vector<double>& flexionDeg, int repetitions) {
    std::vector<TorqueCondition> out;
    for (double q : flexionDeg) out.push_back({q, MuscleGroup::Flexor, 1.0, repetitions});
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

bool TorqueProtocol::hasChannels() const {
    return !volumeScan.empty() || anthropometry ||
           std::any_of(conditions.begin(), conditions.end(), [](const TorqueCondition& c) { return c.ultrasound || c.emg; });
}

void TorqueProtocol::validate() const {
    if (conditions.empty()) throw FieldError("conditions", "no conditions: expected at least one");
    std::set<ConditionKey> seen;
    for (std::size_t k = 0; k < conditions.size(); ++k) {
        const TorqueCondition& c = conditions[k];
        checkField(conditionField(k, "flexion_deg"), c.flexionDeg, Bound::closed(0, 180, "deg, 0 = extended"));
        checkField(conditionField(k, "level"), c.level, Bound{0, 1, true, false, "fraction of maximal, in (0, 1]"});
        checkField(conditionField(k, "repetitions"), c.repetitions, Bound::closed(1, 100));
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
    checkField("channel_noise.fascicle_length", n.fascicleLength, Bound{0, 0.5, true, true, "relative sd"});
    checkField("channel_noise.volume", n.volume, Bound{0, 0.5, true, true, "relative sd"});
    checkField("channel_noise.emg", n.emg, Bound{0, 1, true, true, "relative sd"});
    checkField("channel_noise.emg_crosstalk", n.emgCrosstalk, Bound::closed(0, 0.5));
    checkField("channel_noise.upper_arm_length", n.upperArmLength, Bound{0, 0.1, true, true, "m"});
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
        out += (out.empty() ? "" : "; ") + std::string(getEffortName(MuscleGroup(effort))) + " " +
               (level == 1 ? std::string("MVC") : formatNumber(100 * level) + " %") + " at " + angles[key] +
               " deg x " + std::to_string(repetitions);
        if (channels) out += std::string(" with ") + (channels & 1 ? "ultrasound" : "") + (channels == 3 ? " and " : "") +
                             (channels & 2 ? "EMG" : "");
    }
    if (!protocol.volumeScan.empty()) out += "; volume scan of " + formatList(protocol.volumeScan);
    if (protocol.anthropometry) out += "; anthropometry";
    return out;
}

TorqueProtocol readTorqueProtocol(const std::string& path) {
    const ParamNode root = ParamNode::loadFile(path);
    TorqueProtocol p;
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
            p.transducerNoise = s.getNumber("transducer_noise", Bound::closed(0, 0.5), p.transducerNoise);
        }
        s.finish();
    }
    if (root.has("measurements")) {
        const ParamNode m = root.child("measurements");
        if (m.has("volume_scan")) p.volumeScan = m.getStrings("volume_scan");
        p.anthropometry = m.getBool("anthropometry", false);
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
        tc.flexionDeg = c.getNumber("flexion_deg", Bound::closed(0, 180, "deg, 0 = extended"));
        tc.effort = c.getChoice("effort", {"flexion", "extension"}, "flexion") == "flexion" ? MuscleGroup::Flexor
                                                                                            : MuscleGroup::Extensor;
        tc.level = c.getNumber("level", Bound{0, 1, true, false, "fraction of maximal, in (0, 1]"}, 1.0);
        tc.repetitions = c.getInt("repetitions", 1, 100, 1);
        if (c.has("rotation_deg")) tc.rotationDeg = c.getNumber("rotation_deg", Bound::closed(-180, 180, "deg, + = supination"));
        if (c.has("channels")) {
            const std::vector<std::string> channels = c.getStrings("channels");
            for (const std::string& name : channels) {
                if (name == "ultrasound") tc.ultrasound = true;
                else if (name == "emg") tc.emg = true;
                else if (name != "torque")
                    throw InputError(c.where("channels") + ": field '" + c.path("channels") + "' = '" + name +
                                     "': expected torque, ultrasound or emg");
            }
            if (std::find(channels.begin(), channels.end(), "torque") == channels.end())
                throw InputError(c.where("channels") + ": field '" + c.path("channels") +
                                 "' leaves out torque: expected every effort to be read by the transducer (list torque)");
        }
        c.finish();
        p.conditions.push_back(tc);
    }
    root.finish();
    root.rethrowWithLocation([&] { p.validate(); });
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
        out += "  model: " + p.model + "\n  transducer_noise: " + formatNumber(p.transducerNoise) + "\n";
    if (p.hasChannels()) {
        const ChannelNoise& n = p.channelNoise;
        std::string names;
        for (const std::string& v : p.volumeScan) names += (names.empty() ? "" : ", ") + v;
        out += "measurements: {volume_scan: [" + names + "]" +
               ", anthropometry: " + (p.anthropometry ? "true" : "false") + "}\n";
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
                                                    unsigned noiseSeed, int jobs) {
    protocol.validate();
    PortableRandom rng{noiseSeed, subject.seed, unsigned(subject.index)};
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
            data.push_back(o);
        }
    const std::vector<IsometricTrialResult> results = runIsometricTrials(subject.setup, trials, jobs);
    for (std::size_t k = 0; k < data.size(); ++k) {
        data[k].cleanTorque = results[k].summary.meanMuscleTorque;
        data[k].restFascicleLength = results[k].summary.restFascicleLength;
        data[k].fascicleLength = results[k].summary.meanFascicleLength;
    }
    return setTransducerNoise(std::move(data), subject.transducerNoise);
}

std::vector<TorqueObservation> setTransducerNoise(std::vector<TorqueObservation> data, double sd) {
    checkField("transducer noise", sd, Bound{0, 0.5, false, true, "relative sd"});
    for (TorqueObservation& o : data) o.torque = o.cleanTorque * (1 + sd * o.noiseDraw);
    return data;
}

std::string formatTorqueData(const std::vector<TorqueObservation>& data, bool truth) {
    const bool postures = hasPostures(data);
    std::string out = "# tared elbow torque per trial; flexion_deg: 0 = extended; effort: 1 = flexion, -1 = extension;\n"
                      "# level: drive as a fraction of maximal; torque_Nm: + = flexion";
    out += postures ? "; rotation_deg: forearm posture, + = supination, NaN = the model's\n" : "\n";
    out += "flexion_deg,effort,level,repetition,torque_Nm";
    out += postures ? ",rotation_deg" : "";
    out += truth ? ",activation,clean_torque_Nm\n" : "\n";
    for (const TorqueObservation& o : data) {
        out += formatNumber(o.flexionDeg) + "," + (o.effort == MuscleGroup::Flexor ? "1" : "-1") + "," +
               formatNumber(o.level) + "," + std::to_string(o.repetition) + "," + formatNumber(o.torque);
        if (postures) out += "," + (std::isnan(o.rotationDeg) ? std::string("NaN") : formatNumber(o.rotationDeg));
        if (truth) out += "," + formatNumber(o.activation) + "," + formatNumber(o.cleanTorque);
        out += "\n";
    }
    return out;
}

std::vector<TorqueObservation> readTorqueData(const std::string& path) {
    return makeTorqueData(Table::readCsv(path), path);
}

std::vector<TorqueObservation> makeTorqueData(const Table& t, const std::string& path) {
    static const std::set<std::string> known = {"flexion_deg", "effort", "level", "repetition", "torque_Nm",
                                                "rotation_deg", "activation", "clean_torque_Nm"};
    for (const std::string& c : t.getColumnNames())
        if (!known.count(c))
            throw InputError(path + ": unknown column '" + c +
                             "': expected flexion_deg, torque_Nm and optionally effort, level, repetition, rotation_deg "
                             "(activation, clean_torque_Nm: truth of synthetic data, ignored)");
    for (const char* c : {"flexion_deg", "torque_Nm"})
        if (!t.hasColumn(c)) throw InputError(path + ": missing column '" + std::string(c) + "'");
    if (t.getNumRows() == 0) throw InputError(path + ": no data rows");
    std::vector<TorqueObservation> data;
    std::map<ConditionKey, int> count;
    std::set<std::pair<ConditionKey, int>> seen;
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
        if (!std::isfinite(o.torque)) fail("torque_Nm", o.torque, "a finite number");
        if (t.hasColumn("effort")) {
            const double e = t.get(r, "effort");
            if (e != 1 && e != -1) fail("effort", e, "1 (flexion) or -1 (extension)");
            o.effort = e == 1 ? MuscleGroup::Flexor : MuscleGroup::Extensor;
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
        const ConditionKey key = getConditionKey(o);
        if (t.hasColumn("repetition")) {
            const double v = t.get(r, "repetition");
            if (!std::isfinite(v) || v != std::floor(v) || v < 0 || v > 1e6) fail("repetition", v, "an integer >= 0");
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
        if (o.effort == MuscleGroup::Flexor ? o.torque < 0 : o.torque > 0)
            fail("torque_Nm", o.torque,
                 std::string(o.effort == MuscleGroup::Flexor ? ">= 0 for a flexion effort" : "<= 0 for an extension effort") +
                     " (+ = flexion; a tared transducer)");
        data.push_back(o);
    }
    return data;
}

void writeTorquePlot(const std::string& path, const std::vector<TorqueObservation>& data, const std::string& title) {
    PlotSpec plot;
    plot.title = title;
    plot.xLabel = "elbow flexion (deg, 0 = extended)";
    plot.yLabel = "tared torque (N m, + = flexion)";
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
        series.y.push_back(o.torque);
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

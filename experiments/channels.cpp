#include "experiments/channels.h"
#include "basics/numbers.h"

#include "basics/bound.h"
#include "basics/csv.h"
#include "basics/errors.h"
#include "basics/files.h"
#include "basics/format.h"
#include "basics/plot.h"
#include "basics/portable_random.h"
#include "basics/table.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>
#include <tuple>

namespace armsim {

namespace {

const TorqueCondition* findCondition(const TorqueProtocol& p, const TorqueObservation& o) {
    for (const TorqueCondition& c : p.conditions)
        if (c.flexionDeg == o.flexionDeg && c.effort == o.effort && c.level == o.level &&
            (std::isnan(c.rotationDeg) ? std::isnan(o.rotationDeg) : c.rotationDeg == o.rotationDeg))
            return &c;
    return nullptr;
}

}  // namespace

const std::vector<std::string>& getChannelNames() {
    static const std::vector<std::string> names = {"fascicle_length", "volume", "emg", "upper_arm_length"};
    return names;
}

std::vector<ChannelObservation> synthesizeChannelData(const VirtualSubject& subject, const TorqueProtocol& protocol,
                                                      const std::vector<TorqueObservation>& torque,
                                                      unsigned noiseSeed) {
    protocol.validate();
    const ArmSetup& s = subject.setup;
    const ChannelNoise& n = protocol.channelNoise;
    PortableRandom rng{noiseSeed, subject.seed, unsigned(subject.index), 2u};
    const std::string primary = s.muscles[s.primary].params.name;
    std::vector<ChannelObservation> out;
    auto add = [&](ChannelObservation o, double clean, double relativeSd, double floor) {
        o.cleanValue = clean;
        o.sd = relativeSd * std::max(std::abs(clean), floor);  // the device's sd at the true level
        o.value = clean + o.sd * rng.drawNormal();
        out.push_back(o);
    };
    const SubjectEffort& e = s.effort;
    const double emgMvc = e.voluntaryActivation + n.emgCrosstalk * e.coContraction;  // at its own group's MVC
    for (const TorqueObservation& t : torque) {
        const TorqueCondition* c = findCondition(protocol, t);
        if (!c) throw InputError("synthesizeChannelData: a torque trial at " + formatNumber(t.flexionDeg) +
                                 " deg is not a condition of protocol '" + protocol.name + "'");
        ChannelObservation o;
        o.flexionDeg = t.flexionDeg;
        o.effort = t.effort;
        o.repetition = t.repetition;
        if (c->ultrasound) {
            if (!std::isfinite(t.restFascicleLength) || !std::isfinite(t.fascicleLength))
                throw InputError("synthesizeChannelData: trial at " + formatNumber(t.flexionDeg) +
                                 " deg has no fascicle length (expected synthesizeTorqueData's output)");
            o.channel = "fascicle_length";
            o.muscle = primary;
            o.level = 0;
            add(o, t.restFascicleLength, n.fascicleLength, 0);
            o.level = t.level;
            add(o, t.fascicleLength, n.fascicleLength, 0);
        }
        if (c->emg) {
            if (s.surfaceEmg.empty())
                throw InputError(protocol.describe() + " records emg at " + formatNumber(c->flexionDeg) +
                                 " deg, but model '" + s.name + "' names no muscles for it: expected a roles: "
                                 "surface_emg list in the model file");
            o.channel = "emg";
            o.level = t.level;
            for (int m : s.surfaceEmg) {
                const MuscleGroup g = s.muscles[m].group;
                if (g != MuscleGroup::Flexor && g != MuscleGroup::Extensor) continue;
                const bool agonist = isAgonistOf(t.effort, g, 0.0);
                const double own = agonist ? t.activation : t.antagonistActivation;
                const double other = agonist ? t.antagonistActivation : t.activation;
                o.muscle = s.muscles[m].params.name;
                add(o, (own + n.emgCrosstalk * other) / emgMvc, n.emg, kEmgFloor);
            }
        }
    }
    for (const std::string& name : protocol.volumeScan) {
        int m = 0;
        try {
            m = s.findMuscle(name);
        } catch (const InputError& x) {
            throw InputError((protocol.volumeScanWhere.empty() ? protocol.describe() : protocol.volumeScanWhere) +
                             ": field 'measurements.volume_scan': " + x.what());
        }
        const MuscleParameters& p = s.muscles[m].params;
        ChannelObservation o;
        o.channel = "volume";
        o.muscle = name;
        add(o, p.mass / p.coefficients.density, n.volume, 0);
    }
    if (protocol.anthropometry) {
        ChannelObservation o;
        o.channel = "upper_arm_length";
        o.cleanValue = s.arm.upperArmLength;
        o.value = o.cleanValue + n.upperArmLength * rng.drawNormal();
        o.sd = n.upperArmLength;
        out.push_back(o);
    }
    return out;
}

std::string formatChannelData(const std::vector<ChannelObservation>& data, bool truth) {
    std::vector<std::string> header = {"channel", "muscle", "flexion_deg", "effort", "level", "repetition", "value", "sd"};
    if (truth) header.push_back("clean_value");
    CsvText csv(header);
    for (const ChannelObservation& o : data) {
        CsvRow r;
        r.addText(o.channel).addText(o.muscle).addNumber(o.flexionDeg).addInteger(o.effort == Effort::Flexion ? 1 : -1);
        r.addNumber(o.level).addInteger(o.repetition).addNumber(o.value).addNumber(o.sd);
        if (truth) r.addNumber(o.cleanValue);
        csv.addRow(r);
    }
    return "# channels besides torque (docs/channels.md): fascicle_length [m] (level 0: at rest), volume [m^3],\n"
           "# emg [1, of the muscle's MVC amplitude], upper_arm_length [m]; sd: the measurement's sd, same units.\n"
           "# The EMG crosstalk is the protocol's channel_noise.emg_crosstalk (identify-torque --emg-crosstalk).\n" +
           csv.getText();
}

namespace {

constexpr double kMinSdRelative = kMinChannelSdRelative;
constexpr double kMinSdEmg = kMinChannelSdEmg;

// A measurement's identity in a file: channel, muscle, angle (-1: none), effort, level, repetition.
using ChannelKey = std::tuple<std::string, std::string, double, int, double, int>;

// Columns a channel does not read hold nothing, or what formatChannelData writes there (effort 1,
// level 0): a value there is a row meant for another channel, or a slip.
template <class Text, class Fail>
void checkUnusedChannelColumns(const std::string& channel, const Text& text, const Fail& fail) {
    const bool scan = channel == "volume" || channel == "upper_arm_length";
    if (channel == "upper_arm_length" && !text("muscle").empty())
        fail("muscle", "'" + text("muscle") + "'", "empty for upper_arm_length (the arm's, not a muscle's)");
    if (!scan) return;
    auto isNumber = [&](const char* c, double v) {
        const std::string t = text(c);
        try {
            std::size_t used = 0;
            return t.empty() || (std::stod(t, &used) == v && used == t.size());
        } catch (const std::exception&) {
            return false;
        }
    };
    if (!text("flexion_deg").empty()) fail("flexion_deg", text("flexion_deg"), "empty for " + channel + " (not read at an angle)");
    if (!isNumber("effort", 1)) fail("effort", text("effort"), "empty or 1 for " + channel + " (not read in an effort)");
    if (!isNumber("level", 0)) fail("level", text("level"), "empty or 0 for " + channel + " (not read in an effort)");
}

// A channel file's header: each column's place; InputError at `at` for an unknown, repeated or missing one.
std::map<std::string, int> readChannelHeader(const std::vector<std::string>& header, const std::string& at) {
    static const std::vector<std::string> known = {"channel", "muscle", "flexion_deg", "effort", "level",
                                                   "repetition", "value", "sd", "clean_value"};
    checkCommaSeparatedHeader(header, at);
    std::map<std::string, int> column;
    for (std::size_t k = 0; k < header.size(); ++k) {
        if (std::find(known.begin(), known.end(), header[k]) == known.end())
            throw InputError(at + ": unknown column '" + header[k] +
                             "': expected channel, muscle, flexion_deg, effort, level, repetition, value, sd "
                             "(clean_value: truth of synthetic data, ignored)");
        if (!column.emplace(header[k], int(k)).second) throw InputError(at + ": column '" + header[k] + "' appears twice");
    }
    for (const char* c : {"channel", "value", "sd"})
        if (!column.count(c)) throw InputError(at + ": missing column '" + std::string(c) + "'");
    return column;
}

}  // namespace

namespace {

// The file's angles are degrees, not radians (as the torque data's), named at the first not whole.
void checkChannelAnglesInDegrees(const std::string& path, const std::vector<ChannelObservation>& data) {
    std::vector<double> angles;
    std::vector<int> lines;
    for (const ChannelObservation& o : data)
        if (!std::isnan(o.flexionDeg)) angles.push_back(o.flexionDeg), lines.push_back(o.line);
    try {
        checkDegreesNotRadians("flexion_deg", angles);
    } catch (const FieldError& e) {
        throw InputError(path + ":" + std::to_string(lines[findFirstFractional(angles)]) + ": column 'flexion_deg' " +
                         e.getDetail());
    }
}

// A measurement (channel, muscle, angle, effort, level, repetition) given once; lineOf: each one's first line.
void checkMeasuredOnce(const ChannelObservation& o, const std::string& at, std::map<ChannelKey, int>& lineOf) {
    const ChannelKey key{o.channel, o.muscle, std::isnan(o.flexionDeg) ? -1.0 : o.flexionDeg, int(o.effort), o.level, o.repetition};
    const auto [earlier, fresh] = lineOf.emplace(key, o.line);
    if (!fresh)
        throw InputError(at + ": the same measurement as line " + std::to_string(earlier->second) + " (" + o.channel +
                         (o.muscle.empty() ? "" : " of " + o.muscle) +
                         (std::isnan(o.flexionDeg) ? "" : " at " + formatNumber(o.flexionDeg) + " deg") + ", level " +
                         formatNumber(o.level) + ", repetition " + std::to_string(o.repetition) +
                         "): expected each once (a repeated measurement takes the next repetition number)");
}

}  // namespace

std::vector<ChannelObservation> readChannelData(const std::string& path) {
    checkInputFile(path, 64u << 20);
    std::istringstream in(readFileText(path));
    std::string line;
    int lineNo = 0;
    std::vector<std::string> header;
    std::map<std::string, int> column;
    std::vector<ChannelObservation> data;
    std::map<ChannelKey, int> lineOf;   // each measurement's first line
    while (std::getline(in, line)) {
        ++lineNo;
        if (lineNo == 1 && line.rfind("\xEF\xBB\xBF", 0) == 0) line.erase(0, 3);   // a UTF-8 byte-order mark
        if (!line.empty() && line.back() == '\r') line.pop_back();
        const auto first = line.find_first_not_of(" \t");
        if (first == std::string::npos || line[first] == '#') continue;
        const std::vector<std::string> cells = splitCsvRecord(line);
        const std::string at = path + ":" + std::to_string(lineNo);
        if (header.empty()) {
            header = cells;
            column = readChannelHeader(header, at);
            continue;
        }
        if (cells.size() != header.size())
            throw InputError(at + ": " + std::to_string(cells.size()) + " cells: expected " +
                             std::to_string(header.size()) + " (one per header column)");
        auto text = [&](const char* c) { return column.count(c) ? cells[column[c]] : std::string(); };
        auto number = [&](const char* c, double fallback) {
            const std::string v = text(c);
            if (v.empty()) return fallback;
            std::size_t used = 0;
            double x = 0;
            try {
                x = std::stod(v, &used);
            } catch (const std::exception&) {
                used = 0;
            }
            if (used != v.size() || !std::isfinite(x) || isHexadecimalText(v.c_str()))
                throw InputError(at + ": column '" + std::string(c) + "' = '" + v + "': expected a finite number");
            return x;
        };
        auto fail = [&](const char* c, const std::string& v, const std::string& expected) {
            throw InputError(at + ": column '" + std::string(c) + "' = " + v + ": expected " + expected);
        };
        ChannelObservation o;
        o.line = lineNo;
        o.channel = text("channel");
        if (std::find(getChannelNames().begin(), getChannelNames().end(), o.channel) == getChannelNames().end())
            fail("channel", "'" + o.channel + "'", "fascicle_length, volume, emg or upper_arm_length");
        o.muscle = text("muscle");
        if (o.muscle.empty() && o.channel != "upper_arm_length") fail("muscle", "''", "the muscle's name in the model");
        o.flexionDeg = number("flexion_deg", kNaN);
        const bool atAngle = o.channel == "fascicle_length" || o.channel == "emg";
        if (atAngle && !(o.flexionDeg >= 0 && o.flexionDeg <= 180))
            fail("flexion_deg", formatNumber(o.flexionDeg), "in [0, 180] (0 = extended) for " + o.channel);
        const double effort = number("effort", 1);
        if (effort != 1 && effort != -1) fail("effort", formatNumber(effort), "1 (flexion) or -1 (extension)");
        o.effort = effort == 1 ? Effort::Flexion : Effort::Extension;
        o.level = number("level", 0);
        if (!(o.level >= 0 && o.level <= 1)) fail("level", formatNumber(o.level), "in [0, 1] (0: relaxed)");
        if (o.channel == "emg" && o.level == 0) fail("level", "0", "> 0 for emg (an effort's EMG)");
        const double rep = number("repetition", 0);
        if (rep != std::floor(rep) || rep < 0 || rep > 1e6) fail("repetition", formatNumber(rep), "an integer in [0, 1000000]");
        o.repetition = int(rep);
        o.value = number("value", kNaN);
        // Upper limits a typo (cm for m, mm^3 for m^3) or a unit slip passes: a fascicle or an upper arm
        // of 1 m, a muscle of 10 L, EMG at 10 times its MVC amplitude.
        const bool isEmg = o.channel == "emg";
        const double limit = isEmg ? 10 : o.channel == "volume" ? 0.01 : 1;
        if (!std::isfinite(o.value) || (!isEmg && o.value <= 0) || std::abs(o.value) > limit)
            fail("value", formatNumber(o.value),
                 isEmg ? "a fraction of the MVC amplitude in [-10, 10]"
                       : "in (0, " + formatNumber(limit) + "] " + (o.channel == "volume" ? "m^3" : "m") + " (SI units)");
        o.sd = number("sd", kNaN);
        if (!(o.sd > 0)) fail("sd", formatNumber(o.sd), "> 0 (the measurement's sd, units of value)");
        // A floor no instrument reaches (docs/channels.md: ultrasound 5 %, a volume scan 10 %, a tape 1 %,
        // EMG 15 %): an sd below it would pin the fit to one row and hide the rest.
        const double floor = isEmg ? kMinSdEmg : kMinSdRelative * std::abs(o.value);
        if (o.sd < floor)
            fail("sd", formatNumber(o.sd), ">= " + formatNumber(floor, 3) + (isEmg ? " (of the MVC amplitude)" : " (0.1 % of the value)") +
                                               ": no lab measures " + o.channel + " this finely");
        // A ceiling as far: an sd above the value itself (or above the MVC amplitude for EMG) says nothing
        // of the muscle, and is a unit slip more often than a measurement (sd in mm beside a value in m).
        if (const double ceiling = isEmg ? 1 : std::abs(o.value); o.sd > ceiling)
            fail("sd", formatNumber(o.sd), "<= " + formatNumber(ceiling, 4) + (isEmg ? " (the MVC amplitude)" : " (the value itself)") +
                                               ": is it in other units than value?");
        checkUnusedChannelColumns(o.channel, text, fail);
        o.cleanValue = number("clean_value", kNaN);
        o.source = path;
        checkMeasuredOnce(o, at, lineOf);
        if (data.size() == kMaxChannelRows)
            throw InputError(at + ": more than " + std::to_string(kMaxChannelRows) + " measurements: expected at most " +
                             std::to_string(kMaxChannelRows) + " (each is fitted; a lab's session records some hundreds)");
        data.push_back(o);
    }
    if (header.empty()) throw InputError(path + ": no header line");
    if (data.empty()) throw InputError(path + ": no data rows");
    checkChannelAnglesInDegrees(path, data);
    return data;
}

std::vector<std::string> writeChannelPlots(const std::string& dir, const std::vector<ChannelObservation>& data,
                                           const std::string& title) {
    PlotSpec fascicle, emg;
    fascicle.title = title + ": fascicle length (ultrasound)";
    fascicle.xLabel = emg.xLabel = "elbow flexion (deg, 0 = extended)";
    fascicle.yLabel = "fascicle length (cm)";
    emg.title = title + ": normalised EMG";
    emg.yLabel = "EMG (fraction of MVC amplitude)";
    auto seriesOf = [](PlotSpec& p, const std::string& label) -> PlotSeries& {
        for (PlotSeries& s : p.series)
            if (s.label == label) return s;
        p.series.push_back({label, {}, {}, true, int(p.series.size()) % 8});
        return p.series.back();
    };
    for (const ChannelObservation& o : data) {
        if (o.channel == "fascicle_length") {
            PlotSeries& s = seriesOf(fascicle, o.muscle + (o.level == 0 ? " at rest" : " at " + formatNumber(100 * o.level) + " %"));
            s.x.push_back(o.flexionDeg);
            s.y.push_back(100 * o.value);
        } else if (o.channel == "emg") {
            PlotSeries& s = seriesOf(emg, o.muscle + (o.effort == Effort::Flexion ? " in flexion" : " in extension"));
            s.x.push_back(o.flexionDeg);
            s.y.push_back(o.value);
        }
    }
    std::vector<std::string> paths;
    if (!fascicle.series.empty()) {
        paths.push_back(dir + "/fascicle_length.png");
        writePlotPng(paths.back(), fascicle);
    }
    if (!emg.series.empty()) {
        paths.push_back(dir + "/emg.png");
        writePlotPng(paths.back(), emg);
    }
    return paths;
}

}  // namespace armsim

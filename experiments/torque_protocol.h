// Torque protocols: isometric efforts of a (virtual) subject at elbow angles, read by a
// tared joint-torque transducer. A condition is one effort kind at one angle: a flexion or an extension
// effort, or on a model with a forearm rotation a supination or a pronation effort, maximal (level 1)
// or held at a fraction of the agonists' MVC EMG by EMG feedback (level < 1), repeated. A two-axis
// transducer (measurements.forearm_torque, implied by a rotation effort) also reads the torque about
// the forearm axis in every trial. The thesis's protocol is five flexion MVCs x 3. Protocol files (kind: torque) are what
// `armsim design` writes and `armsim protocol` and `armsim validate --protocol` run; torque data files
// (CSV) are what a run writes and the identifiers read.
//
// Efforts: at level l the agonists get U = l VA (1 + cv z) (clipped to [0, 1]) and the antagonists
// l CC, with VA the subject's voluntary activation, CC its co-contraction, cv its trial-to-trial
// variation and z ~ N(0, 1) per trial. Each trial's tared torque is averaged over the end of the hold,
// then multiplied by (1 + sd z') for a one-axis transducer (z' ~ N(0, 1)). A two-axis transducer adds
// sd |T| z' to each axis it reads, |T| the magnitude of the clean torque vector (both axes): a load
// cell's error scales with its load, cross-talk between the axes included.
#pragma once

#include "basics/numbers.h"

#include "experiments/population.h"
#include "model/geometry.h"

#include <cmath>
#include <functional>
#include <string>
#include <tuple>
#include <vector>

namespace armsim {

class Table;
struct ChannelObservation;

/// One condition of a torque protocol.
struct TorqueCondition {
    double flexionDeg = 90;                     ///< elbow flexion [deg], 0 = extended
    Effort effort = Effort::Flexion;            ///< what the subject does (agonists: model/model_file.h)
    double level = 1.0;                         ///< drive as a fraction of maximal (1 = MVC) [1]
    int repetitions = 3;                        ///< trials of this condition
    /// Channels recorded in each trial besides torque (experiments/channels.h): ultrasound images the
    /// primary muscle's fascicle at rest and at the plateau; emg records the surface_emg muscles.
    bool ultrasound = false;
    bool emg = false;
    /// Forearm posture [deg], + = supination (rotation_deg; a model with a forearm rotation only);
    /// NaN = the model's posture. Ultrasound and EMG are read at the model's posture only.
    double rotationDeg = kNaN;
};

/// Measurement error of the channels besides torque (experiments/channels.h). Defaults and their
/// sources: docs/channels.md.
struct ChannelNoise {
    double fascicleLength = 0.05;   ///< relative sd of one ultrasound fascicle length (extended field of view) [1]
    double volume = 0.10;           ///< relative sd of one head's volume from a panoramic scan [1]
    double emg = 0.15;              ///< relative sd of one trial's normalised EMG amplitude [1]
    double emgCrosstalk = 0.10;     ///< c: fraction of the other group's activation an electrode picks up [1]
    double upperArmLength = 0.01;   ///< sd of the anthropometric upper-arm length [m]
};


/// The effort column's code in data files: 1 flexion, -1 extension, 2 supination, -2 pronation.
int getEffortCode(Effort e);

/// A protocol of isometric efforts read by a tared torque transducer.
struct TorqueProtocol {
    std::string name = "thesis_mvc";
    std::string description;
    /// Default: the thesis's five flexion MVCs (45..150 deg included = 135..30 deg flexion) x 3.
    std::vector<TorqueCondition> conditions = makeFlexionMvcs(getThesisMvcFlexionDeg(), 3);
    double restDuration = 0.5;       ///< [s] relaxed, transducer tared at its start
    double holdDuration = 3.0;       ///< [s] effort (thesis: 3 s)
    double averagingWindow = 1.0;    ///< [s] end of the hold averaged (thesis: last second)
    double sampleRate = 200.0;       ///< [Hz] transducer samples
    /// Who `armsim protocol` runs it on: person `subjectIndex` of this population file, or, when it is
    /// empty, the model `model` (name or file) with its own effort and `transducerNoise`.
    std::string population;
    int subjectIndex = 0;
    std::string model = kDefaultSubjectModel;
    /// An OpenSim model's (usesOsimModel) coordinate the efforts act about, "" = its only one. Its
    /// conditions' flexion_deg is then that coordinate's value [deg], flexion its positive direction.
    std::string coordinate;
    double transducerNoise = 0.02;   ///< relative sd (model subject only) [1]
    unsigned seed = 1;               ///< population and noise seed
    /// Muscles whose volume a panoramic ultrasound scan measures (once each; names in the model).
    std::vector<std::string> volumeScan;
    std::string volumeScanWhere;     ///< "file:line" of volume_scan when read from a file, for messages
    std::string source;              ///< the file it was read from ("" when made in code), for messages
    /// "<file>: protocol '<name>'" (or "protocol '<name>'"), how messages name it.
    std::string describe() const { return (source.empty() ? "" : source + ": ") + "protocol '" + name + "'"; }
    bool anthropometry = false;      ///< the upper-arm length measured
    /// A two-axis transducer: every trial also reads the torque about the forearm axis (a model with a
    /// forearm rotation). Rotation efforts imply it (readsForearmTorque).
    bool forearmTorque = false;
    ChannelNoise channelNoise;       ///< errors of the channels besides torque

    /// Flexion MVCs at the angles, each repeated.
    static std::vector<TorqueCondition> makeFlexionMvcs(const std::vector<double>& flexionDeg, int repetitions);
    int getNumTrials() const;        ///< sum of the repetitions
    /// true when some condition is a submaximal (EMG-feedback) effort.
    bool usesEmg() const;
    /// true when some condition or measurement records a channel besides torque.
    bool hasChannels() const;
    /// true when the trials read the forearm axis too: forearmTorque or a rotation effort.
    bool readsForearmTorque() const;
    /// true when the subject is an OpenSim model (model/osim_forward.h isOsimModel).
    bool usesOsimModel() const;
    /// FieldError naming the field ("conditions[2].level", ...) unless every value is in range.
    void validate() const;
};

/// One line, e.g. "flexion MVC at 135, 120, 90 deg x 3; extension 50 % at 90 deg x 2".
std::string describeConditions(const TorqueProtocol& protocol);

/// Reads a protocol file of kind torque strictly (unknown keys, values out of range and duplicate
/// conditions are InputErrors naming file, line and key).
TorqueProtocol readTorqueProtocol(const std::string& path);
/// The file text readTorqueProtocol reads back (same conditions and settings).
std::string formatTorqueProtocol(const TorqueProtocol& protocol);

/// true when the protocol file's kind is torque (it is read with readTorqueProtocol, not readProtocol).
bool isTorqueProtocolFile(const std::string& path);
/// The subject the protocol names: person subjectIndex of its population (seeded with its seed), or its
/// model with the model's effort and the protocol's transducer noise.
VirtualSubject loadTorqueProtocolSubject(const TorqueProtocol& protocol);

/// One measured effort.
struct TorqueObservation {
    double flexionDeg = 0;     ///< [deg], 0 = extended
    Effort effort = Effort::Flexion;
    double level = 1.0;        ///< drive as a fraction of maximal [1]
    int repetition = 0;
    double torque = 0;         ///< tared elbow torque, + = flexion [N m] (with transducer noise)
    double activation = NAN;   ///< agonist activation the subject actually produced (truth; not used by identifiers) [1]
    double cleanTorque = NAN;  ///< the torque before transducer noise (truth) [N m]
    double noiseDraw = NAN;    ///< the standard normal draw of its noise: torque = cleanTorque (1 + sd noiseDraw)
    double antagonistActivation = NAN;  ///< the antagonists' activation (truth) [1]
    double restFascicleLength = NAN;    ///< the primary's fascicle at rest before the effort (truth) [m]
    double fascicleLength = NAN;        ///< the primary's fascicle at the plateau, window mean (truth) [m]
    double rotationDeg = kNaN;  ///< forearm posture [deg], + = supination; NaN = the model's posture
    /// Tared torque about the forearm axis, + = supination [N m] (with transducer noise); NaN: not read.
    double forearmTorque = kNaN;
    double cleanForearmTorque = kNaN;  ///< the same before transducer noise (truth) [N m]
    double forearmNoiseDraw = kNaN;    ///< its standard normal noise draw
    int line = 0;              ///< line in the file it was read from (0: synthesized)
    /// The reading about the effort's own axis: torque for flexion and extension, forearmTorque for
    /// supination and pronation [N m].
    double getEffortTorque() const { return isForearmEffort(effort) ? forearmTorque : torque; }
    /// The magnitude of the torque the transducer reads [N m]: |torque| on one axis, the length of the
    /// (torque, forearmTorque) vector on two. The transducer noise's sd is proportional to it.
    double getLoad() const { return std::isfinite(forearmTorque) ? std::hypot(torque, forearmTorque) : std::abs(torque); }
    /// A maximal flexion effort.
    bool isFlexionMvc() const { return effort == Effort::Flexion && level == 1; }
    /// A maximal flexion effort in the model's forearm posture: what the thesis's method uses.
    bool isThesisMvc() const { return isFlexionMvc() && std::isnan(rotationDeg); }
};

/// What a torque protocol's run on the subject it names gives.
struct TorqueProtocolRun {
    std::string subject;                       ///< who ran it, for reports ("model twin", "arm26 (OpenSim) ...")
    std::vector<TorqueObservation> data;       ///< per trial, with its truth columns
    std::vector<ChannelObservation> channels;  ///< the channels besides torque (hasChannels)
};

/// Runs the protocol on its subject (`armsim protocol`, Python's run_protocol): synthesizeTorqueData
/// and synthesizeChannelData on a population person or an armsim model, synthesizeOsimTorqueData on an
/// OpenSim model. Seeded with the protocol's seed; trials on `jobs` threads; progress(done, total) per
/// trial of an armsim model, from the caller's thread.
TorqueProtocolRun runTorqueProtocol(const TorqueProtocol& protocol, int jobs = 1,
                                    const std::function<void(int, int)>& progress = {});

/// The protocol's trials on its OpenSim model (usesOsimModel): each an isometric trial
/// (model/osim_trial.h) of the coordinate locked at flexion_deg, the muscles that pull it the effort's
/// way (flexion: its positive direction) excited to `level` and the others at rest, read as the tared
/// torque about the coordinate (+ = its positive direction) with the protocol's relative transducer
/// noise. No voluntary-activation deficit or trial variation (the file has no such model), no channels
/// and no forearm axis (validate refuses them). Reproducible from noiseSeed; trials on `jobs` threads.
std::vector<TorqueObservation> synthesizeOsimTorqueData(const TorqueProtocol& protocol, unsigned noiseSeed, int jobs = 1);

/// What makes a condition: (flexion, effort, level, rotation), the model's posture (NaN) as +inf so
/// keys compare and sort.
using ConditionKey = std::tuple<double, int, double, double>;
ConditionKey getConditionKey(const TorqueObservation& o);
/// true when a and b are the same condition (angle, effort, level, posture).
bool isSameCondition(const TorqueObservation& a, const TorqueObservation& b);
/// true when an observation has a forearm posture other than the model's (files then carry rotation_deg).
bool hasPostures(const std::vector<TorqueObservation>& data);
/// A forearm posture for tables: "-" for the model's (NaN), else the rotation in deg ("-90", "90").
std::string formatPosture(double rotationDeg);

/// Runs the protocol on the subject and adds relative transducer noise of the subject's sd.
/// Reproducible from (subject, noiseSeed); trials run on `jobs` threads. Trial order: repetition-major
/// (every condition's first trial, then every second one, ...).
std::vector<TorqueObservation> synthesizeTorqueData(const VirtualSubject& subject, const TorqueProtocol& protocol,
                                                    unsigned noiseSeed, int jobs = 1,
                                                    const std::function<void(int, int)>& progress = {});

/// The same efforts read through a transducer of another relative noise sd (the same noise draws:
/// common random numbers across noise levels).
std::vector<TorqueObservation> setTransducerNoise(std::vector<TorqueObservation> data, double sd);

/// Torque data as CSV: flexion_deg, effort (1 = flexion, -1 = extension, 2 = supination, -2 = pronation),
/// level, repetition, torque_Nm; rotation_deg when a trial has a posture; forearm_torque_Nm (+ =
/// supination, NaN where not read) when a trial reads the forearm axis; with truth=true also activation,
/// clean_torque_Nm (and clean_forearm_torque_Nm) (synthetic data).
std::string formatTorqueData(const std::vector<TorqueObservation>& data, bool truth);
/// The most rows a torque data file may have: each identification evaluates every row many times.
constexpr int kMaxTorqueRows = 10000;
/// Reads a torque data file (Table::readCsv: '#' comments, header line). Required columns flexion_deg
/// and torque_Nm; effort (default 1), level (default 1), repetition (default: count per condition),
/// rotation_deg and forearm_torque_Nm optional (a rotation effort needs its forearm torque); other
/// columns are errors; at most kMaxTorqueRows rows. Errors name file, line, column, value and the
/// expected range.
std::vector<TorqueObservation> readTorqueData(const std::string& path);
/// The same from a table already in memory; `source` names it in messages.
std::vector<TorqueObservation> makeTorqueData(const Table& table, const std::string& source);

/// PNG of tared torque vs flexion angle, one series per effort kind (flexion/extension, level), every
/// trial as a marker. Written whole or not at all.
void writeTorquePlot(const std::string& path, const std::vector<TorqueObservation>& data, const std::string& title);

/// What `armsim protocol` writes for a torque protocol's run into dir: torque_data.csv (with the
/// truth columns), protocol.yaml and torque_angle.png, and with channels channel_data.csv (truth
/// column too) and their plots (writeChannelPlots), each whole or not at all. Returns the paths.
std::vector<std::string> writeTorqueProtocolRun(const std::string& dir, const TorqueProtocol& protocol,
                                                const std::vector<TorqueObservation>& data,
                                                const std::vector<ChannelObservation>& channels = {});

}  // namespace armsim

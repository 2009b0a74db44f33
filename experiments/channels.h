// The channels a lab records besides joint torque, each with its measurement model, synthesized on
// virtual subjects and read from a lab's CSV:
// - fascicle_length: B-mode ultrasound of the primary muscle's fascicle length [m], imaged at rest
//   (level 0) just before an effort and at the effort's plateau; relative error sd_f (the fascicle
//   runs beyond the probe and is extrapolated).
// - volume: a muscle's volume [m^3] from a panoramic ultrasound scan (ACSA x length x shape factor):
//   relative error sd_v. With specific tension varying between people, torque sees
//   F0 = sigma V / L0 and only this channel sees V (mass = rho V).
// - emg: surface EMG amplitude of each muscle in the model's surface_emg role, normalised to that
//   muscle's amplitude in an MVC of its own group: e_m = (a_m + c a_o) / (VA + c CC) with a_m the
//   muscle's activation, a_o the activation of the other group (crosstalk c) and VA, CC the subject's
//   voluntary activation and co-contraction; relative error sd_e.
// - upper_arm_length: anthropometry, acromion to lateral epicondyle [m]; absolute error sd_a. It gives
//   the person's size (the population's geometry scale: segments, paths and muscle lengths together).
// Every error is multiplicative (or additive for anthropometry) and Gaussian, drawn per measurement.
#pragma once

#include "basics/numbers.h"

#include "experiments/torque_protocol.h"

#include <string>
#include <vector>

namespace armsim {

/// One measurement of a channel other than torque.
struct ChannelObservation {
    std::string channel;        ///< fascicle_length, volume, emg or upper_arm_length
    std::string muscle;         ///< the muscle measured (empty for upper_arm_length)
    double flexionDeg = kNaN;  ///< elbow flexion during the measurement [deg] (NaN: volume, anthropometry)
    Effort effort = Effort::Flexion;  ///< the effort it was recorded in (flexion or extension)
    double level = 0;           ///< the effort's drive [1]; 0: relaxed (fascicle at rest)
    int repetition = 0;
    double value = 0;           ///< the measurement [m, m^3 or 1]
    double sd = 0;              ///< its measurement sd, same units [> 0]
    double cleanValue = kNaN;  ///< before measurement error (truth; synthetic data)
    int line = 0;               ///< line in the file it was read from (0: synthesized)
    std::string source;         ///< the file it was read from ("" : synthesized)
};

/// Floor of the level an EMG amplitude's relative error applies to: a relaxed muscle reads about 1-2 %
/// of its MVC amplitude (an assumption, docs/channels.md), so the sd of small values does not vanish.
inline constexpr double kEmgFloor = 0.02;
/// The smallest sd a channel file may give: 0.1 % of the value (fascicle length, volume, upper-arm
/// length), 1e-4 of the MVC amplitude (EMG). Finer than any instrument (docs/channels.md); the
/// protocol's channel_noise has the matching lower bounds, so synthesized files read back.
inline constexpr double kMinChannelSdRelative = 1e-3;
inline constexpr double kMinChannelSdEmg = 1e-4;

/// The most measurements a channel file may hold (each is a residual of every fit; 400,000 rows ran
/// for minutes): the torque data's cap.
inline constexpr std::size_t kMaxChannelRows = 10000;

/// The names channels may have.
const std::vector<std::string>& getChannelNames();

/// Synthesizes every channel the protocol names on the subject: per condition with ultrasound, the
/// primary muscle's fascicle length at rest and at the plateau of each trial (from the trials of
/// `torque`, which must be synthesizeTorqueData's output for the same subject and protocol); per
/// condition with emg, every surface_emg muscle's normalised amplitude per trial; the volume scan and
/// anthropometry when the protocol asks. Errors from the protocol's channel noise, seeded by
/// (noiseSeed, subject). Throws InputError for a protocol that records EMG on a model without a
/// surface_emg role, or a volume scan of a muscle the model does not have.
std::vector<ChannelObservation> synthesizeChannelData(const VirtualSubject& subject, const TorqueProtocol& protocol,
                                                      const std::vector<TorqueObservation>& torque,
                                                      unsigned noiseSeed);

/// Channel data as CSV: channel, muscle, flexion_deg, effort (1 flexion, -1 extension), level,
/// repetition, value, sd; with truth=true also clean_value.
std::string formatChannelData(const std::vector<ChannelObservation>& data, bool truth);
/// Reads channel data ('#' comments, a header line, RFC 4180 cells). Required: channel, value, sd; muscle
/// (required except for upper_arm_length), flexion_deg (required for fascicle_length and emg),
/// effort, level, repetition optional. Errors name file, line, column, value and what was expected.
std::vector<ChannelObservation> readChannelData(const std::string& path);

/// PNGs against flexion angle, every measurement a marker, each written whole or not at all:
/// dir/fascicle_length.png (the ultrasound channel) and dir/emg.png, each only when the data hold
/// that channel. Returns the paths written.
std::vector<std::string> writeChannelPlots(const std::string& dir, const std::vector<ChannelObservation>& data,
                                           const std::string& title);

}  // namespace armsim

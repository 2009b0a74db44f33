// Channels besides torque: protocol files name them and read back, synthesis follows the stated
// measurement models (checked against the steady state and the subject's parameters), channel CSVs read
// back what was written, and bad files are refused naming file, line, column and value.
#include "basics/errors.h"
#include "basics/files.h"
#include "experiments/channels.h"
#include "model/mvc_curve.h"
#include "muscles/muscle_file.h"

#include "tests/support/temp_files.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

using namespace armsim;

namespace {

std::string writeTemp(const std::string& name, const std::string& text) { return armsim::testing::writeTempFile(name, text); }

template <class F> std::string errorOf(F&& f) { return armsim::testing::getInputErrorOf(f); }

// Two flexion MVCs with every channel, a submaximal one with EMG only, every measurement.
TorqueProtocol makeChannelProtocol(double noise) {
    TorqueProtocol p;
    p.name = "channels";
    p.conditions = {{30, Effort::Flexion, 1.0, 2, true, true}, {90, Effort::Flexion, 1.0, 1, true, true},
                    {120, Effort::Flexion, 0.4, 1, false, true}};
    p.holdDuration = 2.0;
    p.averagingWindow = 0.5;
    p.volumeScan = {"BIClong", "BRA"};
    p.anthropometry = true;
    p.channelNoise = {noise, noise, noise, 0.1, noise};
    return p;
}

const Population& population() {
    static const Population p = loadDefaultPopulation();
    return p;
}

}  // namespace

TEST(Channels, ProtocolFileReadsBackItsChannels) {
    const TorqueProtocol p = readTorqueProtocol(findAsset("protocols/recommended.yaml"));
    ASSERT_TRUE(p.hasChannels());
    const TorqueProtocol q = readTorqueProtocol(writeTemp("armsim_channels_protocol.yaml", formatTorqueProtocol(p)));
    ASSERT_EQ(q.conditions.size(), p.conditions.size());
    for (std::size_t k = 0; k < p.conditions.size(); ++k) {
        EXPECT_EQ(q.conditions[k].ultrasound, p.conditions[k].ultrasound) << k;
        EXPECT_EQ(q.conditions[k].emg, p.conditions[k].emg) << k;
    }
    EXPECT_EQ(q.volumeScan, p.volumeScan);
    EXPECT_EQ(q.anthropometry, p.anthropometry);
    EXPECT_EQ(q.channelNoise.volume, p.channelNoise.volume);
    EXPECT_EQ(q.channelNoise.emgCrosstalk, p.channelNoise.emgCrosstalk);
    EXPECT_FALSE(TorqueProtocol().hasChannels());
    EXPECT_NE(describeConditions(p).find("with ultrasound and EMG"), std::string::npos) << describeConditions(p);
}

TEST(Channels, BadProtocolChannelsNameFileLineAndValue) {
    const std::string head = "name: x\nkind: torque\nconditions:\n";
    std::string e = errorOf([&] {
        readTorqueProtocol(writeTemp("armsim_ch_bad1.yaml", head + "  - {flexion_deg: 90, channels: [torque, mri]}\n"));
    });
    EXPECT_NE(e.find("armsim_ch_bad1.yaml:4"), std::string::npos) << e;
    EXPECT_NE(e.find("'mri'"), std::string::npos) << e;
    e = errorOf([&] {
        readTorqueProtocol(writeTemp("armsim_ch_bad2.yaml", head + "  - {flexion_deg: 90, channels: [emg]}\n"));
    });
    EXPECT_NE(e.find("leaves out torque"), std::string::npos) << e;
    e = errorOf([&] {
        readTorqueProtocol(writeTemp("armsim_ch_bad3.yaml", "name: x\nkind: torque\nchannel_noise: {volume: 0.9}\n"
                                                            "conditions:\n  - {flexion_deg: 90}\n"));
    });
    EXPECT_NE(e.find("volume"), std::string::npos) << e;
    EXPECT_NE(e.find("0.9"), std::string::npos) << e;
    e = errorOf([&] {
        readTorqueProtocol(writeTemp("armsim_ch_bad4.yaml", "name: x\nkind: torque\nmeasurements: {volume_scan: [BIClong, BIClong]}\n"
                                                            "conditions:\n  - {flexion_deg: 90}\n"));
    });
    EXPECT_NE(e.find("'measurements.volume_scan' (entry 2)"), std::string::npos) << e;
    EXPECT_NE(e.find("listed twice"), std::string::npos) << e;
    {  // EMG on a model that names no surface_emg muscles
        VirtualSubject bare = drawSubject(population(), 1, 0);
        bare.setup.surfaceEmg.clear();
        const TorqueProtocol q = makeChannelProtocol(0.05);
        e = errorOf([&] { synthesizeChannelData(bare, q, synthesizeTorqueData(bare, q, 1), 1); });
        EXPECT_NE(e.find("surface_emg"), std::string::npos) << e;
    }
    // A volume scan of a muscle the subject does not have: named at synthesis.
    TorqueProtocol p = makeChannelProtocol(0.05);
    p.volumeScan = {"DELT"};
    const VirtualSubject v = drawSubject(population(), 1, 0);
    e = errorOf([&] { synthesizeChannelData(v, p, synthesizeTorqueData(v, p, 1), 1); });
    EXPECT_NE(e.find("volume_scan"), std::string::npos) << e;
    EXPECT_NE(e.find("DELT"), std::string::npos) << e;
}

// Clean values follow the measurement models: the fascicle at rest is the relaxed steady state (a
// second method: steady solve vs the trial's integration), at the plateau the steady state at the
// trial's activation; volume = M / rho; EMG = (a + c a_o) / (VA + c CC); upper-arm length = the
// subject's. Errors have the stated relative sd.
TEST(Channels, SynthesisFollowsTheMeasurementModels) {
    constexpr double kRest = 1e-6;      // relative: same equilibrium, the trial starts from it
    constexpr double kPlateau = 2e-3;   // relative: 2 s hold vs the steady state (activation dynamics settle)
    constexpr double kExact = 1e-12;
    const TorqueProtocol p = makeChannelProtocol(0.05);
    const VirtualSubject v = drawSubject(population(), 4, 2);
    const std::vector<TorqueObservation> torque = synthesizeTorqueData(v, p, 3);
    const std::vector<ChannelObservation> data = synthesizeChannelData(v, p, torque, 3);
    const ArmSetup& s = v.setup;
    const MuscleParameters& q = s.muscles[s.primary].params;
    int fascicles = 0, emgs = 0, volumes = 0, arms = 0;
    double sumSq = 0;
    int drawn = 0;
    for (const ChannelObservation& o : data) {
        ASSERT_GT(o.sd, 0) << o.channel;
        if (o.channel != "upper_arm_length") {
            sumSq += std::pow(o.value / o.cleanValue - 1, 2);
            ++drawn;
        }
        if (o.channel == "fascicle_length") {
            ++fascicles;
            const TorqueObservation* t = nullptr;
            for (const TorqueObservation& x : torque)
                if (x.flexionDeg == o.flexionDeg && x.repetition == o.repetition) t = &x;
            ASSERT_NE(t, nullptr);
            SubjectEffort e;
            e.voluntaryActivation = o.level == 0 ? 0 : t->activation;
            e.coContraction = o.level == 0 ? 0 : t->antagonistActivation;
            const SteadyMvcCurve c = calcSteadyMvcCurve(s, MuscleGroup::Flexor, e, {o.flexionDeg});
            const double steady = c.points[0][s.primary].fibreLength * q.optimalFascicleLength;
            EXPECT_NEAR(o.cleanValue, steady, (o.level == 0 ? kRest : kPlateau) * steady) << o.flexionDeg << " " << o.level;
        } else if (o.channel == "volume") {
            ++volumes;
            const MuscleParameters& m = s.muscles[s.findMuscle(o.muscle)].params;
            EXPECT_NEAR(o.cleanValue, m.mass / m.coefficients.density, kExact);
        } else if (o.channel == "emg") {
            ++emgs;
            const TorqueObservation* t = nullptr;
            for (const TorqueObservation& x : torque)
                if (x.flexionDeg == o.flexionDeg && x.repetition == o.repetition) t = &x;
            ASSERT_NE(t, nullptr);
            const bool agonist = s.muscles[s.findMuscle(o.muscle)].group == MuscleGroup::Flexor;
            const double own = agonist ? t->activation : t->antagonistActivation;
            const double other = agonist ? t->antagonistActivation : t->activation;
            const double mvc = s.effort.voluntaryActivation + 0.1 * s.effort.coContraction;
            EXPECT_NEAR(o.cleanValue, (own + 0.1 * other) / mvc, kExact) << o.muscle;
        } else {
            ++arms;
            EXPECT_NEAR(o.cleanValue, s.arm.upperArmLength, kExact);
            EXPECT_NEAR(o.cleanValue, v.geometryScale * population().base.arm.upperArmLength, kExact);
        }
    }
    EXPECT_EQ(fascicles, 2 * 3);                           // rest + plateau per trial with ultrasound
    EXPECT_EQ(emgs, 4 * int(s.surfaceEmg.size()));         // every trial records EMG
    EXPECT_EQ(volumes, 2);
    EXPECT_EQ(arms, 1);
    // Relative errors have sd 0.05: with ~30 draws the sample sd lies within 0.025..0.08 (chi-square 99.9 %).
    const double sd = std::sqrt(sumSq / drawn);
    EXPECT_GT(sd, 0.025);
    EXPECT_LT(sd, 0.08);
    // Reproducible from the seeds.
    const std::vector<ChannelObservation> again = synthesizeChannelData(v, p, torque, 3);
    ASSERT_EQ(again.size(), data.size());
    for (std::size_t k = 0; k < data.size(); ++k) EXPECT_EQ(again[k].value, data[k].value);
}

TEST(Channels, CsvReadsBackWhatWasWritten) {
    const TorqueProtocol p = makeChannelProtocol(0.05);
    const VirtualSubject v = drawSubject(population(), 1, 1);
    const std::vector<ChannelObservation> data = synthesizeChannelData(v, p, synthesizeTorqueData(v, p, 1), 1);
    const std::vector<ChannelObservation> back =
        readChannelData(writeTemp("armsim_channels.csv", formatChannelData(data, true)));
    ASSERT_EQ(back.size(), data.size());
    for (std::size_t k = 0; k < data.size(); ++k) {
        EXPECT_EQ(back[k].channel, data[k].channel);
        EXPECT_EQ(back[k].muscle, data[k].muscle);
        EXPECT_EQ(back[k].value, data[k].value);
        EXPECT_EQ(back[k].sd, data[k].sd);
        EXPECT_EQ(back[k].level, data[k].level);
        EXPECT_EQ(back[k].effort, data[k].effort);
        EXPECT_TRUE(back[k].flexionDeg == data[k].flexionDeg || (std::isnan(back[k].flexionDeg) && std::isnan(data[k].flexionDeg)));
    }
}

TEST(Channels, BadCsvNamesFileLineColumnAndValue) {
    const std::string header = "channel,muscle,flexion_deg,level,value,sd\n";
    auto error = [&](const std::string& body) {
        return errorOf([&] { readChannelData(writeTemp("armsim_ch_bad.csv", header + body)); });
    };
    std::string e = error("fascicle_length,BIClong,90,0,0.12,0.006\nmri,BIClong,90,0,0.12,0.006\n");
    EXPECT_NE(e.find("armsim_ch_bad.csv:3"), std::string::npos) << e;
    EXPECT_NE(e.find("'mri'"), std::string::npos) << e;
    e = error("volume,BIClong,,0,0.0002,0\n");
    EXPECT_NE(e.find("column 'sd' = 0"), std::string::npos) << e;
    e = error("fascicle_length,BIClong,,0,0.12,0.006\n");
    EXPECT_NE(e.find("flexion_deg"), std::string::npos) << e;
    e = error("emg,TRIlong,90,0,0.1,0.02\n");
    EXPECT_NE(e.find("level"), std::string::npos) << e;
    e = error("volume,BIClong,,0,abc,0.1\n");
    EXPECT_NE(e.find("'abc'"), std::string::npos) << e;
    e = errorOf([&] { readChannelData(writeTemp("armsim_ch_bad2.csv", "channel,value,sd,colour\n")); });
    EXPECT_NE(e.find("unknown column 'colour'"), std::string::npos) << e;
}

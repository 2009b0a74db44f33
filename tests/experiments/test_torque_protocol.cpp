// Torque protocols and torque data files: files read back what was written, bad files are refused
// with file, line and field, and synthesized trials follow the stated effort model.
#include "basics/errors.h"
#include "experiments/torque_protocol.h"
#include "model/osim_file.h"
#include "model/osim_trial.h"
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

TorqueProtocol makeMixedProtocol() {
    TorqueProtocol p;
    p.name = "mixed";
    p.description = "flexion, extension and submaximal";
    p.conditions = {{90, Effort::Flexion, 1.0, 2}, {45, Effort::Extension, 1.0, 3},
                    {120, Effort::Flexion, 0.3, 1}};
    p.holdDuration = 1.5;
    p.averagingWindow = 0.5;
    p.seed = 11;
    return p;
}

}  // namespace

TEST(TorqueProtocol, FileReadsBackWhatWasWritten) {
    const TorqueProtocol p = makeMixedProtocol();
    const TorqueProtocol q = readTorqueProtocol(writeTemp("armsim_torque_protocol.yaml", formatTorqueProtocol(p)));
    EXPECT_TRUE(isTorqueProtocolFile(writeTemp("armsim_torque_protocol.yaml", formatTorqueProtocol(p))));
    ASSERT_EQ(q.conditions.size(), p.conditions.size());
    for (std::size_t k = 0; k < p.conditions.size(); ++k) {
        EXPECT_EQ(q.conditions[k].flexionDeg, p.conditions[k].flexionDeg);
        EXPECT_EQ(q.conditions[k].effort, p.conditions[k].effort);
        EXPECT_EQ(q.conditions[k].level, p.conditions[k].level);
        EXPECT_EQ(q.conditions[k].repetitions, p.conditions[k].repetitions);
    }
    EXPECT_EQ(q.name, p.name);
    EXPECT_EQ(q.description, p.description);
    EXPECT_EQ(q.holdDuration, p.holdDuration);
    EXPECT_EQ(q.seed, p.seed);
    EXPECT_EQ(q.getNumTrials(), 6);
    EXPECT_TRUE(q.usesEmg());
    EXPECT_EQ(describeConditions(q), "flexion MVC at 90 deg x 2; extension MVC at 45 deg x 3; flexion 30 % at 120 deg x 1");
}

// Forearm postures (issue 31): rotation_deg reads back from the protocol file and the torque CSV (NaN
// there: the model's posture), the same angle in two postures is two conditions, and ultrasound or EMG
// with a posture is refused with the field named.
TEST(TorqueProtocol, ForearmPosturesReadBackAndKeepConditionsApart) {
    TorqueProtocol p;
    p.conditions = TorqueProtocol::makeFlexionMvcs({90, 60}, 2);
    TorqueCondition pronated = p.conditions[0];
    pronated.rotationDeg = -90;
    p.conditions.push_back(pronated);
    const TorqueProtocol q = readTorqueProtocol(writeTemp("armsim_posture_protocol.yaml", formatTorqueProtocol(p)));
    ASSERT_EQ(q.conditions.size(), 3u);
    EXPECT_TRUE(std::isnan(q.conditions[0].rotationDeg));
    EXPECT_EQ(q.conditions[2].rotationDeg, -90);
    std::vector<TorqueObservation> data(3);
    data[0] = {90, Effort::Flexion, 1.0, 0, 60.5};
    data[1] = {90, Effort::Flexion, 1.0, 0, 40.25};
    data[1].rotationDeg = -90;
    data[2] = {90, Effort::Flexion, 1.0, 1, 41.0};
    data[2].rotationDeg = -90;
    const std::vector<TorqueObservation> back = readTorqueData(writeTemp("armsim_posture.csv", formatTorqueData(data, false)));
    ASSERT_EQ(back.size(), 3u);
    EXPECT_TRUE(std::isnan(back[0].rotationDeg));
    EXPECT_EQ(back[1].rotationDeg, -90);
    EXPECT_FALSE(isSameCondition(back[0], back[1]));   // same angle, other posture
    EXPECT_TRUE(isSameCondition(back[1], back[2]));
    const std::string e = errorOf([&] {
        readTorqueProtocol(writeTemp("armsim_bad_posture.yaml", "name: t\nkind: torque\nconditions:\n"
                                     "  - {flexion_deg: 90, rotation_deg: 90, channels: [torque, ultrasound]}\n"));
    });
    EXPECT_NE(e.find("armsim_bad_posture.yaml"), std::string::npos) << e;
    EXPECT_NE(e.find("'channels' (conditions, entry 1)"), std::string::npos) << e;
    EXPECT_NE(errorOf([&] { readTorqueData(writeTemp("armsim_bad_posture.csv", "flexion_deg,torque_Nm,rotation_deg\n90,50,200\n")); })
                  .find("'rotation_deg' = 200"), std::string::npos);
}

TEST(TorqueProtocol, BadFilesNameTheFileLineAndField) {
    const std::string head = "name: t\nkind: torque\nconditions:\n";
    auto read = [&](const std::string& body) {
        return errorOf([&] { readTorqueProtocol(writeTemp("armsim_bad_torque.yaml", head + body)); });
    };
    std::string e = read("  - {effort: flexion, flexion_deg: 90, level: 0}\n");
    EXPECT_NE(e.find("armsim_bad_torque.yaml:4"), std::string::npos) << e;
    EXPECT_NE(e.find("level"), std::string::npos) << e;
    e = read("  - {effort: sideways, flexion_deg: 90}\n");
    EXPECT_NE(e.find("sideways"), std::string::npos) << e;
    EXPECT_NE(e.find("extension"), std::string::npos) << e;
    e = read("  - {effort: flexion, flexion_deg: 190}\n");
    EXPECT_NE(e.find("flexion_deg"), std::string::npos) << e;
    e = read("  - {effort: flexion, flexion_deg: 90, repeats: 2}\n");
    EXPECT_NE(e.find("repeats"), std::string::npos) << e;
    e = read("  - {flexion_deg: 90}\n  - {flexion_deg: 90, repetitions: 2}\n");
    EXPECT_NE(e.find("listed twice"), std::string::npos) << e;
    e = errorOf([&] { readTorqueProtocol(writeTemp("armsim_bad_torque.yaml", "name: t\nkind: mvc\nconditions: []\n")); });
    EXPECT_NE(e.find("kind"), std::string::npos) << e;
}

TEST(TorqueData, FileReadsBackAndBadRowsNameLineAndColumn) {
    std::vector<TorqueObservation> data(3);
    data[0] = {90, Effort::Flexion, 1.0, 0, 60.5};
    data[1] = {90, Effort::Flexion, 1.0, 1, 58.25};
    data[2] = {45, Effort::Extension, 0.5, 0, -20.125};
    const std::vector<TorqueObservation> back = readTorqueData(writeTemp("armsim_torque.csv", formatTorqueData(data, false)));
    ASSERT_EQ(back.size(), 3u);
    for (std::size_t k = 0; k < 3; ++k) {
        EXPECT_EQ(back[k].flexionDeg, data[k].flexionDeg);
        EXPECT_EQ(back[k].effort, data[k].effort);
        EXPECT_EQ(back[k].level, data[k].level);
        EXPECT_EQ(back[k].repetition, data[k].repetition);
        EXPECT_EQ(back[k].torque, data[k].torque);
    }
    EXPECT_TRUE(isSameCondition(back[0], back[1]));
    EXPECT_FALSE(isSameCondition(back[0], back[2]));
    auto read = [&](const std::string& text) {
        return errorOf([&] { readTorqueData(writeTemp("armsim_bad_torque.csv", text)); });
    };
    std::string e = read("flexion_deg,torque_Nm\n90,50\n90,-5\n");
    EXPECT_NE(e.find("armsim_bad_torque.csv:3"), std::string::npos) << e;
    EXPECT_NE(e.find("torque_Nm"), std::string::npos) << e;
    e = read("flexion_deg,effort,torque_Nm\n90,3,50\n");
    EXPECT_NE(e.find("'effort' = 3"), std::string::npos) << e;
    // A rotation effort needs its forearm torque, of its own sign; the forearm axis is NaN where not read.
    e = read("flexion_deg,effort,torque_Nm\n90,2,50\n");
    EXPECT_NE(e.find("supination effort without its forearm torque"), std::string::npos) << e;
    e = read("flexion_deg,effort,torque_Nm,forearm_torque_Nm\n90,1,50,NaN\n90,-2,5,3\n");
    EXPECT_NE(e.find("armsim_bad_torque.csv:3: column 'forearm_torque_Nm' = 3: expected <= 0 for a pronation effort"),
              std::string::npos) << e;
    const std::vector<TorqueObservation> twoAxis = readTorqueData(
        writeTemp("armsim_two_axis.csv", "flexion_deg,effort,torque_Nm,forearm_torque_Nm\n90,1,50,NaN\n90,2,20,9.5\n"));
    ASSERT_EQ(twoAxis.size(), 2u);
    EXPECT_TRUE(std::isnan(twoAxis[0].forearmTorque));
    EXPECT_EQ(twoAxis[1].effort, Effort::Supination);
    EXPECT_EQ(twoAxis[1].getEffortTorque(), 9.5);
    EXPECT_NEAR(twoAxis[1].getLoad(), std::hypot(20.0, 9.5), 1e-12);
    e = read("flexion_deg,torque,repetition\n90,50,0\n");
    EXPECT_NE(e.find("unknown column 'torque'"), std::string::npos) << e;
    e = read("flexion_deg,torque_Nm,repetition\n90,50,0\n90,51,0\n");
    EXPECT_NE(e.find("appears earlier"), std::string::npos) << e;
    e = read("flexion_deg,torque_Nm,level\n90,50,1.5\n");
    EXPECT_NE(e.find("level"), std::string::npos) << e;
}

// Synthesized trials follow the effort model: extension efforts read negative torque, a submaximal
// level scales the drive (activation = level x VA x (1 + cv z)), and the same seed gives the same data.
TEST(TorqueProtocol, SynthesizedEffortsFollowTheStatedModel) {
    const Population population = loadDefaultPopulation();
    const VirtualSubject v = drawSubject(population, 3, 1);
    const TorqueProtocol p = makeMixedProtocol();
    const std::vector<TorqueObservation> a = synthesizeTorqueData(v, p, 5, 2), b = synthesizeTorqueData(v, p, 5, 1);
    ASSERT_EQ(a.size(), 6u);
    const double va = v.setup.effort.voluntaryActivation, cv = v.setup.effort.trialCv;
    for (std::size_t k = 0; k < a.size(); ++k) {
        EXPECT_EQ(a[k].torque, b[k].torque) << "threads changed the data";
        EXPECT_EQ(a[k].effort == Effort::Flexion, a[k].torque > 0) << k;
        EXPECT_NEAR(a[k].activation / (a[k].level * va), 1.0, 4 * cv) << k;  // |z| < 4
        EXPECT_NEAR(a[k].torque, a[k].cleanTorque * (1 + v.transducerNoise * a[k].noiseDraw), 1e-12);
    }
    // Repetition-major order: every condition's first trial, then the second ones.
    EXPECT_EQ(a[0].repetition, 0);
    EXPECT_EQ(a[3].repetition, 1);
    EXPECT_EQ(a[5].repetition, 2);
    EXPECT_EQ(a[5].effort, Effort::Extension);
}

// The two-axis transducer (issue 31): a protocol with a supination effort reads the forearm axis in
// every trial, the file reads back with the rotation effort and the measurement, each axis carries
// noise sd |T| z (|T| the load on both axes, its own draw), a supination effort supinates, and the
// same protocol on a model without a forearm rotation, or channels in a rotation effort, are refused.
TEST(TorqueProtocol, TwoAxisTrialsReadTheForearmAxis) {
    const Population population = loadDefaultPopulation();
    const VirtualSubject v = drawSubject(population, 3, 1);
    TorqueProtocol p;
    p.name = "two_axis";
    p.conditions = {{90, Effort::Flexion, 1.0, 2}, {90, Effort::Supination, 1.0, 2}};
    p.conditions[1].rotationDeg = -60;
    p.holdDuration = 1.5;
    p.averagingWindow = 0.5;
    ASSERT_TRUE(p.readsForearmTorque());
    const TorqueProtocol back = readTorqueProtocol(writeTemp("armsim_two_axis.yaml", formatTorqueProtocol(p)));
    ASSERT_EQ(back.conditions.size(), 2u);
    EXPECT_EQ(back.conditions[1].effort, Effort::Supination);
    EXPECT_TRUE(back.readsForearmTorque());
    TorqueProtocol flexionOnly = p;
    flexionOnly.conditions.resize(1);
    EXPECT_FALSE(flexionOnly.readsForearmTorque());
    flexionOnly.forearmTorque = true;
    EXPECT_TRUE(readTorqueProtocol(writeTemp("armsim_fa.yaml", formatTorqueProtocol(flexionOnly))).forearmTorque);

    const std::vector<TorqueObservation> a = synthesizeTorqueData(v, p, 5, 2);
    ASSERT_EQ(a.size(), 4u);
    for (const TorqueObservation& o : a) {
        ASSERT_TRUE(std::isfinite(o.forearmTorque));
        const double load = std::hypot(o.cleanTorque, o.cleanForearmTorque);
        EXPECT_NEAR(o.torque, o.cleanTorque + v.transducerNoise * load * o.noiseDraw, 1e-12);
        EXPECT_NEAR(o.forearmTorque, o.cleanForearmTorque + v.transducerNoise * load * o.forearmNoiseDraw, 1e-12);
        EXPECT_NE(o.noiseDraw, o.forearmNoiseDraw);
    }
    EXPECT_GT(a[1].cleanForearmTorque, 5.0);  // N m: the supination effort (repetition-major: trial 1)
    EXPECT_GT(a[0].cleanTorque, 20.0);        // the flexion effort flexes
    // The flexion axis's draws are those of a one-axis protocol: its data do not move.
    TorqueProtocol oneAxis = p;
    oneAxis.conditions.resize(1);
    const std::vector<TorqueObservation> one = synthesizeTorqueData(v, oneAxis, 5, 1);
    EXPECT_EQ(one[0].noiseDraw, a[0].noiseDraw);
    EXPECT_TRUE(std::isnan(one[0].forearmTorque));
    // CSV: effort 2 and the forearm column read back.
    const std::vector<TorqueObservation> csv = readTorqueData(writeTemp("armsim_two_axis.csv", formatTorqueData(a, true)));
    ASSERT_EQ(csv.size(), a.size());
    EXPECT_EQ(csv[1].effort, Effort::Supination);
    EXPECT_NEAR(csv[1].forearmTorque, a[1].forearmTorque, 1e-9 * std::abs(a[1].forearmTorque));

    Population elbow = loadPopulation(findAsset("subjects/elbow_population.yaml"));
    EXPECT_THROW(synthesizeTorqueData(drawSubject(elbow, 3, 1), p, 5, 1), InputError);
    TorqueProtocol withEmg = p;
    withEmg.conditions[1].emg = true;
    EXPECT_THROW(withEmg.validate(), InputError);
}

namespace {

// arm26_torque.yaml cut short: flexion MVC at 90 deg x 2, extension MVC at 90, half flexion at 60.
TorqueProtocol makeArm26Protocol() {
    TorqueProtocol p = readTorqueProtocol(std::string(ARMSIM_ASSET_DIR) + "/protocols/arm26_torque.yaml");
    p.conditions = {{90, Effort::Flexion, 1.0, 2}, {90, Effort::Extension, 1.0, 1}, {60, Effort::Flexion, 0.5, 1}};
    p.holdDuration = 0.5;
    p.averagingWindow = 0.25;
    return p;
}

}  // namespace

// A protocol on an OpenSim model runs each condition as that model's isometric trial (second method:
// runOsimIsometricTrial called directly with the condition's coordinate, angle, direction and level):
// the clean torque is its tared window mean to the last bit, the reading carries the relative transducer
// noise, flexion pulls the positive way and extension the other, and the result does not depend on
// the number of threads.
TEST(TorqueProtocol, OsimModelTrialsAreItsIsometricTrialsWithTransducerNoise) {
    const TorqueProtocol p = makeArm26Protocol();
    ASSERT_TRUE(p.usesOsimModel());
    const std::vector<TorqueObservation> data = synthesizeOsimTorqueData(p, 5, 2);
    ASSERT_EQ(data.size(), 4u);
    const OsimModel model = readOsimFile(std::string(ARMSIM_ASSET_DIR) + "/models/arm26.osim");
    for (const TorqueObservation& o : data) {
        OsimIsometricTrialSettings s;
        s.coordinate = "r_elbow_flex";
        s.angleDeg = o.flexionDeg;
        s.direction = o.effort == Effort::Extension ? -1 : 1;
        s.activation = o.level;
        s.holdDuration = 0.5;
        s.averagingWindow = 0.25;
        s.sampleRate = p.sampleRate;
        EXPECT_EQ(o.cleanTorque, runOsimIsometricTrial(model, s).summary.meanTaredTorque) << o.flexionDeg;
        EXPECT_DOUBLE_EQ(o.torque, o.cleanTorque * (1 + p.transducerNoise * o.noiseDraw));
        EXPECT_EQ(o.activation, o.level);
    }
    EXPECT_GT(data[0].cleanTorque, 10);   // flexion MVC at 90 deg (arm26: about 63 N m)
    EXPECT_LT(data[1].cleanTorque, -10);  // extension
    EXPECT_LT(data[2].cleanTorque, data[0].cleanTorque);
    EXPECT_EQ(data[3].cleanTorque, data[0].cleanTorque);  // repetition 2: same trial, its own noise
    EXPECT_NE(data[3].torque, data[0].torque);
    const std::vector<TorqueObservation> oneThread = synthesizeOsimTorqueData(p, 5, 1);
    for (std::size_t k = 0; k < data.size(); ++k) EXPECT_EQ(oneThread[k].torque, data[k].torque) << k;
    // The protocol file says what ran it, and reads back.
    const std::string text = formatTorqueProtocol(p);
    EXPECT_NE(text.find("coordinate: r_elbow_flex"), std::string::npos) << text;
    const TorqueProtocol back = readTorqueProtocol(writeTemp("armsim_arm26_back.yaml", text));
    EXPECT_EQ(back.coordinate, "r_elbow_flex");
    EXPECT_EQ(back.conditions.size(), p.conditions.size());
}

// What an OpenSim model's protocol cannot do is refused with the file, the line and the field.
TEST(TorqueProtocol, OsimProtocolRefusesWhatItsModelCannotDoAtItsLine) {
    const std::string head = "name: t\nkind: torque\nsubject: {model: arm26, coordinate: r_elbow_flex}\nconditions:\n";
    auto read = [&](const std::string& body, const std::string& h) {
        return errorOf([&] { readTorqueProtocol(writeTemp("armsim_osim_torque.yaml", h + body)); });
    };
    struct Case {
        std::string header, body, expected;
    };
    const std::vector<Case> cases = {
        {head, "  - {flexion_deg: 90}\n  - {flexion_deg: 150}\n", "armsim_osim_torque.yaml:6: field 'flexion_deg' (conditions, entry 2) = 150: expected in [0, 130]"},
        {head, "  - {flexion_deg: 90, effort: supination}\n", "expected flexion (the positive direction) or extension"},
        {head, "  - {flexion_deg: 90, rotation_deg: 30}\n", "expected no forearm posture"},
        {head, "  - {flexion_deg: 90, channels: [torque, ultrasound]}\n", "expected torque only"},
        {"name: t\nkind: torque\nsubject: {model: arm26, coordinate: r_elbow_flex}\nmeasurements: {forearm_torque: true}\n"
         "conditions:\n", "  - {flexion_deg: 90}\n", "expected no volume scan, anthropometry or forearm torque"},
        {"name: t\nkind: torque\nsubject: {model: arm26, coordinate: elbow}\nconditions:\n", "  - {flexion_deg: 90}\n",
         "armsim_osim_torque.yaml:3: field 'subject.coordinate' 'elbow': not a coordinate of arm26"},
        {"name: t\nkind: torque\nsubject: {model: twin, coordinate: r_elbow_flex}\nconditions:\n", "  - {flexion_deg: 90}\n",
         "only an OpenSim model"},
        {"name: t\nkind: torque\ntrial: {hold: 100, sample_rate: 1e6}\nsubject: {model: arm26, coordinate: r_elbow_flex}\n"
         "conditions:\n", "  - {flexion_deg: 90}\n",
         "armsim_osim_torque.yaml:3: field 'trial.sample_rate' = 1e+06 Hz over trial.rest + trial.hold = 100.5 s = 100500001 samples: expected at most 1e+07"},
    };
    for (const Case& c : cases) {
        const std::string e = read(c.body, c.header);
        EXPECT_NE(e.find(c.expected), std::string::npos) << e;
    }
}

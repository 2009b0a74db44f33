// The protocol file kinds' table: every kind a file can name runs through it, and a run through it
// equals the kind's own runner called directly.
#include "basics/errors.h"
#include "basics/files.h"
#include "experiments/protocol_files.h"

#include "tests/support/temp_files.h"

#include <gtest/gtest.h>

#include <set>

using namespace armsim;

TEST(ProtocolFiles, TheTableHoldsEveryArmKindAndTorque) {
    std::set<std::string> names;
    for (const ProtocolFileKind& k : getProtocolFileKinds()) names.insert(k.name);
    for (ProtocolKind kind : {ProtocolKind::Mvc, ProtocolKind::Submaximal, ProtocolKind::ForceLength, ProtocolKind::Composition})
        EXPECT_EQ(names.count(getProtocolKindName(kind)), 1u) << getProtocolKindName(kind);
    EXPECT_EQ(names.count("torque"), 1u);
    const std::string bad = armsim::testing::writeTempFile("armsim_kind.yaml", "name: x\nkind: isokinetic\n");
    const std::string msg = armsim::testing::getInputErrorOf([&] { runProtocolFile(bad, {}); });
    EXPECT_NE(msg.find("armsim_kind.yaml:2"), std::string::npos) << msg;
    EXPECT_NE(msg.find("composition, torque"), std::string::npos) << msg;
}

// A torque protocol through the table gives what runTorqueProtocol gives; an arm kind (the composition
// grid, the quickest) what runProtocol gives; neither writes when asked to compute only.
TEST(ProtocolFiles, ARunThroughTheTableEqualsTheKindsOwnRunner) {
    TorqueProtocol t;
    t.name = "table_check";
    t.conditions = {{90, Effort::Flexion, 1.0, 2}, {60, Effort::Extension, 1.0, 1}};
    t.holdDuration = 1.0;
    t.averagingWindow = 0.5;
    const std::string torqueFile = armsim::testing::writeTempFile("armsim_table_torque.yaml", formatTorqueProtocol(t));
    ProtocolFileOptions computeOnly;
    computeOnly.write = false;
    const ProtocolFileRun viaTable = runProtocolFile(torqueFile, computeOnly);
    ASSERT_TRUE(viaTable.torqueRun.has_value());
    EXPECT_EQ(viaTable.kind, "torque");
    EXPECT_TRUE(viaTable.files.empty());
    const TorqueProtocolRun direct = runTorqueProtocol(readTorqueProtocol(torqueFile));
    ASSERT_EQ(viaTable.torqueRun->data.size(), direct.data.size());
    for (std::size_t k = 0; k < direct.data.size(); ++k) EXPECT_EQ(viaTable.torqueRun->data[k].torque, direct.data[k].torque);

    const std::string armFile = std::string(ARMSIM_ASSET_DIR) + "/protocols/motor_unit_composition.yaml";
    std::string started;
    computeOnly.onStart = [&](const std::string& name, const std::string&) { started = name; };
    const ProtocolFileRun arm = runProtocolFile(armFile, computeOnly);
    EXPECT_EQ(started, "motor_unit_composition");
    ASSERT_TRUE(arm.armResult.has_value());
    EXPECT_EQ(arm.kind, "composition");
    const Protocol p = readProtocol(armFile);
    const ProtocolResult r = runProtocol(p, loadProtocolSubject(p), {"", 1, {}});
    ASSERT_EQ(arm.armResult->composition.getNumRows(), r.composition.getNumRows());
    for (int i = 0; i < r.composition.getNumRows(); ++i)
        EXPECT_EQ(arm.armResult->composition.get(i, "force_N"), r.composition.get(i, "force_N"));
    EXPECT_NE(arm.text.find("3 slow + 3 fast units"), std::string::npos) << arm.text;
    // Videos need per-trial series: a torque protocol refuses them before it runs.
    ProtocolFileOptions video;
    video.write = false;
    video.beforeCommit = [](OutputFolder&, const ArmSetup&, const ProtocolResult&) {};
    EXPECT_NE(armsim::testing::getInputErrorOf([&] { runProtocolFile(torqueFile, video); }).find("no per-trial series"),
              std::string::npos);
}

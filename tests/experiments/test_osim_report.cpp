// model show for an OpenSim model (experiments/osim_report.h): model show's files and columns, moment arms
// as the built model gives them, and the steady torque against a 3 s integration of each muscle.
#include "experiments/osim_report.h"

#include "basics/errors.h"
#include "basics/files.h"
#include "model/osim_arm.h"
#include "muscles/simbody_isometric.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

using namespace armsim;
namespace fs = std::filesystem;

TEST(OsimReport, Arm26ElbowSweepWritesModelShowsFilesAndItsTorqueIsTheIntegratedOne) {
    const OsimModel model = readOsimFile(std::string(ARMSIM_ASSET_DIR) + "/models/arm26.osim");
    const fs::path dir = fs::temp_directory_path() / ("armsim_osim_report_" + std::to_string(::getpid()));
    fs::remove_all(dir);
    OsimReportSettings s;
    s.coordinate = "r_elbow_flex";
    s.stepDeg = 10;
    const OsimReportFiles r = writeOsimModelReport(model, s, dir.string());
    EXPECT_EQ(r.coordinate, "r_elbow_flex");
    for (const char* f : {"muscles.csv", "moment_arms.csv", "moment_arms.png", "mvc_flexion.csv", "mvc_flexion.png",
                          "mvc_extension.csv", "mvc_extension.png"})
        EXPECT_TRUE(fs::exists(dir / f)) << f;
    const Table arms = Table::readCsv((dir / "moment_arms.csv").string());
    const Table flexion = Table::readCsv((dir / "mvc_flexion.csv").string());
    ASSERT_TRUE(arms.hasColumn("flexion_deg"));
    ASSERT_TRUE(flexion.hasColumn("torque_total_Nm"));
    ASSERT_TRUE(flexion.hasColumn("fibre_length_BIClong"));
    EXPECT_EQ(arms.get(0, 0), 0.0);                         // the range 0 .. 130 deg
    EXPECT_NEAR(arms.get(arms.getNumRows() - 1, 0), 130.0, 1e-6);
    // At 90 deg: moment arms as the built model gives them, and the flexion torque as the sum over the
    // flexors of a 3 s full-excitation integration's end force times their moment arm (extensors at none).
    const OsimArm arm(model);
    SimTK::State st = arm.getDefaultState();
    arm.setCoordinateValue(st, 1, 90 * 3.14159265358979323846 / 180);
    arm.getSystem().realize(st, SimTK::Stage::Position);
    int row = 0;
    while (arms.get(row, 0) < 89.9) ++row;
    double total = 0;
    for (int i = 0; i < arm.getNumMuscles(); ++i) {
        const double R = arm.calcMomentArm(st, i, 1);
        EXPECT_NEAR(arms.get(row, arms.findColumn("moment_arm_" + arm.getMuscleName(i) + "_m")), R, 1e-10);
        MuscleIsometricSettings m;
        m.pathLength = arm.calcPathLength(st, i);
        m.activation = ActivationProfile::constant(R > 0 ? 1.0 : 0.0);
        m.duration = 3.0;
        m.sampleRate = 10;
        m.startSteady = false;
        m.integration.accuracy = 1e-8;
        const Table t = runMuscleIsometric(arm.getMuscleForce(i).getMuscle(), m);
        total += t.get(t.getNumRows() - 1, t.findColumn("force_N")) * R;
    }
    EXPECT_NEAR(flexion.get(row, flexion.findColumn("torque_total_Nm")), total, 1e-5 * std::abs(total));
    EXPECT_GT(r.peakPositive, 0);
    fs::remove_all(dir);
}

// Which coordinate: named when the model has several, and refused naming the model's coordinates.
TEST(OsimReport, TheCoordinateMustBeNamedWhenThereAreSeveral) {
    const OsimModel model = readOsimFile(std::string(ARMSIM_ASSET_DIR) + "/models/arm26.osim");
    const fs::path dir = fs::temp_directory_path() / ("armsim_osim_report_c_" + std::to_string(::getpid()));
    for (const auto& [name, expected] : std::vector<std::pair<std::string, std::string>>{
             {"", "has 2 coordinates (r_shoulder_elev, r_elbow_flex): name the one to sweep"},
             {"wrist", "--coordinate 'wrist': not a coordinate of arm26 (r_shoulder_elev, r_elbow_flex)"}}) {
        OsimReportSettings s;
        s.coordinate = name;
        try {
            writeOsimModelReport(model, s, dir.string());
            ADD_FAILURE() << "accepted '" << name << "'";
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
        }
        EXPECT_FALSE(fs::exists(dir));  // nothing written
    }
}

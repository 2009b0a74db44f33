// Forward dynamics of arm26 against OpenSim's own result (opensim-models, Tutorials/Computed_Muscle_
// Control/OutputReference/ForwardDynamics/PhysiologicalResults: OpenSim 2.x's Forward tool driving arm26
// with the controls it lists, integrator tolerance 1e-5; copied to tests/data/opensim/arm26_forward/),
// storage files read and written, and the Forward tool's setup file.
#include "model/osim_forward.h"

#include "basics/errors.h"
#include "basics/files.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

using namespace armsim;
namespace fs = std::filesystem;

namespace {

std::string data(const std::string& name) { return std::string(ARMSIM_SOURCE_DIR) + "/tests/data/opensim/arm26_forward/" + name; }

constexpr double kDeg = 3.14159265358979323846 / 180;
constexpr double kActivationTol = 1e-4;       // issue 29's goal
constexpr double kAngleTol = 1 * kDeg;        // issue 29's goal
constexpr double kFiberTol = 0.5e-3;          // m, fibre lengths (not a goal of the issue)
// OpenSim's TRIlong fibre jumps 8 mm within 5 ms and relaxes back within 10 ms more while the joints move
// 0.02 deg: its path length jumps (a wrap toggling in OpenSim's iterative multi-wrap algorithm); excluded,
// and checked to be there.
constexpr double kGlitchStart = 0.8454, kGlitchEnd = 0.8600;

// Linear interpolation of column `name` of t at time `time`.
double interpolate(const Table& t, const std::string& name, double time) {
    const int c = t.findColumn(name);
    int r = 0;
    while (r + 2 < t.getNumRows() && t.get(r + 1, 0) < time) ++r;
    const double t0 = t.get(r, 0), t1 = t.get(r + 1, 0);
    const double f = t1 > t0 ? std::clamp((time - t0) / (t1 - t0), 0.0, 1.0) : 0.0;
    return t.get(r, c) + f * (t.get(r + 1, c) - t.get(r, c));
}

}  // namespace

// arm26 driven by the tutorial's controls from the reference's first row, under OpenSim 2.x's Thelen
// equations (the reference's): every activation within 1e-4 and both joint angles within 1 deg at every
// one of the reference's 348 rows over the 1 s movement (elbow 0 -> 85 deg, shoulder 0 -> -17 deg), fibre
// lengths within 0.5 mm. Measured: 6.8e-5, 0.43 deg, 0.22 mm.
TEST(OsimForward, Arm26ReproducesOpenSimsForwardResult) {
    const OsimModel model = readOsimFile(std::string(ARMSIM_ASSET_DIR) + "/models/arm26.osim");
    const OsimStorage controls = readOsimStorage(data("arm26_controls.sto"));
    const OsimStorage reference = readOsimStorage(data("arm26_states.sto"));
    OsimForwardSettings s;
    s.finalTime = 1.0;
    s.sampleRate = 1000;
    s.muscleModel = "thelen2003_opensim2";
    const OsimForwardResult r = runOsimForward(model, controls, &reference, s);
    ASSERT_EQ(r.states.getColumnNames(), reference.table.getColumnNames());  // OpenSim's names and order
    const Table& ref = reference.table;
    double activation = 0, angle = 0, fiber = 0;
    for (int row = 0; row < ref.getNumRows(); ++row) {
        const double t = ref.get(row, 0);
        for (int c = 1; c < ref.getNumColumns(); ++c) {
            const std::string& name = ref.getColumnNames()[c];
            const double d = std::abs(interpolate(r.states, name, t) - ref.get(row, c));
            if (name.find(".activation") != std::string::npos) {
                EXPECT_LE(d, kActivationTol) << name << " at " << t;
                activation = std::max(activation, d);
            } else if (name.find(".fiber_length") != std::string::npos) {
                if (t > kGlitchStart && t < kGlitchEnd) continue;
                EXPECT_LE(d, kFiberTol) << name << " at " << t;
                fiber = std::max(fiber, d);
            } else if (name.find("_u") == std::string::npos) {
                EXPECT_LE(d, kAngleTol) << name << " at " << t;
                angle = std::max(angle, d);
            }
        }
    }
    // The excluded window holds OpenSim's jump: TRIlong's fibre up by more than 5 mm within it.
    double jump = 0;
    for (int row = 0; row < ref.getNumRows(); ++row)
        if (ref.get(row, 0) > kGlitchStart && ref.get(row, 0) < kGlitchEnd)
            jump = std::max(jump, ref.get(row, ref.findColumn("TRIlong.fiber_length")) - interpolate(ref, "TRIlong.fiber_length", kGlitchStart));
    EXPECT_GT(jump, 5e-3);
    std::ostringstream text;
    text << "activation " << activation << ", angle " << angle / kDeg << " deg, fibre " << fiber * 1000 << " mm, steps "
         << r.stats.steps;
    RecordProperty("worst", text.str());
}

// Under OpenSim 4's Thelen (the file's own type) the same run differs from the 2.x reference in
// activation by more than the tolerance: the two models' activation dynamics differ (OpenSim 4's time
// constant scales with 0.5 + 1.5 a and has a floor of 0.01), so the reference needs the 2.x variant.
TEST(OsimForward, OpenSim4ThelenIsNotTheReferencesModel) {
    const OsimModel model = readOsimFile(std::string(ARMSIM_ASSET_DIR) + "/models/arm26.osim");
    const OsimStorage controls = readOsimStorage(data("arm26_controls.sto"));
    const OsimStorage reference = readOsimStorage(data("arm26_states.sto"));
    OsimForwardSettings s;
    s.finalTime = 0.2;
    s.sampleRate = 1000;
    const OsimForwardResult r = runOsimForward(model, controls, &reference, s);
    double worst = 0;
    for (int row = 0; row < reference.table.getNumRows() && reference.table.get(row, 0) < 0.2; ++row)
        worst = std::max(worst, std::abs(interpolate(r.states, "BIClong.activation", reference.table.get(row, 0)) -
                                         reference.table.get(row, reference.table.findColumn("BIClong.activation"))));
    EXPECT_GT(worst, 10 * kActivationTol);
}

// Without initial states the model starts at its defaults with every muscle in equilibrium at the
// first excitation; the states file written and read back gives the same table (17 digits), and a run
// started from that file's last row continues the first run.
TEST(OsimForward, StatesRoundTripThroughAStorageFile) {
    const OsimModel model = readOsimFile(std::string(ARMSIM_ASSET_DIR) + "/models/arm26.osim");
    const OsimStorage controls = readOsimStorage(data("arm26_controls.sto"));
    OsimForwardSettings s;
    s.finalTime = 0.2;
    s.sampleRate = 100;
    const OsimForwardResult r = runOsimForward(model, controls, nullptr, s);
    ASSERT_EQ(r.states.getNumRows(), 21);
    // At t = 0 each muscle is in equilibrium: activation = the first excitation, or OpenSim 4's floor 0.01.
    for (const char* m : {"BIClong", "TRIlat"})
        EXPECT_NEAR(r.states.get(0, r.states.findColumn(std::string(m) + ".activation")),
                    std::max(0.01, controls.table.get(0, controls.table.findColumn(m))), 1e-12) << m;
    const fs::path dir = fs::temp_directory_path() / ("armsim_forward_states_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    std::ofstream(dir / "states.sto") << formatStorage(r.states, "arm26_states", false, 17);
    const OsimStorage back = readOsimStorage((dir / "states.sto").string());
    ASSERT_EQ(back.table.getNumRows(), r.states.getNumRows());
    for (int row = 0; row < r.states.getNumRows(); ++row)
        for (int c = 0; c < r.states.getNumColumns(); ++c) EXPECT_EQ(back.table.get(row, c), r.states.get(row, c));
    // From t = 0.1 with the row written there: the second half again, to the integrator's accuracy.
    s.initialTime = 0.1;
    const OsimForwardResult second = runOsimForward(model, controls, &back, s);
    for (const char* c : {"r_elbow_flex", "r_shoulder_elev", "BIClong.activation"})
        EXPECT_NEAR(second.states.get(second.states.getNumRows() - 1, second.states.findColumn(c)),
                    r.states.get(r.states.getNumRows() - 1, r.states.findColumn(c)), 1e-4) << c;
    fs::remove_all(dir);
}

// A control column naming no muscle, an excitation outside [0, 1] and a states file starting after the
// final time are refused naming the file, column and value.
TEST(OsimForward, BadControlsAndStatesNameTheFileAndColumn) {
    const OsimModel model = readOsimFile(std::string(ARMSIM_ASSET_DIR) + "/models/arm26.osim");
    const fs::path dir = fs::temp_directory_path() / ("armsim_forward_bad_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    auto storage = [&](const std::string& name, const std::string& columns, const std::string& rows, int n, int m) {
        std::ofstream(dir / name) << "c\nversion=1\nnRows=" << n << "\nnColumns=" << m << "\ninDegrees=no\nendheader\n"
                                  << columns << "\n" << rows;
        return readOsimStorage((dir / name).string());
    };
    struct Case {
        OsimStorage controls;
        std::string expected;
    };
    const std::vector<Case> cases = {
        {storage("a.sto", "time\tBIC", "0\t0.1\n1\t0.1\n", 2, 2), "a.sto: column 'BIC' names no muscle"},
        {storage("b.sto", "time\tBIClong", "0\t0.1\n1\t1.5\n", 2, 2), "b.sto: column 'BIClong' at t = 1 s: excitation 1.5"},
    };
    for (const Case& c : cases) {
        try {
            runOsimForward(model, c.controls, nullptr, OsimForwardSettings());
            ADD_FAILURE() << "ran: " << c.expected;
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find(c.expected), std::string::npos) << e.what();
        }
    }
    const OsimStorage late = storage("s.sto", "time\tr_elbow_flex", "0.5\t0.1\n", 1, 2);
    OsimForwardSettings s;
    s.finalTime = 0.1;
    try {
        runOsimForward(model, readOsimStorage(data("arm26_controls.sto")), &late, s);
        ADD_FAILURE() << "a states file after the initial time was accepted";
    } catch (const InputError& e) {
        // The run starts at the states file's first row (OpenSim's rule), after the final time.
        EXPECT_NE(std::string(e.what()).find("final time 0.1 s: expected after the initial time 0.5 s (from"), std::string::npos)
            << e.what();
        EXPECT_NE(std::string(e.what()).find("s.sto)"), std::string::npos) << e.what();
    }
    fs::remove_all(dir);
}

// The tutorial's setup file names its model, times and tolerance; its controls are an XML ControlSet,
// which is refused naming the line; with a .sto controls file it reads whole.
TEST(OsimForward, ForwardToolSetupFile) {
    const fs::path dir = fs::temp_directory_path() / ("armsim_forward_setup_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    const std::string setup =
        "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<OpenSimDocument Version=\"20302\">\n<ForwardTool name=\"arm26\">\n"
        "<model_file> arm26.osim </model_file>\n<results_directory> Results </results_directory>\n"
        "<initial_time> 0 </initial_time>\n<final_time> 0.5 </final_time>\n"
        "<integrator_error_tolerance> 1e-6 </integrator_error_tolerance>\n<ControllerSet name=\"Controllers\"><objects>\n"
        "<ControlSetController name=\"\"><controls_file> CONTROLS </controls_file></ControlSetController>\n"
        "</objects></ControllerSet>\n<states_file> </states_file>\n</ForwardTool>\n</OpenSimDocument>\n";
    auto write = [&](const std::string& controls) {
        std::string text = setup;
        text.replace(text.find("CONTROLS"), 8, controls);
        std::ofstream(dir / "setup.xml") << text;
        return (dir / "setup.xml").string();
    };
    const OsimForwardSetup s = readOsimForwardSetup(write("arm26_controls.sto"));
    EXPECT_EQ(s.modelFile, (dir / "arm26.osim").string());
    EXPECT_EQ(s.controlsFile, (dir / "arm26_controls.sto").string());
    EXPECT_EQ(s.resultsDirectory, (dir / "Results").string());
    EXPECT_EQ(s.finalTime, 0.5);
    EXPECT_EQ(s.tolerance, 1e-6);
    EXPECT_TRUE(s.statesFile.empty());
    try {
        readOsimForwardSetup(write("arm26_controls.xml"));
        ADD_FAILURE() << "an XML ControlSet was accepted";
    } catch (const OsimError& e) {
        EXPECT_NE(std::string(e.what()).find(":10: <ControlSetController>: controls file 'arm26_controls.xml' is an XML ControlSet"),
                  std::string::npos) << e.what();
    }
    // Elements that cannot change the states are skipped; the step-size limit is read; an element that is
    // not the tool's (a misspelling) and external loads are refused with the line.
    auto withElements = [&](const std::string& elements) {
        std::string text = setup;
        text.replace(text.find("CONTROLS"), 8, "arm26_controls.sto");
        text.insert(text.find("<states_file>"), elements);
        std::ofstream(dir / "setup.xml") << text;
        return (dir / "setup.xml").string();
    };
    const OsimForwardSetup skipped = readOsimForwardSetup(withElements(
        "<output_precision>8</output_precision><maximum_integrator_step_size>0.01</maximum_integrator_step_size>\n"
        "<AnalysisSet name=\"Analyses\"><objects/></AnalysisSet><external_loads_file>Unassigned</external_loads_file>\n"
        "<force_set_files/><replace_force_set>false</replace_force_set>\n"
        "<output_detailed_results>false</output_detailed_results><body1_linear_corrective_spring_active>false"
        "</body1_linear_corrective_spring_active><spring_linear_stiffness>10</spring_linear_stiffness>\n"));
    EXPECT_EQ(skipped.maxStepSize, 0.01);
    EXPECT_EQ(s.maxStepSize, 1.0);  // OpenSim's default
    const std::pair<std::string, std::string> refused[] = {
        {"<final_tme>2</final_tme>\n", ":12: <final_tme>: not an element of OpenSim's Forward tool setup"},
        {"<external_loads_file>grf.xml</external_loads_file>\n", ":12: <external_loads_file> 'grf.xml': not supported yet"},
        {"<use_specified_dt>true</use_specified_dt>\n", ":12: <use_specified_dt> 'true': not supported yet"},
        {"<replace_force_set>true</replace_force_set>\n", ":12: <replace_force_set> 'true': not supported yet (the Forward tool would add or replace forces"},
        {"<body1_linear_corrective_spring_active>true</body1_linear_corrective_spring_active>\n",
         ":12: <body1_linear_corrective_spring_active> 'true': not supported yet (the Forward tool would add corrective springs"},
        {"<maximum_integrator_step_size>0</maximum_integrator_step_size>\n", ":12: <maximum_integrator_step_size> 0: expected > 0 s"}};
    for (const auto& [elements, message] : refused) {
        try {
            readOsimForwardSetup(withElements(elements));
            ADD_FAILURE() << elements << " was accepted";
        } catch (const OsimError& e) {
            EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
        }
    }
    fs::remove_all(dir);
}

// Controls as OpenSim's ControlLinear reads them: a row repeating a time replaces the earlier one (no
// step), and past the last row the excitation goes on along the last two rows' line, clamped to [0, 1].
// Under OpenSim 2.x's Thelen (da/dt = (u - a) / 0.01 s while rising) the activation follows u(t) with a
// lag of tau x du/dt.
TEST(OsimForward, ControlsReplaceRepeatedTimesAndExtrapolateLinearly) {
    const OsimModel model = readOsimFile(std::string(ARMSIM_ASSET_DIR) + "/models/arm26.osim");
    const fs::path dir = fs::temp_directory_path() / ("armsim_forward_controls_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    std::ofstream(dir / "c.sto") << "c\nversion=1\nnRows=4\nnColumns=2\ninDegrees=no\nendheader\ntime\tBIClong\n"
                                    "0\t0.1\n1\t0.1\n1\t0.5\n2\t0.6\n";
    const OsimStorage controls = readOsimStorage((dir / "c.sto").string());
    OsimForwardSettings s;
    s.finalTime = 3.0;
    s.sampleRate = 10;
    s.muscleModel = "thelen2003_opensim2";
    const OsimForwardResult r = runOsimForward(model, controls, nullptr, s);
    auto activationAt = [&](double t) { return r.states.get(int(std::lround(t * 10)), r.states.findColumn("BIClong.activation")); };
    EXPECT_NEAR(activationAt(0.5), 0.3 - 0.01 * 0.4, 2e-3);  // u = 0.1 -> 0.5 linearly over 0..1 s (not a step at 1 s)
    EXPECT_NEAR(activationAt(2.5), 0.65 - 0.01 * 0.1, 2e-3); // extrapolated: 0.6 + 0.1 (t - 2)
    bool noted = false;
    for (const std::string& n : r.notes) noted = noted || n.find("extrapolated linearly") != std::string::npos;
    EXPECT_TRUE(noted);
    // From 0.05 s to 0.3 s at 10 Hz the rows fall at 0.05, 0.15, 0.25 s: said, the last row named.
    s.initialTime = 0.05;
    s.finalTime = 0.3;
    const OsimForwardResult offGrid = runOsimForward(model, controls, nullptr, s);
    EXPECT_NEAR(offGrid.states.get(offGrid.states.getNumRows() - 1, 0), 0.25, 1e-12);
    bool said = false;
    for (const std::string& n : offGrid.notes) said = said || n.find("rows every 0.1 s from 0.05 s: the last at 0.25 s, not at the final time 0.3 s") != std::string::npos;
    EXPECT_TRUE(said);
    for (const std::string& n : r.notes) EXPECT_EQ(n.find("not at the final time"), std::string::npos) << n;
    fs::remove_all(dir);
}

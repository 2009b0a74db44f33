// The bad-input catalogue (issue 15): every command and file kind fed missing, empty, binary, mistyped,
// out-of-range, huge and unknown input. Each case asserts exit code 2 (bad input), a message naming the
// option, file, field or line together with the value and what was expected, and that nothing was
// written: the case's output folder does not exist afterwards.
#include "tests/support/run_armsim.h"
#include "tests/support/temp_files.h"
#include "basics/bound.h"
#include "basics/files.h"
#include "muscles/muscle_file.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;
using armsim::testing::CommandResult;
using armsim::testing::runArmsim;
using armsim::readFileText;

struct BadInput {
    std::string name;                           ///< test case name
    std::map<std::string, std::string> files;   ///< input files (name -> text) written into IN
    std::string args;                           ///< IN and OUT are replaced by the case's folders
    std::vector<std::string> expected;          ///< fragments the message must contain
};

void PrintTo(const BadInput& c, std::ostream* os) { *os << c.name << ": armsim " << c.args; }

std::string replaceAll(std::string s, const std::string& from, const std::string& to) {
    for (std::size_t at = s.find(from); at != std::string::npos; at = s.find(from, at + to.size())) s.replace(at, from.size(), to);
    return s;
}

const std::string kProtocolHead =
    "name: bad\nkind: mvc\nseed: 1\nsubject:\n  arm: arm/default_male.yaml\n  muscle: muscles/biceps_long_head.yaml\n";
const std::string kTrial = "trial:\n  rest: 0.5\n  hold: 1.0\n  averaging_window: 0.5\n";
const std::string kAngles = "conditions:\n  elbow_angles_deg: [90]\n";
const std::string kTorqueHead = "kind: torque\nname: bad\n";
const std::string kStudyHead = "kind: study\nname: bad\nsubjects: 1\nprotocols: [thesis]\nnoise_levels: [0.02]\n";

std::vector<BadInput> makeCatalogue() {
    const std::string binary("\x7f" "ELF\x02\x01\x01\0\0\0\xff\xfe", 12);
    const std::string arm = armsim::readFileText(armsim::getAssetDirectory() + "/arm/default_male.yaml");
    const std::string muscle = replaceAll(armsim::readFileText(armsim::getAssetDirectory() + "/muscles/biceps_long_head.yaml"),
                                          "fibre_types: ", "fibre_types: " + armsim::getAssetDirectory() + "/muscles/");
    const std::string sto = "c\nversion=1\nnRows=1\nnColumns=2\ninDegrees=no\nendheader\n";
    const std::string condition = "  - {flexion_deg: 90, effort: flexion, level: 1, repetitions: 3}\n";
    const std::string channelHead = "channel,muscle,flexion_deg,effort,level,repetition,value,sd\n";
    const std::string arm26 = armsim::readFileText(armsim::getAssetDirectory() + "/models/arm26.osim");
    const std::string elbow = replaceAll(armsim::readFileText(armsim::getAssetDirectory() + "/models/elbow.yaml"),
                                         "fibre_types: ../", "fibre_types: " + armsim::getAssetDirectory() + "/");
    // arm26 with its ForceSet's objects emptied, and with the elbow locked.
    const std::string noMuscles = [&] {
        const auto set = arm26.find("<ForceSet");
        const auto open = arm26.find("<objects>", set), close = arm26.rfind("</objects>", arm26.find("</ForceSet>", set));
        return arm26.substr(0, open + 9) + arm26.substr(close);
    }();
    const std::string lockedElbow = [&] {
        std::string t = arm26;
        const auto c = t.find("<Coordinate name=\"r_elbow_flex\">");
        const auto l = t.find("<locked>false</locked>", c);
        return t.replace(l, 22, "<locked>true</locked>");
    }();
    return {
        // ---- command line -----------------------------------------------------------------------
        {"UnknownCommand", {}, "nosuch", {"unknown command 'nosuch'", "expected one of", "muscle"}},
        // An output never replaces a file the command read (the input here sits where --out writes).
        {"IdentifyOutputWouldReplaceItsInput",
         {{"identification_history.csv", armsim::readFileText(armsim::getAssetDirectory() + "/measured/thesis_measured.csv")}},
         "identify IN/identification_history.csv --out IN", {"would replace", "identification_history.csv", "read as input"}},
        // A second YAML document would never be read.
        {"SettingsWithASecondYamlDocument", {{"y.yaml", "type: isometric\nhold: 0.2\n---\ntype: free\n"}},
         "trial --settings IN/y.yaml --out OUT/t.csv", {"y.yaml:4", "a second YAML document"}},
        // A folder with someone else's manifest.json is not an armsim run to replace.
        {"ProtocolOverAForeignManifest", {{"manifest.json", "{}"}, {"precious.txt", "keep"}},
         "protocol " + armsim::getAssetDirectory() + "/protocols/force_length.yaml --out IN",
         {"not an armsim run", "manifest.json"}},
        {"UnknownOption", {}, "muscle steady --foo 1", {"--foo"}},
        {"NotANumber", {}, "muscle steady --path abc", {"--path", "abc"}},
        {"MissingOptionValue", {}, "muscle steady --path", {"--path"}},
        {"ActivationAboveOne", {}, "muscle steady --activation 1.5", {"activation", "1.5", "[0, 1]"}},
        {"ActivationNan", {}, "muscle steady --activation nan", {"activation", "nan"}},
        {"NegativePath", {}, "muscle steady --path -1", {"-1"}},
        {"ZeroMass", {}, "muscle steady --mass 0", {"--mass", "= 0", "(0, 10] (kg)"}},
        {"HugeMass", {}, "muscle steady --mass 1e300", {"--mass", "1e+300", "(0, 10] (kg)"}},
        {"FreeTrialOnsetAfterTheEnd", {}, "trial --type free --onset 5 --duration 2 --out OUT/f.csv",
         {"--onset 5 s", "--duration 2 s", "before the end"}},
        {"FreeTrialFileOnsetAfterTheEnd", {{"f.yaml", "type: free\nonset: 3\nduration: 1\n"}},
         "trial --settings IN/f.yaml --out OUT/f.csv", {"f.yaml", "onset", "= 3 s", "before the end"}},
        {"IdentifyAllZeroForces", {{"z.csv", "angle_deg,force_N\n90,0\n120,0\n60,0\n"}}, "identify IN/z.csv --out OUT/id",
         {"z.csv", "force_N", "0 N in every row"}},
        {"TorqueDataAllZero", {{"z.csv", "flexion_deg,torque_Nm\n30,0\n60,0\n90,0\n"}}, "identify-torque IN/z.csv --out OUT/id",
         {"z.csv", "torque_Nm", "0 in every row"}},
        {"RenderLoadHuge", {{"t.csv", "time_s\n0\n"}}, "render IN/t.csv --out OUT/v.mp4 --load 1e9", {"--load", "1e+09", "[0, 50] (kg)"}},
        {"IdentifyToleranceZero", {}, "identify measured/thesis_measured.csv --tolerance 0 --out OUT/id",
         {"--tolerance = 0", "expected > 0 (N)"}},
        {"ValidateAngleOutOfRange", {}, "validate --truth elbow --angles 10,400 --subjects 2 --out OUT/v",
         {"--angles = 400", "[0, 180]"}},
        {"DesignAngleOutOfRange", {}, "design --angles 10,400 --out OUT/d", {"--angles = 400", "[0, 180]"}},
        {"YamlFlowNestedTooDeep", {{"deep.yaml", "a: " + std::string(5000, '[') + std::string(5000, ']') + "\n"}},
         "protocol IN/deep.yaml --out OUT/run", {"deep.yaml:1", "nested deeper than"}},
        {"NoMotorUnits", {}, "muscle steady --slow-units 0 --fast-units 0", {"--slow-units 0", "--fast-units 0", "at least one motor unit"}},
        {"NegativeSlowUnits", {}, "muscle steady --slow-units -1", {"--slow-units", "-1", "[0, 100]"}},
        {"TendonTooLong", {}, "muscle steady --tendon-length 5", {"--tendon-length", "= 5", "(0, 2] (m)"}},
        {"UnknownModel", {}, "muscle steady --model no_such_model", {"no_such_model"}},
        // ---- muscle files ----------------------------------------------------------------------
        {"MuscleFileMissing", {}, "muscle steady --muscle IN/missing.yaml", {"missing.yaml"}},
        {"MuscleFileNoMotorUnits", {{"m.yaml", "name: b\nmass: 0.3\noptimal_fascicle_length: 0.16\noptimal_tendon_length: 0.245\n"
                                              "max_path_length: 0.43\nfibre_fractions: {slow: 0.3, fast: 0.7}\n"
                                              "motor_units:\n  slow: 0\n  fast: 0\nfibre_types: muscles/human_fibre_types.yaml\n"}},
         "muscle steady --muscle IN/m.yaml", {"m.yaml:9", "slow + fast = 0", "at least one motor unit"}},
        {"MuscleFileEmpty", {{"m.yaml", ""}}, "muscle steady --muscle IN/m.yaml", {"m.yaml"}},
        {"MuscleFileBinary", {{"m.yaml", binary}}, "muscle steady --muscle IN/m.yaml", {"m.yaml"}},
        {"MuscleFileNotYaml", {{"m.yaml", "mass: [1, 2\n"}}, "muscle steady --muscle IN/m.yaml", {"m.yaml:2", "invalid YAML"}},
        // ---- trials and their sizes ------------------------------------------------------------
        {"TrialRateHuge", {}, "muscle trial --rate 1e12 --out OUT/t.csv", {"--duration = 3 s x --rate 1e+12 Hz", "samples", "at most 1e+07"}},
        {"TrialDurationHuge", {}, "muscle trial --duration 1e9 --out OUT/t.csv", {"--duration = 1e+09 s x --rate 1000 Hz", "at most 1e+07"}},
        {"TrialDurationNegative", {}, "muscle trial --duration -1 --out OUT/t.csv", {"duration", "-1"}},
        {"TrialActivationBad", {}, "muscle trial --activation 2 --out OUT/t.csv", {"activation", "= 2"}},
        {"TrialOutUnwritable", {}, "muscle trial --duration 0.1 --out /proc/armsim/t.csv", {"/proc/armsim/t.csv", "cannot write"}},
        {"SweepStepTiny", {}, "muscle sweep --step 1e-9 --out OUT/s.csv", {"--step 1e-09", "at most 1000001"}},
        {"SweepStepZero", {}, "muscle sweep --step 0 --out OUT/s.csv", {"--step", "= 0"}},
        {"ArmAngleFullExtension", {}, "trial --angle 180 --out OUT/t.csv", {"--angle = 180", "below 180"}},
        {"ArmAngleOutsideRange", {}, "trial --angle 10 --out OUT/t.csv", {"--angle = 10", "[40, 180] (deg)"}},
        {"ArmActivationNegative", {}, "trial --activation -0.1 --out OUT/t.csv", {"activation", "-0.1", "[0, 1]"}},
        {"ArmHoldZero", {}, "trial --hold 0 --out OUT/t.csv", {"hold", "= 0"}},
        {"ArmRateHuge", {}, "trial --rate 1e12 --out OUT/t.csv", {"--rest + --rise + --hold = 3.5 s x --rate 1e+12 Hz", "at most 1e+07"}},
        {"ArmTypeUnknown", {}, "trial --type sideways --out OUT/t.csv", {"--type", "sideways"}},
        {"TrialSettingsMissing", {}, "trial --settings IN/none.yaml --out OUT/t.csv", {"none.yaml"}},
        {"TrialSettingsUnknownKey", {{"s.yaml", "type: isometric\nweather: sunny\n"}},
         "trial --settings IN/s.yaml --out OUT/t.csv", {"s.yaml:2", "unknown field 'weather'"}},
        // ---- protocol files --------------------------------------------------------------------
        {"ProtocolMissing", {}, "protocol IN/none.yaml --out OUT/run", {"none.yaml"}},
        {"ProtocolEmpty", {{"p.yaml", ""}}, "protocol IN/p.yaml --out OUT/run", {"p.yaml"}},
        {"ProtocolBinary", {{"p.yaml", binary}}, "protocol IN/p.yaml --out OUT/run", {"p.yaml"}},
        {"ProtocolUnknownKey", {{"p.yaml", kProtocolHead + kTrial + kAngles + "colour: blue\n"}},
         "protocol IN/p.yaml --out OUT/run", {"p.yaml", "colour"}},
        {"ProtocolHoldNegative", {{"p.yaml", kProtocolHead + "trial:\n  hold: -3\n" + kAngles}},
         "protocol IN/p.yaml --out OUT/run", {"p.yaml", "hold", "-3"}},
        {"ProtocolHoldHuge", {{"p.yaml", kProtocolHead + "trial:\n  hold: 1.0e9\n" + kAngles}},
         "protocol IN/p.yaml --out OUT/run", {"samples", "at most 1e+07"}},
        {"ProtocolFromADevice", {}, "protocol /dev/zero --out OUT/run", {"/dev/zero", "not a regular file"}},
        {"ProtocolRunTooLarge", {{"p.yaml", kProtocolHead + "repetitions: 1000\ntrial:\n  hold: 9000\n" +
                                             "conditions:\n  elbow_angles_deg: [45, 60, 90, 120, 150]\n"}},
         "protocol IN/p.yaml --out OUT/run", {"p.yaml", "5000 trials", "samples in the run", "at most 1e+08"}},
        {"ProtocolAngleOutOfRange", {{"p.yaml", kProtocolHead + kTrial + "conditions:\n  elbow_angles_deg: [200]\n"}},
         "protocol IN/p.yaml --out OUT/run", {"p.yaml", "200"}},
        {"ProtocolWrongType", {{"p.yaml", kProtocolHead + "trial:\n  hold: long\n" + kAngles}},
         "protocol IN/p.yaml --out OUT/run", {"p.yaml", "hold", "long"}},
        {"TorqueProtocolLevelAboveOne",
         {{"p.yaml", kTorqueHead + "conditions:\n  - {flexion_deg: 90, effort: flexion, level: 1.5, repetitions: 3}\n"}},
         "protocol IN/p.yaml --out OUT/run", {"p.yaml", "level", "1.5"}},
        // ---- force data (identify) -------------------------------------------------------------
        {"ForceDataMissing", {}, "identify IN/none.csv --out OUT/id", {"none.csv", "no such file"}},
        {"ForceDataEmpty", {{"d.csv", ""}}, "identify IN/d.csv --out OUT/id", {"d.csv"}},
        {"ForceDataBinary", {{"d.csv", binary}}, "identify IN/d.csv --out OUT/id", {"d.csv"}},
        {"ForceDataUnknownColumn", {{"d.csv", "path_cm,force_N,emg\n41,600,1\n"}}, "identify IN/d.csv --out OUT/id",
         {"d.csv", "unknown column 'emg'"}},
        {"ForceDataTruncatedRow", {{"d.csv", "path_cm,force_N\n41,600\n37.5\n"}}, "identify IN/d.csv --out OUT/id",
         {"d.csv:3"}},
        {"ForceDataNan", {{"d.csv", "path_cm,force_N\n41,nan\n37.5,458\n"}}, "identify IN/d.csv --out OUT/id",
         {"d.csv:2", "force_N"}},
        {"ForceDataHuge", {{"d.csv", "path_cm,force_N\n41,1e308\n37.5,458\n"}}, "identify IN/d.csv --out OUT/id",
         {"d.csv:2", "force_N", "1e+308", "at most 1e5 N"}},
        {"ForceDataNegative", {{"d.csv", "path_cm,force_N\n41,-600\n37.5,458\n"}}, "identify IN/d.csv --out OUT/id",
         {"d.csv:2", "force_N", "-600", ">= 0"}},
        {"ForceDataAngleOutOfRange", {{"d.csv", "angle_deg,force_N\n200,600\n90,458\n"}}, "identify IN/d.csv --out OUT/id",
         {"d.csv:2", "angle_deg", "200", "(0, 180]"}},
        {"IdentifyMethodUnknown", {}, "identify measured/thesis_measured.csv --method newton --out OUT/id", {"--method", "newton"}},
        {"IdentifyBoundsNotANumber", {}, "identify measured/thesis_measured.csv --bounds mass=abc:1 --out OUT/id",
         {"--bounds mass lower", "abc"}},
        {"IdentifyOutIsAFile", {{"afile", "x"}}, "identify measured/thesis_measured.csv --out IN/afile/id",
         {"--out", "afile", "not a folder"}},
        {"ModelIsAnOsimFile", {{"arm.osim", "<?xml version=\"1.0\"?>\n<OpenSimDocument Version=\"40000\"/>\n"}},
         "muscle steady --model IN/arm.osim",
         {"arm.osim", "an OpenSim model", "`armsim forward`, `armsim trial`, `armsim model show`", "takes an armsim model file (.yaml)"}},
        {"ModelShowOsimWithoutModel", {{"arm.osim", "<?xml version=\"1.0\"?>\n<OpenSimDocument Version=\"40000\"/>\n"}},
         "model show --model IN/arm.osim --out OUT/ms", {"arm.osim:2", "<OpenSimDocument>", "missing <Model>"}},
        {"ModelShowCoordinateForYaml", {}, "model show --model twin --coordinate r_elbow_flex --out OUT/ms",
         {"--coordinate 'r_elbow_flex'", "only for OpenSim models (.osim)"}},
        {"ValidatePriorWithHillMuscles", {{"h.yaml", "name: hill\nmodel: twin\nmuscle_model: thelen2003\n"}},
         "validate --truth elbow --truth-population IN/h.yaml --prior IN/h.yaml --subjects 2 --out OUT/v",
         {"prior population 'hill'", "muscle_model thelen2003", "expected virtual_muscle"}},
        {"MuscleModelUnknown", {}, "muscle steady --model twin --muscle-model hill",
         {"--muscle-model", "'hill'", "expected one of virtual_muscle, thelen2003, degroote2016"}},
        // ---- forward dynamics of .osim models ----------------------------------------------------
        {"ForwardModelUnknown", {{"c.sto", "c\nversion=1\nnRows=1\nnColumns=2\ninDegrees=no\nendheader\ntime\tBIClong\n0\t0.1\n"}},
         "forward --model nope --controls IN/c.sto --final-time 1 --out OUT/f", {"--model 'nope'", "no shipped OpenSim model"}},
        {"ForwardControlsNameNoMuscle", {{"c.sto", "c\nversion=1\nnRows=1\nnColumns=2\ninDegrees=no\nendheader\ntime\tBIC\n0\t0.1\n"}},
         "forward --model arm26 --controls IN/c.sto --final-time 0.1 --out OUT/f", {"c.sto", "column 'BIC' names no muscle"}},
        {"ForwardNoFinalTime", {{"c.sto", "c\nversion=1\nnRows=1\nnColumns=2\ninDegrees=no\nendheader\ntime\tBIClong\n0\t0.1\n"}},
         "forward --model arm26 --controls IN/c.sto --out OUT/f", {"no final time", "--final-time"}},
        {"ForwardMuscleModelUnknown", {{"c.sto", "c\nversion=1\nnRows=1\nnColumns=2\ninDegrees=no\nendheader\ntime\tBIClong\n0\t0.1\n"}},
         "forward --model arm26 --controls IN/c.sto --final-time 0.1 --muscle-model hill --out OUT/f",
         {"muscle model 'hill'", "expected thelen2003, thelen2003_opensim2 or degroote2016"}},
        {"ForwardFinalTimeNan", {{"c.sto", sto + "time\tBIClong\n0\t0.1\n"}},
         "forward --model arm26 --controls IN/c.sto --final-time nan --out OUT/f", {"--final-time = nan", "expected a finite number"}},
        {"ForwardControlsTimesBackwards", {{"c.sto", replaceAll(sto, "nRows=1", "nRows=2") + "time\tBIClong\n1\t0.1\n0\t0.2\n"}},
         "forward --model arm26 --controls IN/c.sto --final-time 2 --out OUT/f", {"c.sto: row 2: time 0 s is before the previous row's 1 s"}},
        {"ForwardStatesNotANumber", {{"c.sto", sto + "time\tBIClong\n0\t0.1\n"}, {"s.sto", sto + "time\tr_elbow_flex\n0\tnan\n"}},
         "forward --model arm26 --controls IN/c.sto --initial-states IN/s.sto --final-time 0.1 --out OUT/f",
         {"s.sto: column 'r_elbow_flex' at t = 0 s: nan: expected a finite number"}},
        {"ForwardStatesActivationFive", {{"c.sto", sto + "time\tBIClong\n0\t0.1\n"}, {"s.sto", sto + "time\tBIClong.activation\n0\t5\n"}},
         "forward --model arm26 --controls IN/c.sto --initial-states IN/s.sto --final-time 0.1 --out OUT/f",
         {"s.sto: column 'BIClong.activation'", "expected an activation in [0, 1]"}},
        {"ForwardOutputOnItsControls", {{"states.csv", "time,BIClong\n0,0.1\n"}},
         "forward --model arm26 --controls IN/states.csv --final-time 0.1 --out IN",
         {"--controls", "states.csv", "which forward writes", "it would replace the input"}},
        {"ForwardSetupNumberWithText",
         {{"s.xml", "<OpenSimDocument Version=\"40000\"><ForwardTool><model_file>x.osim</model_file>\n<final_time>0.2abc</final_time>"
                    "</ForwardTool></OpenSimDocument>\n"}},
         "forward IN/s.xml --out OUT/f", {"s.xml:2", "<final_time> '0.2abc': expected a number"}},
        {"ForwardSetupElementTwice",
         {{"s.xml", "<OpenSimDocument Version=\"40000\"><ForwardTool><model_file>x.osim</model_file>\n<final_time>1</final_time>\n"
                    "<final_time>2</final_time></ForwardTool></OpenSimDocument>\n"}},
         "forward IN/s.xml --out OUT/f", {"s.xml:3", "<final_time>: given twice (first at line 2)"}},
        {"ForwardSetupOtherController",
         {{"s.xml", "<OpenSimDocument Version=\"40000\"><ForwardTool><model_file>x.osim</model_file>\n<ControllerSet><objects>\n"
                    "<PrescribedController/></objects></ControllerSet></ForwardTool></OpenSimDocument>\n"}},
         "forward IN/s.xml --out OUT/f", {"s.xml:3", "controller type PrescribedController is not supported"}},
        {"ForwardStepLimitTiny", {{"c.sto", sto + "time\tBIClong\n0\t0.1\n"},
                                  {"s.xml", "<OpenSimDocument Version=\"40000\"><ForwardTool><model_file>arm26.osim</model_file>\n"
                                            "<final_time>0.2</final_time><maximum_integrator_step_size>1e-12</maximum_integrator_step_size>"
                                            "<ControllerSet><objects><ControlSetController><controls_file>c.sto</controls_file>"
                                            "</ControlSetController></objects></ControllerSet></ForwardTool></OpenSimDocument>\n"},
                                  {"arm26.osim", armsim::readFileText(armsim::getAssetDirectory() + "/models/arm26.osim")}},
         "forward IN/s.xml --out OUT/f", {"maximum_integrator_step_size", "1e-12 s", "2e+11 steps", "expected at most 1e+07"}},
        {"OsimTrialWithoutMuscles", {{"m.osim", noMuscles}}, "trial --model IN/m.osim --coordinate r_elbow_flex --out OUT/t.csv",
         {"has no muscles", "a trial excites muscles"}},
        {"OsimTrialFreeOfALockedCoordinate", {{"m.osim", lockedElbow}},
         "trial --model IN/m.osim --type free --coordinate r_elbow_flex --out OUT/t.csv",
         {"--coordinate 'r_elbow_flex' is locked in", "m.osim (line"}},
        {"OsimTwoMusclesOfOneName", {{"m.osim", replaceAll(arm26, "<Thelen2003Muscle name=\"BICshort\">", "<Thelen2003Muscle name=\"BIClong\">")}},
         "trial --model IN/m.osim --coordinate r_elbow_flex --out OUT/t.csv", {"m.osim:", "muscle 'BIClong' is named twice"}},
        {"JobsNotAWholeNumber", {}, "design --jobs 1.5 --out OUT/d", {"--jobs = '1.5': expected an integer in [1, 64]"}},
        {"RateNotANumberInARange", {}, "forward --model arm26 --rate abc --out OUT/f", {"--rate = 'abc': expected a number in [0.001, 1e+06]"}},
        {"AccuracyZeroInARange", {}, "forward --model arm26 --accuracy 0 --out OUT/f", {"--accuracy = 0: expected a number in [1e-12, 0.1]"}},
        {"OsimMusclePropertyOutOfRange",
         {{"m.osim", replaceAll(arm26, "<FmaxTendonStrain>0.033000000000000002</FmaxTendonStrain>", "<FmaxTendonStrain>-1</FmaxTendonStrain>")}},
         "trial --model IN/m.osim --coordinate r_elbow_flex --out OUT/t.csv", {"m.osim:", "<FmaxTendonStrain> (muscle '", "= -1: expected in (0, 1)"}},
        {"IdentifyFreeMaxPathDefaultBound", {}, "identify measured/thesis_measured.csv --free mass,tendon_length,max_path_length --out OUT/id",
         {"the default lower bound of max_path_length (give --bounds max_path_length=LO:HI) = 0.35 m",
          "expected >= the longest path 0.41 m", "thesis_measured.csv:4"}},
        {"TrialListDuplicateNoise", {}, "validate --noise 0,0 --out OUT/v", {"--noise = 0 is listed twice"}},
        {"DesignPostureOfTheModel", {}, "design --postures 0 --draws 2 --out OUT/d", {"--postures", "the model's own posture"}},
        {"ModelFileMuscleModelUnknown",
         {{"m.yaml", "name: m\narm: arm/default_male.yaml\nmuscle_model: hill\nmuscles:\n  - name: A\n    mass: 0.1\n"}},
         "model show --model IN/m.yaml --out OUT/ms", {"m.yaml:3", "muscle_model", "'hill'", "expected one of"}},
        // ---- torque data, validation, design, studies ------------------------------------------
        {"TorqueDataMissing", {}, "identify-torque IN/none.csv --out OUT/it", {"none.csv"}},
        {"TorqueDataWrongSign", {{"t.csv", "flexion_deg,torque_Nm\n90,-40\n"}}, "identify-torque IN/t.csv --out OUT/it",
         {"t.csv:2", "torque_Nm", "-40"}},
        {"TorqueActivationZero", {}, "identify-torque measured/thesis_mvc_torque.csv --activation 0 --out OUT/it",
         {"--activation", "voluntary activation 0: expected in (0, 1]"}},
        {"TorqueNoiseLevelOutOfRange", {}, "identify-torque measured/thesis_mvc_torque.csv --noise-level 2 --out OUT/it",
         {"--noise-level", "2"}},
        {"ValidateNoiseNotANumber", {}, "validate --noise abc --out OUT/v", {"--noise", "abc"}},
        {"ValidateNoiseNotFinite", {}, "validate --noise 0,inf --out OUT/v", {"--noise", "'inf'", "expected a finite number"}},
        {"ValidateSubjectsZero", {}, "validate --truth elbow --subjects 0 --out OUT/v", {"--subjects", "0"}},
        {"ValidateTruthPopulationMissing", {}, "validate --truth elbow --truth-population IN/none.yaml --out OUT/v",
         {"none.yaml"}},
        {"ValidatePriorWithoutElbow", {}, "validate --prior subjects/default_population.yaml --out OUT/v",
         {"--prior", "needs --truth elbow"}},
        {"ValidateBadMeanScale", {{"p.yaml", "name: p\nmodel: elbow\nstrength: {mean_scale: 9}\n"}},
         "validate --truth elbow --truth-population IN/p.yaml --out OUT/v", {"p.yaml:3", "strength.mean_scale", "9"}},
        {"ValidateOutIsAFile", {{"afile", "x"}}, "validate --seeds 0 --noise 0 --out IN/afile", {"--out", "not a folder"}},
        {"DesignTrialsZero", {}, "design --trials 0 --out OUT/d", {"--trials", "0"}},
        {"DesignAnglesNotNumbers", {}, "design --angles 30,abc --out OUT/d", {"--angles", "abc"}},
        {"DesignLevelsEmpty", {}, "design --levels '' --out OUT/d", {"--levels", "''", "leave the option out"}},
        {"StudyMissing", {}, "study IN/none.yaml --out OUT/s", {"none.yaml"}},
        {"StudyUnknownKey", {{"s.yaml", kStudyHead + "methods:\n  - {method: thesis}\nweather: rain\n"}},
         "study IN/s.yaml --out OUT/s", {"s.yaml", "weather"}},
        {"StudyNoiseOutOfRange", {{"s.yaml", "kind: study\nname: bad\nsubjects: 1\nprotocols: [thesis]\nnoise_levels: [3]\n"
                                            "methods:\n  - {method: thesis}\n"}},
         "study IN/s.yaml --out OUT/s", {"s.yaml", "noise_levels", "3"}},
        // ---- render and model ------------------------------------------------------------------
        {"RenderTableMissing", {}, "render IN/none.csv --out OUT/v.mp4", {"none.csv"}},
        {"RenderTableWithoutStates", {{"t.csv", "time_s,activation\n0,0\n0.1,1\n"}}, "render IN/t.csv --out OUT/v.mp4",
         {"t.csv", "column"}},
        {"RenderCodecUnknown", {{"t.csv", "time_s\n0\n"}}, "render IN/t.csv --out OUT/v.mp4 --codec vp9",
         {"--codec = 'vp9'", "expected one of"}},
        {"ModelShowUnknown", {}, "model show --model no_such_model --out OUT/m", {"no_such_model"}},
        {"TrialPlotEmpty", {}, "trial --plot '' --out OUT/t.csv", {"--plot: is empty", "leave the option out for its default"}},
        {"IdentifyTorquePopulationEmpty", {}, "identify-torque measured/thesis_mvc_torque.csv --population '' --out OUT/i",
         {"--population: is empty"}},
        {"IdentifyDataEmpty", {}, "identify '' --out OUT/i", {"data: is empty: expected a file name"}},
        {"OutEmpty", {}, "identify-torque measured/thesis_mvc_torque.csv --out ''", {"--out: is empty", "leave the option out"}},
        {"OutNameTooLong", {}, "identify measured/thesis_measured.csv --out OUT/" + std::string(230, 'n'),
         {"--out", "a folder name of 230 characters", "expected at most 215"}},
        {"OutNameTooLongWithSlash", {}, "identify measured/thesis_measured.csv --out OUT/" + std::string(230, 'n') + "/",
         {"--out", "a folder name of 230 characters", "expected at most 215"}},
        {"IdentifyFaithfulHoldHuge", {}, "identify measured/thesis_measured.csv --forward faithful --hold 1e9 --out OUT/id",
         {"samples", "at most 1e+07"}},
        {"EmgInternalRateHuge", {{"p.yaml", "name: bad\nkind: submaximal\nseed: 1\nsubject:\n  arm: arm/default_male.yaml\n"
                                            "  muscle: muscles/biceps_long_head.yaml\n" + std::string("trial:\n  hold: 1.0\n"
                                            "  averaging_window: 0.5\nconditions:\n  elbow_angles_deg: [90]\n"
                                            "  levels_pct_mvc: [50, 100]\nsensors:\n  emg:\n    internal_rate: 1.0e12\n")}},
         "protocol IN/p.yaml --out OUT/run", {"p.yaml", "internal_rate", "1e+12"}},
        // ---- several outputs: checked before the work, written together or not at all (issue 34) ----
        {"TrialPlotIsTheCsv", {}, "trial --hold 0.2 --out OUT/t.png --plot OUT/t.png",
         {"--plot", "is the file --out writes", "expected a path of its own"}},
        {"TrialPlotUnderAFile", {{"afile", "x"}}, "trial --hold 0.2 --out OUT/t.csv --plot IN/afile/p.png",
         {"--plot", "afile/p.png", "is a file"}},
        {"TrialVideoUnderAFile", {{"afile", "x"}}, "trial --hold 0.2 --out OUT/t.csv --video IN/afile/v.mp4",
         {"--video", "afile/v.mp4", "is a file"}},
        {"SweepPlotUnderAFile", {{"afile", "x"}}, "muscle sweep --out OUT/s.csv --plot IN/afile/p.png",
         {"--plot", "afile/p.png", "is a file"}},
        {"MuscleTrialPlotIsTheCsv", {}, "muscle trial --out OUT/m.png --plot OUT/m.png", {"--plot", "is the file --out writes"}},
        {"RenderStillIsTheVideo", {{"t.csv", "time_s\n0\n"}}, "render IN/t.csv --out OUT/v.mp4 --still-at 0.1 --still OUT/v.mp4",
         {"--still", "is the file --out writes"}},
        {"ProtocolVideoFpsTiny", {}, "protocol protocols/mvc_force_angle.yaml --out OUT/run --video --video-fps 1e-9",
         {"--video-fps", "1e-09", "[1, 240]"}},
        // ---- issue 34, round 3: each class of the sweep over every file kind ----------------------
        // a key twice: refused with both lines, in every YAML file kind and inside flow and block maps
        {"DupKeyMuscleFile", {{"m.yaml", muscle + "mass: 0.5\n"}}, "muscle steady --muscle IN/m.yaml",
         {"m.yaml:", "key 'mass' appears again (first at line"}},
        {"DupKeyArmFile", {{"a.yaml", "hand_load: 1\nhand_load: 2\n"}}, "trial --arm IN/a.yaml --hold 0.2 --out OUT/t.csv",
         {"a.yaml:2", "key 'hand_load' appears again (first at line 1)"}},
        {"DupKeyModelFile", {{"m.yaml", "name: a\narm: arm/default_male.yaml\nname: b\n"}}, "model show --model IN/m.yaml --out OUT/ms",
         {"m.yaml:3", "key 'name' appears again (first at line 1)"}},
        {"DupKeyPopulation", {{"p.yaml", "name: p\nmodel: elbow\nname: q\n"}},
         "validate --truth elbow --truth-population IN/p.yaml --subjects 2 --out OUT/v", {"p.yaml:3", "key 'name' appears again"}},
        {"DupKeyStudy", {{"s.yaml", kStudyHead + "subjects: 2\nmethods:\n  - {method: thesis}\n"}}, "study IN/s.yaml --out OUT/s",
         {"s.yaml:6", "key 'subjects' appears again (first at line 3)"}},
        {"DupKeyTrialSettings", {{"s.yaml", "type: isometric\nhold: 1\nhold: 2\n"}}, "trial --settings IN/s.yaml --out OUT/t.csv",
         {"s.yaml:3", "key 'hold' appears again (first at line 2)"}},
        {"DupKeyTorqueProtocol", {{"p.yaml", "kind: torque\nname: a\nname: b\nconditions:\n" + condition}},
         "protocol IN/p.yaml --out OUT/run", {"p.yaml:3", "key 'name' appears again"}},
        {"DupKeyInFlowMap", {{"p.yaml", kTorqueHead + "conditions:\n  - {flexion_deg: 90, flexion_deg: 60, effort: flexion, level: 1, repetitions: 3}\n"}},
         "protocol IN/p.yaml --out OUT/run", {"p.yaml:4", "key 'flexion_deg' appears again"}},
        {"DupKeyInBlockItem", {{"p.yaml", kTorqueHead + "conditions:\n  - flexion_deg: 90\n    effort: flexion\n    effort: extension\n"
                                                       "    level: 1\n    repetitions: 3\n"}},
         "protocol IN/p.yaml --out OUT/run", {"p.yaml:6", "key 'effort' appears again (first at line 5)"}},
        {"DupKeyAnatomyTargets", {{"t.yaml", "name: t\nname: u\n"}}, "model check --model twin --targets IN/t.yaml --out OUT/mc",
         {"t.yaml:2", "key 'name' appears again"}},
        // a column twice: refused with both columns, in every CSV and storage kind
        {"DupHeaderForceData", {{"d.csv", "angle_deg,force_N,force_N\n90,400,401\n60,300,301\n"}}, "identify IN/d.csv --out OUT/id",
         {"d.csv:1", "column 'force_N' appears twice in the header (columns 2 and 3)"}},
        {"DupHeaderTorqueData", {{"t.csv", "flexion_deg,torque_Nm,torque_Nm\n90,40,41\n60,30,31\n"}}, "identify-torque IN/t.csv --out OUT/it",
         {"t.csv:1", "column 'torque_Nm' appears twice"}},
        {"DupHeaderChannelData", {{"c.csv", "channel,muscle,flexion_deg,value,value\nvolume,BIClong,,1e-4,1e-4\n"}},
         "identify-torque measured/thesis_mvc_torque.csv --channels IN/c.csv --out OUT/it", {"c.csv:1", "column 'value' appears twice"}},
        {"DupHeaderActivationTrace", {{"u.csv", "time_s,activation,activation\n0,0,0\n1,1,1\n"}},
         "muscle trial --activation-trace IN/u.csv --out OUT/t.csv", {"u.csv:1", "column 'activation' appears twice"}},
        {"DupHeaderRenderTable", {{"t.csv", "time_s,time_s\n0,0\n"}}, "render IN/t.csv --out OUT/v.mp4",
         {"t.csv:1", "column 'time_s' appears twice"}},
        {"DupHeaderControls", {{"c.sto", sto + "time\tBIClong\tBIClong\n0\t0.1\t0.2\n"}},
         "forward --model arm26 --controls IN/c.sto --final-time 0.1 --out OUT/f", {"c.sto:7", "column 'BIClong' appears twice"}},
        // bounds in files as on the command line
        {"ArmFileHandLoadHuge", {{"a.yaml", replaceAll(arm, "hand_load: 0", "hand_load: 1.0e6")}},
         "trial --arm IN/a.yaml --hold 0.2 --out OUT/t.csv", {"a.yaml:", "field 'hand_load' = 1e+06", "[0, 50] (kg)"}},
        {"MuscleFileMassHuge", {{"m.yaml", replaceAll(muscle, "mass: 0.33599", "mass: 1.0e6")}}, "muscle steady --muscle IN/m.yaml",
         {"m.yaml:6", "mass", "1e+06", "(0, 10] (kg)"}},
        {"ArmFileBodyMassHuge", {{"a.yaml", replaceAll(arm, "mass: 73.0 ", "mass: 1.0e6")}},
         "trial --arm IN/a.yaml --hold 0.2 --out OUT/t.csv", {"a.yaml:8", "'body.mass' = 1e+06", "(0, 700] (kg, a person)"}},
        {"ArmFileHeightHuge", {{"a.yaml", replaceAll(arm, "height: 1.741 ", "height: 50")}},
         "trial --arm IN/a.yaml --hold 0.2 --out OUT/t.csv", {"a.yaml:9", "'body.height' = 50", "(0, 3] (m, a person)"}},
        {"ArmFileStopDissipationHuge", {{"a.yaml", replaceAll(arm, "stop_dissipation: 0.1 ", "stop_dissipation: 1e9")}},
         "trial --arm IN/a.yaml --hold 0.2 --out OUT/t.csv", {"a.yaml:32", "'elbow.stop_dissipation' = 1e+09", "[0, 100]"}},
        {"MuscleFilePathHuge", {{"m.yaml", replaceAll(muscle, "max_path_length: 0.43 ", "max_path_length: 100")}},
         "muscle steady --muscle IN/m.yaml", {"m.yaml:9", "max_path_length", "100", "(0, 3] (m)"}},
        {"MuscleFileFascicleTiny", {{"m.yaml", replaceAll(muscle, "optimal_fascicle_length: ", "optimal_fascicle_length: 1.0e-9 #")}},
         "muscle steady --muscle IN/m.yaml", {"m.yaml", "optimal_fascicle_length", "1e-09", "[0.001, 1] (m, a muscle fascicle)"}},
        {"OsimBodyMassHuge", {{"m.osim", replaceAll(arm26, "<mass>1.8645719999999999</mass>", "<mass>1e9</mass>")}},
         "model show --model IN/m.osim --out OUT/ms", {"m.osim:", "mass 1e+09", "expected 0 to 1e5 kg"}},
        {"IdentifyRelativeForceSdHuge", {}, "identify measured/thesis_measured.csv --noise relative --force-sd 5 --out OUT/i",
         {"--force-sd", "5", "(0, 1]"}},
        {"ChannelValueInCentimetres", {{"c.csv", "channel,muscle,flexion_deg,value,sd\nfascicle_length,BIClong,90,50,1\n"}},
         "identify-torque measured/thesis_mvc_torque.csv --channels IN/c.csv --out OUT/it",
         {"c.csv:2", "column 'value' = 50", "(0, 1] m"}},
        // options and fields that would be ignored
        {"IdentifySeedWithIlc", {}, "identify measured/thesis_measured.csv --method ilc-secant --seed 4 --out OUT/i",
         {"--seed is an option of --method lm", "ilc-secant would ignore it"}},
        {"IdentifyStartTwice", {}, "identify measured/thesis_measured.csv --start mass=0.3 --start mass=0.4 --out OUT/i",
         {"--start mass=0.4", "'mass' is given twice"}},
        {"IdentifyBoundsTwiceByAlias", {},
         "identify measured/thesis_measured.csv --bounds tendon_length=0.1:0.3 --bounds optimal_tendon_length=0.2:0.4 --out OUT/i",
         {"--bounds optimal_tendon_length=0.2:0.4", "is given twice"}},
        {"ValidateMassIgnored", {}, "validate --mass 0.4 --seeds 0 --out OUT/v", {"--mass", "would be ignored"}},
        {"ValidateElbowModelIgnored", {}, "validate --truth elbow --model thesis --subjects 1 --out OUT/v",
         {"--model with --truth elbow", "would be ignored"}},
        {"HelpHintNamesTheCommand", {}, "model show --step abc", {"--step = 'abc'", "(armsim model show --help lists its options)"}},
        {"TrialPlotNotPng", {}, "trial --hold 0.2 --out OUT/t.csv --plot OUT/t.svg", {"--plot '", "t.svg': extension '.svg': expected .png"}},
        {"DesignTrialsNotWholeBlocks", {}, "design --trials 4 --repetitions 3 --out OUT/d",
         {"--trials = 4: expected a multiple of the repetitions 3", "3 or 6"}},
        {"SweepStepLongerThanTheRange", {}, "muscle sweep --step 1 --out OUT/s.csv", {"--step 1 m is longer than --from"}},
        {"SweepToPastTheLongestPath", {}, "muscle sweep --to 0.5 --out OUT/s.csv", {"--to: ", "0.5"}},
        {"ModelRoleListsAMuscleTwice", {{"e.yaml", replaceAll(elbow, "synergists: [BRA, BRD]", "synergists: [BRA, BRA]")}},
         "model show --model IN/e.yaml --out OUT/m", {"e.yaml:", "'roles.synergists' lists 'BRA' twice"}},
        {"ModelRoleHeadAsSynergist", {{"e.yaml", replaceAll(elbow, "synergists: [BRA, BRD]", "synergists: [BRA, BICshort]")}},
         "model show --model IN/e.yaml --out OUT/m", {"e.yaml:", "lists 'BICshort', a biceps head"}},
        {"ArmFileForearmMassFractionHuge", {{"a.yaml", replaceAll(arm, "mass_fraction: 0.022", "mass_fraction: 0.9")}},
         "trial --arm IN/a.yaml --hold 0.2 --out OUT/t.csv", {"a.yaml", "forearm_hand.mass_fraction", "0.9", "(0, 0.1]"}},
        {"RenderFpsEmpty", {{"t.csv", "time_s\n0\n"}}, "render IN/t.csv --fps '' --out OUT/v.mp4", {"--fps", "is empty: expected a number"}},
        {"TorqueDataInNewtonMillimetres", {{"t.csv", "flexion_deg,torque_Nm\n90,45000\n60,40000\n"}},
         "identify-torque IN/t.csv --out OUT/it", {"t.csv:2", "torque_Nm", "45000", "[-1000, 1000] (N m)"}},
        {"ForwardFinalBeforeInitial", {}, "forward --model arm26 --controls " + std::string(ARMSIM_SOURCE_DIR) +
         "/tests/data/opensim/arm26_forward/arm26_controls.sto --initial-time 0.8 --final-time 0.2 --out OUT/f",
         {"--final-time = 0.2 s: expected after the initial time 0.8 s"}},
        {"DesignPopulationMissing", {}, "design --population nope --out OUT/d", {"--population 'nope': no such file"}},
        {"ValidateTooManyFits", {}, "validate --truth elbow --subjects 1000000 --noise 1,2,3,4 --out OUT/v",
         {"1000000 subjects x 4 noise levels x 3 identifiers = 12000000 fits", "expected at most 4000000"}},
        {"DesignTrialsWithBudget", {}, "design --budget 60 --trials 10 --out OUT/d", {"--trials with --budget", "give one or the other"}},
        {"MuscleUnitsOfAHillMuscle", {}, "muscle steady --model thesis --muscle-model thelen2003 --slow-units 3",
         {"--slow-units", "thelen2003 muscle", "no motor units"}},
        {"DesignBudgetBelowOneBlock", {}, "design --budget 1 --draws 3000 --out OUT/d",
         {"--budget = 1 min: no MVC block (8 min for 3 repetitions) fits", "expected at least 8 min"}},
        {"TorqueProtocolChannelTwice",
         {{"p.yaml", kTorqueHead + "subject:\n  model: twin\nconditions:\n  - {flexion_deg: 90, effort: flexion, channels: [torque, torque]}\n"}},
         "protocol IN/p.yaml --out OUT/run", {"p.yaml:6: field 'channels' (conditions, entry 1) lists 'torque' twice"}},
        {"CompositionWithoutMotorUnits",
         {{"p.yaml", "name: bad\nkind: composition\nconditions:\n  slow_units: {from: 0, to: 0}\n  fast_units: {from: 0, to: 0}\n"}},
         "protocol IN/p.yaml --out OUT/run", {"p.yaml:5: fields 'conditions.slow_units' and 'conditions.fast_units' both end at 0"}},
        {"ModelTendonSlackLengthInMillimetres",
         {{"m.yaml", "name: m\narm: arm/default_male.yaml\nmuscles:\n  - name: b\n    max_isometric_force: 600\n"
                     "    optimal_fascicle_length: 0.1157\n    tendon_slack_length: 272.3\n"
                     "    fibre_fractions: {slow: 0.5, fast: 0.5}\n    fibre_types: " + armsim::getAssetDirectory() +
                     "/muscles/human_fibre_types.yaml\n    path:\n      origin: {body: upper_arm, location: [0, 0.3, 0]}\n"
                     "      insertion: {body: forearm, location: [0, -0.05, 0]}\n"}},
         "model show --model IN/m.yaml --out OUT/s", {"m.yaml:7: field 'tendon_slack_length' (muscles, entry 1) = 272.3", "(0, 2] (m)"}},
        {"StudyOutOnSysfs", {{"s.yaml", kStudyHead + "methods:\n  - {method: thesis}\n"}}, "study IN/s.yaml --out /sys/kernel/armsim_study",
         {"'/sys/kernel/armsim_study': cannot create the folder"}},
        {"ValidateMethodsUnknown", {}, "validate --methods LM --out OUT/v", {"--methods: method 'LM': expected one of"}},
        {"MuscleWithoutItsCommand", {}, "muscle", {"armsim muscle needs a command: expected one of steady, sweep, trial"}},
        {"TrialRateTwice", {}, "trial --rate 100 --rate=200 --out OUT/t.csv", {"--rate is given 2 times (100, 200): expected it once"}},
        {"RenderArrowScaleHuge", {{"t.csv", "time_s\n0\n"}}, "render IN/t.csv --out OUT/v.mp4 --arrow-scale 1e308",
         {"--arrow-scale", "1e+308", "[0, 0.1] (m/N, 0 = automatic)"}},
        {"TrialLoadBeyondDouble", {}, "trial --load 1e309 --out OUT/t.csv", {"--load: '1e309' is beyond the largest number"}},
        {"IdentifyForceBeyondDouble", {{"f.csv", "path_cm,force_N\n41,1e309\n37.5,458\n"}}, "identify IN/f.csv --out OUT/id",
         {"f.csv:2: column 'force_N' = '1e309': beyond the largest number"}},
        {"StudyShardPastTheGroups", {{"s.yaml", kStudyHead + "methods:\n  - {method: thesis}\n"}}, "study IN/s.yaml --shard 5/6 --out OUT/s",
         {"shard 5/6: the study has 1 group (truths x subjects x protocols)", "expected N at most the number of groups"}},
        {"StudyThesisMethodActivationSd", {{"s.yaml", kStudyHead + "methods:\n  - {method: thesis, activation_sd: 0.05}\n"}},
         "study IN/s.yaml --out OUT/s", {"s.yaml:", "'activation_sd' with method thesis", "would be ignored"}},
        {"TorqueNoiseLevelBelowTheFloor", {}, "identify-torque measured/thesis_mvc_torque.csv --noise-level 0.001 --out OUT/it",
         {"--noise-level", "0.001", "[0.002, 0.5]"}},
        {"StudyMethodNoiseLevelBelowTheFloor", {{"s.yaml", kStudyHead + "methods:\n  - {method: synergist, noise_level: 0.0001}\n"}},
         "study IN/s.yaml --out OUT/s", {"s.yaml:7", "noise_level", "1e-04", "[0.002, 0.5]"}},
        {"StudyNoiseLevelTwice", {{"s.yaml", replaceAll(kStudyHead, "noise_levels: [0.02]", "noise_levels: [0.02, 0.02]") +
                                             "methods:\n  - {method: thesis}\n"}},
         "study IN/s.yaml --out OUT/s", {"s.yaml:", "lists 0.02 twice"}},
        {"MuscleSteadyPathInfinite", {}, "muscle steady --path inf", {"--path = inf", "(0, 3]"}},
        {"ProtocolSampleRateBelowEmgBand",
         {{"p.yaml", replaceAll(armsim::readFileText(armsim::getAssetDirectory() + "/protocols/mvc_force_angle.yaml"),
                                "sample_rate: 1000 ", "sample_rate: 200 ")}},
         "protocol IN/p.yaml --out OUT/run", {"p.yaml:32", "band_high", "half of trial.sample_rate = 200 Hz"}},
        {"OsimMismatchedElement",
         {{"m.osim", "<?xml version=\"1.0\"?>\n<OpenSimDocument Version=\"40000\">\n<Model name=\"x\">\n<BodySet>\n</Model>\n"}},
         "model show --model IN/m.osim --out OUT/ms", {"m.osim:4", "not valid XML: an element closed by another"}},
        {"PopulationSdNegative", {{"p.yaml", "name: p\nmodel: elbow\ntendon_length:\n  sd: -0.1\n"}},
         "validate --truth elbow --truth-population IN/p.yaml --subjects 2 --out OUT/v", {"p.yaml:3", "'tendon_length.sd' = -0.1"}},
        {"StudySubjectsZero", {{"s.yaml", replaceAll(kStudyHead, "subjects: 1", "subjects: 0") + "methods:\n  - {method: thesis}\n"}},
         "study IN/s.yaml --out OUT/s", {"s.yaml:3", "'subjects' = 0", "[1, 1e+07]"}},
        {"StudySubjectsHuge", {{"s.yaml", replaceAll(kStudyHead, "subjects: 1", "subjects: 100000000") + "methods:\n  - {method: thesis}\n"}},
         "study IN/s.yaml --out OUT/s", {"s.yaml:3", "'subjects' = 1e+08", "[1, 1e+07]"}},
        {"TorqueProtocolRepetitionsZero", {{"p.yaml", kTorqueHead + "conditions:\n  - {flexion_deg: 90, effort: flexion, level: 1, repetitions: 0}\n"}},
         "protocol IN/p.yaml --out OUT/run", {"p.yaml:4", "'repetitions' (conditions, entry 1) = 0", "[1, 100]"}},
        {"TorqueProtocolRepetitionsHuge", {{"p.yaml", kTorqueHead + "conditions:\n  - {flexion_deg: 90, effort: flexion, level: 1, repetitions: 1000000000}\n"}},
         "protocol IN/p.yaml --out OUT/run", {"p.yaml:4", "repetitions", "1e+09", "[1, 100]"}},
        {"ProtocolRepetitionsZero", {{"p.yaml", kProtocolHead + "repetitions: 0\n" + kTrial + kAngles}},
         "protocol IN/p.yaml --out OUT/run", {"p.yaml:7", "'repetitions' = 0", "[1, 1000]"}},
        {"ProtocolWindowLongerThanHold", {{"p.yaml", kProtocolHead + "trial:\n  hold: 1.0\n  averaging_window: 2.0\n" + kAngles}},
         "protocol IN/p.yaml --out OUT/run", {"p.yaml:9", "'trial.averaging_window' = 2", "within the hold"}},
        {"TrialSettingsRateZero", {{"s.yaml", "type: isometric\nsample_rate: 0\n"}}, "trial --settings IN/s.yaml --out OUT/t.csv",
         {"s.yaml:2", "'sample_rate' = 0", "> 0 (Hz)"}},
        {"FreeSettingsAngleOutOfRange", {{"s.yaml", "type: free\ninitial_angle_deg: 10\n"}}, "trial --settings IN/s.yaml --out OUT/t.csv",
         {"s.yaml:2", "'initial_angle_deg' = 10", "[40, 180] (deg)"}},
        {"ChannelDataSdZero", {{"c.csv", channelHead + "volume,BIClong,,1,0,1,1e-4,0\n"}},
         "identify-torque measured/thesis_mvc_torque.csv --channels IN/c.csv --out OUT/it", {"c.csv:2", "column 'sd' = 0", "> 0"}},
        {"ChannelDataUnknownChannel", {{"c.csv", channelHead + "xray,BIClong,90,1,0,1,0.1,0.01\n"}},
         "identify-torque measured/thesis_mvc_torque.csv --channels IN/c.csv --out OUT/it", {"c.csv:2", "'xray'", "expected fascicle_length"}},
        {"TorqueDataLevelAboveOne", {{"t.csv", "flexion_deg,effort,level,repetition,torque_Nm\n90,1,1.5,1,40\n60,1,1,1,30\n"}},
         "identify-torque IN/t.csv --out OUT/it", {"t.csv:2", "column 'level' = 1.5", "(0, 1]"}},
        {"TorqueDataEffortBad", {{"t.csv", "flexion_deg,effort,level,repetition,torque_Nm\n90,3,1,1,40\n60,1,1,1,30\n"}},
         "identify-torque IN/t.csv --out OUT/it", {"t.csv:2", "column 'effort' = 3", "1 (flexion), -1 (extension)"}},
        {"ForwardControlsNotNumbers", {{"c.sto", sto + "time\tBIClong\n0\tabc\n"}},
         "forward --model arm26 --controls IN/c.sto --final-time 0.1 --out OUT/f", {"c.sto:8", "column 'BIClong'", "expected a number"}},
        {"ForwardControlsEmpty", {{"c.sto", ""}}, "forward --model arm26 --controls IN/c.sto --final-time 0.1 --out OUT/f",
         {"c.sto", "no 'endheader' line"}},
        {"ForwardControlsMissing", {}, "forward --model arm26 --controls IN/none.sto --final-time 0.1 --out OUT/f", {"none.sto"}},
        // nothing to do, or a list entry wrong: named by its key and place
        {"StudyMethodsEmpty", {{"s.yaml", kStudyHead + "methods: []\n"}}, "study IN/s.yaml --out OUT/s",
         {"s.yaml:6", "'methods' is empty", "at least one identifier"}},
        {"StudyProtocolUnknown", {{"s.yaml", replaceAll(kStudyHead, "[thesis]", "[nosuch]") + "methods:\n  - {method: thesis}\n"}},
         "study IN/s.yaml --out OUT/s", {"s.yaml:4", "'nosuch'", "no such protocol file ('protocols' (entry 1))"}},
        {"StudyDuplicateMethodLabel", {{"s.yaml", kStudyHead + "methods:\n  - {method: thesis}\n  - {method: thesis}\n"}},
         "study IN/s.yaml --out OUT/s", {"s.yaml", "'label' (methods, entry 2) = 'thesis'", "also the label of entry 1"}},
        {"TorqueProtocolNoConditions", {{"p.yaml", kTorqueHead + "conditions: []\n"}}, "protocol IN/p.yaml --out OUT/run",
         {"p.yaml:3", "'conditions' is empty: expected at least one condition"}},
        {"TorqueProtocolSecondEntryBad", {{"p.yaml", kTorqueHead + "conditions:\n" + condition +
                                                    "  - {flexion_deg: 400, effort: flexion, level: 1, repetitions: 3}\n"}},
         "protocol IN/p.yaml --out OUT/run", {"p.yaml:5", "'flexion_deg' (conditions, entry 2) = 400", "[0, 180]"}},
        {"ProtocolAnglesEmpty", {{"p.yaml", kProtocolHead + kTrial + "conditions:\n  elbow_angles_deg: []\n"}},
         "protocol IN/p.yaml --out OUT/run", {"p.yaml:12", "is empty: expected at least one angle"}},
        {"ProtocolSecondAngleBad", {{"p.yaml", kProtocolHead + kTrial + "conditions:\n  elbow_angles_deg: [90, 300]\n"}},
         "protocol IN/p.yaml --out OUT/run", {"p.yaml:12", "'conditions.elbow_angles_deg' (entry 2) = 300"}},
        // options named as typed, in the units typed, checked before any work
        {"TrialAngleNan", {}, "trial --angle nan --out OUT/t.csv", {"--angle = nan", "[40, 180] (deg)"}},
        {"TrialRestNegative", {}, "trial --rest -1 --out OUT/t.csv", {"--rest = -1", "> 0 (s)"}},
        {"TrialAccuracyOne", {}, "trial --accuracy 1 --out OUT/t.csv", {"--accuracy = 1", "[1e-08, 0.1]"}},
        {"FreeTrialInitialAngle", {}, "trial --type free --initial-angle 10 --out OUT/f.csv", {"--initial-angle = 10", "[40, 180] (deg)"}},
        {"FreeTrialLoadHuge", {}, "trial --type free --load 1e6 --out OUT/f.csv", {"--load = 1e+06", "[0, 50] (kg)"}},
        {"ValidateSeedsNegative", {}, "validate --seeds -1 --out OUT/v", {"--seeds = -1", "[0, 1e+06]"}},
        {"ValidateNoiseAsFractions", {}, "validate --noise 0,0.01,0.02 --seeds 1 --out OUT/v",
         {"--noise 0,0.01,0.02: every level is at most 0.05 %", "fractions? expected percent of the force (--noise 0,1,2)"}},
        {"ValidateNoisePercentHuge", {}, "validate --noise 60 --out OUT/v", {"--noise = 60", "[0, 50) (%"}},
        {"ValidateJobsHuge", {}, "validate --jobs 100000 --out OUT/v", {"--jobs = 100000", "[1, 64]"}},
        {"ModelShowStepZero", {}, "model show --model twin --step 0 --out OUT/ms", {"--step = 0 deg", "[0.01, 90]"}},
        {"ModelShowStepTiny", {}, "model show --model twin --step 1e-6 --out OUT/ms", {"--step = 1e-06 deg", "140000000 angles"}},
        {"StudyNameWithAPath", {{"s.yaml", replaceAll(kStudyHead, "name: bad", "name: ../esc") + "methods:\n  - {method: thesis}\n"}},
         "study IN/s.yaml", {"s.yaml:2", "'name' = '../esc'", "without '/'"}},
        {"CsvWithAByteOrderMarkIsRead", {{"d.csv", "\xEF\xBB\xBF" "angle_deg,force_N\n200,600\n"}}, "identify IN/d.csv --out OUT/id",
         {"d.csv:2", "angle_deg", "200"}},
        {"ChannelDataWithAByteOrderMarkIsRead", {{"c.csv", "\xEF\xBB\xBF" + channelHead + "volume,BIClong,,1,0,1,1e-4,0\n"}},
         "identify-torque measured/thesis_mvc_torque.csv --channels IN/c.csv --out OUT/it", {"c.csv:2", "column 'sd' = 0"}},
        {"ControlsWithAByteOrderMarkAreRead", {{"c.sto", "\xEF\xBB\xBF" + sto + "time\tBIC\n0\t0.1\n"}},
         "forward --model arm26 --controls IN/c.sto --final-time 0.1 --out OUT/f", {"c.sto", "column 'BIC' names no muscle"}},
        {"ModelShowOutIsAFile", {{"afile", "x"}}, "model show --model twin --out IN/afile", {"--out", "afile", "not a folder"}},
        {"ModelCheckUnknownModel", {}, "model check --model nosuch --out OUT/mc", {"--model 'nosuch'", "shipped models: elbow, thesis, twin"}},
        {"ModelCheckTargetsMissing", {}, "model check --model twin --targets IN/none.yaml --out OUT/mc", {"none.yaml", "cannot open"}},
        {"AnatomyTargetsBinary", {{"t.yaml", binary}}, "model check --model twin --targets IN/t.yaml --out OUT/mc", {"t.yaml"}},
        {"StudyThreadsNegative", {{"s.yaml", kStudyHead + "methods:\n  - {method: thesis}\n"}}, "study IN/s.yaml --threads -1 --out OUT/s",
         {"--threads", "-1"}},
        {"ForwardFinalTimeNegative", {{"c.sto", sto + "time\tBIClong\n0\t0.1\n"}},
         "forward --model arm26 --controls IN/c.sto --final-time -1 --out OUT/f", {"final time -1 s", "after the initial time"}},
        {"RenderFpsZero", {{"t.csv", "time_s\n0\n"}}, "render IN/t.csv --out OUT/v.mp4 --fps 0", {"--fps = 0", "[1, 240]"}},
        {"RenderWidthTiny", {{"t.csv", "time_s\n0\n"}}, "render IN/t.csv --out OUT/v.mp4 --width 3", {"--width = 3", "[16, 4096] (px)"}},
        {"RenderHeightOdd", {{"t.csv", "time_s\n0\n"}}, "render IN/t.csv --out OUT/v.mp4 --height 101", {"--height = 101", "even"}},
        {"RenderSpeedZero", {{"t.csv", "time_s\n0\n"}}, "render IN/t.csv --out OUT/v.mp4 --speed 0", {"--speed = 0", "> 0"}},
        {"DesignBudgetNegative", {}, "design --budget -5 --out OUT/d", {"--budget", "-5"}},
        {"DesignDrawsZero", {}, "design --draws 0 --out OUT/d", {"--draws", "0"}},
        {"DesignPosturesOutOfRange", {}, "design --postures 0,200 --out OUT/d", {"--postures = 200", "[-90, 90]"}},
        {"DesignCriterionUnknown", {}, "design --criterion best --out OUT/d", {"--criterion", "best", "considered,own"}},
        {"IdentifyMultistartZero", {}, "identify measured/thesis_measured.csv --multistart 0 --out OUT/id", {"--multistart", "0"}},
        {"IdentifyFreeUnknown", {}, "identify measured/thesis_measured.csv --free mass,colour --out OUT/id",
         {"--free", "'colour'", "expected one of mass"}},
        {"TorqueCrosstalkNegative", {}, "identify-torque measured/thesis_mvc_torque.csv --emg-crosstalk -0.5 --out OUT/it",
         {"--emg-crosstalk", "-0.5"}},
        {"IdentifyTorqueChannelsMissing", {}, "identify-torque measured/thesis_mvc_torque.csv --channels IN/none.csv --out OUT/it",
         {"none.csv", "no such file"}},
        {"IdentifyTorquePopulationMissing", {}, "identify-torque measured/thesis_mvc_torque.csv --population IN/none.yaml --out OUT/it",
         {"none.yaml"}},
        {"MuscleSweepFromAboveTo", {}, "muscle sweep --from 0.4 --to 0.3 --out OUT/s.csv", {"--to 0.3 m is below --from 0.4 m"}},
        {"MainJobJobsZero", {}, "run --jobs 0 --out OUT/r", {"--jobs", "0"}},

        // ---- a second sweep (421 probes): inputs overwritten, options ignored, work that keeps nothing ----
        {"TrialOutIsTheSettings", {{"s.yaml", "type: isometric\nhold: 0.3\n"}}, "trial --settings IN/s.yaml --out IN/s.yaml",
         {"--out", "s.yaml' is the file --settings reads", "would be overwritten"}},
        {"MuscleTrialOutIsTheTrace", {{"u.csv", "time_s,activation\n0,0\n0.5,1\n"}},
         "muscle trial --activation-trace IN/u.csv --duration 0.5 --out IN/u.csv", {"is the file --activation-trace reads"}},
        {"SweepOutIsTheMuscleFile", {{"m.yaml", muscle}}, "muscle sweep --muscle IN/m.yaml --out IN/m.yaml",
         {"is the file --muscle reads"}},
        {"RenderStillIsTheTable", {{"t.csv", "time_s\n0\n"}}, "render IN/t.csv --still-at 0.1 --still IN/t.csv",
         {"--still", "is the file the trial-table argument reads"}},
        {"TrialSettingsWithAnOption", {{"s.yaml", "type: isometric\nhold: 0.3\n"}}, "trial --settings IN/s.yaml --angle 60 --out OUT/t.csv",
         {"--settings excludes --angle"}},
        {"FreeTrialWithAnIsometricOption", {}, "trial --type free --angle 60 --out OUT/f.csv", {"--angle is an isometric trial's option"}},
        {"IsometricTrialWithAFreeOption", {}, "trial --load 5 --out OUT/t.csv", {"--load is a free movement's option", "--type free"}},
        {"MuscleTrialTraceWithActivation", {{"u.csv", "time_s,activation\n0,0\n0.5,1\n"}},
         "muscle trial --activation-trace IN/u.csv --activation 0.5 --out OUT/t.csv", {"--activation excludes --activation-trace"}},
        {"MuscleTrialOnsetAfterTheEnd", {}, "muscle trial --onset 5 --duration 0.2 --out OUT/t.csv",
         {"--onset 5 s", "--duration 0.2 s", "before the end"}},
        {"TrialRateKeepsOnlyTheStart", {}, "trial --rate 0.1 --hold 1 --rest 0.5 --out OUT/t.csv",
         {"--rest + --rise + --hold = 1.5 s x --rate 0.1 Hz", "samples after the start: expected at least one"}},
        {"FreeTrialRateKeepsOnlyTheStart", {}, "trial --type free --duration 1.5 --rate 0.5 --out OUT/f.csv",
         {"--duration = 1.5 s x --rate 0.5 Hz = 0.75 samples after the start: expected at least one"}},
        {"TrialSettingsSamplesBeyondTheLimit", {{"s.yaml", "type: isometric\nsample_rate: 1e9\nhold: 100\n"}},
         "trial --settings IN/s.yaml --out OUT/t.csv",
         {"s.yaml:2: rest + rise + hold = 100.5 s x sample_rate 1e+09 Hz = 100500000001 samples: expected at most 1e+07"}},
        {"TrialSamplesBeyondTheLimitNameTheOptions", {}, "trial --hold 5e6 --out OUT/t.csv",
         {"--rest + --rise + --hold = 5000000.5 s x --rate 1000 Hz = 5000000501 samples: expected at most 1e+07"}},
        {"OsimFreeTrialSamplesNameTheOptions", {}, "trial --model arm26 --type free --coordinate r_elbow_flex --duration 1e5 --rate 1000 --out OUT/f.csv",
         {"--duration = 1e+05 s x --rate 1000 Hz = 100000001 samples: expected at most 1e+07"}},
        {"IdentifyDataWithThesisCases", {}, "identify measured/thesis_measured.csv --thesis-cases --out OUT/id", {"excludes --thesis-cases"}},
        {"IdentifyFaithfulOptionWithSteady", {}, "identify measured/thesis_measured.csv --estimate fixed-ratio --out OUT/id",
         {"--estimate is an option of the faithful forward model", "--forward steady"}},
        {"IdentifyBoundsBeyondTheMassBound", {}, "identify measured/thesis_measured.csv --bounds mass=0.2:100 --out OUT/id",
         {"--bounds mass upper = 100", "(0, 10] (kg)"}},
        {"IdentifyDefaultStartOutsideBounds", {}, "identify measured/thesis_measured.csv --bounds mass=0.1:0.3 --out OUT/id",
         {"the default start of mass", "--start mass=VALUE"}},
        {"IdentifyForceDataTooManyRows", {{"d.csv", [] {
             std::string t = "angle_deg,force_N,trial\n";
             for (int i = 0; i < 1001; ++i) t += std::to_string(45 + i % 100) + ",400," + std::to_string(i) + "\n";
             return t;
         }()}}, "identify IN/d.csv --out OUT/id", {"d.csv: more than 1000 data rows", "at most 1000"}},
        {"TorqueActivationSdWithoutActivation", {}, "identify-torque measured/thesis_mvc_torque.csv --activation-sd 0.3 --out OUT/it",
         {"--activation-sd requires --activation"}},
        {"TorqueCrosstalkWithoutChannels", {}, "identify-torque measured/thesis_mvc_torque.csv --emg-crosstalk 0.3 --out OUT/it",
         {"--emg-crosstalk requires --channels"}},
        {"ProtocolVideoOptionWithoutVideo", {}, "protocol protocols/mvc_force_angle.yaml --video-width 3 --out OUT/run",
         {"--video-width requires --video"}},
        {"ProtocolRepeatedAngle", {{"p.yaml", kProtocolHead + kTrial + "conditions:\n  elbow_angles_deg: [90, 60, 90]\n"}},
         "protocol IN/p.yaml --out OUT/run", {"p.yaml:12", "(entry 3) = 90 is also entry 1", "repetitions"}},
        {"DesignRepeatedAngle", {}, "design --angles 90,90 --out OUT/d", {"--angles = 90 is listed twice"}},
        {"DesignTrialsBeyondAProtocol", {}, "design --trials 10000 --out OUT/d", {"--trials = 10000", "at most 100"}},
        {"ValidateMethodTwice", {}, "validate --methods lm,lm --seeds 0 --noise 0 --out OUT/v", {"--methods 'lm' is listed twice"}},
        {"ArmFileGravityHuge", {{"a.yaml", replaceAll(arm, "gravity: 9.80665", "gravity: 1.0e6")}},
         "trial --arm IN/a.yaml --hold 0.2 --out OUT/t.csv", {"a.yaml:", "'gravity' = 1e+06", "[0, 100]"}},
        {"StudyMergeWithoutAFolder", {{"s.yaml", kStudyHead + "methods:\n  - {method: thesis}\n"}}, "study IN/s.yaml --merge --out OUT/s",
         {"--merge: the folder does not exist", "nothing to merge"}},
        {"StudyMergeWithRestart", {{"s.yaml", kStudyHead + "methods:\n  - {method: thesis}\n"}},
         "study IN/s.yaml --merge --restart --out OUT/s", {"--merge with --restart"}},
        {"AnatomyTargetsEmpty", {{"t.yaml", "targets: []\n"}}, "model check --model twin --targets IN/t.yaml --out OUT/mc",
         {"t.yaml:1", "'targets' is empty"}},
        {"OsimTrialWithoutACoordinate", {}, "trial --model arm26 --out OUT/t.csv",
         {"--coordinate not given", "r_shoulder_elev, r_elbow_flex"}},
        {"OsimTrialAngleOutsideTheRange", {}, "trial --model arm26 --coordinate r_elbow_flex --angle 150 --out OUT/t.csv",
         {"--angle = 150", "[0, 130]"}},
        {"OsimTrialUnknownCoordinate", {}, "trial --model arm26 --coordinate elbow --out OUT/t.csv",
         {"--coordinate 'elbow'", "not a coordinate of arm26"}},
        {"ValidateNoiseEmptyItem", {}, "validate --noise 1,,2 --out OUT/v", {"--noise '1,,2'", "item 2 is empty"}},
        {"ValidateMethodsEmptyItem", {}, "validate --methods lm, --out OUT/v", {"--methods 'lm,'", "item 2 is empty"}},
        {"TrialRateNotANumber", {}, "trial --rate abc --out OUT/t.csv", {"--rate = 'abc'", "expected a number"}},
        {"MainJobWithAnOsimModel", {}, "run --model arm26 --out OUT/r",
         {"--model 'arm26'", "an OpenSim model", "`armsim trial`, `armsim model show`"}},
        {"MainJobOnTheElbowModel", {}, "run --model elbow --out OUT/r",
         {"--model elbow: the main job identifies the biceps from the thesis's measured forces", "path 0.41 m", "--model thesis"}},
        {"ModelPrimaryAnExtensor", {{"m.yaml", "name: m\narm: arm/default_male.yaml\nmuscles:\n  - name: b\n    group: extensor\n"
                                               "    parameters: " + armsim::getAssetDirectory() + "/muscles/biceps_long_head.yaml\n    path:\n"
                                               "      origin: {body: upper_arm, location: [0, 0.3, 0]}\n"
                                               "      insertion: {body: forearm, location: [0, -0.05, 0]}\n"}},
         "model show --model IN/m.yaml --out OUT/s", {"m.yaml:5: muscle 'b' is the primary muscle but of group extensor", "expected a flexor"}},
        {"CoordinateOnAnArmsimModel", {}, "trial --model thesis --coordinate r_elbow_flex --out OUT/t.csv",
         {"--coordinate", "only for OpenSim models"}},
        // ---- the fifth sweep's classes (issue 34) ----------------------------------------------
        // units a row-by-row bound cannot see: angles in radians, torques in kN m, a camera in mm
        {"TorqueDataInRadians", {{"t.csv", "flexion_deg,effort,level,torque_Nm\n2.356,1,1,21.39\n2.094,1,1,29.12\n1.571,1,1,33.5\n"}},
         "identify-torque IN/t.csv --out OUT/it", {"t.csv: column 'flexion_deg' = 2.356, 2.094, 1.571", "expected degrees", "135, 120, 90"}},
        {"TorqueDataInKiloNewtonMetres", {{"t.csv", "flexion_deg,effort,level,torque_Nm\n135,1,1,0.02139\n120,1,1,0.02912\n"}},
         "identify-torque IN/t.csv --out OUT/it", {"t.csv", "under 0.5 N m", "0.02912", "expected N m"}},
        {"TorqueDataTabSeparated", {{"t.csv", "flexion_deg\teffort\tlevel\ttorque_Nm\n135\t1\t1\t21.39\n"}},
         "identify-torque IN/t.csv --out OUT/it", {"t.csv:1", "holds a tab", "expected comma-separated columns"}},
        {"TorqueProtocolAnglesInRadians", {{"p.yaml", kTorqueHead + "conditions:\n  - {flexion_deg: 1, effort: flexion, level: 1, repetitions: 3}\n"
                                                                   "  - {flexion_deg: 1.57, effort: flexion, level: 1, repetitions: 3}\n"}},
         "protocol IN/p.yaml --out OUT/run", {"p.yaml:5", "flexion_deg", "1, 1.57", "expected degrees"}},
        {"DesignAnglesInRadians", {}, "design --angles 0.52,1.05,1.57 --out OUT/d", {"--angles = 0.52, 1.05, 1.57", "expected degrees", "29.8, 60.2, 90"}},
        {"ValidateAnglesInRadians", {}, "validate --truth elbow --angles 0.52,1.05,1.57 --subjects 2 --out OUT/v",
         {"--angles = 0.52, 1.05, 1.57", "expected degrees"}},
        {"ArmFileElbowRangeInRadians", {{"a.yaml", replaceAll(replaceAll(arm, "min_angle_deg: 40 ", "min_angle_deg: 0.698"),
                                                              "max_angle_deg: 180 ", "max_angle_deg: 3.1416")}},
         "trial --arm IN/a.yaml --hold 0.2 --out OUT/t.csv", {"a.yaml", "elbow.min_angle_deg", "0.698, 3.1416", "expected degrees"}},
        {"ArmFileOriginInMillimetres", {{"a.yaml", replaceAll(arm, "origin_distance: 0.37 ", "origin_distance: 370")}},
         "trial --arm IN/a.yaml --hold 0.2 --out OUT/t.csv", {"a.yaml", "'biceps.origin_distance' = 370", "within twice upper_arm.length"}},
        {"FibreTimeConstantInMilliseconds",
         {{"m.yaml", readFileText(armsim::getAssetDirectory() + "/muscles/biceps_long_head.yaml")},
          {"human_fibre_types.yaml", replaceAll(readFileText(armsim::getAssetDirectory() + "/muscles/human_fibre_types.yaml"),
                                                "Tf1: 0.034283", "Tf1: 34.283")}},
         "muscle steady --muscle IN/m.yaml", {"Tf1", "34.283", "(0, 1] (s)"}},
        {"RenderCameraInMillimetres", {{"t.csv", "time_s\n0\n"}, {"rs.yaml", "camera:\n  position: [1500, 500, 2000]\n  look_at: [0, 0, 0]\n"}},
         "render IN/t.csv --render-settings IN/rs.yaml --out OUT/v.mp4", {"rs.yaml", "camera.position", "outside the clip range", "(positions in m)"}},
        // channel files: an sd no lab reaches, a row twice, a column the channel does not read
        {"ChannelSdBelowAnyInstrument", {{"c.csv", channelHead + "volume,BIClong,,1,0,0,1e-4,5e-10\n"}},
         "identify-torque measured/thesis_mvc_torque.csv --channels IN/c.csv --out OUT/it", {"c.csv:2", "column 'sd' = 5e-10", ">= 1e-07"}},
        {"ChannelRowTwice", {{"c.csv", channelHead + "volume,BIClong,,1,0,0,1e-4,1e-5\nvolume,BIClong,,1,0,0,1.1e-4,1e-5\n"}},
         "identify-torque measured/thesis_mvc_torque.csv --channels IN/c.csv --out OUT/it",
         {"c.csv:3", "the same measurement as line 2", "repetition"}},
        {"ChannelAngleForAVolume", {{"c.csv", channelHead + "volume,BIClong,90,1,0,0,1e-4,1e-5\n"}},
         "identify-torque measured/thesis_mvc_torque.csv --channels IN/c.csv --out OUT/it",
         {"c.csv:2", "column 'flexion_deg' = 90", "empty for volume"}},
        {"ChannelMuscleForTheUpperArm", {{"c.csv", channelHead + "upper_arm_length,BIClong,,1,0,0,0.3,0.003\n"}},
         "identify-torque measured/thesis_mvc_torque.csv --channels IN/c.csv --out OUT/it",
         {"c.csv:2", "column 'muscle' = 'BIClong'", "empty for upper_arm_length"}},
        // options that would be ignored, limits named by option, data out of range named by file and line
        {"RenderWidthInBothPlaces", {{"t.csv", "time_s\n0\n"}, {"rs.yaml", "width: 800\n"}},
         "render IN/t.csv --render-settings IN/rs.yaml --width 640 --out OUT/v.mp4", {"--width and", "rs.yaml:1", "both set the frame's width"}},
        {"IdentifyJobsWithSteady", {}, "identify measured/thesis_measured.csv --jobs 2 --out OUT/id",
         {"--jobs is an option of the faithful forward model"}},
        {"ForceDataPathOutsideTheArm", {{"d.csv", "path_cm,force_N\n0.41,600\n0.375,458\n"}}, "identify IN/d.csv --out OUT/id",
         {"d.csv:2", "path 0.0041 m", "outside the arm's elbow range"}},
        {"ForwardSamplesNameTheOptions", {{"c.sto", sto + "time\tBIClong\n0\t0.1\n"}},
         "forward --model arm26 --controls IN/c.sto --final-time 100000 --out OUT/f",
         {"--final-time - the controls' first time = 1e+05 s x --rate 200 Hz", "expected at most 1e+07"}},
        {"ValidateSeedsBeyondTheFits", {}, "validate --seeds 1000000 --out OUT/v", {"--seeds = 1000000", "fits", "expected at most 4000000 fits"}},
        {"ValidateOutWhereNoFolderCanBeMade", {}, "validate --seeds 0 --noise 0 --out /proc/armsim_out", {"--out '/proc/armsim_out'", "/proc"}},
        // ---- the sixth sweep's classes (issue 34) ----------------------------------------------
        // efforts and co-contraction the model's muscles cannot make, estimates from a vanishing moment arm
        {"TrialExtensionOnTheThesisArm", {{"s.yaml", "type: isometric\neffort: extension\nhold: 0.3\n"}},
         "trial --settings IN/s.yaml --out OUT/t.csv", {"s.yaml:2", "'effort' = extension", "no muscle that makes it"}},
        {"TrialAntagonistOnTheThesisArm", {{"s.yaml", "type: isometric\nantagonist_activation: 1\nhold: 0.3\n"}},
         "trial --settings IN/s.yaml --out OUT/t.csv", {"s.yaml:2", "'antagonist_activation' = 1", "no antagonist"}},
        {"TorqueProtocolExtensionOnTheThesisArm", {{"p.yaml", kTorqueHead + "subject: {model: thesis}\nconditions:\n"
                                                             "  - {flexion_deg: 90, effort: extension, level: 1, repetitions: 1}\n"}},
         "protocol IN/p.yaml --out OUT/run", {"'effort' (conditions, entry 1) = extension", "no muscle that makes it"}},
        {"TrialAngleWithAVanishingMomentArm", {}, "trial --angle 179.9999 --out OUT/t.csv",
         {"--angle = 179.9999", "moment arm there is", "at least 1 mm"}},
        // steady states a typed path cannot have: bad input, not a solver failure
        {"MuscleSteadyPathTooShort", {}, "muscle steady --path 1e-9", {"--path", "no steady state at path 1e-09 m"}},
        {"MuscleSteadyPathPastPmax", {}, "muscle steady --path 3", {"--path: path length = 3 m exceeds max_path_length"}},
        {"MuscleTrialPathPastPmax", {}, "muscle trial --path 3 --out OUT/t.csv", {"--path: path length = 3 m exceeds max_path_length"}},
        {"IdentifySubjectAbsent", {{"f.csv", "path_cm,force_N,subject\n41,600,1\n37.5,458,1\n41,610,3\n"}},
         "identify IN/f.csv --subject 5 --out OUT/id", {"--subject = 5: ", "has no rows of subject 5 (its subjects: 1, 3)"}},
        {"SubmaximalLevelsAsFractions", {{"p.yaml", "name: bad\nkind: submaximal\nseed: 1\nsubject:\n  arm: arm/default_male.yaml\n"
                                                    "  muscle: muscles/biceps_long_head.yaml\n" + kTrial +
                                                    "conditions:\n  elbow_angles_deg: [90]\n  levels_pct_mvc: [0.25, 0.5, 1.0]\n"}},
         "protocol IN/p.yaml --out OUT/run", {"p.yaml:", "lacks 100", "fractions? expected percent of MVC ([25, 50, 100])"}},
        {"SubmaximalWithoutEmg", {{"p.yaml", "name: bad\nkind: submaximal\nseed: 1\nsubject:\n  arm: arm/default_male.yaml\n"
                                              "  muscle: muscles/biceps_long_head.yaml\n" + kTrial +
                                              "conditions:\n  elbow_angles_deg: [90]\n  levels_pct_mvc: [50, 100]\n"
                                              "sensors:\n  emg:\n    enabled: false\n"}},
         "protocol IN/p.yaml --out OUT/run", {"p.yaml:16: field 'sensors.emg.enabled' = false", "expected EMG enabled"}},
        {"TorqueProtocolVolumeScanOfAnAbsentMuscle",
         {{"p.yaml", kTorqueHead + "subject:\n  model: twin\nmeasurements:\n  volume_scan: [BIClong, DELT]\nconditions:\n"
                                   "  - {flexion_deg: 90, effort: flexion, repetitions: 1}\n"}},
         "protocol IN/p.yaml --out OUT/run", {"p.yaml:6: field 'measurements.volume_scan'", "has no muscle 'DELT'"}},
        {"TorqueProtocolForearmAxisOnTheThesisArm",
         {{"p.yaml", kTorqueHead + "subject:\n  model: thesis\nconditions:\n  - {flexion_deg: 90, effort: supination, repetitions: 1}\n"}},
         "protocol IN/p.yaml --out OUT/run", {"p.yaml: protocol 'bad' reads the forearm axis", "no forearm rotation"}},
        {"SeedPastUnsigned", {}, "design --seed 4294967296 --out OUT/d", {"--seed = '4294967296'", "[0, 4294967295]"}},
        {"MuscleTrialPathShorterThanTheTendon", {}, "muscle trial --model elbow --path 0.1 --out OUT/t.csv",
         {"--path: path length = 0.1 m is too short for muscle 'BIClong'", "start at -0.439"}},
        {"IdentifyForcesInKiloNewtons", {{"f.csv", "path_cm,force_N\n41,0.6\n37.5,0.458\n"}}, "identify IN/f.csv --out OUT/id",
         {"f.csv: column 'force_N' is at most 0.6 N in every row: kN? expected newtons"}},
        {"IdentifyPointTwice", {{"f.csv", "path_cm,force_N\n41,600\n37.5,458\n41,610\n"}}, "identify IN/f.csv --out OUT/id",
         {"f.csv:4: the same point as ", "f.csv:2 (path 0.41 m"}},
        {"IdentifySubjectWithoutAColumn", {}, "identify measured/thesis_measured.csv --subject 2 --out OUT/id",
         {"--subject = 2: ", "no 'subject' column: every row is subject 0"}},
        {"MuscleTrialSteadyStartPathTooShort", {}, "muscle trial --model elbow --path 0.1 --steady-start --out OUT/t.csv",
         {"--path = 0.1 m", "no steady state"}},
        {"MuscleSweepWithNoSteadyStateAnywhere", {}, "muscle sweep --from 1e-6 --to 1e-3 --step 1e-4 --out OUT/s.csv",
         {"--from 1e-06 to --to 0.001", "no steady state"}},
        // ---- the eighth sweep's remainder (issue 34, 2026-11-28) -------------------------------------
        {"OsimPathPointInMillimetres",
         {{"m.osim", replaceAll(arm26, "<location>-0.027140000000000001 -0.11441 -0.0066400000000000001</location>",
                                "<location>-27.14 -114.41 -6.64</location>")}},
         "model show --model IN/m.osim --out OUT/ms", {"m.osim:", "117.8 m from the body's origin", "is it in mm?"}},
        {"OsimWrapRadiusInMillimetres", {{"m.osim", replaceAll(arm26, "<radius>0.016</radius>", "<radius>16</radius>")}},
         "model show --model IN/m.osim --out OUT/ms", {"m.osim:", "radius 16: expected at most 0.5 m"}},
        {"OsimForceInKiloNewtons",
         {{"m.osim", replaceAll(arm26, "<max_isometric_force>798.51999999999998</max_isometric_force>",
                                "<max_isometric_force>0.79852</max_isometric_force>")}},
         "model show --model IN/m.osim --out OUT/ms", {"m.osim:", "max_isometric_force 0.79852", "is it in kN?"}},
        {"ChannelAnglesInRadians", {{"c.csv", "channel,muscle,flexion_deg,level,value,sd\nemg,BIClong,1.5708,1,0.9,0.1\n"
                                              "emg,BIClong,2.0944,1,0.8,0.1\n"}},
         "identify-torque measured/thesis_mvc_torque.csv --channels IN/c.csv --out OUT/it",
         {"c.csv:2: column 'flexion_deg' = 1.5708, 2.0944: expected degrees", "(in degrees: 90, 120)"}},
        {"ChannelSdAboveItsValue", {{"c.csv", "channel,muscle,flexion_deg,level,value,sd\nfascicle_length,BIClong,90,0,0.1,5\n"}},
         "identify-torque measured/thesis_mvc_torque.csv --channels IN/c.csv --out OUT/it",
         {"c.csv:2: column 'sd' = 5: expected <= 0.1 (the value itself)", "other units"}},
        {"ChannelEmgOfADeepMuscle", {{"c.csv", "channel,muscle,flexion_deg,level,value,sd\nemg,BRA,90,1,0.9,0.1\n"}},
         "identify-torque measured/thesis_mvc_torque.csv --channels IN/c.csv --out OUT/it",
         {"c.csv:2: emg of muscle 'BRA'", "has surface EMG of BIClong, BICshort, BRD, TRIlong, TRIlat only"}},
        {"ChannelRowWithoutATorqueTrial", {{"c.csv", "channel,muscle,flexion_deg,level,value,sd\nemg,BIClong,75,1,0.9,0.1\n"}},
         "identify-torque measured/thesis_mvc_torque.csv --channels IN/c.csv --out OUT/it",
         {"c.csv:2: emg at 75 deg, flexion effort, level 1: the torque data has no such trial", "are at 30, "}},
        {"ChannelRowsPastTheCap", {{"c.csv", [] {
              std::string t = "channel,muscle,flexion_deg,level,value,sd\n";
              for (int k = 0; k <= 10000; ++k) t += "emg,BIClong,90,1,0.9,0.1," + std::to_string(k) + "\n";
              return replaceAll(t, "sd\n", "sd,repetition\n");
          }()}},
         "identify-torque measured/thesis_mvc_torque.csv --channels IN/c.csv --out OUT/it",
         {"c.csv:10002: more than 10000 measurements"}},
        {"IdentifyTorqueHillTypePrior", {}, "identify-torque measured/thesis_mvc_torque.csv --population subjects/mismatch/hill_muscles.yaml --out OUT/it",
         {"hill_muscles", "muscle_model thelen2003", "expected virtual_muscle"}},
        {"EmgElectrodeNoiseInVolts", {{"p.yaml", "name: bad\nkind: mvc\nseed: 1\nsubject:\n  arm: arm/default_male.yaml\n"
                                                  "  muscle: muscles/biceps_long_head.yaml\n" + kTrial + kAngles +
                                                  "sensors:\n  emg:\n    electrode_noise_rms: 5\n"}},
         "protocol IN/p.yaml --out OUT/run", {"p.yaml:", "electrode_noise_rms", "[0, 0.01] (V)"}},
        {"ForwardStatesInDegreesHoldRadians", {{"c.sto", sto + "time\tBIClong\n0\t0.1\n"},
                                              {"s.sto", replaceAll(sto, "inDegrees=no", "inDegrees=yes") + "time\tr_elbow_flex\n0\t1.309\n"}},
         "forward --model arm26 --controls IN/c.sto --initial-states IN/s.sto --final-time 0.1 --out OUT/f",
         {"s.sto: header 'inDegrees=yes', but its coordinate values = 1.309", "expected inDegrees=no for radians"}},
        {"ForwardStatesFibreLengthInMillimetres", {{"c.sto", sto + "time\tBIClong\n0\t0.1\n"},
                                                  {"s.sto", replaceAll(sto, "nColumns=2", "nColumns=3") +
                                                                "time\tBIClong.activation\tBIClong.fiber_length\n0\t0.1\t115.7\n"}},
         "forward --model arm26 --controls IN/c.sto --initial-states IN/s.sto --final-time 0.1 --out OUT/f",
         {"s.sto: column 'BIClong.fiber_length' at t = 0 s: 115.7: expected a fibre length in (0, ", "OpenSim lengths are in metres"}},
        {"CalibrateMomentArmOfTheWrongSign", {{"t.yaml", "targets:\n  - {kind: mvc, direction: flexion, flexion_deg: 90, lower: 50, "
                                                          "upper: 70, tolerance: 5, source: x}\n"
                                                          "  - {kind: moment_arm, muscle: BIC, flexion_deg: 90, lower: -49.3, "
                                                          "upper: -41.6, tolerance: 3, source: x}\n"}},
         "model calibrate --model twin --targets IN/t.yaml", {"t.yaml:3: moment_arm of BIC at 90 deg: [-49.3, -41.6] mm",
                                                              "BIClong of model 'twin' is a flexor: expected > 0"}},
        {"StudySameTruthTwice", {{"s.yaml", "kind: study\nname: bad\nsubjects: 1\nprior: default\ntruths:\n"
                                            "  - {population: default, label: a}\n  - {population: default, label: b}\n"
                                            "protocols: [thesis]\nnoise_levels: [0.02]\nmethods:\n  - {method: thesis}\n"}},
         "study IN/s.yaml --out OUT/s", {"s.yaml:7: truth population 'default' is also the truth at", "s.yaml:6"}},
        {"RenderMuscleParameterOnATable", {{"t.csv", "time_s\n0\n"}}, "render IN/t.csv --still-at 0.4 --still OUT/s.png --mass 0.5",
         {"--mass: the trial table", "do not change the video"}},
        {"TransducerNoiseInMilliNewtons", {{"p.yaml", "name: bad\nkind: mvc\nseed: 1\nsubject:\n  arm: arm/default_male.yaml\n"
                                                       "  muscle: muscles/biceps_long_head.yaml\n" + kTrial + kAngles +
                                                       "sensors:\n  transducer:\n    noise_rms: 1000\n"}},
         "protocol IN/p.yaml --out OUT/run", {"p.yaml:", "noise_rms", "1000", "[0, 50] (N)"}},
        {"TargetsToleranceThatPassesAnyModel", {{"t.yaml", "targets:\n  - {kind: moment_arm, muscle: BIC, flexion_deg: 90, lower: 41.6, "
                                                            "upper: 49.3, tolerance: 1000, source: x}\n"}},
         "model check --model twin --targets IN/t.yaml --out OUT/mc", {"t.yaml:2", "tolerance", "1000", "[0, 100] (mm)"}},
        // CLI11 read 0x5A as 90 and an integer's 010 as octal 8; every file reader refuses both.
        {"TrialAngleInHexadecimal", {}, "trial --angle 0x5A --hold 0.2 --out OUT/t.csv",
         {"--angle = '0x5A': expected a decimal number"}},
        {"TrialUnitsWithALeadingZero", {}, "trial --slow-units 010 --hold 0.2 --out OUT/t.csv",
         {"--slow-units = '010': expected a decimal integer without leading zeros"}},
        {"IdentifyForceInHexadecimal", {{"f.csv", "path_cm,force_N\n41,0x258\n37.5,458\n38,470\n"}}, "identify IN/f.csv --out OUT/id",
         {"f.csv:2: column 'force_N' = '0x258': expected a number"}},
        {"TorqueDataRepetitionPastItsBound", {{"t.csv", "flexion_deg,effort,level,torque_Nm,repetition\n90,1,1,35,2147483647\n"}},
         "identify-torque IN/t.csv --out OUT/it", {"t.csv:2", "column 'repetition' = 2147483647", "an integer in [0, 1000000]"}},
        {"IdentifySeedWithOneStart", {}, "identify measured/thesis_measured.csv --seed 7 --out OUT/id",
         {"--seed 7 with --multistart 1", "it would be ignored", "--multistart N"}},
        {"StudyMergeWithThreads", {{"s.yaml", kStudyHead + "methods:\n  - {method: thesis}\n"}}, "study IN/s.yaml --merge --threads 2 --out OUT/s",
         {"--threads 2 with --merge", "the threads would be ignored"}},
        // inputs that ask nothing of the work
        {"ActivationTraceStartingLate", {{"u.csv", "time_s,activation\n1,1\n2,1\n"}},
         "muscle trial --activation-trace IN/u.csv --duration 0.5 --out OUT/t.csv", {"u.csv:2", "'time_s' = 1", "start at 0 s"}},
        {"IdentifyToleranceAboveEveryForce", {}, "identify measured/thesis_measured.csv --method ilc-secant --tolerance 1e6 --out OUT/id",
         {"--tolerance = 1e+06 N", "largest measured force, 600 N"}},
        {"TorqueDataRowTwice", {{"t.csv", "flexion_deg,effort,level,torque_Nm\n135,1,1,21.39\n135,1,1,21.39\n90,1,1,35.37\n"}},
         "identify-torque IN/t.csv --out OUT/it", {"t.csv:3", "the same row as line 2", "repetition column"}},
        {"ValidatePriorWithoutSpread", {{"p.yaml", "name: zero\nmodel: twin\nstrength:\n  subject_sd: 0\n  muscle_sd: 0\n"}},
         "validate --truth elbow --prior IN/p.yaml --subjects 2 --noise 0 --out OUT/v", {"prior population 'zero'", "both 0"}},
        {"StudyWhoseEveryTaskIsSkipped", {{"s.yaml", kStudyHead + "methods:\n  - {method: channels}\n"}},
         "study IN/s.yaml --out OUT/s", {"s.yaml:", "lists only 'channels'", "every task"}},
        {"ForceLengthStepLongerThanTheRange", {{"p.yaml", "kind: force_length\nname: fl\nseed: 1\nrepetitions: 1\n"
                                                          "trial: {rest: 0.2, hold: 0.3, averaging_window: 0.2}\n"
                                                          "conditions:\n  elbow_angle_range_deg: {from: 40, to: 50, step: 500}\n"}},
         "protocol IN/p.yaml --out OUT/run", {"p.yaml:7", "step' = 500 is longer than the range 40 to 50"}},
        // model and target files: roles, wraps and units
        {"ModelSynergistAnExtensor", {{"m.yaml", replaceAll(elbow, "synergists: [BRA, BRD]", "synergists: [BRA, TRIlong]")}},
         "model show --model IN/m.yaml --out OUT/ms", {"m.yaml:68", "'TRIlong', of group extensor"}},
        {"ModelWrapSideZero", {{"m.yaml", replaceAll(elbow, "side: [0.44621, 0.86849, 0.21591]", "side: [0, 0, 0]")}},
         "model show --model IN/m.yaml --out OUT/ms", {"m.yaml:85", "side", "zero vector"}},
        {"TargetsMomentArmInMetres", {{"t.yaml", "targets:\n  - {kind: moment_arm, muscle: BIC, flexion_deg: 90, lower: 0.0416, "
                                                  "upper: 0.0493, tolerance: 3, source: x}\n"}},
         "model check --model twin --targets IN/t.yaml --out OUT/mc", {"t.yaml:2", "within 1 mm", "expected mm"}},
        {"TargetsMvcBeyondAnyElbow", {{"t.yaml", "targets:\n  - {kind: mvc, direction: flexion, flexion_deg: 90, lower: 500, "
                                                  "upper: 600, tolerance: 5, source: x}\n"}},
         "model check --model twin --targets IN/t.yaml --out OUT/mc", {"t.yaml:2", "500", "[0, 300] (N m)"}},
        {"TargetsNoneScorable", {{"t.yaml", "targets:\n  - {kind: volume, muscle: DELT, lower: 100, upper: 200, source: x}\n"}},
         "model check --model twin --targets IN/t.yaml --out OUT/mc", {"--targets", "none of the targets"}},
        {"RenderFieldOfViewTiny", {{"t.csv", "time_s\n0\n"}, {"rs.yaml", "camera:\n  position: [0, 0, 2]\n  vertical_fov: 1e-9\n"}},
         "render IN/t.csv --render-settings IN/rs.yaml --out OUT/v.mp4", {"rs.yaml:3", "vertical_fov", "1e-09", "[0.01"}},
        {"OsimRangeInDegrees", {{"m.osim", replaceAll(arm26, "<range>0 2.2689280300000001</range>", "<range>0 130</range>")}},
         "model show --model IN/m.osim --out OUT/ms", {"m.osim:", "past one turn", "expected radians", "7448 deg"}},
        {"OsimActivationTimeInMilliseconds", {{"m.osim", replaceAll(arm26, "<activation_time_constant>0.01</activation_time_constant>",
                                                                    "<activation_time_constant>10</activation_time_constant>")}},
         "model show --model IN/m.osim --out OUT/ms", {"activation_time_constant", "10", "(0, 1] (s)"}},
        {"MainJobBadModelWritesNothing", {{"m.yaml", "name: m\n"}}, "run --model IN/m.yaml --out OUT/r", {"m.yaml:1", "'arm'"}},
    };
}

class BadInputCatalogue : public ::testing::TestWithParam<BadInput> {};

TEST_P(BadInputCatalogue, ExitsTwoNamesTheInputAndWritesNothing) {
    const BadInput& c = GetParam();
    const fs::path d = armsim::testing::makeFreshDir("bad_input", c.name);
    fs::create_directories(d / "in");
    for (const auto& [file, text] : c.files) std::ofstream(d / "in" / file, std::ios::binary) << text;
    const std::string args = replaceAll(replaceAll(c.args, "IN", (d / "in").string()), "OUT", (d / "out").string());
    const CommandResult r = runArmsim(args);
    EXPECT_EQ(r.exitCode, 2) << args << "\n" << r.output;
    for (const std::string& fragment : c.expected)
        EXPECT_NE(r.output.find(fragment), std::string::npos) << "missing '" << fragment << "' for: " << args << "\n" << r.output;
    EXPECT_FALSE(fs::exists(d / "out")) << "output left behind by: " << args;
    EXPECT_EQ(r.output.find("internal error"), std::string::npos) << r.output;
    fs::remove_all(d);
}

INSTANTIATE_TEST_SUITE_P(Cases, BadInputCatalogue, ::testing::ValuesIn(makeCatalogue()),
                         [](const ::testing::TestParamInfo<BadInput>& info) { return info.param.name; });

TEST(BadInputCatalogue, HasAtLeastOneHundredFiftyCasesOverEveryCommand) {
    const std::vector<BadInput> all = makeCatalogue();
    EXPECT_GE(all.size(), 150u);   // issue 34
    for (const char* command : {"muscle steady", "muscle trial", "muscle sweep", "trial", "protocol", "identify ",
                                "identify-torque", "validate", "design", "study", "render", "model show", "model check",
                                "forward", "run "}) {
        bool found = false;
        for (const BadInput& c : all) found = found || c.args.rfind(command, 0) == 0;
        EXPECT_TRUE(found) << command;
    }
}

}  // namespace

namespace {

// Issue 34: one bound per quantity (basics/bound.h) holds on the command line and in the files alike. Each
// entry of the table is tried just outside its bound through an option and through a file; both must
// refuse with the table's own description of the bound. (tests/python/test_armsim.py does the same for
// the Python module.)
TEST(BoundsTable, EveryEntryPointRefusesOutsideTheSameBound) {
    const std::string assets = armsim::getAssetDirectory();
    const std::string arm = armsim::readFileText(assets + "/arm/default_male.yaml");
    const std::string muscle = replaceAll(armsim::readFileText(assets + "/muscles/biceps_long_head.yaml"),
                                          "fibre_types: ", "fibre_types: " + assets + "/muscles/");
    struct Entry {
        const char* name;
        armsim::Bound bound;
        std::string option;                       ///< a command with the option just outside the bound
        std::pair<std::string, std::string> file; ///< (file name, text) with the field just outside
        std::string fileCommand;                  ///< the command reading it (IN: the file's folder)
    };
    const std::vector<Entry> table = {
        {"hand load", armsim::bounds::kHandLoad, "trial --type free --load 60 --out OUT/f.csv",
         {"a.yaml", replaceAll(arm, "hand_load: 0", "hand_load: 60")}, "trial --arm IN/a.yaml --hold 0.2 --out OUT/t.csv"},
        {"muscle mass", armsim::bounds::kMuscleMass, "muscle steady --mass 11",
         {"m.yaml", replaceAll(muscle, "mass: 0.33599", "mass: 11")}, "muscle steady --muscle IN/m.yaml"},
        {"tendon length", armsim::bounds::kTendonLength, "muscle steady --tendon-length 3",
         {"m.yaml", replaceAll(muscle, "optimal_tendon_length: 0.245", "optimal_tendon_length: 3")},
         "muscle steady --muscle IN/m.yaml"},
        {"path length", armsim::bounds::kPathLength, "muscle steady --max-path 4",
         {"m.yaml", replaceAll(muscle, "max_path_length: 0.43", "max_path_length: 4")}, "muscle steady --muscle IN/m.yaml"},
        {"motor units", armsim::bounds::kMotorUnits, "muscle steady --slow-units 101",
         {"m.yaml", replaceAll(muscle, "slow: 3", "slow: 101")}, "muscle steady --muscle IN/m.yaml"},
        {"trial accuracy", armsim::bounds::kTrialAccuracy, "trial --hold 0.2 --accuracy 1e-30 --out OUT/t.csv",
         {"s.yaml", "hold: 0.2\naccuracy: 1e-30\n"}, "trial --settings IN/s.yaml --out OUT/t.csv"},
    };
    for (const Entry& e : table) {
        const fs::path d = armsim::testing::makeFreshDir("bounds_table", replaceAll(e.name, " ", "_"));
        fs::create_directories(d / "in");
        ASSERT_TRUE(e.file.second != arm && e.file.second != muscle) << e.name << ": the field to change was not found";
        std::ofstream(d / "in" / e.file.first) << e.file.second;
        for (const std::string& args : {e.option, e.fileCommand}) {
            const CommandResult r = runArmsim(replaceAll(replaceAll(args, "IN", (d / "in").string()), "OUT", (d / "out").string()));
            EXPECT_EQ(r.exitCode, 2) << e.name << ": " << args << "\n" << r.output;
            EXPECT_NE(r.output.find(e.bound.describe()), std::string::npos)
                << e.name << ": " << args << " should name the bound '" << e.bound.describe() << "'\n" << r.output;
        }
        fs::remove_all(d);
    }
}

}  // namespace

// Parameter files: the shipped ones load; bad ones fail with a message naming file, field and value.
#include "basics/errors.h"
#include "muscles/muscle_file.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

using namespace armsim;
namespace fs = std::filesystem;

namespace {

std::string readText(const std::string& path) {
    std::ifstream in(path);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
}

/// A copy of the long-head file (and its fibre-type file) in a fresh directory, with `from` replaced
/// by `to` in the muscle file; returns the muscle file's path.
std::string writeVariant(const std::string& from, const std::string& to, const std::string& typesFrom = "",
                         const std::string& typesTo = "") {
    static int counter = 0;
    const fs::path dir = fs::temp_directory_path() / ("armsim_muscle_file_" + std::to_string(::getpid()) + "_" +
                                                      std::to_string(counter++));
    fs::create_directories(dir);
    const std::string assets = std::string(ARMSIM_ASSET_DIR) + "/muscles/";
    std::string muscle = readText(assets + "biceps_long_head.yaml");
    std::string types = readText(assets + "human_fibre_types.yaml");
    if (!from.empty()) {
        const auto at = muscle.find(from);
        EXPECT_NE(at, std::string::npos) << from;
        muscle.replace(at, from.size(), to);
    }
    if (!typesFrom.empty()) {
        const auto at = types.find(typesFrom);
        EXPECT_NE(at, std::string::npos) << typesFrom;
        types.replace(at, typesFrom.size(), typesTo);
    }
    std::ofstream(dir / "human_fibre_types.yaml") << types;
    std::ofstream(dir / "biceps_long_head.yaml") << muscle;
    return (dir / "biceps_long_head.yaml").string();
}

/// The InputError message of loading path (fails the test if it loads).
std::string loadError(const std::string& path) {
    try {
        loadMuscleParameters(path);
    } catch (const InputError& e) {
        return e.what();
    }
    ADD_FAILURE() << "loaded without error: " << path;
    return "";
}

void expectMentions(const std::string& message, std::initializer_list<const char*> parts) {
    for (const char* p : parts) EXPECT_NE(message.find(p), std::string::npos) << "'" << p << "' not in: " << message;
}

}  // namespace

TEST(MuscleFile, ShippedFilesLoad) {
    const auto lh = loadMuscleParameters(std::string(ARMSIM_ASSET_DIR) + "/muscles/biceps_long_head.yaml");
    EXPECT_EQ(lh.name, "biceps long head");
    EXPECT_DOUBLE_EQ(lh.mass, 0.33599);
    EXPECT_DOUBLE_EQ(lh.optimalFascicleLength, 0.16);
    EXPECT_DOUBLE_EQ(lh.optimalTendonLength, 0.245);
    EXPECT_DOUBLE_EQ(lh.slowFraction, 0.3);
    EXPECT_DOUBLE_EQ(lh.fast.aS1, 1.76);
    EXPECT_FALSE(lh.slow.hasSag());
    EXPECT_TRUE(lh.slow.hasYield());
    const auto sh = loadMuscleParameters(std::string(ARMSIM_ASSET_DIR) + "/muscles/biceps_short_head.yaml");
    EXPECT_DOUBLE_EQ(sh.mass, 0.31103);
    EXPECT_DOUBLE_EQ(sh.slowFraction, 0.5);
}

TEST(MuscleFile, NegativeMassNamesFileLineFieldAndBound) {
    const std::string path = writeVariant("mass: 0.33599", "mass: -0.3");
    const std::string msg = loadError(path);
    expectMentions(msg, {"biceps_long_head.yaml:6:", "'mass'", "-0.3", "in (0, 10] (kg)"});
}

TEST(MuscleFile, ZeroLengthsAreRejected) {
    expectMentions(loadError(writeVariant("optimal_fascicle_length: 0.16", "optimal_fascicle_length: 0")),
                   {"optimal_fascicle_length", "= 0", "[0.001, 1] (m, a muscle fascicle)"});
    expectMentions(loadError(writeVariant("optimal_tendon_length: 0.245", "optimal_tendon_length: 0")),
                   {"optimal_tendon_length", "= 0"});
}

TEST(MuscleFile, FibreFractionsMustSumToOne) {
    expectMentions(loadError(writeVariant("fast: 0.7", "fast: 0.6")), {"fibre_fractions", "0.9", "expected 1"});
}

TEST(MuscleFile, UnknownKeysAreErrorsWithTheirLine) {
    expectMentions(loadError(writeVariant("mass: 0.33599", "mass: 0.33599\nmas: 0.3")),
                   {"biceps_long_head.yaml:7:", "unknown field 'mas'"});
    expectMentions(loadError(writeVariant("", "", "  Tf1: 0.0206", "  Tf1: 0.0206\n  Tf5: 1")),
                   {"human_fibre_types.yaml", "unknown field 'fast.Tf5'"});
}

TEST(MuscleFile, FibreTypeValueOutOfBoundNamesItsFile) {
    expectMentions(loadError(writeVariant("", "", "  Tf3: 0.047033", "  Tf3: -1")),
                   {"human_fibre_types.yaml:", "slow.Tf3", "-1", "(0, 1] (s)"});
}

TEST(MuscleFile, PmaxTooShortForTheTendon) {
    expectMentions(loadError(writeVariant("max_path_length: 0.43", "max_path_length: 0.2")),
                   {"max_path_length", "0.2", "LTstar"});
}

TEST(MuscleFile, BadYamlAndMissingFile) {
    expectMentions(loadError(writeVariant("mass: 0.33599", "mass: [0.3")), {"biceps_long_head.yaml", "invalid YAML"});
    expectMentions(loadError("/nonexistent/muscle.yaml"), {"/nonexistent/muscle.yaml", "cannot open"});
}

TEST(MuscleFile, PathLongerThanPmaxOrNotPositiveIsRejected) {
    const VirtualMuscle m(loadMuscleParameters(std::string(ARMSIM_ASSET_DIR) + "/muscles/biceps_long_head.yaml"));
    try {
        m.checkPathLength(0.45);
        ADD_FAILURE() << "no error";
    } catch (const InputError& e) {
        expectMentions(e.what(), {"0.45", "P_max", "0.43"});
    }
    EXPECT_THROW(m.checkPathLength(0.0), InputError);
    EXPECT_THROW(m.checkPathLength(-0.1), InputError);
    EXPECT_THROW(m.calcSteadyState(0.44, 1.0), InputError);
    EXPECT_THROW(m.calcSteadyState(0.40, 1.5), InputError);
}

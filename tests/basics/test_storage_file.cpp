// Result files: OpenSim storage header and read-back, CSV read-back, malformed storage files.
#include "basics/errors.h"
#include "basics/storage_file.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

using namespace armsim;
namespace fs = std::filesystem;

namespace {

Table sampleTable() {
    Table t({"time_s", "elbow_angle_deg", "muscle_force_N", "emg_V"});
    std::mt19937_64 rng(3);
    std::uniform_real_distribution<double> u(-1, 1);
    for (int i = 0; i < 50; ++i) t.appendRow({i / 1000.0, 90 + u(rng), 455.7 * (1 + u(rng)), 1e-3 * u(rng)});
    return t;
}

fs::path tempFile(const std::string& name) {
    return fs::temp_directory_path() / ("armsim_df_" + std::to_string(::getpid()) + "_" + name);
}

void writeText(const fs::path& p, const std::string& text) { std::ofstream(p, std::ios::binary) << text; }

}  // namespace

TEST(Storage, HeaderFollowsTheOpenSimFormat) {
    const Table t = sampleTable();
    const std::string text = formatStorage(t, "trial_a090", true);
    std::istringstream in(text);
    std::string line;
    const std::vector<std::string> expected = {"trial_a090", "version=1", "nRows=50", "nColumns=4", "inDegrees=yes",
                                               "endheader", "time\telbow_angle_deg\tmuscle_force_N\temg_V"};
    for (const std::string& e : expected) {
        ASSERT_TRUE(std::getline(in, line));
        EXPECT_EQ(line, e);
    }
    ASSERT_TRUE(std::getline(in, line));
    EXPECT_EQ(std::count(line.begin(), line.end(), '\t'), 3);
    EXPECT_EQ(formatStorage(t, "x", false).find("inDegrees=no"), std::string("x\nversion=1\nnRows=50\nnColumns=4\n").size());
}

TEST(Storage, WrittenFileReadsBackWithTheSameNumbers) {
    const Table t = sampleTable();
    const fs::path exact = tempFile("exact.sto"), rounded = tempFile("rounded.sto");
    writeText(exact, formatStorage(t, "s", true, 17));
    writeText(rounded, formatStorage(t, "s", true));
    StorageHeader h;
    const Table a = readStorage(exact.string(), &h), b = readStorage(rounded.string());
    EXPECT_EQ(h.name, "s");
    EXPECT_EQ(h.version, 1);
    EXPECT_TRUE(h.inDegrees);
    ASSERT_EQ(a.getNumRows(), t.getNumRows());
    ASSERT_EQ(a.getNumColumns(), t.getNumColumns());
    EXPECT_EQ(a.getColumnNames()[0], "time");
    constexpr double kTenDigitRelTol = 5e-10;  // 10 significant digits
    for (int i = 0; i < t.getNumRows(); ++i)
        for (int c = 0; c < t.getNumColumns(); ++c) {
            EXPECT_EQ(a.getRow(i)[c], t.getRow(i)[c]);  // 17 digits round-trip exactly
            EXPECT_NEAR(b.getRow(i)[c], t.getRow(i)[c], kTenDigitRelTol * std::abs(t.getRow(i)[c]));
        }
    fs::remove(exact);
    fs::remove(rounded);
}

TEST(Csv, FormattedCsvReadsBackIncludingNaN) {
    Table t = sampleTable();
    t.appendRow({1, NAN, 2, 3});
    const fs::path p = tempFile("t.csv");
    writeText(p, t.toCsv(17));
    const Table r = Table::readCsv(p.string());
    ASSERT_EQ(r.getNumRows(), t.getNumRows());
    EXPECT_EQ(r.getColumnNames(), t.getColumnNames());
    for (int i = 0; i < t.getNumRows(); ++i)
        for (int c = 0; c < t.getNumColumns(); ++c)
            if (std::isnan(t.getRow(i)[c])) EXPECT_TRUE(std::isnan(r.getRow(i)[c]));
            else EXPECT_EQ(r.getRow(i)[c], t.getRow(i)[c]);
    fs::remove(p);
}

TEST(Storage, MalformedFilesNameFileAndLine) {
    const fs::path p = tempFile("bad.sto");
    auto expectError = [&](const std::string& text, const std::string& fragment) {
        writeText(p, text);
        try {
            readStorage(p.string());
            ADD_FAILURE() << "no error for: " << text;
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
        }
    };
    expectError("n\nversion=1\nnRows=2\nnColumns=2\ninDegrees=no\ntime\ta\n", "no 'endheader'");
    expectError("n\nversion=1\nnRows=3\nnColumns=2\ninDegrees=no\nendheader\ntime\ta\n0\t1\n1\t2\n", "nRows=3");
    expectError("n\nversion=1\nnRows=1\nnColumns=2\ninDegrees=no\nendheader\ntime\ta\n0\tx\n", "bad.sto:8");
    expectError("n\nversion=1\nnRows=1\nnColumns=3\ninDegrees=no\nendheader\ntime\ta\n0\t1\n", "nColumns=3");
    expectError("n\nnRows=1\nnColumns=2\nendheader\nt\ta\n0\t1\n", "expected 'time'");
    fs::remove(p);
}

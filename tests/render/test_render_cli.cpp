// armsim render and armsim trial --video end to end (no X display): exit codes, the written video
// and still, and named errors that leave no file behind.
#include "basics/table.h"
#include "tests/render/render_test_util.h"
#include "tests/support/run_armsim.h"

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include <filesystem>
#include <opencv2/videoio.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <vector>

#include <memory>
#include <string>

namespace {

using armsim::test::ScratchDir;
namespace fs = std::filesystem;

constexpr double kFpsTolerance = 1e-6;   // container frame rate vs requested (1/s)
constexpr double kRest = 0.2, kHold = 0.3;  // recorded isometric trial (s)

using armsim::testing::CommandResult;
using armsim::testing::runArmsim;

struct VideoInfo {
    int frames = 0;
    double fps = 0;
    cv::Size size;
};

VideoInfo probe(const std::string& path) {
    cv::VideoCapture cap(path, cv::CAP_FFMPEG);
    VideoInfo v;
    if (!cap.isOpened()) return v;
    v.fps = cap.get(cv::CAP_PROP_FPS);
    v.size = cv::Size(int(cap.get(cv::CAP_PROP_FRAME_WIDTH)), int(cap.get(cv::CAP_PROP_FRAME_HEIGHT)));
    for (cv::Mat f; cap.read(f);) ++v.frames;
    return v;
}

int expectedFrames(double duration, double fps) { return int(std::floor(duration * fps + 1e-9)) + 1; }

// Records a short isometric trial into dir/t.csv (and its default video into dir/t.mp4).
CommandResult recordTrial(const ScratchDir& dir) {
    return runArmsim("trial --angle 90 --rest " + std::to_string(kRest) + " --hold " + std::to_string(kHold) +
                     " --rate 100 --out " + dir.file("t.csv") + " --video " + dir.file("t.mp4"));
}

}  // namespace

TEST(RenderCli, TrialVideoAndRenderOfTheRecordedTable) {
    ScratchDir dir;
    const CommandResult trial = recordTrial(dir);
    ASSERT_EQ(trial.exitCode, 0) << trial.output;
    const VideoInfo tv = probe(dir.file("t.mp4"));
    EXPECT_EQ(tv.frames, expectedFrames(kRest + kHold, 30));   // defaults: 30 fps, 1280x720
    EXPECT_EQ(tv.size, cv::Size(1280, 720));

    const CommandResult r = runArmsim("render " + dir.file("t.csv") + " --out " + dir.file("r.mp4") +
                                      " --fps 20 --width 320 --height 240 --still-at 0.4 --still " + dir.file("s.png"));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    const VideoInfo rv = probe(dir.file("r.mp4"));
    EXPECT_EQ(rv.frames, expectedFrames(kRest + kHold, 20));
    EXPECT_NEAR(rv.fps, 20, kFpsTolerance);
    EXPECT_EQ(rv.size, cv::Size(320, 240));
    const cv::Mat still = cv::imread(dir.file("s.png"));
    EXPECT_EQ(still.size(), cv::Size(320, 240));
}

TEST(RenderCli, MissingStateColumnIsANamedErrorAndWritesNothing) {
    ScratchDir dir;
    ASSERT_EQ(recordTrial(dir).exitCode, 0);
    const armsim::Table t = armsim::Table::readCsv(dir.file("t.csv"));
    std::vector<std::string> names;
    for (const std::string& n : t.getColumnNames())
        if (n != "state_feff_3") names.push_back(n);
    armsim::Table cut(names);
    for (int i = 0; i < t.getNumRows(); ++i) {
        std::vector<double> row;
        for (const std::string& n : names) row.push_back(t.get(i, n));
        cut.appendRow(row);
    }
    cut.writeCsv(dir.file("cut.csv"));
    const CommandResult r = runArmsim("render " + dir.file("cut.csv") + " --out " + dir.file("cut.mp4") +
                                      " --still-at 0.1 --still " + dir.file("cut.png"));
    EXPECT_EQ(r.exitCode, 2) << r.output;
    EXPECT_NE(r.output.find("'state_feff_3'"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("cut.csv"), std::string::npos) << r.output;
    std::vector<std::string> files = dir.list();
    std::sort(files.begin(), files.end());
    EXPECT_EQ(files, (std::vector<std::string>{"cut.csv", "t.csv", "t.mp4"}));
}

TEST(RenderCli, BadOptionsAreNamedErrors) {
    ScratchDir dir;
    ASSERT_EQ(recordTrial(dir).exitCode, 0);
    const std::string table = dir.file("t.csv");
    struct Case {
        std::string args, expect;
    };
    const Case cases[] = {
        {"--out " + dir.file("a.mp4") + " --codec vp9", "codec"},
        {"--out " + dir.file("a.mp4") + " --width 0", "width"},
        {"--out " + dir.file("a.mp4") + " --width 321", "even"},
        {"--out " + dir.file("t.csv") + "/a.mp4", "is a file"},  // a missing folder is made; a file in the way is not
        {"--still-at 9 --still " + dir.file("a.png"), "--still-at"},
        {"", "nothing to write"},
        // Options that would be ignored, or half a still, named (issue 34).
        {"--still " + dir.file("a.png"), "--still '" + dir.file("a.png") + "' needs --still-at"},
        {"--still-at 0.1", "--still-at 0.1 needs --still FILE.png"},
        {"--out '' --still-at 0.1 --still " + dir.file("a.png"), "--out: is empty"},
        {"--fps 60 --still-at 0.1 --still " + dir.file("a.png"), "--fps is a video's option: without --out VIDEO"},
        {"--speed 2 --still-at 0.1 --still " + dir.file("a.png"), "--speed is a video's option"},
        {"--out " + dir.file("a.mp4") + " --arrow none --arrow-scale 0.001", "--arrow-scale with --arrow none"},
        // The table is an isometric trial, which armsim trial refuses a --load for.
        {"--out " + dir.file("a.mp4") + " --load 2", "--load = 2 kg: " + table + " is an isometric trial"},
    };
    for (const Case& c : cases) {
        const CommandResult r = runArmsim("render " + table + " " + c.args);
        EXPECT_EQ(r.exitCode, 2) << c.args << ": " << r.output;
        EXPECT_NE(r.output.find(c.expect), std::string::npos) << c.args << ": " << r.output;
    }
    EXPECT_EQ(dir.list().size(), 2u);   // t.csv and t.mp4 only
}

// A damaged trial table is refused naming its file's line, the column and the value (issue 34: NaN
// states, an angle of 1e308 deg, an activation of 7, a flag of 7, a force of -1e6 N were rendered), and
// a table shorter than one frame makes no one-frame video.
TEST(RenderCli, DamagedTablesAreRefusedNamingLineAndColumn) {
    ScratchDir dir;
    ASSERT_EQ(recordTrial(dir).exitCode, 0);
    std::vector<std::string> lines;
    {
        std::ifstream in(dir.file("t.csv"));
        for (std::string line; std::getline(in, line);) lines.push_back(line);
    }
    std::vector<std::string> header;
    {
        std::stringstream h(lines[0]);
        for (std::string cell; std::getline(h, cell, ',');) header.push_back(cell);
    }
    const auto withCell = [&](const std::string& column, const std::string& value) {   // line 5 of the file
        const std::size_t at = std::find(header.begin(), header.end(), column) - header.begin();
        EXPECT_LT(at, header.size()) << column;
        std::stringstream row(lines[4]);
        std::vector<std::string> cells;
        for (std::string cell; std::getline(row, cell, ',');) cells.push_back(cell);
        cells.at(at) = value;
        std::string text;
        for (std::size_t i = 0; i < lines.size(); ++i) {
            std::string line = lines[i];
            if (i == 4) {
                line.clear();
                for (std::size_t k = 0; k < cells.size(); ++k) line += (k ? "," : "") + cells[k];
            }
            text += line + "\n";
        }
        const std::string file = dir.file("bad_" + column + ".csv");
        std::ofstream(file) << text;
        return file;
    };
    std::string state;
    for (const std::string& c : header)
        if (c.rfind("state_", 0) == 0) state = c;
    ASSERT_FALSE(state.empty());
    const std::pair<std::string, std::string> cells[] = {
        {state, "nan"}, {"elbow_angle_deg", "1e308"}, {"activation", "7"}, {"saturated", "7"},
        {"muscle_force_N", "-1e6"}, {"strap_force_N", "nan"}, {"elbow_angle_deg", "1.5708"}};
    for (const auto& [column, value] : cells) {
        const CommandResult r = runArmsim("render " + withCell(column, value) + " --out " + dir.file("x.mp4"));
        EXPECT_EQ(r.exitCode, 2) << column << ": " << r.output;
        EXPECT_NE(r.output.find("line 5: column '" + column + "'"), std::string::npos) << column << ": " << r.output;
    }
    std::ofstream(dir.file("one_row.csv")) << lines[0] << "\n" << lines[1] << "\n";
    const CommandResult oneRow = runArmsim("render " + dir.file("one_row.csv") + " --out " + dir.file("x.mp4"));
    EXPECT_EQ(oneRow.exitCode, 2) << oneRow.output;
    EXPECT_NE(oneRow.output.find("has one row (t = 0 s): a video needs two rows or more"), std::string::npos) << oneRow.output;
    // Two rows 10 ms apart at 30 fps: less than a frame; a slower playback would make one.
    std::ofstream(dir.file("short.csv")) << lines[0] << "\n" << lines[1] << "\n" << lines[2] << "\n";
    const CommandResult shortTable = runArmsim("render " + dir.file("short.csv") + " --out " + dir.file("x.mp4"));
    EXPECT_EQ(shortTable.exitCode, 2) << shortTable.output;
    EXPECT_NE(shortTable.output.find("--speed = 1: the trial table"), std::string::npos) << shortTable.output;
    EXPECT_NE(shortTable.output.find("less than one frame"), std::string::npos) << shortTable.output;
    EXPECT_FALSE(fs::exists(dir.file("x.mp4")));
    // Rows missing from the middle (lines 11-20 of the file: 0.09-0.18 s) are refused, not bridged by interpolation.
    {
        std::ofstream gap(dir.file("gap.csv"));
        for (std::size_t i = 0; i < lines.size(); ++i)
            if (i < 10 || i > 19) gap << lines[i] << "\n";
    }
    const CommandResult gap = runArmsim("render " + dir.file("gap.csv") + " --out " + dir.file("x.mp4"));
    EXPECT_EQ(gap.exitCode, 2) << gap.output;
    EXPECT_NE(gap.output.find("gap.csv:11: time_s jumps from 0.08 to 0.19 s, 11 times the table's sample interval of 0.01 s"),
              std::string::npos) << gap.output;
    // A spreadsheet's quoted header and cells read as the plain ones.
    {
        std::ofstream quoted(dir.file("quoted.csv"));
        std::string header0;
        for (std::size_t k = 0; k < header.size(); ++k) header0 += (k ? "," : "") + ("\"" + header[k] + "\"");
        quoted << header0 << "\n";
        for (std::size_t i = 1; i < lines.size(); ++i) quoted << (i == 1 ? "\"0\"" + lines[i].substr(1) : lines[i]) << "\n";
    }
    const CommandResult quotedStill = runArmsim("render " + dir.file("quoted.csv") + " --still-at 0.1 --still " + dir.file("q.png"));
    EXPECT_EQ(quotedStill.exitCode, 0) << quotedStill.output;
    // One row still makes a still.
    const CommandResult still = runArmsim("render " + dir.file("one_row.csv") + " --still-at 0 --still " + dir.file("s.png"));
    EXPECT_EQ(still.exitCode, 0) << still.output;
}

// A render killed outright (SIGKILL: no handler runs) leaves only files the next run in the folder
// recognises as a dead process's staging and removes.
TEST(RenderCli, AKilledRenderLeavesNothingTheNextRunKeeps) {
    ScratchDir dir;
    ASSERT_EQ(recordTrial(dir).exitCode, 0);
    fs::create_directories(dir.file("out"));
    // Killed once its video's temporary exists (the shell reaps it: no zombie counts as running).
    const std::string out = dir.file("out");
    armsim::testing::runCommand(
        "sh -c '" + std::string(ARMSIM_EXE) + " render " + dir.file("t.csv") + " --speed 0.1 --out " + out +
        "/v.mp4 >/dev/null 2>&1 & pid=$!; for i in $(seq 200); do ls -a " + out + " | grep -q tmp && break; "
        "sleep 0.05; done; kill -KILL $pid; wait $pid'");
    int left = 0;
    for (const fs::directory_entry& e : fs::directory_iterator(out)) {
        EXPECT_EQ(e.path().filename().string().rfind(".armsim-partial-", 0), 0u) << e.path();
        ++left;
    }
    ASSERT_GT(left, 0) << "the render was not caught writing its video";
    const CommandResult r = runArmsim("render " + dir.file("t.csv") + " --still-at 0.1 --still " + dir.file("out/s.png"));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    std::vector<std::string> names;
    for (const fs::directory_entry& e : fs::directory_iterator(dir.file("out"))) names.push_back(e.path().filename().string());
    EXPECT_EQ(names, std::vector<std::string>{"s.png"});
}

TEST(RenderCli, ProtocolVideoRendersEveryTrial) {
    ScratchDir dir;
    const double rest = 0.2, hold = 0.4;
    {
        std::ofstream f(dir.file("p.yaml"));
        f << "name: two_angles\nkind: mvc\ndescription: short\nseed: 7\norder: listed\nrepetitions: 1\n"
          << "trial:\n  rest: " << rest << "\n  hold: " << hold << "\n  averaging_window: 0.2\n"
          << "conditions:\n  elbow_angles_deg: [90, 120]\nsensors:\n  emg:\n    enabled: false\n";
    }
    const CommandResult r = runArmsim("protocol " + dir.file("p.yaml") + " --out " + dir.file("run") +
                                      " --video --video-fps 20 --video-width 320 --video-height 180");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    for (const char* id : {"a090", "a120"}) {
        const VideoInfo v = probe(dir.file("run/videos/" + std::string(id) + ".mp4"));
        EXPECT_EQ(v.frames, expectedFrames(rest + hold, 20)) << id;
        EXPECT_EQ(v.size, cv::Size(320, 180)) << id;
        EXPECT_NEAR(v.fps, 20.0, kFpsTolerance) << id;
    }
}

// `armsim trial --model arm26 --video`: the OpenSim model's free and isometric trials rendered
// (render/osim_video.h; its pixels are tested in test_osim_video.cpp), one frame per 1/30 s, 1280 x 720.
TEST(RenderCli, OsimTrialVideos) {
    ScratchDir dir;
    const CommandResult free = runArmsim("trial --model arm26 --type free --coordinate r_elbow_flex --initial-angle 20 "
                                         "--duration 0.3 --rate 100 --out " + dir.file("f.csv") + " --video " + dir.file("f.mp4"));
    ASSERT_EQ(free.exitCode, 0) << free.output;
    EXPECT_NE(free.output.find("(10 frames)"), std::string::npos) << free.output;
    const VideoInfo fv = probe(dir.file("f.mp4"));
    EXPECT_EQ(fv.frames, expectedFrames(0.3, 30));
    EXPECT_EQ(fv.size, cv::Size(1280, 720));
    const CommandResult iso = runArmsim("trial --model arm26 --coordinate r_elbow_flex --angle 80 --rest 0.2 --hold 0.3 "
                                        "--rate 100 --out " + dir.file("i.csv") + " --video " + dir.file("i.mp4"));
    ASSERT_EQ(iso.exitCode, 0) << iso.output;
    EXPECT_EQ(probe(dir.file("i.mp4")).frames, expectedFrames(0.5, 30));
    // The saved table rendered again (armsim render TABLE --model arm26), with a still; the arm scene's
    // options refused by name, and the table refused without the model it belongs to.
    const CommandResult again = runArmsim("render " + dir.file("f.csv") + " --model arm26 --out " + dir.file("r.mp4") +
                                          " --fps 20 --width 320 --height 240 --still-at 0.2 --still " + dir.file("s.png"));
    ASSERT_EQ(again.exitCode, 0) << again.output;
    const VideoInfo rv = probe(dir.file("r.mp4"));
    EXPECT_EQ(rv.frames, expectedFrames(0.3, 20));
    EXPECT_EQ(rv.size, cv::Size(320, 240));
    EXPECT_EQ(cv::imread(dir.file("s.png")).size(), cv::Size(320, 240));
    const CommandResult load = runArmsim("render " + dir.file("f.csv") + " --model arm26 --load 2 --out " + dir.file("l.mp4"));
    EXPECT_EQ(load.exitCode, 2) << load.output;
    EXPECT_NE(load.output.find("--load with the OpenSim model 'arm26'"), std::string::npos) << load.output;
    const CommandResult armsimModel = runArmsim("render " + dir.file("f.csv") + " --out " + dir.file("m.mp4"));
    EXPECT_EQ(armsimModel.exitCode, 2) << armsimModel.output;
    EXPECT_NE(armsimModel.output.find("armsim render TABLE --model FILE.osim"), std::string::npos) << armsimModel.output;
    EXPECT_FALSE(std::filesystem::exists(dir.file("l.mp4")));
    EXPECT_FALSE(std::filesystem::exists(dir.file("m.mp4")));
}

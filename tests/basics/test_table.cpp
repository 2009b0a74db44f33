#include "basics/errors.h"
#include "basics/table.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <unistd.h>
#include <fstream>

using namespace armsim;
namespace fs = std::filesystem;

TEST(Table, CsvRoundTripsEveryDoubleAt17Digits) {
    Table t({"time_s", "force_N"});
    t.appendRow({0.1, 1.0 / 3.0});
    t.appendRow({2e-300, -123456789.123456789});
    t.appendRow({1e300, std::nan("")});
    const fs::path p = fs::temp_directory_path() / ("armsim_table_" + std::to_string(::getpid()) + ".csv");
    t.writeCsv(p.string(), 17);
    const Table r = Table::readCsv(p.string());
    fs::remove(p);
    ASSERT_EQ(r.getColumnNames(), t.getColumnNames());
    ASSERT_EQ(r.getNumRows(), 3);
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 2; ++j) {
            if (std::isnan(t.get(i, j))) EXPECT_TRUE(std::isnan(r.get(i, j)));
            else EXPECT_EQ(r.get(i, j), t.get(i, j)) << i << "," << j;  // exact: 17 digits round-trip
        }
    EXPECT_EQ(r.getSourceLine(0), 2);
    EXPECT_EQ(r.describeRow("f.csv", 2), "f.csv:4");
}

TEST(Table, CsvTextHasTheRequestedDigitsAndChecksShapes) {
    Table t({"a", "b"});
    t.appendRow({1.0 / 3.0, 2500});
    EXPECT_EQ(t.toCsv(4), "a,b\n0.3333,2500\n");
    EXPECT_THROW(t.toCsv(0), std::invalid_argument);
    EXPECT_THROW(t.appendRow({1}), std::invalid_argument);
    EXPECT_THROW(t.findColumn("c"), std::invalid_argument);
    EXPECT_EQ(t.getColumn("b"), std::vector<double>{2500});
}

TEST(Table, MalformedCellNamesFileLineAndColumn) {
    const fs::path p = fs::temp_directory_path() / ("armsim_bad_" + std::to_string(::getpid()) + ".csv");
    std::ofstream(p) << "time_s,force_N\n# a comment\n0,1\n0.1,abc\n";
    try {
        Table::readCsv(p.string());
        ADD_FAILURE() << "no error";
    } catch (const InputError& e) {
        const std::string m = e.what();
        EXPECT_NE(m.find(p.string() + ":4"), std::string::npos) << m;
        EXPECT_NE(m.find("force_N"), std::string::npos) << m;
        EXPECT_NE(m.find("abc"), std::string::npos) << m;
    }
    std::ofstream(p) << "a,b\n1,2,3\n";
    EXPECT_THROW(Table::readCsv(p.string()), InputError);
    // A repeated column name (a reader would take one of the two silently) is refused with both columns.
    std::ofstream(p) << "# data\nangle_deg,torque_Nm,angle_deg\n90,40,30\n";
    try {
        Table::readCsv(p.string());
        ADD_FAILURE() << "repeated column accepted";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find(p.string() + ":2: column 'angle_deg' appears twice in the header (columns 1 and 3)"),
                  std::string::npos) << e.what();
    }
    fs::remove(p);
}

// A spreadsheet's CSV quotes cells (RFC 4180): the quotes go, a quoted comma stays inside its cell, ""
// is a quote, and a quote left open is named with its line.
TEST(Table, QuotedCellsReadAsTheirText) {
    const fs::path p = fs::temp_directory_path() / ("armsim_quoted_" + std::to_string(::getpid()) + ".csv");
    std::ofstream(p) << "\"time_s\", \"force_N\" ,c\n\"0\",\"1.5\",\"2\"\n";
    const Table t = Table::readCsv(p.string());
    EXPECT_EQ(t.getColumnNames(), (std::vector<std::string>{"time_s", "force_N", "c"}));
    EXPECT_EQ(t.getRow(0), (std::vector<double>{0, 1.5, 2}));
    std::ofstream(p) << "a,\"b,c\",\"d\"\"\"\n1,2,3\n";
    EXPECT_EQ(Table::readCsv(p.string()).getColumnNames(), (std::vector<std::string>{"a", "b,c", "d\""}));
    // Trailing commas (a spreadsheet's empty last columns) read as no columns; an unnamed column inside
    // the header is refused with its place.
    std::ofstream(p) << "a,b,,\n1,2,,\n3,4\n";
    const Table trailing = Table::readCsv(p.string());
    EXPECT_EQ(trailing.getColumnNames(), (std::vector<std::string>{"a", "b"}));
    EXPECT_EQ(trailing.getRow(1), (std::vector<double>{3, 4}));
    std::ofstream(p) << "a,,b\n1,2,3\n";
    try {
        Table::readCsv(p.string());
        ADD_FAILURE() << "an unnamed column accepted";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find(":1: the header's column 2 has no name"), std::string::npos) << e.what();
    }
    std::ofstream(p) << "a,b\n1,\"2\n";
    try {
        Table::readCsv(p.string());
        ADD_FAILURE() << "an open quote accepted";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find(p.string() + ":2: a double quote is opened and not closed"), std::string::npos)
            << e.what();
    }
    fs::remove(p);
}

// Trial tables are sampled evenly; a time that does not increase, or rows missing from the middle, is
// named with its line and the interval (a last interval shorter than the rest is a trial's end).
TEST(Table, SampleTimesMustIncreaseWithoutGaps) {
    Table t({"time_s"});
    for (double x : {0.0, 0.01, 0.02, 0.03, 0.035}) t.appendRow({x});
    EXPECT_NO_THROW(checkSampleTimes(t, "time_s", "t.csv"));
    t.appendRow({0.055});   // 2 intervals: the bound, inclusive
    EXPECT_NO_THROW(checkSampleTimes(t, "time_s", "t.csv"));
    t.appendRow({0.0851});   // 3.01 intervals
    try {
        checkSampleTimes(t, "time_s", "t.csv");
        ADD_FAILURE() << "a gap accepted";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("t.csv row 7: time_s jumps from 0.055 to 0.0851 s, 3.01 times the table's "
                                             "sample interval of 0.01 s: rows are missing"),
                  std::string::npos) << e.what();
    }
    Table back({"time_s"});
    for (double x : {0.0, 0.01, 0.01}) back.appendRow({x});
    EXPECT_THROW(checkSampleTimes(back, "time_s", "t.csv"), InputError);
}

#include "basics/angles.h"
#include "basics/csv.h"
#include "basics/format.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

using namespace armsim;

TEST(Csv, TextIsQuotedOnlyWhenNeededAndStaysOnOneLine) {
    CsvRow row;
    row.addText("plain").addText("a,b").addText("say \"hi\"").addText("line\nbreak").addText("a\n").addText(" pad");
    EXPECT_EQ(row.getText(), "plain,\"a,b\",\"say \"\"hi\"\"\",line break,\"a \",\" pad\"");
    EXPECT_EQ(row.getNumCells(), 6);
    const std::vector<std::string> cells = splitCsvRecord(row.getText());
    EXPECT_EQ(cells, (std::vector<std::string>{"plain", "a,b", "say \"hi\"", "line break", "a ", " pad"}));
}

TEST(Csv, NumbersRoundTripMissingIsEmptyInfinityIsSpelled) {
    CsvRow row;
    row.addNumber(0.1).addNumber(1.0 / 3.0).addNumber(std::nan("")).addNumber(HUGE_VAL).addNumber(-HUGE_VAL);
    row.addNumber(1.0 / 3.0, 4).addInteger(-12).addEmpty();
    EXPECT_EQ(row.getText(), "0.1,0.3333333333333333,,inf,-inf,0.3333,-12,");
    EXPECT_EQ(std::stod(splitCsvRecord(row.getText())[1]), 1.0 / 3.0);
    EXPECT_THROW(CsvRow().addNumber(1, 0), std::invalid_argument);
}

TEST(Csv, RecordsMustHaveTheHeadersWidth) {
    CsvText csv({"a", "b"});
    CsvRow ok;
    ok.addInteger(1).addText("x");
    csv.addRow(ok);
    EXPECT_EQ(csv.getText(), "a,b\n1,x\n");
    CsvRow shorter;
    shorter.addInteger(1);
    EXPECT_THROW(csv.addRow(shorter), std::invalid_argument);
}

TEST(Format, ShortestRoundTripAndDegrees) {
    for (double v : {0.1, 1e300, -2.5e-7, 1.0 / 3.0}) EXPECT_EQ(std::stod(formatNumber(v)), v);
    EXPECT_EQ(formatNumber(0.1), "0.1");
    EXPECT_NEAR(degToRad(180), kPi, 1e-15);
    EXPECT_NEAR(radToDeg(degToRad(37.5)), 37.5, 1e-12);
}

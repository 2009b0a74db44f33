// Field tables (basics/fields.h): a struct written to CSV and JSON and read back from CSV, its SI view.
#include "basics/fields.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace armsim;

namespace {

struct Row {
    std::string name;
    double errorFraction = 0;   // written in %
    double lengthM = 0;         // written in mm
    double massKg = 0;
    int count = 0;
    bool ok = false;
    int covered = -1;
};

#define AT(member) [](auto& r) -> auto& { return r.member; }

const FieldTable<Row>& getRowFields() {
    static const FieldTable<Row> fields({
        textField<Row>("name", AT(name)),
        numberField<Row>("error_pct", "%", AT(errorFraction), 100),
        numberField<Row>("length_mm", "mm", AT(lengthM), 1000),
        numberField<Row>("mass_kg", "kg", AT(massKg)),
        integerField<Row>("count", "", AT(count)),
        boolField<Row>("ok", AT(ok)),
        flagField<Row>("covered", AT(covered)),
    });
    return fields;
}

}  // namespace

TEST(Fields, CsvHeaderRowsAndReadBack) {
    const Row r{"a, \"b\"", 0.125, 0.0025, 0.1 + 0.2, 7, true, -1};
    EXPECT_EQ(getRowFields().getHeader(), "name,error_pct,length_mm,mass_kg,count,ok,covered");
    const std::string line = getRowFields().formatRow(r).getText();
    EXPECT_EQ(line, "\"a, \"\"b\"\"\",12.5,2.5,0.30000000000000004,7,1,");
    Row back;
    ASSERT_TRUE(getRowFields().parseRow(splitCsvRecord(line), back));
    EXPECT_EQ(back.name, r.name);
    EXPECT_DOUBLE_EQ(back.errorFraction, r.errorFraction);
    EXPECT_DOUBLE_EQ(back.lengthM, r.lengthM);
    EXPECT_EQ(back.massKg, r.massKg);   // unscaled numbers read back exactly
    EXPECT_EQ(back.count, 7);
    EXPECT_TRUE(back.ok);
    EXPECT_EQ(back.covered, -1);
    // A malformed cell or a short row is refused.
    std::vector<std::string> cells = splitCsvRecord(line);
    cells[4] = "7.5";
    EXPECT_FALSE(getRowFields().parseRow(cells, back));
    cells.pop_back();
    EXPECT_FALSE(getRowFields().parseRow(cells, back));
    EXPECT_EQ(getRowFields().formatCsv({r, r}), getRowFields().getHeader() + "\n" + line + "\n" + line + "\n");
}

TEST(Fields, JsonAndSiViews) {
    Row r{"x", NAN, 0.003, 1.5, 2, false, 1};
    const nlohmann::ordered_json j = getRowFields().toJson(r);
    EXPECT_TRUE(j["error_pct"].is_null());
    EXPECT_DOUBLE_EQ(j["length_mm"].get<double>(), 3.0);
    EXPECT_EQ(j["covered"], true);
    EXPECT_EQ(j["ok"], false);
    std::vector<std::string> siNames;
    for (const Field<Row>& f : getRowFields().getFields()) siNames.push_back(f.siName);
    EXPECT_EQ(siNames, (std::vector<std::string>{"name", "error", "length_m", "mass_kg", "count", "ok", "covered"}));
    EXPECT_DOUBLE_EQ(getRowFields().getFields()[2].toSi(r).get<double>(), 0.003);
    EXPECT_EQ(getRowFields().getFields()[6].toSi(r).get<int>(), 1);
    // A scaled field must say its scale in its name.
    EXPECT_THROW(numberField<Row>("length_cm", "cm", AT(lengthM), 100), std::logic_error);
}

#undef AT

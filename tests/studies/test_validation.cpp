// Validation of the thesis identifiers against a known truth: a tiny run recovers the thesis truth and
// writes one row per method and noise level.
#include "basics/errors.h"
#include "studies/validation.h"
#include "tests/identification/test_support.h"

#include <algorithm>

using namespace armsim;
using namespace armsim::test;

namespace {

constexpr double kRecoveryTol = 1e-3;  // relative: "within 0.1 %" of the truth

}  // namespace

TEST(Validation, TinyRunRecoversTheThesisTruthAndWritesOneRowPerMethodAndNoiseLevel) {
    const ArmSetup setup = ArmSetup::loadDefault();
    const MuscleParameters base = setup.calcBicepsParameters();
    ValidationSettings s;
    s.seeds = 0;
    s.noiseLevels = {0.0, 0.02};
    s.methods = {Method::LevenbergMarquardt};
    const std::vector<ValidationRow> rows = runValidation(setup.arm, base, s);
    ASSERT_EQ(rows.size(), 2u);
    EXPECT_EQ(rows[0].truth, "thesis");
    EXPECT_LT(std::abs(rows[0].massError), kRecoveryTol) << rows[0].mass;
    EXPECT_LT(std::abs(rows[0].tendonLengthError), kRecoveryTol) << rows[0].tendonLength;
    EXPECT_GT(std::abs(rows[1].massError), std::abs(rows[0].massError));  // noise moves the estimate
    EXPECT_NE(rows[1].massCovered, -1);                                    // lm with n > p has intervals
    const std::string csv = formatValidationCsv(rows);
    EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 3);
    EXPECT_NE(formatValidationTable(rows).find("lm"), std::string::npos);
    s.noiseLevels = {0.6};
    EXPECT_THROW(runValidation(setup.arm, base, s), InputError);
}

#include "basics/errors.h"
#include "muscles/activation.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

using namespace armsim;

TEST(ActivationProfile, PiecewiseLinearWithRightContinuousSteps) {
    constexpr double kTol = 1e-15;
    const ActivationProfile step = ActivationProfile::step(0.5, 0.1, 0.9);
    EXPECT_NEAR(step.getValue(0.0), 0.1, kTol);
    EXPECT_NEAR(step.getValue(0.4999), 0.1, kTol);
    EXPECT_NEAR(step.getValue(0.5), 0.9, kTol);
    EXPECT_NEAR(step.getValue(9.0), 0.9, kTol);
    const ActivationProfile pulse = ActivationProfile::pulse(1.0, 0.2, 0.8, 3.0);
    EXPECT_NEAR(pulse.getValue(1.1), 0.4, 1e-12);
    EXPECT_NEAR(pulse.getValue(2.0), 0.8, kTol);
    EXPECT_NEAR(pulse.getValue(3.1), 0.4, 1e-12);
    EXPECT_NEAR(pulse.getValue(4.0), 0.0, kTol);
    EXPECT_EQ(pulse.getBreakpoints().size(), 4u);
}

TEST(ActivationProfile, RejectsValuesOutsideZeroOneAndUnorderedTimes) {
    EXPECT_THROW(ActivationProfile::constant(1.2), InputError);
    EXPECT_THROW(ActivationProfile::constant(-0.1), InputError);
    EXPECT_THROW(ActivationProfile({0.0, 1.0, 0.5}, {0, 0, 0}), InputError);
    EXPECT_THROW(ActivationProfile({0.0, 1.0}, {0.0}), InputError);
    try {
        ActivationProfile({0.0, 1.0}, {0.5, 2.0}, "trace.csv");
        ADD_FAILURE();
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("trace.csv point 1"), std::string::npos) << e.what();
    }
}

// A recruitment threshold passed on a sloped stretch: the crossing time is the first double at which U
// is past the level (so a restart there sees the unit recruited), rising and falling alike.
TEST(ActivationProfile, FindsWhereASlopedStretchPassesALevel) {
    const ActivationProfile p({1.0, 11.0, 12.0, 12.0, 14.0}, {0.0, 1.0, 1.0, 0.3, 0.1});
    const std::vector<double> levels{0.0, 0.064, 0.2, 0.5, 1.0};
    const std::vector<double> t = p.findCrossings(levels);
    // Rising 0 -> 1 over [1, 11]: 0.064, 0.2, 0.5 and 1 (at the end); 0 is where it starts, not passed.
    // The step 1 -> 0.3 at 12 is a breakpoint, not a crossing. Falling 0.3 -> 0.1 over [12, 14]: 0.2.
    const std::vector<double> expected{1.64, 3.0, 6.0, 11.0, 13.0};
    ASSERT_EQ(t.size(), expected.size());
    for (std::size_t k = 0; k < t.size(); ++k) {
        EXPECT_NEAR(t[k], expected[k], 1e-12) << k;  // a few ulps from the exact time
        const double U = p.getValue(t[k]), before = p.getValue(std::nextafter(t[k], 0.0));
        const double level = k < 4 ? levels[k + 1] : 0.2;
        if (k < 4) EXPECT_TRUE(U >= level && before < level) << k << ": U " << U << ", before " << before;
        else EXPECT_TRUE(U < level && before >= level) << k << ": U " << U << ", before " << before;
    }
    EXPECT_TRUE(ActivationProfile::constant(0.5).findCrossings(levels).empty());
    EXPECT_TRUE(ActivationProfile::step(1.0, 0.0, 1.0).findCrossings(levels).empty());
}

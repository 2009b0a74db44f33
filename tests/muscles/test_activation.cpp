#include "basics/errors.h"
#include "muscles/activation.h"

#include <gtest/gtest.h>

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

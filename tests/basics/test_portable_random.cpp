// Seeded draws that every standard library reproduces (basics/portable_random.h).
#include "basics/portable_random.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>

using namespace armsim;

// std::mt19937_64's output is fixed by the standard: the first output for the default seed 5489 is
// 14514284786278117030 (and the 10000th 9981545732273789042, [rand.predef]). The draws are exact
// functions of it.
TEST(PortableRandom, DrawsAreExactFunctionsOfTheStandardEngine) {
    auto r = PortableRandom::fromSeed(5489);
    EXPECT_EQ(r.drawUniform(), double(14514284786278117030ULL >> 11) * 0x1.0p-53);
    std::mt19937_64 reference(5489);
    reference.discard(9999);
    auto s = PortableRandom::fromSeed(5489);
    for (int i = 0; i < 9999; ++i) s.drawUniform();
    EXPECT_EQ(s.drawUniform(), double(9981545732273789042ULL >> 11) * 0x1.0p-53);
    EXPECT_EQ(reference(), 9981545732273789042ULL);

    // Indices and shuffles: the engine's output modulo n (rejection removes only the last
    // 2^64 mod n values, never met here), positions swapped from the end (Fisher-Yates).
    auto i = PortableRandom::fromSeed(99);
    std::mt19937_64 engine(99);
    for (int k = 0; k < 100; ++k) EXPECT_EQ(i.drawIndex(6), engine() % 6);
    auto shuffled = PortableRandom::fromSeed(7);
    std::mt19937_64 byHand(7);
    std::vector<int> v(10), w(10);
    std::iota(v.begin(), v.end(), 0);
    std::iota(w.begin(), w.end(), 0);
    shuffled.shuffle(v);
    for (std::size_t k = w.size(); k > 1; --k) std::swap(w[k - 1], w[byHand() % k]);
    EXPECT_EQ(v, w);
}

// drawIndex is unbiased: counts of 600,000 draws in [0, 6) within 4 standard deviations of 100,000
// (binomial sd 289); a range that is not a power of two and one near 2^64 stay in range.
TEST(PortableRandom, IndicesAreUniformAndInRange) {
    constexpr int kDraws = 600000, kBins = 6;
    constexpr double kSdTol = 4;
    auto r = PortableRandom::fromSeed(42);
    std::vector<int> count(kBins, 0);
    for (int i = 0; i < kDraws; ++i) ++count[r.drawIndex(kBins)];
    const double p = 1.0 / kBins, sd = std::sqrt(kDraws * p * (1 - p));
    for (int c : count) EXPECT_NEAR(c, kDraws * p, kSdTol * sd);
    const std::uint64_t huge = (std::uint64_t(1) << 63) + 12345;
    for (int i = 0; i < 1000; ++i) EXPECT_LT(r.drawIndex(huge), huge);
    EXPECT_EQ(r.drawIndex(1), 0u);
}

// A shuffle is a permutation, and every position receives every element about equally often.
TEST(PortableRandom, ShuffleIsAnUnbiasedPermutation) {
    constexpr int kRounds = 60000, kSize = 4;
    constexpr double kSdTol = 4;
    auto r = PortableRandom::fromSeed(7);
    std::vector<std::vector<int>> at(kSize, std::vector<int>(kSize, 0));
    for (int k = 0; k < kRounds; ++k) {
        std::vector<int> v(kSize);
        std::iota(v.begin(), v.end(), 0);
        r.shuffle(v);
        std::vector<int> sorted = v;
        std::sort(sorted.begin(), sorted.end());
        ASSERT_EQ(sorted, std::vector<int>({0, 1, 2, 3}));
        for (int i = 0; i < kSize; ++i) ++at[i][v[i]];
    }
    const double p = 1.0 / kSize, sd = std::sqrt(kRounds * p * (1 - p));
    for (const auto& row : at)
        for (int c : row) EXPECT_NEAR(c, kRounds * p, kSdTol * sd);
}

// Normal draws: mean 0 and variance 1 within 5 standard errors over 200,000 draws.
TEST(PortableRandom, NormalDrawsHaveUnitVariance) {
    constexpr int kDraws = 200000;
    constexpr double kSeTol = 5;
    PortableRandom r({3u, 4u});
    double sum = 0, sum2 = 0;
    for (int i = 0; i < kDraws; ++i) {
        const double x = r.drawNormal();
        sum += x;
        sum2 += x * x;
    }
    EXPECT_NEAR(sum / kDraws, 0.0, kSeTol / std::sqrt(double(kDraws)));
    EXPECT_NEAR(sum2 / kDraws, 1.0, kSeTol * std::sqrt(2.0 / kDraws));
}

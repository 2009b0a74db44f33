// Random draws that are the same with every C++ standard library: std::mt19937_64 and std::seed_seq
// are specified exactly by the standard, the std distributions are not (libstdc++, libc++ and MSVC
// draw different normals from the same engine). Uniform and normal draws are made here from the raw
// 64-bit output, so seeded results reproduce on any platform: populations, synthetic torque data,
// protocol effort variation, transducer noise, trial order and surface EMG, validation truths and the
// identifier's multi-start points all draw from here (no std distribution or std::shuffle is used).
#pragma once

#include "basics/angles.h"

#include <cmath>
#include <cstdint>
#include <initializer_list>
#include <random>
#include <utility>
#include <vector>

namespace armsim {

class PortableRandom {
public:
    /// Seeded through std::seed_seq with the given words (e.g. {seed, subject index}).
    PortableRandom(std::initializer_list<std::uint32_t> seeds) {
        std::seed_seq seq(seeds);
        rng_.seed(seq);
    }
    /// Seeded with one 64-bit word directly (e.g. a splitmix of a trial's seed). A named constructor:
    /// PortableRandom{seed} would take the seed_seq constructor and give another stream.
    static PortableRandom fromSeed(std::uint64_t seed) { return PortableRandom(seed, 0); }
    /// Uniform in [0, 1), 53 random bits.
    double drawUniform() { return double(rng_() >> 11) * 0x1.0p-53; }
    /// Uniform in [lo, hi).
    double drawUniform(double lo, double hi) { return lo + (hi - lo) * drawUniform(); }
    /// Uniform integer in [0, n), n >= 1, without modulo bias (rejection of the incomplete last block).
    std::uint64_t drawIndex(std::uint64_t n) {
        const std::uint64_t limit = ~std::uint64_t(0) - (~std::uint64_t(0) % n + 1) % n;  // last full block
        std::uint64_t x;
        do x = rng_();
        while (x > limit);
        return x % n;
    }
    /// Fisher-Yates shuffle with drawIndex (std::shuffle's draws differ between standard libraries).
    template <class T>
    void shuffle(std::vector<T>& v) {
        for (std::size_t i = v.size(); i > 1; --i) std::swap(v[i - 1], v[drawIndex(i)]);
    }
    /// Standard normal (Box-Muller on two uniforms; one value per call).
    double drawNormal() {
        const double u1 = 1.0 - drawUniform();  // (0, 1]: log finite
        const double u2 = drawUniform();
        return std::sqrt(-2.0 * std::log(u1)) * std::cos(2 * kPi * u2);
    }

private:
    PortableRandom(std::uint64_t seed, int) : rng_(seed) {}
    std::mt19937_64 rng_;
};

}  // namespace armsim

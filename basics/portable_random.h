// Random draws that are the same with every C++ standard library: std::mt19937_64 and std::seed_seq
// are specified exactly by the standard, the std distributions are not (libstdc++, libc++ and MSVC
// draw different normals from the same engine). Uniform and normal draws are made here from the raw
// 64-bit output, so seeded results (populations, synthetic data) reproduce on any platform.
#pragma once

#include "basics/angles.h"

#include <cmath>
#include <cstdint>
#include <initializer_list>
#include <random>

namespace armsim {

class PortableRandom {
public:
    /// Seeded through std::seed_seq with the given words (e.g. {seed, subject index}).
    PortableRandom(std::initializer_list<std::uint32_t> seeds) {
        std::seed_seq seq(seeds);
        rng_.seed(seq);
    }
    /// Uniform in [0, 1), 53 random bits.
    double drawUniform() { return double(rng_() >> 11) * 0x1.0p-53; }
    /// Standard normal (Box-Muller on two uniforms; one value per call).
    double drawNormal() {
        const double u1 = 1.0 - drawUniform();  // (0, 1]: log finite
        const double u2 = drawUniform();
        return std::sqrt(-2.0 * std::log(u1)) * std::cos(2 * kPi * u2);
    }

private:
    std::mt19937_64 rng_;
};

}  // namespace armsim

// Power spectrum scaling (Parseval, white-noise level) and MNF/MDF on signals with known spectra.
#include "basics/angles.h"
#include "basics/errors.h"
#include "experiments/signal.h"
#include "experiments/spectrum.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numeric>
#include <random>
#include <string>
#include <vector>

namespace armsim {
namespace {


// Tolerances.
constexpr double kExactHz = 1e-6;              // features that are exact by symmetry (Hz)
constexpr double kLeakageTol = 1e-9;           // Hann leakage ratios of a bin-centred tone
constexpr double kParsevalRelTol = 1e-10;      // periodogram power vs time-domain variance
constexpr double kWhiteLevelRelTol = 0.03;     // Welch level of white noise, 60 s (~5 sigma)
constexpr double kWhiteMnfTolHz = 1.0;         // white-noise MNF vs band centre, 240 s (~4 sigma)
constexpr double kWhiteMdfTolHz = 1.5;         // white-noise MDF vs band centre, 240 s (~4 sigma)
constexpr double kShapedMnfRelTol = 0.01;      // MNF of filtered noise vs response-weighted mean

std::vector<double> whiteNoise(std::size_t n, double sigma, unsigned seed) {
    std::mt19937_64 rng(seed);
    std::normal_distribution<double> d(0.0, sigma);
    std::vector<double> x(n);
    for (double& v : x) v = d(rng);
    return x;
}

std::vector<double> sines(const std::vector<double>& freqs, double fs, std::size_t n) {
    std::vector<double> x(n, 0.0);
    for (std::size_t i = 0; i < n; ++i)
        for (std::size_t j = 0; j < freqs.size(); ++j)
            x[i] += std::sin(2 * kPi * freqs[j] * i / fs + 0.7 * j);
    return x;
}

TEST(Spectrum, PureSineAtBinCentre) {
    const double fs = 1000, f = 87;
    const std::vector<double> x = sines({f}, fs, 3000);
    SpectrumSettings welch;
    welch.segmentLength = 1000;   // 1 Hz bins
    SpectrumSettings whole;
    whole.window = SpectralWindow::Rectangular;
    for (const SpectrumSettings& s : {welch, whole}) {
        const PowerSpectrum p = calcPowerSpectrum(x, fs, s);
        EXPECT_NEAR(calcMeanFrequency(p, 10, 400), f, p.resolution);
        EXPECT_NEAR(calcMedianFrequency(p, 10, 400), f, p.resolution);
        // Bin-centred: the Hann leakage (1/4, 1, 1/4) is symmetric, so both are exact.
        EXPECT_NEAR(calcMeanFrequency(p, 10, 400), f, kExactHz);
        EXPECT_NEAR(calcMedianFrequency(p, 10, 400), f, kExactHz);
    }
    // Periodic Hann: a bin-centred tone leaks into exactly its two neighbours, at 1/4 of its power.
    const PowerSpectrum p = calcPowerSpectrum(x, fs, welch);
    EXPECT_EQ(p.segmentCount, 5);   // hop 500 over 3000 samples
    const std::size_t k0 = std::size_t(f / p.resolution);
    EXPECT_NEAR(p.density[k0 - 1] / p.density[k0], 0.25, kLeakageTol);
    EXPECT_NEAR(p.density[k0 + 1] / p.density[k0], 0.25, kLeakageTol);
    EXPECT_LT(p.density[k0 + 2] / p.density[k0], kLeakageTol);
    EXPECT_LT(p.density[k0 - 20] / p.density[k0], kLeakageTol);
}

TEST(Spectrum, MedianInterpolatesWithinBin) {
    // Each bin's power spread uniformly over its width: hand-made spectra with known medians.
    PowerSpectrum p;
    p.resolution = 1;
    p.frequency = {0, 1, 2, 3, 4, 5};
    p.density = {0, 3, 1, 0, 0, 0};   // power 3 on [0.5, 1.5], 1 on [1.5, 2.5]: half at 0.5 + 2/3
    EXPECT_NEAR(calcMedianFrequency(p, 0, 5), 0.5 + 2.0 / 3.0, kExactHz);
    EXPECT_NEAR(calcMeanFrequency(p, 0, 5), (3 * 1 + 1 * 2) / 4.0, kExactHz);
    EXPECT_NEAR(calcMeanFrequency(p, 1, 2), (3 * 1 + 1 * 2) / 4.0, kExactHz);   // closed band
    p.density = {0, 1, 1, 1, 1, 0};   // uniform on [0.5, 4.5]
    EXPECT_NEAR(calcMedianFrequency(p, 0, 5), 2.5, kExactHz);
    EXPECT_NEAR(calcMedianFrequency(p, 2, 5), 3.0, kExactHz);   // band keeps bins 2..4
}

TEST(Spectrum, TwoEqualSinesGiveMeanOfFrequencies) {
    const double fs = 1000, f1 = 60, f2 = 140;
    SpectrumSettings s;
    s.segmentLength = 500;   // 2 Hz bins, both tones bin-centred
    const PowerSpectrum p = calcPowerSpectrum(sines({f1, f2}, fs, 3000), fs, s);
    EXPECT_NEAR(calcMeanFrequency(p, 10, 400), (f1 + f2) / 2, kExactHz);
    // Half the power lies in each tone: the split falls at the upper edge of f1's leakage.
    const double mdf = calcMedianFrequency(p, 10, 400);
    EXPECT_GT(mdf, f1);
    EXPECT_LT(mdf, f2);
    // Three times the amplitude at f2 moves MNF to (f1 + 9 f2) / 10.
    std::vector<double> x = sines({f1}, fs, 3000), y = sines({f2}, fs, 3000);
    for (std::size_t i = 0; i < x.size(); ++i) x[i] += 3 * y[i];
    EXPECT_NEAR(calcMeanFrequency(calcPowerSpectrum(x, fs, s), 10, 400), (f1 + 9 * f2) / 10,
                kExactHz);
}

TEST(Spectrum, PeriodogramSatisfiesParseval) {
    const double fs = 1000;
    for (std::size_t n : {3000u, 3001u}) {
        std::vector<double> x = whiteNoise(n, 0.3, 2);
        for (double& v : x) v += 1.5;   // removed as the mean
        SpectrumSettings s;
        s.window = SpectralWindow::Rectangular;
        const PowerSpectrum p = calcPowerSpectrum(x, fs, s);
        const double power =
            std::accumulate(p.density.begin(), p.density.end(), 0.0) * p.resolution;
        const double mean = std::accumulate(x.begin(), x.end(), 0.0) / n;
        double var = 0;
        for (double v : x) var += (v - mean) * (v - mean);
        var /= n;
        EXPECT_NEAR(power / var, 1.0, kParsevalRelTol) << n << " samples";
    }
}

TEST(Spectrum, WelchLevelOfWhiteNoise) {
    const double fs = 1000, sigma = 2e-3;
    SpectrumSettings s;
    s.segmentLength = 256;
    const PowerSpectrum p = calcPowerSpectrum(whiteNoise(60000, sigma, 4), fs, s);
    double mean = 0;
    for (std::size_t k = 1; k + 1 < p.density.size(); ++k) mean += p.density[k];
    mean /= p.density.size() - 2;
    EXPECT_NEAR(mean / (2 * sigma * sigma / fs), 1.0, kWhiteLevelRelTol);
}

TEST(Spectrum, WhiteNoiseFeaturesAtBandCentre) {
    const double fs = 1000, lo = 20, hi = 150;
    SpectrumSettings s;
    s.segmentLength = 1000;
    const PowerSpectrum p = calcPowerSpectrum(whiteNoise(240000, 1.0, 9), fs, s);
    EXPECT_NEAR(calcMeanFrequency(p, lo, hi), (lo + hi) / 2, kWhiteMnfTolHz);
    EXPECT_NEAR(calcMedianFrequency(p, lo, hi), (lo + hi) / 2, kWhiteMdfTolHz);
}

TEST(Spectrum, FilteredNoiseMnfMatchesResponse) {
    // MNF of white noise through H equals sum f |H(f)|^2 / sum |H(f)|^2 over the same bins.
    const double fs = 1000;
    const BiquadCascade bp = designButterworthBandPass(2, 30, 120, fs);
    const std::vector<double> y = filterForward(bp, whiteNoise(120000, 1.0, 13));
    SpectrumSettings s;
    s.segmentLength = 512;
    const PowerSpectrum p = calcPowerSpectrum(y, fs, s);
    double num = 0, den = 0;
    for (double f : p.frequency) {
        if (f < 10 || f > 400) continue;
        const double g = std::norm(calcFrequencyResponse(bp, f, fs));
        num += f * g;
        den += g;
    }
    EXPECT_NEAR(calcMeanFrequency(p, 10, 400) / (num / den), 1.0, kShapedMnfRelTol);
}

TEST(Spectrum, SilenceHasNoFrequency) {
    const PowerSpectrum p = calcPowerSpectrum(std::vector<double>(1000, 0.0), 1000);
    EXPECT_TRUE(std::isnan(calcMeanFrequency(p, 10, 400)));
    EXPECT_TRUE(std::isnan(calcMedianFrequency(p, 10, 400)));
}

TEST(Spectrum, BadInputNamesTheField) {
    const std::vector<double> x(1000, 1.0);
    auto expectField = [](auto f, const std::string& field) {
        try {
            f();
            ADD_FAILURE() << "expected a FieldError naming '" << field << "'";
        } catch (const FieldError& e) {
            EXPECT_EQ(e.getField(), field) << e.what();
        }
    };
    SpectrumSettings longSegment;
    longSegment.segmentLength = 2000;
    expectField([&] { calcPowerSpectrum(x, 1000, longSegment); }, "segmentLength");
    SpectrumSettings badOverlap;
    badOverlap.overlap = 1.0;
    expectField([&] { calcPowerSpectrum(x, 1000, badOverlap); }, "overlap");
    expectField([&] { calcPowerSpectrum(x, 0, SpectrumSettings{}); }, "sampleRate");
    const PowerSpectrum p = calcPowerSpectrum(x, 1000);
    expectField([&] { calcMeanFrequency(p, 100, 50); }, "fHigh");
    EXPECT_THROW(calcMedianFrequency(p, 100.2, 100.8), InputError);   // no bin in the band
}

}  // namespace
}  // namespace armsim

// Filters, moving RMS and the EMG acquisition chain against the analytic Butterworth magnitude, the
// designed frequency response (a second method for the time-domain realisation) and known values.
#include "basics/angles.h"
#include "basics/errors.h"
#include "experiments/signal.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <random>
#include <string>
#include <vector>

namespace armsim {
namespace {


// Tolerances.
constexpr double kEdgeDbTol = 0.1;             // -3 dB edges and flat passband (dB)
constexpr double kFormulaRelTol = 1e-6;        // designed |H| vs closed-form Butterworth magnitude
constexpr double kNotchDepthDb = -30.0;        // minimum notch depth at the centre (dB)
constexpr double kNotchSideDbTol = 1.0;        // allowed change at 20 and 100 Hz (dB)
constexpr double kNotchBandwidthRelTol = 0.03; // -3 dB bandwidth vs f0/Q at fs >= 20 f0 (warping)
constexpr double kSteadyAmplitudeRelTol = 1e-4;   // simulated steady-state tone vs |H|
constexpr double kSteadyPhaseTol = 1e-4;       // simulated steady-state phase vs arg H (rad)
constexpr double kResidualAbsTol = 1e-6;       // tone left at the notch centre (unit amplitude in)
constexpr double kConstantTol = 1e-9;          // zero-phase output of a constant
constexpr double kRmsRelTol = 1e-9;            // moving RMS of a sine, window of whole periods
constexpr double kChainGainRelTol = 0.01;      // acquisition gain in the passband (brief: 1 %)
constexpr double kChainResponseRelTol = 1e-4;  // acquired tone vs gain |H_chain|
constexpr double kNoiseRmsRelTol = 0.02;       // noise RMS vs response integral, 60 s (~6 sigma)

double toDb(double gain) { return 20 * std::log10(gain); }

// Independent restatement of the pre-warping map W = 2 fs tan(pi f / fs).
double warp(double f, double fs) { return 2 * fs * std::tan(kPi * f / fs); }

double butterworthLowPass(double f, double fc, int n, double fs) {
    return 1 / std::sqrt(1 + std::pow(warp(f, fs) / warp(fc, fs), 2 * n));
}
double butterworthHighPass(double f, double fc, int n, double fs) {
    return 1 / std::sqrt(1 + std::pow(warp(fc, fs) / warp(f, fs), 2 * n));
}
double butterworthBandPass(double f, double lo, double hi, int n, double fs) {
    const double w = warp(f, fs), wl = warp(lo, fs), wh = warp(hi, fs);
    const double omega = (w * w - wl * wh) / ((wh - wl) * w);
    return 1 / std::sqrt(1 + std::pow(omega, 2 * n));
}

std::vector<double> sine(double amplitude, double f, double fs, std::size_t n, double phase = 0) {
    std::vector<double> x(n);
    for (std::size_t i = 0; i < n; ++i) x[i] = amplitude * std::sin(2 * kPi * f * i / fs + phase);
    return x;
}

// Amplitude and phase of A sin(2 pi f t + phase) in y[begin, end), which must span whole periods.
struct Tone { double amplitude, phase; };
Tone fitTone(const std::vector<double>& y, double f, double fs, std::size_t begin,
             std::size_t end) {
    double s = 0, c = 0;
    for (std::size_t i = begin; i < end; ++i) {
        s += y[i] * std::sin(2 * kPi * f * i / fs);
        c += y[i] * std::cos(2 * kPi * f * i / fs);
    }
    s *= 2.0 / (end - begin);
    c *= 2.0 / (end - begin);
    return {std::hypot(s, c), std::atan2(c, s)};
}

double wrapAngle(double a) { return std::remainder(a, 2 * kPi); }

void expectFieldError(const std::function<void()>& f, const std::string& field) {
    try {
        f();
        ADD_FAILURE() << "expected an InputError naming '" << field << "'";
    } catch (const FieldError& e) {
        EXPECT_EQ(e.getField(), field) << e.what();
        EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
    }
}

// ---------------------------------------------------------------- Butterworth designs

TEST(Butterworth, BandPassEdgesAreMinus3dBAndPassbandFlat) {
    const double fs = 10000;
    const BiquadCascade bp = designButterworthBandPass(4, 10, 400, fs);
    const double minus3dB = toDb(1 / std::sqrt(2.0));
    EXPECT_NEAR(toDb(std::abs(calcFrequencyResponse(bp, 10, fs))), minus3dB, kEdgeDbTol);
    EXPECT_NEAR(toDb(std::abs(calcFrequencyResponse(bp, 400, fs))), minus3dB, kEdgeDbTol);
    EXPECT_NEAR(toDb(std::abs(calcFrequencyResponse(bp, 100, fs))), 0.0, kEdgeDbTol);
}

TEST(Butterworth, BandPassFollowsFormulaInStopBands) {
    const double fs = 10000;
    for (int order = 1; order <= 6; ++order) {
        const BiquadCascade bp = designButterworthBandPass(order, 10, 400, fs);
        EXPECT_EQ(bp.size(), std::size_t(order));
        for (double f : {1.0, 2000.0, 3.0, 25.0, 150.0, 700.0, 4900.0}) {
            const double expected = butterworthBandPass(f, 10, 400, order, fs);
            EXPECT_NEAR(std::abs(calcFrequencyResponse(bp, f, fs)) / expected, 1.0, kFormulaRelTol)
                << "order " << order << " at " << f << " Hz";
        }
    }
    // Order 4 is 80 dB/decade per edge: at 1 Hz and 2 kHz the formula gives about -80 and -56 dB.
    const BiquadCascade bp = designButterworthBandPass(4, 10, 400, fs);
    EXPECT_LT(toDb(std::abs(calcFrequencyResponse(bp, 1, fs))), -75);
    EXPECT_LT(toDb(std::abs(calcFrequencyResponse(bp, 2000, fs))), -50);
}

TEST(Butterworth, LowPassAndHighPassFollowFormula) {
    const double fs = 1000, fc = 100;
    for (int order = 1; order <= 7; ++order) {
        const BiquadCascade lp = designButterworthLowPass(order, fc, fs);
        const BiquadCascade hp = designButterworthHighPass(order, fc, fs);
        for (double f : {1.0, 30.0, 100.0, 180.0, 350.0, 490.0}) {
            EXPECT_NEAR(std::abs(calcFrequencyResponse(lp, f, fs)) /
                            butterworthLowPass(f, fc, order, fs), 1.0, kFormulaRelTol)
                << "low-pass order " << order << " at " << f << " Hz";
            EXPECT_NEAR(std::abs(calcFrequencyResponse(hp, f, fs)) /
                            butterworthHighPass(f, fc, order, fs), 1.0, kFormulaRelTol)
                << "high-pass order " << order << " at " << f << " Hz";
        }
    }
}

TEST(Butterworth, AllPolesInsideUnitCircle) {
    // Jury criterion for 1 + a1 z^-1 + a2 z^-2: |a2| < 1 and |a1| < 1 + a2.
    for (const BiquadCascade& c : {designButterworthBandPass(5, 10, 400, 10000),
                                   designButterworthLowPass(8, 450, 10000),
                                   designButterworthHighPass(3, 0.5, 1000),
                                   designNotch(50, 30, 10000)}) {
        for (const Biquad& s : c) {
            EXPECT_LT(std::abs(s.a2), 1.0);
            EXPECT_LT(std::abs(s.a1), 1.0 + s.a2);
        }
    }
}

TEST(Butterworth, RejectsCutoffsOutsideNyquist) {
    expectFieldError([] { designButterworthLowPass(4, 600, 1000); }, "cutoff");
    expectFieldError([] { designButterworthHighPass(0, 100, 1000); }, "order");
    expectFieldError([] { designButterworthBandPass(4, 400, 10, 1000); }, "lowEdge");
    expectFieldError([] { designNotch(50, -1, 1000); }, "quality");
}

// ---------------------------------------------------------------- notch

TEST(Notch, RemovesMainsAndSparesNeighbours) {
    for (double fs : {1000.0, 10000.0}) {
        const BiquadCascade notch = designNotch(50, 30, fs);
        EXPECT_LT(toDb(std::abs(calcFrequencyResponse(notch, 50, fs))), kNotchDepthDb);
        EXPECT_NEAR(toDb(std::abs(calcFrequencyResponse(notch, 20, fs))), 0.0, kNotchSideDbTol);
        EXPECT_NEAR(toDb(std::abs(calcFrequencyResponse(notch, 100, fs))), 0.0, kNotchSideDbTol);
    }
}

// Frequency in (a, b) where |H|^2 crosses 1/2 (bisection; |H|^2 - 1/2 changes sign once there).
double findHalfPower(const BiquadCascade& h, double a, double b, double fs) {
    const bool aAbove = std::norm(calcFrequencyResponse(h, a, fs)) > 0.5;
    for (int i = 0; i < 200; ++i) {
        const double m = 0.5 * (a + b);
        ((std::norm(calcFrequencyResponse(h, m, fs)) > 0.5) == aAbove ? a : b) = m;
    }
    return 0.5 * (a + b);
}

TEST(Notch, BandwidthMatchesQuality) {
    // The bilinear-mapped analog notch: edges satisfy T0 / (T2 - T1) = Q and T1 T2 = T0^2 with
    // T = tan(pi f / fs); the -3 dB bandwidth is close to f0 / Q for f0 << fs.
    for (double fs : {1000.0, 10000.0}) {
        for (double q : {30.0, 5.0}) {
            const BiquadCascade notch = designNotch(50, q, fs);
            const double f1 = findHalfPower(notch, 1e-3, 50, fs);
            const double f2 = findHalfPower(notch, 50, fs / 2 - 1e-3, fs);
            auto t = [fs](double f) { return std::tan(kPi * f / fs); };
            EXPECT_NEAR(t(50) / (t(f2) - t(f1)) / q, 1.0, kFormulaRelTol) << fs << " Hz, Q " << q;
            EXPECT_NEAR(t(f1) * t(f2) / (t(50) * t(50)), 1.0, kFormulaRelTol);
            EXPECT_NEAR((f2 - f1) / (50 / q), 1.0, kNotchBandwidthRelTol);
        }
    }
}

TEST(Notch, SteadyStateSineMatchesResponse) {
    const double fs = 1000;
    const std::size_t n = 20000, tail = 2000;   // 20 s; the notch transient decays as 0.995^n
    const BiquadCascade notch = designNotch(50, 30, fs);
    for (double f : {50.0, 49.0, 51.5, 45.0}) {
        const std::vector<double> y = filterForward(notch, sine(1, f, fs, n));
        const Tone t = fitTone(y, f, fs, n - tail, n);
        const std::complex<double> h = calcFrequencyResponse(notch, f, fs);
        if (f == 50.0) {
            EXPECT_NEAR(t.amplitude, std::abs(h), kResidualAbsTol);
        } else {
            EXPECT_NEAR(t.amplitude / std::abs(h), 1.0, kSteadyAmplitudeRelTol) << f << " Hz";
            EXPECT_NEAR(wrapAngle(t.phase - std::arg(h)), 0.0, kSteadyPhaseTol) << f << " Hz";
        }
    }
}

// ---------------------------------------------------------------- forward and zero-phase filtering

TEST(Filtering, ForwardSteadyStateMatchesResponse) {
    const double fs = 10000;
    const BiquadCascade bp = designButterworthBandPass(4, 10, 400, fs);
    for (double f : {13.0, 100.0, 390.0}) {
        const std::vector<double> y = filterForward(bp, sine(1, f, fs, 30000));
        const Tone t = fitTone(y, f, fs, 20000, 30000);
        const std::complex<double> h = calcFrequencyResponse(bp, f, fs);
        EXPECT_NEAR(t.amplitude / std::abs(h), 1.0, kSteadyAmplitudeRelTol) << f << " Hz";
        EXPECT_NEAR(wrapAngle(t.phase - std::arg(h)), 0.0, kSteadyPhaseTol) << f << " Hz";
    }
}

// Lag (samples) in [-maxLag, maxLag] maximising sum x[i] y[i + lag] over the middle of the signals.
int peakLag(const std::vector<double>& x, const std::vector<double>& y, int maxLag) {
    const int n = int(x.size());
    int best = 0;
    double bestValue = -1e300;
    for (int lag = -maxLag; lag <= maxLag; ++lag) {
        double s = 0;
        for (int i = n / 4; i < 3 * n / 4; ++i) s += x[i] * y[i + lag];
        if (s > bestValue) bestValue = s, best = lag;
    }
    return best;
}

TEST(Filtering, ZeroPhaseHasNoLag) {
    const double fs = 10000, f = 100;
    const BiquadCascade bp = designButterworthBandPass(4, 10, 400, fs);
    const std::vector<double> x = sine(1, f, fs, 20000);
    const int halfPeriod = int(fs / f / 2);

    const std::vector<double> yz = filterZeroPhase(bp, x);
    EXPECT_EQ(peakLag(x, yz, halfPeriod - 1), 0);
    const Tone t = fitTone(yz, f, fs, 5000, 15000);
    EXPECT_NEAR(t.amplitude, std::norm(calcFrequencyResponse(bp, f, fs)), kSteadyAmplitudeRelTol);

    // The same measurement sees the causal filter's lag, -arg H / (2 pi f) s.
    const std::vector<double> yf = filterForward(bp, x);
    const double expectedLag = -std::arg(calcFrequencyResponse(bp, f, fs)) / (2 * kPi * f) * fs;
    EXPECT_GT(std::abs(expectedLag), 5.0);
    EXPECT_NEAR(peakLag(x, yf, halfPeriod - 1), expectedLag, 1.0);
}

TEST(Filtering, ZeroPhaseEdgesStartInSteadyState) {
    const BiquadCascade lp = designButterworthLowPass(4, 10, 1000);
    const std::vector<double> x(500, 3.0);
    const std::vector<double> y = filterZeroPhase(lp, x);
    ASSERT_EQ(y.size(), x.size());
    for (double v : y) EXPECT_NEAR(v, 3.0, kConstantTol);
    // From rest, the causal filter starts far from the constant.
    EXPECT_LT(filterForward(lp, x)[0], 1.0);
}

TEST(Filtering, StreamingMatchesBlock) {
    const BiquadCascade bp = designButterworthBandPass(3, 20, 200, 2000);
    std::mt19937_64 rng(7);
    std::normal_distribution<double> noise;
    std::vector<double> x(3000);
    for (double& v : x) v = noise(rng);
    const std::vector<double> y = filterForward(bp, x);
    CascadeFilter f(bp);
    for (std::size_t i = 0; i < x.size(); ++i) ASSERT_DOUBLE_EQ(f.step(x[i]), y[i]);
}

// ---------------------------------------------------------------- moving RMS

TEST(MovingRms, SineGivesAmplitudeOverSqrt2) {
    const double fs = 1000, a = 2.5;
    const std::vector<double> x = sine(a, 50, fs, 3000, 0.3);
    const std::vector<double> r = calcMovingRms(x, fs, 0.1);   // five periods
    ASSERT_EQ(r.size(), x.size());
    for (std::size_t i = 50; i + 50 <= x.size(); ++i)
        ASSERT_NEAR(r[i] / (a / std::sqrt(2.0)), 1.0, kRmsRelTol) << "sample " << i;
    EXPECT_NEAR(calcRms(x) / (a / std::sqrt(2.0)), 1.0, kRmsRelTol);
    expectFieldError([&] { calcMovingRms(x, fs, 0.0); }, "window");
}

// ---------------------------------------------------------------- acquisition chain

TEST(Acquisition, AppliesGainInPassband) {
    const double fsIn = 10000, amplitude = 1e-6, f = 100;
    const EmgAcquisitionSettings s;
    auto rng = PortableRandom::fromSeed(1);
    const std::vector<double> y = calcAcquiredEmg(sine(amplitude, f, fsIn, 20000), fsIn, s, rng);
    ASSERT_EQ(y.size(), 2000u);
    const Tone t = fitTone(y, f, s.outputRate, 1000, 2000);
    EXPECT_NEAR(t.amplitude / 5e-3, 1.0, kChainGainRelTol);
    const std::complex<double> h = calcFrequencyResponse(designAcquisitionFilter(s, fsIn), f, fsIn);
    EXPECT_NEAR(t.amplitude / (s.gain * amplitude * std::abs(h)), 1.0, kChainResponseRelTol);
    EXPECT_NEAR(wrapAngle(t.phase - std::arg(h)), 0.0, kSteadyPhaseTol);
}

TEST(Acquisition, ZeroPhaseOptionHasNoPhaseShift) {
    const double fsIn = 5000, f = 80;
    EmgAcquisitionSettings s;
    s.zeroPhase = true;
    auto rng = PortableRandom::fromSeed(1);
    const std::vector<double> y = calcAcquiredEmg(sine(1e-6, f, fsIn, 20000), fsIn, s, rng);
    const Tone t = fitTone(y, f, s.outputRate, 1000, 3000);
    const std::complex<double> h = calcFrequencyResponse(designAcquisitionFilter(s, fsIn), f, fsIn);
    EXPECT_NEAR(t.amplitude / (s.gain * 1e-6 * std::norm(h)), 1.0, kChainResponseRelTol);
    EXPECT_NEAR(wrapAngle(t.phase), 0.0, kSteadyPhaseTol);
}

TEST(Acquisition, NotchRemovesMainsInterference) {
    const double fsIn = 10000;
    EmgAcquisitionSettings s;
    s.mainsAmplitude = 1e-3;
    const std::vector<double> zero(100000, 0.0);
    auto rng = PortableRandom::fromSeed(3);
    const std::vector<double> with = calcAcquiredEmg(zero, fsIn, s, rng);
    s.notch = false;
    const std::vector<double> without = calcAcquiredEmg(zero, fsIn, s, rng);
    const double full = s.gain * s.mainsAmplitude;
    // Without the notch the mains passes with the band-pass/anti-alias gain at 50 Hz.
    const std::complex<double> h =
        calcFrequencyResponse(designAcquisitionFilter(s, fsIn), 50, fsIn);
    EXPECT_NEAR(fitTone(without, 50, 1000, 5000, 10000).amplitude / (full * std::abs(h)), 1.0,
                kChainResponseRelTol);
    EXPECT_LT(toDb(fitTone(with, 50, 1000, 5000, 10000).amplitude / full), kNotchDepthDb);
}

TEST(Acquisition, NoiseRmsMatchesResponseIntegral) {
    const double fsIn = 10000;
    EmgAcquisitionSettings s;
    s.electrodeNoiseRms = 5e-6;
    const std::vector<double> zero(600000, 0.0);   // 60 s
    auto rng = PortableRandom::fromSeed(11);
    const std::vector<double> y = calcAcquiredEmg(zero, fsIn, s, rng);
    const double measured = calcRms(std::vector<double>(y.begin() + 1000, y.end()));

    // Density sigma^2 / (outputRate / 2) over 0..fsIn/2, shaped by |H|^2 (trapezoid, 0.05 Hz).
    const BiquadCascade h = designAcquisitionFilter(s, fsIn);
    const double df = 0.05;
    double integral = 0;
    for (double f = 0; f < fsIn / 2; f += df) {
        const double g0 = std::norm(calcFrequencyResponse(h, f, fsIn));
        const double g1 = std::norm(calcFrequencyResponse(h, f + df, fsIn));
        integral += 0.5 * (g0 + g1) * df;
    }
    const double expected =
        s.gain * s.electrodeNoiseRms * std::sqrt(integral / (s.outputRate / 2));
    EXPECT_NEAR(measured / expected, 1.0, kNoiseRmsRelTol);
}

TEST(Acquisition, SeededNoiseIsReproducible) {
    EmgAcquisitionSettings s;
    s.electrodeNoiseRms = 1e-6;
    s.mainsAmplitude = 1e-5;
    const std::vector<double> zero(5000, 0.0);
    auto a = PortableRandom::fromSeed(5), b = PortableRandom::fromSeed(5), c = PortableRandom::fromSeed(6);
    const std::vector<double> ya = calcAcquiredEmg(zero, 5000, s, a);
    EXPECT_EQ(ya, calcAcquiredEmg(zero, 5000, s, b));
    EXPECT_NE(ya, calcAcquiredEmg(zero, 5000, s, c));
}

TEST(Acquisition, BadSettingsNameTheField) {
    const std::vector<double> x(1000, 0.0);
    auto rng = PortableRandom::fromSeed(1);
    auto acquire = [&](const EmgAcquisitionSettings& s, double fsIn) {
        return [&x, &rng, s, fsIn] { calcAcquiredEmg(x, fsIn, s, rng); };
    };
    EmgAcquisitionSettings reversed;
    reversed.bandLow = 400;
    reversed.bandHigh = 10;
    expectFieldError(acquire(reversed, 10000), "bandLow");
    EmgAcquisitionSettings aboveNyquist;
    aboveNyquist.bandHigh = 600;
    expectFieldError(acquire(aboveNyquist, 10000), "bandHigh");
    expectFieldError(acquire(EmgAcquisitionSettings{}, 10500), "inputRate");
    expectFieldError(acquire(EmgAcquisitionSettings{}, 500), "inputRate");
    EmgAcquisitionSettings negativeNoise;
    negativeNoise.electrodeNoiseRms = -1e-6;
    expectFieldError(acquire(negativeNoise, 10000), "electrodeNoiseRms");
    EmgAcquisitionSettings badAlias;
    badAlias.antiAliasCutoff = 500;
    expectFieldError([&] { badAlias.validate(); }, "antiAliasCutoff");
}

}  // namespace
}  // namespace armsim

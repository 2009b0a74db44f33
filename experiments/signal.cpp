#include "experiments/signal.h"

#include "basics/angles.h"
#include "basics/bound.h"
#include "basics/format.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <utility>

namespace armsim {

namespace {

using Complex = std::complex<double>;

// Pre-warped analog frequency (rad/s) that the bilinear transform maps onto f:
// W = 2 fs tan(pi f / fs) (Oppenheim & Schafer, Discrete-Time Signal Processing, 3rd ed., 7.1.2).
double prewarp(double f, double fs) { return 2 * fs * std::tan(kPi * f / fs); }

// Bilinear transform of one analog root: s = 2 fs (z - 1)/(z + 1)  =>  z = (2 fs + s)/(2 fs - s).
Complex bilinear(Complex s, double fs) { return (2 * fs + s) / (2 * fs - s); }

// Pole k = 1..n of the normalised analog Butterworth low-pass (cutoff 1 rad/s), left half-plane:
// p_k = exp(j pi (2k + n - 1) / (2n)) (Oppenheim & Schafer 7.2.1; Parks & Burrus 1987).
// Poles k and n+1-k are conjugates; for odd n, k = (n+1)/2 gives p = -1.
Complex prototypePole(int k, int n) { return std::polar(1.0, kPi * (2 * k + n - 1) / (2.0 * n)); }

// Section with z-plane zeros q1, q2 and poles p1, p2, each pair real or complex-conjugate:
// (1 - q1 z^-1)(1 - q2 z^-1) / ((1 - p1 z^-1)(1 - p2 z^-1)).
Biquad makeSection(Complex q1, Complex q2, Complex p1, Complex p2) {
    Biquad s;
    s.b0 = 1;
    s.b1 = -(q1 + q2).real();
    s.b2 = (q1 * q2).real();
    s.a1 = -(p1 + p2).real();
    s.a2 = (p1 * p2).real();
    return s;
}

Biquad makeFirstOrderSection(double q, double p) {
    Biquad s;
    s.b0 = 1;
    s.b1 = -q;
    s.a1 = -p;
    return s;
}

Complex sectionResponse(const Biquad& s, double w) {
    const Complex z1 = std::polar(1.0, -w), z2 = z1 * z1;
    return (s.b0 + s.b1 * z1 + s.b2 * z2) / (1.0 + s.a1 * z1 + s.a2 * z2);
}

// Scales the numerator so that |H(e^{jw})| = 1.
void normaliseAt(Biquad& s, double w) {
    const double g = 1.0 / std::abs(sectionResponse(s, w));
    s.b0 *= g;
    s.b1 *= g;
    s.b2 *= g;
}

void checkDesign(int order, double f, const char* field, double fs) {
    checkField("sampleRate", fs, Bound::positive("Hz"));
    checkField("order", order, Bound::closed(1, 20));
    checkField(field, f, Bound::open(0, fs / 2, "Hz"));
}

}  // namespace

BiquadCascade designButterworthLowPass(int order, double cutoff, double sampleRate) {
    checkDesign(order, cutoff, "cutoff", sampleRate);
    const double wc = prewarp(cutoff, sampleRate);
    BiquadCascade out;
    // Low-pass to low-pass: s -> s / Wc, so analog poles Wc p_k; all n zeros at s = inf -> z = -1.
    for (int k = 1; k <= order / 2; ++k) {
        const Complex p = bilinear(wc * prototypePole(k, order), sampleRate);
        out.push_back(makeSection(-1.0, -1.0, p, std::conj(p)));
    }
    if (order % 2) out.push_back(makeFirstOrderSection(-1.0, bilinear(-wc, sampleRate).real()));
    for (Biquad& s : out) normaliseAt(s, 0.0);
    return out;
}

BiquadCascade designButterworthHighPass(int order, double cutoff, double sampleRate) {
    checkDesign(order, cutoff, "cutoff", sampleRate);
    const double wc = prewarp(cutoff, sampleRate);
    BiquadCascade out;
    // Low-pass to high-pass: s -> Wc / s, so analog poles Wc / p_k; all n zeros at s = 0 -> z = +1.
    for (int k = 1; k <= order / 2; ++k) {
        const Complex p = bilinear(wc / prototypePole(k, order), sampleRate);
        out.push_back(makeSection(1.0, 1.0, p, std::conj(p)));
    }
    if (order % 2) out.push_back(makeFirstOrderSection(1.0, bilinear(-wc, sampleRate).real()));
    for (Biquad& s : out) normaliseAt(s, kPi);
    return out;
}

BiquadCascade designButterworthBandPass(int order, double lowEdge, double highEdge,
                                        double sampleRate) {
    checkDesign(order, highEdge, "highEdge", sampleRate);
    checkField("lowEdge", lowEdge, Bound::open(0, highEdge, "Hz"));
    const double wl = prewarp(lowEdge, sampleRate), wh = prewarp(highEdge, sampleRate);
    const double w0sq = wl * wh, bw = wh - wl;
    // Low-pass to band-pass: s -> (s^2 + W0^2)/(B s). Each prototype pole p gives the two roots of
    // s^2 - p B s + W0^2 = 0, s = (p B +- sqrt(p^2 B^2 - 4 W0^2)) / 2 (Oppenheim & Schafer,
    // table 7.1). n zeros at s = 0 (z = +1) and n at s = inf (z = -1): one of each per section.
    auto roots = [&](Complex p) {
        const Complex d = std::sqrt(p * p * bw * bw - 4.0 * w0sq);
        return std::make_pair(bilinear((p * bw + d) / 2.0, sampleRate),
                              bilinear((p * bw - d) / 2.0, sampleRate));
    };
    BiquadCascade out;
    for (int k = 1; k <= order / 2; ++k) {
        // Roots of p and of conj(p) are conjugates of each other: pair each with its conjugate.
        const auto [r1, r2] = roots(prototypePole(k, order));
        out.push_back(makeSection(1.0, -1.0, r1, std::conj(r1)));
        out.push_back(makeSection(1.0, -1.0, r2, std::conj(r2)));
    }
    if (order % 2) {
        // p = -1: the two roots are a conjugate pair or both real; one section either way.
        const auto [r1, r2] = roots(-1.0);
        out.push_back(makeSection(1.0, -1.0, r1, r2));
    }
    // Unit gain at the centre W0, which maps to w0 = 2 atan(W0 / (2 fs)).
    const double w0 = 2 * std::atan(std::sqrt(w0sq) / (2 * sampleRate));
    for (Biquad& s : out) normaliseAt(s, w0);
    return out;
}

BiquadCascade designNotch(double centre, double quality, double sampleRate) {
    checkField("sampleRate", sampleRate, Bound::positive("Hz"));
    checkField("centre", centre, Bound::open(0, sampleRate / 2, "Hz"));
    checkField("quality", quality, Bound::positive());
    // RBJ Audio EQ Cookbook, notch: w0 = 2 pi f0/fs, alpha = sin(w0)/(2Q);
    // b = (1, -2 cos w0, 1), a = (1 + alpha, -2 cos w0, 1 - alpha), divided by a0.
    const double w0 = 2 * kPi * centre / sampleRate;
    const double alpha = std::sin(w0) / (2 * quality), c = std::cos(w0), a0 = 1 + alpha;
    Biquad s;
    s.b0 = 1 / a0;
    s.b1 = -2 * c / a0;
    s.b2 = 1 / a0;
    s.a1 = -2 * c / a0;
    s.a2 = (1 - alpha) / a0;
    return {s};
}

std::complex<double> calcFrequencyResponse(const BiquadCascade& filter, double f,
                                           double sampleRate) {
    const double w = 2 * kPi * f / sampleRate;
    Complex h = 1.0;
    for (const Biquad& s : filter) h *= sectionResponse(s, w);
    return h;
}

CascadeFilter::CascadeFilter(BiquadCascade filter)
    : cascade_(std::move(filter)), state_(2 * cascade_.size(), 0.0) {}

double CascadeFilter::step(double x) {
    double* z = state_.data();
    for (const Biquad& s : cascade_) {
        // Direct form II transposed.
        const double y = s.b0 * x + z[0];
        z[0] = s.b1 * x - s.a1 * y + z[1];
        z[1] = s.b2 * x - s.a2 * y;
        x = y;
        z += 2;
    }
    return x;
}

void CascadeFilter::reset() { std::fill(state_.begin(), state_.end(), 0.0); }

void CascadeFilter::setSteadyState(double x) {
    // For constant input u and output y = H(1) u, the DF2T states are
    // z2 = b2 u - a2 y and z1 = (b1 + b2) u - (a1 + a2) y (as SciPy's sosfilt_zi).
    double* z = state_.data();
    for (const Biquad& s : cascade_) {
        const double y = x * (s.b0 + s.b1 + s.b2) / (1 + s.a1 + s.a2);
        z[0] = (s.b1 + s.b2) * x - (s.a1 + s.a2) * y;
        z[1] = s.b2 * x - s.a2 * y;
        x = y;
        z += 2;
    }
}

std::vector<double> filterForward(const BiquadCascade& filter, const std::vector<double>& x) {
    CascadeFilter f(filter);
    std::vector<double> y(x.size());
    for (std::size_t i = 0; i < x.size(); ++i) y[i] = f.step(x[i]);
    return y;
}

std::vector<double> filterZeroPhase(const BiquadCascade& filter, const std::vector<double>& x,
                                    int padLength) {
    const std::size_t n = x.size();
    if (n == 0) return {};
    std::size_t pad = padLength < 0 ? 3 * (2 * filter.size() + 1) : std::size_t(padLength);
    pad = std::min(pad, n - 1);
    // Odd extension: 2 x[0] - x[pad..1], x, 2 x[n-1] - x[n-2..n-1-pad].
    std::vector<double> e(n + 2 * pad);
    for (std::size_t i = 0; i < pad; ++i) {
        e[i] = 2 * x[0] - x[pad - i];
        e[pad + n + i] = 2 * x[n - 1] - x[n - 2 - i];
    }
    std::copy(x.begin(), x.end(), e.begin() + pad);

    CascadeFilter f(filter);
    f.setSteadyState(e.front());
    for (double& v : e) v = f.step(v);
    f.setSteadyState(e.back());
    for (auto it = e.rbegin(); it != e.rend(); ++it) *it = f.step(*it);
    return std::vector<double>(e.begin() + pad, e.begin() + pad + n);
}

double calcRms(const std::vector<double>& x) {
    if (x.empty()) return 0;
    long double s = 0;
    for (double v : x) s += (long double)v * v;
    return std::sqrt(double(s / x.size()));
}

std::vector<double> calcMovingRms(const std::vector<double>& x, double sampleRate,
                                  double window) {
    checkField("sampleRate", sampleRate, Bound::positive("Hz"));
    checkField("window", window, Bound::positive("s"));
    const std::ptrdiff_t n = x.size();
    const std::ptrdiff_t w = std::max<std::ptrdiff_t>(1, std::llround(window * sampleRate));
    std::vector<long double> cum(n + 1, 0.0L);   // prefix sums of squares
    for (std::ptrdiff_t i = 0; i < n; ++i) cum[i + 1] = cum[i] + (long double)x[i] * x[i];
    std::vector<double> y(n);
    for (std::ptrdiff_t i = 0; i < n; ++i) {
        const std::ptrdiff_t lo = std::max<std::ptrdiff_t>(0, i - w / 2);
        const std::ptrdiff_t hi = std::min<std::ptrdiff_t>(n, i - w / 2 + w);
        y[i] = std::sqrt(std::max(0.0, double((cum[hi] - cum[lo]) / (hi - lo))));
    }
    return y;
}

void EmgAcquisitionSettings::validate() const {
    checkField("gain", gain, Bound::positive());
    checkField("outputRate", outputRate, Bound::positive("Hz"));
    const double nyquist = outputRate / 2;
    checkField("bandHigh", bandHigh, Bound::open(0, nyquist, "Hz"));
    checkField("bandLow", bandLow, Bound::open(0, bandHigh, "Hz"));
    checkField("bandOrder", bandOrder, Bound::closed(1, 10));
    checkField("mainsFrequency", mainsFrequency, Bound::open(0, nyquist, "Hz"));
    checkField("notchQuality", notchQuality, Bound::positive());
    checkField("antiAliasCutoff", antiAliasCutoff, Bound::open(0, nyquist, "Hz"));
    checkField("antiAliasOrder", antiAliasOrder, Bound::closed(1, 20));
    // At the electrodes a surface EMG is some 0.1-5 mV and their noise some uV: 10 mV of noise, or 1 V of
    // mains, is a value in other units (mV typed as V).
    checkField("mainsAmplitude", mainsAmplitude, Bound::closed(0, 1, "V"));
    checkField("electrodeNoiseRms", electrodeNoiseRms, Bound::closed(0, 0.01, "V"));
}

namespace {
// The integer ratio inputRate / outputRate, or FieldError naming "inputRate".
std::size_t decimationFactor(double inputRate, double outputRate) {
    checkField("inputRate", inputRate, Bound::positive("Hz"));
    const double ratio = inputRate / outputRate;
    const double m = std::round(ratio);
    if (m < 1 || std::abs(ratio - m) > 1e-9 * ratio)
        throw FieldError("inputRate", "= " + formatNumber(inputRate, 10) +
                                          ": expected an integer multiple of outputRate = " +
                                          formatNumber(outputRate, 10) + " (Hz)");
    return std::size_t(m);
}
}  // namespace

BiquadCascade designAcquisitionFilter(const EmgAcquisitionSettings& settings, double inputRate) {
    settings.validate();
    decimationFactor(inputRate, settings.outputRate);
    BiquadCascade out = designButterworthBandPass(settings.bandOrder, settings.bandLow,
                                                  settings.bandHigh, inputRate);
    if (settings.notch) {
        const BiquadCascade n =
            designNotch(settings.mainsFrequency, settings.notchQuality, inputRate);
        out.insert(out.end(), n.begin(), n.end());
    }
    const BiquadCascade aa =
        designButterworthLowPass(settings.antiAliasOrder, settings.antiAliasCutoff, inputRate);
    out.insert(out.end(), aa.begin(), aa.end());
    return out;
}

std::vector<double> calcAcquiredEmg(const std::vector<double>& electrodeVoltage, double inputRate,
                                    const EmgAcquisitionSettings& settings, PortableRandom& rng) {
    const BiquadCascade filter = designAcquisitionFilter(settings, inputRate);
    const std::size_t m = decimationFactor(inputRate, settings.outputRate);
    const std::size_t n = electrodeVoltage.size();

    std::vector<double> v(electrodeVoltage);
    if (settings.mainsAmplitude > 0) {
        const double phase = rng.drawUniform(0, 2 * kPi);
        const double w = 2 * kPi * settings.mainsFrequency / inputRate;
        for (std::size_t i = 0; i < n; ++i)
            v[i] += settings.mainsAmplitude * std::sin(w * double(i) + phase);
    }
    if (settings.electrodeNoiseRms > 0) {
        // White noise of RMS sigma over 0..outputRate/2 has per-sample RMS
        // sigma sqrt(inputRate / outputRate) at the internal rate.
        const double sd = settings.electrodeNoiseRms * std::sqrt(double(m));
        for (double& x : v) x += sd * rng.drawNormal();
    }
    for (double& x : v) x *= settings.gain;

    const std::vector<double> y =
        settings.zeroPhase ? filterZeroPhase(filter, v) : filterForward(filter, v);
    std::vector<double> out;
    out.reserve(n / m + 1);
    for (std::size_t i = 0; i < n; i += m) out.push_back(y[i]);
    return out;
}

}  // namespace armsim

#include "experiments/spectrum.h"

#include "basics/angles.h"
#include "basics/bound.h"

#include <fftw3.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <mutex>
#include <numeric>
#include <string>
#include <utility>

namespace armsim {

namespace {


// FFTW's planner is not thread-safe (FFTW 3.3 manual, 5.2 "Thread safety"); only fftw_execute is.
std::mutex& fftwPlannerMutex() {
    static std::mutex m;
    return m;
}

// A real-to-complex transform of fixed length with its own FFTW buffers.
class RealFft {
public:
    explicit RealFft(std::size_t n)
        : in_(fftw_alloc_real(n)), out_(fftw_alloc_complex(n / 2 + 1)) {
        std::lock_guard<std::mutex> lock(fftwPlannerMutex());
        plan_ = fftw_plan_dft_r2c_1d(int(n), in_, out_, FFTW_ESTIMATE);
    }
    ~RealFft() {
        {
            std::lock_guard<std::mutex> lock(fftwPlannerMutex());
            fftw_destroy_plan(plan_);
        }
        fftw_free(in_);
        fftw_free(out_);
    }
    RealFft(const RealFft&) = delete;
    RealFft& operator=(const RealFft&) = delete;

    double* input() { return in_; }
    void execute() { fftw_execute(plan_); }
    double power(std::size_t k) const { return out_[k][0] * out_[k][0] + out_[k][1] * out_[k][1]; }

private:
    double* in_;
    fftw_complex* out_;
    fftw_plan plan_ = nullptr;
};

// Indices [first, last) of the bins whose centres lie in [fLow, fHigh].
std::pair<std::size_t, std::size_t> bandBins(const PowerSpectrum& s, double fLow, double fHigh) {
    checkField("fLow", fLow, Bound::nonNegative("Hz"));
    checkField("fHigh", fHigh, Bound{fLow, 1e300, true, false, "Hz"});
    std::size_t first = 0;
    while (first < s.frequency.size() && s.frequency[first] < fLow) ++first;
    std::size_t last = first;
    while (last < s.frequency.size() && s.frequency[last] <= fHigh) ++last;
    if (first == last)
        throw InputError("band [" + std::to_string(fLow) + ", " + std::to_string(fHigh) +
                         "] Hz contains no spectral bin (resolution " +
                         std::to_string(s.resolution) + " Hz)");
    return {first, last};
}

}  // namespace

void SpectrumSettings::validate() const {
    checkField("overlap", overlap, Bound{0, 1, false, true, ""});
}

PowerSpectrum calcPowerSpectrum(const std::vector<double>& x, double sampleRate,
                                const SpectrumSettings& settings) {
    settings.validate();
    checkField("sampleRate", sampleRate, Bound::positive("Hz"));
    const std::size_t len = settings.segmentLength ? settings.segmentLength : x.size();
    if (len < 2 || len > x.size())
        throw FieldError("segmentLength", "= " + std::to_string(len) +
                                              ": expected 2 to the signal length (" +
                                              std::to_string(x.size()) + " samples)");
    const std::size_t hop =
        std::max<std::size_t>(1, len - std::size_t(std::llround(settings.overlap * len)));

    std::vector<double> w(len, 1.0);
    if (settings.window == SpectralWindow::Hann)
        for (std::size_t i = 0; i < len; ++i) w[i] = 0.5 * (1 - std::cos(2 * kPi * i / len));
    const double sumW2 = std::inner_product(w.begin(), w.end(), w.begin(), 0.0);

    const std::size_t nBins = len / 2 + 1;
    PowerSpectrum out;
    out.resolution = sampleRate / len;
    out.frequency.resize(nBins);
    out.density.assign(nBins, 0.0);
    for (std::size_t k = 0; k < nBins; ++k) out.frequency[k] = k * out.resolution;

    RealFft fft(len);
    double* in = fft.input();
    for (std::size_t start = 0; start + len <= x.size(); start += hop) {
        double mean = 0;
        if (settings.removeMean) {
            for (std::size_t i = 0; i < len; ++i) mean += x[start + i];
            mean /= len;
        }
        for (std::size_t i = 0; i < len; ++i) in[i] = (x[start + i] - mean) * w[i];
        fft.execute();
        for (std::size_t k = 0; k < nBins; ++k) out.density[k] += fft.power(k);
        ++out.segmentCount;
    }
    // One-sided density: 2 |X_k|^2 / (fs sum w^2), except DC and (even L) Nyquist.
    const double scale = 1.0 / (sampleRate * sumW2 * out.segmentCount);
    for (std::size_t k = 0; k < nBins; ++k) {
        const bool unpaired = k == 0 || (len % 2 == 0 && k == nBins - 1);
        out.density[k] *= unpaired ? scale : 2 * scale;
    }
    return out;
}

double calcMeanFrequency(const PowerSpectrum& spectrum, double fLow, double fHigh) {
    const auto [first, last] = bandBins(spectrum, fLow, fHigh);
    double num = 0, den = 0;
    for (std::size_t k = first; k < last; ++k) {
        num += spectrum.frequency[k] * spectrum.density[k];
        den += spectrum.density[k];
    }
    return den > 0 ? num / den : std::numeric_limits<double>::quiet_NaN();
}

double calcMedianFrequency(const PowerSpectrum& spectrum, double fLow, double fHigh) {
    const auto [first, last] = bandBins(spectrum, fLow, fHigh);
    double total = 0;
    for (std::size_t k = first; k < last; ++k) total += spectrum.density[k];
    if (!(total > 0)) return std::numeric_limits<double>::quiet_NaN();
    const double half = total / 2, df = spectrum.resolution;
    double cum = 0;
    for (std::size_t k = first; k < last; ++k) {
        const double p = spectrum.density[k];
        if (p > 0 && cum + p >= half)
            return spectrum.frequency[k] - df / 2 + df * (half - cum) / p;
        cum += p;
    }
    return spectrum.frequency[last - 1] + df / 2;   // not reached except by rounding
}

}  // namespace armsim

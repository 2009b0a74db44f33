#include "experiments/emg.h"

#include "basics/bound.h"
#include "experiments/spectrum.h"

#include <algorithm>
#include <cmath>

namespace armsim {

namespace {

constexpr double kMinIntervalFraction = 0.2;  // shortest inter-spike interval drawn, in mean intervals

const FibreType& fibreTypeOf(const VirtualMuscle& muscle, int unit) {
    const MuscleParameters& p = muscle.getParameters();
    const FibreType& t = muscle.getUnits()[unit].slow ? p.slow : p.fast;
    if (!(t.f05 > 0))
        throw InputError("fibre type '" + t.name + "' of muscle '" + p.name +
                         "' has no f05 (firing rate at half-maximal force, pps): add it to the fibre-type "
                         "file to synthesise EMG");
    return t;
}

}  // namespace

void SurfaceEmgSettings::validate() const {
    acquisition.validate();
    checkField("internal_rate", internalRate, Bound::closed(1, 1e6, "Hz"));
    const double ratio = internalRate / acquisition.outputRate;
    if (std::round(ratio) < 1 || std::abs(ratio - std::round(ratio)) > 1e-9 * ratio)
        throw FieldError("internal_rate", "= " + std::to_string(internalRate) +
                                              ": expected an integer multiple of the output rate " +
                                              std::to_string(acquisition.outputRate) + " (Hz)");
    checkField("isi_cv", isiCv, Bound::closed(0, 0.5));
    checkField("trains_per_unit", trainsPerUnit, Bound::closed(1, 1000));
    checkField("muap_amplitude", muapAmplitude, Bound::nonNegative("V"));
    // The MUAP must be resolved (its spectrum peaks at 0.225 / lambda): lambda >= 8 / internal_rate.
    const Bound width{8.0 / internalRate, 0.05, false, false, "s; lower bound 8 / internal_rate"};
    checkField("muap_width_slow", muapWidthSlow, width);
    checkField("muap_width_fast", muapWidthFast, width);
}

double calcFiringRate(const VirtualMuscle& muscle, int unit, double U) {
    const FibreType& t = fibreTypeOf(muscle, unit);
    const MotorUnit& mu = muscle.getUnits()[unit];
    return calcEnvelopeFrequency(muscle.getParameters().coefficients, mu.threshold, U) * t.f05;
}

double calcHermiteRodriguezMuap(double t, double lambda) {
    const double x = t / lambda;
    return std::sqrt(2.0 * std::exp(1.0)) * x * std::exp(-x * x);
}

SurfaceEmg calcSurfaceEmg(const VirtualMuscle& muscle, const ActivationProfile& activation, double t0,
                          std::size_t numSamples, const SurfaceEmgSettings& settings, PortableRandom& rng) {
    settings.validate();
    const double fs = settings.internalRate;
    const std::size_t m = std::size_t(std::round(fs / settings.acquisition.outputRate));
    const std::size_t n = numSamples * m;
    const int numUnits = muscle.getNumUnits();
    for (int u = 0; u < numUnits; ++u) fibreTypeOf(muscle, u);  // every present type needs f05

    std::vector<double> U(n);
    for (std::size_t i = 0; i < n; ++i) U[i] = activation.getValue(t0 + double(i) / fs);

    SurfaceEmg out;
    out.sampleRate = settings.acquisition.outputRate;
    out.spikeCounts.assign(numUnits, 0);
    std::vector<double> electrode(n, 0.0);
    auto drawInterval = [&] {  // in mean intervals
        double theta;
        do theta = 1.0 + settings.isiCv * rng.drawNormal();
        while (theta < kMinIntervalFraction);
        return theta;
    };

    std::vector<double> rate(n), cumulative(n);
    for (int u = 0; u < numUnits; ++u) {
        const MotorUnit& mu = muscle.getUnits()[u];
        const double lambda = mu.slow ? settings.muapWidthSlow : settings.muapWidthFast;
        const double amplitude =
            settings.muapAmplitude * mu.fraction / std::sqrt(double(settings.trainsPerUnit));
        // MUAP template, starting at the spike (centre 4 lambda later: the waveform is causal).
        const std::size_t centre = std::size_t(std::ceil(4.0 * lambda * fs));
        std::vector<double> muap(2 * centre + 1);
        for (std::size_t j = 0; j < muap.size(); ++j)
            muap[j] = amplitude * calcHermiteRodriguezMuap((double(j) - double(centre)) / fs, lambda);

        double sum = 0;
        for (std::size_t i = 0; i < n; ++i) {
            rate[i] = calcFiringRate(muscle, u, U[i]);
            sum += rate[i] / fs;
            cumulative[i] = sum;  // expected spikes since t0
        }
        for (int k = 0; k < settings.trainsPerUnit; ++k) {
            std::size_t i = 0;
            while (i < n) {
                while (i < n && rate[i] <= 0) ++i;  // not recruited
                if (i >= n) break;
                // Recruited at i: start with a random phase of the first interval.
                double theta = drawInterval();
                double reference = cumulative[i] - rng.drawUniform() * theta;
                for (; i < n && rate[i] > 0; ++i) {
                    if (cumulative[i] - reference < theta) continue;
                    ++out.spikeCounts[u];
                    const std::size_t len = std::min(muap.size(), n - i);
                    double* v = electrode.data() + i;
                    for (std::size_t j = 0; j < len; ++j) v[j] += muap[j];
                    reference += theta;
                    theta = drawInterval();
                }
            }
        }
    }

    out.emg = calcAcquiredEmg(electrode, fs, settings.acquisition, rng);
    for (double& x : out.emg) x /= settings.acquisition.gain;
    return out;
}

EmgFeatures calcEmgFeatures(const std::vector<double>& emg, double sampleRate, std::size_t from, std::size_t to,
                            double fLow, double fHigh, std::size_t segmentLength) {
    if (!(from < to && to <= emg.size() && to - from >= 2))
        throw InputError("EMG feature window [" + std::to_string(from) + ", " + std::to_string(to) +
                         ") must hold at least 2 of the " + std::to_string(emg.size()) + " samples");
    const std::vector<double> x(emg.begin() + std::ptrdiff_t(from), emg.begin() + std::ptrdiff_t(to));
    EmgFeatures f;
    f.rms = calcRms(x);
    SpectrumSettings s;
    s.segmentLength = std::min(segmentLength, x.size());
    const PowerSpectrum p = calcPowerSpectrum(x, sampleRate, s);
    f.mnf = calcMeanFrequency(p, fLow, fHigh);
    f.mdf = calcMedianFrequency(p, fLow, fHigh);
    return f;
}

}  // namespace armsim

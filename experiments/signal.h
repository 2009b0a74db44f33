// Digital filters and time-domain features for synthetic surface EMG: Butterworth low-, high- and
// band-pass and notch designs as cascades of second-order sections, forward and zero-phase
// filtering, moving RMS, and the thesis acquisition chain (amplifier, band-pass, notch, anti-alias,
// decimation).
// Framework-free (standard library only). Frequencies in Hz, times in s, signals in V.
// Why not liquid-dsp (Debian libliquid-dev 1.5), measured 2026-11-27 against these designs at 10 kHz:
// its designs and filters are single precision (the 4th-order 10 Hz high-pass differs by 1.1e-3
// relative, 0.009 dB, near 2 Hz; the tests hold the closed form to 1e-6), its band-pass takes a
// prototype cut-off and a centre through a digital transform, so the -3 dB edges cannot be set as
// here (best mapping of 10-400 Hz: 0.95 dB off), and it has no Q notch or zero-phase filtering.
#pragma once

#include "basics/portable_random.h"

#include <complex>
#include <cstddef>
#include <vector>

namespace armsim {

/// One second-order section with a0 = 1:
///   H(z) = (b0 + b1 z^-1 + b2 z^-2) / (1 + a1 z^-1 + a2 z^-2).
/// A first-order section has b2 = a2 = 0.
struct Biquad {
    double b0 = 1, b1 = 0, b2 = 0;   ///< numerator coefficients
    double a1 = 0, a2 = 0;           ///< denominator coefficients (a0 = 1)
};

/// A filter as a cascade of second-order sections, applied in order. Its design sampling rate is
/// not stored: pass the same rate to calcFrequencyResponse.
using BiquadCascade = std::vector<Biquad>;

/// Butterworth low-pass of order N (1..20), -3 dB at cutoff, designed by the bilinear transform
/// with the cutoff pre-warped, so |H(f)| = 1/sqrt(1 + (W(f)/W(cutoff))^(2N)) exactly, where
/// W(f) = 2 fs tan(pi f / fs). Requires 0 < cutoff < sampleRate/2 (else FieldError "cutoff").
BiquadCascade designButterworthLowPass(int order, double cutoff, double sampleRate);

/// Butterworth high-pass of order N, -3 dB at cutoff: |H(f)| = 1/sqrt(1 + (W(cutoff)/W(f))^(2N)).
BiquadCascade designButterworthHighPass(int order, double cutoff, double sampleRate);

/// Butterworth band-pass from the order-N low-pass prototype by s -> (s^2 + W0^2)/(B s), with
/// W0^2 = W(lowEdge) W(highEdge) and B = W(highEdge) - W(lowEdge) (pre-warped). The result has 2N
/// poles in N sections (MATLAB/SciPy butter(N, [lo, hi]) convention), -3 dB at both edges, unit
/// gain at the centre, and |H(f)| = 1/sqrt(1 + Omega^(2N)) with Omega = (W^2 - W0^2)/(B W).
/// Requires 0 < lowEdge < highEdge < sampleRate/2.
BiquadCascade designButterworthBandPass(int order, double lowEdge, double highEdge,
                                        double sampleRate);

/// Second-order IIR notch (R. Bristow-Johnson, "Cookbook formulae for audio EQ biquad filter
/// coefficients"): zero gain at centre, unit gain at DC and Nyquist. Its -3 dB edges f1 < f2
/// satisfy T(centre) / (T(f2) - T(f1)) = quality with T(f) = tan(pi f / fs), so the bandwidth is
/// about centre/quality when centre << fs. Requires 0 < centre < sampleRate/2 and quality > 0.
BiquadCascade designNotch(double centre, double quality, double sampleRate);

/// H(e^{jw}) of the cascade at frequency f (Hz), w = 2 pi f / sampleRate.
std::complex<double> calcFrequencyResponse(const BiquadCascade& filter, double f,
                                           double sampleRate);

/// Streaming realisation of a cascade (direct form II transposed), for sample-by-sample use.
class CascadeFilter {
public:
    CascadeFilter() = default;
    explicit CascadeFilter(BiquadCascade filter);
    /// Filters one sample.
    double step(double x);
    /// Zero state (the filter output starts from rest).
    void reset();
    /// The state reached after an infinitely long constant input x (so a signal that starts at x
    /// causes no start-up transient).
    void setSteadyState(double x);
    const BiquadCascade& getCascade() const { return cascade_; }
private:
    BiquadCascade cascade_;
    std::vector<double> state_;   // two per section
};

/// Causal filtering from rest (zero initial state), like MATLAB filter / SciPy sosfilt.
std::vector<double> filterForward(const BiquadCascade& filter, const std::vector<double>& x);

/// Zero-phase forward-backward filtering (magnitude |H|^2, no phase lag), following SciPy's
/// sosfiltfilt: the signal is extended at both ends by an odd reflection of padLength samples
/// (default 3 (2 nSections + 1), clipped to x.size() - 1) and each pass starts from the steady
/// state of its first sample, so edges carry no start-up transient.
std::vector<double> filterZeroPhase(const BiquadCascade& filter, const std::vector<double>& x,
                                    int padLength = -1);

/// Root mean square of x (0 for an empty signal).
double calcRms(const std::vector<double>& x);

/// Moving RMS over a centred window of round(window * sampleRate) samples (at least 1); near the
/// ends the window is truncated to the available samples. Same length as x. Throws InputError
/// naming "sampleRate" or "window" unless both are > 0.
std::vector<double> calcMovingRms(const std::vector<double>& x, double sampleRate,
                                  double window);

/// The surface EMG acquisition chain of the thesis [5.1, 5.3.2]: electrodes -> amplifier (gain) ->
/// band-pass -> mains notch -> anti-alias low-pass -> sampling at outputRate. All filters are
/// designed at the internal (input) rate; the input is the voltage between the electrodes.
struct EmgAcquisitionSettings {
    double gain = 5000;                ///< amplifier gain (V/V) [thesis 5.3.2]
    double bandLow = 10;               ///< band-pass lower -3 dB edge (Hz) [thesis 5.3.2]
    double bandHigh = 400;             ///< band-pass upper -3 dB edge (Hz) [thesis 5.3.2]
    int bandOrder = 4;                 ///< Butterworth prototype order of the band-pass (1..10)
    double mainsFrequency = 50;        ///< mains frequency: notch centre and interference (Hz)
    bool notch = true;                 ///< apply the mains notch [thesis 5.3.2]
    double notchQuality = 30;          ///< notch quality factor: centre / -3 dB bandwidth
    double antiAliasCutoff = 450;      ///< anti-alias Butterworth low-pass -3 dB cutoff (Hz)
    int antiAliasOrder = 8;            ///< anti-alias low-pass order (1..20)
    double outputRate = 1000;          ///< sampling rate of the acquired EMG (Hz) [thesis 5.3.2]
    double mainsAmplitude = 0;         ///< mains amplitude at the electrodes (V); 0 = off
    /// RMS of white Gaussian electrode noise at the electrodes (V), measured over 0..outputRate/2
    /// (so independent of the internal rate); 0 = off.
    double electrodeNoiseRms = 0;
    bool zeroPhase = false;            ///< forward-backward filtering (|H|^2, no lag), not causal

    /// Throws armsim::FieldError naming the field, value and bound: gain > 0;
    /// 0 < bandLow < bandHigh < outputRate/2; 0 < mainsFrequency < outputRate/2; notchQuality > 0;
    /// 0 < antiAliasCutoff < outputRate/2; orders in range; mains in [0, 1] V, electrode noise in [0, 0.01] V.
    void validate() const;
};

/// The chain's whole filter (band-pass, notch, anti-alias) designed at inputRate, without gain.
BiquadCascade designAcquisitionFilter(const EmgAcquisitionSettings& settings, double inputRate);

/// Acquires EMG: adds mains interference (random phase) and electrode noise to electrodeVoltage
/// (sampled at inputRate), amplifies, filters and keeps every (inputRate/outputRate)-th sample:
/// output sample i is at the time of input sample i * M, M = inputRate/outputRate. Randomness comes
/// only from rng. Throws FieldError naming "inputRate" unless it is an integer multiple (>= 1) of
/// outputRate, and whatever settings.validate() throws.
std::vector<double> calcAcquiredEmg(const std::vector<double>& electrodeVoltage, double inputRate,
                                    const EmgAcquisitionSettings& settings, PortableRandom& rng);

}  // namespace armsim

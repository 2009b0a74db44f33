// Power spectra (FFTW, periodogram or Welch average) and the spectral EMG features mean frequency
// (MNF) and median frequency (MDF). Framework-free (FFTW only, hidden in the .cpp).
#pragma once

#include <cstddef>
#include <vector>

namespace armsim {

enum class SpectralWindow {
    Rectangular,   ///< no taper
    Hann,          ///< periodic Hann, w[n] = 0.5 (1 - cos(2 pi n / L)), as Welch (1967) / SciPy
};

/// How calcPowerSpectrum segments, tapers and averages a signal.
struct SpectrumSettings {
    /// Welch segment length (samples); 0 = one periodogram of the whole signal.
    std::size_t segmentLength = 0;
    double overlap = 0.5;                          ///< fraction shared by adjacent segments, [0, 1)
    SpectralWindow window = SpectralWindow::Hann;  ///< taper applied to every segment
    bool removeMean = true;                        ///< subtract each segment's mean before the FFT

    /// Throws FieldError naming "overlap" unless 0 <= overlap < 1.
    void validate() const;
};

/// One-sided power spectral density on the bins k * resolution, k = 0..L/2 (L = segment length).
struct PowerSpectrum {
    double resolution = 0;           ///< bin spacing sampleRate / L (Hz)
    std::vector<double> frequency;   ///< bin centres (Hz)
    std::vector<double> density;     ///< PSD (unit^2/Hz); sum(density) * resolution = power
    int segmentCount = 0;            ///< segments averaged
};

/// PSD of x sampled at sampleRate (Hz) by Welch's method (P. Welch, IEEE Trans. Audio
/// Electroacoust. 15(2), 1967): segments of L samples, hop L - round(overlap L), each tapered by
/// the window, real-to-complex FFT (FFTW), |X_k|^2 scaled by 2 / (sampleRate sum w^2) (DC and
/// Nyquist bins not doubled), averaged over segments: SciPy welch(scaling='density') scaling.
/// Throws InputError naming "sampleRate" or "segmentLength" (the signal must hold at least one
/// segment of >= 2 samples). Thread-safe (FFTW planning is serialised internally).
PowerSpectrum calcPowerSpectrum(const std::vector<double>& x, double sampleRate,
                                const SpectrumSettings& settings = {});

/// Mean frequency MNF = sum f_k P_k / sum P_k over the bins whose centres lie in [fLow, fHigh].
/// Returns NaN when that band holds no power. Throws InputError naming "fLow"/"fHigh" unless
/// 0 <= fLow < fHigh and the band contains at least one bin.
double calcMeanFrequency(const PowerSpectrum& spectrum, double fLow, double fHigh);

/// Median frequency MDF: the frequency that splits the power of the bins in [fLow, fHigh] into
/// equal halves. Each bin's power is spread uniformly over [f_k - df/2, f_k + df/2] and the split
/// point is interpolated linearly within the bin where the cumulative power crosses one half.
/// Returns NaN when the band holds no power; throws like calcMeanFrequency.
double calcMedianFrequency(const PowerSpectrum& spectrum, double fLow, double fHigh);

}  // namespace armsim

// Synthetic surface EMG generated from the Virtual Muscle's own motor units, and its features.
//
// Each recruited model unit u fires at rate r_u(t) = fenv_u(U(t)) * f0.5 of its fibre type (pps), the
// same envelope frequency that drives the muscle's force (muscles/virtual_muscle.h). A model unit
// stands for a pool of real motor units (thesis 7.3: "each unit represents a group of real motor
// units"): it drives trainsPerUnit independent renewal spike trains with Gaussian inter-spike
// intervals (mean 1/r_u, coefficient of variation isiCv). Every spike adds a first-order
// Hermite-Rodriguez motor-unit action potential (Lo Conte, Merletti & Sandri 1994, IEEE TBME
// 41(12):1147) whose peak grows with the unit's PCSA fraction. The electrode voltage then passes the
// thesis acquisition chain (experiments/signal.h: gain, band-pass, notch, noise, mains, sampling).
// Framework-free apart from the muscle model.
#pragma once

#include "basics/portable_random.h"
#include "experiments/signal.h"
#include "muscles/activation.h"
#include "muscles/virtual_muscle.h"

#include <cstddef>
#include <vector>

namespace armsim {

/// Settings of the synthetic surface EMG. Defaults give about 0.9 mV RMS (peaks within about +-4 mV) at
/// the electrodes at full activation for the thesis biceps (3 + 3 units), with a mean frequency near
/// 80 Hz and power mostly in 20-150 Hz (thesis 5.3.2: raw EMG within about +-5 mV, 20-150 Hz).
struct SurfaceEmgSettings {
    /// Rate at which spikes and MUAPs are synthesised [Hz]; an integer multiple of
    /// acquisition.outputRate (the chain decimates to it).
    double internalRate = 10000;
    /// Inter-spike-interval coefficient of variation [1]; 0.1-0.2 is typical of voluntary
    /// contractions (e.g. Clamann 1969, Biophys J 9:1233).
    double isiCv = 0.15;
    /// Independent spike trains (real motor units) per model unit [1]. 1 = one train per model unit.
    int trainsPerUnit = 20;
    /// Peak MUAP voltage at the electrodes of a unit whose PCSA fraction is 1, for trainsPerUnit = 1
    /// [V]. A train of unit u peaks at muapAmplitude * p_u / sqrt(trainsPerUnit), so the EMG power
    /// does not depend on trainsPerUnit. Sets the EMG scale (electrode placement); model choice.
    double muapAmplitude = 5e-3;
    /// Time scale lambda of the Hermite-Rodriguez MUAP of slow units [s] (duration about 8 lambda);
    /// model choice giving a spectral peak near 0.225/lambda = 56 Hz.
    double muapWidthSlow = 4.0e-3;
    /// The same for fast units [s] (faster conduction, shorter MUAP: peak near 75 Hz).
    double muapWidthFast = 3.0e-3;
    /// The acquisition chain (thesis: gain 5000, 10-400 Hz, 50 Hz notch, 1000 Hz).
    EmgAcquisitionSettings acquisition;

    /// Throws FieldError naming the field for a value out of range.
    void validate() const;
};

/// Firing rate of unit u at activation U [pps]: fenv(thr_u, U) times its fibre type's f0.5; 0 below
/// the unit's threshold. Throws InputError if that fibre type has no f05.
double calcFiringRate(const VirtualMuscle& muscle, int unit, double U);

/// First-order Hermite-Rodriguez function scaled to a unit peak:
/// h(t) = sqrt(2 e) (t / lambda) exp(-(t / lambda)^2); peak +1 at t = lambda / sqrt(2), odd, zero mean.
double calcHermiteRodriguezMuap(double t, double lambda);

/// A synthetic surface EMG record.
struct SurfaceEmg {
    double sampleRate = 0;            ///< acquisition.outputRate [Hz]
    /// Acquired EMG referred to the electrodes (amplifier output / gain) [V]; sample k at
    /// t0 + k / sampleRate.
    std::vector<double> emg;
    /// Spikes fired by each model unit (sum over its trains), in unit order.
    std::vector<long> spikeCounts;
};

/// Synthesises numSamples of acquired EMG for the activation U(t) from t0 on. All randomness
/// (spike phases and intervals, electrode noise, mains phase) comes from rng. Throws InputError if
/// a fibre type with units has no f05, and what settings.validate() throws.
SurfaceEmg calcSurfaceEmg(const VirtualMuscle& muscle, const ActivationProfile& activation, double t0,
                          std::size_t numSamples, const SurfaceEmgSettings& settings, PortableRandom& rng);

/// Amplitude and spectral features of an EMG window.
struct EmgFeatures {
    double rms = 0;   ///< root mean square [V]
    double mnf = 0;   ///< mean frequency over the band [Hz] (NaN: no power)
    double mdf = 0;   ///< median frequency over the band [Hz] (NaN: no power)
};

/// Features of emg[from, to): RMS, and MNF / MDF of its Welch spectrum (Hann segments of
/// segmentLength samples, half overlap; the whole window if shorter) over [fLow, fHigh].
EmgFeatures calcEmgFeatures(const std::vector<double>& emg, double sampleRate, std::size_t from, std::size_t to,
                            double fLow = 10, double fHigh = 400, std::size_t segmentLength = 256);

}  // namespace armsim

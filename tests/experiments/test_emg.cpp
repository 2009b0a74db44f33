// Synthetic surface EMG from the muscle's motor units: f0.5 in the fibre-type file, firing rates,
// spike counts, the MUAP shape, amplitude against activation, spectrum, reproducibility.
#include "basics/errors.h"
#include "experiments/emg.h"
#include "experiments/spectrum.h"
#include "muscles/muscle_file.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

using namespace armsim;
namespace fs = std::filesystem;

namespace {

const std::string kAssets = ARMSIM_ASSET_DIR;
constexpr double kThesisEmgPeak = 5e-3;        // thesis 5.3.2: raw surface EMG within about +-5 mV
constexpr double kThesisBandFraction = 0.5;    // thesis 5.3.2: power "mostly" in 20-150 Hz

VirtualMuscle thesisMuscle() {
    return VirtualMuscle(loadMuscleParameters(kAssets + "/muscles/biceps_long_head.yaml"));
}

/// Constant activation U for `seconds` of acquired EMG (1000 Hz) with the default settings.
SurfaceEmg constantEmg(const VirtualMuscle& m, double U, double seconds, std::uint64_t seed,
                       const SurfaceEmgSettings& s = {}) {
    auto rng = PortableRandom::fromSeed(seed);
    return calcSurfaceEmg(m, ActivationProfile::constant(U), 0.0, std::size_t(seconds * 1000), s, rng);
}

std::string readText(const std::string& path) {
    std::ifstream in(path);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
}

}  // namespace

TEST(FibreTypeF05, ShippedFileGivesTwelveAndTwentyPps) {
    const MuscleParameters p = loadMuscleParameters(kAssets + "/muscles/biceps_long_head.yaml");
    EXPECT_EQ(p.slow.f05, 12.0);  // assets/muscles/human_fibre_types.yaml, inferred from the Tf scaling
    EXPECT_EQ(p.fast.f05, 20.0);
}

TEST(FibreTypeF05, NegativeValueIsAnErrorNamingFileLineAndField) {
    const fs::path dir = fs::temp_directory_path() / ("armsim_f05_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    std::string types = readText(kAssets + "/muscles/human_fibre_types.yaml");
    const std::string slowLine = "  f05: 12";
    const std::size_t at = types.find(slowLine);
    ASSERT_NE(at, std::string::npos);
    types.replace(at, slowLine.size(), "  f05: -3");
    int line = 1;
    for (std::size_t i = 0; i < at; ++i) line += types[i] == '\n';
    std::ofstream(dir / "types.yaml") << types;
    FibreType slow, fast;
    MuscleCoefficients c;
    try {
        loadFibreTypes((dir / "types.yaml").string(), slow, fast, c);
        FAIL() << "expected an error";
    } catch (const InputError& e) {
        const std::string msg = e.what();
        EXPECT_NE(msg.find("types.yaml:" + std::to_string(line)), std::string::npos) << msg;
        EXPECT_NE(msg.find("slow.f05"), std::string::npos) << msg;
        EXPECT_NE(msg.find("-3"), std::string::npos) << msg;
    }
    fs::remove_all(dir);
}

TEST(SurfaceEmg, MissingF05IsAnErrorNamingIt) {
    MuscleParameters p = thesisMuscle().getParameters();
    p.fast.f05 = 0;  // "not given"
    const VirtualMuscle m(p);
    auto rng = PortableRandom::fromSeed(1);
    try {
        calcSurfaceEmg(m, ActivationProfile::constant(1), 0, 100, {}, rng);
        FAIL() << "expected an error";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("'fast'"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("f05"), std::string::npos) << e.what();
    }
}

TEST(SurfaceEmg, FiringRateIsEnvelopeFrequencyTimesF05) {
    const VirtualMuscle m = thesisMuscle();
    const MuscleCoefficients& c = m.getParameters().coefficients;
    for (int u = 0; u < m.getNumUnits(); ++u) {
        const MotorUnit& mu = m.getUnits()[u];
        const double f05 = mu.slow ? 12.0 : 20.0;
        EXPECT_DOUBLE_EQ(calcFiringRate(m, u, 1.0), c.fmax * f05);        // every unit at fmax at U = 1
        EXPECT_DOUBLE_EQ(calcFiringRate(m, u, mu.threshold), c.fmin * f05);  // fmin at recruitment
        EXPECT_EQ(calcFiringRate(m, u, 0.999 * mu.threshold), 0.0);        // silent below threshold
    }
}

TEST(SurfaceEmg, SpikeCountsMatchTheFiringRates) {
    const VirtualMuscle m = thesisMuscle();
    constexpr double kSeconds = 10, kU = 0.9;
    constexpr double kSpikeCountRelTol = 0.02;  // renewal counts: sd = cv sqrt(N r T) ~ 0.2 % here
    SurfaceEmgSettings s;
    const SurfaceEmg e = constantEmg(m, kU, kSeconds, 7, s);
    for (int u = 0; u < m.getNumUnits(); ++u) {
        const double expected = calcFiringRate(m, u, kU) * kSeconds * s.trainsPerUnit;
        EXPECT_NEAR(double(e.spikeCounts[u]), expected, kSpikeCountRelTol * expected) << "unit " << u;
    }
}

TEST(SurfaceEmg, HermiteRodriguezMuapHasUnitPeakAndZeroMean) {
    constexpr double kLambda = 3e-3, kTol = 1e-12;
    EXPECT_NEAR(calcHermiteRodriguezMuap(kLambda / std::sqrt(2.0), kLambda), 1.0, kTol);
    EXPECT_NEAR(calcHermiteRodriguezMuap(-kLambda / std::sqrt(2.0), kLambda), -1.0, kTol);
    double area = 0, peak = 0;
    const double dt = kLambda / 1000;
    for (double t = -8 * kLambda; t <= 8 * kLambda; t += dt) {
        area += calcHermiteRodriguezMuap(t, kLambda) * dt;
        peak = std::max(peak, calcHermiteRodriguezMuap(t, kLambda));
    }
    constexpr double kAreaTol = 1e-9;  // s, rectangle rule on an odd function
    EXPECT_NEAR(area, 0.0, kAreaTol);
    EXPECT_LE(peak, 1.0 + kTol);
}

TEST(SurfaceEmg, RmsRisesMonotonicallyWithActivation) {
    const VirtualMuscle m = thesisMuscle();
    double previous = -1;  // U = 0: no spikes and no noise by default, RMS 0
    for (int k = 0; k <= 10; ++k) {
        const double U = 0.1 * k;
        const SurfaceEmg e = constantEmg(m, U, 3.0, 100 + k);
        const double rms = calcEmgFeatures(e.emg, e.sampleRate, 1000, e.emg.size()).rms;  // skip the first second
        EXPECT_GT(rms, previous) << "U = " << U;
        previous = rms;
    }
}

TEST(SurfaceEmg, AtRestOnlyTheElectrodeNoiseRemains) {
    const VirtualMuscle m = thesisMuscle();
    SurfaceEmgSettings s;
    s.acquisition.electrodeNoiseRms = 5e-6;
    const SurfaceEmg e = constantEmg(m, 0.0, 2.0, 3, s);
    for (long c : e.spikeCounts) EXPECT_EQ(c, 0);
    // White noise through the 10-400 Hz band keeps about sqrt(390 / 500) of its RMS.
    const double rms = calcEmgFeatures(e.emg, e.sampleRate, 500, e.emg.size()).rms;
    constexpr double kNoiseRmsRelTol = 0.1;  // 1500 samples of noise: RMS within a few %
    EXPECT_NEAR(rms, 5e-6 * std::sqrt(390.0 / 500.0), kNoiseRmsRelTol * 5e-6);
}

TEST(SurfaceEmg, PowerIsMostlyIn20To150HzAndAmplitudeWithinThesisRange) {
    // Thesis 5.3.2: raw surface EMG within about +-5 mV, power mostly in 20-150 Hz.
    const VirtualMuscle m = thesisMuscle();
    const SurfaceEmg e = constantEmg(m, 1.0, 4.0, 11);
    const std::vector<double> x(e.emg.begin() + 1000, e.emg.end());
    SpectrumSettings ss;
    ss.segmentLength = 256;
    const PowerSpectrum p = calcPowerSpectrum(x, e.sampleRate, ss);
    double inBand = 0, total = 0;
    for (std::size_t k = 0; k < p.frequency.size(); ++k) {
        total += p.density[k];
        if (p.frequency[k] >= 20 && p.frequency[k] <= 150) inBand += p.density[k];
    }
    EXPECT_GT(inBand / total, kThesisBandFraction);
    double peak = 0;
    for (double v : x) peak = std::max(peak, std::abs(v));
    EXPECT_LT(peak, kThesisEmgPeak);
    EXPECT_GT(peak, 0.2 * kThesisEmgPeak);  // and not orders of magnitude below it
}

TEST(SurfaceEmg, SameSeedSameSignalOtherSeedOtherSignal) {
    const VirtualMuscle m = thesisMuscle();
    const SurfaceEmg a = constantEmg(m, 0.5, 1.0, 42), b = constantEmg(m, 0.5, 1.0, 42), c = constantEmg(m, 0.5, 1.0, 43);
    EXPECT_EQ(a.emg, b.emg);
    EXPECT_NE(a.emg, c.emg);
}

TEST(SurfaceEmg, BadSettingsNameTheField) {
    const VirtualMuscle m = thesisMuscle();
    auto rng = PortableRandom::fromSeed(1);
    SurfaceEmgSettings s;
    s.internalRate = 2500;  // not a multiple of 1000 Hz
    try {
        calcSurfaceEmg(m, ActivationProfile::constant(1), 0, 10, s, rng);
        FAIL();
    } catch (const FieldError& e) {
        EXPECT_EQ(e.getField(), "internal_rate");
    }
    s = {};
    s.isiCv = -0.1;
    EXPECT_THROW(calcSurfaceEmg(m, ActivationProfile::constant(1), 0, 10, s, rng), FieldError);
}

TEST(EmgFeatures, WindowOfASineGivesItsRmsAndFrequency) {
    constexpr double kRate = 1000, kF = 62.5, kAmp = 2e-3;  // 62.5 Hz = a whole number of bins of 256 at 1 kHz
    std::vector<double> x(4000);
    for (std::size_t i = 0; i < x.size(); ++i) x[i] = kAmp * std::sin(2 * M_PI * kF * double(i) / kRate);
    constexpr double kRmsRelTol = 1e-3, kFrequencyTol = 1.0;  // whole periods; 3.9 Hz bins, symmetric leakage
    const EmgFeatures f = calcEmgFeatures(x, kRate, 1000, 3048);
    EXPECT_NEAR(f.rms, kAmp / std::sqrt(2.0), kRmsRelTol * kAmp);
    EXPECT_NEAR(f.mnf, kF, kFrequencyTol);
    EXPECT_NEAR(f.mdf, kF, kFrequencyTol);
    EXPECT_THROW(calcEmgFeatures(x, kRate, 10, 11), InputError);
}

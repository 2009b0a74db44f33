// Shared fixtures of the identification tests: the biceps long head, a "truth" muscle and
// noise-free synthetic data made by the steady model.
#pragma once

#include "identification/identifier.h"
#include "model/geometry.h"
#include "muscles/muscle_file.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>
#include <unistd.h>
#include <vector>

namespace armsim::test {

/// Thesis Table 7.2 "desired" parameters, used as the truth of synthetic data.
constexpr double kTrueMass = 0.336;           // kg
constexpr double kTrueTendonLength = 0.245;   // m
/// Thesis start (Table 7.2, 7.3).
constexpr double kStartMass = 0.330;          // kg
constexpr double kStartTendonLength = 0.22;   // m
/// Thesis MVC angles [deg] (section 6.1.2).
inline const std::vector<double> kThesisAngles{std::begin(kThesisMvcAnglesDeg), std::end(kThesisMvcAnglesDeg)};

inline MuscleParameters loadBiceps() {
    return loadMuscleParameters(std::string(ARMSIM_ASSET_DIR) + "/muscles/biceps_long_head.yaml");
}

inline MuscleParameters makeTruth() {
    MuscleParameters p = loadBiceps();
    p.mass = kTrueMass;
    p.optimalTendonLength = kTrueTendonLength;
    return p;
}

/// Observations at the given paths [m] with the forces the steady model gives for `truth`.
inline ObservationSet makeSyntheticData(const MuscleParameters& truth, const std::vector<double>& paths,
                                        const std::string& name = "synthetic") {
    ObservationSet set;
    set.source = name;
    for (double P : paths) {
        Observation o;
        o.pathLength = P;
        set.points.push_back(o);
    }
    const std::vector<double> y = SteadyForceModel().calcForces(truth, set.points);
    for (std::size_t k = 0; k < y.size(); ++k) set.points[k].force = y[k];
    return set;
}

inline std::vector<double> thesisAnglePaths() {
    std::vector<double> paths;
    for (double deg : kThesisAngles) paths.push_back(calcThesisPathLength(degToRad(deg)));
    return paths;
}

inline IdentificationProblem makeProblem(const ObservationSet& data, double mass = kStartMass,
                                         double tendon = kStartTendonLength) {
    IdentificationProblem pr;
    pr.base = loadBiceps();
    pr.data = data;
    pr.unknowns = makeDefaultUnknowns();
    pr.unknowns[0].start = mass;
    pr.unknowns[1].start = tendon;
    return pr;
}

/// A unique temporary path.
inline std::filesystem::path tempPath(const std::string& name) {
    return std::filesystem::temp_directory_path() /
           ("armsim_ident_" + std::to_string(::getpid()) + "_" + name);
}

}  // namespace armsim::test

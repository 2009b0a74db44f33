// Measured muscle forces for identification: one Observation per (path length, activation, force),
// read from CSV and validated once. Framework-free.
#pragma once

#include "basics/numbers.h"

#include <functional>
#include <string>
#include <vector>

namespace armsim {

/// Rows a force data set may hold (the covariance and reports grow with their square: 10000 rows took 9 GB).
constexpr int kMaxForceRows = 1000;

class Table;

/// One measured isometric force.
struct Observation {
    double pathLength = 0;   ///< musculotendon path length P [m]
    double activation = 1;   ///< neural activation U [1], 0..1 (MVC data: 1)
    double force = 0;        ///< measured muscle force [N]
    double angle = kNaN;  ///< included elbow angle theta [rad] when the file gave one, else NaN
    int trial = 0;           ///< trial number (CSV column `trial`; 0 when absent)
    int subject = 0;         ///< subject number (CSV column `subject`; 0 when absent)
    int line = 0;            ///< line in the source file (0: not read from a file)
};

/// A set of observations and where they came from (for messages).
struct ObservationSet {
    std::string source;                 ///< file name, or a description for built-in data
    std::vector<Observation> points;

    /// Number of distinct (path length, activation) pairs.
    int countDistinctPoints() const;
    /// "file:line" of point i (the source alone when it has no line).
    std::string where(int i) const;
};

/// Path length [m] as a function of the included elbow angle theta [rad].
using PathFromAngle = std::function<double(double angleRad)>;

/// The thesis's straight-line biceps: calcBicepsPathLength (model/geometry.h) with the default arm's
/// A = 0.37 m and B = 0.06 m (thesis 6.1.2; P(90 deg) = 37.48 cm, the thesis's "37.5 cm"; P(180 deg) =
/// 43 cm). The default angle to path conversion; another arm injects its own (makeArmPathFromAngle).
double calcThesisPathLength(double angleRad);

/// How to read a force file.
struct ObservationOptions {
    PathFromAngle pathFromAngle = calcThesisPathLength;  ///< used for an `angle_deg` column
    int subject = -1;    ///< keep only this subject (-1: keep all)
};

/// Reads a CSV force file (Table::readCsv: header line, '#' comment lines). Columns: exactly one of
/// `path_m`, `path_cm`, `angle_deg` (included elbow angle, 180 = extended), then `force_N`, and
/// optionally `trial`, `subject`, `activation` (default 1). Unknown columns are errors.
/// Throws InputError naming file, line, column and value for: a non-finite value, a negative force,
/// a path <= 0, an angle outside (0, 180] deg, an activation outside [0, 1], a non-integer trial or
/// subject, and a duplicate point (same subject, trial, path and activation as an earlier line).
ObservationSet readObservations(const std::string& path, const ObservationOptions& options = {});
/// The same from a table already in memory (columns as in the file); `source` names it in messages.
ObservationSet makeObservations(const Table& table, const std::string& source, const ObservationOptions& options = {});

/// Points without forces at the included elbow angles anglesDeg [deg] (path lengths from
/// pathFromAngle, activation 1): the conditions a synthetic data set is computed at.
ObservationSet makeAnglePoints(const std::vector<double>& anglesDeg, const PathFromAngle& pathFromAngle);

/// Validates an in-memory set with the same rules as readObservations (InputError naming source,
/// line or index, field and value).
void validateObservations(const ObservationSet& set);

}  // namespace armsim

// An OpenSim model scored against anatomy targets (model/anatomy_targets.h) the way armsim models are:
// one coordinate taken as the elbow (its value in degrees as flexion, its positive direction as
// flexion), the other coordinates at their defaults, the moment arms by virtual work and the steady
// MVC curves with the muscles that pull each way fully excited and the others at none (as `model show`
// draws them). What a .osim file does not say is not scored: volumes (no muscle mass) and the forearm
// targets (no armsim forearm).
#pragma once

#include "model/anatomy_targets.h"
#include "model/osim_file.h"

#include <array>
#include <string>
#include <vector>

namespace armsim {

class OsimArm;

/// The coordinate named (--coordinate), or the model's only one; InputError naming the option and the
/// model's coordinates otherwise, or for a translational one.
int findOsimSweptCoordinate(const OsimArm& arm, const std::string& name);

/// The curves of a built model about its coordinate j at flexionDeg (the coordinate's values [deg],
/// taken as given). minFlexionDeg and maxFlexionDeg are the coordinate's range [deg].
AnatomyCurves calcOsimAnatomyCurves(const OsimArm& arm, int j, const std::vector<double>& flexionDeg);

/// The model's curves at flexionDeg (the coordinate's values [deg], within its range); muscleModel as
/// OsimArm's. minFlexionDeg and maxFlexionDeg are the coordinate's range [deg].
AnatomyCurves calcOsimAnatomyCurves(const OsimModel& model, const std::string& coordinate,
                                    const std::vector<double>& flexionDeg, const std::string& muscleModel = "");

/// Coordinate j's range [deg], rounded to 1e-6 deg (a file's 2.26893 rad reads 130 deg).
std::array<double, 2> getOsimCoordinateRangeDeg(const OsimArm& arm, int j);
/// The same for a coordinate named as findOsimSweptCoordinate takes it; muscleModel
/// as OsimArm's (the model is built to find the coordinate).
std::array<double, 2> getOsimCoordinateRangeDeg(const OsimModel& model, const std::string& coordinate,
                                                const std::string& muscleModel = "");

}  // namespace armsim

// Reading muscle parameter files (assets/muscles/*.yaml). Framework-free.
#pragma once

#include "basics/bound.h"
#include "muscles/virtual_muscle.h"

#include <string>

namespace armsim {

/// Directory of the shipped assets: $ARMSIM_ASSETS if set (InputError naming it when it has no models/),
/// else an installed command's <prefix>/share/armsim/assets, else the source tree's assets/.
std::string getAssetDirectory();
/// Resolves name against the asset directory unless it is an existing path.
std::string findAsset(const std::string& name);

/// Reads a fibre-type file: slow and fast coefficient sets and the whole-muscle coefficients.
void loadFibreTypes(const std::string& path, FibreType& slow, FibreType& fast, MuscleCoefficients& c);

/// A model file's defaults for its muscles: each replaces the fibre-type file's value unless the
/// muscle gives its own key (0: none given).
struct MuscleDefaults {
    double specificTension = 0;  ///< sigma [N/m^2]; 0: the fibre-type file's
    double maxFiringRate = 0;    ///< fmax, every unit's firing rate at full drive [f0.5]; 0: the fibre-type file's
};

/// Reads a muscle file (morphometry, fibre fractions, motor units, and a reference to its fibre-type
/// file, relative to the muscle file), with a model's defaults under the file's own keys. Unknown keys
/// and out-of-bound values throw InputError naming file, line, field, value and bound.
MuscleParameters loadMuscleParameters(const std::string& path, const MuscleDefaults& defaults = {});

class ParamNode;
/// Reads the fields of a muscle file present in root into p (all of them when required): one of mass
/// [kg], max_isometric_force [N] (mass = F0 L0 rho / sigma) and volume [m^3] (mass = rho V, so
/// F0 = sigma V / L0), optimal_fascicle_length, optimal_tendon_length or tendon_slack_length [m]
/// (L0T = slack / LrT, see model/model_file.h), max_path_length, pennation_angle [rad] (Hill-type models),
/// fibre_fractions, motor_units, fibre_types, specific_tension [N/m^2], max_firing_rate [f0.5]. Each of
/// sigma and fmax is, in order of precedence: the muscle's own key, the model's default when > 0, the
/// fibre-type file's; the defaults are applied only where root reads a fibre-type file (or when
/// required), so values read earlier (a `parameters:` file's) are kept. Does not validate.
void readMuscleFields(const ParamNode& root, MuscleParameters& p, bool required, const MuscleDefaults& defaults);
/// Plausible specific tension [N/m^2]: 1-200 N/cm^2 (in vivo 25-30, Virtual Muscle 31.8; model files
/// fitted to strong subjects imply up to ~140).
Bound getSpecificTensionBound();
/// Plausible fmax [f0.5]: above Virtual Muscle's fmin (0.5) and at most 8 (human motor units at MVC
/// fire up to about 4x the mean rate, Bellemare et al. 1983).
Bound getMaxFiringRateBound();

}  // namespace armsim

// The registry of muscle models: a model file's `muscle_model:` names one, and every muscle of an arm
// is built through it. A muscle's morphometry always comes as Virtual Muscle parameters (mass, L0,
// L0T, P_max, pennation; model/model_file.h states the conversions from OpenSim's F0 and slack
// length); each model's own coefficients come as named numbers (defaults in assets/muscles/<file>).
// Adding a model: one file pair implementing MuscleModel and one line in getMuscleModelTypes().
#pragma once

#include "muscles/muscle_model.h"
#include "muscles/virtual_muscle.h"

#include <map>
#include <memory>
#include <string>
#include <vector>

namespace armsim {

/// What a muscle model is built from.
struct MuscleModelInput {
    MuscleParameters params;                      ///< validated morphometry (Virtual Muscle parameters)
    std::map<std::string, double> coefficients;  ///< the model's own coefficients by key (others default)
};

/// One registered muscle model.
struct MuscleModelType {
    std::string name;                          ///< registry name, as model files write it
    std::string description;                   ///< one line for listings
    std::vector<std::string> coefficientKeys;  ///< the keys a model file may give it
    std::string coefficientFile;               ///< assets/muscles/ file with its shipped coefficients ("": none)
    std::shared_ptr<const MuscleModel> (*build)(const MuscleModelInput&);
};

/// Every registered model ("virtual_muscle" first: the default).
const std::vector<MuscleModelType>& getMuscleModelTypes();
/// The model called name; InputError "muscle_model = 'x': expected one of ..." otherwise.
const MuscleModelType& findMuscleModelType(const std::string& name);
/// The registry name of the default model, "virtual_muscle".
inline const char* const kDefaultMuscleModel = "virtual_muscle";

}  // namespace armsim

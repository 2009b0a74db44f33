// The registry of muscle models: a model file's `muscle_model:` names one, and every muscle of an arm
// is built through it. A muscle's morphometry always comes as Virtual Muscle parameters (mass, L0,
// L0T, P_max, pennation; model/model_file.h states the conversions from OpenSim's F0 and slack
// length); each model's own coefficients come as named numbers (defaults in assets/muscles/<file>).
// Adding a model: one file pair implementing MuscleModel and one line in getMuscleModelTypes().
#pragma once

#include "muscles/muscle_model.h"
#include "muscles/virtual_muscle.h"

#include <initializer_list>
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

// ---- Helpers for Hill-type models built from morphometry -------------------------------------------

/// A Hill-type muscle's morphometry from Virtual Muscle parameters: F0 = sigma M / (rho L0) (the same
/// person has the same F0 in every model), optimal fibre length L0, tendon slack length LrT L0T (the
/// inverse of model/model_file.h's L0T = slack / LrT: the Virtual Muscle tendon's linear part
/// extrapolates to zero force there), pennation, the path limit P_max.
struct HillMorphometry {
    std::string name;
    double maxIsometricForce = 0;    ///< [N]
    double optimalFiberLength = 0;   ///< [m]
    double tendonSlackLength = 0;    ///< [m]
    double pennationAngle = 0;       ///< at the optimal fibre length [rad]
    double maxPathLength = 0;        ///< [m]; 0: none given
};
HillMorphometry calcHillMorphometry(const MuscleParameters& params);

/// InputError "muscle 'M': MODEL has no coefficient 'KEY': expected one of ...".
/// Throws InputError unless 0 < P <= maxPathLength (the muscle's anatomical limit).
void checkPathWithin(double pathLength, double maxPathLength, const std::string& muscle);

/// For checkStates of the Hill-type models: SimulationError "t = T s: muscle 'M' state NAME is V (not
/// finite)" for the first state that is not finite.
void checkFiniteStates(double t, const double* y, std::initializer_list<const char*> names, const std::string& muscle);
/// SimulationError "t = T s: muscle 'M' fibre length L optimal lengths: expected > 0" unless L > 0.
void checkPositiveFiberLength(double t, double L, const std::string& muscle);

[[noreturn]] void throwUnknownCoefficient(const std::string& muscle, const std::string& model, const std::string& key,
                                          const std::vector<std::string>& keys);

/// A model coefficient a model file may set: its key and the parameter field it sets.
template <class Params>
struct CoefficientField {
    const char* key;
    double Params::*field;
};

/// The keys of a coefficient table.
template <class Params, std::size_t N>
std::vector<std::string> listCoefficientKeys(const CoefficientField<Params> (&fields)[N]) {
    std::vector<std::string> keys;
    for (const CoefficientField<Params>& f : fields) keys.push_back(f.key);
    return keys;
}

/// Sets p's fields from coefficients through the table; InputError naming the muscle, the model, the
/// unknown key and the keys expected.
template <class Params, std::size_t N>
void applyCoefficients(Params& p, const std::map<std::string, double>& coefficients,
                       const CoefficientField<Params> (&fields)[N], const std::string& model) {
    for (const auto& [key, value] : coefficients) {
        const CoefficientField<Params>* found = nullptr;
        for (const CoefficientField<Params>& f : fields)
            if (key == f.key) found = &f;
        if (!found) throwUnknownCoefficient(p.name, model, key, listCoefficientKeys(fields));
        p.*(found->field) = value;
    }
}

/// A Hill-type model's parameters (fields name, maxIsometricForce, optimalFiberLength,
/// tendonSlackLength, pennationAngleAtOptimal, maxPathLength) from the input's morphometry
/// (calcHillMorphometry) and coefficients (applyCoefficients).
template <class Params, std::size_t N>
Params makeHillParameters(const MuscleModelInput& in, const CoefficientField<Params> (&fields)[N],
                          const std::string& model) {
    const HillMorphometry h = calcHillMorphometry(in.params);
    Params p;
    p.name = h.name;
    p.maxIsometricForce = h.maxIsometricForce;
    p.optimalFiberLength = h.optimalFiberLength;
    p.tendonSlackLength = h.tendonSlackLength;
    p.pennationAngleAtOptimal = h.pennationAngle;
    if (h.maxPathLength > 0) p.maxPathLength = h.maxPathLength;
    applyCoefficients(p, in.coefficients, fields, model);
    return p;
}

}  // namespace armsim

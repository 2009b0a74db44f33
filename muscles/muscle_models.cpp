#include "muscles/muscle_models.h"

#include "basics/errors.h"
#include "basics/format.h"
#include "muscles/degroote2016_muscle.h"
#include "muscles/thelen2003_muscle.h"
#include "muscles/thelen2003_opensim2_muscle.h"

#include <cmath>
#include <sstream>

namespace armsim {

namespace {

std::shared_ptr<const MuscleModel> buildVirtualMuscle(const MuscleModelInput& in) {
    if (!in.coefficients.empty())
        throw InputError("muscle '" + in.params.name + "': muscle_model virtual_muscle takes no coefficient '" +
                         in.coefficients.begin()->first + "' (its coefficients are the fibre-type file's)");
    return std::make_shared<VirtualMuscle>(in.params);
}

}  // namespace

const std::vector<MuscleModelType>& getMuscleModelTypes() {
    static const std::vector<MuscleModelType> types = {
        {kDefaultMuscleModel, "Virtual Muscle 4.0 (motor units, slow and fast fibres, mass node)", {}, "",
         &buildVirtualMuscle},
        {"thelen2003", "Thelen 2003 Hill-type muscle as OpenSim 4's Thelen2003Muscle", getThelen2003CoefficientKeys(),
         "thelen2003.yaml", &buildThelen2003Muscle},
        {"degroote2016", "De Groote-Fregly 2016 Hill-type muscle as OpenSim 4's DeGrooteFregly2016Muscle",
         getDeGroote2016CoefficientKeys(), "degroote2016.yaml", &buildDeGroote2016Muscle},
        {"thelen2003_opensim2", "Thelen 2003 Hill-type muscle as OpenSim 2.x's Thelen2003Muscle (its tutorials' results)",
         getThelen2003Opensim2CoefficientKeys(), "thelen2003_opensim2.yaml", &buildThelen2003Opensim2Muscle},
    };
    return types;
}

HillMorphometry calcHillMorphometry(const MuscleParameters& m) {
    HillMorphometry h;
    h.name = m.name;
    h.maxIsometricForce = calcMaxIsometricForce(m);
    h.optimalFiberLength = m.optimalFascicleLength;
    h.tendonSlackLength = m.coefficients.LrT * m.optimalTendonLength;
    h.pennationAngle = m.pennationAngle;
    h.maxPathLength = m.maxPathLength;
    return h;
}

void checkPathWithin(double P, double maxPath, const std::string& muscle) {
    if (!(P > 0) || !std::isfinite(P)) throw InputError("path length = " + formatNumber(P) + " m: expected > 0");
    if (P > maxPath)
        throw InputError("path length = " + formatNumber(P) + " m exceeds max_path_length = " + formatNumber(maxPath) + " m of muscle '" +
                         muscle + "': expected a path no longer than the anatomical limit");
}

void checkFiniteStates(double t, const double* y, std::initializer_list<const char*> names, const std::string& muscle) {
    int i = 0;
    for (const char* name : names) {
        if (!std::isfinite(y[i])) {
            std::ostringstream msg;
            msg << "t = " << t << " s: muscle '" << muscle << "' state " << name << " is " << y[i] << " (not finite)";
            throw SimulationError(msg.str());
        }
        ++i;
    }
}

void checkPositiveFiberLength(double t, double L, const std::string& muscle) {
    if (L > 0) return;
    std::ostringstream msg;
    msg << "t = " << t << " s: muscle '" << muscle << "' fibre length " << L << " optimal lengths: expected > 0";
    throw SimulationError(msg.str());
}

void throwUnknownCoefficient(const std::string& muscle, const std::string& model, const std::string& key,
                             const std::vector<std::string>& keys) {
    std::string list;
    for (const std::string& k : keys) list += (list.empty() ? "" : ", ") + k;
    throw InputError("muscle '" + muscle + "': " + model + " has no coefficient '" + key + "': expected one of " + list);
}

const MuscleModelType& findMuscleModelType(const std::string& name) {
    std::string names;
    for (const MuscleModelType& t : getMuscleModelTypes()) {
        if (t.name == name) return t;
        names += (names.empty() ? "" : ", ") + t.name;
    }
    throw InputError("muscle_model = '" + name + "': expected one of " + names);
}

}  // namespace armsim

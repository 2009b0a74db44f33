#include "muscles/muscle_models.h"

#include "basics/errors.h"
#include "muscles/thelen2003_muscle.h"

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
    };
    return types;
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

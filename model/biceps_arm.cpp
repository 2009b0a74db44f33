#include "model/biceps_arm.h"

#include "model/geometry.h"
#include "muscles/muscle_file.h"

namespace armsim {

MuscleParameters ArmSetup::calcBicepsParameters() const {
    MuscleParameters p = biceps;
    if (musclePmaxFromArm)
        p.maxPathLength =
            calcBicepsPathLength(arm.originDistance, arm.insertionDistance, degToRad(arm.maxElbowAngleDeg));
    p.validate();
    return p;
}

ArmSetup ArmSetup::loadDefault() {
    ArmSetup s;
    s.arm = loadArmParameters(findAsset("arm/default_male.yaml"));
    s.biceps = loadMuscleParameters(findAsset("muscles/biceps_long_head.yaml"));
    return s;
}

BicepsArm::BicepsArm(const ArmSetup& setup, ActivationProfile activation)
    : arm_(std::make_unique<ArmModel>(setup.arm)),
      muscle_(std::make_shared<VirtualMuscle>(setup.calcBicepsParameters())) {
    biceps_ = VirtualMuscleForce(arm_->updForces(), muscle_, arm_->getUpperArm(), arm_->getOriginStation(),
                                 arm_->getForearm(), arm_->getInsertionStation(), std::move(activation));
    arm_->finalize();
}

}  // namespace armsim

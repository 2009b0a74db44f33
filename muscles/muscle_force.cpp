#include "muscles/muscle_force.h"

#include "basics/errors.h"

#include <cmath>
#include <sstream>

using namespace SimTK;

namespace armsim {

class VirtualMuscleForce::Impl : public Force::Custom::Implementation {
public:
    Impl(SubsystemIndex forces, std::shared_ptr<const VirtualMuscle> muscle, MusclePath path,
         ActivationProfile activation)
        : forces_(forces), muscle_(std::move(muscle)), path_(std::move(path)), activation_(std::move(activation)) {}

    const VirtualMuscle& muscle() const { return *muscle_; }
    const MusclePath& path() const { return path_; }
    const ActivationProfile& activation() const { return activation_; }
    const std::string& name() const { return muscle_->getParameters().name; }

    void realizeTopology(State& s) const override {
        const Vector zInit(muscle_->getNumStates(), 0.0);
        firstZ_ = s.allocateZ(forces_, zInit);
    }

    double pathLength(const State& s) const { return path_.calcLength(s); }
    PathGeometry geometry(const State& s, bool withPolyline = false) const {
        return path_.calcGeometry(s, name(), withPolyline);
    }
    const double* z(const State& s) const { return &s.getZ(forces_)[firstZ_]; }

    void realizeDynamics(const State& s) const override {
        Vector& zdot = s.updZDot(forces_);
        muscle_->calcStateDerivative(pathLength(s), activation_.getValue(s.getTime()), z(s), &zdot[firstZ_]);
    }

    void calcForce(const State& s, Vector_<SpatialVec>& bodyForces, Vector_<Vec3>&, Vector&) const override {
        const PathGeometry g = geometry(s);
        MusclePath::applyTension(g, muscle_->calcForce(g.length, z(s)), bodyForces);
    }

    Real calcPotentialEnergy(const State&) const override { return 0; }

    void calcDecorativeGeometryAndAppend(const State& s, Stage stage,
                                         Array_<DecorativeGeometry>& geometry) const override {
        if (stage != Stage::Position) return;
        const PathGeometry g = this->geometry(s, true);
        const MuscleOutputs out = muscle_->calcOutputs(g.length, activation_.getValue(s.getTime()), z(s));
        appendPathDecorations(path_, g, calcActivationColor(out.activeFraction), 3.0 + 5.0 * out.activeFraction,
                              geometry);
    }

    SubsystemIndex forces_;
    std::shared_ptr<const VirtualMuscle> muscle_;
    MusclePath path_;
    ActivationProfile activation_;
    mutable ZIndex firstZ_;  // topology-stage cache
};

VirtualMuscleForce::VirtualMuscleForce(GeneralForceSubsystem& forces, std::shared_ptr<const VirtualMuscle> muscle,
                                       const MobilizedBody& originBody, const Vec3& originStation,
                                       const MobilizedBody& insertionBody, const Vec3& insertionStation,
                                       ActivationProfile activation)
    : VirtualMuscleForce(forces, std::move(muscle),
                         MusclePath(originBody, originStation, insertionBody, insertionStation),
                         std::move(activation)) {}

VirtualMuscleForce::VirtualMuscleForce(GeneralForceSubsystem& forces, std::shared_ptr<const VirtualMuscle> muscle,
                                       MusclePath path, ActivationProfile activation)
    : Force::Custom(forces, new Impl(forces.getMySubsystemIndex(), std::move(muscle), std::move(path),
                                     std::move(activation))) {}

const VirtualMuscleForce::Impl& VirtualMuscleForce::getImpl() const {
    return dynamic_cast<const Impl&>(getImplementation());
}

const VirtualMuscle& VirtualMuscleForce::getMuscle() const { return getImpl().muscle(); }
const MusclePath& VirtualMuscleForce::getPath() const { return getImpl().path(); }
const ActivationProfile& VirtualMuscleForce::getActivationProfile() const { return getImpl().activation(); }

double VirtualMuscleForce::getPathLength(const State& s) const { return getImpl().pathLength(s); }

PathGeometry VirtualMuscleForce::calcPathGeometry(const State& s, bool withPolyline) const {
    return getImpl().geometry(s, withPolyline);
}

double VirtualMuscleForce::getActivation(const State& s) const {
    return getImpl().activation().getValue(s.getTime());
}

double VirtualMuscleForce::getForce(const State& s) const {
    return getMuscle().calcForce(getPathLength(s), getImpl().z(s));
}

double VirtualMuscleForce::getFascicleLength(const State& s) const {
    return getImpl().z(s)[VirtualMuscle::kL] * getMuscle().getParameters().optimalFascicleLength;
}

double VirtualMuscleForce::getFascicleVelocity(const State& s) const {
    return getImpl().z(s)[VirtualMuscle::kV] * getMuscle().getParameters().optimalFascicleLength;
}

MuscleOutputs VirtualMuscleForce::calcOutputs(const State& s) const {
    return getMuscle().calcOutputs(getPathLength(s), getActivation(s), getImpl().z(s));
}

std::vector<double> VirtualMuscleForce::getMuscleStates(const State& s) const {
    const double* z = getImpl().z(s);
    return std::vector<double>(z, z + getMuscle().getNumStates());
}

int VirtualMuscleForce::getFirstStateIndex(const State& s) const {
    return int(s.getZStart(getImpl().forces_)) + int(getImpl().firstZ_);
}

void VirtualMuscleForce::setMuscleStates(State& s, const std::vector<double>& y) const {
    SimTK_APIARGCHECK_ALWAYS(int(y.size()) == getMuscle().getNumStates(), "VirtualMuscleForce",
                             "setMuscleStates", "wrong number of muscle states");
    Vector& z = s.updZ(getImpl().forces_);
    for (int i = 0; i < int(y.size()); ++i) z[getImpl().firstZ_ + i] = y[i];
}

void VirtualMuscleForce::setInitialMuscleStates(State& s) const {
    const auto& sys = getForceSubsystem().getSystem();
    sys.realize(s, Stage::Position);
    setMuscleStates(s, getMuscle().calcInitialState(getPathLength(s)));
}

void VirtualMuscleForce::setSteadyMuscleStates(State& s) const {
    const auto& sys = getForceSubsystem().getSystem();
    sys.realize(s, Stage::Position);
    const SteadyState ss = getMuscle().calcSteadyState(getPathLength(s), getActivation(s));
    if (!ss.converged) throw SimulationError(ss.message);
    setMuscleStates(s, ss.states);
}

void VirtualMuscleForce::checkMuscleStates(const State& s) const {
    getMuscle().checkStates(s.getTime(), getImpl().z(s));
}

Vec3 VirtualMuscleForce::calcActivationColor(double a) {
    a = std::min(1.0, std::max(0.0, a));
    return Vec3(0.15 + 0.8 * a, 0.25 * (1 - a) + 0.1, 0.85 * (1 - a) + 0.1);
}

}  // namespace armsim

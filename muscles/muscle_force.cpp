#include "muscles/muscle_force.h"

#include "basics/errors.h"

#include <cmath>
#include <sstream>

using namespace SimTK;

namespace armsim {

class MuscleForce::Impl : public Force::Custom::Implementation {
public:
    Impl(SubsystemIndex forces, std::shared_ptr<const MuscleModel> muscle, MusclePath path,
         ActivationProfile activation)
        : forces_(forces), muscle_(std::move(muscle)), path_(std::move(path)), activation_(std::move(activation)) {}

    const MuscleModel& muscle() const { return *muscle_; }
    const MusclePath& path() const { return path_; }
    const ActivationProfile& activation() const { return activation_; }
    void setActivation(ActivationProfile a) { activation_ = std::move(a); }
    const std::string& name() const { return muscle_->getName(); }

    void realizeTopology(State& s) const override {
        const Vector zInit(muscle_->getNumStates(), 0.0);
        firstZ_ = s.allocateZ(forces_, zInit);
        geometryIndex_ = s.allocateLazyCacheEntry(forces_, Stage::Position, new Value<PathGeometry>());
    }

    // The path at the state's positions, computed once per realization (the derivatives and the
    // force both need it).
    const PathGeometry& cachedGeometry(const State& s) const {
        if (!s.isCacheValueRealized(forces_, geometryIndex_)) {
            Value<PathGeometry>::updDowncast(s.updCacheEntry(forces_, geometryIndex_)) =
                path_.calcGeometry(s, name(), false);
            s.markCacheValueRealized(forces_, geometryIndex_);
        }
        return Value<PathGeometry>::downcast(s.getCacheEntry(forces_, geometryIndex_));
    }
    double pathLength(const State& s) const { return path_.isStraight() ? path_.calcLength(s) : cachedGeometry(s).length; }
    PathGeometry geometry(const State& s, bool withPolyline = false) const {
        return withPolyline ? path_.calcGeometry(s, name(), true) : cachedGeometry(s);
    }
    const double* z(const State& s) const { return &s.getZ(forces_)[firstZ_]; }

    void realizeDynamics(const State& s) const override {
        Vector& zdot = s.updZDot(forces_);
        if (muscle_->usesPathVelocity()) {
            const PathGeometry& g = cachedGeometry(s);
            muscle_->calcMovingStateDerivative(g.length, path_.calcLengtheningSpeed(s, g), activation_.getValue(s.getTime()),
                                               z(s), &zdot[firstZ_]);
        } else {
            muscle_->calcStateDerivative(pathLength(s), activation_.getValue(s.getTime()), z(s), &zdot[firstZ_]);
        }
    }

    void calcForce(const State& s, Vector_<SpatialVec>& bodyForces, Vector_<Vec3>&, Vector& mobilityForces) const override {
        const PathGeometry& g = cachedGeometry(s);
        MusclePath::applyTension(g, muscle_->calcForce(g.length, z(s)), bodyForces, mobilityForces);
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
    std::shared_ptr<const MuscleModel> muscle_;
    MusclePath path_;
    ActivationProfile activation_;
    mutable ZIndex firstZ_;  // topology-stage cache
    mutable CacheEntryIndex geometryIndex_;
};

MuscleForce::MuscleForce(GeneralForceSubsystem& forces, std::shared_ptr<const MuscleModel> muscle,
                                       const MobilizedBody& originBody, const Vec3& originStation,
                                       const MobilizedBody& insertionBody, const Vec3& insertionStation,
                                       ActivationProfile activation)
    : MuscleForce(forces, std::move(muscle),
                         MusclePath(originBody, originStation, insertionBody, insertionStation),
                         std::move(activation)) {}

MuscleForce::MuscleForce(GeneralForceSubsystem& forces, std::shared_ptr<const MuscleModel> muscle,
                                       MusclePath path, ActivationProfile activation)
    : Force::Custom(forces, new Impl(forces.getMySubsystemIndex(), std::move(muscle), std::move(path),
                                     std::move(activation))) {}

const MuscleForce::Impl& MuscleForce::getImpl() const {
    return dynamic_cast<const Impl&>(getImplementation());
}

const MuscleModel& MuscleForce::getMuscle() const { return getImpl().muscle(); }
const MusclePath& MuscleForce::getPath() const { return getImpl().path(); }
const ActivationProfile& MuscleForce::getActivationProfile() const { return getImpl().activation(); }
void MuscleForce::setActivationProfile(ActivationProfile activation) {
    dynamic_cast<Impl&>(updImplementation()).setActivation(std::move(activation));
}

double MuscleForce::getPathLength(const State& s) const { return getImpl().pathLength(s); }

PathGeometry MuscleForce::calcPathGeometry(const State& s, bool withPolyline) const {
    return getImpl().geometry(s, withPolyline);
}

double MuscleForce::getActivation(const State& s) const {
    return getImpl().activation().getValue(s.getTime());
}

double MuscleForce::getForce(const State& s) const {
    return getMuscle().calcForce(getPathLength(s), getImpl().z(s));
}

double MuscleForce::getFascicleLength(const State& s) const {
    return getMuscle().calcFascicleLength(getPathLength(s), getImpl().z(s));
}

double MuscleForce::getFascicleVelocity(const State& s) const {
    return getMuscle().calcFascicleVelocity(getPathLength(s), getActivation(s), getImpl().z(s));
}

MuscleOutputs MuscleForce::calcOutputs(const State& s) const {
    return getMuscle().calcOutputs(getPathLength(s), getActivation(s), getImpl().z(s));
}

std::vector<double> MuscleForce::getMuscleStates(const State& s) const {
    const double* z = getImpl().z(s);
    return std::vector<double>(z, z + getMuscle().getNumStates());
}

int MuscleForce::getFirstStateIndex(const State& s) const {
    return int(s.getZStart(getImpl().forces_)) + int(getImpl().firstZ_);
}

void MuscleForce::setMuscleStates(State& s, const std::vector<double>& y) const {
    SimTK_APIARGCHECK_ALWAYS(int(y.size()) == getMuscle().getNumStates(), "MuscleForce",
                             "setMuscleStates", "wrong number of muscle states");
    Vector& z = s.updZ(getImpl().forces_);
    for (int i = 0; i < int(y.size()); ++i) z[getImpl().firstZ_ + i] = y[i];
}

void MuscleForce::setInitialMuscleStates(State& s) const {
    const auto& sys = getForceSubsystem().getSystem();
    sys.realize(s, Stage::Position);
    setMuscleStates(s, getMuscle().calcInitialState(getPathLength(s)));
}

void MuscleForce::setSteadyMuscleStates(State& s) const {
    const auto& sys = getForceSubsystem().getSystem();
    sys.realize(s, Stage::Position);
    const SteadyState ss = getMuscle().calcSteadyState(getPathLength(s), getActivation(s));
    if (!ss.converged) throw SimulationError(ss.message);
    setMuscleStates(s, ss.states);
}

void MuscleForce::checkMuscleStates(const State& s) const {
    getMuscle().checkStates(s.getTime(), getImpl().z(s));
}

Vec3 MuscleForce::calcActivationColor(double a) {
    a = std::min(1.0, std::max(0.0, a));
    return Vec3(0.15 + 0.8 * a, 0.25 * (1 - a) + 0.1, 0.85 * (1 - a) + 0.1);
}

}  // namespace armsim

// A small Simbody system for the render tests and benchmark: a pendulum on a Pin about Ground z at
// the origin, with a rod (cylinder), a bob (sphere) and a hub (brick) as body decorations, a bench
// (brick) on Ground, and a custom force element that draws a line from a Ground anchor to the bob
// coloured from blue (parameter 0) to red (parameter 1), like a muscle coloured by activation.
#pragma once

#include "muscles/simbody.h"

#include <cmath>

namespace armsim::test {

/// Geometry of the pendulum scene (m).
struct PendulumGeometry {
    static constexpr double kLength = 0.5;        ///< pivot to bob centre
    static constexpr double kBobRadius = 0.06;
    static constexpr double kRodRadius = 0.02;
    static constexpr double kHubHalf = 0.03;      ///< hub brick half-size
    static constexpr double kLineThickness = 6;   ///< coloured line (px)
    static SimTK::Vec3 bobColor() { return {1, 0.55, 0}; }
    static SimTK::Vec3 anchor() { return {0.45, 0.2, 0}; }          ///< line start on Ground
    static SimTK::Vec3 benchCentre() { return {0, 0.05, 0}; }
    static SimTK::Vec3 benchHalf() { return {0.3, 0.03, 0.05}; }
    /// Every piece of geometry lies inside this Ground box (min, max corners).
    static SimTK::Vec3 boxMin() { return {-0.6, -0.6, -0.07}; }
    static SimTK::Vec3 boxMax() { return {0.6, 0.25, 0.07}; }
};

/// Force element with no force that draws a coloured line at a chosen stage.
class ColouredLine : public SimTK::Force::Custom::Implementation {
public:
    ColouredLine(const SimTK::MobilizedBody& body, const SimTK::Vec3& anchor_G, const SimTK::Vec3& station_B,
                 SimTK::Stage stage)
        : body_(body), anchor_G_(anchor_G), station_B_(station_B), stage_(stage) {}

    void setParameter(double p) { parameter_ = p; }

    void calcForce(const SimTK::State&, SimTK::Vector_<SimTK::SpatialVec>&, SimTK::Vector_<SimTK::Vec3>&,
                   SimTK::Vector&) const override {}
    SimTK::Real calcPotentialEnergy(const SimTK::State&) const override { return 0; }
    void calcDecorativeGeometryAndAppend(const SimTK::State& s, SimTK::Stage stage,
                                         SimTK::Array_<SimTK::DecorativeGeometry>& geometry) const override {
        if (stage != stage_) return;
        const SimTK::Vec3 p_G = body_.findStationLocationInGround(s, station_B_);
        geometry.push_back(SimTK::DecorativeLine(anchor_G_, p_G)
                               .setColor(SimTK::Vec3(parameter_, 0, 1 - parameter_))
                               .setLineThickness(PendulumGeometry::kLineThickness));
    }

private:
    SimTK::MobilizedBody body_;
    SimTK::Vec3 anchor_G_, station_B_;
    SimTK::Stage stage_;
    double parameter_ = 0;
};

/// The pendulum system. Not copyable (the subsystems refer to the system).
class PendulumScene {
public:
    using G = PendulumGeometry;

    explicit PendulumScene(SimTK::Stage lineStage = SimTK::Stage::Position) : matter_(system_), forces_(system_) {
        using namespace SimTK;
        matter_.setShowDefaultGeometry(false);
        const Vec3 bob(0, -G::kLength, 0);
        Body::Rigid bodyInfo(MassProperties(1.0, bob, UnitInertia::pointMassAt(bob)));
        pendulum_ = MobilizedBody::Pin(matter_.Ground(), Transform(), bodyInfo, Transform());
        pendulum_.addBodyDecoration(Transform(Vec3(0, -0.5 * G::kLength, 0)),
                                    DecorativeCylinder(G::kRodRadius, 0.5 * G::kLength).setColor(Vec3(0.5)));
        pendulum_.addBodyDecoration(Transform(bob), DecorativeSphere(G::kBobRadius).setColor(G::bobColor()));
        pendulum_.addBodyDecoration(Transform(), DecorativeBrick(Vec3(G::kHubHalf)).setColor(Vec3(0.2, 0.6, 0.2)));
        matter_.Ground().addBodyDecoration(Transform(G::benchCentre()),
                                           DecorativeBrick(G::benchHalf()).setColor(Vec3(0.45, 0.35, 0.25)));
        line_ = new ColouredLine(pendulum_, G::anchor(), bob, lineStage);
        Force::Custom(forces_, line_);
        system_.realizeTopology();
    }

    /// A state with the pendulum at angle q (rad, about z from hanging straight down), realized to
    /// stage. Sets the line's colour parameter, which is a member of the force element (not state):
    /// it applies to every frame rendered until the next makeState().
    SimTK::State makeState(double q, double parameter, SimTK::Stage stage = SimTK::Stage::Position) {
        line_->setParameter(parameter);
        SimTK::State s = system_.getDefaultState();
        pendulum_.setOneQ(s, 0, q);
        system_.realize(s, stage);
        return s;
    }

    /// Bob centre in Ground at angle q.
    static SimTK::Vec3 bobCentre(double q) { return {G::kLength * std::sin(q), -G::kLength * std::cos(q), 0}; }

    const SimTK::MultibodySystem& getSystem() const { return system_; }
    const SimTK::MobilizedBody::Pin& getPendulum() const { return pendulum_; }

private:
    SimTK::MultibodySystem system_;
    SimTK::SimbodyMatterSubsystem matter_;
    SimTK::GeneralForceSubsystem forces_;
    SimTK::MobilizedBody::Pin pendulum_;
    ColouredLine* line_ = nullptr;  // owned by the Force::Custom in forces_
};

}  // namespace armsim::test

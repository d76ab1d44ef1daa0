// Simbody's side of the peer (simbody_arm.hpp): the arm built from its parameters, and its
// constrained accelerations. Compiled as C++17: Simbody 3.7's headers do not compile as C++20
// (their index types' comparison operators become ambiguous under C++20's rewritten candidates),
// and without NDEBUG, as Debian's Simbody is (its headers' inline code differs with it).
#include "simbody_arm.hpp"

#include <Simbody.h>

#include <cmath>
#include <memory>

namespace gausstrack::peer {
namespace {

// The hand (station `tip` of the last link) on c + R (cos(w t + phase), sin(w t + phase)).
class HandOnCircle : public SimTK::Constraint::Custom::Implementation {
 public:
  HandOnCircle(SimTK::MobilizedBody& hand, const SimTK::Vec3& tip, const ArmParameters& arm)
      : Implementation(hand.updMatterSubsystem(), 2, 0, 0),
        tip_(tip),
        center_(arm.center[0], arm.center[1], 0),
        radius_(arm.radius),
        rate_(arm.rate),
        phase_(arm.phase) {
    // Ground is a constrained body too: the constraint's frame is then Ground, not the hand's.
    ground_ = addConstrainedBody(hand.updMatterSubsystem().Ground());
    hand_ = addConstrainedBody(hand);
  }
  Implementation* clone() const override { return new HandOnCircle(*this); }

  void calcPositionErrors(const SimTK::State& s,
                          const SimTK::Array_<SimTK::Transform, SimTK::ConstrainedBodyIndex>& x,
                          const SimTK::Array_<SimTK::Real, SimTK::ConstrainedQIndex>&,
                          SimTK::Array_<SimTK::Real>& e) const override {
    const SimTK::Vec3 d = findStationLocation(x, hand_, tip_) - point(s.getTime(), 0);
    e[0] = d[0], e[1] = d[1];
  }
  void calcPositionDotErrors(const SimTK::State& s,
                             const SimTK::Array_<SimTK::SpatialVec, SimTK::ConstrainedBodyIndex>& v,
                             const SimTK::Array_<SimTK::Real, SimTK::ConstrainedQIndex>&,
                             SimTK::Array_<SimTK::Real>& e) const override {
    const SimTK::Vec3 d = findStationVelocity(s, v, hand_, tip_) - point(s.getTime(), 1);
    e[0] = d[0], e[1] = d[1];
  }
  void calcPositionDotDotErrors(
      const SimTK::State& s, const SimTK::Array_<SimTK::SpatialVec, SimTK::ConstrainedBodyIndex>& a,
      const SimTK::Array_<SimTK::Real, SimTK::ConstrainedQIndex>&,
      SimTK::Array_<SimTK::Real>& e) const override {
    const SimTK::Vec3 d = findStationAcceleration(s, a, hand_, tip_) - point(s.getTime(), 2);
    e[0] = d[0], e[1] = d[1];
  }
  // G^T lambda: the multipliers as a force at the hand (and its reaction on Ground).
  void addInPositionConstraintForces(
      const SimTK::State& s, const SimTK::Array_<SimTK::Real>& lambda,
      SimTK::Array_<SimTK::SpatialVec, SimTK::ConstrainedBodyIndex>& forces,
      SimTK::Array_<SimTK::Real, SimTK::ConstrainedQIndex>&) const override {
    const SimTK::Vec3 f(lambda[0], lambda[1], 0);
    addInStationForce(s, hand_, tip_, f, forces);
    addInStationForce(s, ground_, findStationLocationFromState(s, hand_, tip_), -f, forces);
  }

 private:
  // The circle's point (derivative 0), velocity (1) or acceleration (2) at t.
  SimTK::Vec3 point(SimTK::Real t, int derivative) const {
    const SimTK::Real a = rate_ * t + phase_, c = std::cos(a), s = std::sin(a);
    if (derivative == 0) return center_ + radius_ * SimTK::Vec3(c, s, 0);
    if (derivative == 1) return radius_ * rate_ * SimTK::Vec3(-s, c, 0);
    return -radius_ * rate_ * rate_ * SimTK::Vec3(c, s, 0);
  }
  SimTK::ConstrainedBodyIndex ground_, hand_;
  SimTK::Vec3 tip_, center_;
  SimTK::Real radius_, rate_, phase_;
};

}  // namespace

// The arm as a Simbody system.
struct SimbodyArm::Impl {
  explicit Impl(const ArmParameters& arm)
      : matter(system), forces(system), gravity(forces, matter, SimTK::Vec3(0, -arm.gravity, 0)) {
    SimTK::MobilizedBody* parent = &matter.Ground();
    for (int i = 0; i < 3; ++i) {
      const SimTK::Vec3 com(arm.com[i], 0, 0);
      // Simbody takes the inertia about the body's origin (the joint), not its centre of mass.
      const SimTK::Body::Rigid body(SimTK::MassProperties(
          arm.mass[i], com, SimTK::Inertia(arm.inertia[i]).shiftFromMassCenter(com, arm.mass[i])));
      const SimTK::Vec3 joint(i == 0 ? 0.0 : arm.length[i - 1], 0, 0);
      links[i] =
          SimTK::MobilizedBody::Pin(*parent, SimTK::Transform(joint), body, SimTK::Transform());
      parent = &links[i];
      // The model's viscous joint damping, -c q'.
      if (arm.damping != 0)
        SimTK::Force::MobilityLinearDamper(forces, links[i], SimTK::MobilizerUIndex(0),
                                           arm.damping);
    }
    hand = SimTK::Constraint::Custom(
        new HandOnCircle(links[2], SimTK::Vec3(arm.length[2], 0, 0), arm));
    state = system.realizeTopology();
  }
  SimTK::MultibodySystem system;
  SimTK::SimbodyMatterSubsystem matter;
  SimTK::GeneralForceSubsystem forces;
  SimTK::Force::UniformGravity gravity;
  SimTK::MobilizedBody::Pin links[3];
  SimTK::Constraint::Custom hand;
  SimTK::State state;
};

SimbodyArm::SimbodyArm(const ArmParameters& arm) : impl_(std::make_unique<Impl>(arm)) {}
SimbodyArm::~SimbodyArm() = default;

void SimbodyArm::acceleration(const double* q, const double* qd, double t, double* qdd) {
  SimTK::State& s = impl_->state;
  s.setTime(t);
  for (int i = 0; i < 3; ++i) {
    s.updQ()[i] = q[i];
    s.updU()[i] = qd[i];
  }
  impl_->system.realize(s, SimTK::Stage::Acceleration);
  const SimTK::Vector& udot = s.getUDot();
  for (int i = 0; i < 3; ++i) qdd[i] = udot[i];
}

void SimbodyArm::multipliers(double* lambda) const {
  const SimTK::Vector l = impl_->hand.getMultipliersAsVector(impl_->state);
  lambda[0] = -l[0], lambda[1] = -l[1];
}

}  // namespace gausstrack::peer

// The planar three-link arm of systems::PlanarArm built in Simbody 3.7 (the peer a user might
// pick instead of the law): three Pin mobilizers in series in Simbody's x-y plane (a Pin turns
// about z, its q the joint's relative angle, as the model's q), each link a rigid body with the
// model's mass, centre of mass and inertia, uniform gravity along -y, and the hand held on the
// model's circle by a holonomic Constraint::Custom of two rows written as the model writes phi.
// Simbody's realize(Acceleration) then solves M u' + G^T lambda = f, G u' = b exactly (no
// stabilization): the constrained motion the law's eq. (30) gives without its Baumgarte term.
// Plain types only here (simbody_arm.cpp holds Simbody, compiled as C++17).
#pragma once

#include <memory>

namespace gausstrack::peer {

/// The arm's parameters, as systems::PlanarArm names them (arm_parameters() copies them).
struct ArmParameters {
  double mass[3], length[3], com[3], inertia[3];
  double gravity, damping;
  double center[2], radius, rate, phase;
};

/// The arm as a Simbody system, and its accelerations at (q, q', t).
class SimbodyArm {
 public:
  explicit SimbodyArm(const ArmParameters& arm);
  ~SimbodyArm();
  SimbodyArm(const SimbodyArm&) = delete;
  SimbodyArm& operator=(const SimbodyArm&) = delete;

  /// q'' at (q, q', t): Simbody's realize(Acceleration) from a state whose positions changed.
  void acceleration(const double* q, const double* qd, double t, double* qdd);
  /// The hand's two multipliers in the law's sign (A q'' + f = Q + D^T lambda), after
  /// acceleration().
  void multipliers(double* lambda) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// The parameters of a systems::PlanarArm.
template <typename Arm>
ArmParameters arm_parameters(const Arm& arm) {
  ArmParameters p{};
  for (int i = 0; i < 3; ++i) {
    p.mass[i] = arm.mass(i), p.length[i] = arm.length(i), p.com[i] = arm.com(i),
    p.inertia[i] = arm.inertia(i);
  }
  p.gravity = arm.gravity, p.damping = arm.damping;
  p.center[0] = arm.center_x, p.center[1] = arm.center_y;
  p.radius = arm.radius, p.rate = arm.rate, p.phase = arm.phase;
  return p;
}

}  // namespace gausstrack::peer

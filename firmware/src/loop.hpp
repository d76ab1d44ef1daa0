// The firmware loop, written once for the target (float, Cortex-M) and for the host's reference
// run (double): each period, read the state, evaluate the control law, apply the force; the plant
// is integrated over the period under the held force by classical RK4 (on the target too).
//
// Laws (chosen at compile time, one per image, so that each image's footprint is the law's):
//   kDuffing     TrackingController<CoupledDuffing>: eq. (35), 2 x 1, stabilization zeta 1, omega 20
//   kArm         TrackingController<PlanarArm>: the three-link arm's hand on its circle, written as
//                phi(q, t), 3 x 2, stabilization zeta 1, omega 20
//   kClosedForm  the hand-derived Duffing force (bench/controller/duffing_closed_form.hpp), the floor
//   kDuffingHeld, kArmHeld  the same laws with the sampled-data hold of one period (the force held
//                over the period is the law's at its middle: docs/sampled_law.md)
//   kCartPole    ActuatedController<CartPole>: one motor on the cart, the pendulum's angle tracking
//                0.4 sin(3 t), 2 x 1 with K = 1 (docs/actuation.md)
//   kArmPassiveWrist  ActuatedController<PlanarArmPassiveWrist>: the arm's hand on its circle with
//                motors at the shoulder and the elbow alone, 3 x 2 with K = 2
//   kDifferentialDrive  ActuatedController<DifferentialDrive>: a point ahead of the axle on the
//                figure-eight, drive force and yaw torque (K = 2), the no-slip row physical: the
//                law leaves it to the plant, and the plant here holds it (its constrained
//                acceleration, eq. 31, with the row's velocity error damped against RK4's drift)
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <type_traits>

#include "../../bench/controller/duffing_closed_form.hpp"
#include "gausstrack/actuation.hpp"
#include "gausstrack/consistent_state.hpp"
#include "gausstrack/systems/cart_pole.hpp"
#include "gausstrack/systems/coupled_duffing.hpp"
#include "gausstrack/systems/differential_drive.hpp"
#include "gausstrack/systems/planar_arm.hpp"
#include "gausstrack/tracking_controller.hpp"

namespace firmware {

enum class Law { kDuffing, kArm, kClosedForm, kDuffingHeld, kArmHeld, kCartPole, kArmPassiveWrist, kDifferentialDrive };

template <Law L>
constexpr bool is_arm() {
  return L == Law::kArm || L == Law::kArmHeld || L == Law::kArmPassiveWrist;
}

// The model each law controls (and its plant).
template <Law L, typename S>
struct ModelOf {
  using type = gausstrack::systems::CoupledDuffing<S>;
};
template <Law L, typename S>
requires(L == Law::kArm || L == Law::kArmHeld) struct ModelOf<L, S> {
  using type = gausstrack::systems::PlanarArm<S>;
};
template <typename S>
struct ModelOf<Law::kArmPassiveWrist, S> {
  using type = gausstrack::systems::PlanarArmPassiveWrist<S>;
};
template <typename S>
struct ModelOf<Law::kCartPole, S> {
  using type = gausstrack::systems::CartPole<S>;
};
template <typename S>
struct ModelOf<Law::kDifferentialDrive, S> {
  using type = gausstrack::systems::DifferentialDrive<S>;
};

inline constexpr int kPeriods = 10000;  // 10 s at 1 kHz
inline constexpr double kPeriod = 1e-3;  // [s]

template <Law L>
constexpr int dof() {
  return is_arm<L>() || L == Law::kDifferentialDrive ? 3 : 2;
}

/// One law and its plant, in scalar type S.
template <Law L, typename S>
class Loop {
 public:
  static constexpr int N = dof<L>();
  using Vector = Eigen::Matrix<S, N, 1>;
  using Model = typename ModelOf<L, S>::type;

  Loop() {
    if constexpr (is_arm<L>()) {
      q_ << S(0.2), S(0.9), S(0.6);
      qd_.setZero();
      gausstrack::make_consistent(model_, q_, qd_, S(0), S(1e-6));
    } else if constexpr (L == Law::kDifferentialDrive) {
      // differential_drive.yaml's start: 0.14 m off the path, at rest, heading 45 deg.
      q_ << S(-0.312), S(-0.112), S(0.7853981633974483);
      qd_.setZero();
    } else if constexpr (L == Law::kCartPole) {
      q_ << S(0), S(0);  // on the trajectory: theta = 0, theta' = 1.2
      qd_ << S(0), S(1.2);
    } else {
      q_ << S(1), S(1);
      qd_ << model_.consistent_x1_velocity(S(2)), S(2);
    }
  }

  /// The control law: force for the measured state (the timed part of a period).
  __attribute__((noinline)) gausstrack::Status control(const Vector& q, const Vector& qd, S t, Vector& force) {
    if constexpr (L == Law::kClosedForm) {
      force = gausstrack::bench::duffing_closed_form_force(model_, q, qd, t);
      return gausstrack::Status::kOk;
    } else {
      const gausstrack::Status s = law_.controller.compute(q, qd, t, law_.out);
      force = law_.out.force;
      return s;
    }
  }

  /// The plant over one period under the held force u: classical RK4, one step.
  void advance(const Vector& u, S t, S dt) {
    Vector k1q, k1v, k2q, k2v, k3q, k3v, k4q, k4v;
    acceleration(q_, qd_, u, t, k1v);
    k1q = qd_;
    acceleration(q_ + dt / S(2) * k1q, qd_ + dt / S(2) * k1v, u, t + dt / S(2), k2v);
    k2q = qd_ + dt / S(2) * k1v;
    acceleration(q_ + dt / S(2) * k2q, qd_ + dt / S(2) * k2v, u, t + dt / S(2), k3v);
    k3q = qd_ + dt / S(2) * k2v;
    acceleration(q_ + dt * k3q, qd_ + dt * k3v, u, t + dt, k4v);
    k4q = qd_ + dt * k3v;
    q_ += dt / S(6) * (k1q + S(2) * k2q + S(2) * k3q + k4q);
    qd_ += dt / S(6) * (k1v + S(2) * k2v + S(2) * k3v + k4v);
  }

  /// The tracking error at the current state [m]: the constraint's value (x1 - x2 - s(t), or the
  /// hand's distance from its point on the circle).
  S tracking_error(S t) const {
    const auto e = model_.phi(q_, t);
    return e.norm();
  }

  const Vector& q() const { return q_; }
  const Vector& qd() const { return qd_; }

 private:
  // The library's law and its output (absent from the closed-form image).
  struct LibraryLaw {
    static gausstrack::ControllerOptions<S> options() {
      gausstrack::ControllerOptions<S> o;
      o.stabilization = {S(1), S(20)};
      if constexpr (L == Law::kDuffingHeld || L == Law::kArmHeld) o.hold = {S(kPeriod), S(0)};
      return o;
    }
    gausstrack::LawFor<Model> controller{Model{}, options()};  // ActuatedController with actuators
    typename gausstrack::LawFor<Model>::Output out{};
  };
  struct NoLaw {};
  // The plant's own dynamics: A q'' + f = Q + u (the same model as the law's: no mismatch, so the
  // float run differs from the double one by rounding alone).
  void acceleration(const Vector& q, const Vector& qd, const Vector& u, S t, Vector& qdd) {
    if constexpr (L == Law::kDifferentialDrive) {
      // A diagonal, one physical row d q'' = g_p: q'' = a + A^-1 d^T (g_p - k psi - d a) / (d A^-1 d^T).
      gausstrack::evaluate_model(model_, q, qd, t, terms_);
      const Vector inverse_mass = terms_.mass_matrix.diagonal().cwiseInverse();
      const Vector a = (terms_.applied_force + u - terms_.nonlinear_force).cwiseProduct(inverse_mass);
      const auto d = terms_.constraint_matrix.row(2).transpose();
      const S target = terms_.constraint_rhs(2) - kPlantRowDamping * terms_.constraint_error_rate(2);
      const S multiplier = (target - d.dot(a)) / d.cwiseProduct(inverse_mass).dot(d);
      qdd = a + multiplier * d.cwiseProduct(inverse_mass);
      return;
    }
    model_.evaluate(q, qd, t, terms_);
    const Vector rhs = terms_.applied_force + u - terms_.nonlinear_force;
    if constexpr (is_arm<L>() || L == Law::kCartPole) {
      qdd = terms_.mass_matrix.llt().solve(rhs);
    } else {
      qdd = rhs.cwiseQuotient(terms_.mass_matrix.diagonal());
    }
  }

  static constexpr S kPlantRowDamping = S(50);  // [1/s]: the plant's slip velocity decays as e^(-50 t)
  Model model_{};
  std::conditional_t<L == Law::kClosedForm, NoLaw, LibraryLaw> law_{};
  gausstrack::TermsOf<Model> terms_{};
  Vector q_ = Vector::Zero(), qd_ = Vector::Zero();
};

}  // namespace firmware

// A differential-drive robot (two driven wheels on one axle) tracking a figure-eight: a machine
// with fewer actuators than coordinates (N = 3, K = 2) and a constraint the ground holds (its
// wheels do not slip sideways). The task is written for a point ahead of the axle, which the two
// actuators can move in any direction; the axle's centre itself cannot be steered sideways at an
// instant (docs/actuation.md, "Posing the task").
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <cstdint>

#include "gausstrack/model.hpp"

namespace gausstrack::systems {

/// q = (x, y, theta): the axle centre [m] and the heading [rad]; mass m at the axle centre, yaw
/// inertia J about it.
///   A = diag(m, m, J),  f = (c v cos theta, c v sin theta, c_w theta'),  Q = 0
///                 rolling resistance c [N s/m] against the speed v = x' cos theta + y' sin theta,
///                 and c_w [N m s] against the yaw rate
///   B = [cos theta, 0; sin theta, 0; 0, 1]      drive force [N] along the heading, yaw torque [N
///   m]
/// Rows (P = 3):
///   0, 1  task, holonomic: the point l ahead of the axle on the figure-eight (Gerono's lemniscate)
///         phi = (x + l cos theta - r sin(w t), y + l sin theta - (r / 2) sin(2 w t))
///   2     physical, nonholonomic: no side slip, psi = -x' sin theta + y' cos theta
///         (the ground holds it; the law never pushes along it)
template <typename Scalar_ = double>
struct DifferentialDrive {
  using Scalar = Scalar_;
  static constexpr int kDof = 3;
  static constexpr int kConstraints = 3;
  static constexpr int kHolonomicRows = 2;
  static constexpr int kNonholonomicRows = 1;
  static constexpr std::uint64_t kPhysicalRowMask = std::uint64_t{1} << 2;
  static constexpr int kActuators = 2;
  using Vector = Eigen::Matrix<Scalar, 3, 1>;
  using Terms = ModelTerms<3, 3, Scalar>;

  Scalar mass = Scalar(10);            ///< m [kg]
  Scalar inertia = Scalar(0.5);        ///< J [kg m^2]
  Scalar rolling_damping = Scalar(2);  ///< c [N s/m]
  Scalar yaw_damping = Scalar(0.2);    ///< c_w [N m s]
  Scalar look_ahead = Scalar(0.3);     ///< l [m]
  Scalar radius = Scalar(2);           ///< r [m], the figure-eight's half width
  Scalar rate = Scalar(0.3);           ///< w [rad/s]

  /// Visits every parameter by name: f(name, reference).
  template <typename F>
  void parameters(F&& f) {
    f("mass", mass), f("inertia", inertia), f("rolling_damping", rolling_damping),
        f("yaw_damping", yaw_damping);
    f("look_ahead", look_ahead), f("radius", radius), f("rate", rate);
  }

  void evaluate(const Vector& q, const Vector& qd, Scalar, Terms& terms) const noexcept {
    using std::cos;
    using std::sin;
    const Scalar c = cos(q(2)), s = sin(q(2));
    const Scalar v = qd(0) * c + qd(1) * s;
    terms.mass_matrix.diagonal() << mass, mass, inertia;
    terms.nonlinear_force << rolling_damping * v * c, rolling_damping * v * s, yaw_damping * qd(2);
  }
  void actuation(const Vector& q, Scalar, Eigen::Matrix<Scalar, 3, 2>& b) const noexcept {
    using std::cos;
    using std::sin;
    b << cos(q(2)), Scalar(0), sin(q(2)), Scalar(0), Scalar(0), Scalar(1);
  }
  template <typename T>
  Eigen::Matrix<T, 2, 1> phi(const Eigen::Matrix<T, 3, 1>& q, const T& t) const {
    using std::cos;
    using std::sin;
    return Eigen::Matrix<T, 2, 1>(
        q(0) + look_ahead * cos(q(2)) - radius * sin(rate * t),
        q(1) + look_ahead * sin(q(2)) - (radius / Scalar(2)) * sin(Scalar(2) * rate * t));
  }
  template <typename T>
  Eigen::Matrix<T, 1, 1> psi(const Eigen::Matrix<T, 3, 1>& q, const Eigen::Matrix<T, 3, 1>& qd,
                             const T&) const {
    using std::cos;
    using std::sin;
    return Eigen::Matrix<T, 1, 1>(-qd(0) * sin(q(2)) + qd(1) * cos(q(2)));
  }
};

}  // namespace gausstrack::systems

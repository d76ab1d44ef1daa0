// A planar arm of three revolute links whose end effector tracks a circle: P = 2 constraint rows
// on N = 3 joints, so Gauss's principle picks, among the infinitely many forces that make the hand
// follow the circle, the one of least A^-1 norm (eq. 32). The mass matrix depends on q, and the
// constraint matrix (the hand's Jacobian) loses rank when the arm is stretched or folded.
#pragma once

#include <Eigen/Core>
#include <cmath>

#include "gausstrack/model.hpp"

namespace gausstrack::systems {

/// q = (q1, q2, q3): relative joint angles [rad]; link i's absolute angle is
/// theta_i = q1 + ... + qi from the x axis, in the vertical x-y plane with gravity along -y.
/// Link i has mass m_i, length l_i, its centre of mass at distance r_i from its joint and moment
/// of inertia I_i about that centre.
///   A(q) = sum_i m_i Jv_i^T Jv_i + I_i Jw_i^T Jw_i   (Jv_i: centre of mass i, Jw_i = [1 .. 1 0 ..])
///   f(q, q') = sum_i m_i Jv_i^T (Jv_i' q')           Coriolis and centrifugal forces [N m]
///   Q(q, q') = sum_i m_i Jv_i^T (0, -gravity) - damping q'   gravity and viscous joint damping,
///                                                    impressed forces [N m]
/// Constraint: the hand p(q) = sum_i l_i (cos theta_i, sin theta_i) on the circle
///   phi(q, t) = p(q) - c - R (cos(w t + phase), sin(w t + phase)) = 0   (two rows).
template <typename Scalar_ = double>
struct PlanarArm {
  using Scalar = Scalar_;
  static constexpr int kDof = 3;
  static constexpr int kConstraints = 2;
  static constexpr int kHolonomicRows = 2;
  using Vector = Eigen::Matrix<Scalar, 3, 1>;
  using Terms = ModelTerms<3, 2, Scalar>;

  Vector mass{Scalar(2), Scalar(1.5), Scalar(1)};          ///< m_i [kg]
  Vector length{Scalar(1), Scalar(0.8), Scalar(0.6)};      ///< l_i [m]
  Vector com{Scalar(0.5), Scalar(0.4), Scalar(0.3)};       ///< r_i [m]
  Vector inertia{Scalar(1) / 6, Scalar(0.08), Scalar(0.03)};  ///< I_i about the centre [kg m^2]
  Scalar gravity = Scalar(9.81);                           ///< [m/s^2], along -y
  Scalar damping = Scalar(0);                              ///< viscous damping of every joint [N m s/rad]
  // The circle the hand tracks.
  Scalar center_x = Scalar(1.2), center_y = Scalar(0.6);   ///< c [m]
  Scalar radius = Scalar(0.3);                             ///< R [m]
  Scalar rate = Scalar(1.2566370614359172);                ///< w [rad/s] (one turn in 5 s)
  Scalar phase = Scalar(0);                                ///< [rad]

  /// Visits every parameter by name: f(name, reference); link i's are mass_i, length_i, com_i,
  /// inertia_i (i = 1..3).
  template <typename F>
  void parameters(F&& f) {
    static constexpr const char* kNames[4][3] = {{"mass_1", "mass_2", "mass_3"},
                                                 {"length_1", "length_2", "length_3"},
                                                 {"com_1", "com_2", "com_3"},
                                                 {"inertia_1", "inertia_2", "inertia_3"}};
    for (int i = 0; i < 3; ++i)
      f(kNames[0][i], mass(i)), f(kNames[1][i], length(i)), f(kNames[2][i], com(i)), f(kNames[3][i], inertia(i));
    f("gravity", gravity), f("damping", damping), f("center_x", center_x), f("center_y", center_y), f("radius", radius);
    f("rate", rate), f("phase", phase);
  }

  void evaluate(const Vector& q, const Vector& qd, Scalar, Terms& terms) const noexcept {
    // Kinematics shared by A, f and Q: absolute angles, their rates, sines and cosines.
    Scalar c[3], s[3], w[3];
    Scalar theta = Scalar(0), omega = Scalar(0);
    for (int i = 0; i < 3; ++i) {
      theta += q(i);
      omega += qd(i);
      c[i] = std::cos(theta);
      s[i] = std::sin(theta);
      w[i] = omega;
    }
    Scalar a[3][3] = {}, f[3] = {}, g[3] = {};
    for (int i = 0; i < 3; ++i) {
      Scalar jx[3] = {}, jy[3] = {};
      Scalar cx = -com(i) * s[i], cy = com(i) * c[i];
      Scalar bx = -com(i) * w[i] * w[i] * c[i], by = -com(i) * w[i] * w[i] * s[i];
      for (int k = i; k >= 0; --k) {
        jx[k] = cx, jy[k] = cy;
        if (k > 0) {
          cx -= length(k - 1) * s[k - 1], cy += length(k - 1) * c[k - 1];
          const Scalar lw2 = length(k - 1) * w[k - 1] * w[k - 1];
          bx -= lw2 * c[k - 1], by -= lw2 * s[k - 1];
        }
      }
      for (int r = 0; r <= i; ++r) {
        for (int k = 0; k <= i; ++k) a[r][k] += mass(i) * (jx[r] * jx[k] + jy[r] * jy[k]) + inertia(i);
        f[r] += mass(i) * (jx[r] * bx + jy[r] * by);
        g[r] -= mass(i) * gravity * jy[r];
      }
    }
    for (int r = 0; r < 3; ++r) {
      for (int k = 0; k < 3; ++k) terms.mass_matrix(r, k) = a[r][k];
      terms.nonlinear_force(r) = f[r];
      terms.applied_force(r) = g[r] - damping * qd(r);
    }
  }

  /// The hand's position p(q) [m].
  template <typename T>
  Eigen::Matrix<T, 2, 1> hand(const Eigen::Matrix<T, 3, 1>& q) const {
    using std::cos, std::sin;
    T theta = q(0);
    T x = length(0) * cos(theta), y = length(0) * sin(theta);
    for (int i = 1; i < 3; ++i) {
      theta = theta + q(i);
      x = x + length(i) * cos(theta);
      y = y + length(i) * sin(theta);
    }
    return {x, y};
  }
  template <typename T>
  Eigen::Matrix<T, 2, 1> phi(const Eigen::Matrix<T, 3, 1>& q, const T& t) const {
    using std::cos, std::sin;
    const T a = rate * t + phase;
    const Eigen::Matrix<T, 2, 1> p = hand(q);
    return {p(0) - (center_x + radius * cos(a)), p(1) - (center_y + radius * sin(a))};
  }
};

/// The same arm with its wrist (joint 3) passive: motors at the shoulder and the elbow alone,
/// K = 2, B = [e1 e2] (torques [N m]). Two motors hold the hand's two rows; the wrist link, hinged
/// at the hand's prescribed path, swings as gravity and the arm's motion take it (the task's zero
/// dynamics: a pendulum hanging from the hand while link 3 points up from the wrist).
template <typename Scalar_ = double>
struct PlanarArmPassiveWrist : PlanarArm<Scalar_> {
  using Scalar = Scalar_;
  static constexpr int kActuators = 2;
  void actuation(const Eigen::Matrix<Scalar, 3, 1>&, Scalar, Eigen::Matrix<Scalar, 3, 2>& b) const noexcept {
    b << Scalar(1), Scalar(0), Scalar(0), Scalar(1), Scalar(0), Scalar(0);
  }
};

}  // namespace gausstrack::systems

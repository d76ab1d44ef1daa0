// The Duffing force of eq. (32) worked out by hand (the floor the benchmarks compare against):
// for D = [1, -1], A = diag(m1, m2) and Q = 0,
//   Q' = (r, -r) / (1/m1 + 1/m2),   r = s''(t) - (a1 - a2),   a = A^-1 (Q - f).
#pragma once

#include <Eigen/Core>

#include "gausstrack/systems/coupled_duffing.hpp"

namespace gausstrack::bench {

inline Eigen::Vector2d duffing_closed_form_force(const systems::CoupledDuffing<double>& m, const Eigen::Vector2d& q,
                                                 const Eigen::Vector2d& qd, double t) {
  const double d = q(0) - q(1), dd = qd(0) - qd(1), x2 = q(1);
  const double coupling = m.k1 * d + m.c1 * dd + m.kb1 * d * d * d;
  const double ground = m.k2 * x2 + m.c2 * qd(1) + m.kb2 * x2 * x2 * x2;
  const double a1 = -coupling / m.m1, a2 = -(ground - coupling) / m.m2;
  const double r = (m.trajectory.acceleration(t) - (a1 - a2)) / (1 / m.m1 + 1 / m.m2);
  return {r, -r};
}

}  // namespace gausstrack::bench

// The Duffing force of eq. (32) worked out by hand (the floor the benchmarks and the firmware
// images compare against): for D = [1, -1], A = diag(m1, m2) and Q = 0,
//   Q' = (r, -r) / (1/m1 + 1/m2),   r = s''(t) - (a1 - a2),   a = A^-1 (Q - f).
#pragma once

#include <Eigen/Core>

#include "gausstrack/systems/coupled_duffing.hpp"

namespace gausstrack::bench {

template <typename S>
Eigen::Matrix<S, 2, 1> duffing_closed_form_force(const systems::CoupledDuffing<S>& m, const Eigen::Matrix<S, 2, 1>& q,
                                                 const Eigen::Matrix<S, 2, 1>& qd, S t) {
  const S d = q(0) - q(1), dd = qd(0) - qd(1), x2 = q(1);
  const S coupling = m.k1 * d + m.c1 * dd + m.kb1 * d * d * d;
  const S ground = m.k2 * x2 + m.c2 * qd(1) + m.kb2 * x2 * x2 * x2;
  const S a1 = -coupling / m.m1, a2 = -(ground - coupling) / m.m2;
  const S r = (m.trajectory.acceleration(t) - (a1 - a2)) / (S(1) / m.m1 + S(1) / m.m2);
  return {r, -r};
}

}  // namespace gausstrack::bench

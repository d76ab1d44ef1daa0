// An independent formulation for the tests and the accuracy study (not part of the product's
// run loop): the constant-length pendulum in its angle coordinate, theta'' = -(g / L) sin(theta)
// with x = L sin(theta), y = L cos(theta) (y downwards), integrated tightly and compared with a
// run of a Cartesian pendulum scene (pendulum_length constraint with mu = 0, gravity on y).
#pragma once

#include <Eigen/Core>
#include <boost/numeric/odeint.hpp>
#include <boost/numeric/odeint/external/eigen/eigen.hpp>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "gausstrack/plant_sim/scene.hpp"
#include "gausstrack/plant_sim/simulation.hpp"

namespace gausstrack::testing {

struct AngleModelComparison {
  double max_difference = 0;  ///< max over samples of |(x, y) - (x, y)_angle| [m]
  double max_angle_deg = 0;   ///< largest |angle| from the vertical reached by the run [deg]
};

inline AngleModelComparison compare_with_angle_model(const plant_sim::Scene& s, const plant_sim::RunResult& run) {
  namespace odeint = boost::numeric::odeint;
  using plant_sim::EffectKind;
  if (s.constraints.size() != 1 || s.constraints[0].kind != plant_sim::ConstraintKind::kPendulumLength ||
      s.constraints[0].mu != 0.0)
    throw std::invalid_argument("the angle model is a constant-length pendulum");
  const auto& c = s.constraints.front().coordinates;
  double gravity = 0;
  for (const plant_sim::EffectSpec& e : s.effects)
    if (e.kind == EffectKind::kGravity && e.a == c[1]) gravity += e.value;
  const double L = s.constraints.front().length;
  const auto i = [](int k) { return static_cast<std::size_t>(k); };
  const double x0 = s.q0[i(c[0])], y0 = s.q0[i(c[1])], xd0 = s.qd0[i(c[0])], yd0 = s.qd0[i(c[1])];
  using S2 = Eigen::Matrix<double, 2, 1>;
  const S2 th(std::atan2(x0, y0), (xd0 * y0 - yd0 * x0) / (x0 * x0 + y0 * y0));
  auto pendulum = [&](const S2& z, S2& dz, double) { dz << z(1), -gravity / L * std::sin(z(0)); };
  using D2 = odeint::runge_kutta_dopri5<S2, double, S2, double, odeint::vector_space_algebra>;
  auto ds = odeint::make_dense_output(1e-13, 1e-13, D2());
  ds.initialize(th, 0.0, 1e-3);
  AngleModelComparison out;
  for (const plant_sim::Sample& smp : run.samples) {
    while (ds.current_time() < smp.t) ds.do_step(pendulum);
    S2 z = th;
    if (smp.t > 0) ds.calc_state(smp.t, z);
    const double x = smp.q[i(c[0])], y = smp.q[i(c[1])];
    out.max_difference = std::max(out.max_difference, std::hypot(x - L * std::sin(z(0)), y - L * std::cos(z(0))));
    out.max_angle_deg = std::max(out.max_angle_deg, std::abs(std::atan2(x, y)) * 180.0 / std::numbers::pi);
  }
  return out;
}

}  // namespace gausstrack::testing

// The control law alone: a puck with drag must follow a circle; the law gives the force once per
// 1 ms period, a fixed-step loop moves the puck under it, and the tracking error is printed.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <gausstrack/tracking_controller.hpp>

struct Puck {  // A q'' + f = Q + force, with the task written as phi(q, t) = 0
  using Scalar = double;
  static constexpr int kDof = 2, kConstraints = 2, kHolonomicRows = 2;
  double mass = 1.0, drag = 0.3, radius = 0.5, rate = 2.0;  // [kg], [N s/m], [m], [rad/s]

  void evaluate(const Eigen::Vector2d&, const Eigen::Vector2d& qd, double,
                gausstrack::ModelTerms<2, 2, double>& terms) const noexcept {
    terms.mass_matrix = mass * Eigen::Matrix2d::Identity();  // A
    terms.nonlinear_force = drag * qd;                       // f (Q stays 0)
  }
  template <typename T>  // q(t) = R (cos wt, sin wt); the library differentiates phi twice
  Eigen::Matrix<T, 2, 1> phi(const Eigen::Matrix<T, 2, 1>& q, const T& t) const {
    using std::cos, std::sin;
    return {q(0) - radius * cos(rate * t), q(1) - radius * sin(rate * t)};
  }
};

int main() {
  gausstrack::ControllerOptions<double> options;
  options.stabilization = {.zeta = 1.0, .omega = 20.0};  // errors decay instead of persisting
  gausstrack::TrackingController<Puck> controller(Puck{}, options);
  gausstrack::TrackingController<Puck>::Output out;
  const Puck& puck = controller.model();
  Eigen::Vector2d q(0.6, 0.0), qd(0.0, 0.0);  // 0.1 m off the circle, at rest
  const double h = 1e-3;                      // control period [s]
  double worst_after_2s = 0;
  for (int k = 0; k <= 5000; ++k) {
    const double t = k * h;
    if (gausstrack::failed(controller.compute(q, qd, t, out)))
      return std::printf("failed: %s\n", gausstrack::to_string(out.diagnostics.status)), 1;
    const double error = out.constraint_error.norm();  // |phi| = distance from the target [m]
    if (k % 1000 == 0) std::printf("t %.0f s  error %.1e m  |force| %.3f N\n", t, error, out.force.norm());
    if (t >= 2.0) worst_after_2s = std::max(worst_after_2s, error);
    const Eigen::Vector2d qdd = (out.force - puck.drag * qd) / puck.mass;  // the puck, force held
    qd += h * qdd;                                                         // semi-implicit Euler
    q += h * qd;
  }
  std::printf("largest error after 2 s: %.1e m\n", worst_after_2s);
  return worst_after_2s < 1e-3 ? 0 : 1;
}

// Integrates the coupled Duffing oscillator of eq. (35) under the control force of eq. (32)
// (Dormand-Prince 5(4), local tolerance 1e-10 as in the paper) and prints the force, its
// closed-loop and feedforward parts and the tracking error over the first second.
#include <boost/numeric/odeint.hpp>
#include <boost/numeric/odeint/external/eigen/eigen.hpp>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "gausstrack/systems/coupled_duffing.hpp"
#include "gausstrack/tracking_controller.hpp"

namespace {

using Duffing = gausstrack::systems::CoupledDuffing<double>;
using State = Eigen::Matrix<double, 4, 1>;  // (x1, x2, x1', x2')

}  // namespace

int main(int argc, char** argv) {
  const double alpha = argc > 1 ? std::atof(argv[1]) : 4.0;
  Duffing model;
  model.trajectory.alpha = alpha;
  gausstrack::TrackingController<Duffing> controller(model);
  gausstrack::TrackingController<Duffing>::Output out;

  auto rhs = [&](const State& x, State& dxdt, double t) {
    controller.compute(x.head<2>(), x.tail<2>(), t, out);
    dxdt << x.tail<2>(), out.acceleration;
  };

  const double d = 2.0;  // x2'(0); x1'(0) = c follows from the constraint
  State x0(1.0, 1.0, model.consistent_x1_velocity(d), d);
  std::vector<double> times;
  for (int i = 0; i <= 20; ++i) times.push_back(0.05 * i);

  namespace odeint = boost::numeric::odeint;
  using Stepper = odeint::runge_kutta_dopri5<State, double, State, double, odeint::vector_space_algebra>;
  std::printf("# coupled Duffing oscillator, eq. (35), tracking x1 - x2 = exp(-%g t) sin(2 pi t)\n",
              alpha);
  std::printf("# %5s %12s %12s %12s %12s %12s %12s %12s\n", "t", "x1", "x2", "f1", "f2",
              "closed_loop1", "feedfwd1", "track_err");
  odeint::integrate_times(
      odeint::make_dense_output(1e-10, 1e-10, Stepper()), rhs, x0, times.begin(), times.end(),
      0.01, [&](const State& x, double t) {
        if (gausstrack::failed(controller.compute(x.head<2>(), x.tail<2>(), t, out))) {
          std::fprintf(stderr, "control law failed at t = %g: %s\n", t,
                       gausstrack::to_string(out.diagnostics.status));
          std::exit(1);
        }
        std::printf("%7.3f %12.6f %12.6f %12.6f %12.6f %12.6f %12.6f %12.3e\n", t, x(0), x(1),
                    out.force(0), out.force(1), out.closed_loop(0), out.feedforward(0),
                    out.constraint_error(0));
      });
  return 0;
}

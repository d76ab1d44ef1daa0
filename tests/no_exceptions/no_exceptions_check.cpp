// Built with -fno-exceptions -fno-rtti: the whole control law compiles and runs for double and
// float, the way a firmware build would use it. Exits nonzero when an answer is wrong.
#include <cmath>
#include <cstdio>

#include "gausstrack/gausstrack.hpp"
#include "gausstrack/systems/coupled_duffing.hpp"
#include "gausstrack/systems/duffing_chain.hpp"
#include "gausstrack/systems/nonholonomic_particle.hpp"
#include "gausstrack/systems/pendulum.hpp"
#include "gausstrack/systems/planar_arm.hpp"

namespace {

int failures = 0;

void expect(bool ok, const char* what) {
  if (!ok) {
    std::printf("FAILED: %s\n", what);
    ++failures;
  }
}

template <typename Scalar>
void check_duffing(gausstrack::InverseStrategy strategy, Scalar tol) {
  using Model = gausstrack::systems::CoupledDuffing<Scalar>;
  gausstrack::ControllerOptions<Scalar> options;
  options.solver.strategy = strategy;
  options.stabilization.omega = Scalar(5);
  gausstrack::TrackingController<Model> controller(Model{}, options);
  typename gausstrack::TrackingController<Model>::Output out;
  const Eigen::Matrix<Scalar, 2, 1> q(Scalar(0.3), Scalar(-0.2)), qd(Scalar(1), Scalar(0.5));
  expect(controller.compute(q, qd, Scalar(0.25), out) == gausstrack::Status::kOk, "duffing status");
  // Equal and opposite force; the constraint x1'' - x2'' = g - 2 zeta w e' - w^2 e is met.
  expect(std::abs(out.force(0) + out.force(1)) <= tol * (1 + std::abs(out.force(0))), "f1 = -f2");
  const Model& m = controller.model();
  const Scalar target = m.trajectory.acceleration(Scalar(0.25)) -
                        Scalar(10) * out.constraint_error_rate(0) - Scalar(25) * out.constraint_error(0);
  expect(std::abs(out.acceleration(0) - out.acceleration(1) - target) <= tol * (1 + std::abs(target)),
         "constraint met");
}

template <typename Model>
void check_runs(const Model& model) {
  using Scalar = typename Model::Scalar;
  gausstrack::TrackingController<Model> controller(model);
  typename gausstrack::TrackingController<Model>::Output out;
  const Eigen::Matrix<Scalar, Model::kDof, 1> q = Eigen::Matrix<Scalar, Model::kDof, 1>::Constant(Scalar(0.5));
  expect(controller.compute(q, q, Scalar(0), out) == gausstrack::Status::kOk, "model status");
  expect(out.force.allFinite(), "finite force");
}

}  // namespace

int main() {
  for (auto s : {gausstrack::InverseStrategy::kCholeskyWithFallback, gausstrack::InverseStrategy::kSvd,
                 gausstrack::InverseStrategy::kCompleteOrthogonal,
                 gausstrack::InverseStrategy::kDampedLeastSquares}) {
    check_duffing<double>(s, 1e-12);
    check_duffing<float>(s, 1e-4f);
  }
  check_runs(gausstrack::systems::Pendulum<double>{});
  check_runs(gausstrack::systems::Pendulum<float>{});
  check_runs(gausstrack::systems::NonholonomicParticle<double>{});
  check_runs(gausstrack::systems::NonholonomicParticle<float>{});
  check_runs(gausstrack::systems::DuffingChain<3, 1, double>{});
  check_runs(gausstrack::systems::DuffingChain<3, 1, float>{});
  check_runs(gausstrack::systems::PlanarArm<double>{});
  check_runs(gausstrack::systems::PlanarArm<float>{});
  std::printf("%s\n", failures == 0 ? "no-exceptions build: all checks passed" : "no-exceptions build: FAILED");
  return failures == 0 ? 0 : 1;
}

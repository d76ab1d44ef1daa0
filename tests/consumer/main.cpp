#include <cmath>
#include <cstdio>

#include <gausstrack/gausstrack.hpp>
#include <gausstrack/systems/coupled_duffing.hpp>

int main() {
  using Model = gausstrack::systems::CoupledDuffing<double>;
  gausstrack::TrackingController<Model> controller;
  gausstrack::TrackingController<Model>::Output out;
  const auto status = controller.compute(Eigen::Vector2d(1, 1), Eigen::Vector2d(2 + 2 * M_PI, 2), 0.0, out);
  std::printf("consumer: status %s, force (%g, %g)\n", gausstrack::to_string(status), out.force(0), out.force(1));
  return status == gausstrack::Status::kOk && std::abs(out.force(0) + out.force(1)) < 1e-12 ? 0 : 1;
}

// Build-cost probe: one translation unit holding a user's 2 x 1 model (examples/my_first_model)
// and one compute() call, as a user's controller has. scripts/build-cost compiles it alone.
#include <cstdio>

#include "gausstrack/tracking_controller.hpp"
#include "my_model.hpp"

int main() {
  gausstrack::TrackingController<TetheredPuck> controller;
  gausstrack::TrackingController<TetheredPuck>::Output out;
  const auto status = controller.compute(Eigen::Vector2d(1, 0), Eigen::Vector2d(0, 0.3), 0.0, out);
  std::printf("%s %g %g\n", gausstrack::to_string(status), out.force(0), out.force(1));
  return gausstrack::failed(status) ? 1 : 0;
}

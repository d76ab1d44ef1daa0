// Build-cost probe: one translation unit holding the 3-link arm (3 x 2, natural-form constraint on
// jets) and one compute() call. scripts/build-cost compiles it alone.
#include <cstdio>

#include "gausstrack/systems/planar_arm.hpp"
#include "gausstrack/tracking_controller.hpp"

int main() {
  using Arm = gausstrack::systems::PlanarArm<double>;
  gausstrack::TrackingController<Arm> controller;
  gausstrack::TrackingController<Arm>::Output out;
  const auto status = controller.compute(Arm::Vector::Constant(0.3), Arm::Vector::Zero(), 0.0, out);
  std::printf("%s %g %g %g\n", gausstrack::to_string(status), out.force(0), out.force(1),
              out.force(2));
  return gausstrack::failed(status) ? 1 : 0;
}

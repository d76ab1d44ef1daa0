// Checks the model before it drives anything: its rows D, g and e' (derived from phi by the
// library) against finite differences of phi along the motion, A symmetric positive definite,
// every output finite; then moves an initial state onto the constraint. Prints the report.
//   my_model_check
#include <cstdio>

#include "gausstrack/consistent_state.hpp"
#include "gausstrack/model_check.hpp"
#include "my_model.hpp"

int main() {
  const TetheredPuck puck;
  int failures = 0;
  // A few states on and off the circle, moving in different directions.
  const double states[][5] = {
      {1.0, 0.2, 0.1, -0.3, 0.0}, {0.3, -0.9, 0.5, 0.2, 1.5}, {-0.2, 1.1, -0.4, 0.7, 4.0}};
  for (const auto& s : states) {
    const Eigen::Vector2d q(s[0], s[1]), qd(s[2], s[3]), qdd(0.2, -0.1);
    const gausstrack::ModelCheckReport report = gausstrack::check_model(puck, q, qd, qdd, s[4]);
    std::printf("at q = (%g, %g), q' = (%g, %g), t = %g:\n%s", s[0], s[1], s[2], s[3], s[4],
                report.text.c_str());
    failures += report.failures;
  }
  Eigen::Vector2d q(0.0, 1.3),
      qd(0.0, 0.0);  // off the circle of radius 1 about the anchor at t = 0
  const bool consistent = gausstrack::make_consistent(puck, q, qd, 0.0);
  std::printf("make_consistent: %s, q = (%.6f, %.6f), q' = (%.6f, %.6f)\n",
              consistent ? "ok" : "failed", q(0), q(1), qd(0), qd(1));
  return failures == 0 && consistent ? 0 : 1;
}

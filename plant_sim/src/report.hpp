// Failure text (internal to plant_sim): numbers and states as the run's failure messages show them.
#pragma once

#include <Eigen/Core>
#include <string>

namespace gausstrack::plant_sim::detail {

/// v with 6 significant digits ("%.6g").
std::string number(double v);
/// "q = (q1, ..., qN), q' = (q1', ..., qN')" for a state x = (q, q').
std::string describe_state(const Eigen::VectorXd& x);

}  // namespace gausstrack::plant_sim::detail

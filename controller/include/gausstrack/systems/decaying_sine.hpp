// The paper's desired relative displacement s(t) = A e^(-alpha t) sin(omega t), eq. (35c).
#pragma once

#include <cmath>
#include <numbers>

namespace gausstrack::systems {

template <typename Scalar = double>
struct DecayingSine {
  Scalar amplitude = Scalar(1);                     ///< A [m]
  Scalar alpha = Scalar(4);                         ///< decay rate [1/s]
  Scalar omega = Scalar(2) * std::numbers::pi_v<Scalar>;  ///< [rad/s]

  /// s(t), for Scalar or a jet (constraints differentiate through it).
  template <typename T>
  T position(const T& t) const {
    using std::exp, std::sin;
    return amplitude * (exp(-alpha * t) * sin(omega * t));
  }
  /// s'(t) and s''(t), for hand-written rows and initial conditions.
  Scalar velocity(Scalar t) const noexcept {
    return amplitude * std::exp(-alpha * t) *
           (omega * std::cos(omega * t) - alpha * std::sin(omega * t));
  }
  Scalar acceleration(Scalar t) const noexcept {
    return amplitude * std::exp(-alpha * t) *
           ((alpha * alpha - omega * omega) * std::sin(omega * t) -
            Scalar(2) * alpha * omega * std::cos(omega * t));
  }
};

}  // namespace gausstrack::systems

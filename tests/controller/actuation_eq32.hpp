// B = I against eq. (32) (actuation_eq32_*_test.cpp): any model with every coordinate actuated,
// and the comparison of ActuatedController with TrackingController at random states for the
// Cholesky, SVD and complete-orthogonal strategies. Split over two files so that no translation
// unit compiles six models' controllers twice over.
#pragma once

#include <gtest/gtest.h>

#include "gausstrack/actuation.hpp"
#include "test_support.hpp"

namespace gausstrack::test {

// Any model with every coordinate actuated (B = I).
template <typename M>
struct FullyActuated : M {
  static constexpr int kActuators = M::kDof;
  FullyActuated() = default;
  explicit FullyActuated(M m) : M(std::move(m)) {}
  void actuation(const Eigen::Matrix<typename M::Scalar, M::kDof, 1>&, typename M::Scalar,
                 Eigen::Matrix<typename M::Scalar, M::kDof, M::kDof>& b) const noexcept {
    b.setIdentity();
  }
};

template <typename Fixed>
double relative_gap(const Fixed& a, const Fixed& b) {
  return (a - b).norm() / (1.0 + b.norm());
}

template <typename M>
void expect_equal_to_eq32(const M& model, const char* name) {
  RandomSource<double> rng(7);
  for (InverseStrategy s : {InverseStrategy::kCholeskyWithFallback, InverseStrategy::kSvd,
                            InverseStrategy::kCompleteOrthogonal}) {
    ControllerOptions<double> o;
    o.solver.strategy = s;
    o.stabilization = {1.0, 20.0};
    TrackingController<M> plain(model, o);
    ActuatedController<FullyActuated<M>> actuated(FullyActuated<M>(model), o);
    // No B declared: the plain case (the plain law's solver) under the Cholesky and SVD
    // strategies, B = I through W^(1/2) = L^-1 under the complete-orthogonal one.
    ActuatedController<M> bare(model, o);
    typename TrackingController<M>::Output expected;
    typename ActuatedController<FullyActuated<M>>::Output got;
    typename ActuatedController<M>::Output got_bare;
    for (int k = 0; k < 20; ++k) {
      const auto q = rng.template matrix<M::kDof, 1>();
      const auto qd = rng.template matrix<M::kDof, 1>();
      const double t = rng.uniform(0, 2);
      ASSERT_EQ(plain.compute(q, qd, t, expected), Status::kOk) << name;
      ASSERT_EQ(actuated.compute(q, qd, t, got), Status::kOk) << name;
      const char* strategy = to_string(s);
      EXPECT_LT(relative_gap(got.force, expected.force), 1e-9) << name << ", " << strategy;
      EXPECT_LT(relative_gap(got.closed_loop, expected.closed_loop), 1e-9)
          << name << ", " << strategy;
      EXPECT_LT(relative_gap(got.feedforward, expected.feedforward), 1e-9)
          << name << ", " << strategy;
      EXPECT_LT(relative_gap(got.stabilizing, expected.stabilizing), 1e-9)
          << name << ", " << strategy;
      EXPECT_LT(relative_gap(got.acceleration, expected.acceleration), 1e-9)
          << name << ", " << strategy;
      EXPECT_EQ(got.control, got.force) << name;
      EXPECT_EQ(got.unmet_rows, 0u) << name;
      ASSERT_EQ(bare.compute(q, qd, t, got_bare), Status::kOk) << name;
      EXPECT_LT(relative_gap(got_bare.force, expected.force), 1e-9)
          << name << ", " << strategy << ", no B";
      EXPECT_LT(relative_gap(got_bare.closed_loop, expected.closed_loop), 1e-9)
          << name << ", " << strategy;
      EXPECT_LT(relative_gap(got_bare.feedforward, expected.feedforward), 1e-9)
          << name << ", " << strategy;
      EXPECT_LT(relative_gap(got_bare.stabilizing, expected.stabilizing), 1e-9)
          << name << ", " << strategy;
      EXPECT_LT(relative_gap(got_bare.acceleration, expected.acceleration), 1e-9)
          << name << ", " << strategy;
      EXPECT_EQ(got_bare.unmet_rows, 0u) << name;
      // The default strategy takes the normal equations exactly when the plain law does (the same
      // task Gram matrix D A^-1 D^T; with B = I declared, the same up to the basis' rounding).
      if (s == InverseStrategy::kCholeskyWithFallback) {
        EXPECT_EQ(got_bare.diagnostics.strategy_used, expected.diagnostics.strategy_used) << name;
        EXPECT_EQ(got.diagnostics.strategy_used, expected.diagnostics.strategy_used) << name;
        EXPECT_EQ(got_bare.diagnostics.warnings & warning::kFellBackToSvd,
                  expected.diagnostics.warnings & warning::kFellBackToSvd)
            << name;
      } else {
        EXPECT_EQ(got_bare.diagnostics.strategy_used, InverseStrategy::kSvd) << name;
      }
    }
  }
}

}  // namespace gausstrack::test

// The actuated law's test systems (actuation_*_test.cpp): a system given by its terms, and the
// Duffing pair with one actuator.
#pragma once

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <Eigen/LU>

#include "gausstrack/actuation.hpp"
#include "gausstrack/systems/coupled_duffing.hpp"
#include "test_support.hpp"

namespace gausstrack::test {

// A system given by its terms: A, f, Q, D, g (and e) fixed, the model ignoring the state; no B:
// every coordinate actuated (B = I).
template <int N, int P>
struct GivenUnactuated {
  using Scalar = double;
  static constexpr int kDof = N;
  static constexpr int kConstraints = P;
  Eigen::Matrix<double, N, N> A = Eigen::Matrix<double, N, N>::Identity();
  Eigen::Matrix<double, N, 1> f = Eigen::Matrix<double, N, 1>::Zero(), Q = Eigen::Matrix<double, N, 1>::Zero();
  Eigen::Matrix<double, P, N> D = Eigen::Matrix<double, P, N>::Zero();
  Eigen::Matrix<double, P, 1> g = Eigen::Matrix<double, P, 1>::Zero();
  Eigen::Matrix<double, P, 1> e = Eigen::Matrix<double, P, 1>::Zero();  ///< the rows' errors
  void evaluate(const Eigen::Matrix<double, N, 1>&, const Eigen::Matrix<double, N, 1>&, double,
                ModelTerms<N, P, double>& terms) const noexcept {
    terms.mass_matrix = A;
    terms.nonlinear_force = f;
    terms.applied_force = Q;
    terms.constraint_matrix = D;
    terms.constraint_rhs = g;
    terms.constraint_error = e;
  }
  static GivenUnactuated random(RandomSource<double>& rng) {
    GivenUnactuated s;
    s.A = rng.spd<N>(100.0, 2.0);
    s.f = rng.matrix<N, 1>();
    s.Q = rng.matrix<N, 1>();
    s.D = rng.matrix<P, N>();
    s.g = rng.matrix<P, 1>();
    return s;
  }
};

// The same with B fixed: K actuators.
template <int N, int P, int K>
struct GivenSystem : GivenUnactuated<N, P> {
  static constexpr int kActuators = K;
  Eigen::Matrix<double, N, K> B = Eigen::Matrix<double, N, K>::Zero();
  void actuation(const Eigen::Matrix<double, N, 1>&, double, Eigen::Matrix<double, N, K>& b) const noexcept { b = B; }

  static GivenSystem random(RandomSource<double>& rng) {
    GivenSystem s;
    static_cast<GivenUnactuated<N, P>&>(s) = GivenUnactuated<N, P>::random(rng);
    s.B = rng.matrix<N, K>();
    return s;
  }
};

// The Duffing pair with a force on mass 1 alone.
struct Duffing1 : systems::CoupledDuffing<double> {
  static constexpr int kActuators = 1;
  void actuation(const Eigen::Vector2d&, double, Eigen::Matrix<double, 2, 1>& b) const noexcept { b << 1, 0; }
};

// Least u^T W u subject to D A^-1 B u = g - D a, by Lagrange multipliers: [2W K^T; K 0] [u; mu] = [0; r].
inline Eigen::VectorXd kkt_control(const Eigen::MatrixXd& A, const Eigen::VectorXd& f, const Eigen::VectorXd& Q,
                            const Eigen::MatrixXd& D, const Eigen::VectorXd& g, const Eigen::MatrixXd& B,
                            const Eigen::MatrixXd& W) {
  const Eigen::MatrixXd Ainv = A.inverse();
  const Eigen::MatrixXd K = D * Ainv * B;
  const Eigen::VectorXd r = g - D * (Ainv * (Q - f));
  const Eigen::Index m = B.cols(), p = D.rows();
  Eigen::MatrixXd kkt = Eigen::MatrixXd::Zero(m + p, m + p);
  kkt.topLeftCorner(m, m) = 2 * W;
  kkt.topRightCorner(m, p) = K.transpose();
  kkt.bottomLeftCorner(p, m) = K;
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(m + p);
  rhs.tail(p) = r;
  return kkt.fullPivLu().solve(rhs).head(m);
}

template <int N, int P, int K>
void expect_least_cost(RandomSource<double>& rng, bool gauss) {
  for (int k = 0; k < 20; ++k) {
    using S = GivenSystem<N, P, K>;
    const S sys = S::random(rng);
    ActuatedController<S> c(sys);
    Eigen::MatrixXd W;
    if (gauss) {
      const Eigen::MatrixXd a = sys.A, b = sys.B;  // at run-time size: one inverse for every size
      W = b.transpose() * a.inverse() * b;
    } else {
      const Eigen::Matrix<double, K, K> w = rng.spd<K>(10.0, 1.0);
      ASSERT_TRUE(c.set_weight(w));
      W = w;
    }
    typename ActuatedController<S>::Output out;
    ASSERT_EQ(c.compute(Eigen::Matrix<double, N, 1>::Zero(), Eigen::Matrix<double, N, 1>::Zero(), 0.0, out), Status::kOk);
    const Eigen::VectorXd u = kkt_control(sys.A, sys.f, sys.Q, sys.D, sys.g, sys.B, W);
    EXPECT_LT((out.control - u).norm() / (1 + u.norm()), 1e-9) << N << "x" << P << "x" << K << (gauss ? " Gauss" : " given W");
    EXPECT_LT((out.force - sys.B * u).norm() / (1 + u.norm()), 1e-9);
    // The rows are met, and the parts add up to the whole.
    EXPECT_EQ(out.unmet_rows, 0u);
    EXPECT_LT((sys.D * out.acceleration - sys.g).norm(), 1e-9 * (1 + sys.g.norm()));
    EXPECT_LT((out.control_closed_loop + out.control_feedforward + out.control_stabilizing - out.control).norm(),
              1e-12 * (1 + out.control.norm()));
  }
}

}  // namespace gausstrack::test

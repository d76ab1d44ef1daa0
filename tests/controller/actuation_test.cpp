// The actuated law (ActuatedController, actuation.hpp) against independent formulations: eq. (32)
// through TrackingController for every shipped model and strategy when B = I; a Lagrange-multiplier
// (KKT) solve of least u^T W u subject to the task rows, for Gauss's weight and for a given one;
// the least-squares answer through a Moore-Penrose inverse when the rows cannot all be actuated;
// closed forms (one actuator on one mass of the Duffing pair, two actuators on one coordinate);
// bad inputs; no allocation.
#undef NDEBUG
#define EIGEN_RUNTIME_NO_MALLOC

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <cmath>
#include <limits>

#include "allocation_counter.hpp"
#include "gausstrack/actuation.hpp"
#include "gausstrack/systems/cart_double_pendulum.hpp"
#include "gausstrack/systems/cart_pole.hpp"
#include "gausstrack/systems/coupled_duffing.hpp"
#include "gausstrack/systems/duffing_chain.hpp"
#include "gausstrack/systems/nonholonomic_particle.hpp"
#include "gausstrack/systems/pendulum.hpp"
#include "gausstrack/systems/planar_arm.hpp"
#include "oracles.hpp"
#include "test_support.hpp"

namespace gausstrack::test {
namespace {

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
    typename TrackingController<M>::Output expected;
    typename ActuatedController<FullyActuated<M>>::Output got;
    for (int k = 0; k < 20; ++k) {
      const auto q = rng.template matrix<M::kDof, 1>();
      const auto qd = rng.template matrix<M::kDof, 1>();
      const double t = rng.uniform(0, 2);
      ASSERT_EQ(plain.compute(q, qd, t, expected), Status::kOk) << name;
      ASSERT_EQ(actuated.compute(q, qd, t, got), Status::kOk) << name;
      const char* strategy = to_string(s);
      EXPECT_LT(relative_gap(got.force, expected.force), 1e-9) << name << ", " << strategy;
      EXPECT_LT(relative_gap(got.closed_loop, expected.closed_loop), 1e-9) << name << ", " << strategy;
      EXPECT_LT(relative_gap(got.feedforward, expected.feedforward), 1e-9) << name << ", " << strategy;
      EXPECT_LT(relative_gap(got.stabilizing, expected.stabilizing), 1e-9) << name << ", " << strategy;
      EXPECT_LT(relative_gap(got.acceleration, expected.acceleration), 1e-9) << name << ", " << strategy;
      EXPECT_EQ(got.control, got.force) << name;
      EXPECT_EQ(got.unmet_rows, 0u) << name;
    }
  }
}

TEST(Actuation, EveryCoordinateActuatedIsEq32ForEveryShippedModelAndStrategy) {
  expect_equal_to_eq32(systems::CoupledDuffing<double>{}, "coupled_duffing");
  expect_equal_to_eq32(systems::Pendulum<double>{}, "pendulum");
  expect_equal_to_eq32(systems::NonholonomicParticle<double>{}, "nonholonomic_particle");
  expect_equal_to_eq32(systems::PlanarArm<double>{}, "planar_arm");
  expect_equal_to_eq32(systems::DuffingChain<8, 4>{}, "duffing_chain");
  expect_equal_to_eq32(systems::CartDoublePendulum<double>{}, "cart_double_pendulum");
}

// A system given by its terms: A, f, Q, D, g and B fixed (the model ignores the state).
template <int N, int P, int K>
struct GivenSystem {
  using Scalar = double;
  static constexpr int kDof = N;
  static constexpr int kConstraints = P;
  static constexpr int kActuators = K;
  Eigen::Matrix<double, N, N> A = Eigen::Matrix<double, N, N>::Identity();
  Eigen::Matrix<double, N, 1> f = Eigen::Matrix<double, N, 1>::Zero(), Q = Eigen::Matrix<double, N, 1>::Zero();
  Eigen::Matrix<double, P, N> D = Eigen::Matrix<double, P, N>::Zero();
  Eigen::Matrix<double, P, 1> g = Eigen::Matrix<double, P, 1>::Zero();
  Eigen::Matrix<double, N, K> B = Eigen::Matrix<double, N, K>::Zero();
  void evaluate(const Eigen::Matrix<double, N, 1>&, const Eigen::Matrix<double, N, 1>&, double,
                ModelTerms<N, P, double>& terms) const noexcept {
    terms.mass_matrix = A;
    terms.nonlinear_force = f;
    terms.applied_force = Q;
    terms.constraint_matrix = D;
    terms.constraint_rhs = g;
  }
  void actuation(const Eigen::Matrix<double, N, 1>&, double, Eigen::Matrix<double, N, K>& b) const noexcept { b = B; }

  static GivenSystem random(RandomSource<double>& rng) {
    GivenSystem s;
    s.A = rng.spd<N>(100.0, 2.0);
    s.f = rng.matrix<N, 1>();
    s.Q = rng.matrix<N, 1>();
    s.D = rng.matrix<P, N>();
    s.g = rng.matrix<P, 1>();
    s.B = rng.matrix<N, K>();
    return s;
  }
};

// Least u^T W u subject to D A^-1 B u = g - D a, by Lagrange multipliers: [2W K^T; K 0] [u; mu] = [0; r].
Eigen::VectorXd kkt_control(const Eigen::MatrixXd& A, const Eigen::VectorXd& f, const Eigen::VectorXd& Q,
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
      W = sys.B.transpose() * sys.A.inverse() * sys.B;
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

TEST(Actuation, LeastCostAmongCommandsMeetingTheRowsAsLagrangeMultipliersGiveIt) {
  RandomSource<double> rng(11);
  for (bool gauss : {true, false}) {
    expect_least_cost<4, 2, 3>(rng, gauss);
    expect_least_cost<6, 2, 2>(rng, gauss);
    expect_least_cost<5, 1, 5>(rng, gauss);
    expect_least_cost<8, 3, 6>(rng, gauss);
  }
}

// More rows than actuators: the least-squares answer W^(-1/2) (K W^(-1/2))^+ r, the rows flagged,
// and the force still in the range of B.
TEST(Actuation, RowsBeyondTheActuatorsAreMetInTheLeastSquaresSenseAndFlagged) {
  RandomSource<double> rng(13);
  using S = GivenSystem<5, 3, 2>;
  for (int k = 0; k < 20; ++k) {
    const S sys = S::random(rng);
    ActuatedController<S> c(sys);
    S::Scalar t = 0;
    ActuatedController<S>::Output out;
    ASSERT_EQ(c.compute(Eigen::Matrix<double, 5, 1>::Zero(), Eigen::Matrix<double, 5, 1>::Zero(), t, out), Status::kOk);
    const Eigen::MatrixXd Ainv = sys.A.inverse();
    const Eigen::MatrixXd W = sys.B.transpose() * Ainv * sys.B;
    const Eigen::MatrixXd R = W.llt().matrixU();  // W = R^T R
    const Eigen::MatrixXd Rinv = R.inverse();
    const Eigen::VectorXd r = sys.g - sys.D * (Ainv * (sys.Q - sys.f));
    const Eigen::VectorXd u = Rinv * oracle::pseudo_inverse(sys.D * Ainv * sys.B * Rinv, 1e-12) * r;
    EXPECT_LT((out.control - u).norm() / (1 + u.norm()), 1e-9);
    EXPECT_TRUE(out.diagnostics.has(warning::kRankDeficient));
    EXPECT_TRUE(out.diagnostics.has(warning::kConstraintsNotMet));
    EXPECT_NE(out.unmet_rows, 0u);
    EXPECT_EQ(out.diagnostics.rank, 2);
    // B u: its component off B's range, by an independent projection, is rounding.
    const Eigen::Matrix<double, 5, 5> project = sys.B * oracle::pseudo_inverse(sys.B, 1e-12);
    EXPECT_LT((out.force - project * out.force).norm(), 1e-12 * (1 + out.force.norm()));
  }
}

// The Duffing pair with a force on mass 1 alone.
struct Duffing1 : systems::CoupledDuffing<double> {
  static constexpr int kActuators = 1;
  void actuation(const Eigen::Vector2d&, double, Eigen::Matrix<double, 2, 1>& b) const noexcept { b << 1, 0; }
};

// Closed form: the Duffing pair's task x1 - x2 = x_d(t) with a force on mass 1 alone needs
// u = m1 (g - (a1 - a2)), and the rows are met.
TEST(Actuation, OneActuatorOnTheFirstMassOfTheDuffingPairIsTheClosedForm) {
  ActuatedController<Duffing1> c;
  TrackingController<systems::CoupledDuffing<double>> plain;  // for the model's terms at the state
  RandomSource<double> rng(17);
  for (int k = 0; k < 10; ++k) {
    const Eigen::Vector2d q = rng.matrix<2, 1>(), qd = rng.matrix<2, 1>();
    const double t = rng.uniform(0, 3);
    ActuatedController<Duffing1>::Output out;
    ASSERT_EQ(c.compute(q, qd, t, out), Status::kOk);
    TrackingController<systems::CoupledDuffing<double>>::Output unused;
    ASSERT_EQ(plain.compute(q, qd, t, unused), Status::kOk);
    const auto& terms = plain.terms();
    const Eigen::Vector2d a = terms.mass_matrix.ldlt().solve(terms.applied_force - terms.nonlinear_force);
    const double expected = terms.mass_matrix(0, 0) * (terms.constraint_rhs(0) - (a(0) - a(1)));
    EXPECT_NEAR(out.control(0), expected, 1e-12 * (1 + std::abs(expected)));
    EXPECT_EQ(out.force(1), 0.0);
    EXPECT_EQ(out.unmet_rows, 0u);
  }
}

// Closed forms: two independent unit masses tracked each, one actuator on the first: the second
// row cannot be actuated (flagged alone) and the first is met exactly. Two actuators on one
// coordinate with W = diag(w1, w2) share the force as 1 / w_i (Gauss's weight would be singular).
TEST(Actuation, AnUnactuatedRowIsNamedAndRedundantActuatorsShareByTheWeight) {
  GivenSystem<2, 2, 1> two;
  two.D.setIdentity();
  two.g << 0.7, -0.4;
  two.B << 1, 0;
  ActuatedController<GivenSystem<2, 2, 1>> c(two);
  ActuatedController<GivenSystem<2, 2, 1>>::Output out;
  ASSERT_EQ(c.compute(Eigen::Vector2d::Zero(), Eigen::Vector2d::Zero(), 0.0, out), Status::kOk);
  EXPECT_EQ(out.unmet_rows, 0b10u);
  EXPECT_NEAR(out.control(0), 0.7, 1e-15);
  EXPECT_NEAR(out.row_residual(1), 0.4, 1e-15);

  GivenSystem<1, 1, 2> shared;
  shared.D << 1;
  shared.g << 3.0;
  shared.B << 1, 1;
  ActuatedController<GivenSystem<1, 1, 2>> redundant(shared);
  ActuatedController<GivenSystem<1, 1, 2>>::Output r;
  EXPECT_EQ(redundant.compute(Eigen::Matrix<double, 1, 1>::Zero(), Eigen::Matrix<double, 1, 1>::Zero(), 0.0, r),
            Status::kWeightNotPositiveDefinite);
  EXPECT_EQ(r.control, Eigen::Vector2d::Zero());
  ASSERT_TRUE(redundant.set_weight(Eigen::Vector2d(1.0, 4.0).asDiagonal().toDenseMatrix()));
  ASSERT_EQ(redundant.compute(Eigen::Matrix<double, 1, 1>::Zero(), Eigen::Matrix<double, 1, 1>::Zero(), 0.0, r),
            Status::kOk);
  EXPECT_NEAR(r.control(0), 3.0 * 4.0 / 5.0, 1e-14);
  EXPECT_NEAR(r.control(1), 3.0 * 1.0 / 5.0, 1e-14);
  EXPECT_FALSE(redundant.set_weight(Eigen::Vector2d(1.0, -4.0).asDiagonal().toDenseMatrix()));
}

// With a hold the commands are the actuated law's at the middle of the hold interval, at the state
// predicted through the acceleration the measured state's commands give (as TrackingController).
TEST(Actuation, TheHeldCommandsAreTheLawAtThePredictedMidpoint) {
  ControllerOptions<double> o;
  o.stabilization = {1.0, 20.0};
  const double h = 1e-3, d = 2e-4, t = 0.3, tau = d + h / 2;
  const Eigen::Vector2d q(1.02, 0.97), qd(8.1, 2.2);
  ActuatedController<Duffing1> held(Duffing1{}, o), plain(Duffing1{}, o);
  ASSERT_TRUE(held.set_hold({h, d}));
  ActuatedController<Duffing1>::Output out, at_t, at_m;
  ASSERT_EQ(held.compute(q, qd, t, out), Status::kOk);
  ASSERT_EQ(plain.compute(q, qd, t, at_t), Status::kOk);
  const Eigen::Vector2d q_m = q + tau * qd + 0.5 * tau * tau * at_t.acceleration;
  const Eigen::Vector2d qd_m = qd + tau * at_t.acceleration;
  ASSERT_EQ(plain.compute(q_m, qd_m, t + tau, at_m), Status::kOk);
  EXPECT_NEAR(out.control(0), at_m.control(0), 1e-12 * (1 + std::abs(at_m.control(0))));
  EXPECT_GT(std::abs(out.control(0) - at_t.control(0)), 1e-6 * std::abs(at_t.control(0)));  // the hold moved it
  EXPECT_EQ(out.constraint_error, at_t.constraint_error);
  EXPECT_FALSE(out.diagnostics.has(warning::kHoldAtMeasuredState));
}

// Columns of B that are dependent (the second three times the first) make Gauss's weight
// singular: refused, not answered with a command of 1 / eps along B's null space.
TEST(Actuation, DependentActuatorsAreRefusedUnderGausssWeight) {
  RandomSource<double> rng(19);
  GivenSystem<3, 1, 2> sys = GivenSystem<3, 1, 2>::random(rng);
  sys.B.col(1) = 3.0 * sys.B.col(0);
  ActuatedController<GivenSystem<3, 1, 2>> c(sys);
  ActuatedController<GivenSystem<3, 1, 2>>::Output out;
  EXPECT_EQ(c.compute(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), 0.0, out), Status::kWeightNotPositiveDefinite);
  EXPECT_TRUE(out.control.isZero(0));
}

// Actuator limits scale the commands as a whole and say so; the force is B times the scaled u.
TEST(Actuation, ActuatorLimitsScaleTheCommands) {
  ActuatedController<Duffing1> free_law, limited;
  ActuatedController<Duffing1>::Output f, l;
  const Eigen::Vector2d q(1.3, 0.2), qd(3.0, -1.0);
  ASSERT_EQ(free_law.compute(q, qd, 0.4, f), Status::kOk);
  ASSERT_GT(std::abs(f.control(0)), 1.0);
  ASSERT_TRUE(limited.set_actuator_limit(Eigen::Matrix<double, 1, 1>(0.5)));
  ASSERT_EQ(limited.compute(q, qd, 0.4, l), Status::kOk);
  EXPECT_TRUE(l.diagnostics.has(warning::kSaturated));
  EXPECT_NEAR(std::abs(l.control(0)), 0.5, 1e-15);
  EXPECT_NEAR(l.saturation_scale, 0.5 / std::abs(f.control(0)), 1e-15);
  EXPECT_EQ(l.force(0), l.control(0));
  EXPECT_FALSE(limited.set_actuator_limit(Eigen::Matrix<double, 1, 1>(0.0)));
}

// The cart-pole's pendulum nearly horizontal: the cart's force barely reaches the angle
// (D A^-1 B = -m l cos theta / det A). With one row and one actuator the task's own condition is
// 1; measured against D A^(-1/2) the loss of reach is flagged.
TEST(Actuation, ActuatorsThatBarelyReachTheRowAreFlagged) {
  ActuatedController<systems::CartPole<double>> c;
  ActuatedController<systems::CartPole<double>>::Output out;
  ASSERT_EQ(c.compute(Eigen::Vector2d(0.0, 0.3), Eigen::Vector2d(0.0, 1.0), 0.0, out), Status::kOk);
  EXPECT_FALSE(out.diagnostics.has(warning::kIllConditioned));
  ASSERT_EQ(c.compute(Eigen::Vector2d(0.0, std::acos(1e-12)), Eigen::Vector2d(0.0, 1.0), 0.0, out), Status::kOk);
  EXPECT_TRUE(out.diagnostics.has(warning::kIllConditioned)) << out.diagnostics.condition_estimate;
}

// The cart-pole's A, f and Q against its Lagrangian, differentiated numerically: T from the bob's
// velocity (x' + l cos theta theta', l sin theta theta'), V = -m g l cos theta;
// A = d2T/dqd2, f = (d/dq dT/dqd) qd - dT/dq, Q = -dV/dq.
TEST(Actuation, CartPoleTermsAreItsLagrangians) {
  const systems::CartPole<double> m;
  auto kinetic = [&](const Eigen::Vector2d& q, const Eigen::Vector2d& qd) {
    const double vx = qd(0) + m.length * std::cos(q(1)) * qd(1), vy = m.length * std::sin(q(1)) * qd(1);
    return 0.5 * m.cart_mass * qd(0) * qd(0) + 0.5 * m.mass * (vx * vx + vy * vy);
  };
  auto potential = [&](const Eigen::Vector2d& q) { return -m.mass * m.gravity * m.length * std::cos(q(1)); };
  auto momentum = [&](const Eigen::Vector2d& q, const Eigen::Vector2d& qd) {  // dT/dqd, exact for a quadratic
    Eigen::Vector2d p;
    for (int i = 0; i < 2; ++i) {
      const Eigen::Vector2d e = Eigen::Vector2d::Unit(i);
      p(i) = (kinetic(q, qd + e) - kinetic(q, qd - e)) / 2;
    }
    return p;
  };
  RandomSource<double> rng(23);
  for (int k = 0; k < 10; ++k) {
    const Eigen::Vector2d q = 2 * rng.matrix<2, 1>(), qd = 2 * rng.matrix<2, 1>();
    ModelTerms<2, 1, double> terms;
    m.evaluate(q, qd, 0.0, terms);
    const double h = 1e-5;
    Eigen::Matrix2d a, dp_dq;
    Eigen::Vector2d dt_dq, dv_dq;
    for (int j = 0; j < 2; ++j) {
      const Eigen::Vector2d e = Eigen::Vector2d::Unit(j);
      a.col(j) = (momentum(q, qd + e) - momentum(q, qd - e)) / 2;
      dp_dq.col(j) = (momentum(q + h * e, qd) - momentum(q - h * e, qd)) / (2 * h);
      dt_dq(j) = (kinetic(q + h * e, qd) - kinetic(q - h * e, qd)) / (2 * h);
      dv_dq(j) = (potential(q + h * e) - potential(q - h * e)) / (2 * h);
    }
    EXPECT_LT((terms.mass_matrix - a).norm(), 1e-9);
    EXPECT_LT((terms.nonlinear_force - (dp_dq * qd - dt_dq)).norm(), 1e-7);
    EXPECT_LT((terms.applied_force + dv_dq).norm(), 1e-7);
  }
}

TEST(Actuation, ANonFiniteActuationIsRefusedWithZeroOutputs) {
  GivenSystem<2, 1, 1> sys;
  sys.D << 1, -1;
  sys.g << 1;
  sys.B << std::numeric_limits<double>::quiet_NaN(), 0;
  ActuatedController<GivenSystem<2, 1, 1>> c(sys);
  ActuatedController<GivenSystem<2, 1, 1>>::Output out;
  EXPECT_EQ(c.compute(Eigen::Vector2d::Zero(), Eigen::Vector2d::Zero(), 0.0, out), Status::kNonFiniteInput);
  EXPECT_EQ(out.diagnostics.non_finite_inputs, input::kActuation);
  EXPECT_TRUE(out.force.isZero(0));
  EXPECT_TRUE(out.control.isZero(0));
}

TEST(Actuation, AllocationFree) {
  ActuatedController<Duffing1> c;
  ActuatedController<FullyActuated<systems::PlanarArm<double>>> arm;
  ActuatedController<Duffing1>::Output out;
  ActuatedController<FullyActuated<systems::PlanarArm<double>>>::Output arm_out;
  Eigen::internal::set_is_malloc_allowed(false);
  const long n = support::allocations_during([&] {
    for (int i = 0; i < 10; ++i) {
      ASSERT_EQ(c.compute(Eigen::Vector2d(0.1 * i, 0.2), Eigen::Vector2d(1, 2), 0.01 * i, out), Status::kOk);
      ASSERT_EQ(arm.compute(Eigen::Vector3d(0.3, 0.2 * i, 0.1), Eigen::Vector3d(0, 1, 0), 0.01 * i, arm_out),
                Status::kOk);
    }
  });
  Eigen::internal::set_is_malloc_allowed(true);
  EXPECT_EQ(n, 0);
}

}  // namespace
}  // namespace gausstrack::test

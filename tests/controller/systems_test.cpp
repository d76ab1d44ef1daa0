// The paper's systems as models: their hand-derived D and g agree with finite differences of
// the constraint functions, and the Duffing chain of size 2 is the coupled Duffing oscillator.
#include "gausstrack/systems/coupled_duffing.hpp"
#include "gausstrack/systems/duffing_chain.hpp"
#include "gausstrack/systems/nonholonomic_particle.hpp"
#include "gausstrack/systems/pendulum.hpp"
#include "gausstrack/model.hpp"
#include "test_support.hpp"

namespace gausstrack::test {
namespace {

static_assert(Model<systems::CoupledDuffing<double>> && HasPositionError<systems::CoupledDuffing<double>>);
static_assert(Model<systems::Pendulum<float>> && HasVelocityError<systems::Pendulum<float>>);
static_assert(Model<systems::NonholonomicParticle<double>> &&
              !HasPositionError<systems::NonholonomicParticle<double>> &&
              HasVelocityError<systems::NonholonomicParticle<double>>);
static_assert(Model<systems::DuffingChain<8, 4>>);

// Along q(s) = q + qd s + qdd s^2 / 2 (time t + s), the constraint error e has
// e'(0) = constraint_error_rate and e''(0) = D qdd - g. Central differences, step h.
template <typename M>
void check_holonomic_derivatives(const M& model, RandomSource<double>& rng, double scale) {
  constexpr int N = M::kDof;
  using V = Eigen::Matrix<double, N, 1>;
  for (int it = 0; it < 200; ++it) {
    const V q = scale * rng.matrix<N, 1>(), qd = rng.matrix<N, 1>(), qdd = rng.matrix<N, 1>();
    const double t = rng.uniform(0, 5), h = 1e-4;
    auto e = [&](double s) { return model.constraint_error(V(q + qd * s + 0.5 * qdd * s * s), t + s); };
    using R = Eigen::Matrix<double, M::kConstraints, 1>;
    const R first = (e(h) - e(-h)) / (2 * h);
    const R second = (e(h) - 2 * e(0) + e(-h)) / (h * h);
    const R rate = model.constraint_error_rate(q, qd, t);
    const R expected = model.constraint_matrix(q, t) * qdd - model.constraint_rhs(q, qd, t);
    ASSERT_TRUE(near(first, rate, 1e-6, 1 + inf_norm(rate), "e' by differences")) << "state " << it;
    ASSERT_TRUE(near(second, expected, 1e-4, 1 + inf_norm(expected), "D q'' - g by differences"))
        << "state " << it;
  }
}

TEST(Systems, PendulumConstraintDerivatives) {
  RandomSource<double> rng(1);
  systems::Pendulum<double> constant;
  check_holonomic_derivatives(constant, rng, 1.0);
  systems::Pendulum<double> nonlinear;
  nonlinear.mu = -0.1;
  check_holonomic_derivatives(nonlinear, rng, 1.0);
}

TEST(Systems, DuffingConstraintDerivatives) {
  RandomSource<double> rng(2);
  systems::CoupledDuffing<double> duffing;
  check_holonomic_derivatives(duffing, rng, 2.0);
  systems::DuffingChain<6, 4> chain;
  chain.trajectories[1].omega = 3.0;
  chain.trajectories[3].alpha = 0.4;
  check_holonomic_derivatives(chain, rng, 2.0);
}

// The nonholonomic e' = y' - z x' has d/ds e'(q(s), q'(s)) = D q'' - g.
TEST(Systems, ParticleConstraintDerivative) {
  RandomSource<double> rng(3);
  systems::NonholonomicParticle<double> p;
  for (int it = 0; it < 200; ++it) {
    const Eigen::Vector3d q = rng.matrix<3, 1>(), qd = rng.matrix<3, 1>(), qdd = rng.matrix<3, 1>();
    const double h = 1e-5;
    auto rate = [&](double s) {
      return p.constraint_error_rate(Eigen::Vector3d(q + qd * s + 0.5 * qdd * s * s),
                                     Eigen::Vector3d(qd + qdd * s), 0.0);
    };
    const Eigen::Matrix<double, 1, 1> derivative = (rate(h) - rate(-h)) / (2 * h);
    const Eigen::Matrix<double, 1, 1> expected = p.constraint_matrix(q, 0.0) * qdd - p.constraint_rhs(q, qd, 0.0);
    ASSERT_TRUE(near(derivative, expected, 1e-8, 1 + inf_norm(expected), "particle"));
  }
}

TEST(Systems, DuffingChainOfTwoIsTheCoupledDuffingOscillator) {
  RandomSource<double> rng(4);
  systems::CoupledDuffing<double> paper;
  systems::DuffingChain<2, 1> chain;
  for (int it = 0; it < 200; ++it) {
    const Eigen::Vector2d q = 2 * rng.matrix<2, 1>(), qd = 2 * rng.matrix<2, 1>();
    const double t = rng.uniform(0, 10);
    ASSERT_TRUE(near(chain.mass_matrix(q, t), paper.mass_matrix(q, t), 0, 1, "A"));
    ASSERT_TRUE(near(chain.nonlinear_force(q, qd, t), paper.nonlinear_force(q, qd, t), 1e-15, 100, "f"));
    ASSERT_TRUE(near(chain.constraint_matrix(q, t), paper.constraint_matrix(q, t), 0, 1, "D"));
    ASSERT_TRUE(near(chain.constraint_rhs(q, qd, t), paper.constraint_rhs(q, qd, t), 0, 1, "g"));
  }
}

// Eq. (35) itself, written independently: the chain's f must be the left side of (35a, 35b)
// minus the inertia terms, with the corrected cubic coefficients kb1 and kb2.
TEST(Systems, DuffingForcesAreEquation35) {
  RandomSource<double> rng(5);
  systems::CoupledDuffing<double> m;
  for (int it = 0; it < 200; ++it) {
    const double x1 = rng.uniform(-2, 2), x2 = rng.uniform(-2, 2), v1 = rng.uniform(-2, 2), v2 = rng.uniform(-2, 2);
    const double f1 = 10 * (x1 - x2) + 0.1 * (v1 - v2) + 1 * std::pow(x1 - x2, 3);
    const double f2 = 12 * x2 - 10 * (x1 - x2) + 0.15 * v2 - 0.1 * (v1 - v2) + 2 * std::pow(x2, 3) -
                      1 * std::pow(x1 - x2, 3);
    ASSERT_TRUE(near(m.nonlinear_force(Eigen::Vector2d(x1, x2), Eigen::Vector2d(v1, v2), 0.0),
                     Eigen::Vector2d(f1, f2), 1e-14, 100, "eq. 35"));
  }
}

}  // namespace
}  // namespace gausstrack::test

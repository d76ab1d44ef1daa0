// Constraints in their natural form: the rows the library derives from phi and psi equal the
// hand-written ones (hand_written_systems.hpp) for every shipped system, random nonlinear
// constraints agree with finite differences, the model checker passes good models and names
// what is wrong with a bad one, and the paper's systems keep their physics.
#include <algorithm>
#include <array>
#include <random>
#include <vector>

#include "gausstrack/consistent_state.hpp"
#include "gausstrack/model_check.hpp"
#include "gausstrack/systems/coupled_duffing.hpp"
#include "gausstrack/systems/duffing_chain.hpp"
#include "gausstrack/systems/nonholonomic_particle.hpp"
#include "gausstrack/systems/pendulum.hpp"
#include "gausstrack/systems/planar_arm.hpp"
#include "gausstrack/tracking_controller.hpp"
#include "hand_written_systems.hpp"
#include "test_support.hpp"

namespace gausstrack::test {
namespace {

static_assert(Model<systems::CoupledDuffing<double>> && Model<systems::Pendulum<float>> &&
              Model<systems::NonholonomicParticle<double>> && Model<systems::DuffingChain<8, 4>> &&
              Model<systems::PlanarArm<double>> && Model<HandArm<double>> && Model<HandParticle<float>>);
static_assert(RowLayout<systems::NonholonomicParticle<double>>::kNonholonomic == 1 &&
              RowLayout<systems::NonholonomicParticle<double>>::kHolonomic == 0 &&
              RowLayout<HandArm<double>>::kAcceleration == 2 && RowLayout<systems::PlanarArm<double>>::kHolonomic == 2);

// Derived and hand-written terms at random states: every entry of D, g, e, e' to 1e-13 relative to
// the size of the row's terms.
template <typename Natural, typename Hand>
void expect_same_rows(const Natural& natural, const Hand& hand, RandomSource<double>& rng, double q_scale) {
  constexpr int N = Natural::kDof, P = Natural::kConstraints;
  for (int it = 0; it < 500; ++it) {
    const Eigen::Matrix<double, N, 1> q = q_scale * rng.matrix<N, 1>(), qd = 2 * rng.matrix<N, 1>();
    const double t = rng.uniform(0, 10);
    TermsOf<Natural> a;
    TermsOf<Hand> b;
    evaluate_model(natural, q, qd, t, a);
    evaluate_model(hand, q, qd, t, b);
    const double scale = 1 + inf_norm(b.constraint_matrix) * (1 + inf_norm(qd)) * (1 + inf_norm(qd)) +
                         inf_norm(b.constraint_rhs) + inf_norm(b.constraint_error);
    ASSERT_TRUE(near(a.constraint_matrix, b.constraint_matrix, 1e-13, scale, "D")) << "state " << it;
    ASSERT_TRUE(near(a.constraint_rhs, b.constraint_rhs, 1e-13, scale, "g")) << "state " << it;
    ASSERT_TRUE(near(a.constraint_error, b.constraint_error, 1e-13, scale, "e")) << "state " << it;
    ASSERT_TRUE(near(a.constraint_error_rate, b.constraint_error_rate, 1e-13, scale, "e'")) << "state " << it;
    ASSERT_TRUE(near(a.mass_matrix, b.mass_matrix, 0, 1, "A"));
    static_assert(P == Hand::kConstraints);
  }
}

TEST(NaturalForm, DerivedRowsEqualHandWrittenForEveryShippedSystem) {
  RandomSource<double> rng(1);
  expect_same_rows(systems::CoupledDuffing<double>{}, HandDuffing<double>{}, rng, 2.0);
  systems::Pendulum<double> pendulum;
  HandPendulum<double> hand_pendulum;
  expect_same_rows(pendulum, hand_pendulum, rng, 20.0);
  pendulum.mu = hand_pendulum.mu = -0.1;
  expect_same_rows(pendulum, hand_pendulum, rng, 3.0);
  expect_same_rows(systems::NonholonomicParticle<double>{}, HandParticle<double>{}, rng, 2.0);
  systems::DuffingChain<6, 4> chain;
  HandDuffingChain<6, 4> hand_chain;
  chain.trajectories[1].omega = hand_chain.trajectories[1].omega = 3.0;
  chain.trajectories[3].alpha = hand_chain.trajectories[3].alpha = 0.4;
  expect_same_rows(chain, hand_chain, rng, 2.0);
  expect_same_rows(systems::PlanarArm<double>{}, HandArm<double>{}, rng, 3.0);
}

// A made-up model mixing every kind of row, with constraints that exercise every function a jet
// implements: two holonomic rows, one nonholonomic row, one hand-written row.
struct Mixed {
  using Scalar = double;
  static constexpr int kDof = 4;
  static constexpr int kConstraints = 4;
  static constexpr int kHolonomicRows = 2;
  static constexpr int kNonholonomicRows = 1;
  using V = Eigen::Matrix<double, 4, 1>;
  double a = 0.7, b = 1.3;
  void evaluate(const V& q, const V& qd, double t, ModelTerms<4, 4, double>& terms) const noexcept {
    terms.mass_matrix = Eigen::Matrix4d::Identity() + 0.1 * Eigen::Matrix4d::Ones();
    terms.nonlinear_force = qd.cwiseProduct(q);
    terms.applied_force.setConstant(std::sin(t));
    // Hand-written row 3: q3 - q0 q1 = cos(t); e' = q3' - q0' q1 - q0 q1' + sin t,
    // D = [-q1, -q0, 0, 1], g = 2 q0' q1' - cos t.
    terms.constraint_matrix.row(3) << -q(1), -q(0), 0, 1;
    terms.constraint_rhs(3) = 2 * qd(0) * qd(1) - std::cos(t);
    terms.constraint_error(3) = q(3) - q(0) * q(1) - std::cos(t);
    terms.constraint_error_rate(3) = qd(3) - qd(0) * q(1) - q(0) * qd(1) + std::sin(t);
  }
  template <typename T>
  Eigen::Matrix<T, 2, 1> phi(const Eigen::Matrix<T, 4, 1>& q, const T& t) const {
    using std::sin, std::cos, std::exp, std::sqrt, std::atan2, std::log, std::tanh, std::pow, std::atan;
    const T r = sqrt(q(0) * q(0) + q(1) * q(1) + T(1));
    return {sin(a * q(0) * t) / (T(2) + cos(q(1))) + exp(-b * t) * q(2) * r - atan2(q(1), q(0) + T(3)),
            log(T(3) + tanh(q(2) * q(3))) + pow(r, 1.5) * atan(q(3) - t) / (T(1) + q(0) * q(0))};
  }
  template <typename T>
  Eigen::Matrix<T, 1, 1> psi(const Eigen::Matrix<T, 4, 1>& q, const Eigen::Matrix<T, 4, 1>& qd, const T& t) const {
    using std::sin, std::cos;
    return Eigen::Matrix<T, 1, 1>(sin(q(0) + t) * qd(1) - q(2) * q(3) * qd(0) + cos(q(1)) * qd(3) + a * t * t);
  }
};
static_assert(Model<Mixed> && RowLayout<Mixed>::kAcceleration == 1);

// phi and psi rows against central finite differences of phi and psi themselves: D by
// differences in q (phi) or q' (psi); e' and g by differences along (q + q' s, t + s).
TEST(NaturalForm, RandomNonlinearConstraintsAgainstFiniteDifferences) {
  RandomSource<double> rng(2);
  const Mixed m;
  for (int it = 0; it < 300; ++it) {
    const Eigen::Vector4d q = rng.matrix<4, 1>(), qd = rng.matrix<4, 1>();
    const double t = rng.uniform(0, 2), h = 1e-5;
    TermsOf<Mixed> terms;
    evaluate_model(m, q, qd, t, terms);
    auto phi = [&](const Eigen::Vector4d& x, double s) { return Eigen::Vector2d(m.phi(x, s)); };
    auto psi = [&](const Eigen::Vector4d& x, const Eigen::Vector4d& v, double s) { return m.psi(x, v, s)(0); };
    for (int j = 0; j < 4; ++j) {
      const Eigen::Vector4d dq = h * Eigen::Vector4d::Unit(j);
      const Eigen::Vector2d dphi = (phi(q + dq, t) - phi(q - dq, t)) / (2 * h);
      ASSERT_TRUE(near(Eigen::Vector2d(terms.constraint_matrix.block<2, 1>(0, j)), dphi, 1e-8, 1 + inf_norm(dphi),
                       "phi_q"));
      const double dpsi = (psi(q, qd + dq, t) - psi(q, qd - dq, t)) / (2 * h);
      ASSERT_NEAR(terms.constraint_matrix(2, j), dpsi, 1e-8 * (1 + std::abs(dpsi)));
    }
    auto phi_along = [&](double s) { return phi(q + qd * s, t + s); };
    const Eigen::Vector2d first = (phi_along(h) - phi_along(-h)) / (2 * h);
    const double hh = 1e-4;
    const Eigen::Vector2d second = (phi_along(hh) - 2 * phi_along(0) + phi_along(-hh)) / (hh * hh);
    EXPECT_TRUE(near(Eigen::Vector2d(terms.constraint_error_rate.head<2>()), first, 1e-8, 1 + inf_norm(first), "e'"));
    EXPECT_TRUE(near(Eigen::Vector2d(-terms.constraint_rhs.head<2>()), second, 1e-5, 1 + inf_norm(second), "g"));
    EXPECT_TRUE(near(Eigen::Vector2d(terms.constraint_error.head<2>()), phi(q, t), 1e-15, 1 + inf_norm(phi(q, t)),
                     "e"));
    const double psi_rate = (psi(q + qd * h, qd, t + h) - psi(q - qd * h, qd, t - h)) / (2 * h);
    EXPECT_NEAR(-terms.constraint_rhs(2), psi_rate, 1e-8 * (1 + std::abs(psi_rate)));
    EXPECT_EQ(terms.constraint_error(2), 0.0);
    EXPECT_NEAR(terms.constraint_error_rate(2), psi(q, qd, t), 1e-15 * (1 + std::abs(psi(q, qd, t))));
  }
}

// Jets store their gradients on an interval of coordinates: rows whose terms touch coordinates
// far apart (a gap between two supports), one coordinate, or t alone through a factor, against
// finite differences, with the entries outside every support exactly zero.
struct Sparse {
  using Scalar = double;
  static constexpr int kDof = 7;
  static constexpr int kConstraints = 3;
  static constexpr int kHolonomicRows = 3;
  using V = Eigen::Matrix<double, 7, 1>;
  void evaluate(const V&, const V&, double, ModelTerms<7, 3, double>& terms) const noexcept {
    terms.mass_matrix.setIdentity();
  }
  template <typename T>
  Eigen::Matrix<T, 3, 1> phi(const Eigen::Matrix<T, 7, 1>& q, const T& t) const {
    using std::sin, std::exp, std::cos;
    const T s = T(0.5) * exp(-T(2) * t) * sin(T(3) * t);  // t alone: no gradient
    return {q(1) * sin(q(5)) - s,                         // {1, 5}: a gap of three
            s * q(3) + cos(t) * q(3) * q(3),              // {3}, scaled by functions of t
            (q(6) - q(0)) / (T(2) + s) + q(2) * q(2) * s - (q(2) - q(2))};  // {0, 2, 6}
  }
};
static_assert(Model<Sparse>);

TEST(NaturalForm, SparseGradientsAgainstFiniteDifferences) {
  RandomSource<double> rng(4);
  const Sparse m;
  const std::array<std::vector<int>, 3> support{{{1, 5}, {3}, {0, 2, 6}}};
  for (int it = 0; it < 200; ++it) {
    const Eigen::Matrix<double, 7, 1> q = rng.matrix<7, 1>(), qd = rng.matrix<7, 1>();
    const double t = rng.uniform(0, 2), h = 1e-5;
    TermsOf<Sparse> terms;
    terms.constraint_matrix.setConstant(7.0);  // every entry must be written
    evaluate_model(m, q, qd, t, terms);
    auto phi = [&](const Eigen::Matrix<double, 7, 1>& x, double s) { return Eigen::Vector3d(m.phi(x, s)); };
    for (int j = 0; j < 7; ++j) {
      const Eigen::Matrix<double, 7, 1> dq = h * Eigen::Matrix<double, 7, 1>::Unit(j);
      const Eigen::Vector3d dphi = (phi(q + dq, t) - phi(q - dq, t)) / (2 * h);
      for (int k = 0; k < 3; ++k) {
        const auto& in = support[static_cast<std::size_t>(k)];
        if (std::find(in.begin(), in.end(), j) == in.end()) {
          ASSERT_EQ(terms.constraint_matrix(k, j), 0.0) << "row " << k << " column " << j;
        } else {
          ASSERT_NEAR(terms.constraint_matrix(k, j), dphi(k), 1e-8 * (1 + std::abs(dphi(k))));
        }
      }
    }
    auto phi_along = [&](double s) { return phi(q + qd * s, t + s); };
    const Eigen::Vector3d first = (phi_along(h) - phi_along(-h)) / (2 * h);
    const double hh = 1e-4;
    const Eigen::Vector3d second = (phi_along(hh) - 2 * phi_along(0) + phi_along(-hh)) / (hh * hh);
    EXPECT_TRUE(near(Eigen::Vector3d(terms.constraint_error_rate), first, 1e-8, 1 + inf_norm(first), "e'"));
    EXPECT_TRUE(near(Eigen::Vector3d(-terms.constraint_rhs), second, 1e-5, 1 + inf_norm(second), "g"));
  }
}

TEST(NaturalForm, FloatDerivativesAgreeWithDouble) {
  RandomSource<double> rng(3);
  systems::PlanarArm<float> arm_f;
  systems::PlanarArm<double> arm_d;
  for (int it = 0; it < 200; ++it) {
    const Eigen::Vector3d q = 3 * rng.matrix<3, 1>(), qd = rng.matrix<3, 1>();
    const double t = rng.uniform(0, 5);
    TermsOf<systems::PlanarArm<float>> f;
    TermsOf<systems::PlanarArm<double>> d;
    evaluate_model(arm_f, Eigen::Vector3f(q.cast<float>()), Eigen::Vector3f(qd.cast<float>()), float(t), f);
    evaluate_model(arm_d, q, qd, t, d);
    ASSERT_TRUE(near(f.constraint_matrix, d.constraint_matrix, 1e-5, 10, "float D"));
    ASSERT_TRUE(near(f.constraint_rhs, d.constraint_rhs, 1e-5, 10 + inf_norm(d.constraint_rhs), "float g"));
  }
}

// The checker passes every shipped model, natural and hand-written, at random states.
template <typename M>
void expect_checker_passes(const M& m, RandomSource<double>& rng, double q_scale, int states = 50) {
  constexpr int N = M::kDof;
  for (int it = 0; it < states; ++it) {
    const Eigen::Matrix<double, N, 1> q = q_scale * rng.matrix<N, 1>(), qd = rng.matrix<N, 1>(),
                                      qdd = rng.matrix<N, 1>();
    const ModelCheckReport r = check_model(m, q, qd, qdd, rng.uniform(0, 5));
    ASSERT_TRUE(r.ok()) << r.text;
    ASSERT_EQ(r.unchecked_rows, 0) << r.text;
  }
}

TEST(ModelCheck, PassesEveryShippedModel) {
  RandomSource<double> rng(4);
  expect_checker_passes(systems::CoupledDuffing<double>{}, rng, 2);
  expect_checker_passes(HandDuffing<double>{}, rng, 2);
  systems::Pendulum<double> p;
  p.mu = -0.1;
  expect_checker_passes(p, rng, 2);
  expect_checker_passes(HandPendulum<double>{}, rng, 2);
  expect_checker_passes(systems::NonholonomicParticle<double>{}, rng, 2);
  expect_checker_passes(HandParticle<double>{}, rng, 2);
  expect_checker_passes(systems::DuffingChain<8, 4>{}, rng, 2);
  expect_checker_passes(HandDuffingChain<8, 4>{}, rng, 2);
  expect_checker_passes(systems::PlanarArm<double>{}, rng, 3);
  expect_checker_passes(HandArm<double>{}, rng, 3);
  expect_checker_passes(Mixed{}, rng, 1);
}

// Each kind of mistake a user makes by hand is caught and named.
template <int Mistake>
struct BrokenArm : HandArm<double> {
  void evaluate(const V& q, const V& qd, double t, Terms& terms) const noexcept {
    HandArm<double>::evaluate(q, qd, t, terms);
    if constexpr (Mistake == 0) terms.constraint_rhs(1) += 0.5 * qd(0) * qd(1);  // a term missing from g
    if constexpr (Mistake == 1) terms.constraint_matrix(0, 2) *= -1;               // a sign in D
    if constexpr (Mistake == 2) terms.mass_matrix(0, 1) += 0.1;                    // A not symmetric
    if constexpr (Mistake == 3) terms.mass_matrix(2, 2) = -1;                      // A not positive definite
    if constexpr (Mistake == 4) terms.nonlinear_force(1) = std::numeric_limits<double>::quiet_NaN();
  }
};

TEST(ModelCheck, NamesWhatIsWrong) {
  const Eigen::Vector3d q(0.3, 0.5, -0.4), qd(0.7, -0.2, 0.9), qdd(0.4, 0.1, -0.6);
  const auto g_wrong = check_model(BrokenArm<0>{}, q, qd, qdd, 0.3);
  EXPECT_FALSE(g_wrong.ok());
  EXPECT_NE(g_wrong.text.find("row 1 (hand-written): de'/ds"), std::string::npos) << g_wrong.text;
  EXPECT_NE(g_wrong.text.find("ok    row 0"), std::string::npos) << g_wrong.text;
  const auto d_wrong = check_model(BrokenArm<1>{}, q, qd, qdd, 0.3);
  EXPECT_FALSE(d_wrong.ok());
  EXPECT_NE(d_wrong.text.find("de'/dq'_2"), std::string::npos) << d_wrong.text;
  const auto asym = check_model(BrokenArm<2>{}, q, qd, qdd, 0.3);
  EXPECT_NE(asym.text.find("A is not symmetric"), std::string::npos) << asym.text;
  const auto indefinite = check_model(BrokenArm<3>{}, q, qd, qdd, 0.3);
  EXPECT_NE(indefinite.text.find("not positive definite"), std::string::npos) << indefinite.text;
  const auto nan = check_model(BrokenArm<4>{}, q, qd, qdd, 0.3);
  EXPECT_FALSE(nan.all_finite);
  EXPECT_NE(nan.text.find("non-finite output: f"), std::string::npos) << nan.text;
  std::printf("%s\n", g_wrong.text.c_str());
}

// A model that declares its mass matrix diagonal but writes an off-diagonal entry is caught: the
// solver would read the diagonal alone and silently drop the coupling.
struct CoupledButDeclaredDiagonal : systems::CoupledDuffing<double> {
  void evaluate(const Vector& q, const Vector& qd, double t, Terms& terms) const noexcept {
    systems::CoupledDuffing<double>::evaluate(q, qd, t, terms);
    terms.mass_matrix(0, 1) = terms.mass_matrix(1, 0) = 0.25;
  }
};
TEST(ModelCheck, DeclaredDiagonalMassMatrixMustBeDiagonal) {
  const Eigen::Vector2d q(0.3, -0.2), qd(0.1, 0.4), qdd(-0.5, 0.2);
  const auto bad = check_model(CoupledButDeclaredDiagonal{}, q, qd, qdd, 0.7);
  EXPECT_FALSE(bad.ok());
  EXPECT_NE(bad.text.find("declared diagonal"), std::string::npos) << bad.text;
  const auto good = check_model(systems::CoupledDuffing<double>{}, q, qd, qdd, 0.7);
  EXPECT_TRUE(good.ok()) << good.text;
  EXPECT_NE(good.text.find("ok    A diagonal, as declared"), std::string::npos) << good.text;
}

// A hand-written row that gives neither e nor e' is reported as unchecked, not passed silently.
struct Bare {
  using Scalar = double;
  static constexpr int kDof = 2;
  static constexpr int kConstraints = 1;
  void evaluate(const Eigen::Vector2d&, const Eigen::Vector2d&, double, ModelTerms<2, 1, double>& terms) const noexcept {
    terms.mass_matrix.setIdentity();
    terms.constraint_matrix << 1, 1;
    terms.constraint_rhs(0) = 1;
  }
};
TEST(ModelCheck, RowsWithoutErrorsAreReportedUnchecked) {
  const auto r = check_model(Bare{}, Eigen::Vector2d(1, 2), Eigen::Vector2d(0, 1), Eigen::Vector2d(1, 0), 0.0);
  EXPECT_EQ(r.unchecked_rows, 1);
  EXPECT_NE(r.text.find("gives neither e nor e'"), std::string::npos) << r.text;
}

// The arm's A and f against the recursive Newton-Euler form, written independently: link by link,
// velocities and accelerations outward, forces and moments inward, joint torques
// tau = A q'' + f - Q. A's column k is tau(q, 0, e_k) without gravity, f is tau(q, q', 0) without
// gravity, -Q is tau(q, 0, 0) with gravity alone.
Eigen::Vector3d rnea(const systems::PlanarArm<double>& arm, const Eigen::Vector3d& q, const Eigen::Vector3d& qd,
                     const Eigen::Vector3d& qdd, double gravity) {
  auto cross = [](double w, const Eigen::Vector2d& r) { return Eigen::Vector2d(-w * r(1), w * r(0)); };
  auto moment = [](const Eigen::Vector2d& r, const Eigen::Vector2d& f) { return r(0) * f(1) - r(1) * f(0); };
  std::array<Eigen::Vector2d, 3> joint_to_com, joint_to_next, com_acc;
  std::array<double, 3> alpha;
  Eigen::Vector2d joint_acc = Eigen::Vector2d::Zero();
  double theta = 0, omega = 0, domega = 0;
  for (int i = 0; i < 3; ++i) {
    theta += q(i);
    omega += qd(i);
    domega += qdd(i);
    const Eigen::Vector2d u(std::cos(theta), std::sin(theta));
    joint_to_com[i] = arm.com(i) * u;
    joint_to_next[i] = arm.length(i) * u;
    com_acc[i] = joint_acc + cross(domega, joint_to_com[i]) - omega * omega * joint_to_com[i];
    joint_acc += cross(domega, joint_to_next[i]) - omega * omega * joint_to_next[i];
    alpha[i] = domega;
  }
  Eigen::Vector3d tau;
  Eigen::Vector2d force_from_outer = Eigen::Vector2d::Zero();
  double moment_from_outer = 0;
  const Eigen::Vector2d g(0, -gravity);
  for (int i = 2; i >= 0; --i) {
    const Eigen::Vector2d f = arm.mass(i) * (com_acc[i] - g) + force_from_outer;  // force joint i exerts on link i
    const double n = arm.inertia(i) * alpha[i] + moment(joint_to_com[i], arm.mass(i) * (com_acc[i] - g)) +
                     moment(joint_to_next[i], force_from_outer) + moment_from_outer;
    tau(i) = n;
    force_from_outer = f;
    moment_from_outer = n;
  }
  return tau;
}

TEST(PlanarArm, MassMatrixAndForcesAgreeWithNewtonEuler) {
  RandomSource<double> rng(5);
  systems::PlanarArm<double> arm;
  arm.mass << 1.7, 2.3, 0.6;
  arm.length << 0.9, 1.1, 0.5;
  arm.com << 0.35, 0.6, 0.2;
  arm.inertia << 0.2, 0.15, 0.02;
  for (int it = 0; it < 500; ++it) {
    const Eigen::Vector3d q = 4 * rng.matrix<3, 1>(), qd = 3 * rng.matrix<3, 1>();
    TermsOf<systems::PlanarArm<double>> terms;
    evaluate_model(arm, q, qd, 0.0, terms);
    Eigen::Matrix3d a;
    for (int k = 0; k < 3; ++k) a.col(k) = rnea(arm, q, Eigen::Vector3d::Zero(), Eigen::Vector3d::Unit(k), 0.0);
    ASSERT_TRUE(near(terms.mass_matrix, a, 1e-12, 1 + inf_norm(a), "A vs RNEA"));
    const Eigen::Vector3d f = rnea(arm, q, qd, Eigen::Vector3d::Zero(), 0.0);
    ASSERT_TRUE(near(terms.nonlinear_force, f, 1e-12, 1 + inf_norm(f), "f vs RNEA"));
    const Eigen::Vector3d gravity_torque = rnea(arm, q, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), arm.gravity);
    ASSERT_TRUE(near(Eigen::Vector3d(-terms.applied_force), gravity_torque, 1e-12, 1 + inf_norm(gravity_torque),
                     "Q vs RNEA"));
  }
}

TEST(ConsistentState, PutsTheArmOnItsCircle) {
  systems::PlanarArm<double> arm;
  Eigen::Vector3d q(0.2, 0.9, 0.6), qd(0.1, -0.3, 0.2);
  ASSERT_TRUE(make_consistent(arm, q, qd, 0.0));
  TermsOf<systems::PlanarArm<double>> terms;
  evaluate_model(arm, q, qd, 0.0, terms);
  EXPECT_LT(terms.constraint_error.norm(), 1e-12);
  EXPECT_LT(terms.constraint_error_rate.norm(), 1e-12);
}

// Eq. (35) itself, written independently: f must be the left side of (35a, 35b) minus the
// inertia terms, with the corrected cubic coefficients kb1 and kb2; and a chain of two masses is
// the coupled oscillator.
TEST(Systems, DuffingForcesAreEquation35) {
  RandomSource<double> rng(6);
  systems::CoupledDuffing<double> m;
  systems::DuffingChain<2, 1> chain;
  for (int it = 0; it < 200; ++it) {
    const double x1 = rng.uniform(-2, 2), x2 = rng.uniform(-2, 2), v1 = rng.uniform(-2, 2), v2 = rng.uniform(-2, 2);
    const double f1 = 10 * (x1 - x2) + 0.1 * (v1 - v2) + 1 * std::pow(x1 - x2, 3);
    const double f2 = 12 * x2 - 10 * (x1 - x2) + 0.15 * v2 - 0.1 * (v1 - v2) + 2 * std::pow(x2, 3) -
                      1 * std::pow(x1 - x2, 3);
    TermsOf<systems::CoupledDuffing<double>> a;
    TermsOf<systems::DuffingChain<2, 1>> b;
    const Eigen::Vector2d q(x1, x2), qd(v1, v2);
    evaluate_model(m, q, qd, 0.3, a);
    evaluate_model(chain, q, qd, 0.3, b);
    ASSERT_TRUE(near(a.nonlinear_force, Eigen::Vector2d(f1, f2), 1e-14, 100, "eq. 35"));
    ASSERT_TRUE(near(b.nonlinear_force, a.nonlinear_force, 1e-15, 100, "chain f"));
    ASSERT_TRUE(near(b.mass_matrix, a.mass_matrix, 0, 1, "chain A"));
    ASSERT_TRUE(near(b.constraint_rhs, a.constraint_rhs, 1e-15, 100, "chain g"));
  }
}

// Per-row Baumgarte gains: stabilizing one row changes only that row's correction.
TEST(Stabilization, PerRowGainsActOnTheirRowOnly) {
  TrackingController<Mixed> controller;
  ASSERT_TRUE(controller.set_stabilization(1, {1.0, 10.0}));
  EXPECT_FALSE(controller.set_stabilization(4, {1.0, 10.0}));
  EXPECT_FALSE(controller.set_stabilization(0, {1.0, -1.0}));
  EXPECT_EQ(controller.stabilization(0).omega, 0.0);
  const Eigen::Vector4d q(0.2, -0.3, 0.5, 0.1), qd(0.3, 0.2, -0.1, 0.4);
  TrackingController<Mixed>::Output out;
  ASSERT_EQ(controller.compute(q, qd, 0.4, out), Status::kOk);
  // D q'' = g + correction, with the correction only in row 1.
  const auto& terms = controller.terms();
  const Eigen::Vector4d achieved = terms.constraint_matrix * out.acceleration - terms.constraint_rhs;
  const double row1 = -2 * 1.0 * 10.0 * terms.constraint_error_rate(1) - 100.0 * terms.constraint_error(1);
  EXPECT_TRUE(near(achieved, Eigen::Vector4d(0, row1, 0, 0), 1e-10, 1 + std::abs(row1), "per-row correction"));
}

}  // namespace
}  // namespace gausstrack::test

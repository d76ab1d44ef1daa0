// Singular configurations: a physical-scale floor on the singular values of D A^(-1/2) flags a
// near-singular solve and bounds its force where a relative rank tolerance cannot see it (every
// row shrinks together); actuator limits are never exceeded and saturation is reported.
#include <Eigen/SVD>

#include "gausstrack/systems/planar_arm.hpp"
#include "gausstrack/tracking_controller.hpp"
#include "test_support.hpp"

namespace gausstrack::test {
namespace {

// A unit point mass in the plane on a circle of radius R about the origin. One row, whose
// gradient D = (x, y) vanishes at the centre: near it, holding the constraint takes a force like
// 1 / |q|, and D A^(-1/2) has a single singular value |q| that no relative tolerance can judge.
struct CircleMass {
  using Scalar = double;
  static constexpr int kDof = 2;
  static constexpr int kConstraints = 1;
  static constexpr int kHolonomicRows = 1;
  double radius = 1.0;
  void evaluate(const Eigen::Vector2d&, const Eigen::Vector2d&, double, ModelTerms<2, 1, double>& terms) const noexcept {
    terms.mass_matrix.setIdentity();
    terms.applied_force << 0.0, -9.81;
  }
  template <typename T>
  Eigen::Matrix<T, 1, 1> phi(const Eigen::Matrix<T, 2, 1>& q, const T&) const {
    return Eigen::Matrix<T, 1, 1>((q(0) * q(0) + q(1) * q(1) - radius * radius) / T(2));
  }
};

// ||Q'|| <= ||A^(1/2)|| ||g - D a|| / floor: the bound the floor promises.
template <typename M>
double force_bound(const TrackingController<M>& c, double floor) {
  const auto& t = c.terms();
  const auto a = t.mass_matrix.llt().solve(t.applied_force - t.nonlinear_force).eval();
  const double sqrt_a = std::sqrt(t.mass_matrix.operatorNorm());
  return sqrt_a * (t.constraint_rhs - t.constraint_matrix * a).norm() / floor;
}

TEST(SingularConfigurations, VanishingGradientIsFlaggedAndItsForceBounded) {
  ControllerOptions<double> guarded;
  guarded.solver.min_singular_value = 3e-3;
  TrackingController<CircleMass> plain, bounded({}, guarded);
  TrackingController<CircleMass>::Output a, b;
  const Eigen::Vector2d qd(1.0, -0.5);
  double previous = 0;
  for (double eps = 1.0; eps >= 1e-9; eps /= 10) {
    const Eigen::Vector2d q = eps * Eigen::Vector2d(0.8, 0.6);
    ASSERT_EQ(plain.compute(q, qd, 0.0, a), Status::kOk);
    ASSERT_EQ(bounded.compute(q, qd, 0.0, b), Status::kOk);
    // The relative tolerance sees nothing: full rank, no warning about rank, a growing force.
    EXPECT_EQ(a.diagnostics.rank, 1) << eps;
    EXPECT_FALSE(a.diagnostics.has(warning::kRankDeficient)) << eps;
    // Out of the box the reach (|q| here) is judged against the largest the controller has seen
    // (1, at the first call): below sqrt(eps) of it the call says the reach is vanishing.
    EXPECT_EQ(a.diagnostics.has(warning::kVanishingReach), eps < 1.49e-8) << eps;
    EXPECT_GT(a.force.norm(), previous) << eps;
    previous = a.force.norm();
    // The floor flags it once |q| (the singular value) is below it, and bounds the force.
    EXPECT_EQ(b.diagnostics.has(warning::kNearSingular), eps < 3e-3) << eps;
    EXPECT_LE(b.force.norm(), force_bound(bounded, 3e-3) * (1 + 1e-12)) << eps;
    if (eps >= 1e-1) {
      EXPECT_TRUE(near(b.force, a.force, 1e-12, 1 + a.force.norm(), "unchanged away from it"));
    }
  }
  EXPECT_GT(previous, 1e8);  // unbounded without the floor
}

// The solver alone keeps the same history: a one-row constraint D = s (0.8, 0.6) shrinking from
// s = 1 is flagged from s < sqrt(eps) on, with the force still computed (it grows like 1 / s). A
// fresh solver has no history: its first call, even at s = 1e-15, is not flagged (the floor in the
// model's units covers that case), and set_options starts the history again.
TEST(SingularConfigurations, TheSolverFlagsAReachVanishingAgainstItsHistory) {
  ConstraintSolver<2, 1> solver;
  ConstraintSolver<2, 1>::Solution out;
  const Eigen::Matrix2d A = Eigen::Vector2d(2.0, 0.5).asDiagonal();
  const Eigen::Vector2d f(0.1, -0.2), Q(0.0, -9.81);
  const Eigen::Matrix<double, 1, 1> g(0.3);
  for (double s = 1.0; s >= 1e-15; s /= 10) {
    const Eigen::Matrix<double, 1, 2> D = s * Eigen::RowVector2d(0.8, 0.6);
    ASSERT_EQ(solver.solve(A, f, Q, D, g, out), Status::kOk) << s;
    const double reach = (D * A.inverse() * D.transpose()).cwiseSqrt()(0, 0);  // |D A^(-1/2)|
    const double first = std::sqrt(0.8 * 0.8 / 2.0 + 0.6 * 0.6 / 0.5);
    EXPECT_EQ(out.diagnostics.has(warning::kVanishingReach),
              reach < std::sqrt(2.220446049250313e-16) * first)
        << s;
    EXPECT_FALSE(out.diagnostics.has(warning::kRankDeficient)) << s;
  }
  ConstraintSolver<2, 1> fresh;
  ASSERT_EQ(fresh.solve(A, f, Q, Eigen::RowVector2d(0.8e-15, 0.6e-15), g, out), Status::kOk);
  EXPECT_FALSE(out.diagnostics.has(warning::kVanishingReach));
  EXPECT_GT(out.constraint_force.norm(), 1e13);
  solver.set_options(solver.options());
  ASSERT_EQ(solver.solve(A, f, Q, Eigen::RowVector2d(0.8e-15, 0.6e-15), g, out), Status::kOk);
  EXPECT_FALSE(out.diagnostics.has(warning::kVanishingReach));
}

// The arm stretched (q2 = q3 = 0): the hand's Jacobian loses a direction. Approaching it, the
// second singular value shrinks like the bend while the first stays: the relative tolerance
// catches only the exact singularity, the floor every configuration near it, for every strategy.
TEST(SingularConfigurations, ArmThroughItsStretchedConfiguration) {
  for (InverseStrategy s : {InverseStrategy::kCholeskyWithFallback, InverseStrategy::kSvd,
                            InverseStrategy::kCompleteOrthogonal, InverseStrategy::kDampedLeastSquares}) {
    ControllerOptions<double> plain_options, guarded;
    plain_options.solver.strategy = guarded.solver.strategy = s;
    guarded.solver.min_singular_value = 0.05;
    TrackingController<systems::PlanarArm<double>> plain(systems::PlanarArm<double>{}, plain_options);
    TrackingController<systems::PlanarArm<double>> bounded(systems::PlanarArm<double>{}, guarded);
    TrackingController<systems::PlanarArm<double>>::Output a, b;
    const Eigen::Vector3d qd(0.3, -0.4, 0.5);
    double worst_plain = 0;
    for (double bend : {0.5, 0.1, 1e-2, 1e-3, 1e-4, 1e-6}) {
      const Eigen::Vector3d q(0.4, bend, -0.5 * bend);
      ASSERT_EQ(plain.compute(q, qd, 0.0, a), Status::kOk) << to_string(s);
      ASSERT_EQ(bounded.compute(q, qd, 0.0, b), Status::kOk) << to_string(s);
      worst_plain = std::max(worst_plain, a.force.norm());
      EXPECT_LE(b.force.norm(), force_bound(bounded, 0.05) * 1.01) << to_string(s) << " bend " << bend;
      if (bend <= 1e-3) {
        EXPECT_TRUE(b.diagnostics.has(warning::kNearSingular)) << to_string(s) << " bend " << bend;
      }
      if (bend >= 0.5) {
        EXPECT_FALSE(b.diagnostics.has(warning::kNearSingular)) << to_string(s);
      }
    }
    EXPECT_GT(worst_plain, 1e4) << to_string(s);
  }
}

// Against the exact singular values (a Jacobi SVD in the test): every strategy flags exactly the
// solves with a singular value below the floor and keeps the force under the bound, including
// nearly parallel rows whose Cholesky diagonal overstates the smallest singular value.
TEST(SingularConfigurations, EveryStrategyHonoursTheFloor) {
  RandomSource<double> rng(7);
  const double floor = 1e-2;
  for (InverseStrategy s : {InverseStrategy::kCholeskyWithFallback, InverseStrategy::kSvd,
                            InverseStrategy::kCompleteOrthogonal, InverseStrategy::kDampedLeastSquares}) {
    SolverOptions<double> o;
    o.strategy = s;
    o.min_singular_value = floor;
    ConstraintSolver<4, 2> solver(o);
    ConstraintSolution<4, 2> sol;
    int flagged = 0;
    for (int it = 0; it < 400; ++it) {
      const double smallest = std::pow(10.0, rng.uniform(-4, 0));
      if (std::abs(smallest / floor - 1) < 1e-6) continue;
      const Eigen::Matrix<double, 2, 4> D = rng.with_singular_values<2, 4>(Eigen::Vector2d(1.0, smallest));
      const Eigen::Vector4d f = rng.matrix<4, 1>(), Q = rng.matrix<4, 1>();
      const Eigen::Vector2d g = rng.matrix<2, 1>();
      ASSERT_EQ(solver.solve(Eigen::Matrix4d::Identity(), f, Q, D, g, sol), Status::kOk);
      const bool below = Eigen::JacobiSVD<Eigen::MatrixXd>(Eigen::MatrixXd(D)).singularValues()(1) < floor;
      EXPECT_EQ(sol.diagnostics.has(warning::kNearSingular), below) << to_string(s) << " sigma " << smallest;
      flagged += below;
      const double bound = (g - D * (Q - f)).norm() / floor;  // A = I: ||A^(1/2)|| = 1, a = Q - f
      EXPECT_LE(sol.constraint_force.norm(), bound * (1 + 1e-9)) << to_string(s) << " sigma " << smallest;
    }
    EXPECT_GT(flagged, 50) << to_string(s);
  }
  // The case where the Cholesky diagonal misleads: rows of norm 0.1 and 1 at 5.7 degrees.
  const double angle = 0.1;
  Eigen::Matrix<double, 2, 2> D;
  D << 0.1, 0.0, std::cos(angle), std::sin(angle);
  SolverOptions<double> o;
  o.min_singular_value = 0.02;
  ConstraintSolver<2, 2> solver(o);
  ConstraintSolution<2, 2> sol;
  ASSERT_EQ(solver.solve(Eigen::Matrix2d::Identity(), Eigen::Vector2d::Zero(), Eigen::Vector2d::Zero(), D,
                         Eigen::Vector2d(1.0, -1.0), sol),
            Status::kOk);
  EXPECT_TRUE(sol.diagnostics.has(warning::kNearSingular));
  EXPECT_LE(sol.constraint_force.norm(), std::sqrt(2.0) / 0.02 * (1 + 1e-9));
}

TEST(ForceLimit, NeverExceededAndReported) {
  RandomSource<double> rng(1);
  using Arm = systems::PlanarArm<double>;
  TrackingController<Arm> limited, free;
  const Eigen::Vector3d limit(40.0, 25.0, 10.0);
  ASSERT_TRUE(limited.set_force_limit(limit));
  EXPECT_FALSE(limited.set_force_limit(Eigen::Vector3d(1.0, 0.0, 1.0)));
  EXPECT_FALSE(limited.set_force_limit(Eigen::Vector3d(1.0, std::nan(""), 1.0)));
  TrackingController<Arm>::Output a, b;
  int saturated = 0;
  for (int it = 0; it < 500; ++it) {
    const Eigen::Vector3d q = 2 * rng.matrix<3, 1>(), qd = 3 * rng.matrix<3, 1>();
    const double t = rng.uniform(0, 5);
    ASSERT_EQ(free.compute(q, qd, t, a), Status::kOk);
    ASSERT_EQ(limited.compute(q, qd, t, b), Status::kOk);
    EXPECT_TRUE((b.force.cwiseAbs().array() <= limit.array()).all()) << b.force.transpose();
    const bool over = (a.force.cwiseAbs().array() > limit.array()).any();
    EXPECT_EQ(b.diagnostics.has(warning::kSaturated), over);
    if (!over) {
      EXPECT_EQ(b.saturation_scale, 1.0);
      EXPECT_TRUE(b.force == a.force);
      continue;
    }
    ++saturated;
    // Scaled as a whole: same direction, parts still adding up, q'' the model's under it.
    EXPECT_TRUE(near(b.force, Eigen::Vector3d(b.saturation_scale * a.force), 1e-12, 1 + a.force.norm(), "scaled"));
    EXPECT_TRUE(near(Eigen::Vector3d(b.closed_loop + b.feedforward + b.stabilizing), b.force, 1e-12,
                     1 + b.force.norm(), "parts"));
    const auto& terms = limited.terms();
    const Eigen::Vector3d residual =
        terms.mass_matrix * b.acceleration + terms.nonlinear_force - terms.applied_force - b.force;
    EXPECT_TRUE(near(residual, Eigen::Vector3d::Zero(), 1e-10, 1 + b.force.norm(), "A q'' + f = Q + Q'"));
  }
  EXPECT_GT(saturated, 20);
}

}  // namespace
}  // namespace gausstrack::test

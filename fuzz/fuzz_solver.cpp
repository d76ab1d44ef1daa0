// The law's inputs as raw bytes: A, f, Q, D, g of the solver at 2x1, 3x2 and 4x2 (and 3x2 with
// the mass matrix declared diagonal) under each strategy and fuzzed options, and the Duffing
// tracking controller at a fuzzed state with fuzzed gains and actuator limits.
//
// Properties (any violation aborts, so libFuzzer keeps the input):
// - an input holding NaN or Inf gets Status::kNonFiniteInput and all-zero outputs;
// - finite input gives finite outputs, whatever the status; a failed status gives all zeros;
// - a successful solve reports a rank in [0, P] and a condition estimate that is not NaN;
// - solving the same input again (the kept factorization) gives the same status and answer, and a
//   kept solver answers a changed input as a fresh one, but for kVanishingReach, which is set
//   exactly when the reach is below vanishing_ratio times the largest the solver computed before;
// - the controller's published force and its parts are finite, and within the force limit set.
#include <Eigen/Core>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>

#include "fuzz_input.hpp"
#include "gausstrack/constraint_solver.hpp"
#include "gausstrack/systems/coupled_duffing.hpp"
#include "gausstrack/tracking_controller.hpp"

namespace {

using gausstrack::fuzz::FuzzInput;

template <typename Derived>
void fill(FuzzInput& in, bool raw, Eigen::MatrixBase<Derived>& m) {
  for (Eigen::Index j = 0; j < m.cols(); ++j)
    for (Eigen::Index i = 0; i < m.rows(); ++i) m(i, j) = in.number(raw);
}

template <int N, int P, gausstrack::MassMatrix kMass = gausstrack::MassMatrix::kDense>
void solve_case(FuzzInput& in) {
  using Solver = gausstrack::ConstraintSolver<N, P, double, kMass>;
  const std::uint8_t mode = in.byte();
  const bool raw = (mode & 1) != 0;
  typename Solver::Options options;
  options.strategy = static_cast<gausstrack::InverseStrategy>((mode >> 1) % 4);
  if (mode & 8) options.rank_tolerance = in.number(raw);
  if (mode & 16) options.min_singular_value = in.number(raw);
  if (mode & 32) options.damping = in.number(raw);
  if (mode & 64) options.fallback_rcond = in.number(raw);

  typename Solver::MatrixNN A;
  typename Solver::VectorN f, Q;
  typename Solver::MatrixPN D;
  typename Solver::VectorP g;
  fill(in, raw, A);
  if (mode & 128) A = (A * A.transpose()).eval();  // often positive definite, sometimes singular
  fill(in, raw, f);
  fill(in, raw, Q);
  fill(in, raw, D);
  fill(in, raw, g);

  Solver solver(options);
  typename Solver::Solution out;
  const gausstrack::Status status = solver.solve(A, f, Q, D, g, out);
  GAUSSTRACK_FUZZ_CHECK(status == out.diagnostics.status);

  // A declared-diagonal solver reads the diagonal of A alone.
  const bool finite_a =
      kMass == gausstrack::MassMatrix::kDiagonal ? A.diagonal().allFinite() : A.allFinite();
  const bool finite_input =
      finite_a && f.allFinite() && Q.allFinite() && D.allFinite() && g.allFinite();
  if (!finite_input) GAUSSTRACK_FUZZ_CHECK(status == gausstrack::Status::kNonFiniteInput);
  GAUSSTRACK_FUZZ_CHECK(out.acceleration.allFinite() && out.constraint_force.allFinite() &&
                        out.force_from_impressed.allFinite() && out.force_from_rhs.allFinite() &&
                        out.unconstrained_acceleration.allFinite());
  if (gausstrack::failed(status)) {
    GAUSSTRACK_FUZZ_CHECK(out.acceleration.isZero(0) && out.constraint_force.isZero(0) &&
                          out.force_from_impressed.isZero(0) && out.force_from_rhs.isZero(0));
  } else {
    GAUSSTRACK_FUZZ_CHECK(out.diagnostics.rank >= 0 && out.diagnostics.rank <= P);
    GAUSSTRACK_FUZZ_CHECK(!std::isnan(out.diagnostics.condition_estimate));
    GAUSSTRACK_FUZZ_CHECK(!std::isnan(out.diagnostics.residual_norm));
    const typename Solver::VectorN extra = solver.force_for_rhs(g);
    GAUSSTRACK_FUZZ_CHECK(extra.allFinite());
  }
  typename Solver::Solution again;
  GAUSSTRACK_FUZZ_CHECK(solver.solve(A, f, Q, D, g, again) == status);
  // kVanishingReach compares the reach with the largest this solver has computed, so a kept
  // solver and a fresh one may differ in that bit alone; it is checked against the history below.
  auto same = [](const typename Solver::Solution& x, const typename Solver::Solution& y,
                 std::uint32_t ignored = 0) {
    return x.constraint_force == y.constraint_force &&
           x.force_from_impressed == y.force_from_impressed &&
           x.force_from_rhs == y.force_from_rhs && x.acceleration == y.acceleration &&
           (x.diagnostics.warnings & ~ignored) == (y.diagnostics.warnings & ~ignored) &&
           x.diagnostics.rank == y.diagnostics.rank &&
           x.diagnostics.strategy_used == y.diagnostics.strategy_used;
  };
  GAUSSTRACK_FUZZ_CHECK(same(again, out));
  const double reach = out.diagnostics.sigma_max;
  const double seen =
      !gausstrack::failed(status) && reach >= 0 && reach <= std::numeric_limits<double>::max()
          ? reach
          : 0.0;
  // One entry of D one ulp away: the kept solver answers as a fresh one (no stale factorization).
  if (D.allFinite() && D(0, 0) != 0) {
    D(0, 0) = std::nextafter(D(0, 0), D(0, 0) > 0 ? HUGE_VAL : -HUGE_VAL);
    Solver fresh(options);
    typename Solver::Solution expected;
    const gausstrack::Status fresh_status = fresh.solve(A, f, Q, D, g, expected);
    GAUSSTRACK_FUZZ_CHECK(solver.solve(A, f, Q, D, g, again) == fresh_status);
    GAUSSTRACK_FUZZ_CHECK(same(again, expected, gausstrack::warning::kVanishingReach));
    if (!gausstrack::failed(fresh_status)) {
      const bool vanishing =
          (again.diagnostics.warnings & gausstrack::warning::kVanishingReach) != 0;
      GAUSSTRACK_FUZZ_CHECK(vanishing ==
                            (again.diagnostics.sigma_max < options.vanishing_ratio * seen));
    }
  }
}

void controller_case(FuzzInput& in) {
  using Model = gausstrack::systems::CoupledDuffing<double>;
  using Controller = gausstrack::TrackingController<Model>;
  const std::uint8_t mode = in.byte();
  const bool raw = (mode & 1) != 0;
  Model model;
  model.parameters([&](const char*, double& value) {
    if (mode & 2) value = in.number(raw);
  });
  Controller::Options options;
  if (mode & 4) {
    options.stabilization.zeta = in.number(raw);
    options.stabilization.omega = in.number(raw);
  }
  if (mode & 8) options.solver.min_singular_value = in.number(raw);
  if (options.validate() != nullptr) return;  // the constructor refuses these (tested elsewhere)
  Controller controller(model, options);
  Controller::VectorN limit;
  limit << in.number(raw), in.number(raw);
  const bool limited = (mode & 16) && controller.set_force_limit(limit);

  Controller::VectorN q, qd;
  q << in.number(raw), in.number(raw);
  qd << in.number(raw), in.number(raw);
  const double t = in.number(raw);
  Controller::Output out;
  const gausstrack::Status status = controller.compute(q, qd, t, out);
  if (!q.allFinite() || !qd.allFinite() || !std::isfinite(t))
    GAUSSTRACK_FUZZ_CHECK(status == gausstrack::Status::kNonFiniteInput);
  GAUSSTRACK_FUZZ_CHECK(out.force.allFinite() && out.closed_loop.allFinite() &&
                        out.feedforward.allFinite() && out.stabilizing.allFinite() &&
                        out.acceleration.allFinite());
  GAUSSTRACK_FUZZ_CHECK(!std::isnan(out.saturation_scale));
  if (gausstrack::failed(status)) GAUSSTRACK_FUZZ_CHECK(out.force.isZero(0));
  if (limited) {
    for (int i = 0; i < 2; ++i) GAUSSTRACK_FUZZ_CHECK(std::abs(out.force(i)) <= limit(i));
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  FuzzInput in(data, size);
  switch (in.byte() % 5) {
    case 0:
      solve_case<2, 1>(in);
      break;
    case 1:
      solve_case<3, 2>(in);
      break;
    case 2:
      solve_case<4, 2>(in);
      break;
    case 3:
      solve_case<3, 2, gausstrack::MassMatrix::kDiagonal>(in);
      break;
    default:
      controller_case(in);
      break;
  }
  return 0;
}

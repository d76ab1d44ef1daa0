// Outcome of a real-time call: whether it failed, and how good the answer is.
#pragma once

#include <array>
#include <cstdint>
#include <limits>

namespace gausstrack {

/// Whether a solve produced an answer. Failures leave every output at zero (never NaN), so a
/// caller that ignores the status still applies no force rather than garbage.
enum class Status : std::uint8_t {
  kOk = 0,                          ///< answer computed; read `warnings` for its quality
  kNonFiniteInput,                  ///< NaN or Inf in an input; see `non_finite_inputs`
  kMassMatrixNotPositiveDefinite,   ///< Cholesky of A failed: A is not symmetric positive definite
  kNonFiniteResult,                 ///< finite input overflowed (entries near the range limit)
  /// The actuation's weight W is not positive definite: with Gauss's weight B^T A^-1 B, the
  /// columns of the actuation matrix B are dependent (ActuatedController).
  kWeightNotPositiveDefinite,
};

/// True when the call produced no answer (outputs are zero).
constexpr bool failed(Status s) noexcept { return s != Status::kOk; }

constexpr const char* to_string(Status s) noexcept {
  switch (s) {
    case Status::kOk: return "ok";
    case Status::kNonFiniteInput: return "non-finite input";
    case Status::kMassMatrixNotPositiveDefinite: return "mass matrix not positive definite";
    case Status::kNonFiniteResult: return "non-finite result";
    case Status::kWeightNotPositiveDefinite: return "actuation weight not positive definite";
  }
  return "unknown";
}

/// Quality warnings on a successful solve, as bit flags in `SolveDiagnostics::warnings`.
namespace warning {
/// rank(D A^(-1/2)) < P: redundant or locally degenerate constraints.
inline constexpr std::uint32_t kRankDeficient = 1u << 0;
/// ||D q'' - g|| above the residual tolerance: the constraints are inconsistent (met in the
/// least-squares sense) or damping gave part of them up.
inline constexpr std::uint32_t kConstraintsNotMet = 1u << 1;
/// condition estimate of D A^(-1/2) above `SolverOptions::warn_condition`.
inline constexpr std::uint32_t kIllConditioned = 1u << 2;
/// the full-rank Cholesky path found D A^-1 D^T singular or ill-conditioned and the
/// rank-revealing SVD path answered instead.
inline constexpr std::uint32_t kFellBackToSvd = 1u << 3;
/// a singular value of D A^(-1/2) above the relative rank tolerance but below the absolute floor
/// `SolverOptions::min_singular_value`: that direction was given up (its rows are not met) so that
/// the force stays bounded. The physical-scale signal of a near-singular configuration (an arm
/// stretched, a constraint whose gradient vanishes), which a relative tolerance cannot see when
/// every row shrinks together.
inline constexpr std::uint32_t kNearSingular = 1u << 4;
/// the force exceeded a limit set with TrackingController::set_force_limit and was scaled down
/// to it (all its parts alike); `ControlOutput::saturation_scale` says by how much.
inline constexpr std::uint32_t kSaturated = 1u << 5;
/// with a sampled-data hold, the law could not be evaluated at the predicted state (a non-finite
/// prediction, a failed solve there): the force is the law's at the measured state, held.
inline constexpr std::uint32_t kHoldAtMeasuredState = 1u << 6;
/// the largest singular value of D A^(-1/2) (the rows' reach; for ActuatedController outside its
/// plain case the Frobenius norm of its active task rows' D A^(-1/2)) fell below
/// `SolverOptions::vanishing_ratio` times the largest this solver or controller has computed: the
/// rows' gradient is vanishing as a whole (a one-row constraint at a point where its gradient is
/// zero), so the force grows like 1 / reach. The rank tolerance and the condition estimate, both
/// relative to the current reach, cannot see it. The answer is unchanged; a floor
/// (`min_singular_value`) or a force limit bounds it.
inline constexpr std::uint32_t kVanishingReach = 1u << 7;

/// The number of warning kinds: bits 0 to kCount - 1.
inline constexpr int kCount = 8;
/// The kinds that say task rows were not met by the answer: inconsistent or given-up rows.
inline constexpr std::uint32_t kRowsNotMet = kConstraintsNotMet | kNearSingular;

/// The name of warning bit `bit` (0 .. kCount - 1), as summaries print it.
constexpr const char* name(int bit) noexcept {
  constexpr const char* kNames[kCount] = {
      "rank_deficient", "constraints_not_met", "ill_conditioned",        "fell_back_to_svd",
      "near_singular",  "saturated",           "hold_at_measured_state", "vanishing_reach"};
  return bit >= 0 && bit < kCount ? kNames[bit] : "unknown";
}
}  // namespace warning

/// warning::kVanishingReach on `diagnostics` when its sigma_max is below `ratio` times `seen`, the
/// largest reach before it; returns the largest reach including this one.
template <typename Diagnostics, typename Scalar>
Scalar flag_vanishing_reach(Scalar ratio, Scalar seen, Diagnostics& diagnostics) noexcept {
  const Scalar reach = diagnostics.sigma_max;
  if (!(reach >= Scalar(0)) || !(reach <= std::numeric_limits<Scalar>::max()))
    return seen;  // NaN or Inf
  if (reach < ratio * seen) diagnostics.warnings |= warning::kVanishingReach;
  return reach > seen ? reach : seen;
}

/// A run's warnings, tallied call by call (or control period by control period): how many carried
/// each kind, how many failed (no answer: zero force), and how many left task rows unmet
/// (warning::kRowsNotMet, or failed). Allocation-free.
struct WarningTally {
  std::array<std::uint64_t, warning::kCount> by_kind{};
  std::uint64_t failed = 0;
  std::uint64_t rows_not_met = 0;
  std::uint64_t calls = 0;

  constexpr void add_failure() noexcept {
    ++calls;
    ++failed;
    ++rows_not_met;
  }
  constexpr void add(std::uint32_t warnings) noexcept {
    ++calls;
    for (int b = 0; b < warning::kCount; ++b)
      if (warnings & (1u << b)) ++by_kind[static_cast<std::size_t>(b)];
    if (warnings & warning::kRowsNotMet) ++rows_not_met;
  }
  /// The share of the calls whose answer left task rows unmet (0 without calls).
  constexpr double rows_not_met_share() const noexcept {
    return calls == 0 ? 0.0 : static_cast<double>(rows_not_met) / static_cast<double>(calls);
  }
};

/// Which inputs held a NaN or Inf, as bit flags in `SolveDiagnostics::non_finite_inputs`.
namespace input {
inline constexpr std::uint32_t kMassMatrix = 1u << 0;       // A
inline constexpr std::uint32_t kNonlinearForce = 1u << 1;   // f
inline constexpr std::uint32_t kAppliedForce = 1u << 2;     // Q
inline constexpr std::uint32_t kConstraintMatrix = 1u << 3; // D
inline constexpr std::uint32_t kConstraintRhs = 1u << 4;    // g
inline constexpr std::uint32_t kState = 1u << 5;            // q, q' or t given to a controller
inline constexpr std::uint32_t kActuation = 1u << 6;        // B, or an actuation weight W
}  // namespace input

}  // namespace gausstrack

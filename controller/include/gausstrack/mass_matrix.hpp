// How a model's mass matrix A is stored, which decides how the solver reads and factors it.
#pragma once

#include <cstdint>

namespace gausstrack {

/// kDense: A is read whole and factored by Cholesky. kDiagonal: A is read on its diagonal only
/// (the rest must be zero; check_model verifies it) and its factor is diag(sqrt(A_ii)). A model
/// declares the diagonal case with `static constexpr MassMatrix kMassMatrix = MassMatrix::kDiagonal;`.
enum class MassMatrix : std::uint8_t { kDense, kDiagonal };

}  // namespace gausstrack

// The wire codec: moves q, q' and forces between the LCM messages and Eigen vectors of N
// coordinates, checking what arrives. N is fixed at compile time (a model's kDof), or
// Eigen::Dynamic for a dimension chosen at run time (a plant from a scene): its vectors then
// live in bounded storage of the messages' 32 entries. Encoding and decoding allocate nothing
// and throw nothing.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "gausstrack/control_command_t.hpp"
#include "gausstrack/control_diagnostics_t.hpp"
#include "gausstrack/loop_stats_t.hpp"
#include "gausstrack/plant_state_t.hpp"

namespace gausstrack::nodes {

inline constexpr int kMaxDimension = plant_state_t::MAX_DIMENSION;
/// The longest hold delay a state may report (plant_state_t::hold_delay_ns) [ns].
inline constexpr std::int64_t kMaxHoldDelayNs = 1'000'000'000;
static_assert(control_command_t::MAX_DIMENSION == kMaxDimension &&
              control_diagnostics_t::MAX_DIMENSION == kMaxDimension);

/// q, q' or a force on the wire's side: fixed size N, or at most 32 entries without allocation.
template <int N>
using WireVector =
    Eigen::Matrix<double, N, 1, Eigen::ColMajor, N == Eigen::Dynamic ? kMaxDimension : N, 1>;

/// Why a message was refused (each is counted by the nodes).
enum class Refusal : std::uint8_t {
  kNone,
  kMalformed,  ///< does not decode as the expected type (truncated, foreign, corrupt)
  kDimension,  ///< a dimension other than the receiver's
  kNonFinite,  ///< NaN or infinity in a value the receiver would use
};

inline const char* to_string(Refusal r) noexcept {
  switch (r) {
    case Refusal::kNone:
      return "none";
    case Refusal::kMalformed:
      return "malformed";
    case Refusal::kDimension:
      return "wrong dimension";
    case Refusal::kNonFinite:
      return "non-finite";
  }
  return "unknown";
}

template <int N>
class Codec {
 public:
  static_assert(N == Eigen::Dynamic || (N >= 1 && N <= kMaxDimension),
                "the messages carry 1..32 coordinates");
  using Vector = WireVector<N>;

  /// `dimension` must be N for a fixed N; 1..32 for Eigen::Dynamic (checked by valid()).
  explicit Codec(int dimension = N) noexcept : n_(dimension) {}
  bool valid() const noexcept {
    return n_ >= 1 && n_ <= kMaxDimension && (N == Eigen::Dynamic || n_ == N);
  }
  int dimension() const noexcept { return n_; }

  /// Decodes a plant state into `msg` and its q, q'.
  Refusal decode_state(const void* data, std::size_t size, plant_state_t& msg, Vector& q,
                       Vector& qd) const noexcept {
    if (size > static_cast<std::size_t>(INT32_MAX) ||
        msg.decode(data, 0, static_cast<int>(size)) < 0)
      return Refusal::kMalformed;
    if (msg.dimension != n_) return Refusal::kDimension;
    if (msg.hold_delay_ns < 0 || msg.hold_delay_ns > kMaxHoldDelayNs) return Refusal::kMalformed;
    if (!std::isfinite(msg.t)) return Refusal::kNonFinite;
    q = Eigen::Map<const Vector>(msg.q, n_);
    qd = Eigen::Map<const Vector>(msg.qd, n_);
    if (!q.allFinite() || !qd.allFinite()) return Refusal::kNonFinite;
    return Refusal::kNone;
  }

  /// Decodes a command into `msg` and its force. A failed solve's command (status not 0) is
  /// accepted with a zero force whatever its force entries say; otherwise a non-finite force is
  /// refused.
  /// The actuator commands (msg.actuators of them, at most kMaxDimension) are refused in the same
  /// way: a count out of range as malformed, a non-finite command of a successful solve as
  /// non-finite.
  Refusal decode_command(const void* data, std::size_t size, control_command_t& msg,
                         Vector& force) const noexcept {
    if (size > static_cast<std::size_t>(INT32_MAX) ||
        msg.decode(data, 0, static_cast<int>(size)) < 0)
      return Refusal::kMalformed;
    if (msg.dimension != n_) return Refusal::kDimension;
    if (msg.actuators < 0 || msg.actuators > kMaxDimension) return Refusal::kMalformed;
    if (msg.status != 0) {
      force = Vector::Zero(n_);
      return Refusal::kNone;
    }
    force = Eigen::Map<const Vector>(msg.force, n_);
    if (!force.allFinite()) return Refusal::kNonFinite;
    for (int i = 0; i < msg.actuators; ++i)
      if (!std::isfinite(msg.control[i])) return Refusal::kNonFinite;
    return Refusal::kNone;
  }

  /// Fills the state message (entries past the dimension zero) and encodes it into `buffer`.
  /// Returns the encoded size, or -1 if the buffer is too small.
  template <typename Q, typename Qd>
  int encode_state(plant_state_t& msg, const Eigen::MatrixBase<Q>& q,
                   const Eigen::MatrixBase<Qd>& qd, std::uint8_t* buffer,
                   std::size_t capacity) const noexcept {
    msg.dimension = n_;
    for (int i = 0; i < kMaxDimension; ++i) {
      msg.q[i] = i < n_ ? q(i) : 0.0;
      msg.qd[i] = i < n_ ? qd(i) : 0.0;
    }
    return encode(msg, buffer, capacity);
  }

  /// A command with the force alone (msg.actuators = 0).
  template <typename F>
  int encode_command(control_command_t& msg, const Eigen::MatrixBase<F>& force,
                     std::uint8_t* buffer, std::size_t capacity) const noexcept {
    msg.dimension = n_;
    msg.actuators = 0;
    for (int i = 0; i < kMaxDimension; ++i) {
      msg.force[i] = i < n_ ? force(i) : 0.0;
      msg.control[i] = 0.0;
    }
    return encode(msg, buffer, capacity);
  }
  /// A command with the force B u and the actuator commands u (u.size() of them, at most
  /// kMaxDimension; -1 beyond).
  template <typename F, typename U>
  int encode_command(control_command_t& msg, const Eigen::MatrixBase<F>& force,
                     const Eigen::MatrixBase<U>& control, std::uint8_t* buffer,
                     std::size_t capacity) const noexcept {
    const auto k = static_cast<int>(control.size());
    if (k > kMaxDimension) return -1;
    msg.dimension = n_;
    msg.actuators = k;
    for (int i = 0; i < kMaxDimension; ++i) {
      msg.force[i] = i < n_ ? force(i) : 0.0;
      msg.control[i] = i < k ? control(i) : 0.0;
    }
    return encode(msg, buffer, capacity);
  }

  template <typename A, typename B, typename C>
  int encode_diagnostics(control_diagnostics_t& msg, const Eigen::MatrixBase<A>& closed_loop,
                         const Eigen::MatrixBase<B>& feedforward,
                         const Eigen::MatrixBase<C>& stabilizing, std::uint8_t* buffer,
                         std::size_t capacity) const noexcept {
    msg.dimension = n_;
    for (int i = 0; i < kMaxDimension; ++i) {
      msg.closed_loop[i] = i < n_ ? closed_loop(i) : 0.0;
      msg.feedforward[i] = i < n_ ? feedforward(i) : 0.0;
      msg.stabilizing[i] = i < n_ ? stabilizing(i) : 0.0;
    }
    return encode(msg, buffer, capacity);
  }

 private:
  template <typename Message>
  static int encode(const Message& msg, std::uint8_t* buffer, std::size_t capacity) noexcept {
    const int size = msg.getEncodedSize();
    if (size < 0 || static_cast<std::size_t>(size) > capacity) return -1;
    return msg.encode(buffer, 0, size) == size ? size : -1;
  }

  int n_;
};

/// Decodes loop statistics, refusing what the generated decoder would mishandle: LCM 1.3.1's C++
/// decoder trusts a string's length field, and a length below 1 makes it throw std::length_error
/// (or read before the buffer). Returns false for anything that is not a whole loop_stats_t.
inline bool decode_loop_stats(const void* data, std::size_t size, loop_stats_t& msg) noexcept {
  // Layout: fingerprint (8 bytes), utime (8), the process string's length counting its '\0'
  // (int32, big-endian), its bytes, then the fixed-size fields.
  constexpr std::size_t kLengthAt = 16;
  if (size > static_cast<std::size_t>(INT32_MAX) || size < kLengthAt + 4) return false;
  const auto* b = static_cast<const std::uint8_t*>(data) + kLengthAt;
  const auto length = static_cast<std::int32_t>(static_cast<std::uint32_t>(b[0]) << 24 |
                                                static_cast<std::uint32_t>(b[1]) << 16 |
                                                static_cast<std::uint32_t>(b[2]) << 8 | b[3]);
  if (length < 1 || static_cast<std::size_t>(length) > size - kLengthAt - 4) return false;
  return msg.decode(data, 0, static_cast<int>(size)) == static_cast<int>(size);
}

/// Encoded sizes of the messages are fixed (their arrays are): a buffer of this size holds any.
inline constexpr std::size_t kMessageBufferBytes = 4096;

}  // namespace gausstrack::nodes

// Reads a fuzzer's bytes as the values a target needs. Past the end every read gives zero, so any
// input, however short, is a complete case.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>

namespace gausstrack::fuzz {

class FuzzInput {
 public:
  FuzzInput(const std::uint8_t* data, std::size_t size) noexcept : data_(data), size_(size) {}

  std::uint8_t byte() noexcept { return pos_ < size_ ? data_[pos_++] : 0; }

  /// Raw mode: the next 8 bytes as an IEEE double (any value: NaN, Inf, denormals, 1e308).
  /// Scaled mode: the next 2 bytes as a signed integer / 256, so that ordinary magnitudes and
  /// exact cancellations (singular matrices) are reached often.
  double number(bool raw) noexcept {
    if (raw) {
      std::uint64_t bits = 0;
      for (int i = 0; i < 8; ++i) bits |= static_cast<std::uint64_t>(byte()) << (8 * i);
      double x;
      std::memcpy(&x, &bits, sizeof x);
      return x;
    }
    const auto lo = static_cast<std::uint16_t>(byte());
    const auto hi = static_cast<std::uint16_t>(byte());
    return static_cast<double>(static_cast<std::int16_t>(static_cast<std::uint16_t>(lo | (hi << 8)))) / 256.0;
  }

  const std::uint8_t* rest() const noexcept { return data_ + (pos_ < size_ ? pos_ : size_); }
  std::size_t rest_size() const noexcept { return pos_ < size_ ? size_ - pos_ : 0; }

 private:
  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t pos_ = 0;
};

/// Stops the fuzzer with a message when a property fails (a finding, written as a crash input).
[[noreturn]] void property_failed(const char* what) noexcept;

}  // namespace gausstrack::fuzz

#define GAUSSTRACK_FUZZ_CHECK(condition) \
  ((condition) ? static_cast<void>(0) : ::gausstrack::fuzz::property_failed(#condition))

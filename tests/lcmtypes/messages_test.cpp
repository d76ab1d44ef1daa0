// The wire types: encode into a fixed buffer and decode back exactly; truncated, foreign and
// random bytes are refused with an error, never a crash.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <random>

#include "gausstrack/control_command_t.hpp"
#include "gausstrack/loop_stats_t.hpp"
#include "gausstrack/plant_state_t.hpp"

namespace {

gausstrack::plant_state_t sample_state() {
  gausstrack::plant_state_t s{};
  s.utime = 1700000000123456;
  s.sequence = 42;
  s.t = 1.25;
  s.hold_delay_ns = 1'000'000;
  s.dimension = 2;
  s.q[0] = 1.5;
  s.q[1] = -0.25;
  s.qd[0] = 8.283185307179586;
  s.qd[1] = 2.0;
  return s;
}

TEST(Messages, PlantStateRoundTripsThroughAFixedBuffer) {
  const auto s = sample_state();
  std::array<std::uint8_t, 1024> buf{};
  const int size = s.getEncodedSize();
  ASSERT_LE(size, static_cast<int>(buf.size()));
  // Fixed-size arrays: the encoded size does not depend on the content.
  // fingerprint, utime, sequence, run_id, t, hold_delay_ns, dimension, q, qd
  EXPECT_EQ(size, 8 + 8 + 8 + 8 + 8 + 8 + 4 + 2 * 32 * 8);
  ASSERT_EQ(s.encode(buf.data(), 0, size), size);
  gausstrack::plant_state_t d{};
  ASSERT_EQ(d.decode(buf.data(), 0, size), size);
  EXPECT_EQ(d.utime, s.utime);
  EXPECT_EQ(d.sequence, s.sequence);
  EXPECT_EQ(d.t, s.t);
  EXPECT_EQ(d.hold_delay_ns, s.hold_delay_ns);
  EXPECT_EQ(d.dimension, 2);
  for (int i = 0; i < 32; ++i) {
    EXPECT_EQ(d.q[i], s.q[i]);
    EXPECT_EQ(d.qd[i], s.qd[i]);
  }
}

TEST(Messages, ControlCommandRoundTrips) {
  gausstrack::control_command_t c{};
  c.sequence = 7;
  c.state_sequence = 42;
  c.dimension = 2;
  c.force[0] = -42.4;
  c.force[1] = 42.4;
  c.run_id = 0x1234567890LL;
  c.status = 0;
  c.warnings = 8;
  c.compute_ns = 150;
  c.actuators = 1;
  c.control[0] = -42.4;
  std::array<std::uint8_t, 2048> buf{};
  const int size = c.getEncodedSize();
  ASSERT_EQ(c.encode(buf.data(), 0, size), size);
  gausstrack::control_command_t d{};
  ASSERT_EQ(d.decode(buf.data(), 0, size), size);
  EXPECT_EQ(d.state_sequence, 42);
  EXPECT_EQ(d.force[1], 42.4);
  EXPECT_EQ(d.run_id, 0x1234567890LL);
  EXPECT_EQ(d.warnings, 8);
  EXPECT_EQ(d.actuators, 1);
  EXPECT_EQ(d.control[0], -42.4);
}

TEST(Messages, TruncatedForeignAndRandomBytesAreRefused) {
  const auto s = sample_state();
  std::array<std::uint8_t, 1024> buf{};
  const int size = s.getEncodedSize();
  ASSERT_EQ(s.encode(buf.data(), 0, size), size);
  gausstrack::plant_state_t d{};
  for (int cut : {0, 4, 8, 20, size - 1})
    EXPECT_LT(d.decode(buf.data(), 0, cut), 0) << "cut at " << cut;
  // A plant state read as a control command: the type fingerprint differs.
  gausstrack::control_command_t c{};
  EXPECT_LT(c.decode(buf.data(), 0, size), 0);
  // Random bytes: refused by the fingerprint (or, if ever accepted, decoded within bounds).
  std::mt19937 rng(3);
  int accepted = 0;
  for (int it = 0; it < 2000; ++it) {
    for (auto& b : buf) b = static_cast<std::uint8_t>(rng());
    accepted += d.decode(buf.data(), 0, size) >= 0 ? 1 : 0;
  }
  EXPECT_EQ(accepted, 0);
}

TEST(Messages, LoopStatsCarryTheProcessName) {
  gausstrack::loop_stats_t st{};
  st.process = "plant";
  st.deadline_misses = 3;
  std::array<std::uint8_t, 512> buf{};
  const int size = st.getEncodedSize();
  ASSERT_EQ(st.encode(buf.data(), 0, size), size);
  gausstrack::loop_stats_t d{};
  ASSERT_EQ(d.decode(buf.data(), 0, size), size);
  EXPECT_EQ(d.process, "plant");
  EXPECT_EQ(d.deadline_misses, 3);
}

}  // namespace

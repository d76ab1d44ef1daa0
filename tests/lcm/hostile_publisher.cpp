// Publishes, on a state channel: random bytes, a truncated state, a control command (another
// type), a state of the wrong dimension, one with NaN, a valid state, and a repeat of an old
// sequence number. A controller must answer exactly the one valid state and reject the six others.
#include <lcm/lcm-cpp.hpp>

#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <thread>

#include "gausstrack/control_command_t.hpp"
#include "gausstrack/plant_state_t.hpp"

int main(int argc, char** argv) {
  if (argc != 2) return std::fprintf(stderr, "usage: %s STATE_CHANNEL\n", argv[0]), 2;
  const std::string channel = argv[1];
  lcm::LCM lcm;
  if (!lcm.good()) return 1;
  std::array<std::uint8_t, 4096> buf{};
  auto send = [&](const auto& msg, int size) {
    msg.encode(buf.data(), 0, msg.getEncodedSize());
    lcm.publish(channel, buf.data(), static_cast<unsigned>(size));
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  };
  gausstrack::plant_state_t good{};
  good.sequence = 10;
  good.t = 0.5;
  good.dimension = 2;
  good.q[0] = 1.0;
  good.q[1] = 0.9;
  good.qd[0] = 0.1;

  std::array<std::uint8_t, 64> noise{};
  for (std::size_t i = 0; i < noise.size(); ++i) noise[i] = static_cast<std::uint8_t>(i * 37 + 11);
  lcm.publish(channel, noise.data(), noise.size());
  send(good, good.getEncodedSize() / 2);  // truncated
  gausstrack::control_command_t other{};
  other.dimension = 2;
  send(other, other.getEncodedSize());
  auto wrong = good;
  wrong.dimension = 5;
  wrong.sequence = 1;
  send(wrong, wrong.getEncodedSize());
  auto nan = good;
  nan.sequence = 2;
  nan.q[1] = std::numeric_limits<double>::quiet_NaN();
  send(nan, nan.getEncodedSize());
  send(good, good.getEncodedSize());  // answered
  auto old = good;
  old.sequence = 9;
  send(old, old.getEncodedSize());
  return 0;
}

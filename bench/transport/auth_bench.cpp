// What authentication costs a receiver per message, beside decoding the message alone (the work
// every message costed before). Each receiver step on the wire's fixed-size messages (a command,
// ~300 bytes; a state, ~550 bytes):
//   decode           the LCM decode and checks alone (the baseline)
//   verify+decode    a sealed message verified and decoded: one keyed BLAKE2b over the message,
//                    a constant-time compare, the counter compare, the decode (the message is
//                    sealed once and presented again, so from the second iteration on it is
//                    refused as replayed at the very end: the same work as accepting it)
//   refuse garbage   bytes without a trailer (a size check and a 4-byte compare)
//   refuse forged    a trailer made with another key (the whole hash, then refused)
//   seal             the sender's side: counter, clock read and hash
#include <benchmark/benchmark.h>

#include <array>
#include <cstdint>
#include <random>

#include "gausstrack/control_command_t.hpp"
#include "gausstrack/nodes/auth.hpp"
#include "gausstrack/nodes/codec.hpp"
#include "gausstrack/plant_state_t.hpp"

namespace {

using gausstrack::control_command_t;
using gausstrack::plant_state_t;
using gausstrack::nodes::AuthRefusal;
using gausstrack::nodes::ChannelAuth;
using gausstrack::nodes::Codec;
using gausstrack::nodes::MessageKey;

constexpr int kDimension = 2;  // the Duffing pair; the messages' size does not depend on it
using WireCodec = Codec<Eigen::Dynamic>;

MessageKey key(std::uint8_t seed) {
  std::array<std::uint8_t, gausstrack::nodes::kKeyBytes> bytes{};
  for (std::size_t i = 0; i < bytes.size(); ++i) bytes[i] = static_cast<std::uint8_t>(seed + 17 * i);
  return MessageKey(bytes);
}

struct Message {
  std::array<std::uint8_t, 4096> buf{};
  int size = 0;
};

Message command() {
  Message m;
  control_command_t c{};
  c.run_id = 7;
  c.state_sequence = 41;
  c.sequence = 42;
  c.dimension = kDimension;
  c.force[0] = 1.5;
  c.force[1] = -2.5;
  m.size = c.getEncodedSize();
  c.encode(m.buf.data(), 0, m.size);
  return m;
}

Message state() {
  Message m;
  plant_state_t s{};
  s.run_id = 7;
  s.sequence = 41;
  s.dimension = kDimension;
  s.t = 0.041;
  s.q[0] = 0.1;
  s.qd[1] = -0.2;
  m.size = s.getEncodedSize();
  s.encode(m.buf.data(), 0, m.size);
  return m;
}

Message sealed(Message m, const MessageKey& k, const char* channel) {
  ChannelAuth sender(k, channel);
  m.size = sender.seal(m.buf.data(), static_cast<std::size_t>(m.size), m.buf.size());
  return m;
}

// Decodes a command or a state, as the plant or the controller does.
bool decode(const WireCodec& codec, const Message& m, std::size_t size, bool is_command) {
  if (is_command) {
    control_command_t msg{};
    WireCodec::Vector force;
    return codec.decode_command(m.buf.data(), size, msg, force) == gausstrack::nodes::Refusal::kNone;
  }
  plant_state_t msg{};
  WireCodec::Vector q, qd;
  return codec.decode_state(m.buf.data(), size, msg, q, qd) == gausstrack::nodes::Refusal::kNone;
}

void BM_Decode(benchmark::State& st, bool is_command) {
  const WireCodec codec(kDimension);
  const Message m = is_command ? command() : state();
  for (auto _ : st) benchmark::DoNotOptimize(decode(codec, m, static_cast<std::size_t>(m.size), is_command));
  st.counters["bytes"] = m.size;
}

void BM_VerifyAndDecode(benchmark::State& st, bool is_command) {
  const WireCodec codec(kDimension);
  const char* channel = is_command ? "GAUSSTRACK_COMMAND" : "GAUSSTRACK_STATE";
  const Message m = sealed(is_command ? command() : state(), key(1), channel);
  ChannelAuth receiver(key(1), channel);
  long accepted = 0;
  for (auto _ : st) {
    std::size_t body = 0;
    const AuthRefusal r = receiver.open(m.buf.data(), static_cast<std::size_t>(m.size), body);
    accepted += r == AuthRefusal::kNone;
    // Decoded whatever the verdict, so that each iteration does an accepted message's work.
    benchmark::DoNotOptimize(decode(codec, m, static_cast<std::size_t>(m.size) - gausstrack::nodes::kTrailerBytes,
                                    is_command));
  }
  if (accepted != 1) st.SkipWithError("the sealed message did not verify exactly once");
  st.counters["bytes"] = m.size;
}

void BM_RefuseGarbage(benchmark::State& st) {
  Message m = command();
  std::mt19937_64 rng(5);
  for (int i = 0; i < m.size; ++i) m.buf[static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(rng());
  ChannelAuth receiver(key(1), "GAUSSTRACK_COMMAND");
  for (auto _ : st) {
    std::size_t body = 0;
    benchmark::DoNotOptimize(receiver.open(m.buf.data(), static_cast<std::size_t>(m.size), body));
  }
}

void BM_RefuseForged(benchmark::State& st) {
  const Message m = sealed(command(), key(2), "GAUSSTRACK_COMMAND");
  ChannelAuth receiver(key(1), "GAUSSTRACK_COMMAND");
  long refused = 0;
  for (auto _ : st) {
    std::size_t body = 0;
    refused += receiver.open(m.buf.data(), static_cast<std::size_t>(m.size), body) == AuthRefusal::kBadTag;
  }
  if (refused != static_cast<long>(st.iterations())) st.SkipWithError("a forged message was not refused");
}

void BM_Seal(benchmark::State& st) {
  const Message plain = command();
  Message m = plain;
  ChannelAuth sender(key(1), "GAUSSTRACK_COMMAND");
  for (auto _ : st) {
    benchmark::DoNotOptimize(sender.seal(m.buf.data(), static_cast<std::size_t>(plain.size), m.buf.size()));
    benchmark::ClobberMemory();
  }
}

BENCHMARK_CAPTURE(BM_Decode, command, true);
BENCHMARK_CAPTURE(BM_VerifyAndDecode, command, true);
BENCHMARK_CAPTURE(BM_Decode, state, false);
BENCHMARK_CAPTURE(BM_VerifyAndDecode, state, false);
BENCHMARK(BM_RefuseGarbage);
BENCHMARK(BM_RefuseForged);
BENCHMARK(BM_Seal);

}  // namespace

BENCHMARK_MAIN();

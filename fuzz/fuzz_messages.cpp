// Every message decoder and validator on hostile bytes: the generated decoders of the three
// fixed-size message types, the checked decoder of loop statistics (decode_loop_stats), the
// codec's state and command validation at any dimension, the controller node's handling of a
// state (serve, repeat, supersede or refuse) and the plant node's handling of a command.
//
// Properties (any violation aborts, so libFuzzer keeps the input):
// - a decoded state or command that the codec accepts has finite values and its dimension;
// - the controller node accounts for every datagram (served + repeated + duplicates + superseded
//   + rejected), whether it answers each at once or takes several before answering the newest,
//   and every command it publishes decodes, answers that run with a finite force, and is zero when failed;
// - the plant node accounts for every command (kept or refused, never applied twice);
// - with the pair's key the nodes account for authentication refusals too, and datagrams the
//   harness seals with that key reach the checks behind the authentication.
#include <lcm/lcm-cpp.hpp>

#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>
#include <string>

#include "fuzz_input.hpp"
#include "gausstrack/control_command_t.hpp"
#include "gausstrack/control_diagnostics_t.hpp"
#include "gausstrack/loop_stats_t.hpp"
#include "gausstrack/nodes/auth.hpp"
#include "gausstrack/nodes/codec.hpp"
#include "gausstrack/nodes/controller_node.hpp"
#include "gausstrack/nodes/message_log.hpp"
#include "gausstrack/nodes/plant_node.hpp"
#include "gausstrack/plant_state_t.hpp"
#include "gausstrack/systems/coupled_duffing.hpp"

namespace {

namespace gn = gausstrack::nodes;
using gausstrack::fuzz::FuzzInput;
using Duffing = gausstrack::systems::CoupledDuffing<double>;

constexpr std::int64_t kPlantRunId = 42;  // the seed corpus's commands answer this run

// One in-process LCM (no network) shared by every input; its queue is drained after each input.
struct Harness {
  lcm::LCM lcm{"memq://"};
  gn::Outbox commands{lcm, "COMMAND", nullptr, false};
  gn::Outbox states{lcm, "STATE", nullptr, false};
  long commands_seen = 0;
  gn::Codec<2> codec;

  Harness() { lcm.subscribe("COMMAND", &Harness::on_command, this); }

  // A command the controller node published: it must be well formed.
  void on_command(const lcm::ReceiveBuffer* rbuf, const std::string&) {
    ++commands_seen;
    gausstrack::control_command_t msg;
    gn::WireVector<2> force;
    GAUSSTRACK_FUZZ_CHECK(codec.decode_command(rbuf->data, rbuf->data_size, msg, force) ==
                          gn::Refusal::kNone);
    GAUSSTRACK_FUZZ_CHECK(force.allFinite());
    for (int i = 0; i < gn::kMaxDimension; ++i)
      GAUSSTRACK_FUZZ_CHECK(std::isfinite(msg.force[i]) && std::isfinite(msg.control[i]));
    GAUSSTRACK_FUZZ_CHECK(msg.actuators == 0);  // the Duffing pair's law actuates every coordinate
    if (msg.status != 0) GAUSSTRACK_FUZZ_CHECK(force.isZero(0));
  }
  void drain() {
    while (lcm.handleTimeout(0) > 0) {
    }
  }
};

Harness& harness() {
  static Harness h;
  return h;
}

template <typename Message>
void decode_generated(const std::uint8_t* data, std::size_t size) {
  Message m;
  const int n = m.decode(data, 0, static_cast<int>(size));
  GAUSSTRACK_FUZZ_CHECK(n <= static_cast<int>(size));
  if (n >= 0) {
    // What decoded encodes again to the same size.
    GAUSSTRACK_FUZZ_CHECK(m.getEncodedSize() == n);
  }
}

void codec_case(std::uint8_t dimension, const std::uint8_t* data, std::size_t size) {
  gn::Codec<Eigen::Dynamic> codec(dimension % 40);
  if (!codec.valid()) return;
  gausstrack::plant_state_t state;
  gn::WireVector<Eigen::Dynamic> q, qd, force;
  if (codec.decode_state(data, size, state, q, qd) == gn::Refusal::kNone) {
    GAUSSTRACK_FUZZ_CHECK(state.dimension == codec.dimension() && q.size() == codec.dimension());
    GAUSSTRACK_FUZZ_CHECK(q.allFinite() && qd.allFinite() && std::isfinite(state.t));
  }
  gausstrack::control_command_t command;
  if (codec.decode_command(data, size, command, force) == gn::Refusal::kNone) {
    GAUSSTRACK_FUZZ_CHECK(command.dimension == codec.dimension() &&
                          force.size() == codec.dimension());
    GAUSSTRACK_FUZZ_CHECK(force.allFinite());
    GAUSSTRACK_FUZZ_CHECK(command.actuators >= 0 && command.actuators <= gn::kMaxDimension);
    if (command.status == 0)
      for (int i = 0; i < command.actuators; ++i)
        GAUSSTRACK_FUZZ_CHECK(std::isfinite(command.control[i]));
  }
}

// The length of the next datagram: two bytes (little endian), at most what is left. The top bit
// is not part of it: `flag` (the controller node in batches: answer after this datagram).
std::size_t next_length(FuzzInput& in, bool* flag = nullptr) {
  std::size_t n = in.byte();
  n |= static_cast<std::size_t>(in.byte()) << 8;
  if (flag) *flag = (n & 0x8000) != 0;
  n &= 0x7fff;
  return n < in.rest_size() ? n : in.rest_size();
}

// A sequence of datagrams for one controller node: each is its length and that many bytes.
// With the pair's key: each datagram is sealed with it or not, as its flag byte says. In batches
// (as serve() takes what is queued): each datagram is taken, and the newest state answered after
// a datagram whose length has its top bit set, and at the end.
void controller_case(FuzzInput& in, bool authenticated, bool batches) {
  Harness& h = harness();
  gn::ControllerNode<Duffing> node(gausstrack::TrackingController<Duffing>{}, h.commands, nullptr,
                                   16);
  const gn::MessageKey key(std::array<std::uint8_t, gn::kKeyBytes>{7});
  gn::ChannelAuth open(key, "STATE"), seal(key, "STATE");
  if (authenticated) node.authenticate(open);
  std::array<std::uint8_t, gn::kMessageBufferBytes> sealed{};
  const long before = h.commands_seen;
  long datagrams = 0;
  while (in.rest_size() > 0) {
    const bool seal_this = authenticated && (in.byte() & 1) != 0;
    bool answer_now = false;
    std::size_t n = next_length(in, &answer_now);
    const std::uint8_t* bytes = in.rest();
    for (std::size_t i = 0; i < n; ++i) in.byte();
    if (seal_this && n + gn::kTrailerBytes <= sealed.size()) {
      std::memcpy(sealed.data(), bytes, n);
      const int m = seal.seal(sealed.data(), n, sealed.size());
      GAUSSTRACK_FUZZ_CHECK(m == static_cast<int>(n + gn::kTrailerBytes));
      bytes = sealed.data();
      n = static_cast<std::size_t>(m);
    }
    if (!batches) {
      node.handle(bytes, n);
    } else {
      node.receive(bytes, n);
      if (answer_now) node.answer();
    }
    ++datagrams;
  }
  node.answer();
  h.drain();
  const gn::ControllerCounts& c = node.counts();
  GAUSSTRACK_FUZZ_CHECK(c.served + c.repeated + c.duplicates + c.superseded + c.rejected == datagrams);
  if (!batches) GAUSSTRACK_FUZZ_CHECK(c.superseded == 0 && c.duplicates == 0);
  GAUSSTRACK_FUZZ_CHECK(c.rejected ==
                        c.malformed + c.wrong_dimension + c.non_finite + c.stale + c.auth.total());
  if (!authenticated) GAUSSTRACK_FUZZ_CHECK(c.auth.total() == 0);
  GAUSSTRACK_FUZZ_CHECK(h.commands_seen - before == c.served + c.repeated);
}

void plant_case(FuzzInput& in, bool authenticated) {
  Harness& h = harness();
  gn::PlantNodeOptions o;
  o.run_id = kPlantRunId;
  o.periods = 16;
  gn::PlantNode node(h.lcm, h.states, "PLANT_COMMAND", 1 + in.byte() % 32, o);
  gn::ChannelAuth open(gn::MessageKey(std::array<std::uint8_t, gn::kKeyBytes>{7}), "PLANT_COMMAND");
  if (authenticated) node.authenticate(open);
  long datagrams = 0;
  while (in.rest_size() > 0) {
    std::size_t n = next_length(in);
    const std::uint8_t* bytes = in.rest();
    for (std::size_t i = 0; i < n; ++i) in.byte();
    node.handle_command(bytes, n, 0);
    ++datagrams;
  }
  h.drain();
  const gn::PlantCounts& c = node.counts();
  // No state was published, so no command can be kept: each one is refused for a stated reason.
  GAUSSTRACK_FUZZ_CHECK(c.rejected == datagrams);
  GAUSSTRACK_FUZZ_CHECK(c.rejected == c.malformed + c.wrong_dimension + c.non_finite + c.stale +
                                          c.other_run + c.auth.total());
  GAUSSTRACK_FUZZ_CHECK(open.last_accepted() ==
                        0);  // nothing the fuzzer writes carries the key's tag
  GAUSSTRACK_FUZZ_CHECK(c.commands_applied == 0);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  FuzzInput in(data, size);
  const std::uint8_t selector = in.byte();
  const std::uint8_t* rest = in.rest();
  const std::size_t rest_size = in.rest_size();
  switch (selector % 8) {
    case 0:
      decode_generated<gausstrack::plant_state_t>(rest, rest_size);
      break;
    case 1:
      decode_generated<gausstrack::control_command_t>(rest, rest_size);
      break;
    case 2:
      decode_generated<gausstrack::control_diagnostics_t>(rest, rest_size);
      break;
    case 3: {
      gausstrack::loop_stats_t stats;
      if (gn::decode_loop_stats(rest, rest_size, stats))
        GAUSSTRACK_FUZZ_CHECK(stats.getEncodedSize() == static_cast<int>(rest_size));
      break;
    }
    case 4: {
      const std::uint8_t dimension = in.byte();
      codec_case(dimension, in.rest(), in.rest_size());
      break;
    }
    case 5:
      controller_case(in, false, (selector & 16) != 0);
      break;
    case 6:
      controller_case(in, true, (selector & 16) != 0);
      break;
    default:
      plant_case(in, (selector & 8) != 0);
      break;
  }
  return 0;
}

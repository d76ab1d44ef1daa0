// Writes fuzz_messages's seed corpus into the directory given: valid encodings of every message
// type behind each selector of the target, and sequences of datagrams for the two nodes.
#include <Eigen/Core>

#include <cstdint>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "gausstrack/control_command_t.hpp"
#include "gausstrack/control_diagnostics_t.hpp"
#include "gausstrack/loop_stats_t.hpp"
#include "gausstrack/nodes/codec.hpp"
#include "gausstrack/plant_state_t.hpp"

namespace {

namespace gn = gausstrack::nodes;
using Bytes = std::vector<std::uint8_t>;

template <typename Message>
Bytes encode(const Message& m) {
  Bytes b(static_cast<std::size_t>(m.getEncodedSize()));
  m.encode(b.data(), 0, static_cast<int>(b.size()));
  return b;
}

gausstrack::plant_state_t state(int dimension, std::int64_t run_id, std::int64_t sequence, double t) {
  gausstrack::plant_state_t s{};
  s.utime = 1;
  s.run_id = run_id;
  s.sequence = sequence;
  s.t = t;
  s.dimension = dimension;
  for (int i = 0; i < dimension; ++i) {
    s.q[i] = 0.1 * (i + 1);
    s.qd[i] = -0.05 * i;
  }
  return s;
}

gausstrack::control_command_t command(int dimension, std::int64_t run_id, std::int64_t state_sequence, int status) {
  gausstrack::control_command_t c{};
  c.utime = 2;
  c.sequence = state_sequence + 1;
  c.run_id = run_id;
  c.state_sequence = state_sequence;
  c.status = status;
  c.dimension = dimension;
  for (int i = 0; i < dimension; ++i) c.force[i] = 1.5 * (i + 1);
  return c;
}

Bytes with_selector(std::uint8_t selector, const Bytes& payload, std::vector<std::uint8_t> prefix = {}) {
  Bytes b{selector};
  b.insert(b.end(), prefix.begin(), prefix.end());
  b.insert(b.end(), payload.begin(), payload.end());
  return b;
}

// `answer`: the controller node in batches answers after this datagram (the length's top bit).
void append_datagram(Bytes& b, const Bytes& datagram, bool answer = false) {
  b.push_back(static_cast<std::uint8_t>(datagram.size() & 0xff));
  b.push_back(static_cast<std::uint8_t>((datagram.size() >> 8) | (answer ? 0x80 : 0)));
  b.insert(b.end(), datagram.begin(), datagram.end());
}

void write(const std::string& dir, const std::string& name, const Bytes& b) {
  std::ofstream out(dir + "/" + name, std::ios::binary);
  out.write(reinterpret_cast<const char*>(b.data()), static_cast<std::streamsize>(b.size()));
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s DIRECTORY\n", argv[0]);
    return 2;
  }
  const std::string dir = argv[1];
  gausstrack::control_diagnostics_t diag{};
  diag.dimension = 2;
  diag.rank = 1;
  gausstrack::loop_stats_t stats{};
  stats.process = "plant";
  stats.states_published = 1000;

  write(dir, "state", with_selector(0, encode(state(2, 7, 1, 0.5))));
  write(dir, "command", with_selector(1, encode(command(2, 7, 1, 0))));
  write(dir, "diagnostics", with_selector(2, encode(diag)));
  write(dir, "stats", with_selector(3, encode(stats)));
  write(dir, "codec_state_8", with_selector(4, encode(state(8, 7, 3, 1.0)), {8}));
  write(dir, "codec_command_32", with_selector(4, encode(command(32, 7, 3, 0)), {32}));

  // The controller node: a run, a repeat, a stale state, a restarted plant, a late datagram of
  // the ended run, a state of the wrong dimension.
  Bytes controller{5};
  for (const auto& s : {state(2, 7, 1, 0.0), state(2, 7, 2, 0.001), state(2, 7, 2, 0.001), state(2, 7, 1, 0.0),
                        state(2, 9, 1, 0.0), state(2, 7, 5, 0.005), state(3, 9, 2, 0.001)})
    append_datagram(controller, encode(s));
  write(dir, "controller_sequence", controller);
  // The same node taking states in batches: three queued (the newest answered), a stale one, the
  // newest again, a restarted plant's state superseding its ended run's.
  Bytes batches{5 | 16};
  append_datagram(batches, encode(state(2, 7, 1, 0.0)));
  append_datagram(batches, encode(state(2, 7, 2, 0.001)));
  append_datagram(batches, encode(state(2, 7, 3, 0.002)), true);
  append_datagram(batches, encode(state(2, 7, 2, 0.001)));
  append_datagram(batches, encode(state(2, 7, 3, 0.002)));
  append_datagram(batches, encode(state(2, 7, 4, 0.003)));
  append_datagram(batches, encode(state(2, 9, 0, 0.0)));
  write(dir, "controller_batches", batches);

  // The plant node (run 42, dimension 2): commands of its run, of another run, a failed one.
  Bytes plant{7, 1};
  for (const auto& c : {command(2, 42, 0, 0), command(2, 42, 1, 2), command(2, 5, 0, 0), command(3, 42, 0, 0)})
    append_datagram(plant, encode(c));
  write(dir, "plant_sequence", plant);
  return 0;
}

// The node library without a network (LCM's memq:// provider): the codec at every dimension,
// the controller node's compute, validation, failure contract and plant restarts, the plant
// node's lock-step and real-time exchange, and the scheduler and watchdog alone. One test opens a
// udpm:// LCM (ttl=0, loopback only) to see the priority of its receive thread.
#include <gtest/gtest.h>
#include <sched.h>
#include <sys/syscall.h>
#include <unistd.h>
#include <lcm/lcm-cpp.hpp>

#include <Eigen/Dense>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <random>
#include <filesystem>
#include <thread>
#include <utility>
#include <vector>

#include "gausstrack/nodes/auth.hpp"
#include "gausstrack/nodes/codec.hpp"
#include "gausstrack/nodes/controller_node.hpp"
#include "gausstrack/nodes/plant_node.hpp"
#include "gausstrack/plant_sim/models.hpp"
#include "gausstrack/systems/cart_pole.hpp"
#include "gausstrack/systems/coupled_duffing.hpp"

namespace gausstrack::nodes {
namespace {

using Duffing = systems::CoupledDuffing<double>;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::vector<std::uint8_t> encode_state(int dimension, std::int64_t run_id, std::int64_t sequence,
                                       double t, const std::vector<double>& q,
                                       const std::vector<double>& qd) {
  plant_state_t s{};
  s.run_id = run_id;
  s.sequence = sequence;
  s.t = t;
  s.dimension = dimension;
  for (std::size_t i = 0; i < q.size(); ++i) s.q[i] = q[i], s.qd[i] = qd[i];
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(s.getEncodedSize()));
  s.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  return bytes;
}

// ---------------------------------------------------------------------------------------------
// Codec

template <int N>
void round_trip_fixed(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-1e3, 1e3);
  Codec<N> codec;
  ASSERT_TRUE(codec.valid());
  typename Codec<N>::Vector q, qd, f, q2, qd2, f2;
  for (int i = 0; i < N; ++i) q(i) = u(rng), qd(i) = u(rng), f(i) = u(rng);
  std::array<std::uint8_t, kMessageBufferBytes> buf{};
  plant_state_t s{}, d{};
  s.sequence = 9;
  const int size = codec.encode_state(s, q, qd, buf.data(), buf.size());
  ASSERT_GT(size, 0);
  ASSERT_EQ(codec.decode_state(buf.data(), static_cast<std::size_t>(size), d, q2, qd2),
            Refusal::kNone)
      << N;
  EXPECT_EQ(q2, q) << N;
  EXPECT_EQ(qd2, qd) << N;
  for (int i = N; i < kMaxDimension; ++i) EXPECT_EQ(d.q[i], 0.0);
  // Another receiver's dimension, a truncated message, a NaN: each refused with its reason.
  Codec<Eigen::Dynamic> other(N == kMaxDimension ? N - 1 : N + 1);
  typename Codec<Eigen::Dynamic>::Vector oq, oqd;
  EXPECT_EQ(other.decode_state(buf.data(), static_cast<std::size_t>(size), d, oq, oqd),
            Refusal::kDimension);
  EXPECT_EQ(codec.decode_state(buf.data(), static_cast<std::size_t>(size - 1), d, q2, qd2),
            Refusal::kMalformed);
  q(N - 1) = kNaN;
  const int nan_size = codec.encode_state(s, q, qd, buf.data(), buf.size());
  EXPECT_EQ(codec.decode_state(buf.data(), static_cast<std::size_t>(nan_size), d, q2, qd2),
            Refusal::kNonFinite);

  control_command_t c{}, e{};
  const int csize = codec.encode_command(c, f, buf.data(), buf.size());
  ASSERT_GT(csize, 0);
  ASSERT_EQ(codec.decode_command(buf.data(), static_cast<std::size_t>(csize), e, f2),
            Refusal::kNone);
  EXPECT_EQ(f2, f);
  EXPECT_EQ(other.decode_command(buf.data(), static_cast<std::size_t>(csize), e, oq),
            Refusal::kDimension);
  // A state's bytes are not a command (the type fingerprint differs).
  ASSERT_EQ(codec.encode_state(s, q2, qd2, buf.data(), buf.size()), size);
  EXPECT_EQ(codec.decode_command(buf.data(), static_cast<std::size_t>(size), e, f2),
            Refusal::kMalformed);
}

template <int... N>
void round_trip_all(std::integer_sequence<int, N...>, std::mt19937_64& rng) {
  (round_trip_fixed<N + 1>(rng), ...);
}

TEST(Codec, RoundTripsAtEveryDimensionAndRefusesTheWrongOne) {
  std::mt19937_64 rng(7);
  round_trip_all(std::make_integer_sequence<int, kMaxDimension>{}, rng);
}

// Found by fuzz_messages: the generated decoder of loop_stats_t throws std::length_error on a
// string length of 0 (and reads before the buffer on a negative one); decode_loop_stats refuses
// those and every truncation, and decodes a real message whole.
TEST(Codec, LoopStatsDecoderRefusesBadStringLengths) {
  loop_stats_t s{};
  s.process = "controller";
  s.commands_published = 1234;
  std::vector<std::uint8_t> buf(static_cast<std::size_t>(s.getEncodedSize()));
  ASSERT_EQ(s.encode(buf.data(), 0, static_cast<int>(buf.size())), static_cast<int>(buf.size()));
  loop_stats_t d{};
  ASSERT_TRUE(decode_loop_stats(buf.data(), buf.size(), d));
  EXPECT_EQ(d.process, "controller");
  EXPECT_EQ(d.commands_published, 1234);
  for (std::size_t n = 0; n < buf.size(); ++n)
    EXPECT_FALSE(decode_loop_stats(buf.data(), n, d)) << n;
  // The string's length field: bytes 16..19, big-endian, 11 here ("controller" and its '\0').
  ASSERT_EQ(buf[19], 11);
  for (const std::int32_t bad : {0, -1, -100, INT32_MIN, 1 << 20}) {
    std::vector<std::uint8_t> b = buf;
    const auto u = static_cast<std::uint32_t>(bad);
    b[16] = static_cast<std::uint8_t>(u >> 24), b[17] = static_cast<std::uint8_t>(u >> 16);
    b[18] = static_cast<std::uint8_t>(u >> 8), b[19] = static_cast<std::uint8_t>(u);
    EXPECT_FALSE(decode_loop_stats(b.data(), b.size(), d)) << bad;
  }
}

// An actuated law's command carries u beside B u; the count and the commands are validated as
// the force is.
TEST(Codec, ActuatorCommandsRoundTripAndAreValidated) {
  Codec<3> codec;
  const Eigen::Vector3d force(1.0, -2.0, 0.5);
  const Eigen::Vector2d u(4.0, -0.25);
  std::array<std::uint8_t, kMessageBufferBytes> buf{};
  control_command_t c{}, e{};
  Eigen::Vector3d f2;
  int size = codec.encode_command(c, force, u, buf.data(), buf.size());
  ASSERT_GT(size, 0);
  ASSERT_EQ(codec.decode_command(buf.data(), static_cast<std::size_t>(size), e, f2),
            Refusal::kNone);
  EXPECT_EQ(f2, force);
  EXPECT_EQ(e.actuators, 2);
  EXPECT_EQ(e.control[0], 4.0);
  EXPECT_EQ(e.control[1], -0.25);
  for (int i = 2; i < kMaxDimension; ++i) EXPECT_EQ(e.control[i], 0.0);
  // The force alone: no actuator commands.
  size = codec.encode_command(c, force, buf.data(), buf.size());
  ASSERT_EQ(codec.decode_command(buf.data(), static_cast<std::size_t>(size), e, f2),
            Refusal::kNone);
  EXPECT_EQ(e.actuators, 0);
  // A NaN command of a successful solve is refused; of a failed one (status not 0) it is ignored.
  const Eigen::Vector2d bad(kNaN, 1.0);
  c.status = 0;
  size = codec.encode_command(c, force, bad, buf.data(), buf.size());
  EXPECT_EQ(codec.decode_command(buf.data(), static_cast<std::size_t>(size), e, f2),
            Refusal::kNonFinite);
  c.status = 3;
  size = codec.encode_command(c, force, bad, buf.data(), buf.size());
  EXPECT_EQ(codec.decode_command(buf.data(), static_cast<std::size_t>(size), e, f2),
            Refusal::kNone);
  EXPECT_TRUE(f2.isZero(0));
  // A count out of range, written past the codec, is malformed.
  for (const std::int32_t count : {-1, kMaxDimension + 1}) {
    control_command_t raw{};
    raw.dimension = 3;
    raw.actuators = count;
    const int n = raw.encode(buf.data(), 0, raw.getEncodedSize());
    ASSERT_GT(n, 0);
    EXPECT_EQ(codec.decode_command(buf.data(), static_cast<std::size_t>(n), e, f2),
              Refusal::kMalformed)
        << count;
  }
  // More commands than the message holds are not encoded.
  const Eigen::Matrix<double, kMaxDimension + 1, 1> many =
      Eigen::Matrix<double, kMaxDimension + 1, 1>::Ones();
  EXPECT_EQ(codec.encode_command(c, force, many, buf.data(), buf.size()), -1);
}

TEST(Codec, RunTimeDimensionRoundTripsAndRejectsOutOfRangeDimensions) {
  std::mt19937_64 rng(8);
  std::normal_distribution<double> g;
  for (int n = 1; n <= kMaxDimension; ++n) {
    Codec<Eigen::Dynamic> codec(n);
    ASSERT_TRUE(codec.valid());
    Codec<Eigen::Dynamic>::Vector q(n), qd(n), q2, qd2;
    for (int i = 0; i < n; ++i) q(i) = g(rng), qd(i) = g(rng);
    std::array<std::uint8_t, kMessageBufferBytes> buf{};
    plant_state_t s{}, d{};
    const int size = codec.encode_state(s, q, qd, buf.data(), buf.size());
    ASSERT_EQ(codec.decode_state(buf.data(), static_cast<std::size_t>(size), d, q2, qd2),
              Refusal::kNone);
    EXPECT_EQ(q2, q);
    EXPECT_EQ(qd2, qd);
  }
  EXPECT_FALSE(Codec<Eigen::Dynamic>(0).valid());
  EXPECT_FALSE(Codec<Eigen::Dynamic>(33).valid());
  EXPECT_FALSE(Codec<3>(2).valid());
}

// ---------------------------------------------------------------------------------------------
// Controller node

// Collects what is published on one channel of a memq LCM.
struct Collector {
  std::vector<control_command_t> commands;
  void on(const lcm::ReceiveBuffer* rbuf, const std::string&) {
    control_command_t c{};
    ASSERT_GE(c.decode(rbuf->data, 0, static_cast<int>(rbuf->data_size)), 0);
    commands.push_back(c);
  }
};

plant_sim::TrackingSpec duffing_spec() {
  plant_sim::TrackingSpec spec;
  spec.enabled = true;
  spec.model = "coupled_duffing";
  spec.where = "test";
  spec.parameters = {{"k1", 11.0, "test"}, {"alpha", 0.4, "test"}};
  return spec;
}

// Eq. (32) for the Duffing oscillator written out by hand (not through the library's solver):
// D = [1, -1], g = s''(t), A = diag(m1, m2), a = A^-1 (Q - f), Q' = A D^T (g - D a) / (D A^-1 D^T).
Eigen::Vector2d duffing_force_by_hand(const Duffing& m, const Eigen::Vector2d& q,
                                      const Eigen::Vector2d& qd, double t) {
  const Eigen::Vector2d f = m.spring_damper_force(q, qd);
  const Eigen::Vector2d a(-f(0) / m.m1, -f(1) / m.m2);
  const double lambda = (m.trajectory.acceleration(t) - (a(0) - a(1))) / (1 / m.m1 + 1 / m.m2);
  return {lambda, -lambda};
}

struct ControllerFixture : ::testing::Test {
  lcm::LCM lcm{"memq://"};
  Outbox commands{lcm, "CMD", nullptr, false};
  ControllerNode<Duffing> node{plant_sim::make_controller<Duffing>(duffing_spec()), commands};
  Collector out;
  void SetUp() override {
    ASSERT_TRUE(lcm.good());
    lcm.subscribe("CMD", &Collector::on, &out);
    lcm.subscribe("STATE", &ControllerNode<Duffing>::on_state, &node);
  }
  // Publishes a state and dispatches until nothing is left.
  void send(const std::vector<std::uint8_t>& bytes) {
    lcm.publish("STATE", bytes.data(), static_cast<unsigned>(bytes.size()));
    while (lcm.handleTimeout(0) > 0) {
    }
  }
};

// The actuated law at a state, out of line: inlined into a test body, GCC spends a minute on it.
[[gnu::noinline]] double cart_pole_command(const Eigen::Vector2d& q, const Eigen::Vector2d& qd,
                                           double t) {
  ActuatedController<systems::CartPole<double>> law;
  ActuatedController<systems::CartPole<double>>::Output out;
  return law.compute(q, qd, t, out) == Status::kOk ? out.control(0) : kNaN;
}

// The cart-pole's controller node (one actuator on the cart): its commands carry u, and the force
// is B u = (u, 0), the law's at the state.
TEST(ControllerNodeActuated, TheCommandCarriesTheActuatorCommands) {
  using CartPole = systems::CartPole<double>;
  lcm::LCM lcm{"memq://"};
  ASSERT_TRUE(lcm.good());
  Outbox commands{lcm, "CMD", nullptr, false};
  ControllerNode<CartPole> node{ActuatedController<CartPole>{}, commands};
  Collector out;
  lcm.subscribe("CMD", &Collector::on, &out);
  lcm.subscribe("STATE", &ControllerNode<CartPole>::on_state, &node);
  for (int k = 0; k < 5; ++k) {
    const Eigen::Vector2d q(0.1 * k, 0.2 - 0.05 * k), qd(0.3, -0.1 * k);
    const double t = 0.01 * k;
    const auto bytes = encode_state(2, 7, k, t, {q(0), q(1)}, {qd(0), qd(1)});
    lcm.publish("STATE", bytes.data(), static_cast<unsigned>(bytes.size()));
    while (lcm.handleTimeout(0) > 0) {
    }
    ASSERT_EQ(out.commands.size(), static_cast<std::size_t>(k + 1));
    const control_command_t& c = out.commands.back();
    EXPECT_EQ(c.status, 0);
    EXPECT_EQ(c.actuators, 1);
    EXPECT_EQ(c.control[0], cart_pole_command(q, qd, t));
    EXPECT_EQ(c.force[0], c.control[0]);  // B = (1, 0)
    EXPECT_EQ(c.force[1], 0.0);
    EXPECT_NE(c.control[0], 0.0);
  }
}

TEST_F(ControllerFixture, AnswersEachStateWithTheLawsForce) {
  Duffing m;
  m.k1 = 11.0;
  m.trajectory.alpha = 0.4;
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-2, 2);
  for (int k = 0; k < 50; ++k) {
    const Eigen::Vector2d q(u(rng), u(rng)), qd(u(rng), u(rng));
    const double t = 0.01 * k;
    send(encode_state(2, 77, k, t, {q(0), q(1)}, {qd(0), qd(1)}));
    ASSERT_EQ(out.commands.size(), static_cast<std::size_t>(k + 1));
    const control_command_t& c = out.commands.back();
    EXPECT_EQ(c.status, 0);
    EXPECT_EQ(c.run_id, 77);
    EXPECT_EQ(c.state_sequence, k);
    EXPECT_EQ(c.dimension, 2);
    const Eigen::Vector2d expected = duffing_force_by_hand(m, q, qd, t);
    EXPECT_NEAR(c.force[0], expected(0), 1e-10 * (1 + expected.norm()));
    EXPECT_NEAR(c.force[1], expected(1), 1e-10 * (1 + expected.norm()));
  }
  EXPECT_EQ(node.counts().served, 50);
  EXPECT_EQ(node.counts().rejected, 0);
}

TEST_F(ControllerFixture, RefusesBadStatesWithTheirReasonAndAnswersNothing) {
  send(encode_state(3, 1, 0, 0.0, {0, 0, 0}, {0, 0, 0}));  // dimension
  send(encode_state(2, 1, 1, 0.0, {kNaN, 0}, {0, 0}));     // NaN
  send(encode_state(2, 1, 2, std::numeric_limits<double>::infinity(), {0, 0}, {0, 0}));  // t
  auto bytes = encode_state(2, 1, 3, 0.0, {0, 0}, {0, 0});
  bytes.resize(bytes.size() / 2);  // truncated
  send(bytes);
  send(encode_state(2, 1, 4, 0.0, {0.1, 0}, {0, 0}));   // served
  send(encode_state(2, 1, 3, 0.0, {0.1, 0}, {0, 0}));   // older sequence
  send(encode_state(2, 1, -1, 0.0, {0.1, 0}, {0, 0}));  // negative sequence
  const ControllerCounts& c = node.counts();
  EXPECT_EQ(c.wrong_dimension, 1);
  EXPECT_EQ(c.non_finite, 2);
  EXPECT_EQ(c.malformed, 1);
  EXPECT_EQ(c.stale, 2);
  EXPECT_EQ(c.rejected, 6);
  EXPECT_EQ(c.served, 1);
  EXPECT_EQ(c.runs, 1);
  EXPECT_EQ(out.commands.size(), 1u);
}

// A plant in lock-step that lost a message asks again with the same state: the same command
// comes back, the law is not evaluated twice.
TEST_F(ControllerFixture, ARepeatedStateGetsTheSameCommandAgain) {
  send(encode_state(2, 1, 0, 0.2, {0.3, 0.1}, {0.5, 0}));
  send(encode_state(2, 1, 0, 0.2, {0.3, 0.1}, {0.5, 0}));
  ASSERT_EQ(out.commands.size(), 2u);
  EXPECT_EQ(out.commands[0].sequence, out.commands[1].sequence);
  EXPECT_EQ(out.commands[0].force[0], out.commands[1].force[0]);
  EXPECT_EQ(node.counts().served, 1);
  EXPECT_EQ(node.counts().repeated, 1);
  EXPECT_EQ(node.compute_ns().count(), 1u);
}

TEST_F(ControllerFixture, FailedSolveIsPublishedAsZeroForceWithItsStatus) {
  // Finite but huge: the cubic springs overflow, the law cannot answer.
  send(encode_state(2, 5, 0, 0.0, {1e120, -1e120}, {0, 0}));
  ASSERT_EQ(out.commands.size(), 1u);
  const control_command_t& c = out.commands[0];
  EXPECT_NE(c.status, 0);
  EXPECT_EQ(c.force[0], 0.0);
  EXPECT_EQ(c.force[1], 0.0);
  EXPECT_EQ(node.counts().failed, 1);
  // The next good state is answered normally.
  send(encode_state(2, 5, 1, 0.0, {0.5, 0.1}, {0, 0}));
  ASSERT_EQ(out.commands.size(), 2u);
  EXPECT_EQ(out.commands[1].status, 0);
  EXPECT_NE(out.commands[1].force[0], 0.0);
}

TEST_F(ControllerFixture, RestartedPlantIsANewRunNotStaleStates) {
  for (int k = 0; k < 5; ++k) send(encode_state(2, 100, k, 0.01 * k, {0.1, 0}, {0, 0}));
  // The plant restarts: a new run_id, its sequence from 0 again.
  for (int k = 0; k < 3; ++k) send(encode_state(2, 200, k, 0.01 * k, {0.1, 0}, {0, 0}));
  EXPECT_EQ(node.counts().runs, 2);
  EXPECT_EQ(node.counts().served, 8);
  EXPECT_EQ(node.counts().stale, 0);
  EXPECT_EQ(out.commands.back().run_id, 200);
  EXPECT_EQ(out.commands.back().state_sequence, 2);
  send(encode_state(2, 200, 1, 0.0, {0.1, 0}, {0, 0}));  // old within the new run
  EXPECT_EQ(node.counts().stale, 1);
  // A late datagram of the ended run neither is served nor switches back to that run.
  send(encode_state(2, 100, 5, 0.05, {0.1, 0}, {0, 0}));
  EXPECT_EQ(node.counts().stale, 2);
  EXPECT_EQ(node.counts().runs, 2);
  send(encode_state(2, 200, 3, 0.03, {0.1, 0}, {0, 0}));
  EXPECT_EQ(node.counts().served, 9);
  EXPECT_EQ(node.counts().runs, 2);
}

// A controller that fell behind answers the plant's present state, not the queue: serve() takes
// every state queued and answers only the newest, with the law's force at that state.
TEST_F(ControllerFixture, ServeAnswersOnlyTheNewestQueuedState) {
  Duffing m;
  m.k1 = 11.0;
  m.trajectory.alpha = 0.4;
  const auto publish = [&](const std::vector<std::uint8_t>& bytes) {
    lcm.publish("STATE", bytes.data(), static_cast<unsigned>(bytes.size()));
  };
  std::vector<Eigen::Vector2d> qs;
  for (int k = 0; k < 5; ++k) {
    qs.emplace_back(0.1 * k + 0.05, -0.2 * k);
    publish(encode_state(2, 3, k, 0.01 * k, {qs[k](0), qs[k](1)}, {0.3, 0.1 * k}));
  }
  publish(encode_state(2, 3, 4, 0.04, {qs[4](0), qs[4](1)}, {0.3, 0.4}));  // the newest again
  EXPECT_GT(node.serve(lcm, 0), 0);
  while (lcm.handleTimeout(0) > 0) {
  }
  ASSERT_EQ(out.commands.size(), 1u);
  EXPECT_EQ(out.commands[0].state_sequence, 4);
  const Eigen::Vector2d expected = duffing_force_by_hand(m, qs[4], Eigen::Vector2d(0.3, 0.4), 0.04);
  EXPECT_NEAR(out.commands[0].force[0], expected(0), 1e-10 * (1 + expected.norm()));
  EXPECT_NEAR(out.commands[0].force[1], expected(1), 1e-10 * (1 + expected.norm()));
  EXPECT_EQ(node.counts().served, 1);
  EXPECT_EQ(node.counts().superseded, 4);
  EXPECT_EQ(node.counts().duplicates, 1);
  EXPECT_EQ(node.counts().largest_backlog, 5);  // five states found queued at once (and a duplicate)
  EXPECT_EQ(node.compute_ns().count(), 1u);

  // The answered state again (a lock-step plant asking after a lost answer): the same command,
  // not recomputed.
  publish(encode_state(2, 3, 4, 0.04, {qs[4](0), qs[4](1)}, {0.3, 0.4}));
  node.serve(lcm, 0);
  while (lcm.handleTimeout(0) > 0) {
  }
  ASSERT_EQ(out.commands.size(), 2u);
  EXPECT_EQ(out.commands[1].sequence, out.commands[0].sequence);
  EXPECT_EQ(out.commands[1].force[0], out.commands[0].force[0]);
  EXPECT_EQ(out.commands[1].force[1], out.commands[0].force[1]);
  EXPECT_EQ(node.counts().repeated, 1);
  EXPECT_EQ(node.compute_ns().count(), 1u);
  out.commands.erase(out.commands.begin() + 1);

  // A state alone is answered as before, and an older one queued behind a newer is refused.
  publish(encode_state(2, 3, 6, 0.06, {0.2, 0.1}, {0, 0}));
  publish(encode_state(2, 3, 5, 0.05, {0.2, 0.1}, {0, 0}));
  node.serve(lcm, 0);
  while (lcm.handleTimeout(0) > 0) {
  }
  ASSERT_EQ(out.commands.size(), 2u);
  EXPECT_EQ(out.commands[1].state_sequence, 6);
  EXPECT_EQ(node.counts().stale, 1);
  EXPECT_EQ(node.counts().superseded, 4);
  EXPECT_EQ(node.counts().largest_backlog, 5);  // the largest, not the last
  // Nothing queued: nothing answered, nothing counted.
  EXPECT_EQ(node.serve(lcm, 0), 0);
  EXPECT_EQ(node.counts().served, 2);
}

// Refused datagrams queued behind a good state leave that state to be answered intact; a
// restarted plant's state supersedes the ended run's.
TEST_F(ControllerFixture, RefusedStatesInAQueueLeaveTheNewestGoodOneIntact) {
  const auto publish = [&](const std::vector<std::uint8_t>& bytes) {
    lcm.publish("STATE", bytes.data(), static_cast<unsigned>(bytes.size()));
  };
  Duffing m;
  m.k1 = 11.0;
  m.trajectory.alpha = 0.4;
  const Eigen::Vector2d q(0.7, -0.3), qd(0.2, 0.9);
  publish(encode_state(2, 8, 7, 0.2, {q(0), q(1)}, {qd(0), qd(1)}));
  publish(encode_state(2, 8, 8, 0.3, {kNaN, 5.0}, {1, 1}));   // non-finite
  publish(encode_state(3, 8, 9, 0.3, {4, 4, 4}, {1, 1, 1}));  // another dimension
  auto truncated = encode_state(2, 8, 10, 0.3, {6, 6}, {1, 1});
  truncated.resize(truncated.size() - 9);
  publish(truncated);
  node.serve(lcm, 0);
  while (lcm.handleTimeout(0) > 0) {
  }
  ASSERT_EQ(out.commands.size(), 1u);
  EXPECT_EQ(out.commands[0].state_sequence, 7);
  const Eigen::Vector2d expected = duffing_force_by_hand(m, q, qd, 0.2);
  EXPECT_NEAR(out.commands[0].force[0], expected(0), 1e-10 * (1 + expected.norm()));
  EXPECT_NEAR(out.commands[0].force[1], expected(1), 1e-10 * (1 + expected.norm()));
  EXPECT_EQ(node.counts().rejected, 3);
  EXPECT_EQ(node.counts().superseded, 0);
  EXPECT_EQ(node.counts().largest_backlog, 1);  // refused datagrams are no backlog of states

  publish(encode_state(2, 8, 11, 0.4, {0.1, 0}, {0, 0}));
  publish(encode_state(2, 9, 0, 0.0, {0.1, 0}, {0, 0}));  // the plant restarted
  node.serve(lcm, 0);
  while (lcm.handleTimeout(0) > 0) {
  }
  ASSERT_EQ(out.commands.size(), 2u);
  EXPECT_EQ(out.commands[1].run_id, 9);
  EXPECT_EQ(out.commands[1].state_sequence, 0);
  EXPECT_EQ(node.counts().superseded, 1);
  EXPECT_EQ(node.counts().runs, 2);
}

TEST_F(ControllerFixture, DiagnosticsTravelApartAndAddUpToTheForce) {
  Outbox diag_out(lcm, "DIAG", nullptr, false);
  ControllerNode<Duffing> with_diag(plant_sim::make_controller<Duffing>(duffing_spec()), commands,
                                    &diag_out);
  std::vector<control_diagnostics_t> diags;
  struct DiagCollector {
    std::vector<control_diagnostics_t>* d;
    void on(const lcm::ReceiveBuffer* rbuf, const std::string&) {
      control_diagnostics_t x{};
      ASSERT_GE(x.decode(rbuf->data, 0, static_cast<int>(rbuf->data_size)), 0);
      d->push_back(x);
    }
  } dc{&diags};
  lcm.subscribe("DIAG", &DiagCollector::on, &dc);
  const auto bytes = encode_state(2, 9, 0, 0.3, {0.4, -0.2}, {1, 0.5});
  with_diag.handle(bytes.data(), bytes.size());
  while (lcm.handleTimeout(0) > 0) {
  }
  ASSERT_EQ(diags.size(), 1u);
  ASSERT_EQ(out.commands.size(), 1u);
  for (int i = 0; i < 2; ++i)
    EXPECT_NEAR(diags[0].closed_loop[i] + diags[0].feedforward[i] + diags[0].stabilizing[i],
                out.commands[0].force[i], 1e-12 * (1 + std::abs(out.commands[0].force[i])));
  EXPECT_EQ(diags[0].state_sequence, 0);
  EXPECT_EQ(diags[0].rank, 1);
  // A command carries two arrays of 32 doubles (the force and the actuator commands), not the
  // force's three parts as well.
  EXPECT_LT(control_command_t{}.getEncodedSize(), 3 * 32 * 8);
}

// With the pair's key the controller answers only states that verify, and seals its commands;
// refused states (no trailer, another key, a replay) change nothing it remembers.
TEST(AuthenticatedController, AnswersOnlyVerifiedStatesAndSealsItsCommands) {
  lcm::LCM lcm{"memq://"};
  ASSERT_TRUE(lcm.good());
  const MessageKey key(std::array<std::uint8_t, kKeyBytes>{1, 2, 3}),
      other(std::array<std::uint8_t, kKeyBytes>{9});
  ChannelAuth seal_commands(key, "CMD"), open_states(key, "STATE");
  Outbox commands{lcm, "CMD", nullptr, false, &seal_commands};
  ControllerNode<Duffing> node{plant_sim::make_controller<Duffing>(duffing_spec()), commands};
  node.authenticate(open_states);
  struct Verified {
    ChannelAuth open;
    std::vector<control_command_t> commands;
    long refused = 0;
    void on(const lcm::ReceiveBuffer* rbuf, const std::string&) {
      std::size_t size = 0;
      if (open.open(rbuf->data, rbuf->data_size, size) != AuthRefusal::kNone)
        return void(++refused);
      control_command_t c{};
      ASSERT_EQ(c.decode(rbuf->data, 0, static_cast<int>(size)), static_cast<int>(size));
      commands.push_back(c);
    }
  } out{ChannelAuth(key, "CMD"), {}, 0};
  lcm.subscribe("CMD", &Verified::on, &out);
  lcm.subscribe("STATE", &ControllerNode<Duffing>::on_state, &node);
  ChannelAuth plant(key, "STATE"), stranger(other, "STATE");
  auto sealed = [](ChannelAuth& by, std::vector<std::uint8_t> b) {
    const std::size_t size = b.size();
    b.resize(size + kTrailerBytes);
    b.resize(static_cast<std::size_t>(by.seal(b.data(), size, b.size())));
    return b;
  };
  auto send = [&](const std::vector<std::uint8_t>& bytes) {
    lcm.publish("STATE", bytes.data(), static_cast<unsigned>(bytes.size()));
    while (lcm.handleTimeout(0) > 0) {
    }
  };
  send(encode_state(2, 9, 0, 0.0, {0.1, 0}, {0, 0}));  // no trailer
  const auto first = sealed(plant, encode_state(2, 9, 0, 0.0, {0.1, 0}, {0, 0}));
  send(first);
  ASSERT_EQ(out.commands.size(), 1u);
  send(first);                                                           // replayed
  send(sealed(stranger, encode_state(2, 9, 5, 0.0, {0.1, 0}, {0, 0})));  // another key
  send(sealed(plant, encode_state(2, 9, 1, 0.01, {0.2, 0}, {0, 0})));
  ASSERT_EQ(out.commands.size(), 2u);
  EXPECT_EQ(out.refused, 0);
  EXPECT_EQ(out.commands[1].state_sequence, 1);
  const ControllerCounts& c = node.counts();
  EXPECT_EQ(c.auth.unauthenticated, 1);
  EXPECT_EQ(c.auth.replayed, 1);
  EXPECT_EQ(c.auth.bad_tag, 1);
  EXPECT_EQ(c.rejected, 3);
  EXPECT_EQ(c.served, 2);
  EXPECT_EQ(c.repeated, 0);  // a replayed state is not the plant asking again
}

// ---------------------------------------------------------------------------------------------
// Plant node

// Answers every state on STATE with a command built by `reply` (a stand-in controller).
struct FakeController {
  lcm::LCM* lcm;
  std::function<void(const plant_state_t&, control_command_t&)> reply;
  int answered = 0;
  ChannelAuth* seal = nullptr;  ///< seals its commands with this, when given
  void on(const lcm::ReceiveBuffer* rbuf, const std::string&) {
    plant_state_t s{};
    ASSERT_GE(s.decode(rbuf->data, 0, static_cast<int>(rbuf->data_size)), 0);
    control_command_t c{};
    c.run_id = s.run_id;
    c.state_sequence = s.sequence;
    c.dimension = s.dimension;
    reply(s, c);
    const auto size = static_cast<std::size_t>(c.getEncodedSize());
    std::vector<std::uint8_t> b(size + kTrailerBytes);
    c.encode(b.data(), 0, static_cast<int>(size));
    b.resize(seal ? static_cast<std::size_t>(seal->seal(b.data(), size, b.size())) : size);
    lcm->publish("CMD", b.data(), static_cast<unsigned>(b.size()));
    ++answered;
  }
};

struct PlantFixture : ::testing::Test {
  lcm::LCM lcm{"memq://"};
  Outbox states{lcm, "STATE", nullptr, false};
  FakeController fake{&lcm, {}};
  void SetUp() override {
    ASSERT_TRUE(lcm.good());
    lcm.subscribe("STATE", &FakeController::on, &fake);
  }
  static PlantNodeOptions options(bool lockstep) {
    PlantNodeOptions o;
    o.lockstep = lockstep;
    o.rate_hz = 200;
    o.timeout_ms = 200;
    // Real time: the answers act a fixed period after their states. Measured (the default), the
    // lag grows when the machine stalls the test for a period or more between a state and its
    // answer, and the periods' expected answers with it.
    o.hold_lag = 1;
    o.watchdog_ms = 2000;
    o.run_id = 4242;
    o.periods = 64;
    return o;
  }
};

TEST_F(PlantFixture, LockstepAppliesTheAnswerAndZeroForAFailedSolve) {
  PlantNode node(lcm, states, "CMD", 2, options(true));
  fake.reply = [](const plant_state_t& s, control_command_t& c) {
    c.force[0] = 1.0 + static_cast<double>(s.sequence);
    c.force[1] = -2.0;
    if (s.sequence == 1) c.status = 3;  // failed: its force must not be applied (nor an older one)
  };
  const std::array<double, 2> q{0.1, 0.2}, qd{0, 0};
  std::array<double, 2> u{};
  ASSERT_TRUE(node.exchange(0, 0.0, q, qd, u));
  EXPECT_EQ(u[0], 1.0);
  EXPECT_EQ(u[1], -2.0);
  ASSERT_TRUE(node.exchange(1, 0.005, q, qd, u));
  EXPECT_EQ(u[0], 0.0);
  EXPECT_EQ(u[1], 0.0);
  ASSERT_TRUE(node.exchange(2, 0.010, q, qd, u));
  EXPECT_EQ(u[0], 3.0);
  EXPECT_EQ(node.counts().commands_applied, 3);
  EXPECT_EQ(node.counts().commands_failed, 1);
}

// A plant driven through its own actuators (plant.actuators) holds the force, then u: a command
// must carry one control per actuator (a failed one none, and zero is held).
TEST_F(PlantFixture, ActuatedPlantHoldsTheControlAfterTheForce) {
  PlantNodeOptions o = options(true);
  o.actuators = 1;
  PlantNode node(lcm, states, "CMD", 2, o);
  int replies = 0;
  fake.reply = [&](const plant_state_t& s, control_command_t& c) {
    ++replies;
    c.force[0] = 1.0, c.force[1] = -2.0;
    c.actuators = (s.sequence == 1 && replies == 2) ? 0 : 1;  // state 1's first answer lacks u
    c.control[0] = 7.0 + static_cast<double>(s.sequence);
    if (s.sequence == 2) c.status = 3, c.actuators = 0;
  };
  const std::array<double, 2> q{0.1, 0.2}, qd{0, 0};
  std::array<double, 3> u{};
  ASSERT_TRUE(node.exchange(0, 0.0, q, qd, u));
  EXPECT_EQ(u, (std::array<double, 3>{1.0, -2.0, 7.0}));
  ASSERT_TRUE(node.exchange(1, 0.005, q, qd, u));  // the resent state's answer carries u
  EXPECT_EQ(u, (std::array<double, 3>{1.0, -2.0, 8.0}));
  EXPECT_EQ(node.counts().wrong_dimension, 1);
  ASSERT_TRUE(node.exchange(2, 0.010, q, qd, u));
  EXPECT_EQ(u, (std::array<double, 3>{0.0, 0.0, 0.0}));
  EXPECT_EQ(node.counts().commands_failed, 1);
  // A command span without room for the control stops the run.
  std::array<double, 2> force_only{};
  EXPECT_FALSE(node.exchange(3, 0.015, q, qd, force_only));
  // Force and control share the message's 32 entries.
  o.actuators = 13;
  EXPECT_THROW(PlantNode(lcm, states, "CMD2", 20, o), std::invalid_argument);
}

// The hold's delay each state reports (what the controller's sampled-data hold predicts over):
// none in lock-step; in real time none for the first state (its answer is awaited), then the
// period (an answer acts from the next period), as measured from the applied commands.
TEST_F(PlantFixture, StatesReportTheDelayWithWhichAnswersAreApplied) {
  for (bool lockstep : {true, false}) {
    PlantNode node(lcm, states, "CMD", 2, options(lockstep));
    std::vector<std::int64_t> delays;
    fake.reply = [&](const plant_state_t& s, control_command_t& c) {
      delays.push_back(s.hold_delay_ns);
      c.force[0] = 1.0;
    };
    const std::array<double, 2> q{0, 0}, qd{0, 0};
    std::array<double, 2> u{};
    for (int k = 0; k < 4; ++k) ASSERT_TRUE(node.exchange(k, 0.005 * k, q, qd, u));
    const std::int64_t period = lockstep ? 0 : 5'000'000;  // 200 Hz
    // In real time the last state's answer comes after the loop.
    ASSERT_GE(delays.size(), 3u);
    for (std::size_t k = 0; k < delays.size(); ++k)
      EXPECT_EQ(delays[k], k == 0 ? 0 : period)
          << (lockstep ? "lock-step" : "real time") << ", state " << k;
  }
}

// In real time the answer to state k acts from period k + L, L one more than the 75th percentile
// of the round trips in whole periods (HoldLag). With round trips of 2.5 periods each answer waits
// in the plant for period k + 3 and each state reports 3 periods as its hold delay; an answer
// that comes after its period is counted late and applied in the next one, and that one round
// trip of 3.5 periods does not move L. (50 Hz: the test's own scheduling has 10 ms of margin.)
TEST(PlantHoldLag, AnswersActAFixedLagAfterTheirStates) {
  lcm::LCM lcm{"memq://"};
  ASSERT_TRUE(lcm.good());
  Outbox states{lcm, "STATE", nullptr, false};
  struct Delays {
    std::vector<std::int64_t> of_state;
    void on(const lcm::ReceiveBuffer* rbuf, const std::string&) {
      plant_state_t s{};
      ASSERT_GE(s.decode(rbuf->data, 0, static_cast<int>(rbuf->data_size)), 0);
      of_state.resize(std::max(of_state.size(), static_cast<std::size_t>(s.sequence) + 1), -1);
      of_state[static_cast<std::size_t>(s.sequence)] = s.hold_delay_ns;
    }
  } delays;
  lcm.subscribe("STATE", &Delays::on, &delays);
  PlantNodeOptions o;
  o.rate_hz = 50;
  o.timeout_ms = 1;  // the first state goes unanswered
  o.watchdog_ms = 1000;
  o.run_id = 4242;
  o.periods = 64;
  PlantNode node(lcm, states, "CMD", 2, o);
  constexpr std::int64_t kPeriod = 20'000'000;
  auto answer = [&](std::int64_t k, std::int64_t received_ns) {
    control_command_t c{};
    c.run_id = 4242;
    c.state_sequence = k;
    c.dimension = 2;
    c.force[0] = static_cast<double>(k);
    std::vector<std::uint8_t> b(static_cast<std::size_t>(c.getEncodedSize()));
    c.encode(b.data(), 0, static_cast<int>(b.size()));
    node.handle_command(b.data(), b.size(), received_ns);
  };
  // States 30 to 33 get no answer in time; the answer to 30 comes after period 33 started.
  const std::array<double, 2> q{0, 0}, qd{0, 0};
  std::array<double, 2> u{};
  std::vector<double> applied;
  for (int p = 0; p < 40; ++p) {
    ASSERT_TRUE(node.exchange(p, 0.02 * p, q, qd, u));
    applied.push_back(u[0]);
    const std::int64_t now = wall_us() * 1000;  // the state went out just before
    if (p >= 1 && (p < 30 || p > 33)) answer(p, now + 5 * kPeriod / 2);
    if (p == 33) answer(30, now + kPeriod / 2);
  }
  // Period 1 knew no round trip yet (L = 1; state 0 went unanswered); from period 2 on L = 3.
  for (int p = 0; p < 4; ++p)
    EXPECT_EQ(applied[static_cast<std::size_t>(p)], 0.0) << "period " << p;
  for (int p = 4; p < 33; ++p)
    EXPECT_EQ(applied[static_cast<std::size_t>(p)], p - 3) << "period " << p;
  EXPECT_EQ(applied[33], 29.0);  // the answer due (30) had not come
  for (int p = 34; p < 37; ++p)
    EXPECT_EQ(applied[static_cast<std::size_t>(p)], 30.0) << "period " << p;
  for (int p = 37; p < 40; ++p)
    EXPECT_EQ(applied[static_cast<std::size_t>(p)], p - 3) << "period " << p;
  EXPECT_EQ(node.counts().commands_late, 1);
  EXPECT_EQ(node.counts().commands_applied, 29 + 1 + 3);
  ASSERT_GE(delays.of_state.size(), 38u);
  EXPECT_EQ(delays.of_state[0], 0);
  EXPECT_EQ(delays.of_state[1], kPeriod);
  for (std::size_t k = 2; k < delays.of_state.size(); ++k)
    EXPECT_EQ(delays.of_state[k], 3 * kPeriod) << "state " << k;
  EXPECT_EQ(node.hold_lag_periods().max(), 3.0);
  // Each period's held answer: on time while period - state == lag.
  const auto& held = node.applied_states().values();
  ASSERT_EQ(held.size(), 40u);
  EXPECT_EQ(held[32], 29.0);
  EXPECT_EQ(held[33], 29.0);  // 4 periods old: the answer due was missing
  EXPECT_EQ(held[34], 30.0);
  EXPECT_EQ(held[39], 36.0);
}

// The run's warnings over LCM are the held answers': each period counts the warnings of the
// answer it held, a failed answer counts as failed, and both leave rows unmet.
TEST_F(PlantFixture, EachPeriodTalliesTheWarningsOfTheAnswerItHeld) {
  for (bool lockstep : {true, false}) {
    PlantNode node(lcm, states, "CMD", 2, options(lockstep));
    fake.reply = [](const plant_state_t& s, control_command_t& c) {
      c.force[0] = 1.0;
      c.warnings = static_cast<std::int32_t>(s.sequence == 1 ? warning::kConstraintsNotMet |
                                                                   warning::kRankDeficient
                                                             : warning::kSaturated);
      if (s.sequence == 3) c.status = 3, c.warnings = 0;
    };
    const std::array<double, 2> q{0, 0}, qd{0, 0};
    std::array<double, 2> u{};
    for (int k = 0; k < 5; ++k) ASSERT_TRUE(node.exchange(k, 0.005 * k, q, qd, u));
    // Lock-step holds the answers to states 0..4 in periods 0..4; real time the answer to state 0
    // in periods 0 (awaited) and 1 (still held), and to state k - 1 in period k from then on.
    const WarningTally& w = node.counts().warnings;
    const char* mode = lockstep ? "lock-step" : "real time";
    EXPECT_EQ(w.calls, 5u) << mode;
    EXPECT_EQ(w.by_kind[1], 1u) << mode;  // constraints not met: state 1
    EXPECT_EQ(w.by_kind[0], 1u) << mode;  // rank deficient: state 1
    EXPECT_EQ(w.by_kind[5], 3u)
        << mode;  // saturated: states 0, 2, 4 (lock-step); 0 twice, 2 (real time)
    EXPECT_EQ(w.failed, 1u) << mode;  // state 3
    EXPECT_EQ(w.rows_not_met, 2u) << mode;
  }
}

TEST_F(PlantFixture, CommandsOfAnotherRunAreRefused) {
  PlantNode node(lcm, states, "CMD", 2, options(true));
  fake.reply = [](const plant_state_t&, control_command_t& c) {
    c.run_id = 1;  // a previous plant's run
    c.force[0] = 7.0;
  };
  const std::array<double, 2> q{0, 0}, qd{0, 0};
  std::array<double, 2> u{};
  EXPECT_FALSE(node.exchange(0, 0.0, q, qd, u));  // lock-step: nothing valid within the timeout
  // Each sending of the state (the first, and one resend after 100 ms) drew a refused answer.
  EXPECT_GE(node.counts().states_resent, 1);
  EXPECT_EQ(node.counts().other_run, node.counts().states_resent + 1);
  EXPECT_EQ(node.counts().commands_missing, 1);
  EXPECT_EQ(u[0], 0.0);
}

TEST_F(PlantFixture, RealTimeHoldsTheNewestAnswerAndNeverAFailedOnesPredecessor) {
  PlantNode node(lcm, states, "CMD", 2, options(false));
  fake.reply = [](const plant_state_t& s, control_command_t& c) {
    c.force[0] = 10.0 + static_cast<double>(s.sequence);
    if (s.sequence == 2) c.status = 1;
  };
  const std::array<double, 2> q{0, 0}, qd{0, 0};
  std::vector<double> applied;
  for (int k = 0; k < 5; ++k) {
    std::array<double, 2> u{};
    ASSERT_TRUE(node.exchange(k, 0.005 * k, q, qd, u));
    applied.push_back(u[0]);
  }
  // Period 0 waits for the answer to state 0 and applies it; period 1 has no new answer and holds
  // it; period k > 1 applies the answer to state k - 1; state 2's answer failed, so period 3
  // applies zero, not state 1's force.
  EXPECT_EQ(applied, (std::vector<double>{10.0, 10.0, 11.0, 0.0, 13.0}));
  EXPECT_EQ(node.counts().commands_missing, 1);
  EXPECT_EQ(node.counts().commands_failed, 1);
  EXPECT_EQ(node.counts().states_published, 5);
}

// A flood (more than kFloodPerPeriod datagrams in a period) switches the loop to taking messages
// as they come until shortly before its deadline; a quiet period switches it back. The answers
// are applied as without the flood, and every flooding datagram is refused.
TEST_F(PlantFixture, AFloodIsTakenBeforeTheDeadlineAndTheAnswersStillApply) {
  PlantNode node(lcm, states, "CMD", 2, options(false));
  fake.reply = [](const plant_state_t& s, control_command_t& c) { c.force[0] = 10.0 + static_cast<double>(s.sequence); };
  const std::array<double, 2> q{0, 0}, qd{0, 0};
  const std::vector<std::uint8_t> garbage(64, 0xab);
  std::vector<double> applied;
  std::vector<bool> flooded;
  for (int k = 0; k < 6; ++k) {
    if (k == 2)
      for (int i = 0; i < 20; ++i) lcm.publish("CMD", garbage.data(), static_cast<unsigned>(garbage.size()));
    std::array<double, 2> u{};
    ASSERT_TRUE(node.exchange(k, 0.005 * k, q, qd, u));
    applied.push_back(u[0]);
    flooded.push_back(node.flooded());
  }
  EXPECT_EQ(applied, (std::vector<double>{10.0, 10.0, 11.0, 12.0, 13.0, 14.0}));
  EXPECT_EQ(flooded, (std::vector<bool>{false, false, true, false, false, false}));
  EXPECT_EQ(node.counts().rejected, 20);
  EXPECT_EQ(node.counts().commands_missing, 1);
}

TEST_F(PlantFixture, RealTimeWatchdogAppliesTheSafeActionThenRecovers) {
  PlantNodeOptions o = options(false);
  o.watchdog_ms = 20;
  PlantNode node(lcm, states, "CMD", 1, o);
  bool answering = true;
  fake.reply = [&](const plant_state_t&, control_command_t& c) {
    c.force[0] = answering ? 5.0 : kNaN;
  };
  const std::array<double, 1> q{0}, qd{0};
  std::array<double, 1> u{};
  int k = 0;
  for (; k < 3; ++k) ASSERT_TRUE(node.exchange(k, 0, q, qd, u));
  EXPECT_EQ(u[0], 5.0);
  answering = false;  // NaN forces are refused: as if the controller were silent
  // Periods of 5 ms go by until the 20 ms watchdog trips (however late the wake-ups).
  const int silent_from = k;
  for (; !node.watchdog().tripped() && k < silent_from + 400; ++k)
    ASSERT_TRUE(node.exchange(k, 0, q, qd, u));
  EXPECT_GE(k - silent_from, 4);
  EXPECT_EQ(node.watchdog().trips(), 1);
  EXPECT_EQ(u[0], 0.0);
  answering = true;
  for (int j = 0; j < 3; ++j, ++k) ASSERT_TRUE(node.exchange(k, 0, q, qd, u));
  EXPECT_EQ(u[0], 5.0);
  EXPECT_FALSE(node.watchdog().tripped());
  EXPECT_EQ(node.counts().commands_applied + node.counts().commands_missing, k);
}

// A rogue process answers every state first, without the key or with a key of its own: nothing of
// it is applied, the paired controller's answers are.
TEST_F(PlantFixture, WithAKeyARogueAnswerFirstIsRefusedAndThePairedControllersApplied) {
  const MessageKey key(std::array<std::uint8_t, kKeyBytes>{4, 2}),
      own(std::array<std::uint8_t, kKeyBytes>{6});
  ChannelAuth open_commands(key, "CMD"), controller(key, "CMD"), forger(own, "CMD");
  PlantNode node(lcm, states, "CMD", 2, options(true));
  node.authenticate(open_commands);
  fake.reply = [](const plant_state_t&, control_command_t& c) {
    c.force[0] = 50.0, c.sequence = 1'000'000'000;
  };
  FakeController forged{&lcm, fake.reply, 0, &forger};
  FakeController paired{&lcm,
                        [](const plant_state_t& s, control_command_t& c) {
                          c.force[0] = 1.0 + static_cast<double>(s.sequence);
                        },
                        0, &controller};
  lcm.subscribe("STATE", &FakeController::on, &forged);
  lcm.subscribe("STATE", &FakeController::on, &paired);
  const std::array<double, 2> q{0, 0}, qd{0, 0};
  std::array<double, 2> u{};
  for (int k = 0; k < 3; ++k) {
    ASSERT_TRUE(node.exchange(k, 0.005 * k, q, qd, u));
    EXPECT_EQ(u[0], 1.0 + k);
  }
  EXPECT_EQ(node.counts().commands_applied, 3);
  EXPECT_EQ(node.counts().auth.unauthenticated, 3);
  EXPECT_EQ(node.counts().auth.bad_tag, 3);
  EXPECT_EQ(node.counts().rejected, 6);
}

// The pair does not share a key: the plant ends the run at the timeout and says why.
TEST_F(PlantFixture, WithAKeyAndOnlyUnverifiedAnswersTheRunEnds) {
  const MessageKey key(std::array<std::uint8_t, kKeyBytes>{4, 2});
  ChannelAuth open_commands(key, "CMD");
  fake.reply = [](const plant_state_t&, control_command_t& c) { c.force[0] = 50.0; };
  for (bool lockstep : {true, false}) {
    PlantNode node(lcm, states, "CMD", 2, options(lockstep));
    node.authenticate(open_commands);
    const std::array<double, 2> q{0, 0}, qd{0, 0};
    std::array<double, 2> u{};
    int k = 0;
    while (k < 400 && node.exchange(k, 0.005 * k, q, qd, u)) ++k;
    EXPECT_LT(k, 400) << lockstep;
    EXPECT_EQ(u[0], 0.0);
    EXPECT_EQ(node.counts().commands_applied, 0);
    EXPECT_GE(node.counts().auth.unauthenticated, 1);
  }
}

// The hold lag is one more than the 75th percentile of the last 256 round trips in whole
// periods, 1 before any, at most 1 s: a stall's burst of long round trips does not move it.
TEST(HoldLag, FollowsTheRoundTripsPercentileNotItsOutliers) {
  constexpr std::int64_t kPeriod = 1'000'000;
  HoldLag lag(kPeriod);
  EXPECT_EQ(lag.lag(), 1);
  for (int i = 0; i < 100; ++i) lag.record(kPeriod * 3 / 10);
  EXPECT_EQ(lag.lag(), 1);
  for (int i = 0; i < 20; ++i) lag.record(10 * kPeriod);  // a stall's burst: 20 of 121 round trips
  lag.record(-5);                                         // clocks that disagree count as no delay
  EXPECT_EQ(lag.lag(), 1);
  for (int i = 0; i < 200; ++i) lag.record(kPeriod * 22 / 10);
  EXPECT_EQ(lag.lag(), 3);  // the window: 35 under a period, 20 of 10, 1 negative, 200 of 2.2
  for (int i = 0; i < 70; ++i) lag.record(kPeriod * 5);
  EXPECT_EQ(lag.lag(), 6);    // now 70 of 256 above 2.2 periods: more than the 25 % allowed
  HoldLag slow(100'000'000);  // 10 Hz
  slow.record(5'000'000'000);
  EXPECT_EQ(slow.lag(), 10);  // 1 s
}

TEST(HoldLag, AFixedLagIgnoresTheRoundTrips) {
  constexpr std::int64_t kPeriod = 1'000'000;
  HoldLag fixed(kPeriod, 2);
  EXPECT_EQ(fixed.lag(), 2);
  for (int i = 0; i < 300; ++i) fixed.record(7 * kPeriod);
  EXPECT_EQ(fixed.lag(), 2);
  PlantNodeOptions o;
  o.hold_lag = HoldLag::kMaxLag + 1;
  lcm::LCM lcm{"memq://"};
  Outbox states{lcm, "STATE", nullptr, false};
  EXPECT_THROW(PlantNode(lcm, states, "CMD", 2, o), std::invalid_argument);
}

TEST(PlantNode, ASpinIsShorterThanThePeriod) {
  lcm::LCM lcm{"memq://"};
  Outbox states{lcm, "STATE", nullptr, false};
  PlantNodeOptions o;
  o.rate_hz = 1000;
  for (int spin_us : {-1, 1000, 5000}) {
    o.spin_us = spin_us;
    EXPECT_THROW(PlantNode(lcm, states, "CMD", 2, o), std::invalid_argument) << spin_us;
  }
  o.spin_us = 999;
  PlantNode node(lcm, states, "CMD", 2, o);
  EXPECT_EQ(node.scheduler().sleep_until(4), node.scheduler().deadline(4) - 999'000);
}

TEST(Watchdog, TripsOncePerOutageAndClearsOnACommand) {
  Watchdog w(20'000'000, 0);
  EXPECT_FALSE(w.check(19'000'000));
  EXPECT_FALSE(w.check(20'000'000));
  EXPECT_TRUE(w.check(20'000'001));
  EXPECT_TRUE(w.check(90'000'000));
  EXPECT_EQ(w.trips(), 1);
  w.feed(100'000'000);
  EXPECT_FALSE(w.check(110'000'000));
  EXPECT_TRUE(w.check(130'000'000));
  EXPECT_EQ(w.trips(), 2);
}

TEST(PeriodScheduler, DeadlinesAreAbsoluteAndLateWakeUpsAreMisses) {
  PeriodScheduler s(1'000'000, 5'000'000, 16);
  EXPECT_EQ(s.deadline(0), 5'000'000);
  EXPECT_EQ(s.deadline(7), 12'000'000);
  s.record_wake(0, 5'000'100);  // on time
  s.record_wake(1, 6'499'999);  // just under half a period late
  s.record_wake(2, 7'500'001);  // a miss
  s.record_wake(3, 8'000'000);  // the next deadline is not shifted by the miss
  EXPECT_EQ(s.misses(), 1);
  EXPECT_EQ(s.deadline(3), 8'000'000);
  // A real wait wakes at or after its deadline.
  PeriodScheduler real(2'000'000, monotonic_ns(), 4);
  for (int k = 1; k <= 3; ++k) EXPECT_GE(real.wait_for(k), real.deadline(k));
  EXPECT_EQ(real.sleep_until(2), real.deadline(2));
}

// Thread CPU time [ns].
std::int64_t thread_cpu_ns() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<std::int64_t>(t.tv_sec) * 1000000000LL + t.tv_nsec;
}

TEST(PeriodScheduler, ASpinSleepsUntilThatLongBeforeTheDeadlineThenReadsTheClockUntilIt) {
  constexpr std::int64_t kPeriod = 2'000'000, kSpin = 1'500'000;
  PeriodScheduler spinning(kPeriod, monotonic_ns(), 12, kSpin);
  EXPECT_EQ(spinning.sleep_until(3), spinning.deadline(3) - kSpin);
  // Woken 1.5 ms early, it still never returns before a deadline...
  const std::int64_t cpu_before = thread_cpu_ns();
  for (int k = 1; k <= 10; ++k) EXPECT_GE(spinning.wait_for(k), spinning.deadline(k));
  // ... because it spent the time on a CPU: up to 15 ms over the 10 periods, against microseconds
  // asleep. Bounded far below 15 ms, so that a loaded machine that takes the CPU away from the
  // spin most of the time does not fail it; a wait that only slept spends about 0.1 ms.
  const std::int64_t cpu = thread_cpu_ns() - cpu_before;
  EXPECT_GT(cpu, 1'000'000);
  // What it counts as spun is the time from waking to each deadline: at most the spin per period.
  EXPECT_GT(spinning.spun_ns(), 3'000'000);
  EXPECT_LE(spinning.spun_ns(), 10 * kSpin);
  PeriodScheduler sleeping(kPeriod, monotonic_ns(), 4);
  for (int k = 1; k <= 3; ++k) sleeping.wait_for(k);
  EXPECT_EQ(sleeping.spun_ns(), 0);
  // A deadline already passed: no sleep, no spin, a miss counted.
  PeriodScheduler behind(kPeriod, monotonic_ns() - 10 * kPeriod, 4, kSpin);
  EXPECT_GE(behind.wait_for(1), behind.deadline(1));
  EXPECT_EQ(behind.spun_ns(), 0);
  EXPECT_EQ(behind.misses(), 1);
}

// The real-time setup as the processes run it: apply_realtime, the LCM and its subscription (which
// starts LCM's receive thread, inheriting the policy), then the loop raised one above it. Run in a
// thread of its own so that the test process keeps the default scheduler.
TEST(RealTime, TheLoopRunsOnePriorityAboveLcmsReceiveThread) {
  struct Seen {
    bool permitted = true, lcm_good = false;
    int loop_policy = -1, loop_priority = -1;
    std::vector<int> other_fifo_priorities;
  } seen;
  std::thread setup([&] {
    ProcessOptions o;
    o.rt_priority = 10;
    sched_param probe{};
    probe.sched_priority = o.rt_priority;
    if (sched_setscheduler(0, SCHED_FIFO, &probe) != 0) {
      seen.permitted = false;
      return;
    }
    apply_realtime(o, "nodes_test");
    lcm::LCM lcm{"udpm://239.255.76.67:7689?ttl=0"};
    seen.lcm_good = lcm.good();
    if (!seen.lcm_good) return;
    struct Probe {
      void on(const lcm::ReceiveBuffer*, const std::string&) {}
    } handler;
    lcm::Subscription* sub = lcm.subscribe("PRIORITY_PROBE", &Probe::on, &handler);
    raise_loop_above_receiver(o, "nodes_test");
    const pid_t self = static_cast<pid_t>(syscall(SYS_gettid));
    sched_param p{};
    seen.loop_policy = sched_getscheduler(0);
    sched_getparam(0, &p);
    seen.loop_priority = p.sched_priority;
    for (const auto& task : std::filesystem::directory_iterator("/proc/self/task")) {
      const pid_t tid = static_cast<pid_t>(std::stol(task.path().filename().string()));
      if (tid == self || sched_getscheduler(tid) != SCHED_FIFO) continue;
      sched_getparam(tid, &p);
      seen.other_fifo_priorities.push_back(p.sched_priority);
    }
    lcm.unsubscribe(sub);
  });
  setup.join();
  if (!seen.permitted) GTEST_SKIP() << "SCHED_FIFO is not permitted here";
  ASSERT_TRUE(seen.lcm_good);
  EXPECT_EQ(seen.loop_policy, SCHED_FIFO);
  EXPECT_EQ(seen.loop_priority, 11);
  // Exactly one other real-time thread, LCM's receiver, one below the loop.
  EXPECT_EQ(seen.other_fifo_priorities, std::vector<int>{10});
}

}  // namespace
}  // namespace gausstrack::nodes

// ControllerNode<Model>: the controller process's work, for any model. Subscribe it to the
// plant's states and let it serve them; for each state it validates, computes the control law and
// publishes the command:
//
//   lcm::LCM lcm;
//   Outbox commands(lcm, "GAUSSTRACK_COMMAND", nullptr, false);
//   ControllerNode<MyModel> node(make_controller<MyModel>(spec), commands);
//   lcm.subscribe("GAUSSTRACK_STATE", &ControllerNode<MyModel>::on_state, &node);
//   while (!g_stop_requested) node.serve(lcm, 100);
//
// Wire contract:
// - With the pair's key (authenticate()), a state whose trailer does not verify (none, another
//   key, altered, or a counter not above the last accepted: replayed) is counted by reason and
//   dropped before anything of it is read; the commands are sealed by the outbox.
// - A state that does not decode, has another dimension or a non-finite value is counted and
//   dropped; so is one of the current plant run whose sequence is older than the last, and one
//   of a run that has ended (a late datagram of a plant that restarted).
// - Only the newest state is answered: serve() takes every state already queued and answers the
//   newest; the older ones are superseded (counted, not answered). A controller that fell behind
//   (the machine stalled it) answers the plant's present state next instead of working through
//   a queue of old ones. (A plant applying answers a lag of L > 1 periods after their states
//   could still have used the answers to the L - 1 states before the newest; it holds its
//   previous answer for those periods.) A state dispatched by other means (on_state outside
//   serve(), handle()) is answered at once.
// - The last state repeated (a plant in lock-step asking again after a lost message) is
//   answered again with the same command, not recomputed; the same state twice before its answer
//   (a duplicated datagram) is answered once.
// - A state with a new run_id is a new plant run (a restarted plant): its sequence starts again
//   and its states are taken like any other (the ended run's waiting state is superseded).
// - Every answered state gets one command: the force, or all zeros with the status of a failed
//   solve, which the plant applies as zero (never the previous force).
// - The force's parts and the solve's figures go to the diagnostics outbox, if one is given.
// The path from receipt to publish allocates nothing.
#pragma once

#include <lcm/lcm-cpp.hpp>

#include <array>
#include <climits>
#include <cstdint>
#include <string>
#include <utility>

#include "gausstrack/actuation.hpp"
#include "gausstrack/model.hpp"
#include "gausstrack/nodes/auth.hpp"
#include "gausstrack/nodes/codec.hpp"
#include "gausstrack/nodes/latency_recorder.hpp"
#include "gausstrack/nodes/message_log.hpp"
#include "gausstrack/nodes/process.hpp"

namespace gausstrack::nodes {

/// What the controller node counted.
struct ControllerCounts {
  long served = 0;    ///< states answered with a command
  long repeated = 0;  ///< repeated states answered again with the same command
  long superseded = 0;  ///< states not answered: a newer one was queued behind them
  long largest_backlog = 0;  ///< the most new states of the plant one serve() found queued (at most
                             ///< kMaxBatch + 1): how far behind the machine held the controller or its link
  long duplicates = 0;  ///< states that came again before their answer (answered once)
  long failed = 0;    ///< commands reporting a failed solve (force zero)
  long rejected = 0;  ///< states refused (any reason below)
  long malformed = 0, wrong_dimension = 0, non_finite = 0, stale = 0;
  AuthCounts auth;  ///< refused by authentication, by reason (also in rejected)
  long runs = 0;    ///< plant runs seen
};

template <Model M>
class ControllerNode {
 public:
  static constexpr int N = M::kDof;
  static_assert(kActuatorsOf<M> <= kMaxDimension, "a command carries at most 32 actuator commands");
  using Controller = LawFor<M>;  ///< ActuatedController for a model with actuators
  using Scalar = typename Controller::Scalar;

  /// `compute_times`: how many compute times to keep for percentiles (later ones are counted
  /// only). `diagnostics`: where to publish each command's diagnostics, or nullptr.
  ControllerNode(Controller controller, Outbox& commands, Outbox* diagnostics = nullptr,
                 std::size_t compute_times = 1 << 16)
      : controller_(std::move(controller)),
        commands_(commands),
        diagnostics_(diagnostics),
        compute_ns_(compute_times) {
    ended_runs_.fill(INT64_MIN);
  }

  /// With a sampled-data hold (the controller's hold period > 0): take the hold's delay from each
  /// state (plant_state_t::hold_delay_ns, what the plant measured), or keep the controller's own
  /// (a configured delay). Default: from the states.
  void use_measured_delay(bool measured) noexcept { measured_delay_ = measured; }

  /// From now on accepts only states that verify with `states` (the state channel's
  /// authentication, which must outlive the node).
  void authenticate(ChannelAuth& states) noexcept { auth_ = &states; }

  /// LCM subscription handler: inside serve() it takes the state for serve() to answer, outside
  /// it answers the state at once (handle()).
  void on_state(const lcm::ReceiveBuffer* rbuf, const std::string&) noexcept {
    if (serving_) receive(rbuf->data, rbuf->data_size);
    else handle(rbuf->data, rbuf->data_size);
  }

  /// Waits up to `timeout_ms` for a message on `lcm`, takes every message already queued behind
  /// it (at most kMaxBatch) and answers the newest state among them. Returns what
  /// lcm.handleTimeout returned for the first message (< 0: LCM failed).
  int serve(lcm::LCM& lcm, int timeout_ms) noexcept {
    serving_ = true;
    batch_ = 0;
    const int first = lcm.handleTimeout(timeout_ms);
    for (int i = 0; first > 0 && i < kMaxBatch && lcm.handleTimeout(0) > 0; ++i) {
    }
    serving_ = false;
    if (batch_ > counts_.largest_backlog) counts_.largest_backlog = batch_;
    answer();
    return first;
  }

  /// Validates one encoded plant state and, if it is served, publishes the command.
  void handle(const void* data, std::size_t size) noexcept {
    receive(data, size);
    answer();
  }

  /// Validates one encoded plant state and keeps it as the one to answer (a newer state replaces
  /// it). A repeat of the last answered state is answered again at once.
  void receive(const void* data, std::size_t size) noexcept {
    if (!admit(auth_, data, size, counts_.auth)) {
      ++counts_.rejected;
      return;
    }
    // Read into the other slot: a state refused on the way leaves the kept one intact.
    Slot& in = slots_[1 - kept_];
    const Refusal r = codec_.decode_state(data, size, in.msg, in.q, in.qd);
    if (r != Refusal::kNone)
      return refuse(r == Refusal::kMalformed   ? counts_.malformed
                    : r == Refusal::kDimension ? counts_.wrong_dimension
                                               : counts_.non_finite);
    if (in.msg.sequence < 0) return refuse(counts_.stale);
    if (in.msg.run_id != run_id_ || counts_.runs == 0) {
      for (std::int64_t ended : ended_runs_)
        if (ended == in.msg.run_id) return refuse(counts_.stale);
      if (counts_.runs > 0)
        ended_runs_[static_cast<std::size_t>(counts_.runs) % ended_runs_.size()] = run_id_;
      run_id_ = in.msg.run_id;
      last_sequence_ = -1;
      ++counts_.runs;
      if (pending_) ++counts_.superseded;  // the ended run's state, never answered
      pending_ = false;
    }
    if (in.msg.sequence == last_sequence_) {
      if (pending_) {  // the same state again, not yet answered: answered once
        ++counts_.duplicates;
        return;
      }
      if (last_bytes_ > 0) {
        ++counts_.repeated;
        commands_.publish(last_command_.data(), static_cast<std::size_t>(last_bytes_), wall_us());
        return;
      }
    }
    if (in.msg.sequence < last_sequence_) return refuse(counts_.stale);
    if (pending_) ++counts_.superseded;
    last_sequence_ = in.msg.sequence;
    kept_ = 1 - kept_;
    pending_ = true;
    if (serving_) ++batch_;
  }

  const ControllerCounts& counts() const noexcept { return counts_; }
  const LatencyRecorder& compute_ns() const noexcept { return compute_ns_; }
  Controller& controller() noexcept { return controller_; }

  /// The most messages one serve() takes off the queue behind the first.
  static constexpr int kMaxBatch = 64;

  /// Computes and publishes the command for the state receive() kept, if one waits.
  void answer() noexcept {
    if (!pending_) return;
    pending_ = false;
    const Slot& kept = slots_[kept_];
    if (measured_delay_ && controller_.hold().period > 0) {
      // The hold's delay as the plant measured it: the law is evaluated for when its force acts.
      Hold<Scalar> hold = controller_.hold();
      hold.delay = static_cast<Scalar>(static_cast<double>(kept.msg.hold_delay_ns) * 1e-9);
      controller_.set_hold(hold);
    }
    const std::int64_t start = monotonic_ns();
    const Status status = controller_.compute(kept.q, kept.qd, kept.msg.t, out_);
    const std::int64_t compute_ns = monotonic_ns() - start;
    compute_ns_.add(static_cast<double>(compute_ns));
    if (failed(status)) ++counts_.failed;

    command_.utime = wall_us();
    command_.sequence = ++counts_.served;
    command_.run_id = kept.msg.run_id;
    command_.state_sequence = kept.msg.sequence;
    command_.status = static_cast<std::int32_t>(status);
    command_.warnings = static_cast<std::int32_t>(out_.diagnostics.warnings);
    command_.compute_ns = compute_ns;
    // An actuated law's command carries its actuator commands u beside the force B u.
    if constexpr (requires { out_.control; })
      last_bytes_ = codec_.encode_command(command_, out_.force, out_.control, last_command_.data(),
                                          last_command_.size());
    else
      last_bytes_ =
          codec_.encode_command(command_, out_.force, last_command_.data(), last_command_.size());
    if (last_bytes_ > 0)
      commands_.publish(last_command_.data(), static_cast<std::size_t>(last_bytes_),
                        command_.utime);

    if (diagnostics_) {
      diag_.utime = command_.utime;
      diag_.run_id = command_.run_id;
      diag_.state_sequence = command_.state_sequence;
      diag_.status = command_.status;
      diag_.warnings = command_.warnings;
      diag_.rank = out_.diagnostics.rank;
      diag_.condition_estimate = out_.diagnostics.condition_estimate;
      diag_.saturation_scale = out_.saturation_scale;
      const int n = codec_.encode_diagnostics(diag_, out_.closed_loop, out_.feedforward,
                                              out_.stabilizing, buffer_.data(), buffer_.size());
      if (n > 0) diagnostics_->publish(buffer_.data(), static_cast<std::size_t>(n), diag_.utime);
    }
  }

 private:
  void refuse(long& reason) noexcept {
    ++reason;
    ++counts_.rejected;
  }

  Controller controller_;
  typename Controller::Output out_;
  Codec<N> codec_;
  Outbox& commands_;
  Outbox* diagnostics_;
  ChannelAuth* auth_ = nullptr;
  struct Slot {
    plant_state_t msg{};
    typename Codec<N>::Vector q, qd;
  };
  std::array<Slot, 2> slots_{};  ///< the state kept to answer (slots_[kept_]) and the one being read
  int kept_ = 0;
  control_command_t command_{};
  control_diagnostics_t diag_{};
  bool pending_ = false;  ///< slots_[kept_] waits for its answer
  bool serving_ = false;  ///< inside serve(): on_state only takes states
  long batch_ = 0;        ///< new states taken in the present serve()
  std::array<std::uint8_t, kMessageBufferBytes> buffer_{}, last_command_{};
  int last_bytes_ = 0;
  bool measured_delay_ = true;
  std::array<std::int64_t, 8> ended_runs_{};  ///< the last runs that ended (INT64_MIN: none)
  std::int64_t run_id_ = 0, last_sequence_ = -1;
  ControllerCounts counts_;
  LatencyRecorder compute_ns_;
};

}  // namespace gausstrack::nodes

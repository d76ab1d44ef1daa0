// The plant process's work, for any plant: anything that advances a state over one control
// period under a held force calls PlantNode::exchange once at the start of each period (the
// offline simulation's sampled_control, a physics engine's loop, a user's own loop). exchange
// publishes the state and returns the force to hold:
// - Lock-step: waits for the command answering that state (deterministic; for tests and studies),
//   publishing the state again every 100 ms meanwhile, so that one lost datagram costs a resend,
//   not the run.
// - Real time: periods start on absolute deadlines (PeriodScheduler); past the first state the
//   plant never waits for a command. The first state's answer is awaited as in lock-step (up to
//   the timeout) and the clock starts when it comes, so that a run does not begin with a period
//   of no force. The loop wakes once per period, at its deadline, or spin_us before it and then
//   reads the clock until it (a timed wait per incoming message would add a timer's wake-up to
//   every period); it takes the messages that have arrived then, and before sleeping again those
//   that came since, as far as time allows. Under a flood
//   (more than kFloodPerPeriod messages in the last period) it instead takes messages as they
//   come until a quarter period before the deadline, so that the work after the wake stays short. Round trips are
//   measured from the state's publication to the kernel's receive timestamp of the command
//   (LCM's recv_utime), so when a command is taken off the queue changes no figure. The command
//   answering state k acts from period k + L (zero-order hold), L the hold lag (HoldLag: one more
//   than the 75th percentile of recent round trips in whole periods; 1 while they are shorter
//   than a period; or fixed by PlantNodeOptions::hold_lag). Each state reports L periods as its
//   hold_delay_ns, so the controller knows the interval its answer acts on. An answer that comes
//   before its period waits for it; at each period the plant applies the answer due, or when it
//   has not come the newest one older than it (counted late); when none has come for longer than
//   the watchdog time it applies the safe action (zero force, or hold the last one) until
//   commands return.
// A command reporting a failed solve is applied as zero force and counted, never ignored in
// favour of an older force. Commands for another run (a previous plant process) are refused.
// With the pair's key (authenticate()), a command whose trailer does not verify is counted by
// reason and dropped before anything of it is read; the states are sealed by their outbox. A run
// in which no command has verified within the timeout (--timeout-ms, from the start) ends, saying
// why: the controller is missing or holds another key (it then refuses this plant's states). Each
// period takes at most kMaxPerPeriod messages off the socket before it applies its command, so a
// flood cannot hold the period back.
#pragma once

#include <lcm/lcm-cpp.hpp>
#include <nlohmann/json_fwd.hpp>
#include <poll.h>
#include <sys/prctl.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <cstdint>
#include <random>
#include <span>
#include <string>

#include "gausstrack/loop_stats_t.hpp"
#include "gausstrack/nodes/auth.hpp"
#include "gausstrack/nodes/codec.hpp"
#include "gausstrack/nodes/latency_recorder.hpp"
#include "gausstrack/nodes/message_log.hpp"
#include "gausstrack/nodes/process.hpp"
#include "gausstrack/status.hpp"

namespace gausstrack::nodes {

/// The period a rate gives the plant's scheduler, to the nearest nanosecond.
inline std::int64_t period_ns_at(double rate_hz) noexcept { return std::llround(1e9 / rate_hz); }
/// Whether a spin of spin_us fits a period: at least 0 and shorter than it, compared in integer
/// nanoseconds (the node and the programs that refuse a spin before making one decide alike).
inline bool spin_fits_period(int spin_us, std::int64_t period_ns) noexcept {
  return spin_us >= 0 && std::int64_t{spin_us} * 1000 < period_ns;
}

/// Absolute deadlines start + k * period on CLOCK_MONOTONIC: a late wake-up does not shift the
/// deadlines after it. Counts a wake-up later than half a period as a deadline miss.
/// Constructing one sets the calling thread's timer slack to 1 ns (PR_SET_TIMERSLACK): under the
/// default scheduler Linux may otherwise defer every timed wake-up by up to 50 us, which alone
/// misses most periods at 10 kHz. (SCHED_FIFO threads have no slack.)
/// With a spin (spin_ns > 0) the thread sleeps until spin_ns before each deadline and reads the
/// clock until the deadline: a thread already running when its deadline comes does not wait for
/// the scheduler to wake it and give it a CPU, which on a stock kernel (and more so on a virtual
/// CPU that has gone idle) takes tens of us. The price is up to spin_ns of one CPU per period.
class PeriodScheduler {
 public:
  PeriodScheduler(std::int64_t period_ns, std::int64_t start_ns, std::size_t periods, std::int64_t spin_ns = 0)
      : period_ns_(period_ns), spin_ns_(spin_ns), start_ns_(start_ns), wake_late_us_(periods) {
    prctl(PR_SET_TIMERSLACK, 1UL, 0UL, 0UL, 0UL);
  }

  /// Deadline k is start_ns + k * period from now on.
  void restart(std::int64_t start_ns) noexcept { start_ns_ = start_ns; }
  std::int64_t period_ns() const noexcept { return period_ns_; }
  std::int64_t deadline(std::int64_t k) const noexcept { return start_ns_ + period_ns_ * k; }

  /// When the wait for period k stops sleeping: spin_ns before its deadline.
  std::int64_t sleep_until(std::int64_t k) const noexcept { return deadline(k) - spin_ns_; }

  /// Waits until period k's deadline (at once if it has passed): sleeps, then spins the last
  /// spin_ns; records how late it woke and returns the time of waking, never before the deadline.
  std::int64_t wait_for(std::int64_t k) noexcept {
    const std::int64_t due = deadline(k);
    const timespec wake = to_timespec(sleep_until(k));
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &wake, nullptr) == EINTR) {
    }
    std::int64_t now = monotonic_ns();
    if (now < due) spun_ns_ += due - now;
    while (now < due) now = monotonic_ns();
    record_wake(k, now);
    return now;
  }
  /// Records a wake-up for period k at `now` (wait_for calls it; tests call it with any time).
  void record_wake(std::int64_t k, std::int64_t now) noexcept {
    const std::int64_t late = now - deadline(k);
    wake_late_us_.add(static_cast<double>(late) * 1e-3);
    if (late > period_ns_ / 2) ++misses_;
  }
  long misses() const noexcept { return misses_; }
  /// The time wait_for has spent spinning since construction, from waking to each deadline [ns]:
  /// the spin's price in wall time (its CPU time is at most this).
  std::int64_t spun_ns() const noexcept { return spun_ns_; }
  const LatencyRecorder& wake_late_us() const noexcept { return wake_late_us_; }

 private:
  std::int64_t period_ns_, spin_ns_, start_ns_;
  std::int64_t spun_ns_ = 0;
  long misses_ = 0;
  LatencyRecorder wake_late_us_;
};

/// Trips when no command has been applied for longer than the timeout, once per outage, and
/// stays tripped until a command is applied again. Time is passed in: it is tested without a clock.
class Watchdog {
 public:
  explicit Watchdog(std::int64_t timeout_ns, std::int64_t start_ns = 0) noexcept
      : timeout_ns_(timeout_ns), last_fed_ns_(start_ns) {}

  void feed(std::int64_t now_ns) noexcept {
    last_fed_ns_ = now_ns;
    tripped_ = false;
  }
  /// True while the safe action applies (counts a trip when it starts).
  bool check(std::int64_t now_ns) noexcept {
    if (!tripped_ && now_ns - last_fed_ns_ > timeout_ns_) {
      tripped_ = true;
      ++trips_;
    }
    return tripped_;
  }
  bool tripped() const noexcept { return tripped_; }
  long trips() const noexcept { return trips_; }

 private:
  std::int64_t timeout_ns_, last_fed_ns_;
  bool tripped_ = false;
  long trips_ = 0;
};

/// The lag, in whole periods, with which a real-time plant applies answers: the command answering
/// the state of period k acts from period k + lag(). The round trips of the last kWindow commands
/// (from their period's deadline) are kept in whole periods; lag() is one more than their 75th
/// percentile: a delay that lasts moves it, while the burst of long round trips a stall of the
/// machine leaves (tens of answers) does not, so the controller does not predict over a stall's
/// length for the next quarter second (answers held back that long are applied late instead).
/// 1 before any round trip is known (an answer acts from the next period); at most kMaxLag
/// periods and at most 1 s.
class HoldLag {
 public:
  static constexpr int kMaxLag = 32;
  static constexpr int kWindow = 256;

  /// fixed > 0: the lag is that many periods whatever the round trips (clamped to kMaxLag).
  explicit HoldLag(std::int64_t period_ns, int fixed = 0) noexcept
      : period_ns_(period_ns), longest_(static_cast<int>(std::clamp<std::int64_t>(
                                   1'000'000'000 / std::max<std::int64_t>(period_ns, 1), 1, kMaxLag))),
        fixed_(std::clamp(fixed, 0, kMaxLag)) {}

  /// A command's round trip, from its state's sending to its receipt [ns].
  void record(std::int64_t round_trip_ns) noexcept {
    const auto bin = static_cast<int>(std::clamp<std::int64_t>(round_trip_ns / period_ns_, 0, kMaxLag - 1));
    if (recorded_ == kWindow) --counts_[static_cast<std::size_t>(window_[next_])];
    else ++recorded_;
    window_[next_] = static_cast<std::uint8_t>(bin);
    ++counts_[static_cast<std::size_t>(bin)];
    next_ = (next_ + 1) % kWindow;
  }
  int lag() const noexcept {
    if (fixed_ > 0) return fixed_;
    if (recorded_ == 0) return 1;
    const int needed = (recorded_ * 3 + 3) / 4;  // ceil(0.75 n)
    int cumulative = 0, bin = 0;
    while (bin < kMaxLag - 1 && (cumulative += counts_[static_cast<std::size_t>(bin)]) < needed) ++bin;
    return std::min(bin + 1, longest_);
  }

 private:
  std::int64_t period_ns_;
  int longest_, fixed_;
  int recorded_ = 0;
  std::size_t next_ = 0;
  std::array<std::uint8_t, kWindow> window_{};
  std::array<int, kMaxLag> counts_{};
};

struct PlantNodeOptions {
  bool lockstep = false;
  double rate_hz = 1000;       ///< control rate
  int timeout_ms = 2000;       ///< lock-step: longest wait for a command
  int watchdog_ms = 50;        ///< real time: safe action after this long without a command
  bool safe_hold = false;      ///< safe action: hold the last force (else zero)
  /// The plant's actuators driven by the command's control (plant.actuators): a command must carry
  /// that many, and the command held is the force followed by them. 0: the force alone.
  int actuators = 0;
  /// Real time: the answer to state k acts from period k + hold_lag, fixed (a loop whose delay does
  /// not vary, as a discrete-time design assumes); later answers are counted late. 0: one more than
  /// the 75th percentile of the measured round trips in periods (HoldLag).
  int hold_lag = 0;
  /// Real time: spin this long before each deadline instead of sleeping (PeriodScheduler): fewer
  /// late periods at high rates for up to that much CPU time per period. 0 to less than a period.
  int spin_us = 0;
  std::size_t periods = 1 << 16;  ///< periods to keep latency figures for
  std::int64_t run_id = 0;     ///< 0: chosen at random
};

/// What the plant node counted.
struct PlantCounts {
  /// late: came after the period it was due to act from had started.
  long states_published = 0, commands_applied = 0, commands_missing = 0, commands_late = 0;
  long commands_failed = 0, states_resent = 0;
  long rejected = 0;  ///< commands refused, for one of these reasons:
  long malformed = 0, wrong_dimension = 0, non_finite = 0, stale = 0, other_run = 0;
  AuthCounts auth;  ///< refused by authentication, by reason (also in rejected)
  /// The held answers' warnings, each period an answer was held (a failed one counts as failed).
  WarningTally warnings;
};

class PlantNode {
 public:
  using Vector = WireVector<Eigen::Dynamic>;

  PlantNode(lcm::LCM& lcm, Outbox& states, const std::string& command_channel, int dimension,
            const PlantNodeOptions& o)
      : lcm_(lcm), states_(states), o_(o), codec_(checked(dimension)),
        scheduler_(period_ns_at(o.rate_hz), monotonic_ns(), o.periods,
                   std::int64_t{o.spin_us} * 1000),
        watchdog_(static_cast<std::int64_t>(o.watchdog_ms) * 1000000, monotonic_ns()),
        hold_lag_(scheduler_.period_ns(), o.hold_lag), round_trip_us_(o.periods), compute_ns_(o.periods),
        answered_sequences_(o.periods), deadline_work_us_(o.periods), hold_lag_periods_(o.periods),
        applied_states_(o.periods) {
    run_id_ = o.run_id != 0 ? o.run_id : random_run_id();
    if (o.actuators < 0 || dimension + o.actuators > kMaxDimension)
      throw std::invalid_argument("PlantNode: " + std::to_string(o.actuators) + " actuators for dimension " +
                                  std::to_string(dimension) + ": the held command (force, then control) has at most 32 entries");
    if (o.hold_lag < 0 || o.hold_lag > HoldLag::kMaxLag)
      throw std::invalid_argument("PlantNode: a hold lag of " + std::to_string(o.hold_lag) + " periods: 0 (measured) to " +
                                  std::to_string(HoldLag::kMaxLag));
    if (!spin_fits_period(o.spin_us, scheduler_.period_ns()))
      throw std::invalid_argument("PlantNode: a spin of " + std::to_string(o.spin_us) + " us at a period of " +
                                  std::to_string(scheduler_.period_ns() / 1000) + " us: 0 to less than the period");
    const int held = dimension + o.actuators;
    hold_ = Vector::Zero(held);
    incoming_force_ = Vector::Zero(dimension);
    incoming_command_ = Vector::Zero(held);
    latest_force_ = Vector::Zero(held);
    answers_ = Eigen::MatrixXd::Zero(held, kAnswerSlots);
    answer_sequence_.fill(-1);
    subscription_ = lcm_.subscribe(command_channel, &PlantNode::on_command, this);
  }
  ~PlantNode() { lcm_.unsubscribe(subscription_); }
  /// From now on accepts only commands that verify with `commands` (the command channel's
  /// authentication, which must outlive the node).
  void authenticate(ChannelAuth& commands) noexcept { auth_ = &commands; }

  /// Messages taken off the socket at a period's deadline before its command is applied.
  static constexpr int kMaxPerPeriod = 64;
  /// More messages than this in one period (a command is one) is a flood: see the file comment.
  static constexpr long kFloodPerPeriod = 4;

  PlantNode(const PlantNode&) = delete;
  PlantNode& operator=(const PlantNode&) = delete;

  /// Called at the start of control period `period` with the state: publishes it and writes the
  /// command to hold over the period into u (the force, then the actuators' control). Returns false to stop the run (a stop was requested,
  /// or in lock-step no command came within the timeout).
  bool exchange(std::int64_t period, double t, std::span<const double> q, std::span<const double> qd,
                std::span<double> u) noexcept {
    const int n = codec_.dimension();
    const int held = n + o_.actuators;
    const auto sn = static_cast<std::size_t>(n);
    if (g_stop_requested || q.size() != sn || qd.size() != sn || u.size() != static_cast<std::size_t>(held))
      return false;
    if (!started_) {
      // The clock starts with the run, not with the node's construction.
      started_ = true;
      const std::int64_t now = monotonic_ns();
      scheduler_.restart(now);
      watchdog_.feed(now);
    }
    if (!o_.lockstep && counts_.states_published == 0) return start_real_time(period, t, q, qd, u);
    if (!o_.lockstep) {
      // One timed wake-up per period (see the file comment): take what has arrived, sleep until
      // the deadline, take what came meanwhile, apply the answer due and publish the state.
      const std::int64_t early = scheduler_.deadline(period) - scheduler_.period_ns() / 4;
      if (flooded_) service_until(early, [] { return false; });
      else take_arrived(early);
      const std::int64_t now = scheduler_.wait_for(period);
      for (int i = 0; i < kMaxPerPeriod && lcm_.handleTimeout(0) > 0; ++i) {
      }
      flooded_ = messages_ - messages_at_wake_ > kFloodPerPeriod;
      messages_at_wake_ = messages_;
      // The answer due now (to state period - lag), or when it has not come the newest older one
      // not yet applied.
      const int lag = hold_lag_.lag();
      const std::int64_t due = period - lag;
      std::int64_t chosen = -1;
      for (std::int64_t k = std::min(due, answered_); k > last_applied_ && k > due - kAnswerSlots; --k)
        if (answer_sequence_[slot(k)] == k) {
          chosen = k;
          break;
        }
      hold_delay_ns_ = lag * scheduler_.period_ns();
      if (chosen >= 0) {
        last_applied_ = chosen;
        watchdog_.feed(now);
        ++counts_.commands_applied;
        held_failed_ = answer_failed_[slot(chosen)];
        held_warnings_ = answer_warnings_[slot(chosen)];
        held_answer_ = true;
        if (held_failed_) hold_.setZero();
        else hold_ = answers_.col(static_cast<Eigen::Index>(slot(chosen)));
      } else {
        // No new answer this period (also when the lag just grew and the answer held is the one
        // due: periods.csv tells those apart).
        ++counts_.commands_missing;
        if (watchdog_.check(now) && !o_.safe_hold) {
          hold_.setZero();
          held_answer_ = false;
        }
      }
      tally_held_answer();
      hold_lag_periods_.add(lag);
      applied_states_.add(static_cast<double>(last_applied_));
      for (int i = 0; i < held; ++i) u[static_cast<std::size_t>(i)] = hold_(i);
      awaited_ = period;
      exact_ = false;
      publish_state(period, t, q, qd);
      deadline_work_us_.add(static_cast<double>(monotonic_ns() - now) * 1e-3);
      return true;
    }
    if (!await_answer(period, t, q, qd)) {
      if (g_stop_requested) return false;
      ++counts_.commands_missing;
      if (auth_ && counts_.commands_applied == 0) return refuse_to_run("in lock-step");
      std::fprintf(stderr,
                   "error: no command answered state %lld within %d ms (commands refused meanwhile: %ld malformed, "
                   "%ld of another dimension, %ld non-finite, %ld stale, %ld of another run)\n",
                   static_cast<long long>(period), o_.timeout_ms, counts_.malformed, counts_.wrong_dimension,
                   counts_.non_finite, counts_.stale, counts_.other_run);
      return false;
    }
    ++counts_.commands_applied;
    held_failed_ = latest_failed_;
    held_warnings_ = latest_warnings_;
    held_answer_ = true;
    tally_held_answer();
    for (int i = 0; i < held; ++i) u[static_cast<std::size_t>(i)] = latest_failed_ ? 0.0 : latest_force_(i);
    return true;
  }

  // Publishes the state of `period` and waits for the command answering it (resending the state
  // every 100 ms) up to the timeout. True when it came.
  bool await_answer(std::int64_t period, double t, std::span<const double> q, std::span<const double> qd) noexcept {
    awaited_ = period;
    exact_ = true;
    ready_ = false;
    publish_state(period, t, q, qd);
    const std::int64_t give_up = monotonic_ns() + static_cast<std::int64_t>(o_.timeout_ms) * 1000000;
    for (;;) {
      const std::int64_t resend = std::min(give_up, monotonic_ns() + kResendNs);
      service_until(resend, [&] { return ready_ || g_stop_requested != 0; });
      if (ready_ || g_stop_requested || monotonic_ns() >= give_up) return ready_ && !g_stop_requested;
      ++counts_.states_resent;
      send_state();
    }
  }

  // Real time, the first state: its answer is awaited as in lock-step, and the periodic clock
  // starts when it comes, so that the run does not begin with a period of no force (the
  // controller's first answer takes a round trip). Without an answer within the timeout the clock
  // starts anyway, with the safe action (an authenticated plant ends the run instead).
  bool start_real_time(std::int64_t period, double t, std::span<const double> q, std::span<const double> qd,
                       std::span<double> u) noexcept {
    const bool answered = await_answer(period, t, q, qd);
    if (g_stop_requested) return false;
    const std::int64_t now = monotonic_ns();
    scheduler_.restart(now - scheduler_.period_ns() * period);
    exact_ = false;
    hold_.setZero();
    if (answered) {
      watchdog_.feed(now);
      ++counts_.commands_applied;
      last_applied_ = answered_;
      if (!latest_failed_) hold_ = latest_force_;
      held_failed_ = latest_failed_;
      held_warnings_ = latest_warnings_;
      held_answer_ = true;
      tally_held_answer();
      // Applied at once, as in lock-step; the answers to the next states act a period later at
      // the soonest (their round trips set the lag from then on).
      hold_delay_ns_ = hold_lag_.lag() * scheduler_.period_ns();
    } else {
      ++counts_.commands_missing;
      if (auth_) return refuse_to_run("in real time");
    }
    hold_lag_periods_.add(0);
    applied_states_.add(static_cast<double>(last_applied_));
    for (int i = 0; i < hold_.size(); ++i) u[static_cast<std::size_t>(i)] = hold_(i);
    return true;
  }

  void on_command(const lcm::ReceiveBuffer* rbuf, const std::string&) noexcept {
    // The kernel's receive time where LCM has it, else now (both on the wall clock of this host).
    handle_command(rbuf->data, rbuf->data_size, rbuf->recv_utime > 0 ? rbuf->recv_utime * 1000 : wall_us() * 1000);
  }

  /// Keeps a valid command: in lock-step the one answering the awaited state, in real time the
  /// newest one answering a published state not yet answered; counts and drops the rest.
  /// `received_ns`: when it arrived, on the wall clock [ns since the Unix epoch].
  void handle_command(const void* data, std::size_t size, std::int64_t received_ns) noexcept {
    ++messages_;
    if (!admit(auth_, data, size, counts_.auth)) {
      ++counts_.rejected;
      return;
    }
    switch (codec_.decode_command(data, size, incoming_, incoming_force_)) {
      case Refusal::kNone: break;
      case Refusal::kMalformed: return reject(&counts_.malformed);
      case Refusal::kDimension: return reject(&counts_.wrong_dimension);
      case Refusal::kNonFinite: return reject(&counts_.non_finite);
    }
    if (incoming_.run_id != run_id_) return reject(&counts_.other_run);
    // A plant driven through its actuators holds their control: a command must carry one per
    // actuator (a failed one carries none, and holds zero).
    if (o_.actuators > 0 && incoming_.status == 0 && incoming_.actuators != o_.actuators)
      return reject(&counts_.wrong_dimension);
    const std::int64_t k = incoming_.state_sequence;
    if (k > last_published_ || k <= answered_ || (exact_ && k != awaited_) ||
        k <= last_published_ - static_cast<std::int64_t>(published_at_.size()))
      return reject(&counts_.stale);
    // In real time the answer to state k acts from period k + lag: one coming after that period
    // started is late (when it is the newest it is still applied).
    if (!o_.lockstep && k + hold_lag_.lag() <= last_published_) ++counts_.commands_late;
    const std::int64_t sent = published_at_[static_cast<std::size_t>(k) % published_at_.size()];
    round_trip_us_.add(static_cast<double>(received_ns - sent) * 1e-3);
    // The lag counts from the period's deadline: the work before the state went out is added. The
    // awaited first answer (a cold start) is left out.
    if (!o_.lockstep && !exact_)
      hold_lag_.record(received_ns - sent + sent_after_deadline_[static_cast<std::size_t>(k) % sent_after_deadline_.size()]);
    compute_ns_.add(static_cast<double>(incoming_.compute_ns));
    answered_sequences_.add(static_cast<double>(k));
    latest_failed_ = incoming_.status != 0;  // any status but kOk: no answer, zero force
    latest_warnings_ = static_cast<std::uint32_t>(incoming_.warnings);
    if (latest_failed_) ++counts_.commands_failed;
    const int n = codec_.dimension();
    incoming_command_.head(n) = incoming_force_;
    for (int j = 0; j < o_.actuators; ++j) incoming_command_(n + j) = latest_failed_ ? 0.0 : incoming_.control[j];
    latest_force_ = incoming_command_;
    answers_.col(static_cast<Eigen::Index>(slot(k))) = incoming_command_;
    answer_sequence_[slot(k)] = k;
    answer_failed_[slot(k)] = latest_failed_;
    answer_warnings_[slot(k)] = latest_warnings_;
    answered_ = k;
    ready_ = true;
  }

  std::int64_t run_id() const noexcept { return run_id_; }
  const PlantCounts& counts() const noexcept { return counts_; }
  /// The last period brought a flood: the loop takes messages as they come before its deadline.
  bool flooded() const noexcept { return flooded_; }
  const PeriodScheduler& scheduler() const noexcept { return scheduler_; }
  const Watchdog& watchdog() const noexcept { return watchdog_; }
  const LatencyRecorder& round_trip_us() const noexcept { return round_trip_us_; }
  const LatencyRecorder& compute_ns() const noexcept { return compute_ns_; }
  const LatencyRecorder& answered_sequences() const noexcept { return answered_sequences_; }
  /// Real time: per period, from the wake at its deadline to its state's publication (the bounded
  /// drain of the socket, the command's application, the state's encoding and sending) [us].
  const LatencyRecorder& deadline_work_us() const noexcept { return deadline_work_us_; }
  /// Real time: per period from the first, the hold lag in periods with which it applied answers
  /// (HoldLag; 0 for the first period, whose answer was awaited) and the state whose answer it
  /// held (-1: none yet). Period p held the answer due when p - applied state <= the lag.
  const LatencyRecorder& hold_lag_periods() const noexcept { return hold_lag_periods_; }
  const LatencyRecorder& applied_states() const noexcept { return applied_states_; }
  const PlantNodeOptions& options() const noexcept { return o_; }

  /// The run's loop statistics as the plant publishes them when it stops.
  loop_stats_t stats() const {
    loop_stats_t s{};
    s.utime = wall_us();
    s.process = "plant";
    s.states_published = counts_.states_published;
    s.commands_applied = counts_.commands_applied;
    s.commands_missing = counts_.commands_missing;
    s.commands_late = counts_.commands_late;
    s.commands_failed = counts_.commands_failed;
    s.runs = 1;
    s.deadline_misses = scheduler_.misses();
    s.messages_rejected = counts_.rejected;
    s.watchdog_trips = static_cast<std::int32_t>(watchdog_.trips());
    s.round_trip_us_p50 = round_trip_us_.quantile(0.5);
    s.round_trip_us_p99 = round_trip_us_.quantile(0.99);
    s.round_trip_us_p999 = round_trip_us_.quantile(0.999);
    s.round_trip_us_max = round_trip_us_.max();
    s.compute_ns_p50 = compute_ns_.quantile(0.5);
    s.compute_ns_p99 = compute_ns_.quantile(0.99);
    s.compute_ns_max = compute_ns_.max();
    s.wake_late_us_p99 = scheduler_.wake_late_us().quantile(0.99);
    s.wake_late_us_max = scheduler_.wake_late_us().max();
    return s;
  }

  /// The loop's figures as JSON object members (for the run's summary).
  /// Adds the loop's members to a run's summary (summary.json): mode, rate, run id, the counts,
  /// and the round-trip, compute and wake-up percentiles.
  void add_to_summary(nlohmann::ordered_json& summary, long log_dropped) const;

 private:
  static std::int64_t random_run_id() {
    std::random_device rd;
    std::int64_t id = 0;
    while (id == 0)
      id = static_cast<std::int64_t>((static_cast<std::uint64_t>(rd()) << 32) ^ rd() ^
                                     static_cast<std::uint64_t>(monotonic_ns())) & INT64_MAX;
    return id;
  }

  static constexpr std::int64_t kResendNs = 100'000'000;
  /// Answers kept for the period they are due in (more than the longest hold lag).
  static constexpr std::int64_t kAnswerSlots = 2 * HoldLag::kMaxLag;
  static std::size_t slot(std::int64_t k) noexcept { return static_cast<std::size_t>(k % kAnswerSlots); }

  static int checked(int dimension) {
    if (dimension < 1 || dimension > kMaxDimension)
      throw std::invalid_argument("PlantNode: dimension " + std::to_string(dimension) + " is not in 1..32");
    return dimension;
  }

  // A run whose commands all failed authentication: the pair does not share a key.
  bool refuse_to_run(const char* mode) noexcept {
    const AuthCounts& a = counts_.auth;
    std::fprintf(stderr,
                 "error: no command verified within %d ms %s (refused: %ld with another key or altered, %ld without "
                 "a key, %ld replayed): is the controller running, with this plant's key (--key)?\n",
                 o_.timeout_ms, mode, a.bad_tag, a.unauthenticated, a.replayed);
    return false;
  }

  // The period's held answer into the warning tally (nothing while the watchdog's safe action holds).
  void tally_held_answer() noexcept {
    if (!held_answer_) return;
    if (held_failed_) counts_.warnings.add_failure();
    else counts_.warnings.add(held_warnings_);
  }

  void reject(long* reason) noexcept {
    ++counts_.rejected;
    ++*reason;
  }

  void publish_state(std::int64_t period, double t, std::span<const double> q, std::span<const double> qd) noexcept {
    const int n = codec_.dimension();
    state_.sequence = period;
    state_.run_id = run_id_;
    state_.t = t;
    state_.hold_delay_ns = o_.lockstep ? 0 : hold_delay_ns_;
    state_bytes_ = codec_.encode_state(state_, Eigen::Map<const Eigen::VectorXd>(q.data(), n),
                                       Eigen::Map<const Eigen::VectorXd>(qd.data(), n), buffer_.data(),
                                       buffer_.size());
    last_published_ = period;
    sent_after_deadline_[static_cast<std::size_t>(period) % sent_after_deadline_.size()] =
        o_.lockstep ? 0 : std::max<std::int64_t>(0, monotonic_ns() - scheduler_.deadline(period));
    send_state();
    ++counts_.states_published;
  }

  // (Re)sends the encoded state; its round trip counts from the last sending.
  void send_state() noexcept {
    const std::int64_t now_us = wall_us();
    published_at_[static_cast<std::size_t>(last_published_) % published_at_.size()] = now_us * 1000;
    if (state_bytes_ > 0) states_.publish(buffer_.data(), static_cast<std::size_t>(state_bytes_), now_us);
  }

  // Dispatches the messages already received, without waiting, until none is left or the clock
  // reaches `until_ns` (monotonic): a flood is taken off the socket between deadlines as far as
  // time allows, never past them.
  void take_arrived(std::int64_t until_ns) noexcept {
    while (monotonic_ns() < until_ns && lcm_.handleTimeout(0) > 0) {
    }
  }

  // Services LCM until `deadline_ns` (monotonic) or until done(): waits on LCM's socket and
  // dispatches whatever arrives.
  template <typename Done>
  void service_until(std::int64_t deadline_ns, Done&& done) noexcept {
    pollfd fd{lcm_.getFileno(), POLLIN, 0};
    for (;;) {
      const std::int64_t left = deadline_ns - monotonic_ns();
      if (done() || left <= 0) return;
      const timespec timeout = to_timespec(left);
      const int ready = ppoll(&fd, 1, &timeout, nullptr);
      if (ready > 0) lcm_.handle();
      else if (ready == 0 || g_stop_requested) return;
    }
  }

  lcm::LCM& lcm_;
  Outbox& states_;
  PlantNodeOptions o_;
  Codec<Eigen::Dynamic> codec_;
  PeriodScheduler scheduler_;
  Watchdog watchdog_;
  lcm::Subscription* subscription_ = nullptr;
  ChannelAuth* auth_ = nullptr;
  std::int64_t run_id_ = 0;
  plant_state_t state_{};
  control_command_t incoming_{};
  Vector incoming_force_, incoming_command_, latest_force_, hold_;  ///< the last three: force, then control
  bool latest_failed_ = false, ready_ = false, exact_ = true, started_ = false;
  bool flooded_ = false;                      ///< the last period brought a flood (kFloodPerPeriod)
  long messages_ = 0, messages_at_wake_ = 0;  ///< commands' datagrams taken; their count at the last wake
  std::array<std::uint8_t, kMessageBufferBytes> buffer_{};
  int state_bytes_ = 0;
  std::array<std::int64_t, 4096> published_at_{};  ///< wall clock [ns] each state was sent
  std::array<std::int64_t, 4096> sent_after_deadline_{};  ///< [ns] from its period's deadline
  std::int64_t awaited_ = -1, answered_ = -1, last_published_ = -1, last_applied_ = -1;
  std::int64_t hold_delay_ns_ = 0;
  HoldLag hold_lag_;
  Eigen::MatrixXd answers_;  ///< the forces received, column slot(k) for state k
  std::array<std::int64_t, kAnswerSlots> answer_sequence_{};
  std::array<bool, kAnswerSlots> answer_failed_{};
  std::array<std::uint32_t, kAnswerSlots> answer_warnings_{};
  std::uint32_t latest_warnings_ = 0, held_warnings_ = 0;
  bool held_failed_ = false, held_answer_ = false;
  PlantCounts counts_;
  LatencyRecorder round_trip_us_, compute_ns_, answered_sequences_, deadline_work_us_, hold_lag_periods_,
      applied_states_;
};

}  // namespace gausstrack::nodes

// The firmware image: a fixed-period loop at 1 kHz for 10 s of simulated time on the target,
// paced by SysTick (WFI between periods). Each period: read the state, evaluate the law (timed by
// SysTick: cost per call in instructions), apply the force, integrate the plant over the period
// (RK4 in the target's scalar). The first call runs on a painted stack (its deepest use is
// measured). The trajectory (t, q, q', u per period, in that scalar) goes to the host file over
// semihosting; the figures go to stderr as "key value" lines. Exit codes: 0 ok, 1 the law
// failed, 2 a deadline overrun, 3 the output file could not be written; the board's own: 90 a
// fault, 91 an allocation.
#include <cstdint>

#include "../board/board.hpp"
#include "loop.hpp"

#ifndef FIRMWARE_LAW
#error "define FIRMWARE_LAW as firmware::Law::kDuffing, kArm, kClosedForm, kDuffingHeld, kArmHeld, kCartPole, kArmPassiveWrist or kDifferentialDrive"
#endif
#ifndef FIRMWARE_TRAJECTORY
#define FIRMWARE_TRAJECTORY "trajectory.bin"
#endif

namespace {

using Scalar = FIRMWARE_SCALAR;
using LoopT = firmware::Loop<FIRMWARE_LAW, Scalar>;
constexpr int N = LoopT::N;
constexpr std::uint32_t kTicksPerPeriod = board::kTicksPerSecond / 1000u;
constexpr std::uint32_t kPaint = 0xA5A5A5A5u;

LoopT g_loop;  // static storage: the law's workspace is part of .bss, not the stack

// Calls the law once on a painted stack and returns how many bytes below the caller's stack
// pointer it wrote.
__attribute__((noinline)) std::uint32_t measure_stack(const typename LoopT::Vector& q,
                                                      const typename LoopT::Vector& qd, typename LoopT::Vector& u) {
  const std::uintptr_t sp = board::stack_pointer();
  volatile std::uint32_t* bottom = &_stack_bottom;
  for (volatile std::uint32_t* p = bottom; reinterpret_cast<std::uintptr_t>(p) < sp - 64; ++p) *p = kPaint;
  g_loop.control(q, qd, Scalar(0), u);
  volatile std::uint32_t* p = bottom;
  while (*p == kPaint) ++p;
  return static_cast<std::uint32_t>(sp - reinterpret_cast<std::uintptr_t>(p));
}

}  // namespace

int main() {
#ifdef FIRMWARE_ALLOCATE
  // The test that the allocation trap works: this image must end with exit code 91.
  volatile int* p = new int(1);
  *p = 2;
#endif
  const int fd = board::open_for_writing(FIRMWARE_TRAJECTORY);
  if (fd < 0) {
    board::print("firmware: cannot open the trajectory file\n");
    return 3;
  }
  typename LoopT::Vector q = g_loop.q(), qd = g_loop.qd(), u;
  const std::uint32_t stack_bytes = measure_stack(q, qd, u);

  constexpr int kChunk = 100;
  static Scalar buffer[kChunk][1 + 3 * N];
  std::uint32_t max_ticks = 0, min_ticks = 0xFFFFFFFFu, overruns = 0, failures = 0, clock_jumps = 0;
  std::uint64_t total_ticks = 0;
  Scalar worst_error = 0;
  board::start_periodic_tick(kTicksPerPeriod);
  std::uint32_t seen = board::g_ticks;
  for (int k = 0; k < firmware::kPeriods; ++k) {
    board::wait_for_period(seen);
    seen = board::g_ticks;
    const Scalar t = Scalar(k) * Scalar(firmware::kPeriod);
    // Read the state, evaluate the law, apply the force: timed.
    q = g_loop.q();
    qd = g_loop.qd();
    std::uint32_t start = board::systick().val;
    gausstrack::Status status = g_loop.control(q, qd, t, u);
    std::uint32_t end = board::systick().val;
    if (board::g_ticks != seen) {
      // A period boundary passed during the call: the law overran, or QEMU's virtual clock
      // jumped (with -icount sleep=on it catches up with the host's clock after semihosting I/O
      // on a busy host). The call is a function of the state alone: repeat it in the new period;
      // an overrun repeats, a clock jump does not.
      ++clock_jumps;
      seen = board::g_ticks;
      start = board::systick().val;
      status = g_loop.control(q, qd, t, u);
      end = board::systick().val;
    }
    if (failed(status)) ++failures;
    if (board::g_ticks != seen) ++overruns;  // the period ended before the force was applied
    else if (end <= start) {  // (end above start: the counter reloaded, its interrupt not yet taken: no figure)
      const std::uint32_t ticks = start - end;
      max_ticks = ticks > max_ticks ? ticks : max_ticks;
      min_ticks = ticks < min_ticks ? ticks : min_ticks;
      total_ticks += ticks;
    }
    Scalar* row = buffer[k % kChunk];
    row[0] = t;
    for (int i = 0; i < N; ++i) {
      row[1 + i] = q(i);
      row[1 + N + i] = qd(i);
      row[1 + 2 * N + i] = u(i);
    }
    if (k % kChunk == kChunk - 1 && !board::write(fd, buffer, sizeof buffer)) return 3;
    g_loop.advance(u, t, Scalar(firmware::kPeriod));
    const Scalar e = g_loop.tracking_error(t + Scalar(firmware::kPeriod));
    worst_error = e > worst_error ? e : worst_error;
  }
  board::close(fd);
  board::print_uint("periods ", firmware::kPeriods);
  board::print_uint("law_failures ", failures);
  board::print_uint("deadline_overruns ", overruns);
  board::print_uint("clock_jumps_during_call ", clock_jumps);
  board::print_uint("stack_bytes_measured ", stack_bytes);
  board::print_uint("law_state_bytes ", sizeof(LoopT));
  board::print_uint("instructions_per_call_max ", max_ticks * board::kInstructionsPerTick);
  board::print_uint("instructions_per_call_min ", min_ticks * board::kInstructionsPerTick);
  board::print_uint("instructions_per_call_mean ",
                    static_cast<std::uint32_t>(total_ticks * board::kInstructionsPerTick / firmware::kPeriods));
  board::print_uint("max_tracking_error_nm ", static_cast<std::uint32_t>(worst_error * Scalar(1e9)));
  if (failures) return 1;
  if (overruns) return 2;
  return 0;
}

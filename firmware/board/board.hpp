// What the firmware image needs from the MPS2 board as QEMU models it: semihosting (output, host
// files, exit code), the SysTick timer, the stack's extent. Nothing here is part of the law.
#pragma once

#include <cstddef>
#include <cstdint>

namespace board {

// ARM semihosting: operation in r0, argument block in r1, BKPT 0xAB.
inline std::uintptr_t semihost(std::uintptr_t op, const void* arg) {
  register std::uintptr_t r0 asm("r0") = op;
  register const void* r1 asm("r1") = arg;
  asm volatile("bkpt 0xab" : "+r"(r0) : "r"(r1) : "memory");
  return r0;
}

inline std::size_t length(const char* s) {
  std::size_t n = 0;
  while (s[n]) ++n;
  return n;
}

/// Text to the host's stderr (SYS_WRITE0).
inline void print(const char* s) { semihost(0x04, s); }

/// Unsigned decimal into `out` (no printf: newlib's float printf allocates).
inline char* format_uint(char* out, std::uint32_t v) {
  char tmp[12];
  int n = 0;
  do {
    tmp[n++] = static_cast<char>('0' + v % 10);
    v /= 10;
  } while (v);
  while (n) *out++ = tmp[--n];
  *out = 0;
  return out;
}
inline void print_uint(const char* label, std::uint32_t v) {
  char line[96];
  char* p = line;
  for (const char* s = label; *s;) *p++ = *s++;
  p = format_uint(p, v);
  *p++ = '\n';
  *p = 0;
  print(line);
}

/// A host file opened for binary writing (SYS_OPEN mode "wb"); -1 when it cannot be.
inline int open_for_writing(const char* path) {
  const std::uintptr_t args[3] = {reinterpret_cast<std::uintptr_t>(path), 5, length(path)};
  return static_cast<int>(semihost(0x01, args));
}
inline bool write(int fd, const void* data, std::size_t size) {
  const std::uintptr_t args[3] = {static_cast<std::uintptr_t>(fd), reinterpret_cast<std::uintptr_t>(data), size};
  return semihost(0x05, args) == 0;
}
inline void close(int fd) {
  const std::uintptr_t args[1] = {static_cast<std::uintptr_t>(fd)};
  semihost(0x02, args);
}

/// Ends the run with an exit code QEMU passes on (SYS_EXIT_EXTENDED, ADP_Stopped_ApplicationExit).
[[noreturn]] inline void exit(std::uint32_t code) {
  const std::uintptr_t args[2] = {0x20026, code};
  semihost(0x20, args);
  for (;;) {
  }
}

// SysTick: a 24-bit down-counter. Under QEMU's -icount shift=0 the CPU retires one instruction per
// virtual nanosecond and SysTick counts at 25 MHz: one tick is 40 instructions.
struct SysTick {
  volatile std::uint32_t ctrl, load, val, calib;
};
inline SysTick& systick() { return *reinterpret_cast<SysTick*>(0xE000E010u); }
inline constexpr std::uint32_t kTicksPerSecond = 25000000u;
inline constexpr std::uint32_t kInstructionsPerTick = 40u;

/// Starts SysTick with a period of `ticks` and its interrupt (the loop's period).
inline void start_periodic_tick(std::uint32_t ticks) {
  systick().load = ticks - 1;
  systick().val = 0;
  systick().ctrl = 0x7;  // enable, interrupt, processor clock
}

extern volatile std::uint32_t g_ticks;  // periods elapsed, counted by the SysTick handler

/// Sleeps until the next period starts.
inline void wait_for_period(std::uint32_t seen) {
  while (g_ticks == seen) asm volatile("wfi");
}

inline std::uintptr_t stack_pointer() {
  std::uintptr_t sp;
  asm volatile("mov %0, sp" : "=r"(sp));
  return sp;
}

}  // namespace board

extern "C" {
extern std::uint32_t _stack_bottom, _stack_top;
}

// Reset handler and vector table for the MPS2 images: enables the FPU before any C++ runs (the
// first floating-point instruction would fault otherwise), copies .data, zeroes .bss, runs static
// constructors, calls main and passes its result out as the exit code. A fault, or any call to
// the heap, ends the run with a code of its own.
#include <cstddef>
#include <cstdint>

#include "board.hpp"

extern "C" {
extern std::uint32_t _data_load, _data_start, _data_end, _bss_start, _bss_end;
extern void (*__init_array_start[])();
extern void (*__init_array_end[])();
int main();
void reset_handler();
void systick_handler();
void fault_handler();
}

volatile std::uint32_t board::g_ticks = 0;

enum ExitCode : std::uint32_t { kFault = 90, kAllocation = 91 };

extern "C" void reset_handler() {
  // CPACR: full access to CP10 and CP11 (the FPU).
  *reinterpret_cast<volatile std::uint32_t*>(0xE000ED88u) |= (0xFu << 20);
  asm volatile("dsb\n isb");
  for (std::uint32_t *src = &_data_load, *dst = &_data_start; dst < &_data_end;) *dst++ = *src++;
  for (std::uint32_t* dst = &_bss_start; dst < &_bss_end;) *dst++ = 0;
  for (auto f = __init_array_start; f < __init_array_end; ++f) (*f)();
  board::exit(static_cast<std::uint32_t>(main()));
}

extern "C" void systick_handler() { board::g_ticks = board::g_ticks + 1; }

extern "C" void fault_handler() {
  board::print("firmware: FAULT (hard fault, memory management, bus or usage fault)\n");
  board::exit(kFault);
}

// The heap is not there: any allocation ends the run loudly (newlib's malloc family and sbrk).
extern "C" {
[[noreturn]] void allocation_trap() {
  board::print("firmware: ALLOCATION attempted; the control law must not allocate\n");
  board::exit(kAllocation);
}
void* malloc(std::size_t) { allocation_trap(); }
void* calloc(std::size_t, std::size_t) { allocation_trap(); }
void* realloc(void*, std::size_t) { allocation_trap(); }
void free(void*) { allocation_trap(); }
void* _sbrk(int) { allocation_trap(); }
void* _malloc_r(void*, std::size_t) { allocation_trap(); }
void _free_r(void*, void*) { allocation_trap(); }
}

// No C++ runtime library is linked: new and delete are ours, and trap too.
void* operator new(std::size_t) { allocation_trap(); }
void* operator new[](std::size_t) { allocation_trap(); }
void operator delete(void*) noexcept { allocation_trap(); }
void operator delete[](void*) noexcept { allocation_trap(); }
void operator delete(void*, std::size_t) noexcept { allocation_trap(); }
void operator delete[](void*, std::size_t) noexcept { allocation_trap(); }

// Cortex-M vector table: initial stack pointer, reset, NMI, faults, SVC, PendSV, SysTick.
__attribute__((section(".vectors"), used)) void* const g_vectors[16] = {
    &_stack_top,
    reinterpret_cast<void*>(reset_handler),
    reinterpret_cast<void*>(fault_handler),  // NMI
    reinterpret_cast<void*>(fault_handler),  // hard fault
    reinterpret_cast<void*>(fault_handler),  // memory management
    reinterpret_cast<void*>(fault_handler),  // bus fault
    reinterpret_cast<void*>(fault_handler),  // usage fault
    nullptr, nullptr, nullptr, nullptr,
    reinterpret_cast<void*>(fault_handler),  // SVC
    nullptr, nullptr,
    reinterpret_cast<void*>(fault_handler),  // PendSV
    reinterpret_cast<void*>(systick_handler),
};

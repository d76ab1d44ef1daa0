// A program's stop request, one flag for every gausstrack program (the simulator, the plant and
// controller processes): SIGINT or SIGTERM sets it; their loops poll it and end where they are,
// keeping and writing what they computed.
#pragma once

#include <csignal>

namespace gausstrack {

inline volatile std::sig_atomic_t g_stop_requested = 0;

/// Installs the handlers that set g_stop_requested on SIGINT and SIGTERM.
inline void stop_on_signals() {
  auto handler = [](int) { g_stop_requested = 1; };
  std::signal(SIGINT, handler);
  std::signal(SIGTERM, handler);
}

}  // namespace gausstrack

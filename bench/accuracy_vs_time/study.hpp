// What the parts of accuracy_vs_time (study.cpp) share across its units.
#pragma once

#include <chrono>
#include <fstream>

namespace gausstrack::study {

inline double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

/// peer.csv: the Duffing tracking task by odeint and ARKODE at equal tolerances (peer_study.cpp).
void peer(std::ofstream& csv, bool quick);

}  // namespace gausstrack::study

// A LatencyRecorder's percentiles as JSON, for the programs that write summary files. It brings in
// nlohmann-json's whole header: include it in compiled sources, not in headers a model includes.
#pragma once

#include <nlohmann/json.hpp>

#include "gausstrack/nodes/latency_recorder.hpp"

namespace gausstrack::nodes {

/// {"p50", "p99", "p999", "max", "count"} of the recorded values.
inline nlohmann::ordered_json percentiles_json(const LatencyRecorder& r) {
  return {{"p50", r.quantile(0.5)}, {"p99", r.quantile(0.99)}, {"p999", r.quantile(0.999)},
          {"max", r.max()},         {"count", r.count()}};
}

}  // namespace gausstrack::nodes

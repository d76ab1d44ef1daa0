// Records one latency (or any value) per event into storage reserved up front, and reports its
// percentiles: used by the LCM processes per control period and by the benchmarks per call.
#pragma once

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

namespace gausstrack::nodes {

/// Recording never allocates: values past the reserved count are counted as dropped, not kept.
class LatencyRecorder {
 public:
  explicit LatencyRecorder(std::size_t capacity) { values_.reserve(capacity); }

  void add(double v) {
    if (values_.size() < values_.capacity()) values_.push_back(v);
    else ++dropped_;
  }
  void clear() {
    values_.clear();
    dropped_ = 0;
  }
  std::size_t count() const { return values_.size(); }
  std::size_t dropped() const { return dropped_; }
  const std::vector<double>& values() const { return values_; }

  /// The q-quantile (0 <= q <= 1, nearest rank) of the recorded values; 0 when none.
  double quantile(double q) const {
    if (values_.empty()) return 0;
    std::vector<double> v = values_;
    const auto k = static_cast<std::size_t>(std::ceil(q * static_cast<double>(v.size())));
    const std::size_t rank = std::min(v.size() - 1, k == 0 ? 0 : k - 1);
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(rank), v.end());
    return v[rank];
  }
  double max() const { return values_.empty() ? 0 : *std::max_element(values_.begin(), values_.end()); }


 private:
  std::vector<double> values_;
  std::size_t dropped_ = 0;
};

}  // namespace gausstrack::nodes

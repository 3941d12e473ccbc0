// Timing helpers shared by the benchmarks and `tsm bench`.
#pragma once
#include <algorithm>
#include <chrono>
#include <vector>

namespace tsm::bench {

// The median of repeated timings (0 for none).
inline double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

// Milliseconds on the steady clock (differences only).
inline double now_ms() {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

}  // namespace tsm::bench

// Timing helpers shared by the benchmarks and `tsm bench`.
#pragma once
#include <time.h>

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

// Milliseconds of CPU time the calling thread has used (differences only):
// single-threaded work timed this way does not count the time other
// processes of a busy machine take from it.
inline double thread_cpu_ms() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return 1e3 * static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_nsec);
}

}  // namespace tsm::bench

// The thread pool of the segment coders (parallel.hpp): the encoder codes a
// file's segments on it, the decoder decodes them on it (FORMAT.md §4.5).
// A task's exception ends that task, not the process: it becomes the
// Status parallel_for returns.
#include "parallel.hpp"

#include <algorithm>
#include <atomic>
#include <exception>
#include <new>
#include <string>
#include <vector>
#ifndef TSM_NO_THREADS
#include <thread>
#endif

namespace tsm {

void (*parallel_task_hook)(size_t index) = nullptr;

namespace {

// Runs one task; what it throws becomes a Status. The out-of-memory message
// fits std::string's inline buffer, so making it allocates nothing.
Status run_task(const std::function<void(size_t)>& task, size_t i) {
  try {
    if (parallel_task_hook) parallel_task_hook(i);
    task(i);
    return Status::Ok();
  } catch (const std::bad_alloc&) {
    return Status(ErrorCode::limit_exceeded, "out of memory");
  } catch (const std::exception& e) {
    try {
      return Status(ErrorCode::internal, std::string("unexpected exception: ") + e.what());
    } catch (...) {
      return Status(ErrorCode::internal, "exception");
    }
  } catch (...) {
    return Status(ErrorCode::internal, "exception");
  }
}

}  // namespace

Status parallel_for(size_t n, int threads, const std::function<void(size_t)>& task, size_t* failed_task) {
  std::vector<Status> status(n);  // per task; each written by the thread that ran it
  std::atomic<size_t> next{0};
  std::atomic<bool> stop{false};
  auto work = [&] {
    for (size_t i; !stop.load(std::memory_order_relaxed) && (i = next.fetch_add(1)) < n;) {
      status[i] = run_task(task, i);
      if (!status[i].ok()) stop = true;
    }
  };
#ifndef TSM_NO_THREADS
  size_t t = threads > 0 ? static_cast<size_t>(threads) : std::max(1u, std::thread::hardware_concurrency());
  t = std::min(t, n);
  std::vector<std::thread> pool;
  try {
    pool.reserve(t > 0 ? t - 1 : 0);
    for (size_t k = 1; k < t; ++k) pool.emplace_back(work);
  } catch (...) {
    // No more threads to be had (std::system_error, std::bad_alloc): the
    // ones started and this one share the tasks.
  }
  work();
  for (std::thread& th : pool) th.join();
#else
  (void)threads;
  work();
#endif
  for (size_t i = 0; i < n; ++i)
    if (!status[i].ok()) {
      if (failed_task) *failed_task = i;
      return status[i];
    }
  return Status::Ok();
}

}  // namespace tsm

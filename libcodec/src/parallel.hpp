// Internal: the thread pool the segment coders run on (FORMAT.md §4.5: the
// segments of a file are coded, and decoded, independently of each other).
// Below both halves: encode.cpp codes a file's segments on it, decode.cpp
// decodes them on it.
#pragma once
#include <cstddef>
#include <functional>

#include "tsm/status.hpp"

namespace tsm {

// Runs task(i) for every i in 0..n-1, once each, on up to `threads` threads
// (0 = one per core; serial where threads are not available, TSM_NO_THREADS).
// Nothing a task throws leaves it: an exception (std::bad_alloc, anything)
// fails that task, no task starts after it, and the failure of the lowest
// index is returned (limit_exceeded "out of memory" for std::bad_alloc,
// internal with the exception's message otherwise), its index in
// *failed_task when that is given. Ok when no task threw.
Status parallel_for(size_t n, int threads, const std::function<void(size_t)>& task, size_t* failed_task = nullptr);

// Tests only: when set, called at the start of every task with its index,
// inside the task (a test throws from it to check the above). Set it only
// while no parallel_for runs.
extern void (*parallel_task_hook)(size_t index);

}  // namespace tsm

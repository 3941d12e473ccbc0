// The segment coders' thread pool (parallel.hpp): what a task throws
// (std::bad_alloc, anything) becomes an error Status, never std::terminate
// (an exception leaving a std::thread ends the process), on one thread and
// on several; and an encode or decode whose segment task throws returns that
// error for the segment. parallel_task_hook injects the exceptions.
#include <gtest/gtest.h>

#include <atomic>
#include <new>
#include <stdexcept>
#include <string>
#include <vector>

#include "mesh_gen.hpp"
#include "parallel.hpp"
#include "tsm/tsm.hpp"

namespace {

// Sets parallel_task_hook for a scope.
struct HookGuard {
  explicit HookGuard(void (*hook)(size_t)) { tsm::parallel_task_hook = hook; }
  ~HookGuard() { tsm::parallel_task_hook = nullptr; }
};

TEST(Parallel, EveryTaskRunsOnce) {
  for (int threads : {0, 1, 2, 7}) {
    std::vector<std::atomic<int>> ran(100);
    const tsm::Status s = tsm::parallel_for(ran.size(), threads, [&](size_t i) { ++ran[i]; });
    EXPECT_TRUE(s.ok()) << s.to_string();
    for (const std::atomic<int>& r : ran) EXPECT_EQ(r.load(), 1);
  }
  EXPECT_TRUE(tsm::parallel_for(0, 4, [](size_t) { FAIL(); }).ok());
}

TEST(Parallel, TaskExceptionsBecomeStatus) {
  for (int threads : {1, 2, 4}) {
    SCOPED_TRACE("threads " + std::to_string(threads));
    size_t failed = 99;
    tsm::Status s = tsm::parallel_for(
        8, threads, [](size_t i) { if (i == 5) throw std::bad_alloc(); }, &failed);
    EXPECT_EQ(s.code(), tsm::ErrorCode::limit_exceeded);
    EXPECT_EQ(s.message(), "out of memory");
    EXPECT_EQ(failed, 5u);
    s = tsm::parallel_for(8, threads, [](size_t i) { if (i % 3 == 2) throw std::runtime_error("task trouble"); },
                          &failed);
    EXPECT_EQ(s.code(), tsm::ErrorCode::internal);
    EXPECT_NE(s.message().find("task trouble"), std::string::npos) << s.message();
    EXPECT_EQ(failed, 2u);  // the lowest index that failed
    s = tsm::parallel_for(8, threads, [](size_t) { throw 42; });
    EXPECT_EQ(s.code(), tsm::ErrorCode::internal);
  }
}

// A segment's task throwing, in the decoder and the encoder, with threads
// and without.
TEST(Parallel, ThrowingSegmentIsAnErrorNotATermination) {
  const tsm::Mesh m = tsm_test::icosphere(3);
  tsm::EncodeOptions eo;
  eo.segment_faces = 300;
  eo.threads = 2;
  std::string bytes;
  ASSERT_TRUE(tsm::encode(m, eo, bytes).ok());
  tsm::FileInfo fi;
  ASSERT_TRUE(tsm::inspect(bytes, fi).ok());
  ASSERT_GE(fi.segment_count, 3u);
  for (int threads : {1, 2}) {
    SCOPED_TRACE("threads " + std::to_string(threads));
    tsm::DecodeOptions dopt;
    dopt.threads = threads;
    eo.threads = threads;
    {
      HookGuard hook([](size_t i) {
        if (i == 1) throw std::bad_alloc();
      });
      tsm::Mesh out;
      tsm::Status s = tsm::decode(bytes, out, dopt);
      EXPECT_EQ(s.code(), tsm::ErrorCode::limit_exceeded);
      EXPECT_EQ(s.message(), "segment 1: out of memory");
      std::string again;
      s = tsm::encode(m, eo, again);
      EXPECT_EQ(s.code(), tsm::ErrorCode::limit_exceeded);
      EXPECT_NE(s.message().find("out of memory"), std::string::npos) << s.message();
    }
    {
      HookGuard hook([](size_t i) {
        if (i == 2) throw std::logic_error("injected");
      });
      tsm::Mesh out;
      const tsm::Status s = tsm::decode(bytes, out, dopt);
      EXPECT_EQ(s.code(), tsm::ErrorCode::internal);
      EXPECT_NE(s.message().find("segment 2: unexpected exception: injected"), std::string::npos) << s.message();
    }
    // The hook gone, the same calls succeed.
    tsm::Mesh out;
    EXPECT_TRUE(tsm::decode(bytes, out, dopt).ok());
  }
}

}  // namespace

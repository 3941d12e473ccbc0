// Small helpers shared by the tsm tool's commands.
#pragma once
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "tsm/status.hpp"

namespace tsm::cli {

// Exit codes: distinct classes of failure for scripts.
enum Exit : int {
  kExitOk = 0,
  kExitUsage = 2,      // bad command line
  kExitBadInput = 3,   // input file malformed, corrupt, unsupported or over a limit
  kExitIo = 4,         // cannot read or write a file
  kExitInternal = 5,   // a bug in tsm
};
int exit_code_for(const Status& s);

class Stopwatch {
 public:
  Stopwatch() : t0_(std::chrono::steady_clock::now()) {}
  double ms() const { return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0_).count(); }
  void reset() { t0_ = std::chrono::steady_clock::now(); }

 private:
  std::chrono::steady_clock::time_point t0_;
};

std::string json_escape(const std::string& s);
// 1234567 -> "1,234,567"
std::string thousands(unsigned long long n);
std::string fixed(double v, int decimals);
// printf into a std::string.
std::string strf(const char* format, ...) __attribute__((format(printf, 1, 2)));

// The corpus folder beside the source tree (TSM_CORPUS overrides), or "".
std::string default_corpus_dir();
// The default mesh for demos: data/dragon_vrip.ply in the source tree, or "".
std::string default_mesh_path();

int run_bench(const std::vector<std::string>& meshes, bool json, const std::vector<int>& qbits,
              int runs, int level, bool quiet);

}  // namespace tsm::cli

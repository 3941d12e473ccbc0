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

// The inside of a JSON string (without the quotes), made by the JSON
// library: bytes that are not valid UTF-8 become U+FFFD (the replacement
// character), so the JSON is always valid (a file name that is not UTF-8
// shows with U+FFFD in place of its odd bytes).
std::string json_escape(const std::string& s);
// Text for the terminal: control characters (C0, DEL, C1) and bytes that
// are not valid UTF-8 are shown as \xNN, never sent raw (a file's content or
// name cannot move the cursor or garble the terminal).
std::string printable(const std::string& s);
// "1 face", "2 faces", "1,234 faces".
std::string count_of(unsigned long long n, const char* one, const char* many);
// A duration for people: "12 ms" below a second, "1.3 s" above.
std::string duration_text(double ms);
// 1234567 -> "1,234,567"
std::string thousands(unsigned long long n);
std::string fixed(double v, int decimals);
// printf into a std::string.
std::string strf(const char* format, ...) __attribute__((format(printf, 1, 2)));

// The corpus folder beside the source tree (TSM_CORPUS overrides), or "".
std::string default_corpus_dir();
// The default mesh for demos: data/dragon_vrip.ply in the source tree, or "".
std::string default_mesh_path();

// simplify_bounds: percentages of the diagonal for the simplification table
// (none: no table).
int run_bench(const std::vector<std::string>& meshes, bool json, const std::vector<int>& qbits,
              int runs, int level, bool quiet, bool browser, const std::vector<double>& simplify_bounds);

}  // namespace tsm::cli

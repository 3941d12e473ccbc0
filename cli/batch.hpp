// The tool's batch machinery: many files on a pool of worker threads, results
// reported in input order, a progress bar on a terminal, JSON lines, and
// interruption (Ctrl-C, SIGTERM, SIGHUP) that never leaves a temporary or a
// partial file behind.
#pragma once
#include <nlohmann/json.hpp>

#include <atomic>
#include <cstdio>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "tsm/status.hpp"

namespace tsm::cli {

// What one file's job gives back.
struct FileResult {
  Status status;      // ok, or the error (its message names the file)
  std::string text;   // human-readable report of a success (without the final newline)
  std::string note;   // reader warnings, shown on stderr unless --quiet
  std::string json;   // one JSON object (no newline), printed with --json, success or not
};

struct BatchOptions {
  unsigned jobs = 1;            // worker threads (>= 1)
  bool quiet = false;           // no text reports, notes, progress or summary
  bool json = false;            // JSON lines on stdout instead of text reports
  bool text_to_stderr = false;  // stdout carries data (-o -): text reports go to stderr
  std::string verb;             // "encoded", "decoded", "inspected": for the batch summary
};

// Marks where a job is ("reading", "encoding", ...), for the progress bar.
class Phase {
 public:
  void set(const char* what) { what_.store(what, std::memory_order_relaxed); }
  const char* get() const { return what_.load(std::memory_order_relaxed); }

 private:
  std::atomic<const char*> what_{""};
};

// Runs work(i, phase) for every i in [0, names.size()) on options.jobs threads.
// Reports each result in input order (text or JSON on stdout, errors on
// stderr as soon as they happen), then, for more than one file, a summary and
// the list of failures on stderr. Returns the exit code: 0, or the worst
// class among the failures.
int run_batch(const std::vector<std::string>& names, const BatchOptions& options,
              const std::function<FileResult(size_t, Phase&)>& work);

// Call once, before any thread starts: SIGINT, SIGTERM and SIGHUP then wait
// for the atomic writes in progress to finish (no temporary file is left),
// stop new ones, and end the process by that signal. SIGPIPE is ignored
// (a closed stdout is an I/O error), and so is SIGXFSZ (a file size limit
// makes the write fail cleanly instead of killing the process mid-write).
void install_signal_guard();

// tsm::write_file_atomic, unless an interruption is under way (then nothing
// is written and an I/O error is returned).
Status guarded_write_file(const std::string& path, std::string_view bytes);

// Writes everything to stdout ("<stdout>" in messages).
Status write_stdout(std::string_view bytes);
// Reads stdin to its end.
Status read_stdin(std::string& out);

bool is_terminal(FILE* f);

// A JSON object built field by field with the JSON library, written on one
// line as {"a": 1, "b": "x"} (keys in the order added). Strings that are not
// valid UTF-8 (a file name in another encoding) have their odd bytes
// replaced by U+FFFD, so every line is valid JSON.
class JsonObject {
 public:
  JsonObject& str(const char* key, const std::string& value);
  JsonObject& str_or_null(const char* key, const std::string& value);  // null when empty
  JsonObject& num(const char* key, unsigned long long value);
  JsonObject& num(const char* key, double value, int decimals);         // null when not finite
  JsonObject& boolean(const char* key, bool value);
  JsonObject& null(const char* key);
  std::string done() const;

 private:
  nlohmann::ordered_json json_ = nlohmann::ordered_json::object();
};

// One line of JSON for `value`, with ", " and ": " between items (the
// layout of every JSON line the tool prints); invalid UTF-8 as U+FFFD.
std::string json_line(const nlohmann::ordered_json& value);

}  // namespace tsm::cli

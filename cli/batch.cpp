#include "batch.hpp"

#include <pthread.h>
#include <sys/ioctl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <mutex>
#include <new>
#include <shared_mutex>
#include <thread>

#include "cli_util.hpp"
#include "tsm/io.hpp"

namespace tsm::cli {

bool is_terminal(FILE* f) { return ::isatty(fileno(f)) == 1; }

// ---------------------------------------------------------------- signals

namespace {

// Shared: an atomic write in progress; exclusive: stopping. Never destroyed,
// so that a signal during exit still finds it.
std::shared_mutex& write_lock() {
  static std::shared_mutex* lock = new std::shared_mutex;
  return *lock;
}
std::atomic<bool> g_stopping{false};
mode_t g_umask = 022;                  // read once, before any thread starts

void signal_thread(sigset_t set) {
  int sig = 0;
  if (sigwait(&set, &sig) != 0) return;
  g_stopping.store(true);
  // Wait until every atomic write in progress has renamed its file into place
  // (or removed its temporary); new ones see g_stopping and write nothing.
  std::unique_lock<std::shared_mutex> lock(write_lock());
  const char* msg = "tsm: interrupted; outputs already written are complete, no partial file is left\n";
  if (::isatty(STDERR_FILENO) == 1) (void)!::write(STDERR_FILENO, "\r\x1b[K", 4);
  (void)!::write(STDERR_FILENO, msg, std::strlen(msg));
  // End by the signal itself, as the caller (a shell, make) expects.
  std::signal(sig, SIG_DFL);
  sigset_t one;
  sigemptyset(&one);
  sigaddset(&one, sig);
  pthread_sigmask(SIG_UNBLOCK, &one, nullptr);
  std::raise(sig);
  std::_Exit(128 + sig);
}

}  // namespace

void install_signal_guard() {
  static bool installed = false;
  if (installed) return;
  installed = true;
  g_umask = ::umask(0);
  ::umask(g_umask);
  write_lock();
  std::signal(SIGPIPE, SIG_IGN);
  std::signal(SIGXFSZ, SIG_IGN);
  sigset_t set;
  sigemptyset(&set);
  for (int sig : {SIGINT, SIGTERM, SIGHUP}) {
    struct sigaction now = {};
    // A signal ignored by whoever started us (nohup, a background job) stays ignored.
    if (sigaction(sig, nullptr, &now) == 0 && now.sa_handler != SIG_IGN) sigaddset(&set, sig);
  }
  // Blocked here, before any thread starts, so every thread inherits the mask
  // and only signal_thread receives them.
  pthread_sigmask(SIG_BLOCK, &set, nullptr);
  std::thread(signal_thread, set).detach();
}

Status guarded_write_file(const std::string& path, std::string_view bytes) {
  std::shared_lock<std::shared_mutex> lock(write_lock());
  if (g_stopping.load())
    return Status(ErrorCode::io_error, path + ": interrupted before writing; nothing was written");
  Status s = write_file_atomic(path, bytes);
  // write_file_atomic reads the umask by setting it (umask(0), then back),
  // which races between threads and can leave a file world-writable: give
  // the file the permissions the umask read at start-up says.
  if (s.ok()) ::chmod(path.c_str(), 0666 & ~g_umask);
  return s;
}

Status write_stdout(std::string_view bytes) {
  size_t done = 0;
  while (done < bytes.size()) {
    size_t n = std::fwrite(bytes.data() + done, 1, bytes.size() - done, stdout);
    if (n == 0) break;
    done += n;
  }
  if (std::fflush(stdout) != 0 || done != bytes.size() || std::ferror(stdout))
    return Status(ErrorCode::io_error, std::string("<stdout>: write failed after ") + std::to_string(done) + " of " +
                                           std::to_string(bytes.size()) + " bytes: " + std::strerror(errno));
  return Status::Ok();
}

Status read_stdin(std::string& out) {
  out.clear();
  char buf[1 << 16];
  size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, stdin)) > 0) out.append(buf, n);
  if (std::ferror(stdin))
    return Status(ErrorCode::io_error, std::string("<stdin>: read failed: ") + std::strerror(errno));
  return Status::Ok();
}

// ---------------------------------------------------------------- JSON

std::string json_line(const nlohmann::ordered_json& value) {
  if (value.is_object()) {
    std::string out = "{";
    for (auto it = value.begin(); it != value.end(); ++it) {
      if (out.size() > 1) out += ", ";
      out += json_line(nlohmann::ordered_json(it.key())) + ": " + json_line(it.value());
    }
    return out + "}";
  }
  if (value.is_array()) {
    std::string out = "[";
    for (const auto& item : value) {
      if (out.size() > 1) out += ", ";
      out += json_line(item);
    }
    return out + "]";
  }
  return value.dump(-1, ' ', false, nlohmann::ordered_json::error_handler_t::replace);
}

JsonObject& JsonObject::str(const char* k, const std::string& value) {
  json_[k] = value;
  return *this;
}

JsonObject& JsonObject::str_or_null(const char* k, const std::string& value) {
  if (value.empty()) return null(k);
  return str(k, value);
}

JsonObject& JsonObject::num(const char* k, unsigned long long value) {
  json_[k] = value;
  return *this;
}

JsonObject& JsonObject::num(const char* k, double value, int decimals) {
  if (!std::isfinite(value)) return null(k);
  // Rounded to `decimals` places; the library prints the shortest form.
  const double scale = std::pow(10.0, decimals);
  json_[k] = std::round(value * scale) / scale;
  return *this;
}

JsonObject& JsonObject::boolean(const char* k, bool value) {
  json_[k] = value;
  return *this;
}

JsonObject& JsonObject::null(const char* k) {
  json_[k] = nullptr;
  return *this;
}

std::string JsonObject::done() const { return json_line(json_); }

// ---------------------------------------------------------------- batch

namespace {

// A multi-line report, each line made printable.
std::string printable_lines(const std::string& text) {
  std::string out;
  size_t start = 0;
  for (;;) {
    const size_t end = text.find('\n', start);
    out += printable(text.substr(start, end == std::string::npos ? std::string::npos : end - start));
    if (end == std::string::npos) return out;
    out += '\n';
    start = end + 1;
  }
}

int terminal_width() {
  struct winsize ws = {};
  if (::ioctl(STDERR_FILENO, TIOCGWINSZ, &ws) == 0 && ws.ws_col >= 20) return ws.ws_col;
  return 80;
}

// How long work runs before the bar appears (TSM_PROGRESS_AFTER_MS, for tests).
std::chrono::milliseconds progress_delay() {
  if (const char* env = std::getenv("TSM_PROGRESS_AFTER_MS")) {
    char* end = nullptr;
    long v = std::strtol(env, &end, 10);
    if (end != env && v >= 0) return std::chrono::milliseconds(v);
  }
  return std::chrono::milliseconds(1000);
}

class Batch {
 public:
  Batch(const std::vector<std::string>& names, const BatchOptions& o) : names_(names), o_(o), phases_(names.size()) {
    results_.resize(names.size());
    ready_.assign(names.size(), false);
  }

  int run(const std::function<FileResult(size_t, Phase&)>& work) {
    const size_t n = names_.size();
    std::thread progress;
    if (!o_.quiet && n > 0 && is_terminal(stderr)) progress = std::thread([this] { progress_loop(); });
    auto worker = [&] {
      for (;;) {
        size_t i = next_.fetch_add(1);
        if (i >= n || g_stopping.load()) break;
        started_.fetch_add(1);
        current_.store(i);
        FileResult r;
        try {
          r = work(i, phases_[i]);
        } catch (const std::bad_alloc&) {
          r = FileResult();
          r.status = Status(ErrorCode::internal, names_[i] + ": out of memory");
        } catch (const std::exception& e) {
          r = FileResult();
          r.status = Status(ErrorCode::internal, names_[i] + ": internal error: " + e.what());
        }
        finish(i, std::move(r));
      }
    };
    const unsigned threads = static_cast<unsigned>(std::max<size_t>(1, std::min<size_t>(o_.jobs, n)));
    if (threads == 1) {
      worker();
    } else {
      std::vector<std::thread> pool;
      for (unsigned t = 0; t < threads; ++t) pool.emplace_back(worker);
      for (std::thread& t : pool) t.join();
    }
    {
      std::lock_guard<std::mutex> lock(mu_);
      all_done_ = true;
    }
    cv_.notify_all();
    if (progress.joinable()) progress.join();
    return summary();
  }

 private:
  // Called by the worker that finished item i.
  void finish(size_t i, FileResult r) {
    std::lock_guard<std::mutex> lock(mu_);
    done_.fetch_add(1);
    if (!r.status.ok()) {
      if (g_stopping.load()) return;  // interrupted: the signal thread says so and ends the process
      erase_bar();
      std::fprintf(stderr, "tsm: error: %s\n", printable(r.status.message()).c_str());
      std::fflush(stderr);
      failures_.emplace_back(i, r.status);
    }
    results_[i] = std::move(r);
    ready_[i] = true;
    // Reports go out in input order, whatever order the workers finish in.
    while (emitted_ < names_.size() && ready_[emitted_]) {
      emit(results_[emitted_]);
      results_[emitted_] = FileResult();
      ++emitted_;
    }
  }

  void emit(const FileResult& r) {
    if (o_.json) {
      if (!r.json.empty()) {
        erase_bar();
        std::fprintf(stdout, "%s\n", r.json.c_str());
        std::fflush(stdout);
      }
      return;
    }
    if (!r.status.ok() || o_.quiet) return;
    erase_bar();
    if (!r.note.empty()) std::fprintf(stderr, "tsm: note: %s\n", printable(r.note).c_str());
    if (!r.text.empty()) {
      FILE* f = o_.text_to_stderr ? stderr : stdout;
      std::fprintf(f, "%s\n", printable_lines(r.text).c_str());
      std::fflush(f);
    }
  }

  int summary() {
    const size_t n = names_.size();
    std::sort(failures_.begin(), failures_.end(),
              [](const auto& a, const auto& b) { return a.first < b.first; });
    int code = kExitOk;
    for (const auto& f : failures_) code = std::max(code, exit_code_for(f.second));
    if (n > 1) {
      if (!o_.quiet)
        std::fprintf(stderr, "tsm: %s %zu of %zu files in %s\n", o_.verb.c_str(), n - failures_.size(), n,
                     duration_text(sw_.ms()).c_str());
      if (!failures_.empty()) {
        std::fprintf(stderr, "tsm: %zu of %zu files failed:\n", failures_.size(), n);
        for (const auto& f : failures_) std::fprintf(stderr, "  %s\n", printable(f.second.message()).c_str());
      }
    }
    return code;
  }

  // ---- progress bar (stderr is a terminal, not --quiet)

  void erase_bar() {
    if (!bar_shown_) return;
    std::fputs("\r\x1b[K", stderr);
    bar_shown_ = false;
  }

  void progress_loop() {
    std::unique_lock<std::mutex> lock(mu_);
    const auto delay = progress_delay();
    if (delay.count() > 0 && cv_.wait_for(lock, delay, [this] { return all_done_; })) return;
    do {  // at least once after the delay (a zero delay always shows the bar, for tests)
      draw();
      cv_.wait_for(lock, std::chrono::milliseconds(100), [this] { return all_done_; });
    } while (!all_done_);
    erase_bar();
    std::fflush(stderr);
  }

  void draw() {
    const size_t n = names_.size(), done = done_.load(), started = std::max<size_t>(1, started_.load());
    const size_t cur = std::min(current_.load(), n - 1);
    std::string line = "[" + std::to_string(std::min(started, n)) + "/" + std::to_string(n) + "] ";
    if (n > 1) {
      const int width = 20;
      const int filled = static_cast<int>(static_cast<double>(width) * static_cast<double>(done) / static_cast<double>(n));
      line += "[" + std::string(static_cast<size_t>(filled), '#') + std::string(static_cast<size_t>(width - filled), '.') + "] ";
    }
    std::string name = names_[cur] == "-" ? std::string("<stdin>") : printable(std::filesystem::path(names_[cur]).filename().string());
    std::string tail;
    const char* phase = phases_[cur].get();
    if (phase && *phase) tail += std::string(" ") + phase;
    tail += "  " + fixed(sw_.ms() / 1000.0, 1) + " s";
    const size_t cols = static_cast<size_t>(terminal_width() - 1);
    if (line.size() + name.size() + tail.size() > cols) {
      size_t room = cols > line.size() + tail.size() + 3 ? cols - line.size() - tail.size() - 3 : 0;
      name = "..." + name.substr(name.size() - std::min(room, name.size()));
    }
    line += name + tail;
    if (line.size() > cols) line.resize(cols);
    std::fprintf(stderr, "\r%s\x1b[K", line.c_str());
    std::fflush(stderr);
    bar_shown_ = true;
  }

  const std::vector<std::string>& names_;
  const BatchOptions& o_;
  std::vector<Phase> phases_;
  std::vector<FileResult> results_;
  std::vector<bool> ready_;
  std::vector<std::pair<size_t, Status>> failures_;
  size_t emitted_ = 0;
  std::atomic<size_t> next_{0}, started_{0}, done_{0}, current_{0};
  std::mutex mu_;  // the console and everything above
  std::condition_variable cv_;
  bool all_done_ = false, bar_shown_ = false;
  Stopwatch sw_;
};

}  // namespace

int run_batch(const std::vector<std::string>& names, const BatchOptions& options,
              const std::function<FileResult(size_t, Phase&)>& work) {
  Batch b(names, options);
  return b.run(work);
}

}  // namespace tsm::cli

#include "cli_util.hpp"

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdarg>
#include <cstdlib>
#include <filesystem>

namespace tsm::cli {

int exit_code_for(const Status& s) {
  switch (s.code()) {
    case ErrorCode::ok: return kExitOk;
    case ErrorCode::io_error: return kExitIo;
    case ErrorCode::internal: return kExitInternal;
    case ErrorCode::invalid_argument:
    case ErrorCode::parse_error:
    case ErrorCode::corrupt_data:
    case ErrorCode::unsupported:
    case ErrorCode::limit_exceeded: return kExitBadInput;
  }
  return kExitInternal;
}

std::string json_escape(const std::string& s) {
  const std::string quoted = nlohmann::json(s).dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
  return quoted.substr(1, quoted.size() - 2);
}

namespace {
// Length of the valid UTF-8 sequence at s[i] (1 to 4), or 0 when the bytes
// there are not one (overlong forms, surrogates and values past U+10FFFF
// included).
size_t utf8_length(const std::string& s, size_t i) {
  const auto b = [&](size_t k) { return static_cast<unsigned char>(s[k]); };
  const unsigned char c = b(i);
  if (c < 0x80) return 1;
  size_t n;
  unsigned cp;
  if (c >= 0xC2 && c <= 0xDF) n = 2, cp = c & 0x1Fu;
  else if (c >= 0xE0 && c <= 0xEF) n = 3, cp = c & 0x0Fu;
  else if (c >= 0xF0 && c <= 0xF4) n = 4, cp = c & 0x07u;
  else return 0;
  if (i + n > s.size()) return 0;
  for (size_t k = 1; k < n; ++k) {
    if ((b(i + k) & 0xC0) != 0x80) return 0;
    cp = (cp << 6) | (b(i + k) & 0x3Fu);
  }
  if ((n == 3 && (cp < 0x800 || (cp >= 0xD800 && cp <= 0xDFFF))) || (n == 4 && (cp < 0x10000 || cp > 0x10FFFF)))
    return 0;
  return n;
}
}  // namespace

std::string printable(const std::string& s) {
  std::string out;
  out.reserve(s.size());
  for (size_t i = 0; i < s.size();) {
    const auto c = static_cast<unsigned char>(s[i]);
    const size_t n = utf8_length(s, i);
    // C1 controls (U+0080..U+009F) are C2 80..C2 9F in UTF-8.
    const bool control = c < 0x20 || c == 0x7F || (n == 2 && c == 0xC2 && static_cast<unsigned char>(s[i + 1]) < 0xA0);
    if (n == 0 || control) {
      const size_t bad = n == 0 ? 1 : n;
      for (size_t k = 0; k < bad; ++k) out += strf("\\x%02X", static_cast<unsigned char>(s[i + k]));
      i += bad;
    } else {
      out.append(s, i, n);
      i += n;
    }
  }
  return out;
}

std::string count_of(unsigned long long n, const char* one, const char* many) {
  return thousands(n) + " " + (n == 1 ? one : many);
}

std::string duration_text(double ms) {
  if (ms < 1000) return fixed(ms < 10 ? ms : std::round(ms), ms < 10 ? 1 : 0) + " ms";
  return fixed(ms / 1000.0, 1) + " s";
}

std::string thousands(unsigned long long n) {
  std::string s = std::to_string(n);
  for (int i = static_cast<int>(s.size()) - 3; i > 0; i -= 3) s.insert(static_cast<size_t>(i), ",");
  return s;
}

std::string fixed(double v, int decimals) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  return buf;
}

std::string strf(const char* format, ...) {
  va_list args;
  va_start(args, format);
  va_list again;
  va_copy(again, args);
  const int n = std::vsnprintf(nullptr, 0, format, args);
  va_end(args);
  std::string out;
  if (n > 0) {
    out.resize(static_cast<size_t>(n) + 1);
    std::vsnprintf(out.data(), out.size(), format, again);
    out.resize(static_cast<size_t>(n));
  }
  va_end(again);
  return out;
}

std::string default_corpus_dir() {
  if (const char* env = std::getenv("TSM_CORPUS")) return env;
  std::filesystem::path p = std::filesystem::path(TSM_SOURCE_DIR) / ".." / "shared" / "corpus";
  std::error_code ec;
  if (std::filesystem::is_directory(p, ec)) return std::filesystem::weakly_canonical(p, ec).string();
  return "";
}

std::string default_mesh_path() {
  std::filesystem::path p = std::filesystem::path(TSM_SOURCE_DIR) / "data" / "dragon_vrip.ply";
  std::error_code ec;
  if (std::filesystem::is_regular_file(p, ec)) return p.string();
  return "";
}

}  // namespace tsm::cli

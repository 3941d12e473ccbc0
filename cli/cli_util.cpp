#include "cli_util.hpp"

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
  std::string out;
  for (char c : s) {
    switch (c) {
      case '"': out += "\\\""; break;
      case '\\': out += "\\\\"; break;
      case '\n': out += "\\n"; break;
      case '\r': out += "\\r"; break;
      case '\t': out += "\\t"; break;
      default:
        if (static_cast<unsigned char>(c) < 0x20) {
          char buf[8];
          std::snprintf(buf, sizeof buf, "\\u%04x", c);
          out += buf;
        } else {
          out += c;
        }
    }
  }
  return out;
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

// Internal: a cursor over text mesh files (PLY ascii body, OBJ, STL ascii,
// OFF). Counts lines for error messages, accepts LF, CRLF and lone CR line
// ends, and parses numbers with std::from_chars (locale-free, no allocation).
#pragma once
#include <charconv>
#include <cstdint>
#include <limits>
#include <string>
#include <string_view>
#include <system_error>

#include "tsm/status.hpp"

namespace tsm {

class TextCursor {
 public:
  TextCursor(std::string_view text, const std::string& name) : p_(text.data()), end_(text.data() + text.size()), name_(name) {}

  bool at_end() const { return p_ >= end_; }
  size_t line() const { return line_; }
  const char* position() const { return p_; }
  void set_position(const char* p, size_t line) { p_ = p; line_ = line; }

  // Skips spaces and tabs (not line ends).
  void skip_blanks() { while (p_ < end_ && (*p_ == ' ' || *p_ == '\t' || *p_ == '\f' || *p_ == '\v')) ++p_; }
  // True at a line end or the end of the text (after skipping blanks).
  bool at_line_end() { skip_blanks(); return p_ >= end_ || *p_ == '\n' || *p_ == '\r'; }
  // Moves past the rest of the current line and its line end.
  void next_line() {
    while (p_ < end_ && *p_ != '\n' && *p_ != '\r') ++p_;
    consume_line_end();
  }
  // Consumes one line end (LF, CRLF or CR) if there is one.
  bool consume_line_end() {
    if (p_ >= end_) return false;
    if (*p_ == '\r') { ++p_; if (p_ < end_ && *p_ == '\n') ++p_; ++line_; return true; }
    if (*p_ == '\n') { ++p_; ++line_; return true; }
    return false;
  }
  // Skips blanks and line ends, counting lines.
  void skip_whitespace() { for (;;) { skip_blanks(); if (!consume_line_end()) return; } }
  // Next blank-separated token on this line (empty at a line end).
  std::string_view token() {
    skip_blanks();
    const char* s = p_;
    while (p_ < end_ && !is_space(*p_)) ++p_;
    return std::string_view(s, static_cast<size_t>(p_ - s));
  }
  // Rest of the current line without the line end (cursor stays on the line end).
  std::string_view rest_of_line() {
    const char* s = p_;
    while (p_ < end_ && *p_ != '\n' && *p_ != '\r') ++p_;
    return std::string_view(s, static_cast<size_t>(p_ - s));
  }

  // Numbers on the current line. Return false (cursor unspecified) when the
  // next token is missing or not a number of that type.
  template <typename T>
  bool parse_int(T& v) {
    skip_blanks();
    const char* s = p_;
    if (s < end_ && *s == '+') ++s;
    auto r = std::from_chars(s, end_, v);
    if (r.ec != std::errc() || (r.ptr < end_ && !is_space(*r.ptr))) return false;
    p_ = r.ptr;
    return true;
  }
  // Floats: also "inf", "nan" forms (callers decide whether to accept them).
  template <typename T>
  bool parse_float(T& v) {
    skip_blanks();
    const char* s = p_;
    if (s < end_ && *s == '+') ++s;
    auto r = std::from_chars(s, end_, v);
    if (r.ec == std::errc::result_out_of_range) {
      // Out of range for T: from_chars leaves v untouched; parse as the widest
      // type and let the cast give +-inf or 0, as a C reader would.
      long double w = 0;
      auto r2 = std::from_chars(s, end_, w);
      if (r2.ec != std::errc() && r2.ec != std::errc::result_out_of_range) return false;
      // Clamp first: casting an out-of-range value to a narrower type is undefined.
      const long double big = static_cast<long double>(std::numeric_limits<T>::max());
      v = w > big ? std::numeric_limits<T>::infinity() : w < -big ? -std::numeric_limits<T>::infinity() : static_cast<T>(w);
      r.ptr = r2.ptr;
    } else if (r.ec != std::errc()) {
      return false;
    }
    if (r.ptr < end_ && !is_space(*r.ptr)) return false;
    p_ = r.ptr;
    return true;
  }

  // "NAME: line N: what" as a parse_error.
  Status error(const std::string& what) const {
    return Status(ErrorCode::parse_error, name_ + ": line " + std::to_string(line_) + ": " + what);
  }
  const std::string& name() const { return name_; }

  static bool is_space(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\f' || c == '\v'; }

 private:
  const char* p_;
  const char* end_;
  size_t line_ = 1;
  const std::string& name_;
};

// A token for an error message: at most 32 characters, non-printable bytes
// shown as '?', quoted.
inline std::string quote(std::string_view s) {
  std::string out = "'";
  size_t n = s.size() < 32 ? s.size() : 32;
  for (size_t i = 0; i < n; ++i) {
    unsigned char c = static_cast<unsigned char>(s[i]);
    out.push_back(c >= 0x20 && c < 0x7f ? static_cast<char>(c) : '?');
  }
  if (n < s.size()) out += "...";
  out += "'";
  return out;
}

// "NAME: byte OFFSET: what" as a parse_error, for binary formats.
inline Status binary_error(const std::string& name, size_t offset, const std::string& what) {
  return Status(ErrorCode::parse_error, name + ": byte " + std::to_string(offset) + ": " + what);
}

}  // namespace tsm

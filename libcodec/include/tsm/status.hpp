// tsm: error reporting shared by every part of the library.
// A Status is an error code plus a human-readable message that names the
// file (when there is one), where in it, what is wrong and what to do.
#pragma once
#include <string>
#include <utility>

namespace tsm {

enum class ErrorCode : int {
  ok = 0,
  invalid_argument = 1,  // the caller asked for something impossible
  io_error = 2,          // open/read/write/rename failed
  parse_error = 3,       // a mesh file is malformed
  corrupt_data = 4,      // a .tsm stream is malformed or fails its checksum
  unsupported = 5,       // valid, but a feature this build cannot handle
  limit_exceeded = 6,    // counts above a caller-given or hard limit
  internal = 7,          // a bug in tsm
};

const char* error_code_name(ErrorCode code);

class Status {
 public:
  Status() = default;
  Status(ErrorCode code, std::string message) : code_(code), message_(std::move(message)) {}
  static Status Ok() { return Status(); }

  bool ok() const { return code_ == ErrorCode::ok; }
  ErrorCode code() const { return code_; }
  const std::string& message() const { return message_; }
  // "parse_error: bunny.ply: line 12: ..."
  std::string to_string() const;

 private:
  ErrorCode code_ = ErrorCode::ok;
  std::string message_;
};

#define TSM_RETURN_IF_ERROR(expr)          \
  do {                                     \
    ::tsm::Status tsm_status_ = (expr);    \
    if (!tsm_status_.ok()) return tsm_status_; \
  } while (0)

}  // namespace tsm

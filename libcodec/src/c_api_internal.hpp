// Internal: what both halves of the C API (c_api.cpp, c_api_encode.cpp)
// share: the mesh handle and the error reporting.
#pragma once
#include <algorithm>
#include <cstring>
#include <exception>
#include <new>
#include <string>

#include "tsm/tsm.h"
#include "tsm/tsm.hpp"

// A mesh the caller owns, or a view of the stream decoder's growing mesh.
struct tsm_mesh {
  tsm::Mesh mesh;
  const tsm::Mesh* view = nullptr;
  const tsm::Mesh& get() const { return view ? *view : mesh; }
};

namespace tsm::capi {

// Writes the message into err (NUL-terminated, truncated to err_size) and
// returns the code.
inline int report(const tsm::Status& s, char* err, size_t err_size) {
  if (err && err_size > 0) {
    std::string m = s.ok() ? "" : s.message();
    size_t n = std::min(m.size(), err_size - 1);
    std::memcpy(err, m.data(), n);
    err[n] = '\0';
  }
  return static_cast<int>(s.code());
}

template <typename F>
inline int guarded(char* err, size_t err_size, F&& f) {
  try {
    return report(f(), err, err_size);
  } catch (const std::bad_alloc&) {
    return report(tsm::Status(tsm::ErrorCode::limit_exceeded, "out of memory"), err, err_size);
  } catch (const std::exception& e) {
    return report(tsm::Status(tsm::ErrorCode::internal, e.what()), err, err_size);
  }
}

}  // namespace tsm::capi

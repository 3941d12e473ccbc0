// Shared helpers for the GoogleTest suite.
#pragma once
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "tsm/mesh.hpp"

namespace tsm_test {

// ../shared/corpus beside the project (TSM_CORPUS env overrides it).
inline std::string corpus_dir() {
  if (const char* env = std::getenv("TSM_CORPUS")) return env;
  return TSM_CORPUS_DIR;
}
inline bool have_corpus() { return std::filesystem::is_directory(corpus_dir()); }
inline std::string corpus_file(const std::string& rel) { return corpus_dir() + "/" + rel; }

// Faces as corner lists, for exact comparisons.
using Faces = std::vector<std::vector<uint32_t>>;
inline Faces faces_of(const tsm::Mesh& m) {
  Faces out;
  for (size_t f = 0; f < m.face_count(); ++f) out.emplace_back(m.face(f), m.face(f) + m.face_size(f));
  return out;
}

// A fresh empty folder under the system temp dir, removed by the destructor.
struct TempDir {
  std::filesystem::path path;
  TempDir();
  ~TempDir();
  std::string file(const std::string& name) const { return (path / name).string(); }
};

}  // namespace tsm_test

// Skips the current test with a message when ../shared/corpus is absent.
#define TSM_REQUIRE_CORPUS()                                                          \
  do {                                                                                \
    if (!tsm_test::have_corpus())                                                     \
      GTEST_SKIP() << "corpus not found at " << tsm_test::corpus_dir()                \
                   << " (clone the project beside ../shared, or set TSM_CORPUS)";     \
  } while (0)

// Shared helpers for the GoogleTest suite.
#pragma once
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <numeric>
#include <random>
#include <string>
#include <vector>

#include "tsm/compare.hpp"
#include "tsm/mesh.hpp"

namespace tsm_test {

// Built with ASan+UBSan (tests/CMakeLists.txt defines TSM_TEST_SANITIZED).
#ifdef TSM_TEST_SANITIZED
inline constexpr bool kSanitized = true;
#else
inline constexpr bool kSanitized = false;
#endif
// The number of random cases a property test runs: all of them in the plain
// build, a quarter under the sanitizers, which run about ten times slower and
// look for memory errors that the first quarter reaches as well.
inline constexpr int property_runs(int full) { return kSanitized ? (full + 3) / 4 : full; }
// Sweeps over similar cases (meshes x levels x quantizations): every case in
// the plain build; under the sanitizers the cases (a, b) with a + b even, a
// checkerboard that still runs every mesh, level and quantization once.
inline constexpr bool sanitized_skip(size_t a, size_t b) { return kSanitized && (a + b) % 2 == 1; }
// The step of a sweep that damages every k-th byte: k in the plain build,
// 4k under the sanitizers.
inline constexpr size_t sweep_stride(size_t k) { return kSanitized ? 4 * k : k; }

// ../shared/corpus beside the project (TSM_CORPUS env overrides it).
inline std::string corpus_dir() {
  if (const char* env = std::getenv("TSM_CORPUS")) return env;
  return TSM_CORPUS_DIR;
}
inline bool have_corpus() { return std::filesystem::is_directory(corpus_dir()); }
inline std::string corpus_file(const std::string& rel) { return corpus_dir() + "/" + rel; }
// The CI variable is set to a value other than "", "0" or "false" (any case).
bool running_in_ci();
// "corpus not found at DIR (...how to provide it)".
std::string corpus_missing_message();

// Decodes `bytes` with every `stride`-th byte from `from` on XORed with
// `mask`, one at a time: each decode must fail with a message or give a
// valid mesh. Returns how many were refused.
int refused_flips(const std::string& bytes, size_t stride, int mask, size_t from = 0);

// The bits of a float and back, for bit-exact comparisons.
inline uint32_t bits(float x) {
  uint32_t b;
  std::memcpy(&b, &x, 4);
  return b;
}
inline float from_bits(uint32_t b) {
  float x;
  std::memcpy(&x, &b, 4);
  return x;
}

// n pseudo-random bytes from `rng`.
inline std::string random_bytes(std::mt19937& rng, size_t n) {
  std::string s(n, '\0');
  for (char& c : s) c = static_cast<char>(rng() & 0xff);
  return s;
}

// `part` occurs in `text` (an error message, a file), with both shown if not.
inline ::testing::AssertionResult contains(const std::string& text, const std::string& part) {
  if (text.find(part) != std::string::npos) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "'" << part << "' not found in: " << text;
}

// Faces as corner lists, for exact comparisons.
using Faces = std::vector<std::vector<uint32_t>>;
inline Faces faces_of(const tsm::Mesh& m) {
  Faces out;
  for (size_t f = 0; f < m.face_count(); ++f) out.emplace_back(m.face(f), m.face(f) + m.face_size(f));
  return out;
}

// Grid indices of every coordinate (input vertex order) on the codec's grid
// for `bits`, clamped to 0 .. 2^bits - 1, as the encoder quantizes them.
inline std::vector<uint32_t> quantized_positions(const tsm::Mesh& m, int bits) {
  const tsm::Grid grid = tsm::Grid::for_mesh(m, bits);
  const int64_t qmax = (int64_t{1} << bits) - 1;
  std::vector<uint32_t> q(m.positions.size());
  for (size_t i = 0; i < q.size(); ++i) {
    int64_t x = grid.quantize(m.positions[i], static_cast<int>(i % 3));
    q[i] = static_cast<uint32_t>(x < 0 ? 0 : x > qmax ? qmax : x);
  }
  return q;
}

// A fresh empty folder under the system temp dir, removed by the destructor.
struct TempDir {
  std::filesystem::path path;
  TempDir();
  ~TempDir();
  std::string file(const std::string& name) const { return (path / name).string(); }
};

// Renumbers vertices: new vertex perm[v] is old vertex v (positions and
// faces; attributes are dropped).
inline tsm::Mesh permute_vertices(const tsm::Mesh& m, const std::vector<uint32_t>& perm) {
  tsm::Mesh out;
  out.positions.resize(m.positions.size());
  for (size_t v = 0; v < m.vertex_count(); ++v)
    for (size_t a = 0; a < 3; ++a) out.positions[3 * size_t{perm[v]} + a] = m.positions[3 * v + a];
  out.face_offsets = m.face_offsets;
  out.indices.resize(m.indices.size());
  for (size_t i = 0; i < m.indices.size(); ++i) out.indices[i] = perm[m.indices[i]];
  return out;
}

inline std::vector<uint32_t> random_permutation(size_t n, uint32_t seed) {
  std::vector<uint32_t> p(n);
  std::iota(p.begin(), p.end(), 0u);
  std::mt19937 rng(seed);
  std::shuffle(p.begin(), p.end(), rng);
  return p;
}

}  // namespace tsm_test

// Every test that reads ../shared/corpus starts with this. When the corpus is
// absent the test is skipped with a message, except in CI (the CI variable set
// to anything but "", "0" or "false"), where it fails: a CI run that skipped
// the corpus tests would pass without having checked the real meshes.
#define TSM_REQUIRE_CORPUS()                                                          \
  do {                                                                                \
    if (!tsm_test::have_corpus()) {                                                   \
      if (tsm_test::running_in_ci())                                                  \
        GTEST_FAIL() << tsm_test::corpus_missing_message()                            \
                     << "; CI is set, so a missing corpus is a failure, not a skip";  \
      GTEST_SKIP() << tsm_test::corpus_missing_message();                             \
    }                                                                                 \
  } while (0)

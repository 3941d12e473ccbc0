// Connectivity alone. Usage:
//   tsm_bench_connectivity [--runs N] [--fresh-pages] MESH...
//     linearity: encode_connectivity and decode_connectivity on each mesh,
//     medians of several runs (interleaved: run r of every mesh, then run
//     r + 1), triangles per second, and each mesh's rate relative to the
//     fastest (default: the four dragon resolutions).
//     The heap keeps freed memory between runs (glibc: arrays up to 32 MB
//     from the heap, never trimmed), so every mesh is timed on memory the
//     process already has; by default glibc maps arrays above its threshold
//     afresh and unmaps them, so only the large meshes pay the kernel's page
//     faults again on every run (--fresh-pages: that default).
//   tsm_bench_connectivity --sizes [-q BITS] MESH...
//     size: the connectivity bytes of a tsm file (`tsm info`'s figure) at the
//     default level and at -l 9 beside Draco's connectivity alone, measured
//     exactly around its edgebreaker step, at cl10 and cl7 (default: the
//     bunny and the four dragons; q = 11).
// Files from ../shared/corpus.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#ifdef __GLIBC__
#include <malloc.h>
#endif
#include <string>
#include <vector>

#include "connectivity.hpp"
#include "bench_draco.hpp"
#include "bench_timing.hpp"
#include "tsm/tsm.hpp"
#include "tsm/io.hpp"

using tsm::bench::median;
using tsm::bench::now_ms;

namespace {

bool load(const std::string& path, tsm::Mesh& m) {
  const tsm::Status s = tsm::read_mesh(path, m);
  if (!s.ok()) std::fprintf(stderr, "%s: %s\n", path.c_str(), s.to_string().c_str());
  return s.ok();
}

// tsm's connectivity bytes in a file of `mesh` at `level` (0 on failure,
// reported on stderr).
uint64_t tsm_connectivity_bytes(const tsm::Mesh& mesh, int q, int level) {
  tsm::EncodeOptions options;
  options.quantization_bits = q;
  options.level = level;
  std::string bytes;
  tsm::FileInfo info;
  tsm::Status s = tsm::encode(mesh, options, bytes);
  if (s.ok()) s = tsm::inspect(bytes, info);
  if (!s.ok()) std::fprintf(stderr, "tsm at level %d: %s\n", level, s.to_string().c_str());
  return s.ok() ? info.connectivity_bytes : 0;
}

int size_table(const std::vector<std::string>& files, int q) {
  if (!tsm::bench::draco_available()) std::fprintf(stderr, "Draco is not built in: its columns stay empty\n");
  std::printf("| mesh | vertices | tsm bytes | bits/v | tsm -l 9 bytes | bits/v | Draco cl10 bytes | bits/v | Draco cl7 bytes | bits/v | tsm / cl10 |\n");
  std::printf("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  for (const std::string& f : files) {
    tsm::Mesh m;
    if (!load(f, m)) return 3;
    m.attributes.clear();  // connectivity only; positions are what Draco is given
    const double V = static_cast<double>(m.vertex_count());
    const uint64_t t6 = tsm_connectivity_bytes(m, q, tsm::EncodeOptions().level);
    const uint64_t t9 = tsm_connectivity_bytes(m, q, 9);
    std::string error;
    const size_t d10 = tsm::bench::draco_connectivity_bytes(m, q, 10, nullptr, error);
    const size_t d7 = tsm::bench::draco_connectivity_bytes(m, q, 7, nullptr, error);
    if (!error.empty()) std::fprintf(stderr, "%s: %s\n", f.c_str(), error.c_str());
    auto bpv = [V](uint64_t b) { return V > 0 ? 8 * static_cast<double>(b) / V : 0.0; };
    std::printf("| %s | %.0f | %llu | %.3f | %llu | %.3f | %zu | %.3f | %zu | %.3f | %.3f |\n",
                f.substr(f.find_last_of('/') + 1).c_str(), V, static_cast<unsigned long long>(t6), bpv(t6),
                static_cast<unsigned long long>(t9), bpv(t9), d10, bpv(d10), d7, bpv(d7),
                d10 ? static_cast<double>(t6) / static_cast<double>(d10) : 0.0);
    std::fflush(stdout);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  int runs = 5, q = 11;
  bool sizes = false, fresh_pages = false;
  std::vector<std::string> files;
  for (int i = 1; i < argc; ++i) {
    std::string a = argv[i];
    if (a == "--runs" && i + 1 < argc) {
      runs = std::max(1, std::atoi(argv[++i]));
    } else if (a == "-q" && i + 1 < argc) {
      q = std::atoi(argv[++i]);
      if (q < 1 || q > 30) {
        std::fprintf(stderr, "-q takes 1..30 position bits, got %s\n", argv[i]);
        return 2;
      }
    } else if (a == "--sizes") {
      sizes = true;
    } else if (a == "--fresh-pages") {
      fresh_pages = true;
    } else {
      files.push_back(a);
    }
  }
#ifdef __GLIBC__
  if (!fresh_pages) {
    mallopt(M_MMAP_THRESHOLD, 32 << 20);
    mallopt(M_TRIM_THRESHOLD, 1 << 30);
  }
#endif
  if (sizes) {
    if (files.empty())
      for (const char* n : {"bun_zipper.ply", "dragon_vrip_res4.ply", "dragon_vrip_res3.ply", "dragon_vrip_res2.ply",
                            "dragon_vrip.ply"})
        files.push_back(std::string(TSM_CORPUS_DIR) + "/" + n);
    return size_table(files, q);
  }
  if (files.empty())
    for (const char* n : {"dragon_vrip_res4.ply", "dragon_vrip_res3.ply", "dragon_vrip_res2.ply", "dragon_vrip.ply"})
      files.push_back(std::string(TSM_CORPUS_DIR) + "/" + n);
  struct Row {
    std::string name;
    size_t faces;
    double enc, dec;
  };
  // Runs interleaved (run r of every mesh before run r + 1 of any): a busy
  // stretch of a shared machine then slows every mesh a little instead of
  // all runs of one mesh, which the relative columns would read as
  // non-linearity.
  std::vector<tsm::Mesh> meshes(files.size());
  for (size_t i = 0; i < files.size(); ++i)
    if (!load(files[i], meshes[i])) return 3;
  std::vector<std::vector<double>> enc(files.size()), dec(files.size());
  for (int r = 0; r < runs; ++r)
    for (size_t i = 0; i < files.size(); ++i) {
      const tsm::Mesh& m = meshes[i];
      double t0 = now_ms();
      tsm::ConnectivityEncoding ce;
      tsm::Status s = tsm::encode_connectivity(m, ce);
      enc[i].push_back(now_ms() - t0);
      if (!s.ok()) return 5;
      tsm::Mesh back;
      tsm::GeometryLayout layout;
      t0 = now_ms();
      s = tsm::decode_connectivity(ce.streams, m.vertex_count(), m.face_count(), m.corner_count(), back, layout);
      dec[i].push_back(now_ms() - t0);
      if (!s.ok()) return 5;
    }
  std::vector<Row> rows;
  for (size_t i = 0; i < files.size(); ++i)
    rows.push_back({files[i].substr(files[i].find_last_of('/') + 1), meshes[i].face_count(), median(enc[i]),
                    median(dec[i])});
  double best_enc = 0, best_dec = 0;
  for (const Row& r : rows) {
    best_enc = std::max(best_enc, static_cast<double>(r.faces) / r.enc);
    best_dec = std::max(best_dec, static_cast<double>(r.faces) / r.dec);
  }
  std::printf("| mesh | faces | encode ms | encode M tris/s | rel. | decode ms | decode M tris/s | rel. |\n");
  std::printf("|---|---:|---:|---:|---:|---:|---:|---:|\n");
  for (const Row& r : rows) {
    double e = static_cast<double>(r.faces) / r.enc, d = static_cast<double>(r.faces) / r.dec;
    std::printf("| %s | %zu | %.1f | %.2f | %.2f | %.1f | %.2f | %.2f |\n", r.name.c_str(), r.faces, r.enc, e / 1e3,
                e / best_enc, r.dec, d / 1e3, d / best_dec);
  }
  return 0;
}

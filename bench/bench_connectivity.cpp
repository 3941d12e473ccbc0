// Connectivity alone (issue 3's linearity figure): encode_connectivity and
// decode_connectivity on each mesh, medians of several runs, triangles per
// second, and each mesh's rate relative to the fastest. Usage:
//   tsm_bench_connectivity [--runs N] MESH...
// (default: the four dragon resolutions of ../shared/corpus).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "connectivity.hpp"
#include "bench_timing.hpp"
#include "tsm/io.hpp"

using tsm::bench::median;
using tsm::bench::now_ms;

int main(int argc, char** argv) {
  int runs = 5;
  std::vector<std::string> files;
  for (int i = 1; i < argc; ++i) {
    std::string a = argv[i];
    if (a == "--runs" && i + 1 < argc) {
      runs = std::max(1, std::atoi(argv[++i]));
    } else {
      files.push_back(a);
    }
  }
  if (files.empty())
    for (const char* n : {"dragon_vrip_res4.ply", "dragon_vrip_res3.ply", "dragon_vrip_res2.ply", "dragon_vrip.ply"})
      files.push_back(std::string(TSM_CORPUS_DIR) + "/" + n);
  struct Row {
    std::string name;
    size_t faces;
    double enc, dec;
  };
  std::vector<Row> rows;
  for (const std::string& f : files) {
    tsm::Mesh m;
    tsm::Status s = tsm::read_mesh(f, m);
    if (!s.ok()) {
      std::fprintf(stderr, "%s: %s\n", f.c_str(), s.to_string().c_str());
      return 3;
    }
    std::vector<double> enc, dec;
    tsm::ConnectivityEncoding ce;
    for (int r = 0; r < runs; ++r) {
      double t0 = now_ms();
      ce = tsm::ConnectivityEncoding();
      s = tsm::encode_connectivity(m, ce);
      enc.push_back(now_ms() - t0);
      if (!s.ok()) return 5;
      tsm::Mesh back;
      tsm::GeometryLayout layout;
      t0 = now_ms();
      s = tsm::decode_connectivity(ce.streams, m.vertex_count(), m.face_count(), m.corner_count(), back, layout);
      dec.push_back(now_ms() - t0);
      if (!s.ok()) return 5;
    }
    rows.push_back({f.substr(f.find_last_of('/') + 1), m.face_count(), median(enc), median(dec)});
  }
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

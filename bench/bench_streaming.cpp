// Segments and streaming: for each mesh and segment size,
// the file size and its cost against one segment, the references, decode
// time with 1 and 2 threads (medians), and streaming: the bytes that must be
// in before the first triangles come out, the time to first triangles when
// the bytes are fed as fast as they can be, and on a 10 Mbit/s link (bytes
// arriving at 1.25 MB/s, decoding overlapping the transfer). Usage:
//   tsm_bench_streaming [--runs N] [-q BITS] MESH...
// (default: dragon_vrip.ply and bun_zipper.ply of ../shared/corpus).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <thread>
#include <vector>

#include "bench_timing.hpp"
#include "tsm/tsm.hpp"
#include "tsm/io.hpp"

using tsm::bench::median;
using tsm::bench::now_ms;

namespace {

constexpr double kLinkBytesPerMs = 1250.0;  // 10 Mbit/s
constexpr size_t kChunk = 16384;

struct StreamFigures {
  size_t first_bytes = 0;      // bytes fed when the first triangles came out
  double first_ms = 0;         // fed as fast as possible: time to first triangles
  double link_first_ms = 0;    // on the link: first triangles
  double link_done_ms = 0;     // on the link: the whole mesh
};

// Feeds the file in chunks; on the link, chunk k is in at (k+1) * chunk / rate
// and decoding of what is in starts when both the bytes and the decoder are ready.
StreamFigures stream(const std::string& bytes) {
  StreamFigures f;
  tsm::StreamDecoder sd;
  const double t0 = now_ms();
  double link_clock = 0;  // simulated: when the decoder is free
  bool first = false;
  for (size_t at = 0; at < bytes.size(); at += kChunk) {
    const size_t n = std::min(kChunk, bytes.size() - at);
    const double arrived = static_cast<double>(at + n) / kLinkBytesPerMs;
    link_clock = std::max(link_clock, arrived);
    const double a = now_ms();
    if (!sd.feed(std::string_view(bytes).substr(at, n)).ok()) std::exit(1);
    link_clock += now_ms() - a;
    if (!first && sd.mesh().face_count() > 0) {
      first = true;
      f.first_bytes = at + n;
      f.first_ms = now_ms() - t0;
      f.link_first_ms = link_clock;
    }
  }
  if (!sd.finish().ok()) std::exit(1);
  f.link_done_ms = link_clock;
  return f;
}

}  // namespace

int main(int argc, char** argv) {
  int runs = 5, q = 14;
  std::vector<std::string> meshes;
  for (int i = 1; i < argc; ++i) {
    std::string a = argv[i];
    if (a == "--runs" && i + 1 < argc) runs = std::max(1, std::atoi(argv[++i]));
    else if (a == "-q" && i + 1 < argc) q = std::atoi(argv[++i]);
    else meshes.push_back(a);
  }
  if (meshes.empty()) {
    meshes.push_back(TSM_CORPUS_DIR "/dragon_vrip.ply");
    meshes.push_back(TSM_CORPUS_DIR "/bun_zipper.ply");
  }
  std::printf("Segments and streaming, q = %d, level %d, medians of %d runs, %u hardware threads; "
              "link = 10 Mbit/s (1.25 MB/s), fed in %zu-byte chunks\n\n",
              q, tsm::kDefaultLevel, runs, std::thread::hardware_concurrency(), kChunk);
  std::printf("| mesh | faces/segment | segments | bytes | vs one segment | shared vertices | decode 1 thr ms | "
              "decode 2 thr ms | speed-up | bytes before 1st triangles | 1st triangles ms (fed at once) | "
              "link: 1st triangles ms | link: whole mesh ms |\n");
  std::printf("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  for (const std::string& path : meshes) {
    tsm::Mesh m;
    tsm::Status s = tsm::read_mesh(path, m);
    if (!s.ok()) {
      std::fprintf(stderr, "%s: %s\n", path.c_str(), s.to_string().c_str());
      continue;
    }
    const std::string name = path.substr(path.find_last_of('/') + 1);
    const uint32_t whole_faces = static_cast<uint32_t>(std::max<size_t>(m.face_count(), 1));
    size_t whole_bytes = 0;
    for (uint32_t seg : {whole_faces, 0u, 1u << 17, 1u << 16, 1u << 15}) {
      tsm::EncodeOptions eo;
      eo.quantization_bits = q;
      eo.segment_faces = seg;
      std::string bytes;
      if (!tsm::encode(m, eo, bytes).ok()) return 1;
      if (seg == whole_faces) whole_bytes = bytes.size();
      tsm::FileInfo fi;
      if (!tsm::inspect(bytes, fi).ok()) return 1;
      if (seg != whole_faces && seg != 0 && fi.segment_count == 1) continue;
      double ms[2];
      for (int t = 1; t <= 2; ++t) {
        std::vector<double> v;
        tsm::DecodeOptions d;
        d.threads = t;
        for (int r = 0; r < runs; ++r) {
          tsm::Mesh back;
          const double a = now_ms();
          if (!tsm::decode(bytes, back, d).ok()) return 1;
          v.push_back(now_ms() - a);
        }
        ms[t - 1] = median(v);
      }
      std::vector<StreamFigures> sf;
      for (int r = 0; r < runs; ++r) sf.push_back(stream(bytes));
      std::vector<double> first, lfirst, ldone;
      for (const StreamFigures& f : sf) {
        first.push_back(f.first_ms);
        lfirst.push_back(f.link_first_ms);
        ldone.push_back(f.link_done_ms);
      }
      const std::string label = seg == whole_faces ? "whole" : seg == 0 ? "default (262144)" : std::to_string(seg);
      std::printf("| %s | %s | %u | %zu | %+.2f%% | %llu | %.1f | %.1f | %.2fx | %zu (%.0f%%) | %.1f | %.0f | %.0f |\n",
                  name.c_str(), label.c_str(), fi.segment_count, bytes.size(),
                  100.0 * (static_cast<double>(bytes.size()) / static_cast<double>(whole_bytes) - 1.0),
                  static_cast<unsigned long long>(fi.references), ms[0], ms[1], ms[0] / ms[1], sf[0].first_bytes,
                  100.0 * static_cast<double>(sf[0].first_bytes) / static_cast<double>(bytes.size()), median(first),
                  median(lfirst), median(ldone));
      std::fflush(stdout);
    }
  }
  return 0;
}

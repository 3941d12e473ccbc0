// The decoder library on its own (CMake target tsm_decoder): this program
// links only tsm_decoder, none of the encoder, and decodes FORMAT.md §11's
// triangle through the C++ API, the stream decoder and the C API; then,
// given `--manifest tests/golden/MANIFEST.txt`, every golden file it lists,
// checked against the hash of its decoded mesh there. Exit 0 when all decode
// as expected. ctest: decoder.links_alone.
#include <cstdio>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

#include "golden_hash.hpp"
#include "tsm/tsm.h"
#include "tsm/tsm.hpp"

namespace {

// FORMAT.md §11: (0, 0, 0), (2, 0, 0), (0, 1, 0.5), one face, at 8 bits, level 0.
const unsigned char kTriangle[] = {
    0x54, 0x53, 0x4d, 0x1a, 0x0c, 0x03, 0x01, 0x03, 0x08, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,
    0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x40, 0x14, 0x18, 0x03, 0x02, 0x05, 0x0a, 0x00, 0x0a, 0x4e, 0x04, 0x07, 0x00,
    0x04, 0x04, 0xaf, 0x70, 0x04, 0x00, 0x00, 0x00, 0x53, 0xab, 0x90, 0x70, 0x2a, 0x15, 0xf1, 0x89, 0x6e, 0xb0, 0x00};

int failures = 0;

void check(bool ok, const std::string& what) {
  if (!ok) {
    std::fprintf(stderr, "decoder_only: FAILED: %s\n", what.c_str());
    ++failures;
  }
}

bool is_triangle(const tsm::Mesh& m) {
  return m.vertex_count() == 3 && m.face_count() == 1 && m.indices == std::vector<uint32_t>{0, 1, 2} &&
         m.positions[3] == 2.0f && m.positions[7] == 128.0f * 2.0f / 255.0f;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string_view bytes(reinterpret_cast<const char*>(kTriangle), sizeof kTriangle);
  tsm::Mesh m;
  tsm::Status s = tsm::decode(bytes, m);
  check(s.ok() && is_triangle(m), "tsm::decode of the worked example: " + s.to_string());
  tsm::StreamDecoder sd;
  for (char c : bytes) s = sd.feed(std::string_view(&c, 1));
  check(s.ok() && sd.finish().ok() && is_triangle(sd.mesh()), "StreamDecoder, a byte at a time");
  tsm::FileInfo fi;
  check(tsm::inspect(bytes, fi).ok() && fi.format_version == 12 && fi.geometry_predictor == "raw",
        "tsm::inspect: format version 12, predictor raw");
  tsm_mesh* cm = nullptr;
  char err[256];
  check(tsm_decode(kTriangle, sizeof kTriangle, nullptr, &cm, err, sizeof err) == TSM_OK &&
            tsm_mesh_vertex_count(cm) == 3 && tsm_mesh_face_count(cm) == 1,
        "tsm_decode");
  tsm_mesh_free(cm);
  for (int i = 1; i + 1 < argc; i += 2) {
    if (std::string(argv[i]) != "--manifest") break;
    const std::string manifest = argv[i + 1];
    const std::string dir = manifest.substr(0, manifest.find_last_of('/') + 1);
    std::ifstream list(manifest);
    check(list.good(), manifest + ": cannot read");
    int files = 0;
    for (std::string line; std::getline(list, line);) {
      if (line.empty() || line[0] == '#') continue;
      // file mesh option... hash
      std::istringstream f(line);
      std::vector<std::string> t;
      for (std::string w; f >> w;) t.push_back(w);
      if (t.size() < 4) continue;
      const std::string& file = t[0];
      const std::string& hash = t.back();
      std::ifstream in(dir + file, std::ios::binary);
      const std::string data((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
      tsm::Mesh g;
      s = tsm::decode(data, g);
      check(s.ok() && g.valid(), file + ": " + s.to_string());
      check(tsm_golden::hex(tsm_golden::mesh_hash(g)) == hash, file + ": decoded mesh hash is not the manifest's");
      std::printf("%s: %zu vertices, %zu faces, hash %s\n", file.c_str(), g.vertex_count(), g.face_count(),
                  tsm_golden::hex(tsm_golden::mesh_hash(g)).c_str());
      ++files;
    }
    check(files > 0, manifest + ": no golden files listed");
  }
  std::printf("decoder_only: %s (tsm %s)\n", failures ? "FAILED" : "ok", tsm::version_string());
  return failures ? 1 : 0;
}

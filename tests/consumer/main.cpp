// A program outside the tsm tree that uses the installed library: found by
// find_package(tsm) (CMakeLists.txt here) or by pkg-config (tsm.pc). It
// generates a grid, encodes and decodes it (tsm::tsm), writes and reads it
// as PLY (tsm::tsm_io), and exits 0 when all of it works.
#include <cstdio>
#include <string>

#include <tsm/io.hpp>
#include <tsm/tsm.h>
#include <tsm/tsm.hpp>
#include <tsm/version.h>

static int fail(const char* what, const tsm::Status& status) {
  std::fprintf(stderr, "consumer: %s: %s\n", what, status.message().c_str());
  return 1;
}

int main(int argc, char** argv) {
  if (std::string(tsm::version_string()) != TSM_VERSION_STRING) {
    std::fprintf(stderr, "consumer: library %s, header %s\n", tsm::version_string(), TSM_VERSION_STRING);
    return 1;
  }
  const uint32_t n = 20;  // (n+1)^2 vertices, 2 n^2 triangles
  tsm::Mesh mesh;
  for (uint32_t y = 0; y <= n; ++y)
    for (uint32_t x = 0; x <= n; ++x) {
      mesh.positions.push_back(float(x));
      mesh.positions.push_back(float(y));
      mesh.positions.push_back(float((x * y) % 7) * 0.25f);
    }
  for (uint32_t y = 0; y < n; ++y)
    for (uint32_t x = 0; x < n; ++x) {
      uint32_t a = y * (n + 1) + x, b = a + 1, c = a + n + 1, d = c + 1;
      for (uint32_t v : {a, b, d, a, d, c}) mesh.indices.push_back(v);
      mesh.face_offsets.push_back(uint32_t(mesh.indices.size() - 3));
      mesh.face_offsets.push_back(uint32_t(mesh.indices.size()));
    }
  std::string bytes;
  if (auto s = tsm::encode(mesh, tsm::EncodeOptions{}, bytes); !s.ok()) return fail("encode", s);
  tsm::Mesh back;
  if (auto s = tsm::decode(bytes, back); !s.ok()) return fail("decode", s);
  if (back.vertex_count() != mesh.vertex_count() || back.face_count() != mesh.face_count()) {
    std::fprintf(stderr, "consumer: decoded %zu vertices %zu faces, expected %zu %zu\n", size_t(back.vertex_count()),
                 size_t(back.face_count()), size_t(mesh.vertex_count()), size_t(mesh.face_count()));
    return 1;
  }
  const std::string ply = argc > 1 ? argv[1] : "consumer.ply";
  if (auto s = tsm::write_mesh(ply, back); !s.ok()) return fail("write_mesh", s);
  tsm::Mesh read;
  if (auto s = tsm::read_mesh(ply, read); !s.ok()) return fail("read_mesh", s);
  if (read.face_count() != mesh.face_count()) {
    std::fprintf(stderr, "consumer: read %zu faces back, expected %zu\n", size_t(read.face_count()),
                 size_t(mesh.face_count()));
    return 1;
  }
  std::printf("consumer: tsm %s, %zu faces in %zu bytes, round trip ok\n", TSM_VERSION_STRING,
              size_t(mesh.face_count()), bytes.size());
  return 0;
}

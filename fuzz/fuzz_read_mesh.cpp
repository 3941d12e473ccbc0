// libFuzzer target: every mesh reader (format sniffed from the bytes) on
// arbitrary input; an accepted mesh must be valid and survive a PLY round trip.
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "tsm/io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::string_view bytes(reinterpret_cast<const char*>(data), size);
  tsm::Mesh mesh;
  tsm::ReadOptions options;
  options.max_vertices = 1u << 20;
  options.max_faces = 1u << 20;
  for (tsm::MeshFormat f : {tsm::MeshFormat::ply, tsm::MeshFormat::obj, tsm::MeshFormat::stl, tsm::MeshFormat::off}) {
    if (!tsm::read_mesh_from_memory(bytes, "fuzz", mesh, options, nullptr, f).ok()) continue;
    if (!mesh.valid()) __builtin_trap();
    std::string ply;
    tsm::Mesh back;
    if (!tsm::write_ply(mesh, tsm::WriteOptions{}, ply).ok()) continue;
    tsm::ReadOptions all;
    all.allow_nonfinite = true;
    if (!tsm::read_ply(ply, "fuzz.ply", back, all, nullptr).ok()) __builtin_trap();
    if (back.indices != mesh.indices || back.positions.size() != mesh.positions.size()) __builtin_trap();
  }
  return 0;
}

// libFuzzer target: every mesh reader (PLY, OBJ, STL, OFF, glTF / GLB with
// its pass-through entry, and the sniffer) on arbitrary bytes. An accepted
// mesh must be valid; it must survive the writers exactly (binary PLY, ascii
// PLY and OBJ give back bit-identical positions and identical faces, as
// io.hpp and io_obj.cpp promise; what the glTF writer accepts, .gltf and
// .glb, its reader gives back with the same faces and positions); and,
// when small, it must round-trip through the codec under the oracle
// tsm::compare_meshes (readers make meshes with arbitrary float positions, a
// good test of the geometry coder). Any violation aborts.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <string>
#include <string_view>

#include "tsm/io.hpp"
#include "tsm/compare.hpp"
#include "tsm/tsm.hpp"

namespace {

[[noreturn]] void fail(const std::string& what) {
  std::fprintf(stderr, "fuzz_read_mesh: %s\n", what.c_str());
  __builtin_trap();
}

bool same(const tsm::Mesh& a, const tsm::Mesh& b) {
  return a.indices == b.indices && a.face_offsets == b.face_offsets && a.positions.size() == b.positions.size() &&
         (a.positions.empty() ||
          std::memcmp(a.positions.data(), b.positions.data(), a.positions.size() * sizeof(float)) == 0);
}

void check_writers(const tsm::Mesh& mesh, const char* format) {
  tsm::ReadOptions all;
  all.allow_nonfinite = true;
  for (bool ascii : {false, true}) {
    std::string ply;
    tsm::WriteOptions wo;
    wo.ascii = ascii;
    if (!tsm::write_ply(mesh, wo, ply).ok()) continue;
    tsm::Mesh back;
    tsm::Status s = tsm::read_ply(ply, "fuzz.ply", back, all, nullptr);
    if (!s.ok()) fail(std::string(format) + ": the PLY writer wrote what the reader refuses: " + s.to_string());
    if (!same(mesh, back)) fail(std::string(format) + ": PLY write + read changed the mesh");
  }
  std::string obj;
  if (tsm::write_obj(mesh, obj).ok()) {
    tsm::Mesh back;
    tsm::Status s = tsm::read_obj(obj, "fuzz.obj", back, all, nullptr);
    if (!s.ok()) fail(std::string(format) + ": the OBJ writer wrote what the reader refuses: " + s.to_string());
    if (!same(mesh, back)) fail(std::string(format) + ": OBJ write + read changed the mesh");
  }
  for (bool binary : {false, true}) {
    std::string gltf;
    // Refusals are documented (polygons, face and corner attributes,
    // non-finite positions, an entry that does not fit the mesh).
    if (!tsm::write_gltf(mesh, tsm::WriteOptions{}, gltf, binary).ok()) continue;
    tsm::Mesh back;
    tsm::Status s = tsm::read_gltf(gltf, binary ? "fuzz.glb" : "fuzz.gltf", back, all, nullptr);
    if (!s.ok()) fail(std::string(format) + ": the glTF writer wrote what the reader refuses: " + s.to_string());
    if (!same(mesh, back)) fail(std::string(format) + ": glTF write + read changed the mesh");
  }
}

void check_codec(const tsm::Mesh& mesh, const char* format) {
  if (mesh.vertex_count() > 4096 || mesh.corner_count() > 16384 || !mesh.all_finite()) return;
  // At level 2 (the fan predictor, table-coded residuals): the default
  // level's geometry trials took most of an execution's time under the
  // sanitizers; fuzz_roundtrip runs every level.
  std::string bytes;
  tsm::Status s = tsm::encode(mesh, tsm::EncodeOptions{tsm::kDefaultQuantizationBits, 2}, bytes);
  if (!s.ok()) {
    // The one refusal a valid finite mesh can get: a bounding box wider than a float.
    if (s.code() == tsm::ErrorCode::invalid_argument && tsm::bounding_box(mesh).largest_extent() > 3.4e38) return;
    fail(std::string(format) + ": encode refused a read mesh: " + s.to_string());
  }
  tsm::Mesh back;
  s = tsm::decode(bytes, back);
  if (!s.ok()) fail(std::string(format) + ": decode refused the encoder's output: " + s.to_string());
  tsm::CompareResult cr = tsm::compare_meshes(mesh, back, tsm::kDefaultQuantizationBits);
  if (!cr.equal) fail(std::string(format) + ": oracle: the decoded mesh differs: " + cr.difference);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  tsm::ReadOptions options;
  options.max_vertices = 1u << 20;
  options.max_faces = 1u << 20;
  (void)tsm::sniff_format(bytes);
  for (tsm::MeshFormat f : {tsm::MeshFormat::unknown, tsm::MeshFormat::ply, tsm::MeshFormat::obj, tsm::MeshFormat::stl,
                            tsm::MeshFormat::off, tsm::MeshFormat::gltf}) {
    tsm::Mesh mesh;
    tsm::ReadInfo info;
    tsm::Status s = tsm::read_mesh_from_memory(bytes, "fuzz", mesh, options, &info, f);
    if (s.code() == tsm::ErrorCode::internal) fail("a reader reported an internal error: " + s.to_string());
    if (!s.ok()) {
      if (s.message().empty()) fail("a reader failed without a message");
      continue;
    }
    const char* name = tsm::mesh_format_name(f);
    std::string why;
    if (!mesh.valid(&why)) fail(std::string(name) + ": read an invalid mesh: " + why);
    if (!mesh.all_finite()) fail(std::string(name) + ": read non-finite positions without allow_nonfinite");
    check_writers(mesh, name);
    if (f == tsm::MeshFormat::unknown) check_codec(mesh, name);  // once per input is enough
  }
  return 0;
}

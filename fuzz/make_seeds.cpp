// Seed corpus generator for the fuzz targets (run by fuzz/run.sh; seeds are
// generated, never committed):
//
//   fuzz_seeds OUT_DIR
//
// writes OUT_DIR/fuzz_decode/      .tsm files of generated meshes (sphere,
//                                  torus, grid with holes, quads, non-manifold
//                                  fan and book, Moebius strip, soup, point
//                                  set, ...) at a few quantizations and levels
//        OUT_DIR/fuzz_read_mesh/   the same kind of meshes as small PLY
//                                  (ascii, binary little and big endian), OBJ,
//                                  STL (ascii, binary), OFF, glTF and GLB,
//                                  plus hand-written files with the awkward
//                                  forms (a glTF document with two meshes,
//                                  materials, nodes, an image and a morph
//                                  target: the pass-through entry)
//        OUT_DIR/fuzz_roundtrip/   those meshes in fuzz_roundtrip's input
//                                  layout
// and, when ../shared/corpus exists, its small files (read seeds, and encoded
// as decode seeds). Everything is deterministic.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "base64.hpp"
#include "mesh_gen.hpp"
#include "tsm/gltf_transcode.hpp"
#include "tsm/io.hpp"
#include "tsm/tsm.hpp"

namespace fs = std::filesystem;

namespace {

int written = 0;

void put(const fs::path& dir, const std::string& name, const std::string& bytes) {
  std::ofstream f(dir / name, std::ios::binary | std::ios::trunc);
  f.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  if (!f) {
    std::fprintf(stderr, "fuzz_seeds: cannot write %s\n", (dir / name).string().c_str());
    std::exit(1);
  }
  ++written;
}

tsm::Mesh torus(int rings, int sides) {
  tsm::Mesh m;
  const double pi = 3.14159265358979323846;
  for (int i = 0; i < rings; ++i)
    for (int j = 0; j < sides; ++j) {
      double u = 2 * pi * i / rings, v = 2 * pi * j / sides;
      m.add_vertex(static_cast<float>((2 + 0.7 * std::cos(v)) * std::cos(u)),
                   static_cast<float>((2 + 0.7 * std::cos(v)) * std::sin(u)), static_cast<float>(0.7 * std::sin(v)));
    }
  auto at = [&](int i, int j) { return static_cast<uint32_t>((i % rings) * sides + (j % sides)); };
  for (int i = 0; i < rings; ++i)
    for (int j = 0; j < sides; ++j) {
      m.add_triangle(at(i, j), at(i + 1, j), at(i + 1, j + 1));
      m.add_triangle(at(i, j), at(i + 1, j + 1), at(i, j + 1));
    }
  return m;
}

tsm::Mesh quad_grid(int n) {
  tsm::Mesh m;
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x)
      m.add_vertex(static_cast<float>(x), static_cast<float>(y), 0.25f * static_cast<float>(x % 2));
  for (int y = 0; y + 1 < n; ++y)
    for (int x = 0; x + 1 < n; ++x) {
      uint32_t q[4] = {static_cast<uint32_t>(y * n + x), static_cast<uint32_t>(y * n + x + 1),
                       static_cast<uint32_t>((y + 1) * n + x + 1), static_cast<uint32_t>((y + 1) * n + x)};
      m.add_face(q, 4);
    }
  return m;
}

// Non-manifold fan: a closed fan plus two extra triangles on one of its
// edges, and a third on its apex alone.
tsm::Mesh nonmanifold_fan() {
  tsm::Mesh m = tsm_test::fan(8, true);
  uint32_t apex = 0, rim = 1;
  uint32_t a = static_cast<uint32_t>(m.vertex_count());
  m.add_vertex(0.2f, 0.3f, 1.0f);
  m.add_vertex(0.1f, -0.3f, -1.0f);
  m.add_vertex(3.0f, 3.0f, 0.5f);
  m.add_vertex(3.0f, 2.0f, 0.5f);
  m.add_triangle(apex, rim, a);
  m.add_triangle(rim, apex, a + 1);
  m.add_triangle(apex, a + 2, a + 3);
  return m;
}

tsm::Mesh point_set(int n) {
  tsm::Mesh m;
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> d(-3, 4);
  for (int i = 0; i < n; ++i) m.add_vertex(d(rng), d(rng), d(rng));
  return m;
}

struct Named {
  std::string name;
  tsm::Mesh mesh;
};

std::vector<Named> meshes() {
  std::vector<Named> out;
  out.push_back({"sphere", tsm_test::icosphere(2)});
  out.push_back({"sphere1", tsm_test::icosphere(1)});
  out.push_back({"torus", torus(12, 8)});
  out.push_back({"genus2", tsm_test::genus_surface(2, 1)});
  out.push_back({"grid_holes", tsm_test::grid_with_holes(10, 2)});
  out.push_back({"quads", quad_grid(6)});
  out.push_back({"cube_quads", tsm_test::cube_quads()});
  out.push_back({"ngon", tsm_test::ngon(7)});
  out.push_back({"nm_fan", nonmanifold_fan()});
  out.push_back({"book", tsm_test::book(5)});
  out.push_back({"bowtie", tsm_test::bowtie()});
  out.push_back({"moebius", tsm_test::moebius(8)});
  out.push_back({"flipped", tsm_test::flipped_face_sphere(1)});
  out.push_back({"soup", tsm_test::random_soup(40, 60, 3)});
  out.push_back({"copies", tsm_test::copies(tsm_test::cube_quads(), 3)});
  out.push_back({"double_sided", tsm_test::double_sided(tsm_test::icosphere(1))});  // stitch targets by candidates
  out.push_back({"points", point_set(30)});
  tsm::Mesh one;
  one.add_vertex(1.5f, -2.0f, 3.25f);
  out.push_back({"point", one});
  out.push_back({"empty", tsm::Mesh()});
  return out;
}

// --- writers the library does not have (STL, OFF, big-endian PLY) ---------

void le32(std::string& s, uint32_t v) {
  for (int i = 0; i < 4; ++i) s.push_back(static_cast<char>(v >> (8 * i)));
}
void be32(std::string& s, uint32_t v) {
  for (int i = 3; i >= 0; --i) s.push_back(static_cast<char>(v >> (8 * i)));
}
uint32_t bits(float f) {
  uint32_t b;
  std::memcpy(&b, &f, 4);
  return b;
}
std::string num(float f) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.9g", static_cast<double>(f));
  return buf;
}

// Triangles of the mesh (polygons fan-split, faces under 3 corners dropped).
std::vector<uint32_t> triangles(const tsm::Mesh& m) {
  std::vector<uint32_t> t;
  for (size_t f = 0; f < m.face_count(); ++f)
    for (uint32_t i = 2; i < m.face_size(f); ++i) t.insert(t.end(), {m.face(f)[0], m.face(f)[i - 1], m.face(f)[i]});
  return t;
}

std::string stl_ascii(const tsm::Mesh& m) {
  std::string s = "solid seed\n";
  std::vector<uint32_t> t = triangles(m);
  for (size_t i = 0; i < t.size(); i += 3) {
    s += "  facet normal 0 0 1\n    outer loop\n";
    for (int c = 0; c < 3; ++c) {
      const float* p = &m.positions[3 * t[i + static_cast<size_t>(c)]];
      s += "      vertex " + num(p[0]) + " " + num(p[1]) + " " + num(p[2]) + "\n";
    }
    s += "    endloop\n  endfacet\n";
  }
  return s + "endsolid seed\n";
}

std::string stl_binary(const tsm::Mesh& m) {
  std::string s(80, ' ');
  std::vector<uint32_t> t = triangles(m);
  le32(s, static_cast<uint32_t>(t.size() / 3));
  for (size_t i = 0; i < t.size(); i += 3) {
    for (int k = 0; k < 3; ++k) le32(s, bits(k == 2 ? 1.0f : 0.0f));
    for (int c = 0; c < 3; ++c)
      for (int a = 0; a < 3; ++a)
        le32(s, bits(m.positions[3 * t[i + static_cast<size_t>(c)] + static_cast<size_t>(a)]));
    s += std::string(2, '\0');
  }
  return s;
}

std::string off(const tsm::Mesh& m) {
  std::string s = "OFF\n# seed\n" + std::to_string(m.vertex_count()) + " " + std::to_string(m.face_count()) + " 0\n";
  for (size_t v = 0; v < m.vertex_count(); ++v)
    s += num(m.positions[3 * v]) + " " + num(m.positions[3 * v + 1]) + " " + num(m.positions[3 * v + 2]) + "\n";
  for (size_t f = 0; f < m.face_count(); ++f) {
    s += std::to_string(m.face_size(f));
    for (uint32_t i = 0; i < m.face_size(f); ++i) s += " " + std::to_string(m.face(f)[i]);
    s += "\n";
  }
  return s;
}

std::string ply_big_endian(const tsm::Mesh& m) {
  std::string s = "ply\nformat binary_big_endian 1.0\ncomment seed\nelement vertex " +
                  std::to_string(m.vertex_count()) +
                  "\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\nelement face " +
                  std::to_string(m.face_count()) + "\nproperty list uchar int vertex_indices\nend_header\n";
  for (size_t v = 0; v < m.vertex_count(); ++v) {
    for (int a = 0; a < 3; ++a) be32(s, bits(m.positions[3 * v + static_cast<size_t>(a)]));
    s.push_back('\x7f');
  }
  for (size_t f = 0; f < m.face_count(); ++f) {
    s.push_back(static_cast<char>(m.face_size(f)));
    for (uint32_t i = 0; i < m.face_size(f); ++i) be32(s, m.face(f)[i]);
  }
  return s;
}

// Hand-written inputs with the forms the readers have to accept (or refuse).
void handwritten(const fs::path& dir) {
  put(dir, "hand_ascii_extra.ply",
      "ply\r\nformat ascii 1.0\r\ncomment made by hand\r\nobj_info x\r\nelement vertex 4\r\n"
      "property double x\r\nproperty double y\r\nproperty double z\r\nproperty list uchar float normals\r\n"
      "property uchar alpha\r\nelement face 2\r\nproperty list ushort uint vertex_index\r\n"
      "property int flags\r\nelement edge 1\r\nproperty int vertex1\r\nproperty int vertex2\r\nend_header\r\n"
      "0 0 0 3 0 0 1 255\r\n1 0 0 0 255\r\n1 1 0 1 0.5 7\r\n0 1 1e-3 2 1 1 0\r\n"
      "3 0 1 2 9\r\n4 0 2 3 1 0\r\n0 1\r\n");
  put(dir, "hand_types.ply",
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty int8 x\nproperty uint16 y\nproperty float64 z\n"
      "element face 1\nproperty list uint8 int32 vertex_indices\nend_header\n-1 2 3.5\n4 5 -6\n7 8 9\n3 0 1 2\n");
  put(dir, "hand_forms.obj",
      "# hand\nmtllib x.mtl\no thing\ng a b\nv 0 0 0\nv 1 0 0 1.0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvn 0 0 1\n"
      "usemtl m\ns off\nf 1/1/1 2/2/1 3//1\nf -4 -2 -1\nf 1 \\\n 3 4\nl 1 2\np 3\nf 4/2 3/1 2/1 1/2\n"
      "f 2 4 5\nv 2 2 2\n");
  put(dir, "hand_points.obj", "v 1 2 3\nv 4 5 6\nv -1e30 1e-30 0\n");
  put(dir, "hand_color.off",
      "COFF\n# comment\n4 2 6\n0 0 0 255 0 0 255\n1 0 0 0 255 0 255\n1 1 0 0 0 255 255\n0 1 0 1 1 1 1\n"
      "3 0 1 2 1 0 0\n4 0 2 3 1\n");
  put(dir, "hand_noff.off", "NOFF\n3 1 0\n0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n3 0 1 2\n");
  put(dir, "hand_named.stl",
      "solid named thing\nfacet normal 0 0 0\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\n"
      "endfacet\nfacet normal 0 0 0\nouter loop\nvertex 1 0 0\nvertex 0 1 0\nvertex 1 1 0\nendloop\nendfacet\n"
      "endsolid named thing\n");
}

// A .gltf document as exporters write it: two meshes (one with two
// primitives sharing a POSITION accessor, one with a morph target), three
// materials, a node tree with a transform, a camera, an image in a buffer
// view, extras and an extension; read_gltf keeps all but the geometry in the
// "gltf" metadata entry and the writer rebuilds it.
std::string gltf_document() {
  std::string bin;
  auto f32 = [&](float f) { bin.append(reinterpret_cast<const char*>(&f), 4); };
  auto u16 = [&](uint16_t v) { bin.append(reinterpret_cast<const char*>(&v), 2); };
  const float quad[4][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  for (auto& p : quad) for (float c : p) f32(c);                  // 0: positions, 48 bytes
  for (int i : {0, 1, 2, 0, 2, 3}) u16(static_cast<uint16_t>(i));  // 48: indices, 12 bytes
  for (auto& p : quad) { f32(p[0]); f32(p[1]); f32(0.5f); }       // 60: second mesh, 48 bytes
  for (int i = 0; i < 4; ++i) { f32(0); f32(0); f32(0.25f * static_cast<float>(i)); }  // 108: morph, 48 bytes
  bin += "\x89PNG\r\n\x1a\n0000";                                 // 156: image, 12 bytes
  return std::string(R"({"asset":{"version":"2.0","generator":"fuzz_seeds"},"scene":0,)") +
         R"("scenes":[{"nodes":[0]}],"nodes":[{"children":[1,2],"translation":[1,2,3]},{"mesh":0},)" +
         R"({"mesh":1,"matrix":[1,0,0,0,0,1,0,0,0,0,1,0,0,0,0,1],"camera":0}],)" +
         R"("cameras":[{"type":"perspective","perspective":{"yfov":1.0,"znear":0.1}}],)" +
         R"("meshes":[{"primitives":[{"attributes":{"POSITION":0},"indices":1,"material":0},)" +
         R"({"attributes":{"POSITION":0},"indices":2,"material":1}]},)" +
         R"({"primitives":[{"attributes":{"POSITION":3},"indices":2,"targets":[{"POSITION":4}],"mode":4,"material":2}],)" +
         R"("weights":[0.5]}],)" +
         R"("materials":[{"name":"a"},{"name":"b","doubleSided":true},{"pbrMetallicRoughness":{"baseColorTexture":{"index":0}}}],)" +
         R"("textures":[{"source":0}],"images":[{"bufferView":3,"mimeType":"image/png"}],)" +
         R"("accessors":[{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3","min":[0,0,0],"max":[1,1,0]},)" +
         R"({"bufferView":1,"componentType":5123,"count":3,"type":"SCALAR"},)" +
         R"({"bufferView":1,"byteOffset":6,"componentType":5123,"count":3,"type":"SCALAR"},)" +
         R"({"bufferView":2,"componentType":5126,"count":4,"type":"VEC3","min":[0,0,0.5],"max":[1,1,0.5]},)" +
         R"({"bufferView":2,"byteOffset":48,"componentType":5126,"count":4,"type":"VEC3","min":[0,0,0],"max":[0,0,0.75]}],)" +
         R"("bufferViews":[{"buffer":0,"byteLength":48},{"buffer":0,"byteOffset":48,"byteLength":12},)" +
         R"({"buffer":0,"byteOffset":60,"byteLength":96},{"buffer":0,"byteOffset":156,"byteLength":12}],)" +
         R"("buffers":[{"byteLength":168,"uri":"data:application/octet-stream;base64,)" + tsm_test::base64(bin) + R"("}],)" +
         R"("extensionsUsed":["EXT_x"],"extensions":{"EXT_x":{"a":1}},"extras":{"k":[1,"two",null]}})";
}

void gltf_seeds(const fs::path& dir, const std::string& name, const tsm::Mesh& m) {
  std::string s;
  if (tsm::write_gltf(m, tsm::WriteOptions{}, s, false).ok()) put(dir, name + ".gltf", s);
  if (tsm::write_gltf(m, tsm::WriteOptions{}, s, true).ok()) put(dir, name + ".glb", s);
}

// fuzz_gltf_transcode: a small plain .glb and the same compressed by tsm
// (TSM_mesh_compression), level 2 as the target encodes.
void transcode_seeds(const fs::path& dir, const std::string& name, const std::string& glb) {
  put(dir, name + "_plain.glb", glb);
  tsm::GltfTranscodeOptions options;
  options.encode.level = 2;
  options.encode.threads = 1;
  tsm::GltfOutput out;
  if (tsm::transcode_gltf(glb, name, "", options, true, "", out).ok()) put(dir, name + "_tsm.glb", out.main);
}

void roundtrip_seed(const fs::path& dir, const Named& n) {
  const tsm::Mesh& m = n.mesh;
  if (m.vertex_count() == 0 || m.vertex_count() > 256) return;
  for (size_t f = 0; f < m.face_count(); ++f)
    if (m.face_size(f) < 1 || m.face_size(f) > 6) return;
  const int variants[][3] = {{13, 0x46, 10}, {3, 0x13, 40}, {29, 0x29, 60}, {7, 0x70, 163}};
  for (int v = 0; v < 4; ++v) {
    std::string s;
    s.push_back(static_cast<char>(variants[v][0]));
    s.push_back(static_cast<char>(variants[v][1]));
    s.push_back(static_cast<char>(m.vertex_count() - 1));
    s.push_back(static_cast<char>(variants[v][2]));
    for (size_t f = 0; f < m.face_count(); ++f) {
      s.push_back(static_cast<char>(m.face_size(f) - 1));
      for (uint32_t i = 0; i < m.face_size(f); ++i) s.push_back(static_cast<char>(m.face(f)[i]));
    }
    put(dir, n.name + "_" + std::to_string(v) + ".bin", s);
  }
}

void encode_seed(const fs::path& dir, const std::string& name, const tsm::Mesh& m, int q, int level,
                 uint32_t segment_faces = 0) {
  std::string bytes;
  tsm::EncodeOptions eo;
  eo.quantization_bits = q;
  eo.level = level;
  eo.segment_faces = segment_faces;
  tsm::Status s = tsm::encode(m, eo, bytes);
  if (!s.ok()) {
    std::fprintf(stderr, "fuzz_seeds: %s: %s\n", name.c_str(), s.to_string().c_str());
    std::exit(1);
  }
  put(dir,
      name + "_q" + std::to_string(q) + "_l" + std::to_string(level) +
          (segment_faces ? "_s" + std::to_string(segment_faces) : std::string()) + ".tsm",
      bytes);
}

void corpus_seeds(const fs::path& corpus, const fs::path& decode_dir, const fs::path& read_dir) {
  std::error_code ec;
  if (!fs::is_directory(corpus, ec)) return;
  std::vector<fs::path> files;
  for (auto it = fs::recursive_directory_iterator(corpus, ec); !ec && it != fs::recursive_directory_iterator();
       it.increment(ec))
    if (it->is_regular_file() && it->file_size() <= 16384 && it->path().extension() != ".md")
      files.push_back(it->path());
  std::sort(files.begin(), files.end());
  for (const fs::path& p : files) {
    std::string bytes;
    if (!tsm::read_file(p.string(), bytes).ok()) continue;
    std::string base = "corpus_" + p.filename().string();
    put(read_dir, base, bytes);
    tsm::Mesh m;
    if (!tsm::read_mesh_from_memory(bytes, p.string(), m).ok()) continue;
    std::string enc;
    if (tsm::encode(m, tsm::EncodeOptions{}, enc).ok() && enc.size() <= 16384) put(decode_dir, base + ".tsm", enc);
    // Progressive files (FORMAT.md §4.8): the refinement and loose sections.
    tsm::EncodeOptions po;
    po.progressive = true;
    m.attributes.clear();
    if (tsm::encode(m, po, enc).ok() && enc.size() <= 16384) put(decode_dir, base + ".progressive.tsm", enc);
  }
}

// A sphere with spherical texture coordinates per vertex or per corner (a
// seam where u wraps; values shared by the corners of a vertex otherwise),
// a face attribute, and metadata: seeds for the attribute decoder's
// predictors, values of earlier segments and the metadata section.
// An irregular grid with random vertex values, face labels and corner
// values (a seam on every fifth corner): attributes whose residuals the
// fast levels table-code.
tsm::Mesh noisy_attributes() {
  tsm::Mesh m = tsm_test::irregular_grid(20, 5);
  std::mt19937 rng(17);
  tsm::Attribute v, f, c;
  v.name = "noise";
  v.components = 2;
  for (size_t i = 0; i < 2 * m.vertex_count(); ++i) v.values.push_back(static_cast<float>(rng() % 1000) / 999.0f);
  f.name = "label";
  f.domain = tsm::AttributeDomain::face;
  f.type = tsm::AttributeType::i32;
  for (size_t i = 0; i < m.face_count(); ++i) f.values.push_back(static_cast<float>(rng() % 40));
  c.name = "texcoord";
  c.kind = tsm::AttributeKind::texcoord;
  c.domain = tsm::AttributeDomain::corner;
  c.components = 2;
  for (size_t k = 0; k < m.corner_count(); ++k) {
    const uint32_t at = k % 5 == 0 ? static_cast<uint32_t>(m.vertex_count() + k) : m.indices[k];
    c.indices.push_back(at);
  }
  for (size_t i = 0; i < m.vertex_count() + m.corner_count(); ++i) {
    c.values.push_back(static_cast<float>(rng() % 4096) / 4095.0f);
    c.values.push_back(static_cast<float>(rng() % 4096) / 4095.0f);
  }
  m.attributes = {v, f, c};
  return m;
}

tsm::Mesh with_attributes(bool per_corner) {
  tsm::Mesh m = tsm_test::icosphere(2);
  tsm::Attribute t, f;
  t.name = "texcoord";
  t.kind = tsm::AttributeKind::texcoord;
  t.components = 2;
  for (size_t v = 0; v < m.vertex_count(); ++v) {
    const float* p = &m.positions[3 * v];
    t.values.push_back(0.5f + std::atan2(p[1], p[0]) / 6.2831853f);
    t.values.push_back(0.5f + 0.5f * p[2]);
  }
  if (per_corner) {
    t.domain = tsm::AttributeDomain::corner;
    const size_t base = t.value_count();
    for (size_t k = 0; k < m.corner_count(); ++k) {
      const uint32_t v = m.indices[k];
      const bool seam = t.values[2 * v] < 0.1f;
      t.indices.push_back(seam ? static_cast<uint32_t>(base + k) : v);
    }
    for (size_t k = 0; k < m.corner_count(); ++k) {
      t.values.push_back(t.values[2 * m.indices[k]] + 1.0f);
      t.values.push_back(t.values[2 * m.indices[k] + 1]);
    }
  }
  f.name = "material";
  f.domain = tsm::AttributeDomain::face;
  f.type = tsm::AttributeType::u16;
  for (size_t k = 0; k < m.face_count(); ++k) f.values.push_back(static_cast<float>(k % 3));
  m.attributes = {t, f};
  m.metadata = {{"gltf", "{\"materials\":[{},{},{}]}"}, {"note", std::string(100, 'n')}};
  return m;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: fuzz_seeds OUT_DIR\n");
    return 2;
  }
  const fs::path out = argv[1];
  const fs::path decode_dir = out / "fuzz_decode", read_dir = out / "fuzz_read_mesh", rt_dir = out / "fuzz_roundtrip",
                 gltf_dir = out / "fuzz_gltf_transcode";
  for (const fs::path& d : {decode_dir, read_dir, rt_dir, gltf_dir}) {
    fs::remove_all(d);
    fs::create_directories(d);
  }
  for (const Named& n : meshes()) {
    for (int q : {4, 11, 14, 20}) encode_seed(decode_dir, n.name, n.mesh, q, tsm::kDefaultLevel);
    roundtrip_seed(rt_dir, n);
    if (n.mesh.vertex_count() > 200) continue;  // small text seeds only
    tsm::WriteOptions ascii;
    ascii.ascii = true;
    std::string s;
    if (tsm::write_ply(n.mesh, ascii, s).ok()) put(read_dir, n.name + "_ascii.ply", s);
    if (tsm::write_ply(n.mesh, tsm::WriteOptions{}, s).ok()) put(read_dir, n.name + "_le.ply", s);
    put(read_dir, n.name + "_be.ply", ply_big_endian(n.mesh));
    if (tsm::write_obj(n.mesh, s).ok()) put(read_dir, n.name + ".obj", s);
    put(read_dir, n.name + ".off", off(n.mesh));
    if (!triangles(n.mesh).empty()) {
      put(read_dir, n.name + "_ascii.stl", stl_ascii(n.mesh));
      put(read_dir, n.name + "_binary.stl", stl_binary(n.mesh));
    }
    gltf_seeds(read_dir, n.name, n.mesh);
    if (tsm::write_gltf(n.mesh, tsm::WriteOptions{}, s, true).ok()) transcode_seeds(gltf_dir, n.name, s);
  }
  {
    const std::string doc = gltf_document();
    put(read_dir, "hand_document.gltf", doc);
    tsm::Mesh m;
    if (!tsm::read_gltf(doc, "hand_document.gltf", m, tsm::ReadOptions{}, nullptr).ok() || !m.find_metadata("gltf")) {
      std::fprintf(stderr, "fuzz_seeds: the hand-written glTF document is not read with its pass-through entry\n");
      return 1;
    }
    gltf_seeds(read_dir, "hand_document_written", m);  // the writer's form, .gltf and .glb
    std::string glb;
    if (tsm::write_gltf(m, tsm::WriteOptions{}, glb, true).ok()) transcode_seeds(gltf_dir, "hand_document", glb);
  }
  encode_seed(decode_dir, "sphere", tsm_test::icosphere(2), 14, 0);
  encode_seed(decode_dir, "sphere", tsm_test::icosphere(2), 14, 9);
  encode_seed(decode_dir, "grid_holes", tsm_test::grid_with_holes(10, 2), 30, 9);
  // a noisy sphere at level 9: residual mixing
  encode_seed(decode_dir, "noisy_sphere", tsm_test::jittered(tsm_test::icosphere(3), 0.004f, 5), 14, 9);
  // ... and at level 0: table-coded residuals, at 30 bits too
  encode_seed(decode_dir, "noisy_sphere", tsm_test::jittered(tsm_test::icosphere(3), 0.004f, 5), 14, 0);
  encode_seed(decode_dir, "noisy_sphere", tsm_test::jittered(tsm_test::icosphere(2), 0.004f, 5), 30, 0);
  // table-coded connectivity run values (mode 1): an
  // irregular grid with holes and fins (the noisy sphere above has mode 0)
  encode_seed(decode_dir, "irregular_grid", tsm_test::irregular_grid(20, 3), 11, 0);
  encode_seed(decode_dir, "irregular_grid", tsm_test::irregular_grid(24, 3), 11, 0, 400);
  // the fan predictor: levels 1 and 2 (with the tangent
  // step), whole and in segments
  const tsm::Mesh fan_sphere = tsm_test::jittered(tsm_test::icosphere(4), 0.003f, 5);
  encode_seed(decode_dir, "fan_sphere", fan_sphere, 12, 1);
  encode_seed(decode_dir, "fan_sphere", fan_sphere, 12, 2);
  encode_seed(decode_dir, "fan_sphere", fan_sphere, 12, 2, 1500);
  encode_seed(decode_dir, "quads", quad_grid(6), 1, 6);
  // Files of several segments (FORMAT.md §4.5).
  encode_seed(decode_dir, "sphere", tsm_test::icosphere(2), 12, 6, 40);
  encode_seed(decode_dir, "grid_holes", tsm_test::grid_with_holes(10, 2), 10, 0, 25);
  encode_seed(decode_dir, "spheres", tsm_test::copies(tsm_test::icosphere(1), 3), 8, 6, 30);
  // Attributes (predictor 2 per vertex and per corner, values of earlier
  // segments) and metadata.
  encode_seed(decode_dir, "uv_vertex", with_attributes(false), 12, 6);
  encode_seed(decode_dir, "uv_corner", with_attributes(true), 12, 6);
  encode_seed(decode_dir, "uv_corner", with_attributes(true), 12, 6, 60);
  // table-coded attribute residuals: noisy values on an
  // irregular grid at level 0, whole and in segments
  encode_seed(decode_dir, "noisy_attributes", noisy_attributes(), 12, 0);
  encode_seed(decode_dir, "noisy_attributes", noisy_attributes(), 12, 0, 300);
  handwritten(read_dir);
  corpus_seeds(TSM_CORPUS_DIR, decode_dir, read_dir);
  std::printf("fuzz_seeds: %d seed files in %s\n", written, out.string().c_str());
  return 0;
}

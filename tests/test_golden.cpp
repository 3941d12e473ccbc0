// Golden files (tests/golden/, README.md there): small .tsm files that cover
// every feature of the format, made from meshes built here (never from the
// corpus) with the options tests/golden/MANIFEST.txt records beside each
// file's decoded-mesh hash (golden_hash.hpp). For each file: it decodes to
// that hash (whole and streamed a byte at a time), it has the features it
// stands for (tsm::inspect), and the generating mesh encoded with those
// options gives the file byte for byte. So any change to what the encoder
// writes or the decoder reads fails here until the files are regenerated on
// purpose:
//   TSM_UPDATE_GOLDEN=1 build/release/tests/tsm_tests --gtest_filter='Golden.*'
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <map>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "golden_hash.hpp"
#include "mesh_gen.hpp"
#include "tsm/tsm.hpp"

namespace {

using tsm::Attribute;
using tsm::AttributeDomain;
using tsm::AttributeKind;
using tsm::AttributeType;
using tsm::Mesh;

// Every position rounded to a multiple of 2^-16: exact binary values, so
// that a last-place difference in a platform's sin or cos does not change
// the mesh.
Mesh snapped(Mesh m) {
  for (float& x : m.positions) x = std::round(x * 65536.0f) / 65536.0f;
  return m;
}

// Noise from std::mt19937's own output (specified by the standard, unlike
// the distributions): every coordinate moved by a multiple of amplitude /
// 1000 in [-amplitude, amplitude].
Mesh noisy(Mesh m, float amplitude, uint32_t seed) {
  std::mt19937 rng(seed);
  for (float& x : m.positions) x += static_cast<float>(static_cast<int>(rng() % 2001) - 1000) * (amplitude / 1000.0f);
  return m;
}

// The meshes side by side along x (faces only; attributes dropped).
Mesh side_by_side(const std::vector<Mesh>& parts) {
  Mesh out;
  float x0 = 0;
  for (const Mesh& p : parts) {
    const uint32_t base = static_cast<uint32_t>(out.vertex_count());
    float lo = 0, hi = 0;
    for (size_t v = 0; v < p.vertex_count(); ++v) {
      lo = v == 0 ? p.positions[3 * v] : std::min(lo, p.positions[3 * v]);
      hi = v == 0 ? p.positions[3 * v] : std::max(hi, p.positions[3 * v]);
    }
    for (size_t v = 0; v < p.vertex_count(); ++v)
      out.add_vertex(p.positions[3 * v] - lo + x0, p.positions[3 * v + 1], p.positions[3 * v + 2]);
    std::vector<uint32_t> corners;
    for (size_t f = 0; f < p.face_count(); ++f) {
      corners.assign(p.face(f), p.face(f) + p.face_size(f));
      for (uint32_t& c : corners) c += base;
      out.add_face(corners.data(), corners.size());
    }
    x0 += hi - lo + 0.5f;
  }
  return out;
}

// Topology: holes (virtual vertices), a handle (jump edges), quads and a
// heptagon (polygons), a book of four pages and a double-sided sphere
// (non-manifold edges: stitches, their targets by candidate ranks), a
// bowtie (a non-manifold vertex), a degenerate face (a side face) and
// three vertices on no face.
Mesh topology_mesh() {
  Mesh m = side_by_side({tsm_test::grid_with_holes(8, 2), tsm_test::genus_surface(1), tsm_test::cube_quads(),
                         tsm_test::ngon(7), tsm_test::book(4), tsm_test::double_sided(tsm_test::icosphere(1)),
                         tsm_test::bowtie()});
  const uint32_t degenerate[3] = {0, 0, 1};
  m.add_face(degenerate, 3);
  m.add_vertex(-1.0f, 0.25f, 0.5f);
  m.add_vertex(-1.5f, -0.25f, 0.75f);
  m.add_vertex(-1.25f, 0.0f, -0.5f);
  return snapped(m);
}

Attribute attribute(const std::string& name, AttributeKind kind, AttributeDomain domain, AttributeType type,
                    uint32_t components) {
  Attribute a;
  a.name = name;
  a.kind = kind;
  a.domain = domain;
  a.type = type;
  a.components = components;
  return a;
}

// Texture coordinates per corner: one value per vertex from its position,
// except that the corners of faces with x < 0 take a seam copy; plus two
// values no corner uses.
Attribute corner_texcoords(const Mesh& m) {
  Attribute uv = attribute("texcoord", AttributeKind::texcoord, AttributeDomain::corner, AttributeType::f32, 2);
  const size_t V = m.vertex_count();
  for (int copy = 0; copy < 2; ++copy)
    for (size_t v = 0; v < V; ++v) {
      uv.values.push_back(0.5f + 0.5f * m.positions[3 * v] + 0.25f * static_cast<float>(copy));
      uv.values.push_back(0.5f + 0.5f * m.positions[3 * v + 1]);
    }
  uv.values.insert(uv.values.end(), {0.125f, 0.875f, 0.375f, 0.625f});
  for (size_t f = 0; f < m.face_count(); ++f) {
    const bool seam = m.positions[3 * size_t{m.face(f)[0]}] < 0;
    for (uint32_t i = 0; i < m.face_size(f); ++i) uv.indices.push_back(m.face(f)[i] + (seam ? uint32_t(V) : 0u));
  }
  return uv;
}

// Attributes of every domain and kind: vertex normals, corner texture
// coordinates (seams, unused values), face colours (u8), an integer label
// per vertex (i32) and a u16 per face; metadata.
Mesh attributes_mesh() {
  Mesh m = snapped(tsm_test::icosphere(2));
  const size_t V = m.vertex_count(), F = m.face_count();
  Attribute n = attribute("normal", AttributeKind::normal, AttributeDomain::vertex, AttributeType::f32, 3);
  for (size_t v = 0; v < V; ++v) {
    const float* p = &m.positions[3 * v];
    const float r = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    for (int a = 0; a < 3; ++a) n.values.push_back(p[a] / r);
  }
  m.attributes.push_back(n);
  m.attributes.push_back(corner_texcoords(m));
  Attribute c = attribute("color", AttributeKind::color, AttributeDomain::face, AttributeType::u8, 3);
  for (size_t f = 0; f < F; ++f)
    for (uint32_t k = 0; k < 3; ++k) c.values.push_back(static_cast<float>((37 * f + 91 * k) % 256));
  m.attributes.push_back(c);
  Attribute label = attribute("label", AttributeKind::generic, AttributeDomain::vertex, AttributeType::i32, 1);
  for (size_t v = 0; v < V; ++v) label.values.push_back(static_cast<float>(static_cast<int>(v % 11) - 5));
  m.attributes.push_back(label);
  Attribute region = attribute("region", AttributeKind::generic, AttributeDomain::face, AttributeType::u16, 1);
  for (size_t f = 0; f < F; ++f) region.values.push_back(static_cast<float>(f / 40));
  m.attributes.push_back(region);
  m.metadata = {{"gltf", R"({"asset":{"version":"2.0","generator":"tsm golden files"}})"},
                {"note", std::string("bytes \x00\x01\xff kept as given\x00\x00", 25)}};
  return m;
}

// Several segments at the fast level: run values, residuals and attribute
// residuals through tables; a corner attribute whose values several
// segments use.
Mesh segments_mesh() {
  Mesh m = snapped(tsm_test::irregular_grid(40, 3));
  std::mt19937 rng(17);
  Attribute noise = attribute("confidence", AttributeKind::generic, AttributeDomain::vertex, AttributeType::f32, 1);
  for (size_t v = 0; v < m.vertex_count(); ++v) noise.values.push_back(static_cast<float>(rng() % 1000) / 1000.0f);
  m.attributes.push_back(noise);
  m.attributes.push_back(corner_texcoords(m));
  return m;
}

Mesh noisy_sphere() { return snapped(noisy(tsm_test::icosphere(3), 0.004f, 5)); }
Mesh smooth_sphere() { return snapped(noisy(tsm_test::icosphere(4), 0.002f, 5)); }

Mesh cube() { return tsm_test::cube_quads(); }

// Welded (FORMAT.md §8.13): a flat-shaded sphere, every face with vertices
// of its own carrying its normal and a colour, a sliver on split vertices.
Mesh welded_mesh() {
  const Mesh base = snapped(tsm_test::icosphere(1));
  Mesh m;
  Attribute n = attribute("normal", AttributeKind::normal, AttributeDomain::vertex, AttributeType::f32, 3);
  Attribute c = attribute("color", AttributeKind::color, AttributeDomain::vertex, AttributeType::u8, 3);
  for (uint32_t f = 0; f < base.face_count(); ++f) {
    uint32_t corner[3];
    float sum[3] = {0, 0, 0};
    for (uint32_t k = 0; k < 3; ++k)
      for (int a = 0; a < 3; ++a) sum[a] += base.positions[3 * size_t{base.face(f)[k]} + a];
    const float r = std::sqrt(sum[0] * sum[0] + sum[1] * sum[1] + sum[2] * sum[2]);
    for (uint32_t k = 0; k < 3; ++k) {
      const float* p = &base.positions[3 * size_t{base.face(f)[k]}];
      corner[k] = static_cast<uint32_t>(m.vertex_count());
      m.add_vertex(p[0], p[1], p[2]);
      for (int a = 0; a < 3; ++a) n.values.push_back(sum[a] / r);
      for (int a = 0; a < 3; ++a) c.values.push_back(static_cast<float>((29 * f + 70 * a) % 256));
    }
    m.add_triangle(corner[0], corner[1], corner[2]);
  }
  m.add_triangle(0, 0, 1);
  m.attributes = {n, c};
  return m;
}

bool has(const std::string& s, const char* part) { return s.find(part) != std::string::npos; }

struct Case {
  std::string file, mesh;
  int q, level;
  uint32_t segment_faces;
  Mesh (*build)();
  // What the file must show (tsm::inspect): the features it stands for.
  void (*features)(const tsm::FileInfo&);
  // "progressive", "keep_order" or "lossless" (EncodeOptions), or "".
  std::string mode = "";
};

const std::vector<Case>& cases() {
  static const std::vector<Case> all = {
      {"topology.tsm", "topology", 12, 6, 0, topology_mesh,
       [](const tsm::FileInfo& fi) {
         EXPECT_GT(fi.virtual_vertices, 0u);  // holes
         EXPECT_GT(fi.jump_edges, 0u);        // the handle
         EXPECT_GT(fi.stitches, 0u);          // non-manifold edges and vertex
         EXPECT_GT(fi.side_faces, 0u);        // the degenerate face
         EXPECT_GT(fi.components, 5u);
       }},
      {"attributes.tsm", "attributes", 12, 6, 0, attributes_mesh,
       [](const tsm::FileInfo& fi) { EXPECT_EQ(fi.segment_count, 1u); }},
      {"segments_fast.tsm", "segments", 11, 0, 700, segments_mesh,
       [](const tsm::FileInfo& fi) {
         EXPECT_GE(fi.segment_count, 3u);
         EXPECT_GT(fi.references, 0u);
         EXPECT_GE(fi.run_table_parts, 1u);
         EXPECT_GE(fi.table_coded_attributes, 1u);
         EXPECT_TRUE(has(fi.geometry_predictor, "+tables")) << fi.geometry_predictor;
       }},
      {"fan_level1.tsm", "smooth_sphere", 12, 1, 0, smooth_sphere,
       [](const tsm::FileInfo& fi) { EXPECT_EQ(fi.geometry_predictor.rfind("fan", 0), 0u) << fi.geometry_predictor; }},
      {"high_level9.tsm", "noisy_sphere", 14, 9, 0, noisy_sphere,
       [](const tsm::FileInfo& fi) { EXPECT_TRUE(has(fi.geometry_predictor, "+mix")) << fi.geometry_predictor; }},
      {"welded.tsm", "welded", 12, 6, 0, welded_mesh,
       [](const tsm::FileInfo& fi) {
         EXPECT_EQ(fi.welded_points, 42u);
         EXPECT_GT(fi.side_faces, 0u);
       }},
      {"cube_raw.tsm", "cube", 16, 6, 0, cube,
       [](const tsm::FileInfo& fi) {
         EXPECT_EQ(fi.geometry_predictor, "raw+top");
         EXPECT_EQ(fi.lattice_planes[0], 2u);
       }},
      {"progressive.tsm", "smooth_sphere", 12, 6, 0, smooth_sphere,
       [](const tsm::FileInfo& fi) { EXPECT_GE(fi.batches.size(), 3u); }, "progressive"},
      {"keep_order.tsm", "topology", 12, 6, 0, topology_mesh,
       [](const tsm::FileInfo& fi) { EXPECT_GT(fi.stitches, 0u); }, "keep_order"},
      {"lossless.tsm", "noisy_sphere", 14, 2, 0, noisy_sphere,
       [](const tsm::FileInfo& fi) { EXPECT_EQ(fi.batches.size(), 0u); }, "lossless"},
  };
  return all;
}

std::string golden_dir() { return TSM_GOLDEN_DIR; }
std::string manifest_path() { return golden_dir() + "/MANIFEST.txt"; }

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

std::string encode(const Case& c) {
  tsm::EncodeOptions o;
  o.quantization_bits = c.q;
  o.level = c.level;
  o.segment_faces = c.segment_faces;
  o.progressive = c.mode == "progressive";
  o.keep_order = c.mode == "keep_order";
  o.lossless = c.mode == "lossless";
  std::string out;
  const tsm::Status s = tsm::encode(c.build(), o, out);
  EXPECT_TRUE(s.ok()) << c.file << ": " << s.to_string();
  return out;
}

std::string options_of(const Case& c) {
  return "q=" + std::to_string(c.q) + " level=" + std::to_string(c.level) +
         " segment_faces=" + std::to_string(c.segment_faces) + (c.mode.empty() ? "" : " " + c.mode);
}

constexpr const char* kRegenerate =
    "if the change is meant, regenerate: TSM_UPDATE_GOLDEN=1 build/release/tests/tsm_tests "
    "--gtest_filter='Golden.*' (tests/golden/README.md)";

// MANIFEST.txt: per file, `file mesh q=.. level=.. segment_faces=.. hash`.
struct Entry {
  std::string mesh, options, hash;
};
std::map<std::string, Entry> read_manifest() {
  std::map<std::string, Entry> out;
  std::istringstream in(slurp(manifest_path()));
  for (std::string line; std::getline(in, line);) {
    if (line.empty() || line[0] == '#') continue;
    // file mesh option... hash
    std::istringstream f(line);
    std::vector<std::string> t;
    for (std::string w; f >> w;) t.push_back(w);
    if (t.size() < 4) continue;
    std::string options;
    for (size_t i = 2; i + 1 < t.size(); ++i) options += (options.empty() ? "" : " ") + t[i];
    out[t[0]] = {t[1], options, t.back()};
  }
  return out;
}

void write_golden() {
  std::string manifest =
      "# Golden files (README.md): file, the mesh that made it (tests/test_golden.cpp),\n"
      "# the tsm::EncodeOptions it was encoded with (others at their defaults), and\n"
      "# the hash of its decoded mesh (tests/golden_hash.hpp).\n";
  for (const Case& c : cases()) {
    const std::string bytes = encode(c);
    std::ofstream(golden_dir() + "/" + c.file, std::ios::binary) << bytes;
    Mesh m;
    ASSERT_TRUE(tsm::decode(bytes, m).ok()) << c.file;
    manifest += c.file + " " + c.mesh + " " + options_of(c) + " " + tsm_golden::hex(tsm_golden::mesh_hash(m)) + "\n";
  }
  std::ofstream(manifest_path(), std::ios::binary) << manifest;
}

TEST(Golden, FilesDecodeToTheirHashAndReencodeByteForByte) {
  const char* update = std::getenv("TSM_UPDATE_GOLDEN");
  if (update && std::strcmp(update, "1") == 0) {
    write_golden();
    std::printf("TSM_UPDATE_GOLDEN=1: rewrote the golden files and %s\n", manifest_path().c_str());
  }
  const std::map<std::string, Entry> manifest = read_manifest();
  ASSERT_EQ(manifest.size(), cases().size()) << manifest_path() << " does not list the cases; " << kRegenerate;
  size_t total = 0;
  for (const Case& c : cases()) {
    SCOPED_TRACE(c.file);
    const auto it = manifest.find(c.file);
    ASSERT_NE(it, manifest.end()) << c.file << " is not in " << manifest_path() << "; " << kRegenerate;
    const Entry& e = it->second;
    EXPECT_EQ(e.mesh, c.mesh) << kRegenerate;
    EXPECT_EQ(e.options, options_of(c)) << kRegenerate;
    const std::string bytes = slurp(golden_dir() + "/" + c.file);
    ASSERT_FALSE(bytes.empty()) << "cannot read " << golden_dir() << "/" << c.file;
    total += bytes.size();
    // Decodes to the recorded hash, whole and streamed.
    Mesh m;
    const tsm::Status s = tsm::decode(bytes, m);
    ASSERT_TRUE(s.ok()) << s.to_string() << "; " << kRegenerate;
    EXPECT_EQ(tsm_golden::hex(tsm_golden::mesh_hash(m)), e.hash) << "the decoded mesh changed; " << kRegenerate;
    tsm::StreamDecoder sd;
    for (char b : bytes) ASSERT_TRUE(sd.feed(std::string_view(&b, 1)).ok());
    ASSERT_TRUE(sd.finish().ok());
    EXPECT_EQ(tsm_golden::hex(tsm_golden::mesh_hash(sd.mesh())), e.hash) << "streamed";
    tsm::FileInfo fi;
    ASSERT_TRUE(tsm::inspect(bytes, fi).ok());
    EXPECT_EQ(fi.format_version, 12u);
    c.features(fi);
    // The generating mesh encodes to the file, byte for byte.
    const std::string again = encode(c);
    if (again != bytes) {
      size_t at = 0;
      while (at < again.size() && at < bytes.size() && again[at] == bytes[at]) ++at;
      ADD_FAILURE() << "the encoder now writes " << again.size() << " bytes instead of the golden " << bytes.size()
                    << ", first difference at byte " << at << "; " << kRegenerate;
    }
  }
  EXPECT_LT(total, 100000u) << "the golden files should stay small";
}

}  // namespace

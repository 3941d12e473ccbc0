// Format version 4 (FORMAT.md §4.7, §8.5.1, §8.5.10): the mesh section, the
// default-weights flag and the raw predictor, the shorter range-coder flush,
// and version 3 files, which the decoder still reads.
#include <gtest/gtest.h>

#include <random>
#include <string>
#include <vector>

#include "byte_io.hpp"
#include "container.hpp"
#include "geometry_predict.hpp"
#include "mesh_gen.hpp"
#include "range_coder.hpp"
#include "test_util.hpp"
#include "tsm/compare.hpp"
#include "tsm/tsm.hpp"
#include "tsm/io.hpp"

namespace {

using tsm::Mesh;

// Files of version 4 (EncodeOptions::format_version); version 5 adds only
// the tangent step (test_geometry.cpp).
std::string encode(const Mesh& m, int q, int level) {
  std::string out;
  tsm::EncodeOptions o;
  o.quantization_bits = q;
  o.level = level;
  o.format_version = 4;
  const tsm::Status s = tsm::encode(m, o, out);
  EXPECT_TRUE(s.ok()) << s.to_string();
  return out;
}

Mesh decode_ok(const std::string& bytes) {
  Mesh m;
  const tsm::Status s = tsm::decode(bytes, m);
  EXPECT_TRUE(s.ok()) << s.to_string();
  return m;
}

void expect_round_trip(const Mesh& m, const std::string& bytes, int q, const std::string& what) {
  Mesh back;
  const tsm::Status s = tsm::decode(bytes, back);
  ASSERT_TRUE(s.ok()) << what << ": " << s.to_string();
  const tsm::CompareResult r = tsm::compare_meshes(m, back, q);
  EXPECT_TRUE(r.equal) << what << ": " << r.difference;
  EXPECT_LE(r.max_position_error, 0.5 + 1e-3) << what;
}

tsm::ErrorCode decode_code(const std::string& bytes) {
  Mesh m;
  return tsm::decode(bytes, m).code();
}

std::string predictor_of(const std::string& bytes) {
  tsm::FileInfo fi;
  EXPECT_TRUE(tsm::inspect(bytes, fi).ok());
  return fi.geometry_predictor;
}

// A file of one segment rewritten with other sections (same header fields,
// the given version).
std::string rebuild(const std::string& v4, uint16_t version,
                    const std::vector<std::pair<uint16_t, std::string>>& sections) {
  tsm::Header h;
  std::vector<tsm::Section> parsed;
  EXPECT_TRUE(tsm::read_container(v4, h, parsed).ok());
  tsm::ContainerWriter w(h);
  for (const auto& [id, payload] : sections) w.add_section(id, payload, 0);
  w.set_version(version);  // the version field and the header checksum over it
  return w.finish();
}

// The version 3 layout of a version 4 file: sections 3-6 (and 8), the
// predictor header's default weights written out.
std::string as_version3(const std::string& v4) {
  tsm::Header h;
  std::vector<tsm::Section> parsed;
  EXPECT_TRUE(tsm::read_container(v4, h, parsed).ok());
  const tsm::Section* mesh = nullptr;
  for (const tsm::Section& s : parsed)
    if (s.id == tsm::kSectionMesh) mesh = &s;
  EXPECT_NE(mesh, nullptr);
  if (!mesh) return {};
  tsm::MeshPayload p;
  EXPECT_TRUE(tsm::read_mesh_payload(mesh->data, p).ok());
  std::string geometry(p.geometry);
  const uint8_t kind = static_cast<uint8_t>(geometry[0]);
  if (kind & tsm::kDefaultWeightsFlag) {
    geometry[0] = static_cast<char>(kind & 0x7F);
    geometry.insert(1, std::string("\x00\x10\x00\x10\x00\x10", 6));  // 4096 x 3, little-endian
  }
  std::vector<std::pair<uint16_t, std::string>> sections = {{tsm::kSectionVertexTree, std::string(p.vertex_tree)},
                                                            {tsm::kSectionTriangleTree, std::string(p.triangle_tree)},
                                                            {tsm::kSectionTopology, std::string(p.topology)},
                                                            {tsm::kSectionGeometry, geometry}};
  if (!p.attributes.empty()) sections.push_back({tsm::kSectionAttributes, std::string(p.attributes)});
  return rebuild(v4, 3, sections);
}

TEST(FormatV4, OneSegmentIsOneMeshSection) {
  const std::string bytes = encode(tsm_test::icosphere(2), 12, 6);
  tsm::Header h;
  std::vector<tsm::Section> parsed;
  ASSERT_TRUE(tsm::read_container(bytes, h, parsed).ok());
  EXPECT_EQ(h.version, 4);
  ASSERT_EQ(parsed.size(), 1u);
  EXPECT_EQ(parsed[0].id, tsm::kSectionMesh);
}

TEST(FormatV4, Version3FilesStillDecode) {
  // Meshes whose geometry is not raw (version 3 has no predictor 4), with
  // and without default weights and attributes.
  std::vector<Mesh> meshes = {tsm_test::icosphere(3), tsm_test::genus_surface(2), tsm_test::grid_with_holes(8, 2)};
  Mesh with_attr = tsm_test::icosphere(2);
  tsm::Attribute a;
  a.name = "value";
  a.kind = tsm::AttributeKind::generic;
  a.domain = tsm::AttributeDomain::vertex;
  a.components = 1;
  for (size_t v = 0; v < with_attr.vertex_count(); ++v) a.values.push_back(static_cast<float>(v % 7));
  with_attr.attributes.push_back(a);
  meshes.push_back(with_attr);
  int flagged = 0;
  for (const Mesh& m : meshes)
    for (int level : {0, 6}) {
      const std::string v4 = encode(m, 12, level);
      ASSERT_NE(predictor_of(v4), "raw");
      const std::string v3 = as_version3(v4);
      tsm::FileInfo fi;
      ASSERT_TRUE(tsm::inspect(v3, fi).ok());
      EXPECT_EQ(fi.format_version, 3u);
      const Mesh a4 = decode_ok(v4), a3 = decode_ok(v3);
      EXPECT_EQ(a3.indices, a4.indices);
      EXPECT_EQ(a3.positions, a4.positions);
      EXPECT_EQ(a3.attributes.size(), a4.attributes.size());
      if (!a3.attributes.empty()) {
        EXPECT_EQ(a3.attributes[0].values, a4.attributes[0].values);
      }
      tsm::Header h;
      std::vector<tsm::Section> parsed;
      ASSERT_TRUE(tsm::read_container(v4, h, parsed).ok());
      for (const tsm::Section& s : parsed)
        if (s.id == tsm::kSectionMesh) {
          tsm::MeshPayload p;
          ASSERT_TRUE(tsm::read_mesh_payload(s.data, p).ok());
          flagged += (static_cast<uint8_t>(p.geometry[0]) & tsm::kDefaultWeightsFlag) != 0;
        }
    }
  EXPECT_GT(flagged, 0) << "no case exercised the default-weights flag";
}

TEST(FormatV4, VersionRulesForSectionsAndPredictors) {
  const std::string v4 = encode(tsm_test::icosphere(2), 12, 6);
  const std::string v3 = as_version3(v4);
  ASSERT_FALSE(v3.empty());
  tsm::Header h;
  std::vector<tsm::Section> parsed;
  ASSERT_TRUE(tsm::read_container(v4, h, parsed).ok());
  const std::string mesh = parsed[0].data;
  // A version 4 file with version 3 sections is corrupt.
  EXPECT_EQ(decode_code(rebuild(v4, 4, {{tsm::kSectionMesh, mesh}, {tsm::kSectionAttributes, "x"}})),
            tsm::ErrorCode::corrupt_data);
  EXPECT_EQ(decode_code(rebuild(v4, 4, {{tsm::kSectionVertexTree, "x"}, {tsm::kSectionMesh, mesh}})),
            tsm::ErrorCode::corrupt_data);
  // ... and one without its mesh section.
  EXPECT_EQ(decode_code(rebuild(v4, 4, {})), tsm::ErrorCode::corrupt_data);
  // In version 3, id 10 is an unknown section: ignored beside sections 3-6,
  // and not a substitute for them.
  std::vector<tsm::Section> v3_sections;
  ASSERT_TRUE(tsm::read_container(v3, h, v3_sections).ok());
  std::vector<std::pair<uint16_t, std::string>> with_unknown;
  for (const tsm::Section& s : v3_sections) with_unknown.push_back({s.id, s.data});
  with_unknown.push_back({tsm::kSectionMesh, "anything"});
  EXPECT_EQ(decode_ok(rebuild(v4, 3, with_unknown)).indices, decode_ok(v4).indices);
  EXPECT_EQ(decode_code(rebuild(v4, 3, {{tsm::kSectionMesh, mesh}})), tsm::ErrorCode::corrupt_data);
  // Version 12 is not read.
  EXPECT_EQ(decode_code(rebuild(v4, 12, {{tsm::kSectionMesh, mesh}})), tsm::ErrorCode::unsupported);
  // A mesh section whose stream lengths run past its end.
  EXPECT_EQ(decode_code(rebuild(v4, 4, {{tsm::kSectionMesh, std::string("\x05\x00\x00\x00\x01", 5)}})),
            tsm::ErrorCode::corrupt_data);
}

TEST(FormatV4, PredictorByteRules) {
  const Mesh m = tsm_test::icosphere(1);
  const std::string v4 = encode(m, 10, 6);
  tsm::Header h;
  std::vector<tsm::Section> parsed;
  ASSERT_TRUE(tsm::read_container(v4, h, parsed).ok());
  tsm::MeshPayload p;
  ASSERT_TRUE(tsm::read_mesh_payload(parsed[0].data, p).ok());
  auto with_geometry = [&](uint16_t version, const std::string& geometry) {
    tsm::MeshPayload q = p;
    q.geometry = geometry;
    if (version == 4) return rebuild(v4, 4, {{tsm::kSectionMesh, tsm::write_mesh_payload(q)}});
    return rebuild(v4, 3,
                   {{tsm::kSectionVertexTree, std::string(p.vertex_tree)},
                    {tsm::kSectionTriangleTree, std::string(p.triangle_tree)},
                    {tsm::kSectionTopology, std::string(p.topology)},
                    {tsm::kSectionGeometry, geometry}});
  };
  const std::string stream(40, '\x5a');
  for (int bad : {0x05, 0x80, 0x84, 0x85, 0xff})
    EXPECT_EQ(decode_code(with_geometry(4, std::string(1, static_cast<char>(bad)) + stream)),
              tsm::ErrorCode::corrupt_data)
        << bad;
  // Version 3 knows neither the flag nor predictor 4.
  for (int v4_only : {0x04, 0x81, 0x82, 0x83})
    EXPECT_EQ(decode_code(with_geometry(3, std::string(1, static_cast<char>(v4_only)) + std::string(6, '\0') + stream)),
              tsm::ErrorCode::corrupt_data)
        << v4_only;
}

TEST(FormatV4, TinyMeshesTakeTheRawPredictorAndFewBytes) {
  // The triangle of FORMAT.md §11 at 11 bits: 122 bytes in version 3 (Draco
  // 1.5.5 at cl10: 82 for the same triangle in the corpus).
  Mesh tri;
  tri.add_vertex(0.123f, 0.6514f, 0.000001f);
  tri.add_vertex(0.342f, 0.1234f, 0.000002f);
  tri.add_vertex(0.156f, 0.8422f, 0.000003f);
  tri.add_triangle(0, 1, 2);
  const std::string t = encode(tri, 11, 6);
  EXPECT_EQ(predictor_of(t), "raw");
  EXPECT_LE(t.size(), 80u);
  expect_round_trip(tri, t, 11, "triangle");
  // A closed cube of quads: 2 values per axis, so planes and 1-bit indices
  // (Draco: 80 bytes for cube_quads.ply at 11 bits).
  const Mesh cube = tsm_test::cube_quads();
  const std::string c = encode(cube, 11, 6);
  tsm::FileInfo fi;
  ASSERT_TRUE(tsm::inspect(c, fi).ok());
  EXPECT_EQ(fi.lattice_planes[0], 2u);
  EXPECT_LE(c.size(), 80u);
  expect_round_trip(cube, c, 11, "cube");
  // Raw at every level and many grid sizes, in segments too.
  for (int q : {1, 5, 11, 20, 30})
    for (int level : {0, 6, 9}) {
      const std::string b = encode(tri, q, level);
      expect_round_trip(tri, b, q, "triangle q=" + std::to_string(q));
    }
}

TEST(FormatV4, RawPredictorTruncationAndBadIndices) {
  const Mesh cube = tsm_test::cube_quads();
  const std::string good = encode(cube, 11, 6);
  ASSERT_EQ(predictor_of(good), "raw");
  tsm::Header h;
  std::vector<tsm::Section> parsed;
  ASSERT_TRUE(tsm::read_container(good, h, parsed).ok());
  tsm::MeshPayload p;
  ASSERT_TRUE(tsm::read_mesh_payload(parsed[0].data, p).ok());
  // Every shorter geometry stream: refused once more than 8 bytes are missing,
  // never a crash; every byte flipped: refused or decoded, never a crash.
  std::mt19937 rng(4);
  for (size_t cut = 1; cut < p.geometry.size(); ++cut) {
    tsm::MeshPayload q = p;
    q.geometry = p.geometry.substr(0, cut);
    (void)decode_code(rebuild(good, 4, {{tsm::kSectionMesh, tsm::write_mesh_payload(q)}}));
  }
  for (size_t i = 1; i < p.geometry.size(); ++i) {
    std::string g(p.geometry);
    g[i] = static_cast<char>(g[i] ^ (1 + rng() % 255));
    tsm::MeshPayload q = p;
    q.geometry = g;
    (void)decode_code(rebuild(good, 4, {{tsm::kSectionMesh, tsm::write_mesh_payload(q)}}));
  }
  tsm::MeshPayload q = p;
  q.geometry = std::string(1, '\x04');  // raw, nothing else: 24 coordinates from 8 zero bytes
  EXPECT_EQ(decode_code(rebuild(good, 4, {{tsm::kSectionMesh, tsm::write_mesh_payload(q)}})),
            tsm::ErrorCode::corrupt_data);
}

TEST(FormatV4, ShortFlushLeavesAtMostEightBytesOut) {
  // Random symbol streams: the trimmed flush decodes to the same symbols and
  // the decoder never reads more than 8 bytes past the end.
  std::mt19937 rng(11);
  for (int t = 0; t < 300; ++t) {
    const int n = static_cast<int>(rng() % 200);
    std::vector<int> bits(n);
    const uint32_t skew = rng() % 32768;
    tsm::Prob pe;
    tsm::RangeEncoder e;
    for (int& b : bits) {
      b = (rng() % 32768) < skew;
      e.bit(pe, b);
    }
    const uint32_t tail = static_cast<uint32_t>(rng());
    e.direct(tail, 32);
    const std::string out = e.finish();
    tsm::RangeDecoder d(out);
    tsm::Prob pd;
    for (int b : bits) ASSERT_EQ(d.bit(pd), b);
    ASSERT_EQ(d.direct(32), tail);
    EXPECT_LE(d.overrun(), tsm::RangeDecoder::kMaxOverrun);
    if (!out.empty() && d.overrun() < tsm::RangeDecoder::kMaxOverrun) {
      EXPECT_NE(out.back(), '\0') << "a trailing zero byte left in";
    }
  }
  tsm::RangeEncoder empty;
  EXPECT_EQ(empty.finish().size(), 0u);
}

}  // namespace

namespace {

// A file of the given quantization, level and asked-for format version (0:
// the encoder's choice).
// segment_faces: EncodeOptions::segment_faces (0, the default: the mesh
// whole unless it is larger than 2^18 faces).
std::string encode_as(const Mesh& m, int bits, int level, int version, uint32_t segment_faces = 0) {
  std::string out;
  tsm::EncodeOptions o;
  o.quantization_bits = bits;
  o.level = level;
  o.format_version = version;
  o.segment_faces = segment_faces;
  const tsm::Status s = tsm::encode(m, o, out);
  EXPECT_TRUE(s.ok()) << s.to_string();
  return out;
}

uint32_t version_of(const std::string& bytes) {
  tsm::FileInfo fi;
  EXPECT_TRUE(tsm::inspect(bytes, fi).ok());
  return fi.format_version;
}

// A file of one section whose payload needs `version`: relabelled as the
// version before it, it is refused as corrupt; as `version`, it decodes.
void expect_needs_version(const std::string& bytes, uint16_t version) {
  tsm::Header h;
  std::vector<tsm::Section> parsed;
  ASSERT_TRUE(tsm::read_container(bytes, h, parsed).ok());
  ASSERT_EQ(parsed.size(), 1u);
  const std::vector<std::pair<uint16_t, std::string>> sections = {{parsed[0].id, parsed[0].data}};
  EXPECT_EQ(decode_code(rebuild(bytes, static_cast<uint16_t>(version - 1), sections)), tsm::ErrorCode::corrupt_data);
  EXPECT_TRUE(decode_code(rebuild(bytes, version, sections)) == tsm::ErrorCode::ok);
}

}  // namespace

// Version 6 adds residual mixing (FORMAT.md §8.1.1), tried from level 7
// (kMixLevel): the encoder writes version 6 only into files that use it,
// otherwise version 5, unless a version is asked for; a mixed file decodes
// exactly, re-encodes to its own bytes, and is refused as version 5.
TEST(FormatV6, MixingFromLevel7AndVersion6OnlyWhereUsed) {
  const Mesh noisy = tsm_test::jittered(tsm_test::icosphere(4), 0.003f, 11);
  auto encode_v = [&](const Mesh& m, int level, int version) { return encode_as(m, 14, level, version); };
  auto mixed = [](const std::string& bytes) { return predictor_of(bytes).find("+mix") != std::string::npos; };
  const std::string l6 = encode_v(noisy, 6, 0), l9 = encode_v(noisy, 9, 0);
  EXPECT_EQ(version_of(l6), 5u);
  EXPECT_FALSE(mixed(l6));
  EXPECT_EQ(version_of(l9), 6u);
  EXPECT_TRUE(mixed(l9)) << predictor_of(l9);
  EXPECT_LT(l9.size(), encode_v(noisy, 9, 5).size());
  expect_round_trip(noisy, l9, 14, "level 9");
  // Re-encoding the decoded mesh gives the same bytes.
  EXPECT_EQ(encode_v(decode_ok(l9), 9, 0), l9);
  // Asked-for versions: 5 at level 9 has no mixing; 6 at level 6 is written as 6.
  const std::string v5 = encode_v(noisy, 9, 5);
  EXPECT_EQ(version_of(v5), 5u);
  EXPECT_FALSE(mixed(v5));
  EXPECT_EQ(version_of(encode_v(noisy, 6, 6)), 6u);
  // The mixing flag in a version 5 file is an unknown predictor.
  expect_needs_version(l9, 6);
}

// Version 7 codes each axis's last lattice plane from the top (FORMAT.md
// §8.5.2): the encoder sets the flag where the planes cost fewer bytes so,
// and then writes version 7; a box's far corners at qmax cost a few bits
// instead of about 20 each. Files without planes keep version 5.
TEST(FormatV7, LatticePlanesFromTheTopOnlyWhereTheyPay) {
  auto encode_v = [&](const Mesh& m, int bits, int version) {
    return encode_as(m, bits, tsm::kDefaultLevel, version);
  };
  auto top = [](const std::string& bytes) { return predictor_of(bytes).find("+top") != std::string::npos; };
  const Mesh box = tsm_test::cube_quads();
  for (int bits : {11, 16, 24}) {
    SCOPED_TRACE("bits=" + std::to_string(bits));
    const std::string v7 = encode_v(box, bits, 0), v6 = encode_v(box, bits, 6);
    EXPECT_EQ(version_of(v7), 7u);
    EXPECT_TRUE(top(v7)) << predictor_of(v7);
    EXPECT_EQ(version_of(v6), 6u);
    EXPECT_FALSE(top(v6));
    EXPECT_LE(v7.size() + 5, v6.size()) << v6.size() << " -> " << v7.size();
    expect_round_trip(box, v7, bits, "box, version 7");
    EXPECT_EQ(encode_v(decode_ok(v7), bits, 0), v7);
    // The flag in a version 6 file is an unknown predictor.
    expect_needs_version(v7, 7);
  }
  // No planes (random positions): version 5, as before.
  const std::string soup = encode_v(tsm_test::random_soup(200, 300, 3), 14, 0);
  EXPECT_EQ(version_of(soup), 5u);
  EXPECT_FALSE(top(soup));
}

// Version 8 codes the residuals of levels 0-2 with static prefix codes per
// context (FORMAT.md §8.5.11): those files round trip exactly and
// canonically (they say version 9 since the run values are table-coded too,
// FormatV9 below); an asked-for version 7 codes them adaptively; the
// default level keeps version 5; the table flag in a version 7 file is an
// unknown predictor.
TEST(FormatV8, TablesAtTheFastLevelsAndVersion8OnlyThere) {
  const Mesh noisy = tsm_test::jittered(tsm_test::icosphere(4), 0.003f, 5);
  auto tables = [](const std::string& bytes) { return predictor_of(bytes).find("+tables") != std::string::npos; };
  for (int level : {0, 1, 2}) {
    SCOPED_TRACE("level " + std::to_string(level));
    const std::string v8 = encode_as(noisy, 14, level, 8);
    EXPECT_EQ(version_of(v8), 8u);
    EXPECT_TRUE(tables(v8)) << predictor_of(v8);
    expect_round_trip(noisy, v8, 14, "tables");
    EXPECT_EQ(encode_as(decode_ok(v8), 14, level, 8), v8);
    EXPECT_EQ(version_of(encode_as(noisy, 14, level, 0)), 9u);  // with the run tables of version 9
    const std::string v7 = encode_as(noisy, 14, level, 7);
    EXPECT_EQ(version_of(v7), 7u);  // an asked-for version is written as asked
    EXPECT_FALSE(tables(v7));
    // The tables cost a little: within 10% of the adaptive file on 2,562 vertices.
    EXPECT_LT(v8.size(), v7.size() * 11 / 10) << v7.size() << " -> " << v8.size();
    expect_needs_version(v8, 8);
  }
  const std::string l6 = encode_as(noisy, 14, tsm::kDefaultLevel, 0);
  EXPECT_EQ(version_of(l6), 5u);
  EXPECT_FALSE(tables(l6));
  // Segments: each codes its own tables.
  const std::string seg = encode_as(noisy, 14, 0, 8, 1000);
  EXPECT_EQ(version_of(seg), 8u);
  expect_round_trip(noisy, seg, 14, "tables in segments");
}

// The topology stream of a one-segment file (FORMAT.md §4.7, §8.3.1).
std::string topology_of(const std::string& bytes) {
  tsm::Header h;
  std::vector<tsm::Section> parsed;
  EXPECT_TRUE(tsm::read_container(bytes, h, parsed).ok());
  tsm::MeshPayload p;
  EXPECT_TRUE(!parsed.empty() && tsm::read_mesh_payload(parsed[0].data, p).ok());
  return std::string(p.topology);
}

// How many parts of a file have table-coded run values (tsm info).
uint64_t run_table_parts(const std::string& bytes) {
  tsm::FileInfo fi;
  EXPECT_TRUE(tsm::inspect(bytes, fi).ok());
  return fi.run_table_parts;
}

// The same file with another topology stream.
std::string with_topology(const std::string& bytes, const std::string& topology) {
  tsm::Header h;
  std::vector<tsm::Section> parsed;
  EXPECT_TRUE(tsm::read_container(bytes, h, parsed).ok());
  tsm::MeshPayload p;
  EXPECT_TRUE(tsm::read_mesh_payload(parsed[0].data, p).ok());
  p.topology = topology;
  return rebuild(bytes, h.version, {{tsm::kSectionMesh, tsm::write_mesh_payload(p)}});
}

// Version 9 codes the connectivity's run values (vertex-run lengths, march
// counts, stitch and virtual-vertex positions, stitch distances) of levels
// 0-2 through static prefix codes (FORMAT.md §8.3.1) behind a mode byte at
// the start of the topology stream: meshes of 256 faces or more at those
// levels say version 9 and round trip exactly and canonically, whatever
// their topology. Irregular meshes use the tables (mode 1) for a few percent
// of their run values' bytes; regular ones, whose repeating runs the
// adaptive models code in a fraction of a bit, keep the models (mode 0: the
// version-8 streams and one byte). Smaller meshes and other levels keep the
// version-8 layout and bytes; an asked-for version 9 writes mode 0 where
// tables are not used; a forged mode or cut tables are refused.
TEST(FormatV9, RunTablesAtTheFastLevels) {
  const Mesh noisy = tsm_test::jittered(tsm_test::icosphere(4), 0.003f, 5);
  const std::vector<std::pair<std::string, Mesh>> meshes = {
      {"irregular grid", tsm_test::irregular_grid(40, 3)},
      {"irregular grid 2", tsm_test::irregular_grid(60, 4)},
      {"sphere", noisy},                                                // the regular ones from here
      {"grid with holes", tsm_test::grid_with_holes(24, 6)},            // virtual vertices
      {"books", tsm_test::copies(tsm_test::book(6), 50)},             // edges of six faces: stitches
      {"genus 3", tsm_test::genus_surface(3)},                          // jump edges
      {"moebius", tsm_test::moebius(150)},
      {"soup", tsm_test::random_soup(300, 700, 7)},
      {"flipped", tsm_test::flipped_face_sphere(3)},
  };
  for (const auto& [name, m] : meshes) {
    ASSERT_GE(m.face_count(), 256u) << name;
    for (int level : {0, 2}) {
      SCOPED_TRACE(name + ", level " + std::to_string(level));
      const bool irregular = name.rfind("irregular", 0) == 0;
      // Level 2 says version 10 where its fan predictor wins (FormatV10
      // below): asked for version 9 here, the file it wrote before.
      // Level 0 with stitches says version 11 (its stitch targets by
      // candidates, FormatV11 below), where they make the file smaller.
      const std::string v9 = encode_as(m, 12, level, level == 0 ? 0 : 9);
      tsm::FileInfo fi;
      ASSERT_TRUE(tsm::inspect(v9, fi).ok());
      const bool v11 = version_of(v9) == 11;
      EXPECT_TRUE(version_of(v9) == 9 || (v11 && level == 0 && fi.stitches > 0)) << version_of(v9);
      EXPECT_EQ(topology_of(v9).substr(0, 1), std::string(1, irregular ? '\x01' : '\0'));
      EXPECT_EQ(run_table_parts(v9), irregular ? 1u : 0u);
      expect_round_trip(m, v9, 12, name);
      EXPECT_TRUE(encode_as(decode_ok(v9), 12, level, level == 0 ? 0 : 9) == v9);
      const std::string v8 = encode_as(m, 12, level, 8);
      EXPECT_EQ(version_of(v8), 8u);
      expect_round_trip(m, v8, 12, name + " as version 8");
      // Tables cost a few percent of the file at most; mode 0 one byte.
      if (irregular)
        EXPECT_LT(v9.size(), v8.size() * 104 / 100) << v8.size() << " -> " << v9.size();
      else if (v11)
        EXPECT_LE(v9.size(), v8.size()) << v8.size() << " -> " << v9.size();
      else
        EXPECT_EQ(v9.size(), v8.size() + 1);
    }
  }
  // Small meshes and the other levels: the version-8 layout (the same
  // bytes but for the version field, which says the oldest that reads them).
  const Mesh small = tsm_test::icosphere(1);
  for (const auto& [m, level] : {std::pair<const Mesh*, int>{&small, 0}, {&noisy, 6}}) {
    const std::string auto_version = encode_as(*m, 12, level, 0), as_v8 = encode_as(*m, 12, level, 8);
    EXPECT_LE(version_of(auto_version), 8u);
    tsm::Header ha, hb;
    std::vector<tsm::Section> sa, sb;
    ASSERT_TRUE(tsm::read_container(auto_version, ha, sa).ok() && tsm::read_container(as_v8, hb, sb).ok());
    ASSERT_EQ(sa.size(), sb.size());
    for (size_t i = 0; i < sa.size(); ++i) EXPECT_TRUE(sa[i].data == sb[i].data) << level;
  }
  // Asked for: version 9 with mode 0 where no tables are used.
  for (int level : {0, 6}) {
    const Mesh& m = level == 0 ? small : noisy;
    const std::string v9 = encode_as(m, 12, level, 9);
    EXPECT_EQ(version_of(v9), 9u);
    EXPECT_EQ(topology_of(v9).substr(0, 1), std::string(1, '\0'));
    expect_round_trip(m, v9, 12, "mode 0");
    EXPECT_EQ(encode_as(decode_ok(v9), 12, level, 9), v9);
  }
  // Segments of a version 9 file: every one has the mode byte, the small
  // ones mode 0.
  const Mesh grid = tsm_test::irregular_grid(60, 4);
  for (uint32_t faces : {4000u, 300u}) {
    const std::string seg = encode_as(grid, 14, 0, 0, faces);
    EXPECT_EQ(version_of(seg), 11u);  // 9, but its bowtie vertices' stitches pay by candidates (version 11)
    if (faces > 1000) {
      EXPECT_GE(run_table_parts(seg), 1u);
    }
    expect_round_trip(grid, seg, 14, "run tables in segments of " + std::to_string(faces));
    EXPECT_TRUE(encode_as(decode_ok(seg), 14, 0, 0, faces) == seg);
  }
  // Forged: a mode above 1, an empty stream, tables cut short, the bit
  // stream longer than the stream, the tables read as mode 0.
  const std::string v9 = encode_as(grid, 12, 0, 0);
  const std::string topo = topology_of(v9);
  ASSERT_GT(topo.size(), 16u);
  ASSERT_EQ(topo[0], 1);
  std::string bad = topo;
  bad[0] = 2;
  EXPECT_EQ(decode_code(with_topology(v9, bad)), tsm::ErrorCode::corrupt_data);
  EXPECT_EQ(decode_code(with_topology(v9, "")), tsm::ErrorCode::corrupt_data);
  for (size_t cut : {size_t{1}, size_t{3}, size_t{5}, size_t{6}, size_t{9}})
    EXPECT_EQ(decode_code(with_topology(v9, topo.substr(0, cut))), tsm::ErrorCode::corrupt_data) << cut;
  bad = topo;
  bad[4] = static_cast<char>(0x7F);  // bit stream length's top byte
  EXPECT_EQ(decode_code(with_topology(v9, bad)), tsm::ErrorCode::corrupt_data);
  bad = topo;
  bad[0] = 0;
  EXPECT_EQ(decode_code(with_topology(v9, bad)), tsm::ErrorCode::corrupt_data);
  // Every byte after the bit stream's length flipped in turn (the map, the
  // tables, the bit stream, the range-coded rest): refused or decoded,
  // never a crash (the ASan build checks the reads).
  for (size_t i = 5; i < topo.size(); ++i) {
    bad = topo;
    bad[i] = static_cast<char>(bad[i] ^ 0x5A);
    Mesh out;
    (void)tsm::decode(with_topology(v9, bad), out);
  }
}

namespace {

// An attribute of `count` values of `components` components, value j's
// components from gen(j, c).
template <class Gen>
tsm::Attribute attribute(const std::string& name, tsm::AttributeDomain domain, tsm::AttributeType type,
                         uint32_t components, size_t count, Gen gen) {
  tsm::Attribute a;
  a.name = name;
  a.kind = tsm::AttributeKind::generic;
  a.domain = domain;
  a.type = type;
  a.components = components;
  for (size_t j = 0; j < count; ++j)
    for (uint32_t c = 0; c < components; ++c) a.values.push_back(gen(j, c));
  return a;
}

uint64_t table_coded_attributes(const std::string& bytes) {
  tsm::FileInfo fi;
  EXPECT_TRUE(tsm::inspect(bytes, fi).ok());
  return fi.table_coded_attributes;
}

}  // namespace

// Version 9 also codes the attribute residuals of levels 0-2 through static
// prefix codes (FORMAT.md §8.12.1), per attribute where they cost at most
// 9/8 of the adaptive models: noisy values use them, a constant attribute
// (which the models code in a fraction of a bit per value) does not. The
// files decode to the same attributes as version 8's and re-encode to
// their own bytes; damaged files are refused or decoded, never a crash.
TEST(FormatV9, AttributeTablesAtTheFastLevels) {
  Mesh m = tsm_test::irregular_grid(40, 3);
  std::mt19937 rng(9);
  const size_t V = m.vertex_count(), F = m.face_count();
  using tsm::AttributeDomain;
  using tsm::AttributeType;
  m.attributes.push_back(attribute("noise", AttributeDomain::vertex, AttributeType::f32, 1, V,
                                   [&](size_t, uint32_t) { return static_cast<float>(rng() % 1000) / 1000.0f; }));
  m.attributes.push_back(attribute("rgb", AttributeDomain::vertex, AttributeType::u8, 3, V,
                                   [&](size_t, uint32_t) { return static_cast<float>(rng() % 256); }));
  m.attributes.push_back(attribute("label", AttributeDomain::face, AttributeType::i32, 1, F,
                                   [&](size_t, uint32_t) { return static_cast<float>(rng() % 50) - 25.0f; }));
  m.attributes.push_back(
      attribute("constant", AttributeDomain::vertex, AttributeType::f32, 2, V, [](size_t, uint32_t) { return 0.25f; }));
  // Huge integers (the largest floats below 2^30): residuals beyond the
  // symbols' range (|r| >= 2^30) keep the models.
  const float top = static_cast<float>((1 << 30) - 64);
  m.attributes.push_back(attribute("huge", AttributeDomain::vertex, AttributeType::i32, 1, V,
                                   [&](size_t j, uint32_t) { return j % 2 ? top : -top; }));
  for (int level : {0, 2}) {
    SCOPED_TRACE("level " + std::to_string(level));
    const std::string v9 = encode_as(m, 12, level, 0), v8 = encode_as(m, 12, level, 8);
    EXPECT_EQ(version_of(v9), 11u);  // 9, but the grid's bowtie vertices' stitches pay by candidates
    EXPECT_EQ(table_coded_attributes(v9), 3u);  // noise, rgb, label
    EXPECT_EQ(table_coded_attributes(v8), 0u);
    expect_round_trip(m, v9, 12, "attribute tables");
    const Mesh a = decode_ok(v9), b = decode_ok(v8);
    ASSERT_EQ(a.attributes.size(), b.attributes.size());
    for (size_t i = 0; i < a.attributes.size(); ++i) EXPECT_TRUE(a.attributes[i].values == b.attributes[i].values) << i;
    EXPECT_TRUE(encode_as(a, 12, level, 0) == v9);
    // Tables cost a few percent: within 5% of the adaptive file.
    EXPECT_LT(v9.size(), v8.size() * 105 / 100) << v8.size() << " -> " << v9.size();
  }
  // Integers of magnitude 2^30 are refused (their differences need 33 bits),
  // with the attribute's name; before, the encoder failed inside.
  {
    Mesh big = m;
    big.attributes.back().values[1] = static_cast<float>(1 << 30);
    std::string out;
    const tsm::Status s = tsm::encode(big, tsm::EncodeOptions{}, out);
    EXPECT_EQ(s.code(), tsm::ErrorCode::invalid_argument);
    EXPECT_NE(s.message().find("'huge'"), std::string::npos) << s.to_string();
  }
  // The other levels and small meshes: no tables.
  EXPECT_EQ(table_coded_attributes(encode_as(m, 12, 6, 0)), 0u);
  Mesh small = tsm_test::icosphere(1);
  small.attributes.push_back(attribute("noise", AttributeDomain::vertex, AttributeType::f32, 1, small.vertex_count(),
                                       [&](size_t, uint32_t) { return static_cast<float>(rng() % 1000) / 1000.0f; }));
  EXPECT_EQ(table_coded_attributes(encode_as(small, 12, 0, 0)), 0u);
  // In segments, each with its own tables.
  const std::string seg = encode_as(m, 12, 0, 0, 1200);
  EXPECT_GE(table_coded_attributes(seg), 3u);
  expect_round_trip(m, seg, 12, "attribute tables in segments");
  // Damaged: every byte of the attribute payload flipped in turn, and the
  // payload cut at every length: refused or decoded, never a crash (the
  // ASan build checks the reads); cutting into the bit stream is refused.
  const std::string v9 = encode_as(m, 12, 0, 0);
  tsm::Header h;
  std::vector<tsm::Section> parsed;
  ASSERT_TRUE(tsm::read_container(v9, h, parsed).ok());
  tsm::MeshPayload p;
  ASSERT_TRUE(tsm::read_mesh_payload(parsed[0].data, p).ok());
  const std::string attributes(p.attributes);
  auto with_attributes = [&](const std::string& payload) {
    tsm::MeshPayload q = p;
    q.attributes = payload;
    return rebuild(v9, h.version, {{tsm::kSectionMesh, tsm::write_mesh_payload(q)}});
  };
  size_t refused = 0;
  for (size_t i = 0; i < attributes.size(); i += 7) {
    std::string bad = attributes;
    bad[i] = static_cast<char>(bad[i] ^ 0x24);
    refused += decode_code(with_attributes(bad)) != tsm::ErrorCode::ok;
    refused += decode_code(with_attributes(attributes.substr(0, i))) != tsm::ErrorCode::ok;
  }
  EXPECT_GT(refused, attributes.size() / 7);
  EXPECT_EQ(decode_code(with_attributes(attributes.substr(0, attributes.size() / 2))), tsm::ErrorCode::corrupt_data);
}

// A corner attribute whose values no corner uses are many (they follow the
// used ones, §8.12) and table-coded: the decoder's bound on their number
// counts the bit stream's bits too (each table-coded residual takes at least
// one), else such a file, whose range-coded stream holds little, was refused.
TEST(FormatV9, ManyUnusedTableCodedValuesDecode) {
  Mesh m = tsm_test::irregular_grid(14, 3);
  ASSERT_GE(m.face_count(), 256u);
  std::mt19937 rng(4);
  const size_t unused = 100000;
  m.attributes.push_back(attribute("many", tsm::AttributeDomain::corner, tsm::AttributeType::f32, 1, unused + 1,
                                   [&](size_t, uint32_t) { return static_cast<float>(rng() % 65536) / 65535.0f; }));
  m.attributes.back().indices.assign(m.corner_count(), 0);
  const std::string bytes = encode_as(m, 12, 0, 0);
  EXPECT_EQ(table_coded_attributes(bytes), 1u);
  expect_round_trip(m, bytes, 12, "many unused values");
}

// Version 10 adds the fan predictor (FORMAT.md §8.5.5): march order as the
// gate's, each vertex predicted from every triangle around it, residual
// contexts from the parallelograms' spread. Levels 1-2 try it in files
// whose parts have the mode byte (level 2 also with the tangent step) and
// say version 10 only where it wins; it is exact and canonical, smaller
// than level 0 on a noisy sphere, refused as version 9, and never written
// when version 9 is asked for or into a file without the mode byte.
TEST(FormatV10, FanPredictorAtLevels1And2) {
  const Mesh noisy = tsm_test::jittered(tsm_test::icosphere(4), 0.003f, 5);
  const Mesh smooth = tsm_test::jittered(tsm_test::icosphere(5), 0.0005f, 6);
  for (const auto& [name, m] : {std::pair<std::string, const Mesh*>{"noisy sphere", &noisy}, {"sphere", &smooth}}) {
    const std::string l0 = encode_as(*m, 12, 0, 0);
    EXPECT_EQ(predictor_of(l0).rfind("gate", 0), 0u) << predictor_of(l0);
    std::string previous = l0;
    for (int level : {1, 2}) {
      SCOPED_TRACE(name + ", level " + std::to_string(level));
      const std::string fan = encode_as(*m, 12, level, 0);
      EXPECT_EQ(predictor_of(fan).rfind("fan", 0), 0u) << predictor_of(fan);
      EXPECT_EQ(version_of(fan), 10u);
      EXPECT_LE(fan.size(), previous.size());  // each level tries what the one before did, and more
      previous = fan;
      expect_round_trip(*m, fan, 12, name);
      EXPECT_TRUE(encode_as(decode_ok(fan), 12, level, 0) == fan);
      expect_needs_version(fan, 10);
      // Asked for version 9: the gate, as before version 10.
      const std::string v9 = encode_as(*m, 12, level, 9);
      EXPECT_EQ(version_of(v9), 9u);
      EXPECT_EQ(predictor_of(v9).rfind("gate", 0), 0u) << predictor_of(v9);
      expect_round_trip(*m, v9, 12, name + " as version 9");
    }
    EXPECT_LT(previous.size(), l0.size()) << name;
  }
  // Level 2 on the noisy sphere takes the tangent step too.
  EXPECT_EQ(predictor_of(encode_as(smooth, 12, 2, 0)).rfind("fan+tangent", 0), 0u);
  // Without the mode byte (under 256 faces), levels 1-2 keep the gate and version 8.
  const Mesh small = tsm_test::jittered(tsm_test::icosphere(1), 0.003f, 5);
  ASSERT_LT(small.face_count(), 256u);
  for (int level : {1, 2}) {
    const std::string s = encode_as(small, 12, level, 0);
    EXPECT_LE(version_of(s), 8u);
    EXPECT_EQ(predictor_of(s).find("fan"), std::string::npos) << predictor_of(s);
  }
  // Segments choose their predictors each; the file says version 10.
  const std::string seg = encode_as(smooth, 12, 1, 0, 3000);
  EXPECT_EQ(version_of(seg), 10u);
  expect_round_trip(smooth, seg, 12, "fan in segments");
  EXPECT_TRUE(encode_as(decode_ok(seg), 12, 1, 0, 3000) == seg);
}

// Version 11 (FORMAT.md §8.3.2): stitch targets by their rank among
// candidates (neighbours of the stitched vertex's known neighbours), written
// where that makes the file smaller; the mesh decoded is the same.
TEST(FormatV11, StitchTargetsByCandidates) {
  const Mesh sphere = tsm_test::jittered(tsm_test::icosphere(4), 0.003f, 5);
  const std::vector<std::pair<std::string, Mesh>> meshes = {
      {"double-sided sphere", tsm_test::double_sided(sphere)},
      {"double-sided grid with holes", tsm_test::double_sided(tsm_test::grid_with_holes(30, 5))},
      {"books", tsm_test::copies(tsm_test::book(6), 50)},
  };
  for (const auto& [name, m] : meshes)
    for (int level : {0, 6})
      for (uint32_t segment_faces : {0u, 2000u}) {
        SCOPED_TRACE(name + ", level " + std::to_string(level) + ", segments of " + std::to_string(segment_faces));
        const std::string v11 = encode_as(m, 12, level, 0, segment_faces);
        const std::string v10 = encode_as(m, 12, level, 10, segment_faces);
        tsm::FileInfo a, b;
        ASSERT_TRUE(tsm::inspect(v11, a).ok() && tsm::inspect(v10, b).ok());
        EXPECT_EQ(version_of(v11), 11u);
        EXPECT_GT(a.stitches, 0u);
        EXPECT_EQ(a.stitches, b.stitches);
        EXPECT_LT(a.connectivity_bytes, b.connectivity_bytes);
        if (name.rfind("double", 0) == 0) {  // nearly every stitch's target is the first candidate
          EXPECT_LT(10 * a.connectivity_bytes, 7 * b.connectivity_bytes) << b.connectivity_bytes << " -> " << a.connectivity_bytes;
        }
        expect_round_trip(m, v11, 12, name);
        const Mesh x = decode_ok(v11), y = decode_ok(v10);
        EXPECT_TRUE(x.indices == y.indices && x.positions == y.positions);
        EXPECT_TRUE(encode_as(x, 12, level, 0, segment_faces) == v11);
      }
  // Without stitches nothing changes: the version-8 layout.
  EXPECT_LE(version_of(encode_as(sphere, 12, 6, 0)), 8u);
  // Asked for version 11: the file says 11, so its stitches are coded by
  // candidates even where distances would be smaller (a random soup).
  const Mesh soup = tsm_test::random_soup(40, 60, 3);
  const std::string s11 = encode_as(soup, 12, 6, 11), s10 = encode_as(soup, 12, 6, 10);
  EXPECT_EQ(version_of(s11), 11u);
  expect_round_trip(soup, s11, 12, "soup as version 11");
  EXPECT_TRUE(decode_ok(s11).indices == decode_ok(s10).indices);
}

// Every version the encoder may be asked for writes a file that says that
// version, decodes to the quantized mesh and re-encodes to its own bytes,
// on meshes with stitches, holes and handles.
TEST(FormatV11, EveryAskedForVersionRoundTrips) {
  const std::vector<std::pair<std::string, Mesh>> meshes = {
      {"soup", tsm_test::random_soup(40, 60, 3)},
      {"books", tsm_test::copies(tsm_test::book(6), 10)},
      {"double-sided sphere", tsm_test::double_sided(tsm_test::icosphere(2))},
      {"irregular grid", tsm_test::irregular_grid(20, 3)},
      {"grid with holes", tsm_test::grid_with_holes(12, 3)},
      {"genus 2", tsm_test::genus_surface(2)},
  };
  for (const auto& [name, m] : meshes)
    for (int version = 4; version <= tsm::kFormatVersion; ++version)
      for (int level : {0, 2, 6}) {
        SCOPED_TRACE(name + ", version " + std::to_string(version) + ", level " + std::to_string(level));
        const std::string bytes = encode_as(m, 12, level, version);
        EXPECT_EQ(version_of(bytes), static_cast<uint32_t>(version));
        expect_round_trip(m, bytes, 12, name);
        EXPECT_TRUE(encode_as(decode_ok(bytes), 12, level, version) == bytes);
      }
}

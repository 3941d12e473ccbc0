// The one format's features (FORMAT.md): a file of one segment is one mesh
// section, the version and section-id rules, the predictor byte (default
// weights, the raw predictor, residual mixing, planes from the top,
// table-coded residuals, the fan predictor), the range coder's short flush,
// the topology stream's mode byte and run tables, table-coded attribute
// residuals, and stitch targets by candidates: each used where the encoder
// says it is, exact, and canonical (a decoded file re-encodes to its bytes).
#include <gtest/gtest.h>

#include <random>
#include <string>
#include <vector>

#include "byte_io.hpp"
#include "connectivity.hpp"
#include "container.hpp"
#include "geometry_predict.hpp"
#include "mesh_gen.hpp"
#include "range_coder.hpp"
#include "test_util.hpp"
#include "tsm/compare.hpp"
#include "tsm/tsm.hpp"

namespace {

using tsm::Mesh;

// segment_faces: EncodeOptions::segment_faces (0, the default: the mesh
// whole unless it is larger than 2^18 faces).
std::string encode(const Mesh& m, int q, int level, uint32_t segment_faces = 0) {
  std::string out;
  tsm::EncodeOptions o;
  o.quantization_bits = q;
  o.level = level;
  o.segment_faces = segment_faces;
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

tsm::FileInfo info(const std::string& bytes) {
  tsm::FileInfo fi;
  const tsm::Status s = tsm::inspect(bytes, fi);
  EXPECT_TRUE(s.ok()) << s.to_string();
  return fi;
}

std::string predictor_of(const std::string& bytes) { return info(bytes).geometry_predictor; }

bool has(const std::string& predictor, const char* flag) { return predictor.find(flag) != std::string::npos; }

// A file rewritten with other sections (same header).
std::string rebuild(const std::string& file, const std::vector<std::pair<uint16_t, std::string>>& sections) {
  tsm::Header h;
  std::vector<tsm::Section> parsed;
  EXPECT_TRUE(tsm::read_container(file, h, parsed).ok());
  tsm::ContainerWriter w(h);
  for (const auto& [id, payload] : sections) w.add_section(id, payload, 0);
  return w.finish();
}

// The same file with another version (a varint after the magic; version 12
// takes one byte) and the first section's checksum, which covers it, over it.
std::string with_version(const std::string& file, uint16_t version) {
  size_t offset = 0;
  tsm::Header h;
  std::string missing;
  EXPECT_TRUE(tsm::read_header(file, offset, h, missing).ok() && missing.empty());
  size_t first_end = offset;
  tsm::Section s;
  EXPECT_TRUE(tsm::read_section(file, first_end, s, false, missing, 0, std::string_view(file).substr(0, offset)).ok());
  std::string out = file.substr(0, 4);
  tsm::ByteWriter w(out);
  w.varint(version);
  out += file.substr(5, first_end - 4 - 5);
  w.u32(tsm::checksum32(out));
  return out + file.substr(first_end);
}

// The mesh section's payload of a one-segment file.
tsm::MeshPayload mesh_payload(const std::string& file, std::string& storage) {
  tsm::Header h;
  std::vector<tsm::Section> parsed;
  EXPECT_TRUE(tsm::read_container(file, h, parsed).ok());
  tsm::MeshPayload p;
  for (const tsm::Section& s : parsed)
    if (s.id == tsm::kSectionMesh) storage = s.data;
  EXPECT_TRUE(tsm::read_mesh_payload(storage, p).ok());
  return p;
}

TEST(Format, OneSegmentIsOneMeshSection) {
  const std::string bytes = encode(tsm_test::icosphere(2), 12, 6);
  tsm::Header h;
  std::vector<tsm::Section> parsed;
  ASSERT_TRUE(tsm::read_container(bytes, h, parsed).ok());
  EXPECT_EQ(h.version, 12);
  EXPECT_EQ(tsm::kFormatVersion, 12);
  ASSERT_EQ(parsed.size(), 1u);
  EXPECT_EQ(parsed[0].id, tsm::kSectionMesh);
  // Several segments: one segment section each, no mesh section.
  const std::string seg = encode(tsm_test::icosphere(3), 12, 6, 300);
  ASSERT_TRUE(tsm::read_container(seg, h, parsed).ok());
  EXPECT_EQ(h.version, 12);
  EXPECT_GT(h.segment_count, 1u);
  ASSERT_EQ(parsed.size(), h.segment_count);
  for (const tsm::Section& s : parsed) EXPECT_EQ(s.id, tsm::kSectionSegment);
}

// One format until 1.0: a file of any other version is refused as
// unsupported, whole, streamed and inspected, with a message that says what
// to do.
TEST(Format, OnlyVersion12IsRead) {
  const std::string good = encode(tsm_test::icosphere(2), 12, 6);
  ASSERT_EQ(decode_code(with_version(good, 12)), tsm::ErrorCode::ok);
  ASSERT_EQ(with_version(good, 12), good);
  for (int version : {0, 3, 4, 5, 10, 11, 13, 0x100, 0xFFFF}) {
    SCOPED_TRACE(version);
    const std::string bad = with_version(good, static_cast<uint16_t>(version));
    Mesh m;
    const tsm::Status s = tsm::decode(bad, m);
    EXPECT_EQ(s.code(), tsm::ErrorCode::unsupported);
    EXPECT_EQ(s.message(), "format version " + std::to_string(version) +
                               ": this decoder reads only format version 12 (tsm keeps one format until 1.0; "
                               "re-encode from the source mesh)");
    tsm::FileInfo fi;
    EXPECT_EQ(tsm::inspect(bad, fi).code(), tsm::ErrorCode::unsupported);
    tsm::StreamDecoder sd;
    EXPECT_EQ(sd.feed(std::string_view(bad).substr(0, 8)).code(), tsm::ErrorCode::unsupported);
  }
}

// FORMAT.md §4.3: the mesh section is required in a file of one segment and
// refused in a file of several; the reserved ids 3-6 and 8 are refused; ids
// 1 and 2 and unassigned ids are ignored; stream lengths past the section's
// end are refused.
TEST(Format, SectionRules) {
  const std::string good = encode(tsm_test::icosphere(2), 12, 6);
  std::string storage;
  (void)mesh_payload(good, storage);
  const std::string mesh = storage;
  const Mesh expected = decode_ok(good);
  for (int reserved : {3, 4, 5, 6, 8}) {
    SCOPED_TRACE(reserved);
    const uint16_t id = static_cast<uint16_t>(reserved);
    EXPECT_EQ(decode_code(rebuild(good, {{tsm::kSectionMesh, mesh}, {id, "x"}})), tsm::ErrorCode::corrupt_data);
    EXPECT_EQ(decode_code(rebuild(good, {{id, "x"}, {tsm::kSectionMesh, mesh}})), tsm::ErrorCode::corrupt_data);
  }
  for (int ignored : {1, 2, 15, 200, 0xFFFF}) {
    SCOPED_TRACE(ignored);
    const Mesh m = decode_ok(rebuild(good, {{static_cast<uint16_t>(ignored), "anything"}, {tsm::kSectionMesh, mesh}}));
    EXPECT_TRUE(m.indices == expected.indices && m.positions == expected.positions);
  }
  // Section 11 is the order section (FORMAT.md §4.9): garbage there is refused.
  EXPECT_EQ(decode_code(rebuild(good, {{tsm::kSectionMesh, mesh}, {tsm::kSectionOrder, "anything"}})),
            tsm::ErrorCode::corrupt_data);
  EXPECT_EQ(decode_code(rebuild(good, {})), tsm::ErrorCode::corrupt_data);
  EXPECT_EQ(decode_code(rebuild(good, {{tsm::kSectionMesh, mesh}, {tsm::kSectionMesh, mesh}})),
            tsm::ErrorCode::corrupt_data);
  // A mesh section whose stream lengths run past its end.
  EXPECT_EQ(decode_code(rebuild(good, {{tsm::kSectionMesh, std::string("\x05\x00\x00\x00\x01", 5)}})),
            tsm::ErrorCode::corrupt_data);
  // A file of several segments with a mesh section.
  const std::string seg = encode(tsm_test::icosphere(3), 12, 6, 300);
  tsm::Header h;
  std::vector<tsm::Section> parsed;
  ASSERT_TRUE(tsm::read_container(seg, h, parsed).ok());
  std::vector<std::pair<uint16_t, std::string>> sections;
  for (const tsm::Section& s : parsed) sections.push_back({s.id, s.data});
  ASSERT_EQ(decode_code(rebuild(seg, sections)), tsm::ErrorCode::ok);
  sections.push_back({tsm::kSectionMesh, mesh});
  EXPECT_EQ(decode_code(rebuild(seg, sections)), tsm::ErrorCode::corrupt_data);
}

// The predictor byte (FORMAT.md §8.5.1): unknown predictors and flags on
// predictors that cannot take them are refused.
TEST(Format, PredictorByteRules) {
  const Mesh m = tsm_test::icosphere(1);
  const std::string good = encode(m, 10, 6);
  std::string storage;
  const tsm::MeshPayload p = mesh_payload(good, storage);
  auto with_geometry = [&](const std::string& geometry) {
    tsm::MeshPayload q = p;
    q.geometry = geometry;
    return rebuild(good, {{tsm::kSectionMesh, tsm::write_mesh_payload(q)}});
  };
  const std::string stream(40, '\x5a');
  // Predictors 6 and 7, 0x80 alone (no predictor), default weights on raw
  // and ancestors, the tangent step on raw and ancestors, mixing on raw,
  // tables on raw and with mixing.
  for (int bad : {0x06, 0x07, 0x80, 0x84, 0x90, 0x44, 0x40, 0x24, 0x0C, 0x29, 0xff})
    EXPECT_EQ(decode_code(with_geometry(std::string(1, static_cast<char>(bad)) + stream)),
              tsm::ErrorCode::corrupt_data)
        << bad;
}

TEST(Format, TinyMeshesTakeTheRawPredictorAndFewBytes) {
  // The triangle of FORMAT.md §11 at 11 bits (Draco 1.5.5 at cl10: 82 bytes
  // for the same triangle in the corpus).
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

TEST(Format, RawPredictorTruncationAndBadIndices) {
  const Mesh cube = tsm_test::cube_quads();
  const std::string good = encode(cube, 11, 6);
  ASSERT_EQ(predictor_of(good).rfind("raw", 0), 0u) << predictor_of(good);
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
    (void)decode_code(rebuild(good, {{tsm::kSectionMesh, tsm::write_mesh_payload(q)}}));
  }
  for (size_t i = 1; i < p.geometry.size(); ++i) {
    std::string g(p.geometry);
    g[i] = static_cast<char>(g[i] ^ (1 + rng() % 255));
    tsm::MeshPayload q = p;
    q.geometry = g;
    (void)decode_code(rebuild(good, {{tsm::kSectionMesh, tsm::write_mesh_payload(q)}}));
  }
  tsm::MeshPayload q = p;
  q.geometry = std::string(1, '\x04');  // raw, nothing else: 24 coordinates from 8 zero bytes
  EXPECT_EQ(decode_code(rebuild(good, {{tsm::kSectionMesh, tsm::write_mesh_payload(q)}})),
            tsm::ErrorCode::corrupt_data);
}

TEST(Format, ShortFlushLeavesAtMostEightBytesOut) {
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


// Residual mixing (FORMAT.md §8.1.1), tried from level 7 (kMixLevel): a
// mixed file decodes exactly and re-encodes to its own bytes; level 6 never
// mixes. (On uniform noise over a larger sphere the static tables, which
// levels 7-9 try last, beat it: icosphere(4) jittered by 0.003.)
TEST(Format, MixingFromLevel7) {
  const Mesh noisy = tsm_test::jittered(tsm_test::icosphere(3), 0.004f, 11);
  const std::string l6 = encode(noisy, 14, 6), l9 = encode(noisy, 14, 9);
  EXPECT_FALSE(has(predictor_of(l6), "+mix"));
  EXPECT_TRUE(has(predictor_of(l9), "+mix")) << predictor_of(l9);
  EXPECT_LT(l9.size(), l6.size());
  expect_round_trip(noisy, l9, 14, "level 9");
  EXPECT_EQ(encode(decode_ok(l9), 14, 9), l9);
}

// Lattice planes from the top (FORMAT.md §8.5.2): the encoder sets the flag
// where the planes cost fewer bytes so (a box's far corners at qmax: a few
// bits instead of about 20 each); never without planes.
TEST(Format, LatticePlanesFromTheTopWhereTheyPay) {
  const Mesh box = tsm_test::cube_quads();
  for (int bits : {11, 16, 24}) {
    SCOPED_TRACE("bits=" + std::to_string(bits));
    const std::string b = encode(box, bits, tsm::kDefaultLevel);
    EXPECT_TRUE(has(predictor_of(b), "+top")) << predictor_of(b);
    expect_round_trip(box, b, bits, "box");
    EXPECT_EQ(encode(decode_ok(b), bits, tsm::kDefaultLevel), b);
  }
  // No planes (random positions).
  EXPECT_FALSE(has(predictor_of(encode(tsm_test::random_soup(200, 300, 3), 14, tsm::kDefaultLevel)), "+top"));
}

// Levels 0-6 code the residuals with static tables per context and rANS
// (FORMAT.md §8.5.12), levels 7-9 where that beats their winner (on this
// uniform noise it does): those files round trip exactly and canonically,
// in segments too (each with its own tables).
TEST(Format, ResidualTablesUpToTheDefaultLevel) {
  const Mesh noisy = tsm_test::jittered(tsm_test::icosphere(4), 0.003f, 5);
  for (int level : {0, 1, 2, 4, tsm::kDefaultLevel, 9}) {
    SCOPED_TRACE("level " + std::to_string(level));
    const std::string b = encode(noisy, 14, level);
    EXPECT_TRUE(has(predictor_of(b), "+tables")) << predictor_of(b);
    expect_round_trip(noisy, b, 14, "tables");
    EXPECT_EQ(encode(decode_ok(b), 14, level), b);
  }
  const std::string seg = encode(noisy, 14, 0, 1000);
  EXPECT_GT(info(seg).segment_count, 1u);
  expect_round_trip(noisy, seg, 14, "tables in segments");
  EXPECT_EQ(encode(decode_ok(seg), 14, 0, 1000), seg);
}

// The topology stream of a one-segment file (FORMAT.md §4.7, §8.3.1).
std::string topology_of(const std::string& bytes) {
  std::string storage;
  return std::string(mesh_payload(bytes, storage).topology);
}

// The same one-segment file with another topology stream.
std::string with_topology(const std::string& bytes, const std::string& topology) {
  std::string storage;
  tsm::MeshPayload p = mesh_payload(bytes, storage);
  p.topology = topology;
  return rebuild(bytes, {{tsm::kSectionMesh, tsm::write_mesh_payload(p)}});
}

// The topology stream starts with the run coding's mode byte (FORMAT.md
// §8.3.1). At levels 0-2 a part of 256 faces or more codes its run values
// (vertex-run lengths, march counts, stitch and virtual-vertex positions,
// stitch distances) through static prefix codes where they cost at most 1/8
// more than the adaptive models (mode 1): irregular meshes; regular ones,
// whose repeating runs the adaptive models code in a fraction of a bit,
// keep the models (mode 0), as do smaller meshes and the other levels.
// Either way the files round trip exactly and canonically, whatever their
// topology; a forged mode or cut tables are refused.
TEST(Format, RunTablesAtTheFastLevels) {
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
  for (size_t i = 0; i < meshes.size(); ++i) {
    const auto& [name, m] = meshes[i];
    ASSERT_GE(m.face_count(), 256u) << name;
    for (int level : {0, 2}) {
      if (tsm_test::sanitized_skip(i, level / 2)) continue;
      SCOPED_TRACE(name + ", level " + std::to_string(level));
      const bool irregular = name.rfind("irregular", 0) == 0;
      const std::string b = encode(m, 12, level);
      EXPECT_EQ(topology_of(b).substr(0, 1), std::string(1, irregular ? '\x01' : '\0'));
      EXPECT_EQ(info(b).run_table_parts, irregular ? 1u : 0u);
      expect_round_trip(m, b, 12, name);
      EXPECT_TRUE(encode(decode_ok(b), 12, level) == b);
    }
  }
  // Small meshes and the other levels: mode 0.
  const Mesh small = tsm_test::icosphere(1);
  for (const auto& [m, level] : {std::pair<const Mesh*, int>{&small, 0}, {&noisy, 6}}) {
    const std::string b = encode(*m, 12, level);
    EXPECT_EQ(topology_of(b).substr(0, 1), std::string(1, '\0'));
    expect_round_trip(*m, b, 12, "mode 0");
    EXPECT_EQ(encode(decode_ok(b), 12, level), b);
  }
  // Segments: every one has the mode byte, the large ones tables.
  const Mesh grid = tsm_test::irregular_grid(60, 4);
  for (uint32_t faces : {4000u, 300u}) {
    const std::string seg = encode(grid, 14, 0, faces);
    if (faces > 1000) {
      EXPECT_GE(info(seg).run_table_parts, 1u);
    }
    expect_round_trip(grid, seg, 14, "run tables in segments of " + std::to_string(faces));
    EXPECT_TRUE(encode(decode_ok(seg), 14, 0, faces) == seg);
  }
  // Forged: a mode above 1, an empty stream, tables cut short, the bit
  // stream longer than the stream, the tables read as mode 0.
  const std::string tabled = encode(grid, 12, 0);
  const std::string topo = topology_of(tabled);
  ASSERT_GT(topo.size(), 16u);
  ASSERT_EQ(topo[0], 1);
  std::string bad = topo;
  bad[0] = 2;
  EXPECT_EQ(decode_code(with_topology(tabled, bad)), tsm::ErrorCode::corrupt_data);
  EXPECT_EQ(decode_code(with_topology(tabled, "")), tsm::ErrorCode::corrupt_data);
  for (size_t cut : {size_t{1}, size_t{3}, size_t{5}, size_t{6}, size_t{9}})
    EXPECT_EQ(decode_code(with_topology(tabled, topo.substr(0, cut))), tsm::ErrorCode::corrupt_data) << cut;
  bad = topo;
  bad[4] = static_cast<char>(0x7F);  // bit stream length's top byte
  EXPECT_EQ(decode_code(with_topology(tabled, bad)), tsm::ErrorCode::corrupt_data);
  bad = topo;
  bad[0] = 0;
  EXPECT_EQ(decode_code(with_topology(tabled, bad)), tsm::ErrorCode::corrupt_data);
  // Without its mode byte, a mode-0 stream is read from its second byte on:
  // refused or another mesh, never a crash.
  const std::string plain = encode(noisy, 12, 6);
  (void)decode_code(with_topology(plain, topology_of(plain).substr(1)));
  // Every byte after the bit stream's length flipped in turn (the map, the
  // tables, the bit stream, the range-coded rest): refused or decoded,
  // never a crash (the ASan build checks the reads).
  for (size_t i = 5; i < topo.size(); ++i) {
    bad = topo;
    bad[i] = static_cast<char>(bad[i] ^ 0x5A);
    Mesh out;
    (void)tsm::decode(with_topology(tabled, bad), out);
  }
}

uint64_t table_coded_attributes(const std::string& bytes) { return info(bytes).table_coded_attributes; }

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

// Levels 0-2 also code the attribute residuals through static prefix codes
// (FORMAT.md §8.12.1), per attribute where they cost at most 9/8 of the
// adaptive models: noisy values use them, a constant attribute (which the
// models code in a fraction of a bit per value) does not. The files decode
// to the same attributes as the adaptive models' and re-encode to their own
// bytes; damaged files are refused or decoded, never a crash.
TEST(Format, AttributeTablesAtTheFastLevels) {
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
    const std::string fast = encode(m, 12, level), l6 = encode(m, 12, 6);
    EXPECT_EQ(table_coded_attributes(fast), 3u);  // noise, rgb, label
    expect_round_trip(m, fast, 12, "attribute tables");
    // The same values as the adaptive models give (level 6: no tables).
    const Mesh a = decode_ok(fast), b = decode_ok(l6);
    ASSERT_EQ(a.attributes.size(), b.attributes.size());
    for (size_t i = 0; i < a.attributes.size(); ++i) EXPECT_TRUE(a.attributes[i].values == b.attributes[i].values) << i;
    EXPECT_TRUE(encode(a, 12, level) == fast);
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
  EXPECT_EQ(table_coded_attributes(encode(m, 12, 6)), 0u);
  Mesh small = tsm_test::icosphere(1);
  small.attributes.push_back(attribute("noise", AttributeDomain::vertex, AttributeType::f32, 1, small.vertex_count(),
                                       [&](size_t, uint32_t) { return static_cast<float>(rng() % 1000) / 1000.0f; }));
  EXPECT_EQ(table_coded_attributes(encode(small, 12, 0)), 0u);
  // In segments, each with its own tables.
  const std::string seg = encode(m, 12, 0, 1200);
  EXPECT_GE(table_coded_attributes(seg), 3u);
  expect_round_trip(m, seg, 12, "attribute tables in segments");
  // Damaged: every byte of the attribute payload flipped in turn, and the
  // payload cut at every length: refused or decoded, never a crash (the
  // ASan build checks the reads); cutting into the bit stream is refused.
  const std::string fast = encode(m, 12, 0);
  tsm::Header h;
  std::vector<tsm::Section> parsed;
  ASSERT_TRUE(tsm::read_container(fast, h, parsed).ok());
  tsm::MeshPayload p;
  ASSERT_TRUE(tsm::read_mesh_payload(parsed[0].data, p).ok());
  const std::string attributes(p.attributes);
  auto with_attributes = [&](const std::string& payload) {
    tsm::MeshPayload q = p;
    q.attributes = payload;
    return rebuild(fast, {{tsm::kSectionMesh, tsm::write_mesh_payload(q)}});
  };
  size_t refused = 0;
  const size_t stride = tsm_test::sweep_stride(7);
  for (size_t i = 0; i < attributes.size(); i += stride) {
    std::string bad = attributes;
    bad[i] = static_cast<char>(bad[i] ^ 0x24);
    refused += decode_code(with_attributes(bad)) != tsm::ErrorCode::ok;
    refused += decode_code(with_attributes(attributes.substr(0, i))) != tsm::ErrorCode::ok;
  }
  EXPECT_GT(refused, attributes.size() / stride);
  EXPECT_EQ(decode_code(with_attributes(attributes.substr(0, attributes.size() / 2))), tsm::ErrorCode::corrupt_data);
}

// A corner attribute whose values no corner uses are many (they follow the
// used ones, §8.12) and table-coded: the decoder's bound on their number
// counts the bit stream's bits too (each table-coded residual takes at least
// one), else such a file, whose range-coded stream holds little, was refused.
TEST(Format, ManyUnusedTableCodedValuesDecode) {
  Mesh m = tsm_test::irregular_grid(14, 3);
  ASSERT_GE(m.face_count(), 256u);
  std::mt19937 rng(4);
  const size_t unused = 100000;
  m.attributes.push_back(attribute("many", tsm::AttributeDomain::corner, tsm::AttributeType::f32, 1, unused + 1,
                                   [&](size_t, uint32_t) { return static_cast<float>(rng() % 65536) / 65535.0f; }));
  m.attributes.back().indices.assign(m.corner_count(), 0);
  const std::string bytes = encode(m, 12, 0);
  EXPECT_EQ(table_coded_attributes(bytes), 1u);
  expect_round_trip(m, bytes, 12, "many unused values");
}


// The fan predictor (FORMAT.md §8.5.5): march order as the gate's, each
// vertex predicted from every triangle around it, residual contexts from
// the parallelograms' spread. Levels 1-2 try it (level 2 also with the
// tangent step) and keep it where it wins; it is exact and canonical,
// smaller than level 0 on a noisy sphere, in segments too.
TEST(Format, FanPredictorAtLevels1And2) {
  const Mesh noisy = tsm_test::jittered(tsm_test::icosphere(4), 0.003f, 5);
  const Mesh smooth = tsm_test::jittered(tsm_test::icosphere(5), 0.0005f, 6);
  for (const auto& [name, m] : {std::pair<std::string, const Mesh*>{"noisy sphere", &noisy}, {"sphere", &smooth}}) {
    const std::string l0 = encode(*m, 12, 0);
    EXPECT_EQ(predictor_of(l0).rfind("gate", 0), 0u) << predictor_of(l0);
    std::string previous = l0;
    for (int level : {1, 2}) {
      SCOPED_TRACE(name + ", level " + std::to_string(level));
      const std::string fan = encode(*m, 12, level);
      EXPECT_EQ(predictor_of(fan).rfind("fan", 0), 0u) << predictor_of(fan);
      EXPECT_LE(fan.size(), previous.size());  // each level tries what the one before did, and more
      previous = fan;
      expect_round_trip(*m, fan, 12, name);
      EXPECT_TRUE(encode(decode_ok(fan), 12, level) == fan);
    }
    EXPECT_LT(previous.size(), l0.size()) << name;
  }
  // Level 2 on the smooth sphere takes the tangent step too.
  EXPECT_EQ(predictor_of(encode(smooth, 12, 2)).rfind("fan+tangent", 0), 0u);
  // Small meshes at levels 1-2: whichever predictor wins, exact and canonical.
  const Mesh small = tsm_test::jittered(tsm_test::icosphere(1), 0.003f, 5);
  for (int level : {1, 2}) {
    const std::string s = encode(small, 12, level);
    expect_round_trip(small, s, 12, "small, level " + std::to_string(level));
    EXPECT_TRUE(encode(decode_ok(s), 12, level) == s);
  }
  // Segments choose their predictors each.
  const std::string seg = encode(smooth, 12, 1, 3000);
  EXPECT_GT(info(seg).segment_count, 1u);
  expect_round_trip(smooth, seg, 12, "fan in segments");
  EXPECT_TRUE(encode(decode_ok(seg), 12, 1, 3000) == seg);
}

// Stitch targets by their rank among candidates (FORMAT.md §8.3.2:
// neighbours of the stitched vertex's known neighbours): on meshes whose
// stitches follow the surface (double-sided ones) nearly every target is the
// first candidate, so the topology stream is far smaller than with the
// targets as distances (ConnectivityEncoding::distance_topology); the
// files round trip exactly and canonically, whole and in segments, and a
// random soup, whose targets are rarely candidates, too.
TEST(Format, StitchTargetsByCandidates) {
  const Mesh sphere = tsm_test::jittered(tsm_test::icosphere(4), 0.003f, 5);
  const std::vector<std::pair<std::string, Mesh>> meshes = {
      {"double-sided sphere", tsm_test::double_sided(sphere)},
      {"double-sided grid with holes", tsm_test::double_sided(tsm_test::grid_with_holes(30, 5))},
      {"books", tsm_test::copies(tsm_test::book(6), 50)},
      {"soup", tsm_test::random_soup(40, 60, 3)},
  };
  for (const auto& [name, m] : meshes) {
    tsm::ConnectivityEncoding ce;
    ASSERT_TRUE(tsm::encode_connectivity(m, ce).ok());
    ASSERT_GT(ce.stats.stitches, 0u) << name;
    ASSERT_FALSE(ce.distance_topology.empty()) << name;
    if (name.rfind("double", 0) == 0) {
      EXPECT_LT(2 * ce.streams.topology.size(), ce.distance_topology.size())
          << name << ": " << ce.distance_topology.size() << " -> " << ce.streams.topology.size();
    }
    for (int level : {0, 6})
      for (uint32_t segment_faces : {0u, 2000u}) {
        SCOPED_TRACE(name + ", level " + std::to_string(level) + ", segments of " + std::to_string(segment_faces));
        const std::string b = encode(m, 12, level, segment_faces);
        EXPECT_GT(info(b).stitches, 0u);
        expect_round_trip(m, b, 12, name);
        EXPECT_TRUE(encode(decode_ok(b), 12, level, segment_faces) == b);
      }
  }
  // Without stitches: no distance coding kept.
  tsm::ConnectivityEncoding ce;
  ASSERT_TRUE(tsm::encode_connectivity(sphere, ce).ok());
  EXPECT_EQ(ce.stats.stitches, 0u);
  EXPECT_TRUE(ce.distance_topology.empty());
}

// Every level writes a file that decodes to the quantized mesh and
// re-encodes to its own bytes, on meshes with stitches, holes and handles.
TEST(Format, EveryLevelRoundTripsCanonically) {
  const std::vector<std::pair<std::string, Mesh>> meshes = {
      {"soup", tsm_test::random_soup(40, 60, 3)},
      {"books", tsm_test::copies(tsm_test::book(6), 10)},
      {"double-sided sphere", tsm_test::double_sided(tsm_test::icosphere(2))},
      {"irregular grid", tsm_test::irregular_grid(20, 3)},
      {"grid with holes", tsm_test::grid_with_holes(12, 3)},
      {"genus 2", tsm_test::genus_surface(2)},
  };
  for (const auto& [name, m] : meshes)
    for (int level : {0, 1, 2, 6, 9}) {
      SCOPED_TRACE(name + ", level " + std::to_string(level));
      const std::string bytes = encode(m, 12, level);
      EXPECT_EQ(info(bytes).format_version, 12u);
      expect_round_trip(m, bytes, 12, name);
      EXPECT_TRUE(encode(decode_ok(bytes), 12, level) == bytes);
    }
}

}  // namespace

namespace {

// FORMAT.md §8.12: a grid bound that is a multiple of 1/64 in -2 .. 2 (0,
// 0.25, 1: texture coordinates in 0..1) takes one byte instead of four;
// the same grid shifted off those values costs 3 bytes more per bound,
// codes the same values, and both round trip and re-encode to their bytes.
TEST(Format, GridBoundsOnSixtyFourthsTakeOneByte) {
  std::string bytes[2];
  for (int shifted = 0; shifted < 2; ++shifted) {
    Mesh m = tsm_test::icosphere(0);
    const float off = shifted ? 1.0f / 1024 : 0.0f;
    tsm::Attribute uv;
    uv.name = "texcoord";
    uv.kind = tsm::AttributeKind::texcoord;
    uv.components = 2;
    for (size_t v = 0; v < m.vertex_count(); ++v) {
      uv.values.push_back(static_cast<float>(v % 5) / 4.0f + off);
      uv.values.push_back(static_cast<float>(v % 3) / 2.0f + off);
    }
    m.attributes = {uv};
    bytes[shifted] = encode(m, 12, 6);
    expect_round_trip(m, bytes[shifted], 12, shifted ? "shifted" : "on sixty-fourths");
    EXPECT_EQ(encode(decode_ok(bytes[shifted]), 12, 6), bytes[shifted]) << "canonical re-encoding";
  }
  EXPECT_EQ(bytes[0].size() + 3 * 3, bytes[1].size()) << "two origins and the top, 1 byte each instead of 4";
}

}  // namespace

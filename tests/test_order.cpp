// The mapping from decoded to input vertices and faces (EncodeMapping, the
// C API's tsm_encode_mapped), keep-order files (EncodeOptions::keep_order,
// tsm encode --keep-order) and lossless files (EncodeOptions::lossless,
// --lossless, --allow-nonfinite): compared array by array, bit for bit.
#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <numeric>
#include <random>

#include "exact_grid.hpp"
#include "mesh_gen.hpp"
#include "order_coding.hpp"
#include "test_util.hpp"
#include "tsm/io.hpp"
#include "tsm/tsm.h"
#include "tsm/tsm.hpp"

using namespace tsm;
using namespace tsm_test;

namespace {

bool is_permutation_of(const std::vector<uint32_t>& p, size_t n) {
  if (p.size() != n) return false;
  std::vector<uint8_t> seen(n, 0);
  for (uint32_t x : p) {
    if (x >= n || seen[x]) return false;
    seen[x] = 1;
  }
  return true;
}

// Exact integer attributes holding each vertex's and each face's input id,
// to be re-indexed through the mapping.
Mesh with_ids(Mesh m) {
  Attribute v;
  v.name = "vertex_id";
  v.type = AttributeType::i32;
  for (uint32_t i = 0; i < m.vertex_count(); ++i) v.values.push_back(static_cast<float>(i));
  Attribute f;
  f.name = "face_id";
  f.domain = AttributeDomain::face;
  f.type = AttributeType::i32;
  for (uint32_t i = 0; i < m.face_count(); ++i) f.values.push_back(static_cast<float>(i));
  m.attributes.push_back(v);
  m.attributes.push_back(f);
  return m;
}

// Every face on vertices of its own (positions repeated): a welded file
// with split vertices.
Mesh split_corners(const Mesh& m) {
  Mesh out;
  for (size_t f = 0; f < m.face_count(); ++f) {
    std::vector<uint32_t> c;
    for (uint32_t k = 0; k < m.face_size(f); ++k) {
      const uint32_t v = m.face(f)[k];
      c.push_back(static_cast<uint32_t>(out.vertex_count()));
      out.add_vertex(m.positions[3 * v], m.positions[3 * v + 1], m.positions[3 * v + 2]);
    }
    out.add_face(c.data(), c.size());
  }
  return out;
}

// A vertex on no face, a face with a repeated corner and a two-corner face.
Mesh with_odd_parts(Mesh m) {
  m.add_vertex(0.25f, 0.5f, -0.75f);
  const uint32_t rep[3] = {0, 0, 1}, two[2] = {2, 3};
  m.add_face(rep, 3);
  m.add_face(two, 2);
  return m;
}

// The decoded mesh against the input re-indexed through the mapping: grid
// positions, corners, and the id attributes, exactly.
void expect_mapped(const Mesh& in, const Mesh& out, const EncodeMapping& map, int bits) {
  ASSERT_TRUE(is_permutation_of(map.vertex_from, in.vertex_count()));
  ASSERT_TRUE(is_permutation_of(map.face_from, in.face_count()));
  ASSERT_EQ(map.first_corner.size(), in.face_count());
  ASSERT_EQ(out.vertex_count(), in.vertex_count());
  ASSERT_EQ(out.face_count(), in.face_count());
  const Grid g = Grid::for_mesh(in, bits);
  for (size_t v = 0; v < out.vertex_count(); ++v)
    for (int a = 0; a < 3; ++a)
      ASSERT_EQ(g.quantize(out.positions[3 * v + a], a),
                g.quantize(in.positions[3 * size_t{map.vertex_from[v]} + a], a))
          << "vertex " << v;
  for (size_t f = 0; f < out.face_count(); ++f) {
    const uint32_t src = map.face_from[f], n = out.face_size(f);
    ASSERT_EQ(in.face_size(src), n);
    for (uint32_t k = 0; k < n; ++k)
      ASSERT_EQ(map.vertex_from[out.face(f)[k]], in.face(src)[(map.first_corner[f] + k) % n]) << "face " << f;
  }
  for (const Attribute& a : out.attributes) {
    if (a.name == "vertex_id") {
      for (size_t v = 0; v < out.vertex_count(); ++v) ASSERT_EQ(a.values[v], static_cast<float>(map.vertex_from[v]));
    }
    if (a.name == "face_id") {
      for (size_t f = 0; f < out.face_count(); ++f) ASSERT_EQ(a.values[f], static_cast<float>(map.face_from[f]));
    }
  }
}

void check_mapping(const Mesh& in, const EncodeOptions& o) {
  std::string bytes;
  EncodeMapping map;
  ASSERT_TRUE(encode(in, o, bytes, &map).ok());
  std::string plain;
  ASSERT_TRUE(encode(in, o, plain).ok());
  EXPECT_EQ(bytes, plain);  // asking for the mapping changes no byte
  Mesh out;
  ASSERT_TRUE(decode(bytes, out).ok());
  expect_mapped(in, out, map, o.quantization_bits);
}

// Keep-order: the decoded mesh is the input, order for order, on the grid;
// re-encoding it gives the same bytes.
void check_keep_order(const Mesh& in, EncodeOptions o) {
  o.keep_order = true;
  std::string bytes;
  EncodeMapping map;
  ASSERT_TRUE(encode(in, o, bytes, &map).ok());
  Mesh out;
  ASSERT_TRUE(decode(bytes, out).ok());
  ASSERT_EQ(out.face_offsets, in.face_offsets);
  ASSERT_EQ(out.indices, in.indices);
  std::vector<uint32_t> id(in.vertex_count());
  std::iota(id.begin(), id.end(), 0u);
  EXPECT_EQ(map.vertex_from, id);
  expect_mapped(in, out, map, o.quantization_bits);
  std::string again;
  ASSERT_TRUE(encode(out, o, again).ok());
  EXPECT_EQ(again, bytes) << "keep-order re-encoding is not canonical";
  StreamDecoder sd;
  ASSERT_TRUE(sd.feed(bytes).ok());
  ASSERT_TRUE(sd.finish().ok());
  EXPECT_EQ(sd.mesh().indices, in.indices);
  EXPECT_EQ(sd.mesh().positions, out.positions);
}

// The mesh with its vertices and faces shuffled and each face rotated.
Mesh shuffled(const Mesh& m, uint32_t seed) {
  const std::vector<uint32_t> vp = tsm_test::random_permutation(m.vertex_count(), seed);
  const std::vector<uint32_t> fp = tsm_test::random_permutation(m.face_count(), seed + 1);
  Mesh out;
  out.positions.resize(m.positions.size());
  for (size_t v = 0; v < m.vertex_count(); ++v)
    for (size_t a = 0; a < 3; ++a) out.positions[3 * size_t{vp[v]} + a] = m.positions[3 * v + a];
  std::vector<uint32_t> inv(m.face_count());
  for (uint32_t f = 0; f < m.face_count(); ++f) inv[fp[f]] = f;
  std::mt19937 rng(seed);
  for (uint32_t g = 0; g < m.face_count(); ++g) {
    const uint32_t f = inv[g], n = m.face_size(f);
    const uint32_t r = n ? static_cast<uint32_t>(rng() % n) : 0;
    std::vector<uint32_t> c;
    for (uint32_t k = 0; k < n; ++k) c.push_back(vp[m.face(f)[(r + k) % n]]);
    out.add_face(c.data(), c.size());
  }
  return out;
}

}  // namespace

TEST(Mapping, CoversEveryKindOfPart) {
  EncodeOptions o;
  o.quantization_bits = 12;
  check_mapping(with_ids(icosphere(2)), o);
  check_mapping(with_ids(with_odd_parts(icosphere(2))), o);
  check_mapping(with_ids(cube_quads()), o);
  check_mapping(with_ids(ngon(7)), o);
  check_mapping(with_ids(moebius(12)), o);
  check_mapping(with_ids(split_corners(icosphere(2))), o);  // welded, split vertices
  check_mapping(with_ids(shuffled(genus_surface(2), 7)), o);
  check_mapping(random_soup(40, 120, 3), o);  // stitches, canonical rounds
  EncodeOptions seg = o;
  seg.segment_faces = 64;
  check_mapping(with_ids(with_odd_parts(icosphere(3))), seg);  // segments, references
  check_mapping(with_ids(shuffled(icosphere(3), 11)), seg);
}

TEST(Mapping, CApiGivesTheSameArrays) {
  const Mesh m = shuffled(icosphere(2), 5);
  tsm_mesh* cm = nullptr;
  char err[256];
  ASSERT_EQ(tsm_mesh_create(m.positions.data(), m.vertex_count(), nullptr, m.face_count(), m.indices.data(),
                            m.indices.size(), &cm, err, sizeof err),
            0)
      << err;
  uint8_t* out = nullptr;
  size_t size = 0;
  uint32_t *vf = nullptr, *ff = nullptr, *fc = nullptr;
  ASSERT_EQ(tsm_encode_mapped(cm, nullptr, &out, &size, &vf, &ff, &fc, err, sizeof err), 0) << err;
  EncodeMapping map;
  std::string bytes;
  ASSERT_TRUE(encode(m, EncodeOptions{}, bytes, &map).ok());
  EXPECT_EQ(std::string(reinterpret_cast<char*>(out), size), bytes);
  EXPECT_EQ(std::vector<uint32_t>(vf, vf + m.vertex_count()), map.vertex_from);
  EXPECT_EQ(std::vector<uint32_t>(ff, ff + m.face_count()), map.face_from);
  EXPECT_EQ(std::vector<uint32_t>(fc, fc + m.face_count()), map.first_corner);
  tsm_free(out), tsm_free(vf), tsm_free(ff), tsm_free(fc);
  tsm_encode_options opt{};
  opt.level = -1;
  opt.keep_order = 1;
  ASSERT_EQ(tsm_encode(cm, &opt, &out, &size, err, sizeof err), 0) << err;
  tsm_mesh* back = nullptr;
  ASSERT_EQ(tsm_decode(out, size, nullptr, &back, err, sizeof err), 0) << err;
  EXPECT_EQ(std::vector<uint32_t>(tsm_mesh_indices(back), tsm_mesh_indices(back) + m.indices.size()), m.indices);
  tsm_free(out);
  tsm_mesh_free(back);
  // Lossless through the C API: the positions bit for bit, in the input's order.
  opt.lossless = 1;
  ASSERT_EQ(tsm_encode(cm, &opt, &out, &size, err, sizeof err), 0) << err;
  ASSERT_EQ(tsm_decode(out, size, nullptr, &back, err, sizeof err), 0) << err;
  EXPECT_EQ(std::memcmp(tsm_mesh_positions(back), m.positions.data(), 4 * m.positions.size()), 0);
  tsm_free(out);
  tsm_mesh_free(back);
  tsm_mesh_free(cm);
}

TEST(KeepOrder, GivesBackTheInputsOrder) {
  EncodeOptions o;
  o.quantization_bits = 12;
  check_keep_order(icosphere(2), o);
  check_keep_order(with_ids(shuffled(icosphere(3), 1)), o);
  check_keep_order(with_ids(with_odd_parts(shuffled(genus_surface(1), 2))), o);
  check_keep_order(shuffled(cube_quads(), 3), o);
  check_keep_order(with_ids(split_corners(shuffled(icosphere(2), 4))), o);
  check_keep_order(random_soup(30, 90, 8), o);
  Mesh empty;
  check_keep_order(empty, o);
  EncodeOptions seg = o;
  seg.segment_faces = 100;
  check_keep_order(with_ids(shuffled(icosphere(3), 6)), seg);
}

TEST(KeepOrder, CornerAttributesFollowTheirCorners) {
  Mesh m = shuffled(cube_quads(), 9);
  Attribute uv;
  uv.name = "texcoord";
  uv.kind = AttributeKind::texcoord;
  uv.domain = AttributeDomain::corner;
  uv.components = 2;
  for (uint32_t i = 0; i < m.indices.size(); ++i) {
    uv.values.push_back(static_cast<float>(i % 5) / 4.0f);
    uv.values.push_back(static_cast<float>(i % 3) / 2.0f);
    uv.indices.push_back(i);
  }
  m.attributes.push_back(uv);
  EncodeOptions o;
  o.keep_order = true;
  std::string bytes;
  ASSERT_TRUE(encode(m, o, bytes).ok());
  Mesh out;
  ASSERT_TRUE(decode(bytes, out).ok());
  ASSERT_EQ(out.indices, m.indices);
  const Attribute& a = out.attributes.at(0);
  for (size_t i = 0; i < m.indices.size(); ++i)
    for (int c = 0; c < 2; ++c)
      EXPECT_NEAR(a.values[2 * size_t{a.indices[i]} + c], uv.values[2 * i + c], 1e-3) << "corner " << i;
}

TEST(KeepOrder, HostileOrderDataIsRefusedOrAPermutation) {
  const Mesh base = icosphere(2);
  std::mt19937 rng(41);
  int refused = 0;
  for (int t = 0; t < tsm_test::property_runs(400); ++t) {
    Mesh m = base;
    const std::string payload = tsm_test::random_bytes(rng, 1 + rng() % 200);
    const Status s = decode_order(payload, m);
    if (!s.ok()) {
      EXPECT_EQ(s.code(), ErrorCode::corrupt_data);
      ++refused;
      continue;
    }
    ASSERT_EQ(m.vertex_count(), base.vertex_count());
    ASSERT_EQ(m.face_offsets, base.face_offsets);
    for (uint32_t x : m.indices) ASSERT_LT(x, m.vertex_count());
  }
  EXPECT_GT(refused, 0);
  // A real payload cut short is refused.
  EncodeOptions o;
  o.keep_order = true;
  std::string bytes;
  const Mesh in = shuffled(base, 2);
  ASSERT_TRUE(encode(in, o, bytes).ok());
  Mesh decoded;
  EncodeMapping map;
  std::string plain;
  ASSERT_TRUE(encode(in, EncodeOptions{}, plain, &map).ok());
  ASSERT_TRUE(decode(plain, decoded).ok());
  const std::string order = encode_order(decoded, map.vertex_from, map.face_from, map.first_corner);
  Mesh whole = decoded;
  ASSERT_TRUE(decode_order(order, whole).ok());
  EXPECT_EQ(whole.indices, in.indices);
  Mesh cut = decoded;
  EXPECT_FALSE(decode_order(order.substr(0, order.size() / 2), cut).ok());
}

// A grid of `cols` x `rows` vertices in raster order (rows along y), two
// triangles per cell in raster order: a sweep, as scans and marching cubes
// write their files.
Mesh raster_grid(int cols, int rows) {
  Mesh m;
  std::mt19937 rng(7);
  for (int y = 0; y < rows; ++y)
    for (int x = 0; x < cols; ++x)
      m.add_vertex(static_cast<float>(x), static_cast<float>(y), static_cast<float>(rng() % 100) * 0.001f);
  for (int y = 0; y + 1 < rows; ++y)
    for (int x = 0; x + 1 < cols; ++x) {
      const uint32_t a = static_cast<uint32_t>(y * cols + x), b = a + 1, c = a + static_cast<uint32_t>(cols), d = c + 1;
      m.add_triangle(a, b, d);
      m.add_triangle(a, d, c);
    }
  return m;
}

// The order payload of `in` (keep-order), by encode_order on its decoded mesh.
size_t order_bytes(const Mesh& in) {
  Mesh decoded;
  EncodeMapping map;
  std::string plain;
  EXPECT_TRUE(encode(in, EncodeOptions{}, plain, &map).ok());
  EXPECT_TRUE(decode(plain, decoded).ok());
  return encode_order(decoded, map.vertex_from, map.face_from, map.first_corner).size();
}

// `m` with its vertex ids permuted; faces in the same order, same corners.
Mesh renumbered(const Mesh& m, uint32_t seed) {
  const std::vector<uint32_t> vp = tsm_test::random_permutation(m.vertex_count(), seed);
  Mesh out;
  out.positions.resize(m.positions.size());
  for (size_t v = 0; v < m.vertex_count(); ++v)
    for (size_t a = 0; a < 3; ++a) out.positions[3 * size_t{vp[v]} + a] = m.positions[3 * v + a];
  for (uint32_t f = 0; f < m.face_count(); ++f) {
    std::vector<uint32_t> c;
    for (uint32_t k = 0; k < m.face_size(f); ++k) c.push_back(vp[m.face(f)[k]]);
    out.add_face(c.data(), c.size());
  }
  return out;
}

TEST(KeepOrder, ASweptOrderCostsLittle) {
  // 1,200 rows of 3 vertices: every third vertex is no neighbour of the one
  // before, but the next one in sweep order (a jump of 0); the faces follow
  // the rows too. The whole order costs under 4 bits a vertex (1,347 bytes;
  // 2,876 when jumps went by the decoder's vertex order and the first
  // corner of the face before).
  const Mesh in = raster_grid(3, 1200);
  check_keep_order(in, EncodeOptions{});
  const size_t swept = order_bytes(in);
  EXPECT_LT(swept * 8, 4 * in.vertex_count()) << swept;
  // Renumbering the vertices at random changes only the vertex part of the
  // payload (the faces are coded on the decoded mesh): over 10 bits more a
  // vertex.
  const size_t random = order_bytes(renumbered(in, 5));
  EXPECT_GT(random, swept + in.vertex_count() * 10 / 8) << swept << " vs " << random;
}

// `m` with its faces in a random order, each starting at its corner with
// the smallest (x, y) (`by_position`) or at a random corner.
Mesh faces_shuffled(const Mesh& m, bool by_position, uint32_t seed) {
  const std::vector<uint32_t> fp = tsm_test::random_permutation(m.face_count(), seed);
  std::vector<uint32_t> inv(m.face_count());
  for (uint32_t f = 0; f < m.face_count(); ++f) inv[fp[f]] = f;
  std::mt19937 rng(seed);
  Mesh out;
  out.positions = m.positions;
  for (uint32_t g = 0; g < m.face_count(); ++g) {
    const uint32_t f = inv[g], n = m.face_size(f);
    const uint32_t* c = m.face(f);
    uint32_t r = static_cast<uint32_t>(rng() % n);
    if (by_position)
      for (uint32_t k = 0; k < n; ++k) {
        const float* p = &m.positions[3 * size_t{c[k]}];
        const float* q = &m.positions[3 * size_t{c[r]}];
        if (std::make_pair(p[0], p[1]) < std::make_pair(q[0], q[1])) r = k;
      }
    std::vector<uint32_t> d;
    for (uint32_t k = 0; k < n; ++k) d.push_back(c[(r + k) % n]);
    out.add_face(d.data(), d.size());
  }
  return out;
}

TEST(KeepOrder, FirstCornersFollowingTheLatticeCostLittle) {
  // The raster grid's vertices lie on the planes x = i and y = j (each
  // shared by many vertices), so each triangle corner's label says which of
  // its coordinates are the triangle's smallest: a first corner chosen by
  // position, as marching cubes chooses it by cube edge, is predicted by
  // them, where a random one costs log2(3) = 1.58 bits a face.
  const Mesh grid = raster_grid(40, 40);
  const Mesh ruled = faces_shuffled(grid, true, 3), random = faces_shuffled(grid, false, 3);
  check_keep_order(ruled, EncodeOptions{});
  check_keep_order(random, EncodeOptions{});
  const size_t a = order_bytes(ruled), b = order_bytes(random);
  EXPECT_GT(b * 8, a * 8 + grid.face_count()) << a << " vs " << b;
}

TEST(KeepOrder, CorpusMeshesInTheirFilesOrder) {
  TSM_REQUIRE_CORPUS();
  Mesh in;
  ASSERT_TRUE(read_mesh(tsm_test::corpus_file("bun_zipper.ply"), in).ok());
  check_keep_order(in, EncodeOptions{});
}

TEST(KeepOrder, CommandLineFlag) {
  tsm_test::TempDir dir;
  const Mesh m = shuffled(icosphere(2), 12);
  ASSERT_TRUE(write_mesh(dir.file("in.ply"), m).ok());
  const std::string cli = TSM_CLI_PATH;
  ASSERT_EQ(std::system(
                (cli + " encode --keep-order " + dir.file("in.ply") + " -o " + dir.file("k.tsm") + " > /dev/null 2>&1")
                    .c_str()),
            0);
  ASSERT_EQ(
      std::system((cli + " decode " + dir.file("k.tsm") + " -o " + dir.file("k.ply") + " > /dev/null 2>&1").c_str()),
      0);
  Mesh back;
  ASSERT_TRUE(read_mesh(dir.file("k.ply"), back).ok());
  EXPECT_EQ(back.indices, m.indices);
  // Without the flag the order is the decoder's own.
  ASSERT_EQ(
      std::system((cli + " encode " + dir.file("in.ply") + " -o " + dir.file("d.tsm") + " > /dev/null 2>&1").c_str()),
      0);
  ASSERT_EQ(
      std::system((cli + " decode " + dir.file("d.tsm") + " -o " + dir.file("d.ply") + " > /dev/null 2>&1").c_str()),
      0);
  Mesh plain;
  ASSERT_TRUE(read_mesh(dir.file("d.ply"), plain).ok());
  EXPECT_NE(plain.indices, m.indices);
}

namespace {

// Lossless round trip: every coordinate's bits, faces and order as the
// mapping says; re-encoding the decoded mesh gives the same bytes.
void check_lossless(const Mesh& in, EncodeOptions o) {
  o.lossless = true;
  std::string bytes;
  EncodeMapping map;
  const Status s = encode(in, o, bytes, &map);
  ASSERT_TRUE(s.ok()) << s.message();
  Mesh out;
  ASSERT_TRUE(decode(bytes, out).ok());
  ASSERT_EQ(out.vertex_count(), in.vertex_count());
  for (size_t v = 0; v < out.vertex_count(); ++v)
    ASSERT_EQ(std::memcmp(&out.positions[3 * v], &in.positions[3 * size_t{map.vertex_from[v]}], 12), 0)
        << "vertex " << v << ": " << out.positions[3 * v] << " " << in.positions[3 * size_t{map.vertex_from[v]}];
  for (size_t f = 0; f < out.face_count(); ++f)
    for (uint32_t k = 0; k < out.face_size(f); ++k)
      ASSERT_EQ(map.vertex_from[out.face(f)[k]],
                in.face(map.face_from[f])[(map.first_corner[f] + k) % out.face_size(f)]);
  std::string again;
  ASSERT_TRUE(encode(out, o, again).ok());
  EXPECT_EQ(again, bytes) << "lossless re-encoding is not canonical";
  StreamDecoder sd;
  ASSERT_TRUE(sd.feed(bytes).ok());
  ASSERT_TRUE(sd.finish().ok());
  EXPECT_EQ(std::memcmp(sd.mesh().positions.data(), out.positions.data(), 4 * out.positions.size()), 0);
}

// A mesh's positions replaced by `values` (cycled).
Mesh with_positions(Mesh m, const std::vector<float>& values) {
  for (size_t i = 0; i < m.positions.size(); ++i) m.positions[i] = values[i % values.size()];
  return m;
}

}  // namespace

TEST(Lossless, DecimalCoordinatesOnTheirGrid) {
  // Six significant digits, as ascii PLY files have them.
  Mesh m = icosphere(3);
  for (float& x : m.positions) x = std::stof(std::to_string(x * 0.137f).substr(0, 9));
  check_lossless(m, EncodeOptions{});
  EncodeOptions seg;
  seg.segment_faces = 200;
  check_lossless(m, seg);
  seg.keep_order = true;
  check_lossless(shuffled(m, 3), seg);
}

TEST(Lossless, AnyFloatBitForBit) {
  std::mt19937 rng(7);
  std::vector<float> odd = {0.0f,     -0.0f,  1e-45f,      -1e-45f, 1.17e-38f, 3.0e38f,
                            -3.0e38f, 1e-30f, 123456.789f, -7.0f,   0.1f,      1.0f + 1.0f / 8388608.0f};
  for (int i = 0; i < 300; ++i) odd.push_back(tsm_test::from_bits(static_cast<uint32_t>(rng()) & 0xFF7FFFFFu));
  check_lossless(with_positions(icosphere(2), odd), EncodeOptions{});
  check_lossless(with_positions(with_odd_parts(genus_surface(1)), odd), EncodeOptions{});
  std::vector<float> tiny;
  for (int i = 0; i < 50; ++i) tiny.push_back(tsm_test::from_bits(static_cast<uint32_t>(rng()) % 0x00800000u));
  check_lossless(with_positions(icosphere(1), tiny), EncodeOptions{});  // denormals only
  check_lossless(split_corners(icosphere(2)), EncodeOptions{});
}

TEST(Lossless, NonFiniteOnlyWhenAllowed) {
  const float inf = std::numeric_limits<float>::infinity();
  Mesh m = icosphere(1);
  m.positions[4] = std::numeric_limits<float>::quiet_NaN();
  m.positions[7] = -inf;
  m.positions[9] = tsm_test::from_bits(0x7FC12345u);  // a NaN with a payload
  std::string bytes;
  EncodeOptions o;
  o.lossless = true;
  Status s = encode(m, o, bytes);
  EXPECT_EQ(s.code(), ErrorCode::invalid_argument);
  EXPECT_TRUE(tsm_test::contains(s.message(), "--allow-nonfinite"));
  s = encode(m, EncodeOptions{}, bytes);
  EXPECT_TRUE(tsm_test::contains(s.message(), "--lossless --allow-nonfinite"));
  o.allow_nonfinite = true;
  check_lossless(m, o);
}

TEST(Lossless, HostileExceptionsAreRefused) {
  std::vector<float> p(30, 1.0f);
  std::mt19937 rng(3);
  int refused = 0;
  for (int t = 0; t < 500; ++t) {
    std::vector<float> q = p;
    const Status s = apply_exceptions(tsm_test::random_bytes(rng, rng() % 40), q);
    if (!s.ok()) {
      EXPECT_EQ(s.code(), ErrorCode::corrupt_data);
      ++refused;
    }
  }
  EXPECT_GT(refused, 400);
  std::vector<float> q = p;
  EXPECT_FALSE(apply_exceptions(std::string("\x01\x1e\x02", 3), q).ok());                  // coordinate 30 of 30
  EXPECT_FALSE(apply_exceptions(std::string("\x01\x00\xff\xff\xff\xff\x1f", 7), q).ok());  // past the floats
  EXPECT_TRUE(apply_exceptions(std::string("\x01\x02\x02", 3), q).ok());
  EXPECT_EQ(tsm_test::bits(q[2]), tsm_test::bits(1.0f) + 1);
}

TEST(Lossless, CorpusBunnyBitForBit) {
  TSM_REQUIRE_CORPUS();
  Mesh in;
  ASSERT_TRUE(read_mesh(tsm_test::corpus_file("bun_zipper.ply"), in).ok());
  check_lossless(in, EncodeOptions{});
}

TEST(Lossless, CommandLineFlags) {
  tsm_test::TempDir dir;
  Mesh m = icosphere(2);
  for (float& x : m.positions) x = x * 0.3183099f + 1e-3f;
  ASSERT_TRUE(write_mesh(dir.file("in.ply"), m).ok());
  const std::string cli = TSM_CLI_PATH;
  ASSERT_EQ(std::system((cli + " encode --lossless --keep-order " + dir.file("in.ply") + " -o " + dir.file("l.tsm") +
                         " > /dev/null 2>&1")
                            .c_str()),
            0);
  ASSERT_EQ(
      std::system((cli + " decode " + dir.file("l.tsm") + " -o " + dir.file("l.ply") + " > /dev/null 2>&1").c_str()),
      0);
  Mesh back;
  ASSERT_TRUE(read_mesh(dir.file("l.ply"), back).ok());
  EXPECT_EQ(back.indices, m.indices);
  ASSERT_EQ(back.positions.size(), m.positions.size());
  EXPECT_EQ(std::memcmp(back.positions.data(), m.positions.data(), 4 * m.positions.size()), 0);
  // tsm info names both.
  ASSERT_EQ(std::system((cli + " info " + dir.file("l.tsm") + " > " + dir.file("info.txt") + " 2>&1").c_str()), 0);
  std::ifstream f(dir.file("info.txt"));
  const std::string info((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  EXPECT_NE(info.find("lossless: every float32 coordinate exact"), std::string::npos) << info;
  EXPECT_NE(info.find("keep-order:"), std::string::npos) << info;
  EXPECT_EQ(info.find("quantization"), std::string::npos) << info;
  // -q means nothing with --lossless: refused (exit 2), no file written.
  EXPECT_EQ(std::system((cli + " encode --lossless -q 12 " + dir.file("in.ply") + " -o " + dir.file("q.tsm") +
                         " > /dev/null 2>&1")
                            .c_str()),
            2 << 8);
  EXPECT_FALSE(std::ifstream(dir.file("q.tsm")).good());
}

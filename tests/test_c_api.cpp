// The C API (tsm.h): create, encode, decode, accessors, free; error codes and
// messages for null arguments, bad data and limits.
#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "mesh_gen.hpp"
#include "tsm/tsm.h"
#include "tsm/tsm.hpp"

namespace {

// Owns a tsm_mesh* / encoded buffer for the test's duration.
struct MeshPtr {
  tsm_mesh* p = nullptr;
  ~MeshPtr() { tsm_mesh_free(p); }
};
struct Buffer {
  uint8_t* p = nullptr;
  size_t n = 0;
  ~Buffer() { tsm_free(p); }
};

tsm::Mesh view(const tsm_mesh* m) {
  tsm::Mesh out;
  const float* pos = tsm_mesh_positions(m);
  out.positions.assign(pos, pos + 3 * tsm_mesh_vertex_count(m));
  const uint32_t* off = tsm_mesh_face_offsets(m);
  out.face_offsets.assign(off, off + tsm_mesh_face_count(m) + 1);
  const uint32_t* idx = tsm_mesh_indices(m);
  out.indices.assign(idx, idx + tsm_mesh_index_count(m));
  return out;
}

int create_from(const tsm::Mesh& src, tsm_mesh** out, char* err, size_t err_size, bool with_sizes = true) {
  std::vector<uint32_t> sizes(src.face_count());
  for (size_t f = 0; f < src.face_count(); ++f) sizes[f] = src.face_size(f);
  return tsm_mesh_create(src.positions.data(), src.vertex_count(), with_sizes ? sizes.data() : nullptr,
                         src.face_count(), src.indices.data(), src.corner_count(), out, err, err_size);
}

TEST(CApi, Version) {
  ASSERT_NE(tsm_version(), nullptr);
  EXPECT_STREQ(tsm_version(), tsm::version_string());
  EXPECT_GT(std::strlen(tsm_version()), 0u);
}

TEST(CApi, CreateEncodeDecodeRoundTrip) {
  const tsm::Mesh src = tsm_test::copies(tsm_test::cube_quads(), 2);
  char err[256] = "sentinel";
  MeshPtr m;
  ASSERT_EQ(create_from(src, &m.p, err, sizeof err), TSM_OK) << err;
  EXPECT_STREQ(err, "");  // cleared on success
  ASSERT_NE(m.p, nullptr);
  EXPECT_EQ(tsm_mesh_vertex_count(m.p), src.vertex_count());
  EXPECT_EQ(tsm_mesh_face_count(m.p), src.face_count());
  EXPECT_EQ(tsm_mesh_index_count(m.p), src.corner_count());
  tsm::Mesh copy = view(m.p);
  EXPECT_EQ(copy.positions, src.positions);
  EXPECT_EQ(copy.face_offsets, src.face_offsets);
  EXPECT_EQ(copy.indices, src.indices);

  Buffer buf;
  tsm_encode_options eo{12, 5, 0, 0};
  ASSERT_EQ(tsm_encode(m.p, &eo, &buf.p, &buf.n, err, sizeof err), TSM_OK) << err;
  ASSERT_NE(buf.p, nullptr);
  ASSERT_GT(buf.n, 0u);
  // Same bytes as the C++ API.
  std::string cpp;
  ASSERT_TRUE(tsm::encode(src, tsm::EncodeOptions{12, 5}, cpp).ok());
  EXPECT_EQ(std::string(reinterpret_cast<const char*>(buf.p), buf.n), cpp);

  MeshPtr back;
  ASSERT_EQ(tsm_decode(buf.p, buf.n, nullptr, &back.p, err, sizeof err), TSM_OK) << err;
  ASSERT_NE(back.p, nullptr);
  auto r = tsm::compare_meshes(src, view(back.p), 12);
  EXPECT_TRUE(r.equal) << r.difference;
}

TEST(CApi, TrianglesWithoutFaceSizes) {
  const tsm::Mesh src = tsm_test::icosphere(2);
  MeshPtr m;
  char err[128];
  ASSERT_EQ(create_from(src, &m.p, err, sizeof err, /*with_sizes=*/false), TSM_OK) << err;
  EXPECT_EQ(view(m.p).face_offsets, src.face_offsets);
  Buffer buf;
  ASSERT_EQ(tsm_encode(m.p, nullptr, &buf.p, &buf.n, err, sizeof err), TSM_OK) << err;
  MeshPtr back;
  ASSERT_EQ(tsm_decode(buf.p, buf.n, nullptr, &back.p, nullptr, 0), TSM_OK);
  EXPECT_TRUE(tsm::compare_meshes(src, view(back.p), tsm::kDefaultQuantizationBits).equal);
}

TEST(CApi, DefaultOptions) {
  const tsm::Mesh src = tsm_test::icosphere(1);
  MeshPtr m;
  ASSERT_EQ(create_from(src, &m.p, nullptr, 0), TSM_OK);
  std::string cpp;
  ASSERT_TRUE(tsm::encode(src, tsm::EncodeOptions{}, cpp).ok());
  // quantization_bits = 0 and level = -1 mean the defaults; so does NULL.
  tsm_encode_options defaults{0, -1, 0, 0};
  Buffer a, b;
  ASSERT_EQ(tsm_encode(m.p, &defaults, &a.p, &a.n, nullptr, 0), TSM_OK);
  ASSERT_EQ(tsm_encode(m.p, nullptr, &b.p, &b.n, nullptr, 0), TSM_OK);
  EXPECT_EQ(std::string(reinterpret_cast<const char*>(a.p), a.n), cpp);
  EXPECT_EQ(std::string(reinterpret_cast<const char*>(b.p), b.n), cpp);
}

TEST(CApi, EmptyMesh) {
  MeshPtr m;
  char err[64];
  ASSERT_EQ(tsm_mesh_create(nullptr, 0, nullptr, 0, nullptr, 0, &m.p, err, sizeof err), TSM_OK) << err;
  EXPECT_EQ(tsm_mesh_vertex_count(m.p), 0u);
  EXPECT_EQ(tsm_mesh_face_count(m.p), 0u);
  ASSERT_NE(tsm_mesh_face_offsets(m.p), nullptr);
  EXPECT_EQ(tsm_mesh_face_offsets(m.p)[0], 0u);
  Buffer buf;
  ASSERT_EQ(tsm_encode(m.p, nullptr, &buf.p, &buf.n, err, sizeof err), TSM_OK) << err;
  MeshPtr back;
  ASSERT_EQ(tsm_decode(buf.p, buf.n, nullptr, &back.p, err, sizeof err), TSM_OK) << err;
  EXPECT_EQ(tsm_mesh_vertex_count(back.p), 0u);
  EXPECT_EQ(tsm_mesh_index_count(back.p), 0u);
}

TEST(CApi, NullArguments) {
  char err[128];
  const float pos[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  const uint32_t idx[3] = {0, 1, 2};
  EXPECT_EQ(tsm_mesh_create(pos, 3, nullptr, 1, idx, 3, nullptr, err, sizeof err), TSM_INVALID_ARGUMENT);
  EXPECT_STREQ(err, "null argument");
  tsm_mesh* m = nullptr;
  EXPECT_EQ(tsm_mesh_create(nullptr, 3, nullptr, 1, idx, 3, &m, err, sizeof err), TSM_INVALID_ARGUMENT);
  EXPECT_EQ(m, nullptr);
  EXPECT_EQ(tsm_mesh_create(pos, 3, nullptr, 1, nullptr, 3, &m, err, sizeof err), TSM_INVALID_ARGUMENT);
  EXPECT_EQ(m, nullptr);
  EXPECT_NE(std::string(err).find("null"), std::string::npos) << err;

  MeshPtr ok;
  ASSERT_EQ(tsm_mesh_create(pos, 3, nullptr, 1, idx, 3, &ok.p, err, sizeof err), TSM_OK);
  uint8_t* out = nullptr;
  size_t n = 0;
  EXPECT_EQ(tsm_encode(nullptr, nullptr, &out, &n, err, sizeof err), TSM_INVALID_ARGUMENT);
  EXPECT_EQ(tsm_encode(ok.p, nullptr, nullptr, &n, err, sizeof err), TSM_INVALID_ARGUMENT);
  EXPECT_EQ(tsm_encode(ok.p, nullptr, &out, nullptr, err, sizeof err), TSM_INVALID_ARGUMENT);
  EXPECT_EQ(out, nullptr);

  tsm_mesh* d = nullptr;
  EXPECT_EQ(tsm_decode(nullptr, 10, nullptr, &d, err, sizeof err), TSM_INVALID_ARGUMENT);
  EXPECT_EQ(tsm_decode(reinterpret_cast<const uint8_t*>("x"), 1, nullptr, nullptr, err, sizeof err),
            TSM_INVALID_ARGUMENT);
  // NULL data with size 0 is an empty buffer: not a .tsm file.
  EXPECT_EQ(tsm_decode(nullptr, 0, nullptr, &d, err, sizeof err), TSM_CORRUPT_DATA);
  EXPECT_EQ(d, nullptr);

  // Accessors and frees accept NULL.
  EXPECT_EQ(tsm_mesh_vertex_count(nullptr), 0u);
  EXPECT_EQ(tsm_mesh_face_count(nullptr), 0u);
  EXPECT_EQ(tsm_mesh_index_count(nullptr), 0u);
  EXPECT_EQ(tsm_mesh_positions(nullptr), nullptr);
  EXPECT_EQ(tsm_mesh_face_offsets(nullptr), nullptr);
  EXPECT_EQ(tsm_mesh_indices(nullptr), nullptr);
  tsm_mesh_free(nullptr);
  tsm_free(nullptr);
}

TEST(CApi, InvalidMeshesRefused) {
  char err[256];
  const float pos[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
  tsm_mesh* m = nullptr;
  const uint32_t out_of_range[3] = {0, 1, 4};
  EXPECT_EQ(tsm_mesh_create(pos, 4, nullptr, 1, out_of_range, 3, &m, err, sizeof err), TSM_INVALID_ARGUMENT);
  EXPECT_EQ(m, nullptr);
  EXPECT_NE(std::string(err).find("vertex 4"), std::string::npos) << err;

  const uint32_t idx[6] = {0, 1, 2, 0, 2, 3};
  const uint32_t sizes_bad[2] = {3, 4};  // sums to 7, not 6
  EXPECT_EQ(tsm_mesh_create(pos, 4, sizes_bad, 2, idx, 6, &m, err, sizeof err), TSM_INVALID_ARGUMENT);
  EXPECT_NE(std::string(err).find("face sizes"), std::string::npos) << err;
  EXPECT_EQ(tsm_mesh_create(pos, 4, nullptr, 3, idx, 6, &m, err, sizeof err), TSM_INVALID_ARGUMENT);
  EXPECT_EQ(m, nullptr);

  const uint32_t sizes_ok[2] = {2, 4};  // polygons of any size add up
  MeshPtr ok;
  EXPECT_EQ(tsm_mesh_create(pos, 4, sizes_ok, 2, idx, 6, &ok.p, err, sizeof err), TSM_OK) << err;
  EXPECT_EQ(tsm_mesh_face_offsets(ok.p)[1], 2u);

  // NaN positions are accepted into a mesh but refused by the encoder.
  const float nan_pos[9] = {0, 0, 0, 1, 0, 0, 0, std::numeric_limits<float>::quiet_NaN(), 0};
  MeshPtr nm;
  ASSERT_EQ(tsm_mesh_create(nan_pos, 3, nullptr, 1, idx, 3, &nm.p, err, sizeof err), TSM_OK) << err;
  uint8_t stale = 0;
  uint8_t* out = &stale;  // reset to NULL on failure
  size_t out_n = 99;
  EXPECT_EQ(tsm_encode(nm.p, nullptr, &out, &out_n, err, sizeof err), TSM_INVALID_ARGUMENT);
  EXPECT_EQ(out, nullptr);
  EXPECT_EQ(out_n, 0u);
  EXPECT_NE(std::string(err).find("NaN"), std::string::npos) << err;

  // Bad options.
  MeshPtr good;
  ASSERT_EQ(tsm_mesh_create(pos, 3, nullptr, 1, idx, 3, &good.p, err, sizeof err), TSM_OK);
  tsm_encode_options bad_q{31, -1, 0, 0}, bad_level{14, 10, 0, 0};
  EXPECT_EQ(tsm_encode(good.p, &bad_q, &out, &out_n, err, sizeof err), TSM_INVALID_ARGUMENT);
  EXPECT_NE(std::string(err).find("quantization"), std::string::npos) << err;
  EXPECT_EQ(tsm_encode(good.p, &bad_level, &out, &out_n, err, sizeof err), TSM_INVALID_ARGUMENT);
  EXPECT_NE(std::string(err).find("level"), std::string::npos) << err;
}

TEST(CApi, BadDataAndMessages) {
  char err[256];
  tsm_mesh* m = nullptr;
  const uint8_t junk[] = {'n', 'o', 't', ' ', 'a', ' ', 't', 's', 'm'};
  EXPECT_EQ(tsm_decode(junk, sizeof junk, nullptr, &m, err, sizeof err), TSM_CORRUPT_DATA);
  EXPECT_EQ(m, nullptr);
  EXPECT_NE(std::string(err).find("magic"), std::string::npos) << err;

  std::string bytes;
  ASSERT_TRUE(tsm::encode(tsm_test::icosphere(1), tsm::EncodeOptions{}, bytes).ok());
  const auto* data = reinterpret_cast<const uint8_t*>(bytes.data());
  // Truncated.
  EXPECT_EQ(tsm_decode(data, bytes.size() - 1, nullptr, &m, err, sizeof err), TSM_CORRUPT_DATA);
  EXPECT_EQ(m, nullptr);
  EXPECT_GT(std::strlen(err), 0u);
  // A damaged payload byte.
  std::string bad = bytes;
  bad[bad.size() - 10] = static_cast<char>(bad[bad.size() - 10] ^ 0x40);
  EXPECT_EQ(tsm_decode(reinterpret_cast<const uint8_t*>(bad.data()), bad.size(), nullptr, &m, err, sizeof err),
            TSM_CORRUPT_DATA);
  EXPECT_EQ(m, nullptr);

  // Messages are truncated to err_size, always NUL-terminated.
  char small[8];
  std::memset(small, 'x', sizeof small);
  EXPECT_EQ(tsm_decode(junk, sizeof junk, nullptr, &m, small, sizeof small), TSM_CORRUPT_DATA);
  EXPECT_EQ(std::strlen(small), sizeof small - 1);
  char one[1] = {'x'};
  EXPECT_EQ(tsm_decode(junk, sizeof junk, nullptr, &m, one, 1), TSM_CORRUPT_DATA);
  EXPECT_EQ(one[0], '\0');
  // err_size 0 writes nothing.
  char none[2] = {'x', 'y'};
  EXPECT_EQ(tsm_decode(junk, sizeof junk, nullptr, &m, none, 0), TSM_CORRUPT_DATA);
  EXPECT_EQ(none[0], 'x');
}

TEST(CApi, DecodeLimits) {
  const tsm::Mesh src = tsm_test::icosphere(2);
  std::string bytes;
  ASSERT_TRUE(tsm::encode(src, tsm::EncodeOptions{}, bytes).ok());
  const auto* data = reinterpret_cast<const uint8_t*>(bytes.data());
  char err[256];
  tsm_mesh* m = nullptr;
  tsm_decode_options o{src.vertex_count() - 1, 0, 0, 0};
  EXPECT_EQ(tsm_decode(data, bytes.size(), &o, &m, err, sizeof err), TSM_LIMIT_EXCEEDED);
  EXPECT_EQ(m, nullptr);
  EXPECT_NE(std::string(err).find("limit"), std::string::npos) << err;
  o = {0, src.face_count() - 1, 0, 0};
  EXPECT_EQ(tsm_decode(data, bytes.size(), &o, &m, err, sizeof err), TSM_LIMIT_EXCEEDED);
  EXPECT_EQ(m, nullptr);
  o = {0, 0, src.corner_count() - 1, 0};
  EXPECT_EQ(tsm_decode(data, bytes.size(), &o, &m, err, sizeof err), TSM_LIMIT_EXCEEDED);
  EXPECT_EQ(m, nullptr);
  o = {src.vertex_count(), src.face_count(), 0, 0};
  MeshPtr ok;
  EXPECT_EQ(tsm_decode(data, bytes.size(), &o, &ok.p, err, sizeof err), TSM_OK) << err;
  EXPECT_EQ(tsm_mesh_vertex_count(ok.p), src.vertex_count());
}

TEST(CApi, ErrorCodesMatchCpp) {
  EXPECT_EQ(TSM_OK, static_cast<int>(tsm::ErrorCode::ok));
  EXPECT_EQ(TSM_INVALID_ARGUMENT, static_cast<int>(tsm::ErrorCode::invalid_argument));
  EXPECT_EQ(TSM_IO_ERROR, static_cast<int>(tsm::ErrorCode::io_error));
  EXPECT_EQ(TSM_PARSE_ERROR, static_cast<int>(tsm::ErrorCode::parse_error));
  EXPECT_EQ(TSM_CORRUPT_DATA, static_cast<int>(tsm::ErrorCode::corrupt_data));
  EXPECT_EQ(TSM_UNSUPPORTED, static_cast<int>(tsm::ErrorCode::unsupported));
  EXPECT_EQ(TSM_LIMIT_EXCEEDED, static_cast<int>(tsm::ErrorCode::limit_exceeded));
  EXPECT_EQ(TSM_INTERNAL, static_cast<int>(tsm::ErrorCode::internal));
}

}  // namespace

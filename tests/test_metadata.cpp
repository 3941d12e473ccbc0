// Mesh::metadata: passed through the codec byte for byte (FORMAT.md §4.6),
// whole files, segmented files and the stream decoder.
#include <gtest/gtest.h>

#include <random>
#include <string>

#include "mesh_gen.hpp"
#include "test_util.hpp"
#include "tsm/tsm.hpp"

namespace {

using tsm::Mesh;

std::string some_bytes(size_t n, uint32_t seed) {
  std::mt19937 rng(seed);
  return tsm_test::random_bytes(rng, n);
}

std::string encode_ok(const Mesh& m, uint32_t segment_faces = 0) {
  tsm::EncodeOptions eo;
  eo.segment_faces = segment_faces;
  std::string bytes;
  const tsm::Status s = tsm::encode(m, eo, bytes);
  EXPECT_TRUE(s.ok()) << s.to_string();
  return bytes;
}

TEST(Metadata, RoundTripsExactlyWholeAndSegmented) {
  Mesh m = tsm_test::icosphere(2);
  m.metadata = {{"gltf", "{\"materials\":[{\"name\":\"red\"}]}"},
                {"binary", some_bytes(5000, 1)},                // incompressible
                {"text", std::string(20000, 'a') + "end"},     // compresses well
                {"empty-value", ""},
                {std::string(255, 'k'), std::string("\0\0\0", 3)}};
  for (uint32_t seg : {0u, 60u}) {
    const std::string bytes = encode_ok(m, seg);
    Mesh back;
    ASSERT_TRUE(tsm::decode(bytes, back).ok());
    ASSERT_EQ(back.metadata.size(), m.metadata.size());
    for (size_t i = 0; i < m.metadata.size(); ++i) {
      EXPECT_EQ(back.metadata[i].key, m.metadata[i].key);
      EXPECT_EQ(back.metadata[i].value, m.metadata[i].value) << m.metadata[i].key;
    }
    const tsm::CompareResult r = tsm::compare_meshes(m, back, 14);
    EXPECT_TRUE(r.equal) << r.difference;
    // The compressible entry is stored compressed: the file is far smaller than the entries.
    EXPECT_LT(bytes.size(), 20000u) << "segment_faces " << seg;
    tsm::FileInfo info;
    ASSERT_TRUE(tsm::inspect(bytes, info).ok());
    bool listed = false;
    for (const tsm::SectionInfo& s : info.sections) listed = listed || s.name == "metadata";
    EXPECT_TRUE(listed);
  }
}

TEST(Metadata, OracleSeesADifference) {
  Mesh m = tsm_test::icosphere(1);
  m.metadata = {{"a", "1"}};
  Mesh back;
  ASSERT_TRUE(tsm::decode(encode_ok(m), back).ok());
  back.metadata[0].value = "2";
  EXPECT_FALSE(tsm::compare_meshes(m, back, 14).equal);
  back.metadata.clear();
  EXPECT_FALSE(tsm::compare_meshes(m, back, 14).equal);
}

TEST(Metadata, StreamDecoderHasItBeforeAnyGeometry) {
  Mesh m = tsm_test::icosphere(3);
  m.metadata = {{"gltf", some_bytes(300, 2)}};
  const std::string bytes = encode_ok(m, 200);
  tsm::StreamDecoder sd;
  size_t fed = 0;
  while (fed < bytes.size() && sd.mesh().vertex_count() == 0) {
    ASSERT_TRUE(sd.feed(std::string_view(bytes).substr(fed, 1)).ok());
    ++fed;
  }
  ASSERT_EQ(sd.mesh().metadata.size(), 1u) << "metadata must arrive before the first segment";
  EXPECT_EQ(sd.mesh().metadata[0].value, m.metadata[0].value);
  ASSERT_TRUE(sd.feed(std::string_view(bytes).substr(fed)).ok());
  ASSERT_TRUE(sd.finish().ok());
  const tsm::CompareResult r = tsm::compare_meshes(m, sd.mesh(), 14);
  EXPECT_TRUE(r.equal) << r.difference;
}

TEST(Metadata, InvalidEntriesRefusedByTheEncoder) {
  Mesh m = tsm_test::icosphere(1);
  std::string bytes;
  m.metadata = {{"", "x"}};
  tsm::Status s = tsm::encode(m, tsm::EncodeOptions{}, bytes);
  EXPECT_EQ(s.code(), tsm::ErrorCode::invalid_argument);
  EXPECT_TRUE(tsm_test::contains(s.message(), "key"));
  m.metadata = {{"a", "x"}, {"a", "y"}};
  s = tsm::encode(m, tsm::EncodeOptions{}, bytes);
  EXPECT_EQ(s.code(), tsm::ErrorCode::invalid_argument);
  EXPECT_TRUE(tsm_test::contains(s.message(), "twice"));
  m.metadata = {{std::string(256, 'k'), "x"}};
  EXPECT_EQ(tsm::encode(m, tsm::EncodeOptions{}, bytes).code(), tsm::ErrorCode::invalid_argument);
}

TEST(Metadata, NoSectionWithoutMetadata) {
  tsm::FileInfo info;
  ASSERT_TRUE(tsm::inspect(encode_ok(tsm_test::icosphere(1)), info).ok());
  for (const tsm::SectionInfo& s : info.sections) EXPECT_NE(s.name, "metadata");
}

}  // namespace

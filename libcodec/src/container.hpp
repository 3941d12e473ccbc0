// Internal: the .tsm container (see format-spec/FORMAT.md §2-3).
#pragma once
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "tsm/mesh.hpp"
#include "tsm/status.hpp"

namespace tsm {

constexpr char kMagic[4] = {'T', 'S', 'M', '\x1a'};
constexpr uint16_t kFormatVersion = 11;       // what the encoder writes
constexpr uint16_t kOldestFormatVersion = 3;  // the decoder reads versions 3 to 11
constexpr uint16_t kCandidateVersion = 11;    // stitch targets by candidates (FORMAT.md §8.3.2)

enum class SectionCodec : uint8_t { raw = 0, zstd = 1 };
// A stored section may expand at most this much through its codec; the encoder
// stores raw when zstd would exceed it, so a decoder can bound every allocation
// by the input size.
constexpr uint64_t kMaxExpansion = 1024;

enum SectionId : uint16_t {
  kSectionEnd = 0,
  // 1 and 2 were the foundation codec's raw sections; retired, never reused.
  kSectionVertexTree = 3,     // vertex spanning tree runs (range coded)
  kSectionTriangleTree = 4,   // triangle tree runs, marching pattern, polygon flags (range coded)
  kSectionTopology = 5,       // components, jumps, virtual vertices, stitches, side faces (range coded)
  kSectionGeometry = 6,       // predicted quantized positions (range coded)
  kSectionSegment = 7,        // one segment of a mesh coded in several (all of its streams)
  kSectionAttributes = 8,     // normals, colours, texture coordinates, ... (headers + range coded)
  kSectionMetadata = 9,       // Mesh::metadata, passed through (key/value byte strings)
  kSectionMesh = 10,          // version 4: a one-segment mesh's streams 3-6 and attributes in one section
};
const char* section_name(uint16_t id);

struct Header {
  uint16_t version = kFormatVersion;  // as read from the file (kOldestFormatVersion .. kFormatVersion)
  uint64_t vertex_count = 0;
  uint64_t face_count = 0;
  uint64_t corner_count = 0;
  uint8_t quantization_bits = 0;
  uint8_t level = 0;
  float origin[3] = {0, 0, 0};
  double extent = 0;              // largest bounding-box extent (max - min in double)
  uint32_t segment_count = 1;
};

struct Section {
  uint16_t id = 0;
  SectionCodec codec = SectionCodec::raw;
  uint64_t stored_bytes = 0;
  uint64_t raw_bytes = 0;
  uint64_t offset = 0;  // file offset of the section's id
  std::string data;  // raw (decoded) payload
};

class ContainerWriter {
 public:
  explicit ContainerWriter(const Header& header);
  // Adds a section; tries zstd at `zstd_level` (0 = never) and keeps it when smaller.
  void add_section(uint16_t id, std::string_view payload, int zstd_level);
  // Rewrites the preamble's version (and the header checksum over it): the
  // encoder writes the oldest version that holds what it coded.
  void set_version(uint16_t version);
  // Finishes the file (end marker) and returns the bytes.
  std::string finish();

 private:
  std::string out_;
  size_t header_end_ = 0;  // offset of the header checksum
};

// Incremental reading, for bytes that may still be arriving: each reads one
// piece starting at `offset` of the bytes received so far and advances
// `offset` past it. When the bytes end inside the piece, `missing` says what
// is cut off and nothing is consumed (Ok is returned); damage that the bytes
// at hand already show is an error at once.
Status read_header(std::string_view bytes, size_t& offset, Header& header, std::string& missing);
// A section, or the end marker (s.id == kSectionEnd). `base` is the file
// offset of bytes[0] (for messages and Section::offset).
Status read_section(std::string_view bytes, size_t& offset, Section& s, bool decode_payload, std::string& missing,
                    size_t base = 0);

// Which ids may follow which (FORMAT.md §4.3): segment sections only in a
// file of several segments, at most segment_count of them; the whole-mesh
// sections only in a file of one (version 3: sections 3-6 and 8; version 4:
// section 10); any other id at most once.
struct SectionRules {
  std::vector<uint16_t> seen;
  uint32_t segments = 0;
  Status admit(const Section& s, const Header& h);
};

// The mesh section's payload (version 4, FORMAT.md §4.7): the byte lengths
// of the vertex-tree, triangle-tree, topology and geometry streams, the
// streams, then the attribute payload (the rest; empty when none).
struct MeshPayload {
  std::string_view vertex_tree, triangle_tree, topology, geometry, attributes;
};
std::string write_mesh_payload(const MeshPayload& p);
Status read_mesh_payload(std::string_view bytes, MeshPayload& p);

// Parses the whole container: header, then every section with checksum and
// length checks. Raw payloads are returned decompressed.
Status read_container(std::string_view bytes, Header& header, std::vector<Section>& sections,
                      bool decode_payloads = true);

uint32_t checksum32(std::string_view bytes);

// The metadata section's payload (FORMAT.md §4.6): Mesh::metadata entries.
std::string write_metadata(const std::vector<MetadataEntry>& entries);
Status read_metadata(std::string_view payload, std::vector<MetadataEntry>& entries);

}  // namespace tsm

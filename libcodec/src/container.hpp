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
// The preamble's version field. tsm keeps one format until 1.0: the encoder
// writes this version and the decoder reads only it.
constexpr uint16_t kFormatVersion = 12;

enum class SectionCodec : uint8_t { raw = 0, zstd = 1 };
// A stored section may expand at most this much through its codec; the encoder
// stores raw when zstd would exceed it, so a decoder can bound every allocation
// by the input size.
constexpr uint64_t kMaxExpansion = 1024;

enum SectionId : uint16_t {
  kSectionEnd = 0,
  // Ids 3-6 and 8 are reserved: a file that has one is refused
  // (SectionRules); 1, 2 and 13 and up are unassigned: ignored.
  kSectionReservedFirst = 3,  // 3-6: reserved
  kSectionReservedLast = 6,
  kSectionSegment = 7,        // one segment of a mesh coded in several (all of its streams)
  kSectionReserved8 = 8,      // reserved
  kSectionMetadata = 9,       // Mesh::metadata, passed through (key/value byte strings)
  kSectionMesh = 10,          // a one-segment mesh: its four streams and its attributes
  kSectionOrder = 11,         // keep-order: the input's vertex and face order (order_coding.hpp)
  kSectionRefinement = 12,    // a progressive file's batch of vertex splits (FORMAT.md §4.8); repeats
  kSectionLoose = 13,         // a progressive file's vertices no face uses, after its batches (FORMAT.md §4.8)
  kSectionExceptions = 14,    // lossless: the coordinates the exact grid misses (exact_grid.hpp)
};
const char* section_name(uint16_t id);

struct Header {
  uint16_t version = kFormatVersion;  // the version after the magic (read_header accepts only kFormatVersion)
  uint64_t vertex_count = 0;
  uint64_t face_count = 0;
  uint64_t corner_count = 0;
  uint8_t quantization_bits = 0;
  uint8_t level = 0;
  float origin[3] = {0, 0, 0};
  double extent = 0;              // largest bounding-box extent (max - min in double)
  uint32_t segment_count = 1;
  // Lossless (flag kHeaderExactGrid, FORMAT.md §5.1): the grid is
  // (exact_base + q) * exact_step, not the bounding-box grid.
  uint16_t flags = 0;
  double exact_step = 0;
  int64_t exact_base[3] = {0, 0, 0};
};
constexpr uint16_t kHeaderExactGrid = 1;
// The header's grid byte (FORMAT.md §3): quantization bits, the exact-grid
// flag and the axis whose maximum the header stores.
constexpr uint8_t kGridBitsMask = 0x1f;
constexpr uint8_t kGridExact = 0x20;
constexpr int kGridAxisShift = 6;
// The header's level byte: the level (bits 0-3) and, in bit 4, that a
// segment count (2 or more) follows the grid's top; without it, 1 segment.
constexpr uint8_t kLevelMask = 0x0f;
constexpr uint8_t kLevelSegmented = 0x10;

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
  // Finishes the file (end marker) and returns the bytes.
  std::string finish();

 private:
  std::string out_;
  bool first_ = true;  // the next section is the first: its checksum covers the header too
};

// Appends a raw section (FORMAT.md §4.1) to a file's bytes (for sections
// added after the end marker is taken off; never the file's first section).
void append_raw_section(std::string& file, uint16_t id, std::string_view payload);
// The end marker (FORMAT.md §4.4): one byte.
constexpr size_t kEndMarkerBytes = 1;
inline void append_end_marker(std::string& file) { file.push_back(static_cast<char>(kSectionEnd)); }
// The bytes of a section's framing (id and codec, lengths, checksum).
uint64_t section_framing_bytes(const Section& s);

// Incremental reading, for bytes that may still be arriving: each reads one
// piece starting at `offset` of the bytes received so far and advances
// `offset` past it. When the bytes end inside the piece, `missing` says what
// is cut off and nothing is consumed (Ok is returned); damage that the bytes
// at hand already show is an error at once.
Status read_header(std::string_view bytes, size_t& offset, Header& header, std::string& missing);
// A section, or the end marker (s.id == kSectionEnd). `base` is the file
// offset of bytes[0] (for messages and Section::offset). For the file's
// first section `header` holds the file's bytes before it (preamble and
// header), which its checksum covers too; empty for every later section.
Status read_section(std::string_view bytes, size_t& offset, Section& s, bool decode_payload, std::string& missing,
                    size_t base = 0, std::string_view header = {});

// Which ids may follow which (FORMAT.md §4.3): segment sections only in a
// file of several segments, at most segment_count of them; the mesh section
// only in a file of one; the reserved ids 3-6 and 8 never; any other id at
// most once.
constexpr uint32_t kMaxRefinements = 64;  // each batch walks every vertex: bounds the decoder's work to 64 x the vertices
struct SectionRules {
  std::vector<uint16_t> seen;
  uint32_t segments = 0;
  uint32_t refinements = 0;  // refinement sections (id 12): after the base, any number up to kMaxRefinements
  Status admit(const Section& s, const Header& h);
};

// The mesh section's payload (FORMAT.md §4.7): the byte lengths
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
// XXH32 of `first` followed by `second`.
uint32_t checksum32(std::string_view first, std::string_view second);

// The metadata section's payload (FORMAT.md §4.6): Mesh::metadata entries.
std::string write_metadata(const std::vector<MetadataEntry>& entries);
Status read_metadata(std::string_view payload, std::vector<MetadataEntry>& entries);

}  // namespace tsm

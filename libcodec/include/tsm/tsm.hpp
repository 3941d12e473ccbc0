// tsm: Topological Surgery mesh compression, C++ API.
//
//   tsm::Mesh mesh;  tsm::read_mesh("bunny.ply", mesh);   // tsm/io.hpp (tsm_io)
//   std::string bytes;
//   tsm::encode(mesh, tsm::EncodeOptions{}, bytes);
//   tsm::Mesh back;  tsm::decode(bytes, back);
//
// Everything returns a tsm::Status; nothing throws across this API.
#pragma once
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "tsm/quantization.hpp"
#include "tsm/mesh.hpp"
#include "tsm/status.hpp"

namespace tsm {

constexpr int kDefaultQuantizationBits = 14;
constexpr int kDefaultLevel = 6;

struct EncodeOptions {
  int quantization_bits = kDefaultQuantizationBits;  // 1..30
  int level = kDefaultLevel;                         // 0 (fast decode) .. 9 (small)
  // Meshes with more faces are coded as several segments of at most this
  // many faces, each decodable on its own as soon as its bytes are in
  // (streaming, parallel decoding). 0 = the default, 2^18.
  uint32_t segment_faces = 0;
  // Threads coding segments in parallel; 0 = one per core. The bytes do not
  // depend on it.
  int threads = 0;
  // Quantization of float attributes (integer-typed ones are coded exactly).
  AttributeQuantization attribute_bits{};
  // A progressive file (FORMAT.md §4.8): a coarse base mesh, then batches of
  // vertex splits, so that any prefix decodes to a level of detail of the
  // whole shape and the full file to the input. Positions and faces only
  // (a mesh with attributes is refused); not with keep_order or lossless.
  bool progressive = false;
  // The decoded mesh keeps the input's vertex order, face order and each
  // face's first corner (an order section codes the permutation).
  bool keep_order = false;
  // Every float32 coordinate comes back bit for bit: positions are coded on
  // a grid found for the mesh (a decimal or binary spacing that holds most
  // coordinates exactly), the others stored as they are;
  // quantization_bits is not used.
  bool lossless = false;
  // With lossless: NaN and infinite coordinates are kept (else refused).
  bool allow_nonfinite = false;
};

// Where the decoded mesh's vertices and faces come from in the input (the
// decoder's order is its own unless EncodeOptions::keep_order): decoded
// vertex v is input vertex vertex_from[v]; decoded face f is input face
// face_from[f], its corner k the input face's corner (first_corner[f] + k)
// mod n. Covers every vertex (on no face, welded or split) and face.
struct EncodeMapping {
  std::vector<uint32_t> vertex_from, face_from, first_corner;
};

struct DecodeOptions {
  // A client bounds its memory with these (0 = only the format's own limits,
  // which already tie every count to the bytes of the streams that code it).
  uint64_t max_vertices = 0;
  uint64_t max_faces = 0;
  // Face corners; when 0 and max_faces is set, 16 x max_faces.
  uint64_t max_corners = 0;
  // Threads decoding segments in parallel; 0 = one per core.
  int threads = 0;
};

// `mapping`, when given, is filled (with keep_order: the identity).
Status encode(const Mesh& mesh, const EncodeOptions& options, std::string& out, EncodeMapping* mapping = nullptr);
Status decode(std::string_view bytes, Mesh& out, const DecodeOptions& options = {});

// Decoding while the bytes arrive: feed() them in chunks of any size; each
// segment is decoded as soon as its bytes are all in, and mesh() grows: the
// vertices and faces of segment k come after those of the segments before
// it, and its faces only use vertices of segments 0..k. A file of one
// segment appears whole when its last bytes are in. After an error every
// call returns it again.
class StreamDecoder {
 public:
  explicit StreamDecoder(const DecodeOptions& options = {});
  ~StreamDecoder();
  StreamDecoder(const StreamDecoder&) = delete;
  StreamDecoder& operator=(const StreamDecoder&) = delete;
  Status feed(std::string_view bytes);
  // The input is over: Ok when the whole file was decoded, else why not.
  Status finish();
  uint32_t segment_count() const;  // 0 until the header is in
  uint32_t segments_done() const;
  uint32_t batches_done() const;   // progressive files: refinement batches applied
  bool done() const;               // the end marker was read, no error
  // Progressive files (FORMAT.md §4.8): true once the base mesh is whole
  // and the next section is a refinement batch; mesh() is then a level of
  // detail of the whole shape (batches change faces in place: a client
  // redraws it rather than appending).
  bool progressive() const;
  // The encoder's error of the level mesh() holds (model units; the file
  // records it per batch), or -1 while unknown (the base before the first
  // batch's bytes are in, single-rate files).
  double level_error() const;
  // With stop_at_levels(true), feed() returns after each new level of a
  // progressive file (the base, then each batch), keeping the bytes after
  // it; level_pending() then says more may be decodable, and feed() with
  // no bytes continues. finish() decodes whatever is pending first.
  void stop_at_levels(bool on);
  bool level_pending() const;
  const Mesh& mesh() const;
  Mesh take_mesh();                // moves the mesh out (call when done)

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Progressive files (FORMAT.md §4.8): decoding a prefix. Stops after the
// last refinement batch that is whole within the bytes (and within
// max_bytes), or at the first level whose error is at most max_error.
struct PartialOptions {
  uint64_t max_bytes = 0;  // 0 = all the bytes given
  double max_error = -1;   // model units; negative = refine as far as the bytes go
};
struct PartialReport {
  uint32_t batches = 0;        // refinement batches applied
  uint64_t bytes_used = 0;     // bytes of the file those levels needed
  double error = 0;            // the encoder's error of the level decoded (model units)
  bool complete = false;       // the whole file was there and decoded
};
// Ok with the finest level the bytes hold once the base mesh is whole
// (a single-rate file decodes only whole); an error when even the base is
// cut off or any byte in use is damaged.
Status decode_partial(std::string_view bytes, Mesh& out, const PartialOptions& partial = {},
                      PartialReport* report = nullptr, const DecodeOptions& options = {});

// What `tsm info` shows: header fields and the sections with their sizes.
struct SectionInfo {
  uint32_t id = 0;
  std::string name;
  std::string codec;
  uint64_t stored_bytes = 0;   // as stored (after zstd where used)
  uint64_t raw_bytes = 0;      // before the section codec
};
struct SegmentSummary {
  uint64_t vertices = 0;    // the segment's vertices, references included
  uint64_t references = 0;  // vertices of earlier segments it uses
  uint64_t faces = 0;
};
// One attribute as the file codes it (tsm info), summed over the parts.
struct AttributeInfo {
  std::string name;
  AttributeKind kind = AttributeKind::generic;
  AttributeDomain domain = AttributeDomain::vertex;
  AttributeType type = AttributeType::f32;
  uint32_t components = 1;
  std::string coding;      // "exact" (integers), "grid" or "octahedral" (normals)
  int bits = 0;            // grid and octahedral: bits per component; exact: 0
  bool tables = false;     // residuals through static prefix codes in some part
  uint64_t coded_bytes = 0;  // its values in the coded stream (to a few bytes per part)
};
struct FileInfo {
  uint32_t format_version = 0;  // the header's (a file this library reads says 12)
  uint64_t vertex_count = 0;
  uint64_t face_count = 0;
  uint64_t corner_count = 0;
  int quantization_bits = 0;
  int level = 0;
  uint32_t segment_count = 0;
  double bbox_min[3] = {0, 0, 0};
  double step = 0;
  uint64_t file_bytes = 0;
  // Lossless (FORMAT.md §5.1: every coordinate on an exact float32 grid, the
  // misses in the exceptions section) and keep-order (an order section,
  // §4.9: the encoder's input order of vertices, faces and first corners).
  bool lossless = false, keep_order = false;
  std::vector<SectionInfo> sections;
  // Topology figures (from decoding the connectivity streams).
  uint64_t components = 0, vertex_runs = 0, triangle_runs = 0, jump_edges = 0, stitches = 0,
           virtual_vertices = 0, side_faces = 0, marching_bits = 0;
  // Parts (segments) whose connectivity run values are table-coded (the
  // fast levels; FORMAT.md §8.3.1).
  uint64_t run_table_parts = 0;
  // Welded files (FORMAT.md §8.13): the points the connectivity and the
  // positions are coded on (0 when not welded).
  uint64_t welded_points = 0;
  // Attributes whose residuals are table-coded, summed over the parts
  // (the fast levels; FORMAT.md §8.12.1).
  uint64_t table_coded_attributes = 0;
  // Stored bytes by kind; other = header, framing, references, side data.
  uint64_t connectivity_bytes = 0, geometry_bytes = 0, other_bytes = 0;
  uint64_t reference_bytes = 0;  // part of other: the segments' references streams
  uint64_t attribute_bytes = 0;  // part of other: the attribute streams (headers, tables, values)
  std::vector<AttributeInfo> attributes;
  uint64_t references = 0;       // vertices shared across segment borders (coded once, referenced after)
  std::vector<SegmentSummary> segments;
  // Progressive files: the refinement batches, coarsest first, and the
  // error of the base mesh (the encoder's measure, model units).
  struct Batch {
    uint64_t bytes = 0;              // the section, framing included
    uint64_t vertices = 0, faces = 0;  // of the level after it
    double error = 0;
  };
  std::vector<Batch> batches;
  double base_error = 0;
  uint64_t loose_vertices = 0;  // the loose section's: vertices no face uses, after the batches
  uint64_t loose_faces = 0;     // the loose section's: triangles the levels leave out
  // Geometry (from decoding the geometry stream): "parallelograms", "spread",
  // "gate", "fan", "ancestors" (with K) or "raw", followed by "+tangent" (tangent
  // step), "+mix" (residual mixing), "+top" (lattice planes from the top),
  // "+tables" (residuals through static prefix codes) where used, and the
  // lattice planes per axis (0 = unused).
  std::string geometry_predictor;
  int ancestors = 0;
  uint32_t lattice_planes[3] = {0, 0, 0};
};
// Parses the header and section table (checksums verified) and decodes the
// streams for the figures above (so it also validates the whole file).
Status inspect(std::string_view bytes, FileInfo& info);

const char* version_string();

}  // namespace tsm

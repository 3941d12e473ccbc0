// tsm: the in-memory mesh. One type for every reader, writer and codec stage.
//
// Positions are float xyz, interleaved. Faces are polygons stored as a
// compressed row list (face_offsets has face_count()+1 entries, the corners
// of face f are indices[face_offsets[f] .. face_offsets[f+1])). Vertices that
// no face references are kept: the codec gives back exactly what it was given.
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace tsm {

// What an attribute holds (it chooses how the codec quantizes and predicts it).
enum class AttributeKind : uint8_t {
  generic = 0,   // any values
  normal = 1,    // 3 components, unit length (octahedral quantization)
  color = 2,     // 3 or 4 components (RGB, RGBA)
  texcoord = 3,  // 2 components (u, v)
};
// What one value belongs to.
enum class AttributeDomain : uint8_t {
  vertex = 0,  // one value per vertex
  face = 1,    // one value per face
  corner = 2,  // per face corner, through `indices` into a value list of its own (seams, creases)
};
// How the values were stored in the file they came from; integer types hold
// integer values (a u8 colour is 0..255), coded exactly.
enum class AttributeType : uint8_t { f32 = 0, u8 = 1, u16 = 2, i32 = 3 };

// The longest attribute name the format stores (FORMAT.md §8.12).
constexpr size_t kMaxAttributeNameBytes = 1024;

// A per-vertex, per-face or per-corner attribute. `values` holds
// value_count() values of `components` floats each. For the vertex and face
// domains there is one value per vertex / face, in their order, and
// `indices` is empty. For the corner domain `indices` has one entry per face
// corner (in the order of Mesh::indices) naming a value; values may repeat
// or be used by no corner (OBJ's vt / vn lists, glTF seams): all of it is
// kept as given.
struct Attribute {
  std::string name;  // "normal", "color", "texcoord", or the file's own name; at most kMaxAttributeNameBytes
  AttributeKind kind = AttributeKind::generic;
  AttributeDomain domain = AttributeDomain::vertex;
  AttributeType type = AttributeType::f32;
  uint32_t components = 1;  // 1..4
  std::vector<float> values;
  std::vector<uint32_t> indices;  // corner domain only
  size_t value_count() const { return components ? values.size() / components : 0; }
};

// Content of the file a mesh came from that the codec does not model (a glTF
// document's materials, nodes, scenes and images, say), kept as given: the
// encoder stores every entry (zstd-compressed where that is smaller) and the
// decoder hands it back byte for byte. Keys are unique, 1..255 bytes; the
// writers that understand a key use it ("gltf" for the glTF writer).
struct MetadataEntry {
  std::string key;
  std::string value;  // any bytes
};

struct Mesh {
  std::vector<float> positions;            // 3 * vertex_count()
  std::vector<uint32_t> face_offsets{0};   // face_count() + 1, starts with 0
  std::vector<uint32_t> indices;           // corners of all faces
  std::vector<Attribute> attributes;       // normals, colours, texture coordinates, ...
  std::vector<MetadataEntry> metadata;     // passed through unchanged (see MetadataEntry)

  size_t vertex_count() const { return positions.size() / 3; }
  size_t face_count() const { return face_offsets.size() - 1; }
  size_t corner_count() const { return indices.size(); }
  uint32_t face_size(size_t f) const { return face_offsets[f + 1] - face_offsets[f]; }
  const uint32_t* face(size_t f) const { return indices.data() + face_offsets[f]; }

  void clear();
  void reserve(size_t vertices, size_t faces, size_t corners);
  void add_vertex(float x, float y, float z);
  // Appends a face with n corners (n >= 1; callers validate indices).
  void add_face(const uint32_t* corners, size_t n);
  void add_triangle(uint32_t a, uint32_t b, uint32_t c);

  bool all_triangles() const;
  // Faces with fewer than 3 corners or a repeated corner index.
  size_t degenerate_face_count() const;
  // Vertices not referenced by any face.
  size_t unreferenced_vertex_count() const;
  // True when every position is finite.
  bool all_finite() const;  // positions and attribute values
  const Attribute* find_attribute(AttributeKind kind) const;
  const MetadataEntry* find_metadata(const std::string& key) const;
  // Internal consistency (offsets monotone, indices in range, attribute
  // sizes matching their domain); for asserts and for checking meshes handed
  // to the encoder by API users.
  bool valid(std::string* why = nullptr) const;
};

struct BoundingBox {
  float min[3] = {0, 0, 0};
  float max[3] = {0, 0, 0};
  // max - min per axis computed in double (exact for floats), largest of three.
  double largest_extent() const;
  // Length of the box's diagonal, in double.
  double diagonal() const;
};

// Bounding box of all vertices (referenced or not). An empty mesh gives zeros.
BoundingBox bounding_box(const Mesh& mesh);

}  // namespace tsm

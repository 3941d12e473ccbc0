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

struct Mesh {
  std::vector<float> positions;            // 3 * vertex_count()
  std::vector<uint32_t> face_offsets{0};   // face_count() + 1, starts with 0
  std::vector<uint32_t> indices;           // corners of all faces

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
  bool all_finite() const;
  // Internal consistency (offsets monotone, indices in range); for asserts
  // and for checking meshes handed to the encoder by API users.
  bool valid(std::string* why = nullptr) const;
};

struct BoundingBox {
  float min[3] = {0, 0, 0};
  float max[3] = {0, 0, 0};
  // max - min per axis computed in double (exact for floats), largest of three.
  double largest_extent() const;
};

// Bounding box of all vertices (referenced or not). An empty mesh gives zeros.
BoundingBox bounding_box(const Mesh& mesh);

}  // namespace tsm

// tsm: the test oracle. Decides whether a decoded mesh is the mesh that was
// encoded, up to what the codec is allowed to change: the order of vertices,
// the order of faces, the rotation of each face's corner list (orientation is
// kept), and the position quantization the user chose.
#pragma once
#include <cstdint>
#include <string>

#include "tsm/mesh.hpp"

namespace tsm {

// The quantization grid (the one Draco uses, so sizes compare at equal
// precision): origin = bounding-box minimum, step = largest extent /
// (2^bits - 1), q(x) = floor((x - origin) / step + 0.5).
struct Grid {
  int bits = 0;           // 0: no quantization (positions compared bit-exactly)
  double origin[3] = {0, 0, 0};
  double step = 0;        // 0 when the mesh is a single point or empty
  static Grid for_mesh(const Mesh& mesh, int bits);
  // Grid index of coordinate value x on axis a.
  int64_t quantize(double x, int axis) const;
  double dequantize(int64_t q, int axis) const;
};

// Bits of the float attributes (integer-typed ones are coded exactly):
// normals octahedral bits per axis; texture coordinates, float colours and
// other float values as grid bits over the attribute's bounding box; 1..24.
struct AttributeQuantization {
  int normal = 10;
  int texcoord = 12;
  int color = 10;
  int generic = 16;
};

struct CompareResult {
  bool equal = false;
  std::string difference;       // first difference found, for test messages
  double max_position_error = 0; // largest |decoded - original| per axis, in grid steps (q>0)
};

// Compares `decoded` against `original`. Positions of both are quantized on
// the grid of `original` (bits = 0 compares raw float bits). Vertices are
// matched by a canonical labelling that starts from the quantized position
// and is refined by the oriented faces around each vertex, so meshes with
// coincident vertices still compare correctly in practice.
// Attributes are compared through the integers the codec codes them as, with
// the bits the encoder was given (EncodeOptions::attribute_bits).
CompareResult compare_meshes(const Mesh& original, const Mesh& decoded, int bits,
                             const AttributeQuantization& attribute_bits = AttributeQuantization());

}  // namespace tsm

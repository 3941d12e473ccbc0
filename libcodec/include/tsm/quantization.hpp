// tsm: the quantization the codec applies: the position grid and the bits
// of the float attributes. The encoder quantizes with these, the decoder
// dequantizes with them, and the test oracle (compare.hpp) compares on them.
#pragma once
#include <cstdint>

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

}  // namespace tsm

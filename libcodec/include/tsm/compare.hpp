// tsm: the test oracle. Decides whether a decoded mesh is the mesh that was
// encoded, up to what the codec is allowed to change: the order of vertices,
// the order of faces, the rotation of each face's corner list (orientation is
// kept), and the position quantization the user chose.
#pragma once
#include <cstdint>
#include <string>

#include "tsm/mesh.hpp"
#include "tsm/quantization.hpp"

namespace tsm {

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

// Internal: what the encoder (encode.cpp) and the decoder (decode.cpp) both
// need beyond the container and the stages: the grid's step (FORMAT.md §5).
#pragma once
#include <cmath>

#include "container.hpp"

namespace tsm {

// The distance between neighbouring grid values: the header's extent over
// 2^bits - 1 (0 for a mesh of one point).
inline double grid_step(const Header& h) {
  return h.extent > 0 ? h.extent / (std::ldexp(1.0, h.quantization_bits) - 1.0) : 0.0;
}

}  // namespace tsm

// Internal: lossless positions (FORMAT.md §5.1): the exact grid the
// geometry coder codes on and the exceptions section that gives back every
// coordinate the grid does not hold bit for bit. See exact_grid.cpp.
#pragma once
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "tsm/mesh.hpp"
#include "tsm/status.hpp"

namespace tsm {

struct ExactGrid {
  double step = 1;              // the grid's spacing (header field)
  int64_t base[3] = {0, 0, 0};  // grid index 0 of each axis is base * step
  int bits = 1;                 // grid indices 0 .. 2^bits - 1
};

// The float a grid index stands for: float32 of (base + q) * step in binary64.
float exact_value(double step, int64_t base, uint32_t q);

// Encoder: the grid among decimal and binary spacings that minimizes
// (grid bits x coordinates + about the exceptions' bits).
ExactGrid choose_exact_grid(const Mesh& mesh);
// The grid index a coordinate is coded with (0 for a non-finite one).
uint32_t exact_index(const ExactGrid& g, float x, int axis);

// Encoder: the exceptions payload for `positions` in decoded vertex order
// (3 per vertex): every coordinate whose grid value differs in its bits,
// as the difference of the two floats' bits in value order.
std::string encode_exceptions(const ExactGrid& g, const std::vector<float>& positions);
// Decoder: writes the exceptions' bits into the decoded positions.
Status apply_exceptions(std::string_view payload, std::vector<float>& positions);

}  // namespace tsm

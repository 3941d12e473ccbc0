// Internal: geometry coding (seed 004 §3.2; design notes §6).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "tsm/status.hpp"

namespace tsm {

// Quantized positions (3 per vertex, in decoded vertex order), predicted from
// the vertex-tree parent, residuals range coded.
std::string encode_geometry(const std::vector<uint32_t>& q, const std::vector<uint32_t>& parent, int bits);
Status decode_geometry(const std::string& bytes, const std::vector<uint32_t>& parent, int bits,
                       std::vector<uint32_t>& q);

}  // namespace tsm

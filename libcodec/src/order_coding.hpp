// Internal: the order section (FORMAT.md §4.9): the input's face order, each
// face's first corner and the input's vertex order, coded relative to the
// mesh the decoder builds (tsm encode --keep-order). See order_coding.cpp.
#pragma once
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "tsm/mesh.hpp"
#include "tsm/status.hpp"

namespace tsm {

// Encoder. `decoded`: the mesh as the decoder builds it without the order
// section; `vertex_from`, `face_from`, `first_corner`: EncodeMapping's
// (per decoded vertex its input id; per decoded face its input face and
// which of that face's corners its corner 0 is).
std::string encode_order(const Mesh& decoded, const std::vector<uint32_t>& vertex_from,
                         const std::vector<uint32_t>& face_from, const std::vector<uint32_t>& first_corner);

// Decoder: reorders `mesh` (positions, faces, corners, vertex, face and
// corner attributes; a corner attribute's value list stays as it is) into
// the input's order the payload codes. Corrupt data is refused.
Status decode_order(std::string_view payload, Mesh& mesh);

}  // namespace tsm

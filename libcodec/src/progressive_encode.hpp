// Internal: the progressive encoder's entry point (encode() calls it when
// EncodeOptions::progressive is set).
#pragma once
#include <string>

#include "tsm/tsm.hpp"

namespace tsm {

Status encode_progressive(const Mesh& mesh, const EncodeOptions& options, std::string& out);

}  // namespace tsm

// Internal: applying a progressive file's refinement sections (decode.cpp).
#pragma once
#include <vector>

#include "container.hpp"
#include "tsm/tsm.hpp"

namespace tsm {

// Applies the refinement sections (id 12) among `sections`, in order, to the
// decoded base mesh.
Status apply_refinements(const Header& h, const std::vector<Section>& sections, Mesh& mesh,
                         const DecodeOptions& options);

}  // namespace tsm

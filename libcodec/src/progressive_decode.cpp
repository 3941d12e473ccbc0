// Progressive meshes, the decoder's side (seed 003; FORMAT.md §4.8): the
// refinement sections applied to the decoded base mesh in file order, and
// decoding a prefix of a file (the finest level its bytes hold).
#include <algorithm>

#include "container.hpp"
#include "progressive.hpp"
#include "progressive_decode.hpp"

namespace tsm {

Status apply_refinements(const Header& h, const std::vector<Section>& sections, Mesh& mesh,
                         const DecodeOptions& options) {
  LevelMesh level;
  bool ready = false;
  BatchLimits limits{options.max_vertices, options.max_faces};
  uint32_t k = 0;
  for (const Section& s : sections) {
    if (s.id != kSectionRefinement && s.id != kSectionLoose) continue;
    if (!ready) level.init(mesh, h), ready = true;
    Status st = s.id == kSectionLoose ? decode_loose(s.data, level, limits) : decode_batch(s.data, level, limits);
    if (!st.ok()) return Status(st.code(), "batch " + std::to_string(k) + ": " + st.message());
    ++k;
  }
  return Status::Ok();
}

Status decode_partial(std::string_view bytes, Mesh& out, const PartialOptions& partial, PartialReport* report,
                      const DecodeOptions& options) {
  out.clear();
  PartialReport rep;
  Header h;
  size_t pos = 0;
  std::string missing;
  TSM_RETURN_IF_ERROR(read_header(bytes, pos, h, missing));
  if (!missing.empty()) return Status(ErrorCode::corrupt_data, "the file ends inside its header: " + missing);
  const size_t head = pos;
  // Where to cut: after the base's last section, then after each whole
  // refinement within the byte budget, until the error asked for is met.
  const uint64_t budget = partial.max_bytes ? std::min<uint64_t>(partial.max_bytes, bytes.size()) : bytes.size();
  SectionRules rules;
  size_t cut = 0;
  bool base_done = false;
  uint32_t segments = 0, batches = 0;
  double error = 0;
  while (true) {
    Section s;
    const size_t at = pos;
    TSM_RETURN_IF_ERROR(read_section(bytes.substr(0, budget), pos, s, true, missing, 0,
                                     at == head ? bytes.substr(0, head) : std::string_view()));
    if (!missing.empty()) break;
    if (s.id == kSectionEnd) {
      rep.complete = base_done && pos == bytes.size();
      cut = at;
      break;
    }
    TSM_RETURN_IF_ERROR(rules.admit(s, h));
    if (s.id == kSectionRefinement) {
      BatchHeader bh;
      std::string_view stream;
      TSM_RETURN_IF_ERROR(read_batch(s.data, bh, stream));
      if (batches == 0) error = bh.error_before;
      if (partial.max_error >= 0 && error <= partial.max_error) break;
      error = bh.error_after;
      ++batches;
    } else if (s.id == kSectionMesh || (s.id == kSectionSegment && ++segments == h.segment_count)) {
      base_done = true;
    }
    if (base_done) cut = pos;
  }
  if (!base_done)
    return Status(ErrorCode::corrupt_data,
                  "the bytes end before the base mesh is whole (" + std::to_string(bytes.size()) + " bytes)");
  std::string prefix(bytes.substr(0, cut));
  append_end_marker(prefix);
  TSM_RETURN_IF_ERROR(decode(prefix, out, options));
  if (rep.complete && cut + kEndMarkerBytes != bytes.size()) rep.complete = false;
  rep.batches = batches;
  rep.bytes_used = rep.complete ? bytes.size() : cut;
  rep.error = error;
  if (report) *report = rep;
  return Status::Ok();
}

}  // namespace tsm

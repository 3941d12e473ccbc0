// Progressive meshes, the encoder's entry point (seed 003; FORMAT.md §4.8):
// plan the collapses on the quantized input, code the base mesh with the
// single-rate codec, decode it (the vertex order the decoder will have),
// then replay the collapses backwards as vertex splits on that mesh, one
// refinement section per batch, coarsest first.
#include <algorithm>
#include <unordered_map>

#include "container.hpp"
#include "progressive.hpp"
#include "progressive_encode.hpp"
#include "progressive_plan.hpp"

namespace tsm {

static_assert(ProgressiveOptions{}.max_batches <= kMaxRefinements, "the decoder refuses more refinement sections");

namespace {

uint64_t grid_key(const uint32_t* q) {
  return (uint64_t{q[0]} << 42) ^ (uint64_t{q[1]} << 21) ^ uint64_t { q[2] } ^ (uint64_t{q[0]} >> 22);
}

// Base vertex (input id) -> decoded base vertex, by grid point (the plan
// never splits, nor splits next to, a vertex whose grid point is shared).
void map_base(const CollapsePlan& plan, const std::vector<uint32_t>& q, const LevelMesh& level,
              std::vector<uint32_t>& id) {
  std::unordered_map<uint64_t, uint32_t> at;
  std::unordered_map<uint64_t, uint32_t> count;
  for (uint32_t i = 0; i < level.vertex_count(); ++i) {
    const uint64_t k = grid_key(level.q(i));
    at[k] = i;
    ++count[k];
  }
  id.assign(plan.base_id.size(), kNotInBase);
  for (uint32_t i = 0; i < plan.base_id.size(); ++i) {
    if (plan.base_id[i] == kNotInBase) continue;
    const uint64_t k = grid_key(&q[3 * size_t{i}]);
    auto it = at.find(k);
    if (it != at.end() && count[k] == 1) id[i] = it->second;
  }
}

}  // namespace

Status encode_progressive(const Mesh& input, const EncodeOptions& options, std::string& out) {
  if (!input.attributes.empty())
    return Status(ErrorCode::unsupported, "progressive coding carries positions and faces only, and this mesh has " +
                                              std::to_string(input.attributes.size()) +
                                              " attribute(s): encode it single-rate, or drop the attributes first");
  // The plan works on the mesh as a decoder gives it back (positions on
  // the grid, its vertex and face order): its choices depend only on grid
  // points and faces, so the bytes are the same whichever order or float
  // values the input had within its grid cells (canonical re-encoding).
  Mesh gridded;
  {
    EncodeOptions fast = options;
    fast.progressive = false;
    fast.level = 0;
    std::string bytes;
    TSM_RETURN_IF_ERROR(encode(input, fast, bytes));
    TSM_RETURN_IF_ERROR(decode(bytes, gridded));
  }
  const Mesh& mesh = gridded;
  const Grid grid = Grid::for_mesh(mesh, options.quantization_bits);
  const int64_t qmax = (int64_t{1} << options.quantization_bits) - 1;
  std::vector<uint32_t> q(mesh.positions.size());
  for (size_t i = 0; i < q.size(); ++i)
    q[i] =
        static_cast<uint32_t>(std::clamp<int64_t>(grid.quantize(mesh.positions[i], static_cast<int>(i % 3)), 0, qmax));
  CollapsePlan plan;
  plan_collapses(mesh, q, ProgressiveOptions{}, plan);

  EncodeOptions single = options;
  single.progressive = false;
  std::string base;
  TSM_RETURN_IF_ERROR(encode(plan.base, single, base));
  Mesh level_mesh;
  TSM_RETURN_IF_ERROR(decode(base, level_mesh));
  Header h;
  size_t pos = 0;
  std::string missing;
  TSM_RETURN_IF_ERROR(read_header(base, pos, h, missing));
  LevelMesh level;
  level.init(level_mesh, h);
  std::vector<uint32_t> id;
  map_base(plan, q, level, id);

  out.assign(base, 0, base.size() - kEndMarkerBytes);  // without the end marker
  // The plan's errors are in grid steps; the file's in model units.
  auto error_of = [&](size_t b) { return static_cast<float>(plan.errors[b] * grid.step); };
  float before = plan.batches.empty() ? 0.0f : error_of(plan.batches.size() - 1);
  for (size_t b = plan.batches.size(); b-- > 0;) {
    std::vector<VertexSplit> splits;
    for (const CollapseRecord& r : plan.batches[b]) {
      VertexSplit s;
      s.v = id[r.v];
      s.y = r.y == kGhost ? kGhost : id[r.y];
      s.x = r.x == kGhost ? kGhost : id[r.x];
      if (s.v == kNotInBase || s.y == kNotInBase || s.x == kNotInBase)
        return Status(ErrorCode::internal, "progressive: a split around a vertex the base does not identify");
      for (int a = 0; a < 3; ++a) s.q[a] = q[3 * size_t{r.u} + a];
      splits.push_back(s);
    }
    std::string stream;
    std::vector<uint32_t> new_ids;
    BatchHeader bh;
    TSM_RETURN_IF_ERROR(encode_batch(level, splits, stream, new_ids, bh.border));
    for (size_t k = 0; k < splits.size(); ++k) id[plan.batches[b][k].u] = new_ids[k];
    bh.error_before = before;
    bh.error_after = b == 0 ? 0.0f : error_of(b - 1);
    bh.splits = splits.size();
    append_raw_section(out, kSectionRefinement, write_batch(bh, stream));
    before = bh.error_after;
  }
  if (!plan.loose.empty() || !plan.left_out.empty()) {
    // The loose vertices take the next ids in the order the section codes
    // them (loose_order), then the left-out triangles use the level's ids.
    std::vector<uint32_t> plain, lq;
    for (uint32_t i : plan.loose)
      for (int a = 0; a < 3; ++a) plain.push_back(q[3 * size_t{i} + a]);
    for (uint32_t k : loose_order(level, plain)) {
      id[plan.loose[k]] = static_cast<uint32_t>(level.vertex_count() + lq.size() / 3);
      for (int a = 0; a < 3; ++a) lq.push_back(plain[3 * size_t{k} + a]);
    }
    std::vector<std::array<uint32_t, 3>> faces;
    for (const auto& c : plan.left_out) {
      faces.push_back({id[c[0]], id[c[1]], id[c[2]]});
      for (uint32_t x : faces.back())
        if (x == kNotInBase) return Status(ErrorCode::internal, "progressive: a left-out face off the levels");
    }
    std::string payload;
    TSM_RETURN_IF_ERROR(encode_loose(level, std::move(lq), std::move(faces), payload));
    append_raw_section(out, kSectionLoose, payload);
  }
  append_end_marker(out);
  return Status::Ok();
}

}  // namespace tsm

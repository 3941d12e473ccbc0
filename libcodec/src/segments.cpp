// Segments: a large mesh coded as several pieces, each decodable as soon as
// its bytes are in and independently of the others (streaming and parallel
// decoding). The method codes every connected piece with its own trees (seed
// 004 §3, design notes §5 "several components"); a segment is such a piece
// cut out of the mesh, and the paper's motivation of loading a model in
// parts (seed 004 §1) is what it serves.
//
// The encoder cuts the faces by a k-d split of their centroids. Each segment
// is coded like a whole mesh; a vertex that an earlier segment already holds
// is a *reference*: it takes part in the segment's connectivity (it lies on
// a hole along the border), but its position is not coded again and the
// geometry predictor does not use it (the segment is decoded without the
// earlier ones). Which vertices are references, and which earlier vertex
// each one is, is the references stream of this file (FORMAT.md §4.5, §8.11).
#include "segments.hpp"

#include <algorithm>
#include <array>

#include "byte_io.hpp"
#include "range_coder.hpp"

namespace tsm {

namespace {

Status corrupt(const std::string& what) { return Status(ErrorCode::corrupt_data, what); }

struct Splitter {
  const std::vector<std::array<double, 3>>& c;
  const std::vector<uint64_t>& tie;  // per face, an order-free hash of its corners' cells
  uint32_t max_faces;
  std::vector<std::vector<uint32_t>>& out;

  void split(std::vector<uint32_t>& ids, size_t lo, size_t hi) {
    if (hi - lo <= max_faces) {
      out.emplace_back(ids.begin() + static_cast<std::ptrdiff_t>(lo), ids.begin() + static_cast<std::ptrdiff_t>(hi));
      std::sort(out.back().begin(), out.back().end());
      return;
    }
    double mn[3], mx[3];
    for (int a = 0; a < 3; ++a) mn[a] = mx[a] = c[ids[lo]][a];
    for (size_t i = lo; i < hi; ++i)
      for (int a = 0; a < 3; ++a) {
        mn[a] = std::min(mn[a], c[ids[i]][a]);
        mx[a] = std::max(mx[a], c[ids[i]][a]);
      }
    int axis = 0;
    for (int a = 1; a < 3; ++a)
      if (mx[a] - mn[a] > mx[axis] - mn[axis]) axis = a;
    // A total order (centroid along the axis, then the other two, then the
    // corners' cells, then the face), so the set on each side does not
    // depend on the library's nth_element, nor (but for faces on the same
    // cells) on the face order, which a decoded file changes.
    auto less = [&](uint32_t x, uint32_t y) {
      for (int k = 0; k < 3; ++k) {
        const int a = (axis + k) % 3;
        if (c[x][a] != c[y][a]) return c[x][a] < c[y][a];
      }
      return tie[x] != tie[y] ? tie[x] < tie[y] : x < y;
    };
    const size_t mid = lo + (hi - lo) / 2;
    std::nth_element(ids.begin() + static_cast<std::ptrdiff_t>(lo), ids.begin() + static_cast<std::ptrdiff_t>(mid),
                     ids.begin() + static_cast<std::ptrdiff_t>(hi), less);
    split(ids, lo, mid);
    split(ids, mid, hi);
  }
};

}  // namespace

uint64_t mix64(uint64_t x) {
  x ^= x >> 33;
  x *= 0xff51afd7ed558ccdull;
  x ^= x >> 33;
  x *= 0xc4ceb9fe1a85ec53ull;
  return x ^ (x >> 33);
}

uint64_t cell_hash(const uint32_t* cell) {
  return mix64((static_cast<uint64_t>(cell[0]) << 42) ^ (static_cast<uint64_t>(cell[1]) << 21) ^ cell[2]);
}

std::vector<std::vector<uint32_t>> split_faces(const Mesh& mesh, const std::vector<uint32_t>& q, uint32_t max_faces) {
  const uint32_t F = static_cast<uint32_t>(mesh.face_count());
  std::vector<uint32_t> ids(F);
  for (uint32_t f = 0; f < F; ++f) ids[f] = f;
  std::vector<std::vector<uint32_t>> out;
  if (F <= max_faces || max_faces == 0) {
    out.push_back(std::move(ids));
    return out;
  }
  std::vector<std::array<double, 3>> c(F);
  std::vector<uint64_t> tie(F, 0);
  for (uint32_t f = 0; f < F; ++f) {
    double s[3] = {0, 0, 0};
    const uint32_t n = mesh.face_size(f);
    for (uint32_t k = 0; k < n; ++k) {
      const uint32_t* p = &q[3 * static_cast<size_t>(mesh.face(f)[k])];
      for (int a = 0; a < 3; ++a) s[a] += p[a];
      tie[f] += cell_hash(p);
    }
    for (int a = 0; a < 3; ++a) c[f][a] = s[a] / n;
  }
  Splitter sp{c, tie, max_faces, out};
  sp.split(ids, 0, F);
  return out;
}

std::vector<uint8_t> reference_contexts(const GeometryLayout& g) {
  std::vector<uint8_t> ctx(g.vertex_count, 0);
  const std::vector<uint32_t>& corner = g.corners();
  for (size_t t = 0; t + 2 < corner.size(); t += 3) {
    bool hole = false;
    for (int k = 0; k < 3; ++k) hole = hole || corner[t + k] == kNone;
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = corner[t + k];
      if (v != kNone) ctx[v] = std::max<uint8_t>(ctx[v], hole ? 2 : 1);
    }
  }
  return ctx;
}

namespace {

struct ReferenceModels {
  Prob flag[3][2];
  SIntModel delta;
};

}  // namespace

std::string encode_references(const std::vector<uint8_t>& context, const std::vector<uint32_t>& global) {
  RangeEncoder e;
  ReferenceModels m;
  int prev_flag = 0;
  int64_t prev = 0;
  for (size_t v = 0; v < global.size(); ++v) {
    const int is_ref = global[v] != kNone;
    e.bit(m.flag[context[v]][prev_flag], is_ref);
    prev_flag = is_ref;
    if (!is_ref) continue;
    m.delta.encode(e, static_cast<int32_t>(static_cast<int64_t>(global[v]) - prev));
    prev = global[v];
  }
  return e.finish();
}

Status decode_references(std::string_view bytes, const std::vector<uint8_t>& context, uint64_t count,
                         uint64_t limit, std::vector<uint32_t>& global) {
  RangeDecoder d(bytes);
  ReferenceModels m;
  global.assign(context.size(), kNone);
  int prev_flag = 0;
  int64_t prev = 0;
  uint64_t found = 0;
  for (size_t v = 0; v < context.size(); ++v) {
    if (context[v] > 2) return corrupt("bad reference context");
    prev_flag = d.bit(m.flag[context[v]][prev_flag]);
    if (!prev_flag) continue;
    if (++found > count) return corrupt("more references than the segment's count");
    const int64_t g = prev + m.delta.decode(d);
    if (g < 0 || static_cast<uint64_t>(g) >= limit)
      return corrupt("a reference to vertex " + std::to_string(g) + ", not one of the " + std::to_string(limit) +
                     " vertices of the segments before");
    global[v] = static_cast<uint32_t>(g);
    prev = g;
    if ((v & 4095) == 0 && d.overrun() > RangeDecoder::kMaxOverrun) return corrupt("references stream is truncated");
  }
  if (d.overrun() > RangeDecoder::kMaxOverrun) return corrupt("references stream is truncated");
  if (found != count)
    return corrupt("the segment lists " + std::to_string(count) + " references, its stream codes " +
                   std::to_string(found));
  return Status::Ok();
}

GeometryLayout own_layout(const GeometryLayout& g, const std::vector<uint32_t>& global) {
  GeometryLayout o;
  std::vector<uint32_t> rank(g.vertex_count, kNone);
  uint32_t n = 0;
  for (uint32_t v = 0; v < g.vertex_count; ++v)
    if (global[v] == kNone) rank[v] = n++;
  o.vertex_count = n;
  o.twin = g.twin;
  const std::vector<uint32_t>& corner = g.corners();
  o.corner.resize(corner.size());
  for (size_t h = 0; h < corner.size(); ++h) o.corner[h] = corner[h] == kNone ? kNone : rank[corner[h]];
  o.parent.assign(n, kNone);
  if (!g.anchor.empty()) o.anchor.assign(n, kNone);
  for (uint32_t v = 0; v < g.vertex_count; ++v) {
    if (rank[v] == kNone) continue;
    if (v < g.parent.size() && g.parent[v] != kNone) o.parent[rank[v]] = rank[g.parent[v]];
    if (!g.anchor.empty() && g.anchor[v] != kNone) o.anchor[rank[v]] = rank[g.anchor[v]];
  }
  return o;
}

std::string write_segment(const SegmentPayload& p) {
  std::string out;
  ByteWriter w(out);
  w.varint(p.vertex_count);
  w.varint(p.face_count);
  w.varint(p.corner_count);
  w.varint(p.reference_count);
  write_streams(w, {p.vertex_tree, p.triangle_tree, p.topology, p.references, p.geometry}, p.attributes);
  return out;
}

Status read_segment(std::string_view bytes, SegmentPayload& p) {
  ByteReader r(bytes);
  if (!r.varint(p.vertex_count) || !r.varint(p.face_count) || !r.varint(p.corner_count) ||
      !r.varint(p.reference_count))
    return corrupt("segment section: truncated counts");
  std::string_view* const parts[5] = {&p.vertex_tree, &p.triangle_tree, &p.topology, &p.references, &p.geometry};
  switch (read_streams(r, parts, p.attributes)) {
    case StreamsRead::lengths_truncated: return corrupt("segment section: truncated counts");
    case StreamsRead::stream_past_end: return corrupt("segment section: a stream runs past the section's end");
    case StreamsRead::ok: break;
  }
  if (p.reference_count > p.vertex_count) return corrupt("segment section: more references than vertices");
  return Status::Ok();
}

}  // namespace tsm

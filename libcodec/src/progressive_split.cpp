// Progressive meshes (seed 003, Hoppe's vertex splits, in batches as
// Pajarola and Rossignac's Compressed Progressive Meshes; FORMAT.md §4.8):
// one batch of vertex splits, coded and decoded. Per vertex of the current
// level, in id order, a split flag (left out where the batch's independence
// or the vertex's fan already rules a split out); per split vertex, the two
// ring neighbours bounding the faces that move to the new vertex, and the
// new vertex's grid position as a residual from the centroid of its ring.
#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <unordered_map>

#include "byte_io.hpp"
#include "codec_shared.hpp"
#include "progressive.hpp"
#include "range_coder.hpp"

namespace tsm {

constexpr int kFlagContexts = 16;
constexpr int kScaleContexts = 24;
constexpr int kRingContexts = 32;
constexpr int kRankContexts = 4;

struct BatchModels {
  Prob flag[kFlagContexts];                          // by ring size, closed then open
  UIntModelT<2> rank[kRingContexts][kRankContexts];  // by ring size (closed, open), then min(dist, 4)
  UIntModelT<2> dist[kRingContexts];                 // by ring size, closed then open
  SIntModelT<3> residual[kScaleContexts][3];
  SIntModelT<3> border[kScaleContexts][3];  // the new vertex on v's border
};

namespace {

Status corrupt(const std::string& what) { return Status(ErrorCode::corrupt_data, "refinement batch: " + what); }

// The residual's model set: the bit length of the largest coordinate
// difference between v and the new vertex's ring (the local edge length).
int scale_context(const LevelMesh& level, uint32_t v, const std::vector<uint32_t>& ring, uint32_t ia, uint32_t dist) {
  int64_t span = 0;
  for (uint32_t k = 0; k <= dist; ++k) {
    const uint32_t r = ring[(ia + k) % ring.size()];
    if (r == kGhost) continue;
    const uint32_t* p = level.q(r);
    for (int a = 0; a < 3; ++a) span = std::max<int64_t>(span, std::abs(int64_t{p[a]} - int64_t{level.q(v)[a]}));
  }
  return std::min(bit_length(static_cast<uint64_t>(span)), kScaleContexts - 1);
}

double distance(const uint32_t* a, const uint32_t* b) {
  double s = 0;
  for (int k = 0; k < 3; ++k) {
    const double x = static_cast<double>(a[k]) - static_cast<double>(b[k]);
    s += x * x;
  }
  return std::sqrt(s);
}

// The ring positions ia in the order the decoder ranks the arcs r_ia ..
// r_{ia+dist} as a split's (FORMAT.md §4.8), likeliest first. A half-edge
// collapse of u into v gave v the faces of u: the arc's inner vertices
// were u's neighbours only, so they lie farther from v than the rest of
// the ring, and its ends were neighbours of both (nearer). The score is
// the inner vertices' distances from v (the ghost counting 1.5 times the
// ring's mean distance m) less half the ends' (the ghost: m); for one face
// (dist 1), the length of the edge opposite v (with the ghost: m / 2) less
// the same. In binary64 in the order written; ties to the lower position.
void arc_order(const LevelMesh& level, uint32_t v, const std::vector<uint32_t>& ring, uint32_t dist,
               std::vector<uint32_t>& order) {
  const size_t d = ring.size();
  std::vector<double> len(d, 0.0);
  double total = 0;
  size_t real = 0;
  for (size_t i = 0; i < d; ++i) {
    if (ring[i] == kGhost) continue;
    len[i] = distance(level.q(ring[i]), level.q(v));
    total += len[i];
    ++real;
  }
  const double mean = total / static_cast<double>(real);
  std::vector<double> inner(d), end(d), prefix(2 * d + 1, 0.0);
  for (size_t i = 0; i < d; ++i) {
    inner[i] = ring[i] == kGhost ? 1.5 * mean : len[i];
    end[i] = ring[i] == kGhost ? mean : len[i];
  }
  for (size_t j = 0; j < 2 * d; ++j) prefix[j + 1] = prefix[j] + inner[j % d];
  std::vector<double> score(d);
  for (size_t ia = 0; ia < d; ++ia) {
    const uint32_t y = ring[ia], x = ring[(ia + dist) % d];
    double s = 0;
    if (dist == 1)
      s = y == kGhost || x == kGhost ? 0.5 * mean : distance(level.q(y), level.q(x));
    else
      s = prefix[ia + dist] - prefix[ia + 1];
    s -= 0.5 * end[ia];
    s -= 0.5 * end[(ia + dist) % d];
    score[ia] = s;
  }
  order.resize(d);
  for (uint32_t i = 0; i < d; ++i) order[i] = i;
  std::sort(order.begin(), order.end(),
            [&](uint32_t a, uint32_t b) { return score[a] > score[b] || (score[a] == score[b] && a < b); });
}

bool open_ring(const std::vector<uint32_t>& ring) { return ring.back() == kGhost; }

int flag_context(const std::vector<uint32_t>& ring) {
  return static_cast<int>(std::min<size_t>(ring.size(), 10) - 3) + (open_ring(ring) ? kFlagContexts / 2 : 0);
}

uint32_t ring_context(const std::vector<uint32_t>& ring) {
  const uint32_t d = static_cast<uint32_t>(ring.size());
  return std::min<uint32_t>(d, kRingContexts / 2 - 1) + (open_ring(ring) ? kRingContexts / 2 : 0);
}

// The arc's end next to the ghost when the arc starts or ends at it (the
// new vertex then lies on v's border, between v and that neighbour);
// kGhost otherwise.
uint32_t border_neighbour(const std::vector<uint32_t>& ring, uint32_t ia, uint32_t dist) {
  const size_t d = ring.size();
  if (ring[ia] == kGhost) return ring[(ia + 1) % d];
  if (ring[(ia + dist) % d] == kGhost) return ring[(ia + dist + d - 1) % d];
  return kGhost;
}

// The grid position the decoder predicts for the new vertex: the centroid
// of v and the ring neighbours r_ia .. r_{ia+dist} (the new vertex's ring;
// the ghost left out); on v's border, the midpoint of v and the border
// neighbour.
void predict(const LevelMesh& level, uint32_t v, const std::vector<uint32_t>& ring, uint32_t ia, uint32_t dist,
             int64_t out[3]) {
  int64_t sum[3] = {level.q(v)[0], level.q(v)[1], level.q(v)[2]};
  const size_t d = ring.size();
  int64_t n = 1;
  const uint32_t b = border_neighbour(ring, ia, dist);
  for (uint32_t k = 0; k <= dist; ++k) {
    const uint32_t r = ring[(ia + k) % d];
    if (r == kGhost || (b != kGhost && r != b)) continue;
    const uint32_t* p = level.q(r);
    for (int a = 0; a < 3; ++a) sum[a] += p[a];
    ++n;
  }
  for (int a = 0; a < 3; ++a) out[a] = (sum[a] + n / 2) / n;
}

// The ring's normal: the sum of the cross products of consecutive ring
// edges from v, in binary64 (FORMAT.md §4.8).
void ring_normal(const LevelMesh& level, uint32_t v, const std::vector<uint32_t>& ring, double n[3]) {
  n[0] = n[1] = n[2] = 0;
  const uint32_t* c = level.q(v);
  const size_t d = ring.size();
  for (size_t i = 0; i < d; ++i) {
    if (ring[i] == kGhost || ring[(i + 1) % d] == kGhost) continue;
    const uint32_t* a = level.q(ring[i]);
    const uint32_t* b = level.q(ring[(i + 1) % d]);
    double e1[3], e2[3];
    for (int k = 0; k < 3; ++k) {
      e1[k] = static_cast<double>(a[k]) - static_cast<double>(c[k]);
      e2[k] = static_cast<double>(b[k]) - static_cast<double>(c[k]);
    }
    n[0] += e1[1] * e2[2] - e1[2] * e2[1];
    n[1] += e1[2] * e2[0] - e1[0] * e2[2];
    n[2] += e1[0] * e2[1] - e1[1] * e2[0];
  }
}

// The axes by the size of the normal's component on them: order[0] the
// axis closest to the normal (ties to the lower axis). The residuals along
// the normal are smaller than across it, so each rank has its models.
void axis_order(const double n[3], int order[3]) {
  for (int a = 0; a < 3; ++a) {
    int rank = 0;
    for (int b = 0; b < 3; ++b)
      if (std::fabs(n[b]) > std::fabs(n[a]) || (std::fabs(n[b]) == std::fabs(n[a]) && b < a)) ++rank;
    order[rank] = a;
  }
}

int64_t floor_div(int64_t a, int64_t b) {  // b > 0
  return a >= 0 ? a / b : -((-a + b - 1) / b);
}

// The new vertex's offset on the normal's axis order[0] once the two other
// residuals e1, e2 (axes order[1], order[2]) are known: the point of the
// tangent plane (the ring's normal n, in integers of at most 2^15) that
// lies half v's height above the ring's centroid (the curvature at v),
// since the centroid prediction sits on the chord below the surface. In
// integers so every decoder computes the same offset; clamped to +-qmax.
int64_t plane_offset(const LevelMesh& level, uint32_t v, const std::vector<uint32_t>& ring, const double n[3],
                     const int order[3], int64_t e1, int64_t e2, int64_t qmax) {
  const double top = std::fabs(n[order[0]]);
  if (!(top > 0)) return 0;
  int exp = 0;
  std::frexp(top, &exp);
  int64_t N[3];
  for (int a = 0; a < 3; ++a) N[a] = static_cast<int64_t>(std::floor(std::ldexp(n[a], 15 - exp) + 0.5));
  const uint64_t d = ring.size() - (open_ring(ring) ? 1 : 0);
  int64_t height = 0;  // N . (q(v) - centroid of the ring)
  for (int a = 0; a < 3; ++a) {
    uint64_t sum = 0;
    for (uint32_t r : ring)
      if (r != kGhost) sum += level.q(r)[a];
    const int64_t c = static_cast<int64_t>((sum + d / 2) / d);
    height += N[a] * (int64_t{level.q(v)[a]} - c);
  }
  const int64_t n0 = N[order[0]];
  const int64_t t = height - 2 * (N[order[1]] * e1 + N[order[2]] * e2);
  const int64_t m = n0 < 0 ? -n0 : n0;
  const int64_t o = floor_div((n0 < 0 ? -t : t) + m, 2 * m);
  return std::clamp<int64_t>(o, -qmax, qmax);
}

uint32_t position_in(const std::vector<uint32_t>& ring, uint32_t x) {
  return static_cast<uint32_t>(std::find(ring.begin(), ring.end(), x) - ring.begin());
}

}  // namespace

void LevelMesh::init(Mesh& mesh, const Header& h) {
  mesh_ = &mesh;
  h_ = h;
  step_ = grid_step(h);
  // The grid index of a decoded coordinate (FORMAT.md §5: it quantizes
  // back to the index it was decoded from).
  const double qmax = std::ldexp(1.0, h.quantization_bits) - 1.0;
  q_.resize(mesh.positions.size());
  for (size_t i = 0; i < mesh.positions.size(); ++i) {
    const double o = static_cast<double>(h.origin[i % 3]);
    const double x = step_ > 0 ? std::floor((static_cast<double>(mesh.positions[i]) - o) / step_ + 0.5) : 0.0;
    q_[i] = static_cast<uint32_t>(std::min(std::max(x, 0.0), qmax));
  }
  vf_.assign(mesh.vertex_count(), {});
  for (size_t f = 0; f < mesh.face_count(); ++f)
    for (uint32_t k = 0; k < mesh.face_size(f); ++k) {
      std::vector<uint32_t>& uses = vf_[mesh.face(f)[k]];
      if (uses.empty() || uses.back() != f) uses.push_back(static_cast<uint32_t>(f));
    }
}

bool LevelMesh::ring(uint32_t v, std::vector<uint32_t>& ring) const {
  const std::vector<uint32_t>& faces = vf_[v];
  const size_t d = faces.size();
  ring.clear();
  if (d == 0) return false;
  // next[i]: the corner after v in face i, to the one after that.
  std::vector<std::pair<uint32_t, uint32_t>> edge(d);
  for (size_t i = 0; i < d; ++i) {
    const uint32_t f = faces[i];
    if (mesh_->face_size(f) != 3) return false;
    const uint32_t* c = mesh_->face(f);
    const int k = c[0] == v ? 0 : c[1] == v ? 1 : 2;
    edge[i] = {c[(k + 1) % 3], c[(k + 2) % 3]};
  }
  return ring_from_edges(v, edge, ring);
}

bool ring_from_edges(uint32_t v, std::vector<std::pair<uint32_t, uint32_t>>& edge, std::vector<uint32_t>& ring) {
  ring.clear();
  const size_t d = edge.size();
  if (d == 0) return false;
  for (const auto& e : edge)
    if (e.first == v || e.second == v || e.first == e.second) return false;
  std::sort(edge.begin(), edge.end());
  for (size_t i = 1; i < d; ++i)
    if (edge[i].first == edge[i - 1].first) return false;
  // An open fan starts at the one first corner no edge ends at.
  std::vector<uint32_t> ends(d);
  for (size_t i = 0; i < d; ++i) ends[i] = edge[i].second;
  std::sort(ends.begin(), ends.end());
  uint32_t at = edge[0].first;
  size_t starts = 0;
  for (const auto& e : edge)
    if (!std::binary_search(ends.begin(), ends.end(), e.first) && starts++ == 0) at = e.first;
  if (starts > 1 || (starts == 0 && d < 3)) return false;
  for (size_t i = 0; i < d; ++i) {
    ring.push_back(at);
    auto it = std::lower_bound(edge.begin(), edge.end(), std::make_pair(at, uint32_t{0}));
    if (it == edge.end() || it->first != at) return false;
    at = it->second;
  }
  if (starts == 0 && at != ring[0]) return false;
  if (starts == 1) ring.push_back(at);
  std::vector<uint32_t> sorted = ring;
  std::sort(sorted.begin(), sorted.end());
  if (std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end()) return false;
  if (starts == 1) ring.push_back(kGhost);
  return true;
}

bool LevelMesh::adjacent_to_marked(uint32_t v, const std::vector<uint8_t>& marked) const {
  for (uint32_t f : vf_[v]) {
    const uint32_t* c = mesh_->face(f);
    for (uint32_t k = 0; k < mesh_->face_size(f); ++k)
      if (c[k] < marked.size() && marked[c[k]]) return true;
  }
  return false;
}

void LevelMesh::add_point(const uint32_t q[3]) {
  for (int a = 0; a < 3; ++a) q_.push_back(q[a]);
  mesh_->add_vertex(grid_value(h_, step_, 0, q[0]), grid_value(h_, step_, 1, q[1]), grid_value(h_, step_, 2, q[2]));
  vf_.emplace_back();
}

void LevelMesh::add_triangle(uint32_t a, uint32_t b, uint32_t c) {
  const uint32_t f = static_cast<uint32_t>(mesh_->face_count());
  mesh_->add_triangle(a, b, c);
  for (uint32_t w : {a, b, c}) vf_[w].push_back(f);
}

void LevelMesh::neighbours(uint32_t v, std::vector<uint32_t>& out) const {
  out.clear();
  for (uint32_t f : vf_[v]) {
    const uint32_t* c = mesh_->face(f);
    for (uint32_t k = 0; k < mesh_->face_size(f); ++k)
      if (c[k] != v) out.push_back(c[k]);
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
}

void LevelMesh::face_normal(uint32_t v, int64_t n[3]) const {
  n[0] = n[1] = n[2] = 0;
  for (uint32_t f : vf_[v]) {
    const uint32_t* c = mesh_->face(f);
    int64_t e1[3], e2[3];
    for (int a = 0; a < 3; ++a) {
      e1[a] = int64_t{q(c[1])[a]} - int64_t{q(c[0])[a]};
      e2[a] = int64_t{q(c[2])[a]} - int64_t{q(c[0])[a]};
    }
    n[0] += e1[1] * e2[2] - e1[2] * e2[1];
    n[1] += e1[2] * e2[0] - e1[0] * e2[2];
    n[2] += e1[0] * e2[1] - e1[1] * e2[0];
  }
}

uint32_t LevelMesh::split(uint32_t v, const std::vector<uint32_t>& ring, uint32_t ia, uint32_t dist,
                          const uint32_t q[3]) {
  const uint32_t u = static_cast<uint32_t>(vertex_count());
  const size_t d = ring.size();
  for (int a = 0; a < 3; ++a) q_.push_back(q[a]);
  mesh_->add_vertex(grid_value(h_, step_, 0, q[0]), grid_value(h_, step_, 1, q[1]), grid_value(h_, step_, 2, q[2]));
  vf_.emplace_back();
  // The faces (v, r_i, r_{i+1}) of the arc move to u.
  std::vector<uint32_t> keep;
  for (uint32_t f : vf_[v]) {
    uint32_t* c = mesh_->indices.data() + mesh_->face_offsets[f];
    const int k = c[0] == v ? 0 : c[1] == v ? 1 : 2;
    const uint32_t first = position_in(ring, c[(k + 1) % 3]);
    if ((first + d - ia) % d < dist) {
      c[k] = u;
      vf_[u].push_back(f);
    } else {
      keep.push_back(f);
    }
  }
  vf_[v] = std::move(keep);
  // The two faces around the new edge (v, u), but for the ghost's.
  const uint32_t y = ring[ia], x = ring[(ia + dist) % d];
  if (x != kGhost) {
    const uint32_t f = static_cast<uint32_t>(mesh_->face_count());
    mesh_->add_triangle(v, u, x);
    for (uint32_t w : {v, u, x}) vf_[w].push_back(f);
  }
  if (y != kGhost) {
    const uint32_t f = static_cast<uint32_t>(mesh_->face_count());
    mesh_->add_triangle(v, y, u);
    for (uint32_t w : {v, y, u}) vf_[w].push_back(f);
  }
  return u;
}

Status encode_batch(LevelMesh& level, const std::vector<VertexSplit>& splits, std::string& stream,
                    std::vector<uint32_t>& new_ids, uint64_t& border_splits) {
  border_splits = 0;
  const size_t n = level.vertex_count();
  std::vector<uint8_t> marked(n, 0);
  std::vector<const VertexSplit*> by_vertex(n, nullptr);
  for (const VertexSplit& s : splits) by_vertex[s.v] = &s;
  if (!level.models()) level.models() = std::make_shared<BatchModels>();
  BatchModels* m = level.models().get();
  RangeEncoder e;
  std::vector<uint32_t> ring;
  const int64_t qmax = (int64_t{1} << level.bits()) - 1;
  size_t ones = 0;
  for (uint32_t i = 0; i < n && ones < splits.size(); ++i) {
    if (level.adjacent_to_marked(i, marked) || !level.ring(i, ring)) {
      if (by_vertex[i]) return Status(ErrorCode::internal, "progressive: a split the batch cannot code");
      continue;
    }
    const int b = by_vertex[i] != nullptr;
    e.bit(m->flag[flag_context(ring)], b);
    marked[i] = static_cast<uint8_t>(b);
    ones += static_cast<size_t>(b);
  }
  std::vector<uint32_t> ids(n, 0), arcs;
  for (uint32_t v = 0; v < n; ++v) {
    if (!marked[v]) continue;
    const VertexSplit& s = *by_vertex[v];
    level.ring(v, ring);
    const uint32_t d = static_cast<uint32_t>(ring.size());
    const uint32_t ia = position_in(ring, s.y), ix = position_in(ring, s.x);
    const uint32_t dist = (ix + d - ia) % d;
    if (ia >= d || ix >= d || dist == 0) return Status(ErrorCode::internal, "progressive: a split off its ring");
    const uint32_t ctx = ring_context(ring);
    m->dist[ctx].encode(e, dist - 1);
    arc_order(level, v, ring, dist, arcs);
    m->rank[ctx][std::min<uint32_t>(dist, kRankContexts) - 1].encode(e, position_in(arcs, ia));
    int64_t p[3];
    predict(level, v, ring, ia, dist, p);
    const int sc = scale_context(level, v, ring, ia, dist);
    double nrm[3];
    int order[3];
    ring_normal(level, v, ring, nrm);
    axis_order(nrm, order);
    const bool border = border_neighbour(ring, ia, dist) != kGhost;
    SIntModelT<3>* r = border ? m->border[sc] : m->residual[sc];
    const int64_t e1 = int64_t{s.q[order[1]]} - p[order[1]], e2 = int64_t{s.q[order[2]]} - p[order[2]];
    const int64_t o = border ? 0 : plane_offset(level, v, ring, nrm, order, e1, e2, qmax);
    r[1].encode(e, static_cast<int32_t>(e1));
    r[2].encode(e, static_cast<int32_t>(e2));
    r[0].encode(e, static_cast<int32_t>(int64_t{s.q[order[0]]} - p[order[0]] - o));
    border_splits += border ? 1 : 0;
    ids[v] = level.split(v, ring, ia, dist, s.q);
  }
  for (const VertexSplit& s : splits) new_ids.push_back(ids[s.v]);
  stream = e.finish();
  return Status::Ok();
}

std::string write_batch(const BatchHeader& h, std::string_view stream) {
  std::string out;
  ByteWriter w(out);
  w.f32(h.error_before);
  w.f32(h.error_after);
  w.varint(h.splits);
  w.varint(h.border);
  w.bytes(stream);
  return out;
}

Status read_batch(std::string_view payload, BatchHeader& h, std::string_view& stream) {
  ByteReader r(payload);
  if (!r.f32(h.error_before) || !r.f32(h.error_after) || !r.varint(h.splits) || !r.varint(h.border))
    return corrupt("truncated");
  if (h.border > h.splits) return corrupt("more border splits than splits");
  for (float e : {h.error_before, h.error_after})
    if (!(e >= 0) || !std::isfinite(e)) return corrupt("an error that is not a finite non-negative number");
  r.bytes(r.remaining(), stream);
  return Status::Ok();
}

Status decode_batch(std::string_view payload, LevelMesh& level, const BatchLimits& limits) {
  BatchHeader bh;
  std::string_view stream;
  TSM_RETURN_IF_ERROR(read_batch(payload, bh, stream));
  const uint64_t splits = bh.splits;
  const size_t n = level.vertex_count();
  // Each split codes at least one flag and its ring positions: a count the
  // stream cannot hold is refused before anything grows.
  if (splits == 0 || splits > n || splits > max_decisions(stream.size()) / 4)
    return corrupt("split count " + std::to_string(splits) + " out of range");
  Mesh& mesh = level.mesh();
  if ((limits.max_vertices && n + splits > limits.max_vertices) ||
      (limits.max_faces && mesh.face_count() + 2 * splits - bh.border > limits.max_faces))
    return Status(ErrorCode::limit_exceeded, "refinement batch: the mesh would exceed the decoder's limits");
  std::vector<uint8_t> marked(n, 0);
  if (!level.models()) level.models() = std::make_shared<BatchModels>();
  BatchModels* m = level.models().get();
  RangeDecoder dec(stream);
  std::vector<uint32_t> ring;
  uint64_t ones = 0;
  for (uint32_t i = 0; i < n && ones < splits; ++i) {
    if (level.adjacent_to_marked(i, marked) || !level.ring(i, ring)) continue;
    const int b = dec.bit(m->flag[flag_context(ring)]);
    marked[i] = static_cast<uint8_t>(b);
    ones += static_cast<uint64_t>(b);
    if (dec.overrun() > RangeDecoder::kMaxOverrun) return corrupt("the stream ends inside the split flags");
  }
  if (ones != splits) return corrupt("fewer split flags than the split count");
  const int64_t qmax = (int64_t{1} << level.bits()) - 1;
  uint64_t border_splits = 0;
  std::vector<uint32_t> arcs;
  for (uint32_t v = 0; v < n; ++v) {
    if (!marked[v]) continue;
    level.ring(v, ring);
    const uint32_t d = static_cast<uint32_t>(ring.size());
    const uint32_t ctx = ring_context(ring);
    const uint32_t dist = m->dist[ctx].decode(dec) + 1;
    if (dist == 0 || dist >= d) return corrupt("a split's ring neighbours out of range");
    const uint32_t rank = m->rank[ctx][std::min<uint32_t>(dist, kRankContexts) - 1].decode(dec);
    if (rank >= d) return corrupt("a split's ring neighbours out of range");
    arc_order(level, v, ring, dist, arcs);
    const uint32_t ia = arcs[rank];
    int64_t p[3];
    predict(level, v, ring, ia, dist, p);
    const int sc = scale_context(level, v, ring, ia, dist);
    double nrm[3];
    int order[3];
    ring_normal(level, v, ring, nrm);
    axis_order(nrm, order);
    const bool border = border_neighbour(ring, ia, dist) != kGhost;
    SIntModelT<3>* r = border ? m->border[sc] : m->residual[sc];
    uint32_t q[3];
    int64_t e[3] = {0, 0, 0};
    for (int k : {1, 2, 0}) {
      e[k] = r[k].decode(dec);
      const int64_t off = k == 0 && !border ? plane_offset(level, v, ring, nrm, order, e[1], e[2], qmax) : 0;
      const int64_t x = p[order[k]] + off + e[k];
      if (x < 0 || x > qmax) return corrupt("a new vertex off the grid");
      q[order[k]] = static_cast<uint32_t>(x);
    }
    if (dec.overrun() > RangeDecoder::kMaxOverrun) return corrupt("the stream ends inside the splits");
    level.split(v, ring, ia, dist, q);
    border_splits += border ? 1 : 0;
  }
  if (border_splits != bh.border) return corrupt("a border split count that differs from the splits'");
  return Status::Ok();
}

namespace {

// The loose vertices' models (fresh per section): the anchor as a step
// from the previous one's id, then the residuals from it (by axis rank).
struct LooseVertexModels {
  UIntModelT<2> anchor;
  SIntModelT<3> residual[3];
};

// A loose vertex's frame at its anchor a (FORMAT.md §4.8): the axes ranked
// by the anchor's face normal (scaled to at most 16 bits), and the offset
// on the first that puts the vertex on the anchor's tangent plane (the
// loose vertices of a scan lie near its surface).
struct AnchorFrame {
  int64_t n[3] = {0, 0, 0};
  int order[3] = {0, 1, 2};
  int64_t offset(int64_t e1, int64_t e2, int64_t qmax) const {
    const int64_t n0 = n[order[0]];
    if (n0 == 0) return 0;
    const int64_t t = -(n[order[1]] * e1 + n[order[2]] * e2);
    const int64_t m = n0 < 0 ? -n0 : n0;
    return std::clamp<int64_t>(floor_div(2 * (n0 < 0 ? -t : t) + m, 2 * m), -qmax, qmax);
  }
};

void anchor_frame(const LevelMesh& level, uint32_t a, AnchorFrame& f) {
  level.face_normal(a, f.n);
  int shift = 0;
  for (int k = 0; k < 3; ++k)
    shift = std::max(shift, bit_length(static_cast<uint64_t>(f.n[k] < 0 ? -f.n[k] : f.n[k])) - 16);
  for (int k = 0; k < 3; ++k) f.n[k] = floor_div(f.n[k], int64_t{1} << shift);
  const double d[3] = {static_cast<double>(f.n[0]), static_cast<double>(f.n[1]), static_cast<double>(f.n[2])};
  axis_order(d, f.order);
}

// The encoder's anchor search: the level's vertices hashed by grid cell,
// searched in growing shells of cells around a point.
class LooseAnchors {
 public:
  explicit LooseAnchors(const LevelMesh& level) : level_(level) {
    const size_t n = level.vertex_count();
    uint32_t lo = 0xFFFFFFFFu, hi = 0;
    for (uint32_t v = 0; v < n; ++v)
      for (int a = 0; a < 3; ++a) lo = std::min(lo, level.q(v)[a]), hi = std::max(hi, level.q(v)[a]);
    const double side = n == 0 ? 1.0 : static_cast<double>(hi - lo) / std::ceil(std::sqrt(static_cast<double>(n)));
    cell_ = std::max<int64_t>(1, static_cast<int64_t>(side));
    for (uint32_t v = 0; v < n; ++v) cells_[key(cell_of(level.q(v)))].push_back(v);
  }
  // The vertex nearest p (squared grid distance; ties: the least id).
  uint32_t nearest(const uint32_t* p) const {
    const std::array<int64_t, 3> c = cell_of(p);
    uint64_t best = ~uint64_t{0};
    uint32_t at = 0;
    for (int64_t r = 0;; ++r) {
      if (r > kShells) return brute(p);
      for (int64_t i = -r; i <= r; ++i)
        for (int64_t j = -r; j <= r; ++j)
          for (int64_t k = -r; k <= r; ++k) {
            if (std::max({std::abs(i), std::abs(j), std::abs(k)}) != r) continue;
            auto it = cells_.find(key({c[0] + i, c[1] + j, c[2] + k}));
            if (it == cells_.end()) continue;
            for (uint32_t v : it->second) consider(p, v, best, at);
          }
      // Vertices of cells farther out lie at least r * cell + 1 away.
      const uint64_t reach = static_cast<uint64_t>(r * cell_ + 1);
      if (best < reach * reach) return at;
    }
  }

 private:
  static constexpr int64_t kShells = 8;
  std::array<int64_t, 3> cell_of(const uint32_t* p) const {
    return {int64_t{p[0]} / cell_, int64_t{p[1]} / cell_, int64_t{p[2]} / cell_};
  }
  static uint64_t key(const std::array<int64_t, 3>& c) {
    return (static_cast<uint64_t>(c[0]) * 0x9E3779B97F4A7C15ull) ^ (static_cast<uint64_t>(c[1]) << 32) ^
           (static_cast<uint64_t>(c[2]) * 0xC2B2AE3D27D4EB4Full);
  }
  void consider(const uint32_t* p, uint32_t v, uint64_t& best, uint32_t& at) const {
    uint64_t d2 = 0;
    for (int a = 0; a < 3; ++a) {
      const int64_t d = int64_t{p[a]} - int64_t{level_.q(v)[a]};
      d2 += static_cast<uint64_t>(d * d);
    }
    if (d2 < best || (d2 == best && v < at)) best = d2, at = v;
  }
  uint32_t brute(const uint32_t* p) const {
    uint64_t best = ~uint64_t{0};
    uint32_t at = 0;
    for (uint32_t v = 0; v < level_.vertex_count(); ++v) consider(p, v, best, at);
    return at;
  }
  const LevelMesh& level_;
  int64_t cell_ = 1;
  std::unordered_map<uint64_t, std::vector<uint32_t>> cells_;
};

}  // namespace

// The left-out triangles' models (fresh per section): the first corner as
// a step from the previous face's, the others as a pick among the first
// corner's neighbours (the second's too, for the third), 0 = not there,
// then the difference from the first corner.
struct LooseFaceModels {
  UIntModelT<2> first, pick[2], far[2];
};

// The pick candidates of corner k (1, 2) of a triangle whose earlier
// corners are c[0 .. k-1]: the neighbours of those corners, in increasing
// id, without the corners themselves.
void pick_candidates(const LevelMesh& level, const uint32_t* c, int k, std::vector<uint32_t>& out) {
  std::vector<uint32_t> more;
  level.neighbours(c[0], out);
  if (k == 2) {
    level.neighbours(c[1], more);
    out.insert(out.end(), more.begin(), more.end());
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
  }
  out.erase(std::remove_if(out.begin(), out.end(), [&](uint32_t x) { return x == c[0] || (k == 2 && x == c[1]); }),
            out.end());
}

std::vector<uint32_t> loose_order(const LevelMesh& level, const std::vector<uint32_t>& q) {
  const size_t n = q.size() / 3;
  const LooseAnchors anchors(level);
  std::vector<std::array<uint32_t, 5>> keyed(n);  // anchor, grid index, position in q
  for (size_t i = 0; i < n; ++i)
    keyed[i] = {anchors.nearest(&q[3 * i]), q[3 * i], q[3 * i + 1], q[3 * i + 2], static_cast<uint32_t>(i)};
  std::sort(keyed.begin(), keyed.end());
  std::vector<uint32_t> order(n);
  for (size_t i = 0; i < n; ++i) order[i] = keyed[i][4];
  return order;
}

Status encode_loose(LevelMesh& level, std::vector<uint32_t> q, std::vector<std::array<uint32_t, 3>> faces,
                    std::string& out) {
  const size_t n = q.size() / 3;
  const std::vector<uint32_t> order = loose_order(level, q);
  for (size_t i = 0; i < n; ++i)
    if (order[i] != i) return Status(ErrorCode::internal, "progressive: loose vertices out of order");
  const LooseAnchors anchors(level);
  LooseVertexModels m;
  RangeEncoder e;
  const int64_t qmax = (int64_t{1} << level.bits()) - 1;
  uint32_t previous_anchor = 0;
  AnchorFrame frame;
  for (size_t i = 0; i < n; ++i) {
    const uint32_t* p = &q[3 * i];
    const uint32_t a = anchors.nearest(p);
    m.anchor.encode(e, a - previous_anchor);
    if (i == 0 || a != previous_anchor) anchor_frame(level, a, frame);
    previous_anchor = a;
    int64_t r[3];
    for (int k = 1; k < 3; ++k) r[k] = int64_t{p[frame.order[k]]} - int64_t{level.q(a)[frame.order[k]]};
    r[0] = int64_t{p[frame.order[0]]} - int64_t{level.q(a)[frame.order[0]]} - frame.offset(r[1], r[2], qmax);
    for (int k : {1, 2, 0}) m.residual[k].encode(e, static_cast<int32_t>(r[k]));
  }
  for (size_t i = 0; i < n; ++i) level.add_point(&q[3 * i]);
  for (auto& f : faces) std::rotate(f.begin(), std::min_element(f.begin(), f.end()), f.end());
  std::sort(faces.begin(), faces.end());
  auto fm = std::make_unique<LooseFaceModels>();
  std::vector<uint32_t> cand;
  uint32_t previous = 0;
  for (const auto& f : faces) {
    fm->first.encode(e, f[0] - previous);
    previous = f[0];
    for (int k = 1; k < 3; ++k) {
      pick_candidates(level, f.data(), k, cand);
      const auto it = std::lower_bound(cand.begin(), cand.end(), f[k]);
      const bool found = it != cand.end() && *it == f[k];
      fm->pick[k - 1].encode(e, found ? static_cast<uint32_t>(it - cand.begin()) + 1 : 0);
      if (!found) fm->far[k - 1].encode(e, f[k] - f[0] - 1);
    }
    level.add_triangle(f[0], f[1], f[2]);
  }
  ByteWriter w(out);
  w.varint(n);
  w.varint(faces.size());
  w.bytes(e.finish());
  return Status::Ok();
}

Status decode_loose(std::string_view payload, LevelMesh& level, const BatchLimits& limits) {
  ByteReader r(payload);
  uint64_t n = 0, faces = 0;
  if (!r.varint(n) || !r.varint(faces)) return corrupt("loose section: truncated");
  std::string_view stream;
  r.bytes(r.remaining(), stream);
  if (n + faces == 0 || n > max_decisions(stream.size()) / 3 || faces > max_decisions(stream.size()) / 3 ||
      n + faces > max_decisions(stream.size()) / 3)
    return corrupt("loose vertex or face count out of range");
  if ((limits.max_vertices && level.vertex_count() + n > limits.max_vertices) ||
      (limits.max_faces && level.mesh().face_count() + faces > limits.max_faces))
    return Status(ErrorCode::limit_exceeded, "loose section: the mesh would exceed the decoder's limits");
  LooseVertexModels m;
  RangeDecoder dec(stream);
  const int64_t qmax = (int64_t{1} << level.bits()) - 1;
  const uint64_t anchors = level.vertex_count();
  std::vector<uint32_t> points;
  uint64_t at = 0;
  uint32_t framed = 0;
  AnchorFrame f;
  for (uint64_t i = 0; i < n; ++i) {
    at += m.anchor.decode(dec);
    if (at >= anchors) return corrupt("a loose vertex's anchor out of range");
    const uint32_t anchor = static_cast<uint32_t>(at);
    // Anchors never decrease: each one's faces are summed once (the work
    // stays within the level's face corners, whatever the count).
    if (i == 0 || anchor != framed) anchor_frame(level, anchor, f);
    framed = anchor;
    int64_t e[3] = {0, 0, 0};
    uint32_t p[3];
    for (int k : {1, 2, 0}) {
      e[k] = m.residual[k].decode(dec);
      const int64_t x =
          int64_t{level.q(anchor)[f.order[k]]} + e[k] + (k == 0 ? f.offset(e[1], e[2], qmax) : int64_t{0});
      if (x < 0 || x > qmax) return corrupt("a loose vertex off the grid");
      p[f.order[k]] = static_cast<uint32_t>(x);
    }
    if (dec.overrun() > RangeDecoder::kMaxOverrun) return corrupt("the loose vertices' stream ends early");
    points.insert(points.end(), p, p + 3);
  }
  for (uint64_t i = 0; i < n; ++i) level.add_point(&points[3 * i]);
  auto fm = std::make_unique<LooseFaceModels>();
  std::vector<uint32_t> cand;
  const uint64_t vertices = level.vertex_count();
  uint64_t previous = 0;
  for (uint64_t i = 0; i < faces; ++i) {
    uint32_t c[3];
    const uint64_t a = previous + fm->first.decode(dec);
    if (a >= vertices) return corrupt("a left-out face's corner out of range");
    c[0] = static_cast<uint32_t>(a);
    previous = a;
    for (int k = 1; k < 3; ++k) {
      pick_candidates(level, c, k, cand);
      const uint64_t pick = fm->pick[k - 1].decode(dec);
      const uint64_t x =
          pick > 0 ? (pick <= cand.size() ? cand[pick - 1] : vertices) : a + 1 + uint64_t{fm->far[k - 1].decode(dec)};
      if (x >= vertices || x <= a || (k == 2 && x == c[1])) return corrupt("a left-out face's corner out of range");
      c[k] = static_cast<uint32_t>(x);
    }
    if (dec.overrun() > RangeDecoder::kMaxOverrun) return corrupt("the left-out faces' stream ends early");
    level.add_triangle(c[0], c[1], c[2]);
  }
  return Status::Ok();
}

}  // namespace tsm

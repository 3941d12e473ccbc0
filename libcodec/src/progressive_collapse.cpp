// Progressive meshes, encoder side (seed 003, Hoppe's edge collapses, in
// batches as Compressed Progressive Meshes; FORMAT.md §4.8): the input,
// already on the quantization grid, is coarsened by half-edge collapses
// (a vertex u merged into a neighbour v, so every vertex keeps its grid
// position and each split gives back one exactly), in quadric-error order,
// grouped into batches of independent collapses (their faces pairwise
// disjoint). A border vertex merges into a neighbour along its border (the
// border's shape held by quadric planes across its edges), so holes are
// neither closed nor opened. What the collapses cannot handle
// (non-manifold vertices, polygons, degenerate faces, coincident grid
// points) stays in the base mesh.
#include <algorithm>
#include <array>
#include <cmath>
#include <set>
#include <unordered_map>
#include <unordered_set>

#include "progressive.hpp"
#include "progressive_plan.hpp"

namespace tsm {

namespace {

using Quadric = std::array<double, 10>;  // xx xy xz xw yy yz yw zz zw ww

// The weights of a collapse's prediction error and of its edge's squared
// length against its quadric error: short edges first keep the levels'
// triangles regular (where the quadric is flat, e.g. a scan's cut bottom),
// which makes the splits' residuals smaller.
constexpr double kRegularity = 0.2;
constexpr double kLength = 0.02;
// The weight of a border edge's plane (through the edge, across its face)
// per squared edge length.
constexpr double kBorderWeight = 1.0;
// A batch takes no collapse costing more than the one a quarter of the way
// down its candidate list (once it has min_batch_splits): the expensive
// collapses wait for coarser levels, so their vertices come back in early
// batches and a short prefix of the file has the error-removing splits.
constexpr size_t kCeilingAt = 4;

void add_plane(Quadric& q, const double n[3], double d, double w) {
  const double p[4] = {n[0], n[1], n[2], d};
  int k = 0;
  for (int i = 0; i < 4; ++i)
    for (int j = i; j < 4; ++j) q[k++] += w * p[i] * p[j];
}

double quadric_at(const Quadric& q, const double p[3]) {
  const double x = p[0], y = p[1], z = p[2];
  return q[0] * x * x + 2 * q[1] * x * y + 2 * q[2] * x * z + 2 * q[3] * x + q[4] * y * y + 2 * q[5] * y * z +
         2 * q[6] * y + q[7] * z * z + 2 * q[8] * z + q[9];
}

// Ties by the vertices' canonical ranks (their order by grid point), so the
// plan does not depend on the input's vertex order.
struct Candidate {
  double cost;
  uint32_t ru, rv;  // canonical ranks of u and v
  uint32_t u, v;
  bool operator<(const Candidate& o) const {
    return cost < o.cost || (cost == o.cost && (ru < o.ru || (ru == o.ru && rv < o.rv)));
  }
};

class Collapser {
 public:
  Collapser(const Mesh& mesh, const std::vector<uint32_t>& q, const ProgressiveOptions& options)
      : mesh_(mesh), q_(q), options_(options) {}
  void run(CollapsePlan& plan);

 private:
  void rank_vertices();
  void build();
  void lock_special();
  void lock_shared_points();
  void add_border_planes();
  bool ring(uint32_t v, std::vector<uint32_t>& out) const;
  bool keeps_fan(uint32_t w);
  void cross(const uint32_t t[3], uint32_t from, uint32_t to, int64_t n[3]) const;
  bool valid(uint32_t u, uint32_t v, CollapseRecord& rec);
  void collapse(const CollapseRecord& rec);
  std::vector<Candidate> candidates();
  size_t batch(std::vector<CollapseRecord>& out);
  void write_base(CollapsePlan& plan) const;
  bool keep_triangle(const uint32_t c[3]);
  std::vector<uint8_t> choose_kept(const std::vector<std::array<uint32_t, 3>>& tris);
  double level_error() const;

  const Mesh& mesh_;
  const std::vector<uint32_t>& q_;
  ProgressiveOptions options_;
  std::vector<std::array<uint32_t, 3>> tri_;
  std::vector<uint8_t> alive_;
  std::vector<uint32_t> stamp_;  // per triangle: the batch that touched it last (+1)
  uint32_t batch_no_ = 0;
  std::vector<uint32_t> other_faces_;  // faces the collapses leave alone (polygons, degenerate)
  std::vector<std::vector<uint32_t>> vf_;
  std::vector<uint8_t> locked_, dup_, extreme_, removed_, used_;
  std::vector<Quadric> quadric_;
  std::vector<uint32_t> merged_into_;  // per removed vertex: v of its collapse
  size_t vertices_left_ = 0;
  std::vector<uint32_t> ring_u_, ring_v_, ring_w_;
  std::vector<uint32_t> rank_;   // per vertex: its place in the order by grid point (then input id)
  std::vector<uint32_t> order_;  // vertices by rank
  std::vector<std::array<uint32_t, 3>> left_out_;
  std::unordered_map<uint64_t, uint32_t> edge_uses_;  // undirected edge -> faces kept on it
  std::unordered_set<uint64_t> directed_;             // kept directed edges
  std::set<std::array<uint32_t, 3>> corner_sets_;     // kept triangles' sorted corners
};

uint64_t pair_key(uint32_t a, uint32_t b) { return (uint64_t{a} << 32) | b; }

// A triangle (canonical order) joins the levels unless it repeats the
// corners of one kept before, uses an edge in a direction a kept one
// already does, or would be the third on an edge: those are coded after
// the last batch, so the kept faces form fans where a scan's sheets touch.
// (A kept triangle is registered on its edges here.)
bool Collapser::keep_triangle(const uint32_t c[3]) {
  // The encoder finds a vertex of the decoded base by its grid point: one
  // sharing its point with another stays with all its faces.
  const bool forced = dup_[c[0]] || dup_[c[1]] || dup_[c[2]];
  std::array<uint32_t, 3> s = {c[0], c[1], c[2]};
  std::sort(s.begin(), s.end());
  if (!forced && corner_sets_.count(s)) return false;
  for (int k = 0; k < 3 && !forced; ++k) {
    const uint32_t a = c[k], b = c[(k + 1) % 3];
    if (directed_.count(pair_key(a, b))) return false;
    auto it = edge_uses_.find(pair_key(std::min(a, b), std::max(a, b)));
    if (it != edge_uses_.end() && it->second >= 2) return false;
  }
  for (int k = 0; k < 3; ++k) {
    const uint32_t a = c[k], b = c[(k + 1) % 3];
    directed_.insert(pair_key(a, b));
    ++edge_uses_[pair_key(std::min(a, b), std::max(a, b))];
  }
  corner_sets_.insert(s);
  return true;
}

// The plan depends only on the mesh as the decoder gives it back (grid
// points and faces, whatever the vertex and face order and the corners'
// rotation), so that decoding a progressive file and encoding it again
// gives the same bytes: vertices are ranked by grid point, triangles are
// taken rotated to their least-ranked corner, in the order of their ranks.
// Which triangles (canonical corner ranks, sorted) join the levels, by
// keep_triangle in a breadth-first order over shared edges from the first,
// so one orientation spreads over a sheet whose faces are all there twice;
// triangles with an edge no other triangle has (fins) come after the rest.
std::vector<uint8_t> Collapser::choose_kept(const std::vector<std::array<uint32_t, 3>>& tris) {
  const size_t n = tris.size();
  std::vector<std::pair<uint64_t, uint32_t>> edges;
  edges.reserve(3 * n);
  for (uint32_t t = 0; t < n; ++t)
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = tris[t][k], b = tris[t][(k + 1) % 3];
      edges.emplace_back(pair_key(std::min(a, b), std::max(a, b)), t);
    }
  std::sort(edges.begin(), edges.end());
  std::vector<uint8_t> open(n, 0);  // has an edge no other triangle has
  for (size_t i = 0; i < edges.size(); ++i) {
    const bool alone = (i == 0 || edges[i - 1].first != edges[i].first) &&
                       (i + 1 == edges.size() || edges[i + 1].first != edges[i].first);
    if (alone) open[edges[i].second] = 1;
  }
  std::vector<uint8_t> seen(n, 0), kept(n, 0);
  std::vector<uint32_t> queue;
  for (int pass = 0; pass < 2; ++pass)
    for (uint32_t seed = 0; seed < n; ++seed) {
      if (seen[seed] || open[seed] != pass) continue;
      queue.assign(1, seed);
      seen[seed] = 1;
      for (size_t head = 0; head < queue.size(); ++head) {
        const uint32_t t = queue[head];
        const uint32_t c[3] = {order_[tris[t][0]], order_[tris[t][1]], order_[tris[t][2]]};
        kept[t] = keep_triangle(c) ? 1 : 0;
        for (int k = 0; k < 3; ++k) {
          const uint32_t a = tris[t][k], b = tris[t][(k + 1) % 3];
          const uint64_t key = pair_key(std::min(a, b), std::max(a, b));
          auto it = std::lower_bound(edges.begin(), edges.end(), std::make_pair(key, uint32_t{0}));
          for (; it != edges.end() && it->first == key; ++it)
            if (!seen[it->second] && open[it->second] == pass) seen[it->second] = 1, queue.push_back(it->second);
        }
      }
    }
  return kept;
}

void Collapser::rank_vertices() {
  const size_t n = mesh_.vertex_count();
  order_.resize(n);
  for (uint32_t i = 0; i < n; ++i) order_[i] = i;
  std::sort(order_.begin(), order_.end(), [&](uint32_t a, uint32_t b) {
    const uint32_t* qa = &q_[3 * size_t{a}];
    const uint32_t* qb = &q_[3 * size_t{b}];
    if (qa[0] != qb[0]) return qa[0] < qb[0];
    if (qa[1] != qb[1]) return qa[1] < qb[1];
    if (qa[2] != qb[2]) return qa[2] < qb[2];
    return a < b;
  });
  rank_.resize(n);
  for (uint32_t i = 0; i < n; ++i) rank_[order_[i]] = i;
}

void Collapser::build() {
  const size_t n = mesh_.vertex_count();
  vf_.assign(n, {});
  locked_.assign(n, 0);
  dup_.assign(n, 0);
  extreme_.assign(n, 0);
  used_.assign(n, 0);
  removed_.assign(n, 0);
  merged_into_.assign(n, 0);
  quadric_.assign(n, Quadric{});
  lock_shared_points();
  std::vector<std::array<uint32_t, 3>> tris;  // canonical corner ranks
  std::vector<std::pair<std::vector<uint32_t>, uint32_t>> others;
  for (size_t f = 0; f < mesh_.face_count(); ++f) {
    const uint32_t* c = mesh_.face(f);
    const uint32_t k = mesh_.face_size(f);
    for (uint32_t j = 0; j < k; ++j) used_[c[j]] = 1;
    // Rotated to its least-ranked corner.
    uint32_t first = 0;
    for (uint32_t j = 1; j < k; ++j)
      if (rank_[c[j]] < rank_[c[first]]) first = j;
    std::vector<uint32_t> r(k);
    for (uint32_t j = 0; j < k; ++j) r[j] = rank_[c[(first + j) % k]];
    if (k != 3 || c[0] == c[1] || c[1] == c[2] || c[0] == c[2]) {
      for (uint32_t j = 0; j < k; ++j) locked_[c[j]] = 1;
      others.emplace_back(std::move(r), static_cast<uint32_t>(f));
      continue;
    }
    tris.push_back({r[0], r[1], r[2]});
  }
  std::sort(others.begin(), others.end());
  for (const auto& o : others) other_faces_.push_back(o.second);
  std::sort(tris.begin(), tris.end());
  const std::vector<uint8_t> kept = choose_kept(tris);
  for (size_t i = 0; i < tris.size(); ++i) {
    const auto& r = tris[i];
    const uint32_t c[3] = {order_[r[0]], order_[r[1]], order_[r[2]]};
    if (!kept[i]) {
      left_out_.push_back({c[0], c[1], c[2]});
      continue;
    }
    const uint32_t t = static_cast<uint32_t>(tri_.size());
    tri_.push_back({c[0], c[1], c[2]});
    for (int k = 0; k < 3; ++k) vf_[c[k]].push_back(t);
    double p[3][3];
    for (int k = 0; k < 3; ++k)
      for (int a = 0; a < 3; ++a) p[k][a] = q_[3 * size_t{c[k]} + a];
    double e1[3], e2[3], nrm[3];
    for (int a = 0; a < 3; ++a) e1[a] = p[1][a] - p[0][a], e2[a] = p[2][a] - p[0][a];
    nrm[0] = e1[1] * e2[2] - e1[2] * e2[1];
    nrm[1] = e1[2] * e2[0] - e1[0] * e2[2];
    nrm[2] = e1[0] * e2[1] - e1[1] * e2[0];
    const double len = std::sqrt(nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2]);
    if (len == 0) continue;
    for (double& x : nrm) x /= len;
    const double d = -(nrm[0] * p[0][0] + nrm[1] * p[0][1] + nrm[2] * p[0][2]);
    for (int k = 0; k < 3; ++k) add_plane(quadric_[c[k]], nrm, d, 0.5 * len);
  }
  alive_.assign(tri_.size(), 1);
  stamp_.assign(tri_.size(), 0);
  vertices_left_ = n;
}

// A border edge (a, b) (no triangle has (b, a)) adds to both ends the plane
// through it perpendicular to its face, so collapses along the border keep
// its shape within their quadric error.
void Collapser::add_border_planes() {
  std::vector<std::pair<uint32_t, uint32_t>> directed;
  directed.reserve(3 * tri_.size());
  for (const auto& c : tri_)
    for (int k = 0; k < 3; ++k) directed.emplace_back(c[k], c[(k + 1) % 3]);
  std::sort(directed.begin(), directed.end());
  auto pos = [&](uint32_t v, double p[3]) {
    for (int a = 0; a < 3; ++a) p[a] = q_[3 * size_t{v} + a];
  };
  for (const auto& c : tri_)
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = c[k], b = c[(k + 1) % 3];
      if (std::binary_search(directed.begin(), directed.end(), std::make_pair(b, a))) continue;
      double pa[3], pb[3], pc[3], e[3], f[3], n[3], m[3];
      pos(a, pa), pos(b, pb), pos(c[(k + 2) % 3], pc);
      for (int i = 0; i < 3; ++i) e[i] = pb[i] - pa[i], f[i] = pc[i] - pa[i];
      n[0] = e[1] * f[2] - e[2] * f[1];
      n[1] = e[2] * f[0] - e[0] * f[2];
      n[2] = e[0] * f[1] - e[1] * f[0];
      m[0] = e[1] * n[2] - e[2] * n[1];
      m[1] = e[2] * n[0] - e[0] * n[2];
      m[2] = e[0] * n[1] - e[1] * n[0];
      const double len = std::sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
      if (len == 0) continue;
      for (double& x : m) x /= len;
      const double d = -(m[0] * pa[0] + m[1] * pa[1] + m[2] * pa[2]);
      const double w = kBorderWeight * (e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
      add_plane(quadric_[a], m, d, w);
      add_plane(quadric_[b], m, d, w);
    }
}

// Vertices that must stay: those of the faces above, those sharing a grid
// point with another (the encoder finds base vertices in the decoded base
// by their grid point), and one vertex on each side of the grid's box (the
// first in grid-point order at the least and the greatest grid index of
// each axis; the positions are on the grid, so the base mesh has the
// input's box, hence its grid).
void Collapser::lock_shared_points() {
  const size_t n = mesh_.vertex_count();
  std::unordered_map<uint64_t, uint32_t> seen;
  seen.reserve(n);
  for (uint32_t i = 0; i < n; ++i) {
    const uint64_t key = (uint64_t{q_[3 * size_t{i}]} * 0x9E3779B97F4A7C15ull) ^
                         (uint64_t{q_[3 * size_t{i} + 1]} << 32) ^
                         (uint64_t{q_[3 * size_t{i} + 2]} * 0xC2B2AE3D27D4EB4Full);
    auto [it, fresh] = seen.emplace(key, i);
    if (!fresh) locked_[i] = locked_[it->second] = dup_[i] = dup_[it->second] = 1;
  }
}

void Collapser::lock_special() {
  const size_t n = mesh_.vertex_count();
  for (int a = 0; a < 3 && n; ++a) {
    uint32_t lo = order_[0], hi = order_[0];
    for (uint32_t i : order_) {
      if (q_[3 * size_t{i} + a] < q_[3 * size_t{lo} + a]) lo = i;
      if (q_[3 * size_t{i} + a] > q_[3 * size_t{hi} + a]) hi = i;
    }
    locked_[lo] = locked_[hi] = extreme_[lo] = extreme_[hi] = 1;
  }
}

// As LevelMesh::ring (the decoder's), over the live triangles.
bool Collapser::ring(uint32_t v, std::vector<uint32_t>& out) const {
  const std::vector<uint32_t>& faces = vf_[v];
  const size_t d = faces.size();
  out.clear();
  if (d == 0) return false;
  std::vector<std::pair<uint32_t, uint32_t>> edge(d);
  for (size_t i = 0; i < d; ++i) {
    const auto& c = tri_[faces[i]];
    const int k = c[0] == v ? 0 : c[1] == v ? 1 : 2;
    edge[i] = {c[(k + 1) % 3], c[(k + 2) % 3]};
  }
  return ring_from_edges(v, edge, out);
}

// Normal of triangle t with vertex `from` moved to `to`'s grid point.
void Collapser::cross(const uint32_t t[3], uint32_t from, uint32_t to, int64_t n[3]) const {
  int64_t p[3][3];
  for (int k = 0; k < 3; ++k) {
    const uint32_t w = t[k] == from ? to : t[k];
    for (int a = 0; a < 3; ++a) p[k][a] = q_[3 * size_t{w} + a];
  }
  int64_t e1[3], e2[3];
  for (int a = 0; a < 3; ++a) e1[a] = p[1][a] - p[0][a], e2[a] = p[2][a] - p[0][a];
  n[0] = e1[1] * e2[2] - e1[2] * e2[1];
  n[1] = e1[2] * e2[0] - e1[0] * e2[2];
  n[2] = e1[0] * e2[1] - e1[1] * e2[0];
}

// u merged into v keeps both fans manifold, the link condition, and turns
// no triangle over or flat.
// w, a neighbour of both u and v, keeps a fan after losing their shared
// face: 3 faces inside the surface, 1 on a border.
bool Collapser::keeps_fan(uint32_t w) {
  if (w == kGhost) return true;
  if (dup_[w] || vf_[w].size() < 2) return false;
  return vf_[w].size() >= 4 || (ring(w, ring_w_) && ring_w_.back() == kGhost);
}

bool Collapser::valid(uint32_t u, uint32_t v, CollapseRecord& rec) {
  if (!ring(u, ring_u_) || !ring(v, ring_v_)) return false;
  const size_t du = ring_u_.size(), dv = ring_v_.size();
  if (du + dv < 7) return false;
  // A border vertex merges only along its border.
  if (ring_u_.back() == kGhost && v != ring_u_.front() && v != ring_u_[du - 2]) return false;
  const size_t j = static_cast<size_t>(std::find(ring_v_.begin(), ring_v_.end(), u) - ring_v_.begin());
  if (j == dv) return false;
  rec = {u, v, ring_v_[(j + dv - 1) % dv], ring_v_[(j + 1) % dv]};
  std::vector<uint32_t> a = ring_u_, b = ring_v_;
  std::sort(a.begin(), a.end());
  std::sort(b.begin(), b.end());
  std::vector<uint32_t> common;
  std::set_intersection(a.begin(), a.end(), b.begin(), b.end(), std::back_inserter(common));
  if (common.size() != 2) return false;
  for (uint32_t w : {rec.x, rec.y})
    if (!keeps_fan(w)) return false;
  for (uint32_t t : vf_[u]) {
    const auto& c = tri_[t];
    if (c[0] == v || c[1] == v || c[2] == v) continue;
    int64_t before[3], after[3];
    cross(c.data(), u, u, before);
    cross(c.data(), u, v, after);
    if (after[0] == 0 && after[1] == 0 && after[2] == 0) return false;
    const double dot = static_cast<double>(before[0]) * static_cast<double>(after[0]) +
                       static_cast<double>(before[1]) * static_cast<double>(after[1]) +
                       static_cast<double>(before[2]) * static_cast<double>(after[2]);
    if (!(dot > 0)) return false;
  }
  return true;
}

void Collapser::collapse(const CollapseRecord& rec) {
  const uint32_t u = rec.u, v = rec.v;
  auto drop = [&](uint32_t w, uint32_t t) {
    std::vector<uint32_t>& f = vf_[w];
    f.erase(std::find(f.begin(), f.end(), t));
  };
  for (uint32_t t : vf_[u]) {
    auto& c = tri_[t];
    if (c[0] == v || c[1] == v || c[2] == v) {
      alive_[t] = 0;
      for (uint32_t w : c)
        if (w != u) drop(w, t);
      continue;
    }
    for (uint32_t& w : c)
      if (w == u) w = v;
    vf_[v].push_back(t);
  }
  vf_[u].clear();
  for (int k = 0; k < 10; ++k) quadric_[v][k] += quadric_[u][k];
  removed_[u] = 1;
  merged_into_[u] = v;
  --vertices_left_;
}

// Every half-edge u -> v whose u may go, by its quadric cost (a vertex
// whose cheapest merge is refused may still take another).
std::vector<Candidate> Collapser::candidates() {
  std::vector<Candidate> out;
  std::vector<uint32_t> r;
  for (uint32_t u = 0; u < vf_.size(); ++u) {
    if (removed_[u] || locked_[u] || !ring(u, r)) continue;
    // How far u lies from the centroid of its ring: the decoder predicts
    // the new vertex there (FORMAT.md §4.8), so collapses of vertices it
    // predicts well go first.
    // On a border: from the midpoint of its border neighbours.
    const bool border = r.back() == kGhost;
    if (border) r = {r.front(), r[r.size() - 2]};
    double lap2 = 0;
    for (int a = 0; a < 3; ++a) {
      double c = 0;
      for (uint32_t w : r) c += q_[3 * size_t{w} + a];
      const double l = q_[3 * size_t{u} + a] - c / static_cast<double>(r.size());
      lap2 += l * l;
    }
    for (uint32_t v : r) {
      if (locked_[v]) continue;
      Quadric q = quadric_[u];
      for (int k = 0; k < 10; ++k) q[k] += quadric_[v][k];
      const double p[3] = {static_cast<double>(q_[3 * size_t{v}]), static_cast<double>(q_[3 * size_t{v} + 1]),
                           static_cast<double>(q_[3 * size_t{v} + 2])};
      double len2 = 0;
      for (int a = 0; a < 3; ++a) {
        const double d = p[a] - static_cast<double>(q_[3 * size_t{u} + a]);
        len2 += d * d;
      }
      // The quadric error, plus the squared distances above weighted by the
      // faces' area (the quadric's weight, q[0] + q[4] + q[7]).
      const double cost = quadric_at(q, p) + (kRegularity * lap2 + kLength * len2) * (q[0] + q[4] + q[7]);
      out.push_back({cost, rank_[u], rank_[v], u, v});
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

// One batch: the cheapest collapses whose faces no other collapse of the
// batch touches, at most a third of the vertices (+50% on refinement),
// none above the ceiling (kCeilingAt).
size_t Collapser::batch(std::vector<CollapseRecord>& out) {
  ++batch_no_;
  const size_t limit = vertices_left_ / 3;
  CollapseRecord rec;
  const std::vector<Candidate> all = candidates();
  const double ceiling = all.empty() ? 0 : all[all.size() / kCeilingAt].cost;
  for (const Candidate& c : all) {
    if (out.size() >= limit || (c.cost > ceiling && out.size() >= options_.min_batch_splits)) break;
    if (removed_[c.u] || removed_[c.v]) continue;
    bool free = true;
    for (uint32_t w : {c.u, c.v})
      for (uint32_t t : vf_[w]) free = free && stamp_[t] != batch_no_;
    if (!free || !valid(c.u, c.v, rec)) continue;
    for (uint32_t w : {c.u, c.v})
      for (uint32_t t : vf_[w]) stamp_[t] = batch_no_;
    collapse(rec);
    out.push_back(rec);
  }
  return out.size();
}

void Collapser::write_base(CollapsePlan& plan) const {
  const size_t n = mesh_.vertex_count();
  Mesh& base = plan.base;
  base.clear();
  plan.base_id.assign(n, kNotInBase);
  plan.loose.clear();
  for (uint32_t i : order_) {
    if (removed_[i]) continue;
    if (!used_[i] && !extreme_[i] && !plan.batches.empty()) {
      plan.loose.push_back(i);
      continue;
    }
    plan.base_id[i] = static_cast<uint32_t>(base.vertex_count());
    base.add_vertex(mesh_.positions[3 * size_t{i}], mesh_.positions[3 * size_t{i} + 1],
                    mesh_.positions[3 * size_t{i} + 2]);
  }
  std::vector<uint32_t> corners;
  for (uint32_t f : other_faces_) {
    corners.clear();
    for (uint32_t k = 0; k < mesh_.face_size(f); ++k) corners.push_back(plan.base_id[mesh_.face(f)[k]]);
    base.add_face(corners.data(), corners.size());
  }
  for (size_t t = 0; t < tri_.size(); ++t)
    if (alive_[t]) base.add_triangle(plan.base_id[tri_[t][0]], plan.base_id[tri_[t][1]], plan.base_id[tri_[t][2]]);
  plan.left_out.clear();
  for (const auto& c : left_out_) {
    if (plan.batches.empty())
      base.add_triangle(plan.base_id[c[0]], plan.base_id[c[1]], plan.base_id[c[2]]);
    else
      plan.left_out.push_back(c);
  }
  base.metadata = mesh_.metadata;
}

double Collapser::level_error() const {
  double worst = 0;
  for (uint32_t u = 0; u < removed_.size(); ++u) {
    if (!removed_[u]) continue;
    uint32_t r = merged_into_[u];
    while (removed_[r]) r = merged_into_[r];
    double d2 = 0;
    for (int a = 0; a < 3; ++a) {
      const double d = static_cast<double>(q_[3 * size_t{u} + a]) - static_cast<double>(q_[3 * size_t{r} + a]);
      d2 += d * d;
    }
    worst = std::max(worst, d2);
  }
  return std::sqrt(worst);
}

void Collapser::run(CollapsePlan& plan) {
  rank_vertices();
  build();
  add_border_planes();
  lock_special();
  plan.batches.clear();
  plan.errors.clear();
  while (plan.batches.size() < options_.max_batches && vertices_left_ > options_.min_base_vertices) {
    std::vector<CollapseRecord> b;
    if (batch(b) < options_.min_batch_splits) {
      if (!b.empty()) plan.batches.push_back(std::move(b)), plan.errors.push_back(level_error());
      break;
    }
    plan.batches.push_back(std::move(b));
    plan.errors.push_back(level_error());
  }
  write_base(plan);
}

}  // namespace

void plan_collapses(const Mesh& mesh, const std::vector<uint32_t>& q, const ProgressiveOptions& options,
                    CollapsePlan& plan) {
  Collapser(mesh, q, options).run(plan);
}

}  // namespace tsm

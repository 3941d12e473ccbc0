// Keep-order (FORMAT.md §4.9): the permutation from the decoder's vertex
// and face order back to the input's, and each face's first corner, coded
// relative to the decoded mesh so that an input whose order is coherent
// (scan lines, volume sweeps, faces next to the face before) costs little.
// Vertices come first, in input order: each is a pick from the unused
// neighbours of the vertex before it (the one that continues the step from
// the vertex before that first), or an escape (a jump in decoder order).
// Faces follow, in input order: the input id of the first corner, a pick
// from the corners of the face before or a jump from its first corner; then
// the face, a pick from the unused faces at that vertex (those sharing an
// edge with the face before first); the corner at that vertex is the first.
#include "order_coding.hpp"

#include <algorithm>
#include <cmath>

#include "connectivity.hpp"
#include "range_coder.hpp"

namespace tsm {

namespace {

constexpr size_t kMaxCandidates = 16;
constexpr uint32_t kPickContexts = 5;

// Adjacency of the decoded mesh, shared by the encoder and the decoder.
struct OrderContext {
  const Mesh& m;
  std::vector<uint32_t> inc_start, inc;  // vertex -> faces using it (increasing)
  std::vector<uint32_t> nbr_start, nbr;  // vertex -> vertices on an edge with it (increasing)
  std::vector<uint8_t> face_used, vertex_used;

  explicit OrderContext(const Mesh& mesh) : m(mesh) {
    const size_t V = m.vertex_count(), F = m.face_count();
    inc_start.assign(V + 1, 0);
    for (uint32_t x : m.indices) ++inc_start[x + 1];
    for (size_t v = 0; v < V; ++v) inc_start[v + 1] += inc_start[v];
    inc.resize(m.indices.size());
    std::vector<uint32_t> at(inc_start.begin(), inc_start.end() - 1);
    for (uint32_t f = 0; f < F; ++f)
      for (uint32_t k = 0; k < m.face_size(f); ++k) inc[at[m.face(f)[k]]++] = f;
    std::vector<std::pair<uint32_t, uint32_t>> edges;
    edges.reserve(2 * m.indices.size());
    for (uint32_t f = 0; f < F; ++f) {
      const uint32_t n = m.face_size(f);
      const uint32_t* c = m.face(f);
      for (uint32_t k = 0; k < n; ++k) {
        const uint32_t a = c[k], b = c[(k + 1) % n];
        if (a == b) continue;
        edges.emplace_back(a, b);
        edges.emplace_back(b, a);
      }
    }
    std::sort(edges.begin(), edges.end());
    edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
    nbr_start.assign(V + 1, 0);
    for (const auto& e : edges) ++nbr_start[e.first + 1];
    for (size_t v = 0; v < V; ++v) nbr_start[v + 1] += nbr_start[v];
    nbr.resize(edges.size());
    for (size_t i = 0; i < edges.size(); ++i) nbr[i] = edges[i].second;
    face_used.assign(F, 0);
    vertex_used.assign(V, 0);
  }

  // The unused neighbours of `prev`; after a step from `prev2` (kNone:
  // none) the one that continues it furthest first (largest dot product of
  // the two steps, in double, then by id).
  void vertex_candidates(uint32_t prev, uint32_t prev2, std::vector<uint32_t>& out) const {
    out.clear();
    if (prev == kNone) return;
    for (uint32_t i = nbr_start[prev]; i < nbr_start[prev + 1] && out.size() < kMaxCandidates; ++i)
      if (!vertex_used[nbr[i]]) out.push_back(nbr[i]);
    if (prev2 == kNone || out.size() < 2) return;
    std::vector<std::pair<double, uint32_t>> key;
    const float* p = m.positions.data();
    for (uint32_t c : out) {
      double dot = 0;
      for (int a = 0; a < 3; ++a)
        dot += (double(p[3 * size_t{c} + a]) - double(p[3 * size_t{prev} + a])) *
               (double(p[3 * size_t{prev} + a]) - double(p[3 * size_t{prev2} + a]));
      key.emplace_back(std::isfinite(dot) ? -dot : HUGE_VAL, c);
    }
    std::sort(key.begin(), key.end());
    for (size_t i = 0; i < out.size(); ++i) out[i] = key[i].second;
  }

  // The unused faces at decoded vertex x, as (face, corner) pairs: those
  // with two or more vertices of face `prev` (kNone: none) first, then the
  // others, each group by face then corner.
  void face_candidates(uint32_t x, uint32_t prev, std::vector<std::pair<uint32_t, uint32_t>>& out) const {
    out.clear();
    std::vector<std::pair<uint32_t, uint32_t>> later;
    for (uint32_t i = inc_start[x]; i < inc_start[x + 1]; ++i) {
      const uint32_t f = inc[i];
      if (face_used[f] || (i > inc_start[x] && inc[i - 1] == f)) continue;
      const uint32_t* c = m.face(f);
      const uint32_t n = m.face_size(f);
      uint32_t shared = 0;
      if (prev != kNone) {
        const uint32_t* pc = m.face(prev);
        const uint32_t pn = m.face_size(prev);
        for (uint32_t k = 0; k < n; ++k)
          if (std::find(c, c + k, c[k]) == c + k && std::find(pc, pc + pn, c[k]) != pc + pn) ++shared;
      }
      for (uint32_t k = 0; k < n; ++k)
        if (c[k] == x) (shared >= 2 ? out : later).emplace_back(f, k);
    }
    out.insert(out.end(), later.begin(), later.end());
  }
};

struct OrderModels {
  UIntModel vertex_pick[kPickContexts], corner_pick[kPickContexts], face_pick[kPickContexts];
  SIntModel vertex_jump, corner_jump;
};

uint32_t pick_context(size_t candidates) {
  return static_cast<uint32_t>(std::min<size_t>(candidates, kPickContexts - 1));
}

// The corners of input face `prev` (input ids, kNone: none), each once.
void corner_candidates(const Mesh& input_faces_of, uint32_t prev, std::vector<uint32_t>& out) {
  out.clear();
  if (prev == kNone) return;
  const uint32_t* c = input_faces_of.face(prev);
  for (uint32_t k = 0; k < input_faces_of.face_size(prev); ++k)
    if (std::find(out.begin(), out.end(), c[k]) == out.end()) out.push_back(c[k]);
}

Status corrupt(const std::string& what) { return Status(ErrorCode::corrupt_data, "order section: " + what); }

}  // namespace

std::string encode_order(const Mesh& decoded, const std::vector<uint32_t>& vertex_from,
                         const std::vector<uint32_t>& face_from, const std::vector<uint32_t>& first_corner) {
  const size_t V = decoded.vertex_count(), F = decoded.face_count();
  std::vector<uint32_t> faces(F), rot(F), vertices(V);  // input order -> decoded
  for (uint32_t f = 0; f < F; ++f) {
    faces[face_from[f]] = f;
    const uint32_t n = decoded.face_size(f);
    rot[face_from[f]] = (n - first_corner[f] % n) % n;
  }
  for (uint32_t v = 0; v < V; ++v) vertices[vertex_from[v]] = v;
  OrderContext ctx(decoded);
  OrderModels models;
  RangeEncoder e;
  std::vector<uint32_t> cand;
  for (size_t i = 0; i < V; ++i) {
    const uint32_t v = vertices[i];
    const uint32_t prev = i ? vertices[i - 1] : kNone, prev2 = i > 1 ? vertices[i - 2] : kNone;
    ctx.vertex_candidates(prev, prev2, cand);
    const size_t at = std::find(cand.begin(), cand.end(), v) - cand.begin();
    if (!cand.empty()) models.vertex_pick[pick_context(cand.size())].encode(e, at < cand.size() ? uint32_t(at + 1) : 0);
    if (at == cand.size())
      models.vertex_jump.encode(e, static_cast<int32_t>(int64_t{v} - (prev == kNone ? 0 : int64_t{prev} + 1)));
    ctx.vertex_used[v] = 1;
  }
  // The input's faces (input ids), for the corner candidates.
  Mesh input;
  for (size_t j = 0; j < F; ++j) {
    const uint32_t f = faces[j], n = decoded.face_size(f);
    for (uint32_t k = 0; k < n; ++k) input.indices.push_back(vertex_from[decoded.face(f)[(rot[j] + k) % n]]);
    input.face_offsets.push_back(static_cast<uint32_t>(input.indices.size()));
  }
  std::vector<std::pair<uint32_t, uint32_t>> fc;
  for (size_t j = 0; j < F; ++j) {
    const uint32_t f = faces[j], x = decoded.face(f)[rot[j]], u = vertex_from[x];
    const uint32_t prev = j ? static_cast<uint32_t>(j - 1) : kNone;
    corner_candidates(input, prev, cand);
    const size_t at = std::find(cand.begin(), cand.end(), u) - cand.begin();
    if (!cand.empty()) models.corner_pick[pick_context(cand.size())].encode(e, at < cand.size() ? uint32_t(at + 1) : 0);
    if (at == cand.size())
      models.corner_jump.encode(e,
                                static_cast<int32_t>(int64_t{u} - (prev == kNone ? 0 : int64_t{input.face(prev)[0]})));
    ctx.face_candidates(x, j ? faces[j - 1] : kNone, fc);
    const size_t k = std::find(fc.begin(), fc.end(), std::make_pair(f, rot[j])) - fc.begin();
    if (fc.size() > 1) models.face_pick[pick_context(fc.size())].encode(e, static_cast<uint32_t>(k));
    ctx.face_used[f] = 1;
  }
  return e.finish();
}

Status decode_order(std::string_view payload, Mesh& mesh) {
  const size_t V = mesh.vertex_count(), F = mesh.face_count();
  OrderContext ctx(mesh);
  OrderModels models;
  RangeDecoder d(payload);
  std::vector<uint32_t> cand, faces(F), rot(F), vertices(V), input_of(V);
  for (size_t i = 0; i < V; ++i) {
    const uint32_t prev = i ? vertices[i - 1] : kNone, prev2 = i > 1 ? vertices[i - 2] : kNone;
    ctx.vertex_candidates(prev, prev2, cand);
    uint32_t pick = 0;
    if (!cand.empty()) pick = models.vertex_pick[pick_context(cand.size())].decode(d);
    if (pick > cand.size()) return corrupt("vertex " + std::to_string(i) + " picks a candidate it does not have");
    uint32_t v;
    if (pick) {
      v = cand[pick - 1];
    } else {
      const int64_t x = (prev == kNone ? 0 : int64_t{prev} + 1) + models.vertex_jump.decode(d);
      if (x < 0 || x >= static_cast<int64_t>(V) || ctx.vertex_used[static_cast<size_t>(x)])
        return corrupt("vertex " + std::to_string(i) + " is not an unused vertex of the mesh");
      v = static_cast<uint32_t>(x);
    }
    vertices[i] = v;
    input_of[v] = static_cast<uint32_t>(i);
    ctx.vertex_used[v] = 1;
    if (d.overrun() > RangeDecoder::kMaxOverrun) return corrupt("cut off");
  }
  Mesh input;  // the faces decoded so far, on input ids
  input.indices.reserve(mesh.indices.size());
  input.face_offsets.reserve(F + 1);
  std::vector<std::pair<uint32_t, uint32_t>> fc;
  for (size_t j = 0; j < F; ++j) {
    const uint32_t prev = j ? static_cast<uint32_t>(j - 1) : kNone;
    corner_candidates(input, prev, cand);
    uint32_t pick = 0;
    if (!cand.empty()) pick = models.corner_pick[pick_context(cand.size())].decode(d);
    if (pick > cand.size()) return corrupt("face " + std::to_string(j) + " picks a corner it does not have");
    uint32_t u;
    if (pick) {
      u = cand[pick - 1];
    } else {
      const int64_t x = (prev == kNone ? 0 : int64_t{input.face(prev)[0]}) + models.corner_jump.decode(d);
      if (x < 0 || x >= static_cast<int64_t>(V))
        return corrupt("face " + std::to_string(j) + ": first corner out of range");
      u = static_cast<uint32_t>(x);
    }
    ctx.face_candidates(vertices[u], j ? faces[j - 1] : kNone, fc);
    if (fc.empty()) return corrupt("face " + std::to_string(j) + ": no unused face at its first corner");
    uint32_t k = 0;
    if (fc.size() > 1) k = models.face_pick[pick_context(fc.size())].decode(d);
    if (k >= fc.size()) return corrupt("face " + std::to_string(j) + " picks a face it does not have");
    const uint32_t f = fc[k].first, n = mesh.face_size(f);
    faces[j] = f;
    rot[j] = fc[k].second;
    ctx.face_used[f] = 1;
    for (uint32_t c = 0; c < n; ++c) input.indices.push_back(input_of[mesh.face(f)[(rot[j] + c) % n]]);
    input.face_offsets.push_back(static_cast<uint32_t>(input.indices.size()));
    if (d.overrun() > RangeDecoder::kMaxOverrun) return corrupt("cut off");
  }
  // Every face and vertex was taken once: both are permutations.
  Mesh out;
  out.metadata = std::move(mesh.metadata);
  out.positions.resize(3 * V);
  for (size_t i = 0; i < V; ++i)
    for (int a = 0; a < 3; ++a) out.positions[3 * i + a] = mesh.positions[3 * size_t{vertices[i]} + a];
  out.indices = std::move(input.indices);
  out.face_offsets = std::move(input.face_offsets);
  for (Attribute& a : mesh.attributes) {
    Attribute b = a;
    const size_t c = a.components;
    if (a.domain == AttributeDomain::vertex && a.values.size() == c * V) {
      for (size_t i = 0; i < V; ++i)
        std::copy_n(a.values.begin() + static_cast<std::ptrdiff_t>(c * vertices[i]), c,
                    b.values.begin() + static_cast<std::ptrdiff_t>(c * i));
    } else if (a.domain == AttributeDomain::face && a.values.size() == c * F) {
      for (size_t j = 0; j < F; ++j)
        std::copy_n(a.values.begin() + static_cast<std::ptrdiff_t>(c * faces[j]), c,
                    b.values.begin() + static_cast<std::ptrdiff_t>(c * j));
    } else if (a.domain == AttributeDomain::corner && a.indices.size() == mesh.indices.size()) {
      b.indices.clear();
      for (size_t j = 0; j < F; ++j) {
        const uint32_t f = faces[j], n = mesh.face_size(f);
        for (uint32_t k = 0; k < n; ++k) b.indices.push_back(a.indices[mesh.face_offsets[f] + (rot[j] + k) % n]);
      }
    }
    out.attributes.push_back(std::move(b));
  }
  mesh = std::move(out);
  return Status::Ok();
}

}  // namespace tsm

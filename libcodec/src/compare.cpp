// The test oracle (not a step of the method; it checks the method's promise of
// an exact round trip, design notes §5 "Exact round trip"): two meshes are
// equal when their vertex and face counts agree and the multisets of oriented
// faces agree up to vertex permutation, face permutation and rotation of each
// face's corner list, positions compared on the quantization grid.
//
// Vertices are matched by canonical labels: a label starts as the vertex's
// quantized position and is refined a few rounds by the oriented faces around
// it (Weisfeiler-Lehman style), so coincident vertices with different
// neighbourhoods are told apart. Equal label multisets of vertices and faces
// is the equality test.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <sstream>

#include "tsm/compare.hpp"

#include "attributes.hpp"

namespace tsm {


namespace {

uint64_t mix(uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}
uint64_t combine(uint64_t h, uint64_t v) { return mix(h ^ mix(v)); }

struct Labelled {
  std::vector<uint64_t> label;        // per vertex
  std::vector<int64_t> grid;          // 3 per vertex (bits > 0) or float bits
};

Labelled initial_labels(const Mesh& m, const Grid& grid) {
  Labelled out;
  const size_t nv = m.vertex_count();
  out.label.resize(nv);
  out.grid.resize(3 * nv);
  for (size_t v = 0; v < nv; ++v) {
    uint64_t h = 0x1234567;
    for (int a = 0; a < 3; ++a) {
      float x = m.positions[3 * v + static_cast<size_t>(a)];
      int64_t q;
      if (grid.bits <= 0) {
        uint32_t b;
        std::memcpy(&b, &x, 4);
        q = b;
      } else {
        q = grid.quantize(x, a);
      }
      out.grid[3 * v + static_cast<size_t>(a)] = q;
      h = combine(h, static_cast<uint64_t>(q));
    }
    out.label[v] = h;
  }
  return out;
}

// Per-vertex list of (face, corner) incidences.
struct Incidence {
  std::vector<uint32_t> offset, face, corner;
};

Incidence incidences(const Mesh& m) {
  Incidence inc;
  const size_t nv = m.vertex_count();
  inc.offset.assign(nv + 1, 0);
  for (uint32_t v : m.indices) inc.offset[v + 1]++;
  for (size_t v = 0; v < nv; ++v) inc.offset[v + 1] += inc.offset[v];
  inc.face.resize(m.indices.size());
  inc.corner.resize(m.indices.size());
  std::vector<uint32_t> fill(inc.offset.begin(), inc.offset.end() - 1);
  for (size_t f = 0; f < m.face_count(); ++f)
    for (uint32_t c = m.face_offsets[f]; c < m.face_offsets[f + 1]; ++c) {
      uint32_t v = m.indices[c];
      inc.face[fill[v]] = static_cast<uint32_t>(f);
      inc.corner[fill[v]] = c - m.face_offsets[f];
      fill[v]++;
    }
  return inc;
}

// One refinement round: a vertex's new label hashes its old label with the
// sorted signatures of its incident faces, each read from the vertex onward in
// the face's orientation.
std::vector<uint64_t> refine(const Mesh& m, const Incidence& inc, const std::vector<uint64_t>& label) {
  const size_t nv = m.vertex_count();
  std::vector<uint64_t> out(nv);
  std::vector<uint64_t> sig;
  for (size_t v = 0; v < nv; ++v) {
    sig.clear();
    for (uint32_t k = inc.offset[v]; k < inc.offset[v + 1]; ++k) {
      const uint32_t* c = m.face(inc.face[k]);
      uint32_t n = m.face_size(inc.face[k]);
      uint64_t h = n;
      for (uint32_t i = 1; i < n; ++i) h = combine(h, label[c[(inc.corner[k] + i) % n]]);
      sig.push_back(h);
    }
    std::sort(sig.begin(), sig.end());
    uint64_t h = label[v];
    for (uint64_t s : sig) h = combine(h, s);
    out[v] = h;
  }
  return out;
}

size_t distinct(std::vector<uint64_t> v) {
  std::sort(v.begin(), v.end());
  return static_cast<size_t>(std::unique(v.begin(), v.end()) - v.begin());
}

// Attribute keys (the integers the codec codes a value as, on the original
// mesh's quantization): per vertex, per face and per corner, hashed. A
// corner's key also holds how many corners share its value (so merged or
// split seams show), and `unused` lists the values no corner uses.
struct AttributeKeys {
  std::vector<uint64_t> vertex, face, corner, unused;
};

AttributeKeys attribute_keys(const Mesh& m, const std::vector<AttributeHeader>& headers) {
  AttributeKeys k;
  k.vertex.assign(m.vertex_count(), 0);
  k.face.assign(m.face_count(), 0);
  k.corner.assign(m.corner_count(), 0);
  int32_t key[4];
  for (size_t i = 0; i < headers.size() && i < m.attributes.size(); ++i) {
    const AttributeHeader& h = headers[i];
    const Attribute& a = m.attributes[i];
    const uint32_t n = attribute_key_size(h);
    auto value_hash = [&](size_t j) {
      attribute_key(h, &a.values[a.components * j], key);
      uint64_t x = 0x51ed27 + i;
      for (uint32_t c = 0; c < n; ++c) x = combine(x, static_cast<uint64_t>(static_cast<int64_t>(key[c])));
      return x;
    };
    if (a.domain == AttributeDomain::vertex) {
      for (size_t v = 0; v < m.vertex_count(); ++v) k.vertex[v] = combine(k.vertex[v], value_hash(v));
    } else if (a.domain == AttributeDomain::face) {
      for (size_t f = 0; f < m.face_count(); ++f) k.face[f] = combine(k.face[f], value_hash(f));
    } else {
      std::vector<uint32_t> uses(a.value_count(), 0);
      for (uint32_t x : a.indices) uses[x]++;
      for (size_t c = 0; c < m.corner_count(); ++c)
        k.corner[c] = combine(k.corner[c], combine(value_hash(a.indices[c]), uses[a.indices[c]]));
      for (size_t j = 0; j < a.value_count(); ++j)
        if (!uses[j]) k.unused.push_back(value_hash(j));
    }
  }
  std::sort(k.unused.begin(), k.unused.end());
  return k;
}

// Faces as label sequences (each corner's vertex label with its corner
// attribute key, then the face's attribute key) rotated to their
// lexicographically smallest rotation (orientation kept), sorted.
std::vector<std::vector<uint64_t>> canonical_faces(const Mesh& m, const std::vector<uint64_t>& label,
                                                   const AttributeKeys& keys) {
  std::vector<std::vector<uint64_t>> faces(m.face_count());
  std::vector<uint64_t> seq, best;
  for (size_t f = 0; f < m.face_count(); ++f) {
    const uint32_t* c = m.face(f);
    const uint32_t n = m.face_size(f), at = m.face_offsets[f];
    best.clear();
    for (uint32_t r = 0; r < n; ++r) {
      seq.clear();
      for (uint32_t i = 0; i < n; ++i) seq.push_back(combine(label[c[(r + i) % n]], keys.corner[at + (r + i) % n]));
      if (best.empty() || seq < best) best = seq;
    }
    best.push_back(keys.face[f]);
    faces[f] = best;
  }
  std::sort(faces.begin(), faces.end());
  return faces;
}

std::string describe_vertex(const Labelled& l, size_t v, const Grid& grid) {
  std::ostringstream s;
  s << (grid.bits > 0 ? "grid (" : "float bits (") << l.grid[3 * v] << ", " << l.grid[3 * v + 1] << ", "
    << l.grid[3 * v + 2] << ")";
  return s.str();
}

}  // namespace

CompareResult compare_meshes(const Mesh& original, const Mesh& decoded, int bits,
                             const AttributeQuantization& attribute_bits) {
  CompareResult r;
  std::string why;
  if (!original.valid(&why)) { r.difference = "original mesh is invalid: " + why; return r; }
  if (!decoded.valid(&why)) { r.difference = "decoded mesh is invalid: " + why; return r; }
  if (original.vertex_count() != decoded.vertex_count()) {
    r.difference = "vertex count " + std::to_string(decoded.vertex_count()) + ", expected " +
                   std::to_string(original.vertex_count());
    return r;
  }
  if (original.face_count() != decoded.face_count()) {
    r.difference = "face count " + std::to_string(decoded.face_count()) + ", expected " +
                   std::to_string(original.face_count());
    return r;
  }
  if (original.corner_count() != decoded.corner_count()) {
    r.difference = "corner count " + std::to_string(decoded.corner_count()) + ", expected " +
                   std::to_string(original.corner_count());
    return r;
  }
  if (original.attributes.size() != decoded.attributes.size()) {
    r.difference = std::to_string(decoded.attributes.size()) + " attributes, expected " +
                   std::to_string(original.attributes.size());
    return r;
  }
  for (size_t i = 0; i < original.attributes.size(); ++i) {
    if (!same_description(original.attributes[i], decoded.attributes[i])) {
      r.difference = "attribute " + std::to_string(i) + " ('" + original.attributes[i].name +
                     "') is described differently in the decoded mesh";
      return r;
    }
  }
  if (original.metadata.size() != decoded.metadata.size()) {
    r.difference = std::to_string(decoded.metadata.size()) + " metadata entries, expected " +
                   std::to_string(original.metadata.size());
    return r;
  }
  for (size_t i = 0; i < original.metadata.size(); ++i) {
    const MetadataEntry &x = original.metadata[i], &y = decoded.metadata[i];
    if (x.key != y.key || x.value != y.value) {
      r.difference = "metadata entry " + std::to_string(i) + " ('" + x.key + "') differs in the decoded mesh";
      return r;
    }
  }
  const std::vector<AttributeHeader> headers = attribute_headers(original, attribute_bits);
  const AttributeKeys ka = attribute_keys(original, headers), kb = attribute_keys(decoded, headers);
  if (ka.unused != kb.unused) {
    r.difference = "the values no corner uses differ (" + std::to_string(kb.unused.size()) + ", expected " +
                   std::to_string(ka.unused.size()) + ")";
    return r;
  }
  const Grid grid = Grid::for_mesh(original, bits);
  Labelled a = initial_labels(original, grid), b = initial_labels(decoded, grid);
  if (!original.attributes.empty()) {
    std::vector<uint64_t> xa = ka.vertex, xb = kb.vertex;
    for (size_t v = 0; v < a.label.size(); ++v) a.label[v] = combine(a.label[v], ka.vertex[v]);
    for (size_t v = 0; v < b.label.size(); ++v) b.label[v] = combine(b.label[v], kb.vertex[v]);
    std::sort(xa.begin(), xa.end());
    std::sort(xb.begin(), xb.end());
    if (xa != xb) {
      r.difference = "vertex attribute values differ";
      return r;
    }
  }

  // Positions, and the largest error (matched by sorted grid position).
  {
    const size_t nv = original.vertex_count();
    std::vector<uint32_t> ia(nv), ib(nv);
    for (uint32_t i = 0; i < nv; ++i) ia[i] = ib[i] = i;
    auto by_grid = [](const Labelled& l) {
      return [&l](uint32_t x, uint32_t y) {
        return std::lexicographical_compare(&l.grid[3 * x], &l.grid[3 * x + 3], &l.grid[3 * y], &l.grid[3 * y + 3]);
      };
    };
    std::sort(ia.begin(), ia.end(), by_grid(a));
    std::sort(ib.begin(), ib.end(), by_grid(b));
    for (size_t i = 0; i < nv; ++i) {
      if (!std::equal(&a.grid[3 * ia[i]], &a.grid[3 * ia[i] + 3], &b.grid[3 * ib[i]])) {
        r.difference = "vertex positions differ: original vertex " + std::to_string(ia[i]) + " at " +
                       describe_vertex(a, ia[i], grid) + ", decoded has " + describe_vertex(b, ib[i], grid) +
                       " in its place";
        return r;
      }
      if (grid.step > 0)
        for (int ax = 0; ax < 3; ++ax) {
          double e = std::fabs(static_cast<double>(decoded.positions[3 * ib[i] + ax]) -
                               static_cast<double>(original.positions[3 * ia[i] + ax])) / grid.step;
          if (std::isfinite(e)) r.max_position_error = std::max(r.max_position_error, e);
        }
    }
  }

  // Faces with positional labels, then refined labels.
  Incidence inc_a = incidences(original), inc_b = incidences(decoded);
  std::vector<uint64_t> la = a.label, lb = b.label;
  size_t classes = distinct(la);
  bool stable = false;
  for (int round = 0; round < 8; ++round) {
    if (canonical_faces(original, la, ka) != canonical_faces(decoded, lb, kb)) {
      r.difference = round == 0 ? "faces differ (some oriented face of the original, by corner positions, is not in "
                                  "the decoded mesh, or is there a different number of times)"
                                : "faces differ around coincident vertices (refinement round " +
                                      std::to_string(round) + ")";
      return r;
    }
    std::vector<uint64_t> sa = la, sb = lb;
    std::sort(sa.begin(), sa.end());
    std::sort(sb.begin(), sb.end());
    if (sa != sb) {
      r.difference = "vertex neighbourhoods differ (refinement round " + std::to_string(round) + ")";
      return r;
    }
    // Done when every vertex is told apart, or when the last refinement split
    // no class (its labels were still compared above).
    if (classes == original.vertex_count() || stable) break;
    la = refine(original, inc_a, la);
    lb = refine(decoded, inc_b, lb);
    size_t next = distinct(la);
    stable = next == classes;
    classes = next;
  }
  r.equal = true;
  return r;
}

}  // namespace tsm

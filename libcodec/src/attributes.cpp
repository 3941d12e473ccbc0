// Attributes: normals, colours, texture coordinates and generic values per
// vertex, face or corner, coded after the connectivity and the geometry, in
// the order the decoder rebuilds them (seed 004 §5, "Kodierung der Photometrie
// Daten": colours, normals and texture coordinates follow the vertex tree, and
// per-corner values are split where they are discontinuous; design notes §7).
//
// Vertex values follow the output vertex order (the vertex tree's pre-order,
// so consecutive values are usually neighbours); normals may instead be
// predicted from the decoded geometry (the area-weighted normal of the faces
// around the vertex). Face values follow the decoded face order. Corner
// values keep their own value list, as OBJ's vt/vn and glTF seams do: per
// corner the stream says whether it reuses a value already met at the same
// vertex (smooth), starts a new one (a seam or crease), or reuses a value from
// elsewhere; values no corner uses are kept at the end. Quantization: integer
// types exactly, floats on a grid over the attribute's bounding box, normals
// octahedrally. Residuals are range coded (FORMAT.md §8.12).
#include "attributes.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "byte_io.hpp"
#include "connectivity.hpp"
#include "range_coder.hpp"

namespace tsm {

namespace {

Status corrupt(const std::string& what) { return Status(ErrorCode::corrupt_data, "attributes: " + what); }

constexpr int kMaxAttributes = 64;

// Octahedral mapping of a direction onto [0, 2^bits - 1]^2.
void oct_encode(double x, double y, double z, int bits, int32_t out[2]) {
  const double s = std::fabs(x) + std::fabs(y) + std::fabs(z);
  if (!(s > 0)) {
    x = 0;
    y = 0;
    z = 1;
  } else {
    x /= s;
    y /= s;
    z /= s;
  }
  if (z < 0) {
    const double ox = x, oy = y;
    x = (1 - std::fabs(oy)) * (ox >= 0 ? 1 : -1);
    y = (1 - std::fabs(ox)) * (oy >= 0 ? 1 : -1);
  }
  const double m = std::ldexp(1.0, bits) - 1;
  int32_t u = static_cast<int32_t>(std::floor((x * 0.5 + 0.5) * m + 0.5));
  int32_t v = static_cast<int32_t>(std::floor((y * 0.5 + 0.5) * m + 0.5));
  // The square's border is folded onto itself: (u, 0) and (m - u, 0) are one
  // direction, so are (0, v) and (0, m - v) (and the corners are (0, 0, -1)).
  // One representative, so that a decoded normal keys as it was coded.
  const int32_t top = static_cast<int32_t>(m);
  if (v == 0 || v == top) u = std::min(u, top - u);
  if (u == 0 || u == top) v = std::min(v, top - v);
  out[0] = u;
  out[1] = v;
}

void oct_decode(int32_t u, int32_t v, int bits, float out[3]) {
  const double m = std::ldexp(1.0, bits) - 1;
  double x = u / m * 2 - 1, y = v / m * 2 - 1;
  const double z = 1 - std::fabs(x) - std::fabs(y);
  if (z < 0) {
    const double ox = x, oy = y;
    x = (1 - std::fabs(oy)) * (ox >= 0 ? 1 : -1);
    y = (1 - std::fabs(ox)) * (oy >= 0 ? 1 : -1);
  }
  const double n = std::sqrt(x * x + y * y + z * z);
  out[0] = static_cast<float>(x / n);
  out[1] = static_cast<float>(y / n);
  out[2] = static_cast<float>(z / n);
}

double grid_step(const AttributeHeader& h) {
  return h.extent > 0 ? h.extent / (std::ldexp(1.0, h.bits) - 1.0) : 0.0;
}

// Integers per value: 2 for octahedral, else the components.
uint32_t int_components(const AttributeHeader& h) {
  return h.quant == AttributeQuant::octahedral ? 2 : h.components;
}

void to_ints(const AttributeHeader& h, const float* v, int32_t* out) {
  if (h.quant == AttributeQuant::octahedral) {
    oct_encode(v[0], v[1], v[2], h.bits, out);
    return;
  }
  for (uint32_t c = 0; c < h.components; ++c) {
    if (h.quant == AttributeQuant::exact) {
      out[c] = static_cast<int32_t>(v[c]);
    } else {
      const double step = grid_step(h);
      const int64_t top = (int64_t{1} << h.bits) - 1;
      int64_t q = step > 0 ? static_cast<int64_t>(std::floor((static_cast<double>(v[c]) - h.origin[c]) / step + 0.5)) : 0;
      out[c] = static_cast<int32_t>(std::clamp<int64_t>(q, 0, top));
    }
  }
}

void from_ints(const AttributeHeader& h, const int32_t* x, float* out) {
  if (h.quant == AttributeQuant::octahedral) {
    oct_decode(x[0], x[1], h.bits, out);
    return;
  }
  for (uint32_t c = 0; c < h.components; ++c)
    out[c] = h.quant == AttributeQuant::exact ? static_cast<float>(x[c]) : attribute_grid_value(h, static_cast<int>(c), x[c]);
}

// The integer range of one component (decoder checks).
bool in_range(const AttributeHeader& h, int64_t x) {
  if (h.quant == AttributeQuant::exact) return x >= -(int64_t{1} << 30) && x <= (int64_t{1} << 30);
  return x >= 0 && x < (int64_t{1} << h.bits);
}

struct Models {
  SIntModelT<4> res[4][2];
  UIntModel symbol[6];
  UIntModel far;
  UIntModel unused;
};

// Residual coding of one value against a prediction; ctx per component: was
// the previous residual zero.
template <class Coder>
struct ValueCoder {
  Coder& io;
  Models m;
  int last_zero[4] = {1, 1, 1, 1};
  bool value(const AttributeHeader& h, const int32_t* pred, int32_t* x) {
    const uint32_t n = int_components(h);
    for (uint32_t c = 0; c < n; ++c) {
      int32_t r = io.sint(m.res[c][last_zero[c]], static_cast<int64_t>(x[c]) - pred[c]);
      const int64_t v = static_cast<int64_t>(pred[c]) + r;
      if (!in_range(h, v)) return false;
      x[c] = static_cast<int32_t>(v);
      last_zero[c] = r == 0;
    }
    return true;
  }
};

struct Enc {
  RangeEncoder e;
  int32_t sint(SIntModelT<4>& m, int64_t v) {
    m.encode(e, static_cast<int32_t>(v));
    return static_cast<int32_t>(v);
  }
  uint32_t uint(UIntModel& m, uint32_t v) {
    m.encode(e, v);
    return v;
  }
  static constexpr bool kEncoder = true;
};

struct Dec {
  RangeDecoder d;
  int32_t sint(SIntModelT<4>& m, int64_t) { return m.decode(d); }
  uint32_t uint(UIntModel& m, uint32_t) { return m.decode(d); }
  static constexpr bool kEncoder = false;
};

// Area-weighted normals of the own vertices from the faces whose corners
// are all own (fans for polygons), as octahedral indices; has[r] = 0 where
// the sum is zero.
void geometry_normals(const Mesh& faces, const std::vector<uint32_t>& rank, const std::vector<uint32_t>& q,
                      int bits, std::vector<int32_t>& oct, std::vector<uint8_t>& has) {
  const size_t n = q.size() / 3;
  std::vector<double> sum(3 * n, 0.0);
  for (size_t f = 0; f < faces.face_count(); ++f) {
    const uint32_t k = faces.face_size(f);
    const uint32_t* c = faces.face(f);
    bool own = k >= 3;
    for (uint32_t i = 0; i < k && own; ++i) own = rank[c[i]] != kNone;
    if (!own) continue;
    const uint32_t* p0 = &q[3 * static_cast<size_t>(rank[c[0]])];
    double nx = 0, ny = 0, nz = 0;
    for (uint32_t i = 1; i + 1 < k; ++i) {
      const uint32_t* p1 = &q[3 * static_cast<size_t>(rank[c[i]])];
      const uint32_t* p2 = &q[3 * static_cast<size_t>(rank[c[i + 1]])];
      const double a[3] = {double(p1[0]) - p0[0], double(p1[1]) - p0[1], double(p1[2]) - p0[2]};
      const double b[3] = {double(p2[0]) - p0[0], double(p2[1]) - p0[1], double(p2[2]) - p0[2]};
      nx += a[1] * b[2] - a[2] * b[1];
      ny += a[2] * b[0] - a[0] * b[2];
      nz += a[0] * b[1] - a[1] * b[0];
    }
    for (uint32_t i = 0; i < k; ++i) {
      double* s = &sum[3 * static_cast<size_t>(rank[c[i]])];
      s[0] += nx;
      s[1] += ny;
      s[2] += nz;
    }
  }
  oct.assign(2 * n, 0);
  has.assign(n, 0);
  for (size_t r = 0; r < n; ++r) {
    const double* s = &sum[3 * r];
    if (s[0] == 0 && s[1] == 0 && s[2] == 0) continue;
    has[r] = 1;
    oct_encode(s[0], s[1], s[2], bits, &oct[2 * r]);
  }
}

void write_header(ByteWriter& w, const AttributeHeader& h) {
  w.varint(h.name.size());
  w.bytes(h.name);
  w.u8(static_cast<uint8_t>(h.kind));
  w.u8(static_cast<uint8_t>(h.domain));
  w.u8(static_cast<uint8_t>(h.type));
  w.u8(static_cast<uint8_t>(h.components));
  w.u8(static_cast<uint8_t>(h.quant));
  w.u8(static_cast<uint8_t>(h.bits));
  if (h.quant == AttributeQuant::grid) {
    for (uint32_t c = 0; c < h.components; ++c) w.f32(h.origin[c]);
    w.f64(h.extent);
  }
}

Status read_header(ByteReader& r, AttributeHeader& h) {
  uint64_t len = 0;
  std::string_view name;
  uint8_t kind, domain, type, comps, quant, bits;
  if (!r.varint(len) || len > 1024 || !r.bytes(static_cast<size_t>(len), name) || !r.u8(kind) || !r.u8(domain) ||
      !r.u8(type) || !r.u8(comps) || !r.u8(quant) || !r.u8(bits))
    return corrupt("truncated attribute header");
  h.name.assign(name);
  if (kind > 3 || domain > 2 || type > 3 || comps < 1 || comps > 4 || quant > 2) return corrupt("bad attribute header");
  h.kind = static_cast<AttributeKind>(kind);
  h.domain = static_cast<AttributeDomain>(domain);
  h.type = static_cast<AttributeType>(type);
  h.components = comps;
  h.quant = static_cast<AttributeQuant>(quant);
  h.bits = bits;
  if (h.quant != AttributeQuant::exact && (bits < 1 || bits > 24)) return corrupt("bad quantization bits");
  if (h.quant == AttributeQuant::octahedral && comps != 3) return corrupt("octahedral needs 3 components");
  if (h.kind == AttributeKind::normal && comps != 3) return corrupt("a normal has 3 components");
  if (h.kind == AttributeKind::texcoord && comps != 2) return corrupt("a texture coordinate has 2 components");
  if (h.kind == AttributeKind::color && comps < 3) return corrupt("a colour has 3 or 4 components");
  if (h.quant == AttributeQuant::grid) {
    for (uint32_t c = 0; c < comps; ++c)
      if (!r.f32(h.origin[c]) || !std::isfinite(h.origin[c])) return corrupt("bad grid origin");
    if (!r.f64(h.extent) || !std::isfinite(h.extent) || h.extent < 0 || h.extent > 6.9e38)
      return corrupt("bad grid extent");
  }
  return Status::Ok();
}

// The walk shared by the encoder (Coder = Enc, values known) and the decoder
// (Coder = Dec): vertex, face and corner values of one attribute.
template <class Coder>
struct AttributeWalk {
  const AttributeHeader& h;
  ValueCoder<Coder>& vc;
  Coder& io;
  const Mesh& faces;                  // part output faces
  const std::vector<uint32_t>& rank;  // per part vertex: own rank or kNone
  const std::vector<int32_t>* gnormal;  // per own rank: geometry normal (octahedral)
  const std::vector<uint8_t>* ghas;

  // Vertex values, own vertices in output order. `x`: 'ints' per own vertex.
  bool vertices(int predictor, std::vector<int32_t>& x) {
    const uint32_t n = int_components(h);
    int32_t prev[4] = {0, 0, 0, 0};
    const size_t count = x.size() / n;
    for (size_t r = 0; r < count; ++r) {
      int32_t pred[4] = {prev[0], prev[1], prev[2], prev[3]};
      if (predictor == 1 && (*ghas)[r]) {
        pred[0] = (*gnormal)[2 * r];
        pred[1] = (*gnormal)[2 * r + 1];
      }
      if (!vc.value(h, pred, &x[n * r])) return false;
      std::copy(&x[n * r], &x[n * r] + n, prev);
    }
    return true;
  }
  bool face_values(std::vector<int32_t>& x) {
    const uint32_t n = int_components(h);
    int32_t prev[4] = {0, 0, 0, 0};
    for (size_t f = 0; f < x.size() / n; ++f) {
      if (!vc.value(h, prev, &x[n * f])) return false;
      std::copy(&x[n * f], &x[n * f] + n, prev);
    }
    return true;
  }
  // Corner values. Encoder: `in_value` per output corner (the input value
  // index), `in_ints` the input values; out: the part's value list in
  // first-use order (then the unused ones), `index` per corner.
  // max_unused: a bound from the stream's size (each value costs at least
  // one coded decision).
  bool corners(const std::vector<uint32_t>& in_value, const std::vector<int32_t>& in_ints, size_t in_count,
               uint64_t max_unused, std::vector<int32_t>& values, std::vector<uint32_t>& index) {
    const uint32_t n = int_components(h);
    const size_t K = faces.indices.size();
    const size_t V = rank.size();
    std::vector<uint32_t> cand(4 * V, kNone);
    std::vector<uint8_t> ncand(V, 0);
    std::vector<uint32_t> out_of(Coder::kEncoder ? in_count : 0, kNone);  // encoder: input value -> output id
    std::vector<uint32_t> in_of;                                          // encoder: output id -> input value
    index.assign(K, 0);
    values.clear();
    int32_t prev[4] = {0, 0, 0, 0};
    for (size_t k = 0; k < K; ++k) {
      const uint32_t w = faces.indices[k];
      const uint32_t nc = ncand[w];
      uint32_t s = 0, id = kNone;
      if constexpr (Coder::kEncoder) {
        id = out_of[in_value[k]];
        if (id == kNone) {
          s = nc;
        } else {
          s = nc + 1;
          for (uint32_t i = 0; i < nc; ++i)
            if (cand[4 * w + i] == id) s = i;
        }
      }
      s = io.uint(vc.m.symbol[std::min<uint32_t>(nc, 5)], s);
      const uint32_t have = static_cast<uint32_t>(values.size() / n);
      if (s < nc) {
        id = cand[4 * w + s];
      } else if (s == nc) {  // a new value
        id = have;
        values.resize(values.size() + n);
        int32_t* x = &values[n * static_cast<size_t>(id)];
        if constexpr (Coder::kEncoder) {
          std::copy(&in_ints[n * static_cast<size_t>(in_value[k])], &in_ints[n * static_cast<size_t>(in_value[k])] + n, x);
          out_of[in_value[k]] = id;
          in_of.push_back(in_value[k]);
        }
        int32_t pred[4] = {prev[0], prev[1], prev[2], prev[3]};
        const uint32_t r = rank[w];
        if (gnormal && r != kNone && (*ghas)[r]) {
          pred[0] = (*gnormal)[2 * r];
          pred[1] = (*gnormal)[2 * r + 1];
        }
        if (!vc.value(h, pred, x)) return false;
        std::copy(x, x + n, prev);
      } else if (s == nc + 1) {  // a value met elsewhere
        uint32_t back = 0;
        if constexpr (Coder::kEncoder) back = have - 1 - id;
        back = io.uint(vc.m.far, back);
        if (back >= have) return false;
        id = have - 1 - back;
      } else {
        return false;
      }
      index[k] = id;
      if (s >= nc && nc < 4) {
        bool seen = false;
        for (uint32_t i = 0; i < nc; ++i) seen = seen || cand[4 * w + i] == id;
        if (!seen) {
          cand[4 * w + nc] = id;
          ncand[w] = static_cast<uint8_t>(nc + 1);
        }
      }
    }
    // The values no corner uses, in input order.
    uint32_t unused = 0;
    if constexpr (Coder::kEncoder) unused = static_cast<uint32_t>(in_count - in_of.size());
    unused = io.uint(vc.m.unused, unused);
    if (unused == 0xFFFFFFFFu || unused > max_unused) return false;
    size_t next_in = 0;
    for (uint32_t u = 0; u < unused; ++u) {
      const size_t at = values.size();
      values.resize(at + n);
      if constexpr (Coder::kEncoder) {
        while (out_of[next_in] != kNone) ++next_in;
        std::copy(&in_ints[n * next_in], &in_ints[n * next_in] + n, &values[at]);
        ++next_in;
      }
      if (!vc.value(h, prev, &values[at])) return false;
      std::copy(&values[at], &values[at] + n, prev);
    }
    return true;
  }
};

}  // namespace

uint32_t attribute_key_size(const AttributeHeader& h) { return int_components(h); }
void attribute_key(const AttributeHeader& h, const float* value, int32_t* out) { to_ints(h, value, out); }

Attribute described_like(const Attribute& a) {
  Attribute b;
  b.name = a.name;
  b.kind = a.kind;
  b.domain = a.domain;
  b.type = a.type;
  b.components = a.components;
  return b;
}

bool same_description(const Attribute& a, const Attribute& b) {
  return a.name == b.name && a.kind == b.kind && a.domain == b.domain && a.type == b.type &&
         a.components == b.components;
}

float attribute_grid_value(const AttributeHeader& h, int c, int64_t x) {
  const double v = static_cast<double>(h.origin[c]) + static_cast<double>(x) * grid_step(h);
  constexpr double kMax = static_cast<double>(std::numeric_limits<float>::max());
  return static_cast<float>(v > kMax ? kMax : v < -kMax ? -kMax : v);
}

std::vector<AttributeHeader> attribute_headers(const Mesh& mesh, const AttributeBits& bits) {
  std::vector<AttributeHeader> out;
  for (const Attribute& a : mesh.attributes) {
    AttributeHeader h;
    h.name = a.name;
    h.kind = a.kind;
    h.domain = a.domain;
    h.type = a.type;
    h.components = a.components;
    if (a.type != AttributeType::f32) {
      h.quant = AttributeQuant::exact;
    } else if (a.kind == AttributeKind::normal) {
      h.quant = AttributeQuant::octahedral;
      h.bits = bits.normal;
    } else {
      h.quant = AttributeQuant::grid;
      h.bits = a.kind == AttributeKind::texcoord ? bits.texcoord
               : a.kind == AttributeKind::color  ? bits.color
                                                 : bits.generic;
      float mn[4], mx[4];
      for (uint32_t c = 0; c < a.components; ++c) mn[c] = mx[c] = a.values.empty() ? 0.0f : a.values[c];
      for (size_t i = 0; i < a.values.size(); ++i) {
        const uint32_t c = static_cast<uint32_t>(i % a.components);
        mn[c] = std::min(mn[c], a.values[i]);
        mx[c] = std::max(mx[c], a.values[i]);
      }
      for (uint32_t c = 0; c < a.components; ++c) {
        h.origin[c] = mn[c];
        h.extent = std::max(h.extent, static_cast<double>(mx[c]) - static_cast<double>(mn[c]));
      }
    }
    out.push_back(h);
  }
  return out;
}

Status encode_attributes(const std::vector<AttributeHeader>& headers, const AttributeInput& in, std::string& out) {
  out.clear();
  if (headers.empty()) return Status::Ok();
  const Mesh& part = *in.part;
  const Mesh& faces = *in.faces;
  const std::vector<uint32_t>& order = *in.order;
  const size_t V = order.size();
  std::vector<uint32_t> rank(V, kNone);
  uint32_t own = 0;
  for (size_t v = 0; v < V; ++v)
    if (!in.is_ref || in.is_ref->empty() || !(*in.is_ref)[v]) rank[v] = own++;
  // Output faces -> input faces and the rotation of their corners.
  std::vector<uint32_t> face_of(faces.face_count(), kNone), shift(faces.face_count(), 0);
  bool need_faces = false;
  for (const AttributeHeader& h : headers) need_faces = need_faces || h.domain != AttributeDomain::vertex;
  if (need_faces) {
    std::vector<uint32_t> out_id(part.vertex_count(), kNone);
    for (size_t v = 0; v < V; ++v) out_id[order[v]] = static_cast<uint32_t>(v);
    // Key of a face: its corner cycle (output ids) from its smallest rotation.
    auto key = [](const uint32_t* c, uint32_t k, uint32_t& best) {
      best = 0;
      for (uint32_t r = 1; r < k; ++r)
        for (uint32_t i = 0; i < k; ++i) {
          const uint32_t a = c[(r + i) % k], b = c[(best + i) % k];
          if (a != b) {
            if (a < b) best = r;
            break;
          }
        }
      std::vector<uint32_t> cycle(k);
      for (uint32_t i = 0; i < k; ++i) cycle[i] = c[(best + i) % k];
      return cycle;
    };
    std::vector<std::pair<std::vector<uint32_t>, uint32_t>> in_keys;  // (key, input face)
    std::vector<uint32_t> rot_in(part.face_count());
    std::vector<uint32_t> tmp;
    for (uint32_t f = 0; f < part.face_count(); ++f) {
      tmp.assign(part.face(f), part.face(f) + part.face_size(f));
      for (uint32_t& x : tmp) x = out_id[x];
      in_keys.push_back({key(tmp.data(), static_cast<uint32_t>(tmp.size()), rot_in[f]), f});
    }
    std::sort(in_keys.begin(), in_keys.end());
    std::vector<uint8_t> used(in_keys.size(), 0);
    for (uint32_t g = 0; g < faces.face_count(); ++g) {
      uint32_t rot_out = 0;
      std::pair<std::vector<uint32_t>, uint32_t> probe{key(faces.face(g), faces.face_size(g), rot_out), 0};
      auto it = std::lower_bound(in_keys.begin(), in_keys.end(), probe);
      while (it != in_keys.end() && it->first == probe.first && used[static_cast<size_t>(it - in_keys.begin())]) ++it;
      if (it == in_keys.end() || it->first != probe.first)
        return Status(ErrorCode::internal, "attributes: a decoded face matches no input face");
      used[static_cast<size_t>(it - in_keys.begin())] = 1;
      const uint32_t f = it->second, k = faces.face_size(g);
      face_of[g] = f;
      // Output corner i is key corner (i - rot_out), input corner (i - rot_out + rot_in).
      shift[g] = (rot_in[f] + k - rot_out % (k ? k : 1)) % (k ? k : 1);
    }
  }
  std::vector<int32_t> gnormal;
  std::vector<uint8_t> ghas;
  std::string body;
  ByteWriter w(body);
  w.varint(headers.size());
  for (const AttributeHeader& h : headers) write_header(w, h);
  // Per attribute: the predictor byte, chosen by size for vertex normals.
  std::vector<int> predictor(headers.size(), 0);
  for (size_t i = 0; i < headers.size(); ++i) {
    const AttributeHeader& h = headers[i];
    if (h.domain == AttributeDomain::vertex && h.quant == AttributeQuant::octahedral) predictor[i] = 1;
    w.u8(static_cast<uint8_t>(predictor[i]));
  }
  Enc enc;
  for (size_t i = 0; i < headers.size(); ++i) {
    const AttributeHeader& h = headers[i];
    const Attribute& a = part.attributes[i];
    const uint32_t n = int_components(h);
    const std::vector<int32_t>* gn = nullptr;
    const std::vector<uint8_t>* gh = nullptr;
    if (h.quant == AttributeQuant::octahedral) {
      geometry_normals(faces, rank, *in.q, h.bits, gnormal, ghas);
      gn = &gnormal;
      gh = &ghas;
    }
    ValueCoder<Enc> vc{enc, {}};
    AttributeWalk<Enc> walk{h, vc, enc, faces, rank, gn, gh};
    if (h.domain == AttributeDomain::vertex) {
      std::vector<int32_t> x(n * static_cast<size_t>(own));
      for (size_t v = 0; v < V; ++v)
        if (rank[v] != kNone) to_ints(h, &a.values[h.components * static_cast<size_t>(order[v])], &x[n * rank[v]]);
      if (!walk.vertices(predictor[i], x)) return Status(ErrorCode::internal, "attributes: vertex values out of range");
    } else if (h.domain == AttributeDomain::face) {
      std::vector<int32_t> x(n * faces.face_count());
      for (size_t g = 0; g < faces.face_count(); ++g) to_ints(h, &a.values[h.components * static_cast<size_t>(face_of[g])], &x[n * g]);
      if (!walk.face_values(x)) return Status(ErrorCode::internal, "attributes: face values out of range");
    } else {
      const size_t count = a.value_count();
      std::vector<int32_t> ints(n * count);
      for (size_t j = 0; j < count; ++j) to_ints(h, &a.values[h.components * j], &ints[n * j]);
      std::vector<uint32_t> in_value(faces.indices.size());
      for (uint32_t g = 0; g < faces.face_count(); ++g) {
        const uint32_t k = faces.face_size(g), f = face_of[g];
        for (uint32_t c = 0; c < k; ++c)
          in_value[faces.face_offsets[g] + c] = a.indices[part.face_offsets[f] + (c + shift[g]) % k];
      }
      std::vector<int32_t> values;
      std::vector<uint32_t> index;
      if (!walk.corners(in_value, ints, count, UINT64_MAX, values, index))
        return Status(ErrorCode::internal, "attributes: corner values out of range");
    }
  }
  out = body + enc.e.finish();
  return Status::Ok();
}

Status decode_attributes(std::string_view bytes, const AttributePart& in, std::vector<Attribute>& out) {
  out.clear();
  if (bytes.empty()) return Status::Ok();
  const Mesh& faces = *in.faces;
  const std::vector<uint32_t>& global = *in.global;
  ByteReader r(bytes);
  uint64_t count = 0;
  if (!r.varint(count) || count > kMaxAttributes) return corrupt("bad attribute count");
  std::vector<AttributeHeader> headers(static_cast<size_t>(count));
  for (AttributeHeader& h : headers) TSM_RETURN_IF_ERROR(read_header(r, h));
  std::vector<int> predictor(headers.size());
  for (size_t i = 0; i < headers.size(); ++i) {
    uint8_t p = 0;
    if (!r.u8(p) || p > 1 || (p == 1 && (headers[i].domain != AttributeDomain::vertex ||
                                         headers[i].quant != AttributeQuant::octahedral)))
      return corrupt("bad predictor");
    predictor[i] = p;
  }
  std::string_view coded;
  r.bytes(r.remaining(), coded);
  const size_t V = global.size();
  std::vector<uint32_t> rank(V, kNone);
  uint32_t own = 0;
  for (size_t v = 0; v < V; ++v)
    if (global[v] == kNone) rank[v] = own++;
  Dec dec;
  dec.d.init(coded);
  for (size_t i = 0; i < headers.size(); ++i) {
    const AttributeHeader& h = headers[i];
    const uint32_t n = int_components(h);
    std::vector<int32_t> gn;
    std::vector<uint8_t> gh;
    if (h.quant == AttributeQuant::octahedral) geometry_normals(faces, rank, *in.q, h.bits, gn, gh);
    ValueCoder<Dec> vc{dec, {}};
    AttributeWalk<Dec> walk{h, vc, dec, faces, rank, h.quant == AttributeQuant::octahedral ? &gn : nullptr,
                            h.quant == AttributeQuant::octahedral ? &gh : nullptr};
    Attribute a;
    a.name = h.name;
    a.kind = h.kind;
    a.domain = h.domain;
    a.type = h.type;
    a.components = h.components;
    std::vector<int32_t> x;
    if (h.domain == AttributeDomain::vertex) {
      x.assign(n * static_cast<size_t>(own), 0);
      if (!walk.vertices(predictor[i], x)) return corrupt("vertex values of '" + h.name + "' out of range");
    } else if (h.domain == AttributeDomain::face) {
      x.assign(n * faces.face_count(), 0);
      if (!walk.face_values(x)) return corrupt("face values of '" + h.name + "' out of range");
    } else {
      std::vector<uint32_t> none;
      std::vector<int32_t> no_ints;
      const uint64_t budget = 730 * (static_cast<uint64_t>(coded.size()) + 8);
      if (!walk.corners(none, no_ints, 0, budget, x, a.indices))
        return corrupt("corner values of '" + h.name + "' are invalid");
    }
    if (dec.d.overrun() > RangeDecoder::kMaxOverrun) return corrupt("stream is truncated");
    a.values.resize(static_cast<size_t>(h.components) * (x.size() / n));
    for (size_t j = 0; j < x.size() / n; ++j) from_ints(h, &x[n * j], &a.values[h.components * j]);
    out.push_back(std::move(a));
  }
  return Status::Ok();
}

}  // namespace tsm

// The in-memory mesh shared by all stages (not a step of the method itself).
#include "tsm/mesh.hpp"

#include <algorithm>
#include <cmath>

namespace tsm {

void Mesh::clear() {
  positions.clear();
  face_offsets.assign(1, 0);
  indices.clear();
  attributes.clear();
  metadata.clear();
}

void Mesh::reserve(size_t vertices, size_t faces, size_t corners) {
  positions.reserve(3 * vertices);
  face_offsets.reserve(faces + 1);
  indices.reserve(corners);
}

void Mesh::add_vertex(float x, float y, float z) {
  positions.push_back(x);
  positions.push_back(y);
  positions.push_back(z);
}

void Mesh::add_face(const uint32_t* corners, size_t n) {
  indices.insert(indices.end(), corners, corners + n);
  face_offsets.push_back(static_cast<uint32_t>(indices.size()));
}

void Mesh::add_triangle(uint32_t a, uint32_t b, uint32_t c) {
  indices.push_back(a);
  indices.push_back(b);
  indices.push_back(c);
  face_offsets.push_back(static_cast<uint32_t>(indices.size()));
}

bool Mesh::all_triangles() const {
  for (size_t f = 0; f < face_count(); ++f)
    if (face_size(f) != 3) return false;
  return true;
}

size_t Mesh::degenerate_face_count() const {
  size_t count = 0;
  for (size_t f = 0; f < face_count(); ++f) {
    const uint32_t* c = face(f);
    uint32_t n = face_size(f);
    bool degenerate = n < 3;
    for (uint32_t i = 0; i < n && !degenerate; ++i)
      for (uint32_t j = i + 1; j < n && !degenerate; ++j) degenerate = c[i] == c[j];
    count += degenerate;
  }
  return count;
}

size_t Mesh::unreferenced_vertex_count() const {
  std::vector<bool> used(vertex_count(), false);
  for (uint32_t v : indices)
    if (v < used.size()) used[v] = true;
  return static_cast<size_t>(std::count(used.begin(), used.end(), false));
}

bool Mesh::all_finite() const {
  for (float x : positions)
    if (!std::isfinite(x)) return false;
  for (const Attribute& a : attributes)
    for (float x : a.values)
      if (!std::isfinite(x)) return false;
  return true;
}

bool Mesh::valid(std::string* why) const {
  auto fail = [&](const std::string& msg) {
    if (why) *why = msg;
    return false;
  };
  if (positions.size() % 3 != 0) return fail("positions size is not a multiple of 3");
  if (face_offsets.empty() || face_offsets[0] != 0) return fail("face_offsets must start with 0");
  for (size_t f = 0; f + 1 < face_offsets.size(); ++f)
    if (face_offsets[f + 1] < face_offsets[f]) return fail("face_offsets decrease at face " + std::to_string(f));
  if (face_offsets.back() != indices.size()) return fail("face_offsets end does not match the corner count");
  const size_t nv = vertex_count();
  for (size_t i = 0; i < indices.size(); ++i)
    if (indices[i] >= nv)
      return fail("corner " + std::to_string(i) + " references vertex " + std::to_string(indices[i]) +
                  " of " + std::to_string(nv));
  for (size_t k = 0; k < attributes.size(); ++k) {
    const Attribute& a = attributes[k];
    const std::string what = "attribute " + std::to_string(k) + " ('" + a.name.substr(0, 64) + "')";
    if (a.name.size() > kMaxAttributeNameBytes)
      return fail(what + ": a name of " + std::to_string(a.name.size()) + " bytes (at most " +
                  std::to_string(kMaxAttributeNameBytes) + ")");
    if (a.components < 1 || a.components > 4) return fail(what + " has " + std::to_string(a.components) + " components (1..4)");
    if (a.values.size() % a.components != 0) return fail(what + ": values size is not a multiple of its components");
    if (static_cast<uint8_t>(a.kind) > 3 || static_cast<uint8_t>(a.domain) > 2 || static_cast<uint8_t>(a.type) > 3)
      return fail(what + ": unknown kind, domain or type");
    if (a.kind == AttributeKind::normal && a.components != 3) return fail(what + ": a normal has 3 components");
    if (a.kind == AttributeKind::texcoord && a.components != 2) return fail(what + ": a texture coordinate has 2 components");
    if (a.kind == AttributeKind::color && a.components < 3) return fail(what + ": a colour has 3 or 4 components");
    const size_t n = a.value_count();
    switch (a.domain) {
      case AttributeDomain::vertex:
        if (n != nv || !a.indices.empty()) return fail(what + ": a vertex attribute needs one value per vertex");
        break;
      case AttributeDomain::face:
        if (n != face_count() || !a.indices.empty()) return fail(what + ": a face attribute needs one value per face");
        break;
      case AttributeDomain::corner:
        if (a.indices.size() != indices.size()) return fail(what + ": a corner attribute needs one index per corner");
        for (size_t i = 0; i < a.indices.size(); ++i)
          if (a.indices[i] >= n)
            return fail(what + ": corner " + std::to_string(i) + " names value " + std::to_string(a.indices[i]) +
                        " of " + std::to_string(n));
        break;
    }
  }
  for (size_t k = 0; k < metadata.size(); ++k) {
    const std::string& key = metadata[k].key;
    if (key.empty() || key.size() > 255) return fail("metadata entry " + std::to_string(k) + ": a key has 1..255 bytes");
    for (size_t j = 0; j < k; ++j)
      if (metadata[j].key == key) return fail("metadata key '" + key + "' appears twice");
  }
  return true;
}

const MetadataEntry* Mesh::find_metadata(const std::string& key) const {
  for (const MetadataEntry& e : metadata)
    if (e.key == key) return &e;
  return nullptr;
}

const Attribute* Mesh::find_attribute(AttributeKind kind) const {
  for (const Attribute& a : attributes)
    if (a.kind == kind) return &a;
  return nullptr;
}

double BoundingBox::largest_extent() const {
  double e = 0;
  for (int a = 0; a < 3; ++a) e = std::max(e, static_cast<double>(max[a]) - static_cast<double>(min[a]));
  return e;
}

double BoundingBox::diagonal() const {
  double d2 = 0;
  for (int a = 0; a < 3; ++a) {
    const double e = static_cast<double>(max[a]) - static_cast<double>(min[a]);
    d2 += e * e;
  }
  return std::sqrt(d2);
}

BoundingBox bounding_box(const Mesh& mesh) {
  BoundingBox box;
  const size_t n = mesh.vertex_count();
  if (n == 0) return box;
  for (int a = 0; a < 3; ++a) box.min[a] = box.max[a] = mesh.positions[static_cast<size_t>(a)];
  for (size_t v = 0; v < n; ++v)
    for (int a = 0; a < 3; ++a) {
      float x = mesh.positions[3 * v + static_cast<size_t>(a)];
      box.min[a] = std::min(box.min[a], x);
      box.max[a] = std::max(box.max[a], x);
    }
  return box;
}

}  // namespace tsm

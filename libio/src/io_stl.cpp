// STL reading, binary and ASCII (file-format stage, not part of the
// compression method): turns STL triangles into a Mesh.
//
// STL stores each triangle as three corner positions. With
// ReadOptions::stl_weld (the default) corners whose three float bit patterns
// are identical become one vertex, numbered in order of first appearance;
// being exact, +0.0 and -0.0 stay different. Without welding every triangle
// gets three vertices of its own. Normals and the binary attribute word are
// ignored.
//
// Binary is recognised by size: 84 + 50 * (the uint32 at byte 80) bytes,
// whatever the header says (binary headers often begin with "solid" too).
// Otherwise a file starting with "solid" is read as ASCII: keywords are
// case-insensitive, any amount of whitespace is accepted, several solids in
// one file are read in turn.
//
// Writing: binary (80-byte header that does not start with "solid", the
// count, 50 bytes per triangle, attribute word 0) or, with
// WriteOptions::ascii, "solid tsm" text with the shortest decimal text that
// reads back to each float. Each face of n >= 3 corners becomes the fan
// (c0, c[i], c[i+1]); faces of 1 or 2 corners cannot be STL facets and are
// left out. Facet normals are the normalized cross product of the edges (0 0
// 0 for a degenerate triangle). Read back with welding, the positions come
// back bit-identical; vertices at the same position merge, and unreferenced
// vertices, attributes and metadata are lost: WriteInfo::notes says which.
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "byte_io.hpp"
#include "text_scan.hpp"
#include "tsm/io.hpp"
#include "write_notes.hpp"

namespace tsm {

namespace {

constexpr uint64_t kMaxIndexableVertices = std::numeric_limits<uint32_t>::max();


bool iequals(std::string_view a, const char* b) {
  size_t n = std::strlen(b);
  if (a.size() != n) return false;
  for (size_t i = 0; i < n; ++i) {
    char c = a[i];
    if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
    if (c != b[i]) return false;
  }
  return true;
}

bool starts_with_solid(std::string_view bytes) {
  size_t i = 0;
  while (i < bytes.size() && TextCursor::is_space(bytes[i])) ++i;
  if (bytes.size() - i < 5) return false;
  if (!iequals(bytes.substr(i, 5), "solid")) return false;
  return bytes.size() - i == 5 || TextCursor::is_space(bytes[i + 5]);
}

Status limit_error(const std::string& name, const char* what, uint64_t limit) {
  return Status(ErrorCode::limit_exceeded,
                name + ": more than " + std::to_string(limit) + " " + what + " (the limit given for this read)");
}

// Corner welding: an open-addressing hash table (linear probing, load at
// most 1/2) of vertex numbers, keyed on the bit patterns of the positions
// already in the mesh (4-byte slots keep the table small).
class Welder {
 public:
  Welder(Mesh& mesh, bool weld, uint64_t max_vertices) : mesh_(mesh), weld_(weld), max_vertices_(max_vertices) {}
  void reserve(size_t vertices) {
    if (weld_) grow_to(vertices);
  }
  // Vertex number for the corner at p; false when a vertex limit is hit.
  bool add(const float p[3], uint32_t& out) {
    if (!weld_) return new_vertex(p, out);
    uint32_t key[3];
    std::memcpy(key, p, sizeof key);
    if (2 * (mesh_.vertex_count() + 1) > table_.size()) grow_to(mesh_.vertex_count() + 1);
    const size_t mask = table_.size() - 1;
    for (size_t i = hash(key) & mask;; i = (i + 1) & mask) {
      const uint32_t v = table_[i];
      if (v == kEmpty) {
        if (!new_vertex(p, out)) return false;
        table_[i] = out;
        return true;
      }
      uint32_t other[3];
      std::memcpy(other, mesh_.positions.data() + 3 * static_cast<size_t>(v), sizeof other);
      if (other[0] == key[0] && other[1] == key[1] && other[2] == key[2]) {
        out = v;
        return true;
      }
    }
  }

 private:
  static constexpr uint32_t kEmpty = std::numeric_limits<uint32_t>::max();
  static size_t hash(const uint32_t k[3]) {
    uint64_t h = (static_cast<uint64_t>(k[0]) << 32 | k[1]) * 0x9E3779B97F4A7C15ull;
    h ^= (h >> 29) ^ (static_cast<uint64_t>(k[2]) * 0xC2B2AE3D27D4EB4Full);
    h ^= h >> 32;
    h *= 0xD6E8FEB86659FD93ull;
    h ^= h >> 32;
    return static_cast<size_t>(h);
  }
  bool new_vertex(const float p[3], uint32_t& out) {
    const size_t n = mesh_.vertex_count();
    if ((max_vertices_ != 0 && n >= max_vertices_) || n >= kMaxIndexableVertices) return false;
    mesh_.add_vertex(p[0], p[1], p[2]);
    out = static_cast<uint32_t>(n);
    return true;
  }
  // Capacity for at least `vertices` entries at load <= 1/2; rehashes.
  void grow_to(size_t vertices) {
    size_t cap = 16;
    while (cap < 2 * vertices) cap *= 2;
    if (cap <= table_.size()) return;
    table_.assign(cap, kEmpty);
    const size_t mask = cap - 1;
    const size_t n = mesh_.vertex_count();
    for (size_t v = 0; v < n; ++v) {
      uint32_t key[3];
      std::memcpy(key, mesh_.positions.data() + 3 * v, sizeof key);
      size_t i = hash(key) & mask;
      while (table_[i] != kEmpty) i = (i + 1) & mask;
      table_[i] = static_cast<uint32_t>(v);
    }
  }

  Mesh& mesh_;
  bool weld_;
  uint64_t max_vertices_;
  std::vector<uint32_t> table_;
};

Status nonfinite_error(const std::string& where) {
  return Status(ErrorCode::parse_error,
                where + ": non-finite coordinate (NaN or infinity); use --allow-nonfinite to accept it");
}

Status read_binary(std::string_view bytes, const std::string& name, Mesh& mesh, const ReadOptions& options,
                   uint32_t count) {
  const uint64_t n = count;
  if (options.max_faces != 0 && n > options.max_faces) return limit_error(name, "faces", options.max_faces);
  if (!options.stl_weld) {
    if (options.max_vertices != 0 && 3 * n > options.max_vertices)
      return limit_error(name, "vertices", options.max_vertices);
    if (3 * n > kMaxIndexableVertices) return limit_error(name, "vertices", kMaxIndexableVertices);
  }
  if (3 * n > std::numeric_limits<uint32_t>::max())
    return limit_error(name, "face corners in all", std::numeric_limits<uint32_t>::max());
  // The size was checked against the count, so these reservations are backed
  // by real bytes.
  mesh.reserve(options.stl_weld ? static_cast<size_t>(n) : static_cast<size_t>(3 * n), static_cast<size_t>(n),
               static_cast<size_t>(3 * n));
  Welder welder(mesh, options.stl_weld, options.max_vertices);
  welder.reserve(static_cast<size_t>(n) / 2 + 16);  // closed meshes: about F/2 vertices
  ByteReader r(bytes.substr(84));
  for (uint64_t t = 0; t < n; ++t) {
    const size_t offset = 84 + static_cast<size_t>(50 * t);
    float f[12];
    for (float& x : f)
      if (!r.f32(x)) return binary_error(name, offset, "triangle " + std::to_string(t) + " is truncated");
    uint16_t attribute;
    if (!r.u16(attribute)) return binary_error(name, offset, "triangle " + std::to_string(t) + " is truncated");
    uint32_t c[3];
    for (int k = 0; k < 3; ++k) {
      const float* p = f + 3 + 3 * k;
      if (!options.allow_nonfinite && !(std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2])))
        return nonfinite_error(name + ": byte " + std::to_string(offset + 12 + 12 * static_cast<size_t>(k)) +
                               ": triangle " + std::to_string(t));
      if (!welder.add(p, c[k]))
        return limit_error(name, "vertices", options.max_vertices != 0 ? options.max_vertices
                                                                       : kMaxIndexableVertices);
    }
    mesh.add_triangle(c[0], c[1], c[2]);
  }
  return Status::Ok();
}

class AsciiStl {
 public:
  AsciiStl(std::string_view bytes, const std::string& name, Mesh& mesh, const ReadOptions& options)
      : cur_(bytes, name), mesh_(mesh), options_(options), welder_(mesh, options.stl_weld, options.max_vertices) {}

  Status run(ReadInfo* info) {
    size_t solids = 0;
    bool ended = false;  // the last solid had its endsolid
    for (;;) {
      cur_.skip_whitespace();
      if (cur_.at_end()) break;
      std::string_view kw = cur_.token();
      if (!iequals(kw, "solid")) {
        if (solids == 0) return cur_.error("expected 'solid' at the start of an ASCII STL file");
        return cur_.error("expected 'solid' or the end of the file after 'endsolid', found " + quote(kw));
      }
      ++solids;
      cur_.next_line();  // the name
      ended = false;
      for (;;) {
        cur_.skip_whitespace();
        if (cur_.at_end()) break;
        kw = cur_.token();
        if (iequals(kw, "endsolid")) {
          cur_.next_line();
          ended = true;
          break;
        }
        if (!iequals(kw, "facet"))
          return cur_.error("expected 'facet' or 'endsolid', found " + quote(kw));
        TSM_RETURN_IF_ERROR(facet());
      }
      if (!ended) break;
    }
    if (info && solids > 0 && !ended) info->notes = "the file ends without 'endsolid'";
    return Status::Ok();
  }

 private:
  Status expect(const char* kw, const char* context) {
    cur_.skip_whitespace();
    if (cur_.at_end()) return cur_.error(std::string("the file ends inside a facet (expected '") + kw + "')");
    std::string_view t = cur_.token();
    if (!iequals(t, kw)) return cur_.error(std::string("expected '") + kw + "' " + context + ", found " + quote(t));
    return Status::Ok();
  }
  Status facet() {
    // "facet normal nx ny nz": the normal is ignored (not even required).
    cur_.next_line();
    TSM_RETURN_IF_ERROR(expect("outer", "after 'facet'"));
    TSM_RETURN_IF_ERROR(expect("loop", "after 'outer'"));
    cur_.next_line();
    uint32_t c[3];
    for (int k = 0; k < 3; ++k) {
      cur_.skip_whitespace();
      if (cur_.at_end()) return cur_.error("the file ends inside a facet (expected 'vertex')");
      std::string_view t = cur_.token();
      if (!iequals(t, "vertex")) {
        if (iequals(t, "endloop"))
          return cur_.error("facet has " + std::to_string(k) + " vertices (STL facets have exactly 3)");
        return cur_.error("expected 'vertex', found " + quote(t));
      }
      float p[3];
      for (float& x : p) {
        cur_.skip_blanks();
        const char* s = cur_.position();
        const size_t line = cur_.line();
        if (!cur_.parse_float(x)) {
          cur_.set_position(s, line);
          if (cur_.at_line_end()) return cur_.error("vertex has fewer than 3 coordinates");
          return cur_.error("bad number " + quote(cur_.token()) + " in a vertex");
        }
        if (!options_.allow_nonfinite && !std::isfinite(x))
          return nonfinite_error(cur_.name() + ": line " + std::to_string(cur_.line()));
      }
      if (!cur_.at_line_end()) return cur_.error("unexpected " + quote(cur_.token()) + " after a vertex's 3 coordinates");
      if (!welder_.add(p, c[k]))
        return limit_error(cur_.name(), "vertices",
                           options_.max_vertices != 0 ? options_.max_vertices : kMaxIndexableVertices);
    }
    cur_.skip_whitespace();
    if (!cur_.at_end()) {
      const char* s = cur_.position();
      const size_t line = cur_.line();
      std::string_view t = cur_.token();
      if (iequals(t, "vertex")) {
        cur_.set_position(s, line);
        return cur_.error("facet has more than 3 vertices (STL facets have exactly 3)");
      }
      cur_.set_position(s, line);
    }
    TSM_RETURN_IF_ERROR(expect("endloop", "after 3 vertices"));
    TSM_RETURN_IF_ERROR(expect("endfacet", "after 'endloop'"));
    cur_.next_line();
    if (options_.max_faces != 0 && mesh_.face_count() >= options_.max_faces)
      return limit_error(cur_.name(), "faces", options_.max_faces);
    if (mesh_.indices.size() + 3 > std::numeric_limits<uint32_t>::max())
      return limit_error(cur_.name(), "face corners in all", std::numeric_limits<uint32_t>::max());
    mesh_.add_triangle(c[0], c[1], c[2]);
    return Status::Ok();
  }

  TextCursor cur_;
  Mesh& mesh_;
  const ReadOptions& options_;
  Welder welder_;
};

}  // namespace

Status read_stl(std::string_view bytes, const std::string& name, Mesh& out, const ReadOptions& options,
                ReadInfo* info) {
  if (info) {
    *info = ReadInfo();
    info->format = MeshFormat::stl;
  }
  out.clear();
  Mesh mesh;
  uint32_t count = 0;
  bool has_count = bytes.size() >= 84;
  if (has_count) {
    ByteReader r(bytes.substr(80, 4));
    r.u32(count);
  }
  const uint64_t expected = 84 + 50 * static_cast<uint64_t>(count);
  if (has_count && expected == bytes.size()) {
    if (info) info->binary = true;
    TSM_RETURN_IF_ERROR(read_binary(bytes, name, mesh, options, count));
    out = std::move(mesh);
    return Status::Ok();
  }
  if (starts_with_solid(bytes)) {
    AsciiStl ascii(bytes, name, mesh, options);
    Status st = ascii.run(info);
    if (!st.ok()) {
      if (has_count && st.code() == ErrorCode::parse_error)
        return Status(st.code(), st.message() + " (read as ASCII because it starts with 'solid'; as binary STL its " +
                                     "triangle count " + std::to_string(count) + " would need " +
                                     std::to_string(expected) + " bytes, but the file has " +
                                     std::to_string(bytes.size()) + ")");
      return st;
    }
    out = std::move(mesh);
    return Status::Ok();
  }
  if (bytes.empty()) return binary_error(name, 0, "empty file, not an STL mesh");
  if (!has_count)
    return binary_error(name, bytes.size(),
                        "the file ends inside the 84-byte binary STL header (and it does not start with 'solid')");
  if (bytes.size() < expected) {
    const uint64_t whole = (bytes.size() - 84) / 50;
    return binary_error(name, static_cast<size_t>(84 + 50 * whole),
                        "binary STL truncated: triangle " + std::to_string(whole) + " of " + std::to_string(count) +
                            " is incomplete (the header's count needs " + std::to_string(expected) +
                            " bytes, the file has " + std::to_string(bytes.size()) + ")");
  }
  return binary_error(name, static_cast<size_t>(expected),
                      "binary STL has " + std::to_string(bytes.size() - expected) +
                          " bytes after its last triangle (the header says " + std::to_string(count) +
                          " triangles, " + std::to_string(expected) + " bytes)");
}

namespace {

// The unit normal of triangle (a, b, c) by the right-hand rule, computed in
// double; zeros when the triangle has no area (or a non-finite corner).
void facet_normal(const float* a, const float* b, const float* c, float n[3]) {
  const double u[3] = {double(b[0]) - a[0], double(b[1]) - a[1], double(b[2]) - a[2]};
  const double v[3] = {double(c[0]) - a[0], double(c[1]) - a[1], double(c[2]) - a[2]};
  const double x[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
  const double len = std::sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
  for (int k = 0; k < 3; ++k) n[k] = len > 0 && std::isfinite(len) ? static_cast<float>(x[k] / len) : 0.0f;
}

void put_f32_le(std::string& out, float x) {
  uint32_t b;
  std::memcpy(&b, &x, 4);
  for (int i = 0; i < 4; ++i) out.push_back(static_cast<char>(b >> (8 * i)));
}

void put_text(std::string& out, const char* lead, const float p[3]) {
  char buf[96];
  char* w = buf;
  for (const char* k = lead; *k; ++k) *w++ = *k;
  for (int a = 0; a < 3; ++a) {
    *w++ = ' ';
    w = std::to_chars(w, buf + sizeof buf, p[a]).ptr;  // shortest text that reads back to p[a]
  }
  *w++ = '\n';
  out.append(buf, static_cast<size_t>(w - buf));
}

}  // namespace

Status write_stl(const Mesh& mesh, const WriteOptions& options, std::string& out, WriteInfo* info) {
  std::string why;
  if (!mesh.valid(&why)) return Status(ErrorCode::invalid_argument, "cannot write STL: invalid mesh: " + why);
  uint64_t triangles = 0, short_faces = 0, polygons = 0;
  for (size_t f = 0; f < mesh.face_count(); ++f) {
    const uint32_t n = mesh.face_size(f);
    if (n < 3) {
      ++short_faces;
    } else {
      triangles += n - 2;
      if (n > 3) ++polygons;
    }
  }
  if (triangles > std::numeric_limits<uint32_t>::max())
    return Status(ErrorCode::limit_exceeded, "cannot write STL: " + std::to_string(triangles) +
                                                 " triangles are more than an STL file can count (4294967295); "
                                                 "write PLY or OBJ instead");
  if (info) {
    if (polygons > 0)
      info->add_note("STL holds triangles only: split " + std::to_string(polygons) + " polygon" +
                     (polygons == 1 ? "" : "s") + " into triangle fans");
    if (short_faces > 0)
      info->add_note("STL cannot hold faces of 1 or 2 corners: left out " + std::to_string(short_faces));
    const size_t loose = mesh.unreferenced_vertex_count();
    if (loose > 0)
      info->add_note("STL cannot hold vertices no face uses: left out " + std::to_string(loose));
    std::string dropped;
    for (const Attribute& a : mesh.attributes) dropped += (dropped.empty() ? "" : ", ") + attribute_words(a);
    note_not_written(mesh, "STL", dropped, nullptr, info);
  }

  out.clear();
  const float* pos = mesh.positions.data();
  auto for_each_triangle = [&](auto&& emit) {
    for (size_t f = 0; f < mesh.face_count(); ++f) {
      const uint32_t n = mesh.face_size(f);
      const uint32_t* c = mesh.face(f);
      for (uint32_t i = 1; i + 1 < n; ++i) emit(pos + 3 * size_t{c[0]}, pos + 3 * size_t{c[i]}, pos + 3 * size_t{c[i + 1]});
    }
  };
  if (!options.ascii) {
    // The header must not begin with "solid", or readers that look only at
    // the first word would take the file for ASCII.
    std::string header = "binary STL written by tsm";
    header.resize(80, ' ');
    out.reserve(84 + 50 * static_cast<size_t>(triangles));
    out += header;
    const uint32_t count = static_cast<uint32_t>(triangles);
    for (int i = 0; i < 4; ++i) out.push_back(static_cast<char>(count >> (8 * i)));
    for_each_triangle([&](const float* a, const float* b, const float* c) {
      float n[3];
      facet_normal(a, b, c, n);
      for (const float* p : {static_cast<const float*>(n), a, b, c})
        for (int k = 0; k < 3; ++k) put_f32_le(out, p[k]);
      out.push_back('\0');
      out.push_back('\0');
    });
    return Status::Ok();
  }
  out.reserve(30 + 250 * static_cast<size_t>(triangles));
  out += "solid tsm\n";
  for_each_triangle([&](const float* a, const float* b, const float* c) {
    float n[3];
    facet_normal(a, b, c, n);
    put_text(out, "facet normal", n);
    out += "outer loop\n";
    put_text(out, "vertex", a);
    put_text(out, "vertex", b);
    put_text(out, "vertex", c);
    out += "endloop\nendfacet\n";
  });
  out += "endsolid tsm\n";
  return Status::Ok();
}

}  // namespace tsm

// OFF (Object File Format) reading and writing (file-format stage, not part
// of the compression method): turns an OFF file into a Mesh and back.
//
// Accepted: the header keyword OFF with the optional prefixes of the
// Geomview family in their order, ST (texture coordinates), C (colours),
// N (normals) -- "OFF", "COFF", "NOFF", "STOFF", "CNOFF", "STCNOFF" -- then the
// counts "V F E" (E ignored, may be missing), V vertices and F faces
// "n i0 .. i(n-1)" with 0-based indices. The counts may follow the keyword on
// its line, also glued to it ("OFF8 6 0", as some exporters write).
// Coordinates and indices may span lines; what follows a vertex's x y z and a
// face's n indices is read from the rest of that line. "#" starts a comment.
// 4OFF (homogeneous), nOFF (any dimension) and OFF BINARY are refused as
// unsupported. Faces are kept as read (polygons, 1 or 2 corners).
//
// Attributes: after x y z a vertex line holds, in this order, the normal
// (N: 3 numbers), the colour (C: 3 or 4, RGB or RGBA) and the texture
// coordinates (ST: 2), as the header announces. They become the vertex
// attributes 'normal' (kind normal), 'color' (kind color) and 'texcoord'
// (kind texcoord). After a face's indices, 3 or 4 numbers on every face give
// the face attribute 'color'. Colours are u8 when every value of the
// attribute is written as an integer (no '.' or exponent) from 0 to 255, else
// f32 as written. When the lines do not agree (a vertex line with another
// count of numbers than the header and the first line say, some faces with a
// colour and others without), the attribute cannot be kept: it is dropped
// with a note naming a line, as are numbers the header announces nothing for.
// Non-finite attribute values are refused unless
// ReadOptions::allow_nonfinite, as for positions.
//
// Writing (write_off): "OFF", with the prefixes ST, C, N for a vertex-domain
// texcoord, colour and normal attribute ("COFF" for a coloured mesh), then
// the counts, vertices with their values and faces "n i0 .. i(n-1)" followed
// by a face-domain colour when there is one. Floats use the shortest text
// that reads back bit-identically; f32 colours always get a '.' (so they
// read back as f32) and u8 ones are written as integers (read back as u8),
// u16 ones as 0..1 fractions. Other attributes and metadata are not written
// (WriteInfo::notes names them).
#include <charconv>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "text_scan.hpp"
#include "tsm/io.hpp"
#include "write_notes.hpp"

namespace tsm {

namespace {

constexpr uint64_t kMaxIndexableVertices = std::numeric_limits<uint32_t>::max();


class OffReader {
 public:
  OffReader(std::string_view bytes, const std::string& name, const ReadOptions& options)
      : cur_(bytes, name), end_(bytes.data() + bytes.size()), options_(options) {}

  Status run(Mesh& mesh, ReadInfo* info);

 private:
  // The numbers after a record on the rest of its line (up to kMaxExtra;
  // parsing stops at the first token that is not a number). `integers`
  // says whether each was written as an integer.
  static constexpr int kMaxExtra = 16;
  struct Extra {
    float v[kMaxExtra];
    bool integer[kMaxExtra];
    int count = 0;
    bool other = false;  // a token that is not a number, or more than kMaxExtra numbers
  };
  void read_extra(Extra& e);
  // One optional per-vertex or per-face attribute while the file is read.
  struct Values {
    std::vector<float> v;
    bool integers = true;  // every value written as an integer 0..255
    int components = 0;
  };
  Status add_values(Values& out, const Extra& e, int first, int count, bool color);
  void finish(Mesh& mesh, ReadInfo* info);
  // Skips blanks, line ends and comments.
  void skip_space() {
    for (;;) {
      cur_.skip_whitespace();
      if (cur_.at_end() || *cur_.position() != '#') return;
      cur_.next_line();
    }
  }
  size_t remaining() const { return static_cast<size_t>(end_ - cur_.position()); }
  std::string_view peek_token() {
    const char* s = cur_.position();
    const size_t line = cur_.line();
    std::string_view t = cur_.token();
    cur_.set_position(s, line);
    return t;
  }
  // An unsigned count or index (possibly on a following line).
  Status read_uint(uint64_t& v, const char* what) {
    skip_space();
    if (cur_.at_end()) return cur_.error(std::string("the file ends where ") + what + " was expected");
    const char* s = cur_.position();
    const size_t line = cur_.line();
    if (*s == '-') return cur_.error(std::string("negative ") + what + " " + quote(peek_token()));
    if (!cur_.parse_int(v)) {
      cur_.set_position(s, line);
      return cur_.error(std::string("bad ") + what + " " + quote(peek_token()));
    }
    return Status::Ok();
  }
  Status read_header();

  TextCursor cur_;
  const char* end_;
  const ReadOptions& options_;
  uint64_t first_count_ = 0;  // V glued to the keyword ("OFF8 6 0")
  bool have_first_count_ = false;
  bool has_st_ = false, has_c_ = false, has_n_ = false;  // header prefixes
  std::string keyword_;                                  // as written, for notes

  Values normals_, colors_, texcoords_, face_colors_;
  bool vertex_extras_ok_ = true;  // every vertex line fits the layout
  int color_count_ = 0;           // 3 or 4 once the first vertex line set it
  size_t vertex_first_line_ = 0, vertex_bad_line_ = 0;
  size_t unannounced_lines_ = 0, unannounced_first_ = 0;  // numbers after x y z of a plain OFF
  // Face colours: every face has 3 (or every face 4) numbers after its indices.
  enum class FaceColors { unknown, all, none, mixed } face_state_ = FaceColors::unknown;
  size_t face_line_with_ = 0, face_line_without_ = 0;
  size_t face_other_lines_ = 0, face_other_first_ = 0;  // other counts (a colour-map index)
};

void OffReader::read_extra(Extra& e) {
  e.count = 0;
  e.other = false;
  for (;;) {
    cur_.skip_blanks();
    if (cur_.at_line_end() || *cur_.position() == '#') return;
    if (e.count == kMaxExtra) {
      e.other = true;
      return;
    }
    const char* s = cur_.position();
    const size_t line = cur_.line();
    float x;
    if (!cur_.parse_float(x)) {
      cur_.set_position(s, line);
      e.other = true;
      return;
    }
    bool integer = true;
    for (const char* q = s; q < cur_.position(); ++q)
      if (!((*q >= '0' && *q <= '9') || *q == '-' || *q == '+')) integer = false;
    e.v[e.count] = x;
    e.integer[e.count] = integer;
    ++e.count;
  }
}

Status OffReader::add_values(Values& out, const Extra& e, int first, int count, bool color) {
  out.components = count;
  for (int k = first; k < first + count; ++k) {
    const float x = e.v[k];
    if (!options_.allow_nonfinite && !std::isfinite(x))
      return cur_.error(std::string("non-finite ") + (color ? "colour" : "attribute") +
                        " value (NaN or infinity); use --allow-nonfinite to accept it");
    if (!e.integer[k] || !(x >= 0.0f && x <= 255.0f)) out.integers = false;
    out.v.push_back(x);
  }
  return Status::Ok();
}

void OffReader::finish(Mesh& mesh, ReadInfo* info) {
  std::vector<std::string> notes;
  const size_t nv = mesh.vertex_count();
  auto attribute = [&](Values& val, const char* name, AttributeKind kind, AttributeDomain domain) {
    Attribute a;
    a.name = name;
    a.kind = kind;
    a.domain = domain;
    a.components = static_cast<uint32_t>(val.components);
    a.type = kind == AttributeKind::color && val.integers ? AttributeType::u8 : AttributeType::f32;
    a.values = std::move(val.v);
    mesh.attributes.push_back(std::move(a));
  };
  if (nv > 0 && (has_n_ || has_c_ || has_st_)) {
    if (vertex_extras_ok_) {
      if (has_n_) attribute(normals_, "normal", AttributeKind::normal, AttributeDomain::vertex);
      if (has_c_) attribute(colors_, "color", AttributeKind::color, AttributeDomain::vertex);
      if (has_st_) attribute(texcoords_, "texcoord", AttributeKind::texcoord, AttributeDomain::vertex);
    } else {
      notes.push_back("ignored the vertex " + std::string(has_n_ ? "normals " : "") + (has_c_ ? "colours " : "") +
                      (has_st_ ? "texture coordinates " : "") + "the header " + quote(keyword_) +
                      " announces: line " + std::to_string(vertex_bad_line_) +
                      " has another count of numbers after x y z than line " + std::to_string(vertex_first_line_) +
                      " (kept only when every vertex line has them)");
    }
  }
  if (unannounced_lines_ > 0)
    notes.push_back("ignored the numbers after x y z on " + std::to_string(unannounced_lines_) + " vertex line" +
                    (unannounced_lines_ == 1 ? "" : "s") + " (first: line " + std::to_string(unannounced_first_) +
                    "): the header " + quote(keyword_) +
                    " announces no normals, colours or texture coordinates (COFF, NOFF, STOFF would)");
  if (face_state_ == FaceColors::all && mesh.face_count() > 0) {
    attribute(face_colors_, "color", AttributeKind::color, AttributeDomain::face);
  } else if (face_state_ == FaceColors::mixed) {
    notes.push_back("ignored the face colours: line " + std::to_string(face_line_with_) + " has one but line " +
                    std::to_string(face_line_without_) +
                    " has none or one of another size (kept only when every face has 3 or every face 4 numbers)");
  }
  if (face_other_lines_ > 0)
    notes.push_back("ignored the numbers after the indices of " + std::to_string(face_other_lines_) + " face" +
                    (face_other_lines_ == 1 ? "" : "s") + " (first: line " + std::to_string(face_other_first_) +
                    "; a face colour is 3 or 4 numbers)");
  if (info)
    for (const std::string& n : notes) info->add_note(n);
}

Status OffReader::read_header() {
  skip_space();
  if (cur_.at_end()) return cur_.error("empty file, expected the 'OFF' header");
  std::string_view kw = cur_.token();
  // Split "[ST][C][N][4][n]OFF[digits]".
  size_t at = kw.find("OFF");
  if (at == std::string_view::npos) return cur_.error("expected the 'OFF' header, found " + quote(kw));
  std::string_view prefix = kw.substr(0, at);
  std::string_view tail = kw.substr(at + 3);
  std::string_view p = prefix;
  auto take = [&](std::string_view part) {
    if (p.substr(0, part.size()) == part) {
      p.remove_prefix(part.size());
      return true;
    }
    return false;
  };
  keyword_ = std::string(kw);
  has_st_ = take("ST");
  has_c_ = take("C");
  has_n_ = take("N");
  bool four = take("4");
  bool ndim = take("n");
  if (!p.empty()) return cur_.error("expected the 'OFF' header, found " + quote(kw));
  if (four || ndim)
    return Status(ErrorCode::unsupported, cur_.name() + ": line " + std::to_string(cur_.line()) + ": " +
                                              quote(kw) + " files (4D or n-dimensional vertices) are not supported");
  if (!tail.empty()) {
    // "OFF8" (counts glued on): digits only.
    for (char c : tail)
      if (c < '0' || c > '9') return cur_.error("expected the 'OFF' header, found " + quote(kw));
    TextCursor digits(tail, cur_.name());
    if (!digits.parse_int(first_count_)) return cur_.error("bad vertex count in " + quote(kw));
    have_first_count_ = true;
  }
  if (peek_token() == "BINARY")
    return Status(ErrorCode::unsupported,
                  cur_.name() + ": line " + std::to_string(cur_.line()) + ": binary OFF is not supported");
  return Status::Ok();
}

Status OffReader::run(Mesh& mesh, ReadInfo* info) {
  TSM_RETURN_IF_ERROR(read_header());
  uint64_t nv = first_count_, nf = 0;
  if (!have_first_count_) TSM_RETURN_IF_ERROR(read_uint(nv, "the vertex count"));
  TSM_RETURN_IF_ERROR(read_uint(nf, "the face count"));
  if (!cur_.at_line_end() && *cur_.position() != '#') {
    uint64_t ne;
    TSM_RETURN_IF_ERROR(read_uint(ne, "the edge count"));
  }
  const size_t header_line = cur_.line();
  cur_.next_line();

  auto limit = [&](const char* what, uint64_t have, uint64_t max) {
    return Status(ErrorCode::limit_exceeded, cur_.name() + ": line " + std::to_string(header_line) + ": " +
                                                 std::to_string(have) + " " + what + " is more than " +
                                                 std::to_string(max) + " (the limit given for this read)");
  };
  if (options_.max_vertices != 0 && nv > options_.max_vertices)
    return limit("vertices", nv, options_.max_vertices);
  if (options_.max_faces != 0 && nf > options_.max_faces) return limit("faces", nf, options_.max_faces);
  if (nv > kMaxIndexableVertices) return limit("vertices", nv, kMaxIndexableVertices);
  // Every vertex takes at least 6 bytes ("0 0 0\n"), every face at least 2:
  // refuse counts the rest of the file cannot hold before reserving.
  const uint64_t rest = remaining();
  if (nv > rest / 6 || nf > rest / 2 || 6 * nv + 2 * nf > rest + 1)
    return Status(ErrorCode::parse_error,
                  cur_.name() + ": line " + std::to_string(header_line) + ": the header says " + std::to_string(nv) +
                      " vertices and " + std::to_string(nf) + " faces, but only " + std::to_string(rest) +
                      " bytes follow (truncated file or wrong counts)");
  mesh.reserve(static_cast<size_t>(nv), static_cast<size_t>(nf), static_cast<size_t>(3 * nf));

  static const char* const kAxis[3] = {"x coordinate", "y coordinate", "z coordinate"};
  Extra extra;
  for (uint64_t v = 0; v < nv; ++v) {
    float xyz[3];
    for (int a = 0; a < 3; ++a) {
      skip_space();
      if (cur_.at_end())
        return cur_.error("the file ends at vertex " + std::to_string(v) + " of " + std::to_string(nv) +
                          " (truncated file or wrong vertex count)");
      const char* s = cur_.position();
      const size_t line = cur_.line();
      if (!cur_.parse_float(xyz[a])) {
        cur_.set_position(s, line);
        return cur_.error("bad number " + quote(peek_token()) + " for the " + kAxis[a] + " of vertex " +
                          std::to_string(v));
      }
      if (!options_.allow_nonfinite && !std::isfinite(xyz[a]))
        return cur_.error("non-finite coordinate " +
                          quote(std::string_view(s, static_cast<size_t>(cur_.position() - s))) +
                          " (NaN or infinity); use --allow-nonfinite to accept it");
    }
    mesh.add_vertex(xyz[0], xyz[1], xyz[2]);
    // Normals, colours, texture coordinates on the rest of the line.
    read_extra(extra);
    const int fixed = (has_n_ ? 3 : 0) + (has_st_ ? 2 : 0);
    if (has_n_ || has_c_ || has_st_) {
      if (vertex_extras_ok_) {
        int colors = extra.count - fixed;
        if (v == 0) {
          vertex_first_line_ = cur_.line();
          color_count_ = colors;
        }
        const bool fits = !extra.other && (has_c_ ? (colors == 3 || colors == 4) && colors == color_count_ : colors == 0);
        if (!fits) {
          vertex_extras_ok_ = false;
          vertex_bad_line_ = cur_.line();
          normals_ = Values();
          colors_ = Values();
          texcoords_ = Values();
        } else {
          int at = 0;
          if (has_n_) {
            TSM_RETURN_IF_ERROR(add_values(normals_, extra, at, 3, false));
            at += 3;
          }
          if (has_c_) {
            TSM_RETURN_IF_ERROR(add_values(colors_, extra, at, colors, true));
            at += colors;
          }
          if (has_st_) TSM_RETURN_IF_ERROR(add_values(texcoords_, extra, at, 2, false));
        }
      }
    } else if (extra.count > 0 || extra.other) {
      if (unannounced_lines_++ == 0) unannounced_first_ = cur_.line();
    }
    cur_.next_line();
  }

  std::vector<uint32_t> corners;
  for (uint64_t f = 0; f < nf; ++f) {
    skip_space();
    if (cur_.at_end())
      return cur_.error("the file ends at face " + std::to_string(f) + " of " + std::to_string(nf) +
                        " (truncated file or wrong face count)");
    uint64_t n;
    TSM_RETURN_IF_ERROR(read_uint(n, "corner count"));
    if (n == 0) return cur_.error("face " + std::to_string(f) + " has 0 corners");
    // Each index takes at least 2 bytes (" 0").
    if (n > remaining() / 2)
      return cur_.error("face " + std::to_string(f) + " says it has " + std::to_string(n) + " corners but only " +
                        std::to_string(remaining()) + " bytes follow (truncated file?)");
    if (mesh.indices.size() + n > std::numeric_limits<uint32_t>::max())
      return Status(ErrorCode::limit_exceeded, cur_.name() + ": line " + std::to_string(cur_.line()) +
                                                   ": more than 4294967295 face corners in all");
    corners.clear();
    for (uint64_t k = 0; k < n; ++k) {
      uint64_t i;
      TSM_RETURN_IF_ERROR(read_uint(i, "vertex index"));
      if (i >= nv)
        return cur_.error("vertex index " + std::to_string(i) + " is out of range (the file has " +
                          std::to_string(nv) + " vertices, numbered from 0)");
      corners.push_back(static_cast<uint32_t>(i));
    }
    mesh.add_face(corners.data(), corners.size());
    // A face colour: 3 or 4 numbers on the rest of the line.
    read_extra(extra);
    const bool color = !extra.other && (extra.count == 3 || extra.count == 4);
    if (!color && (extra.count > 0 || extra.other)) {
      if (face_other_lines_++ == 0) face_other_first_ = cur_.line();
    }
    if (color) {
      if (face_line_with_ == 0) face_line_with_ = cur_.line();
      if (face_state_ == FaceColors::none ||
          (face_state_ == FaceColors::all && face_colors_.components != extra.count)) {
        if (face_line_without_ == 0) face_line_without_ = cur_.line();
        face_state_ = FaceColors::mixed;
        face_colors_ = Values();
      } else if (face_state_ != FaceColors::mixed) {
        face_state_ = FaceColors::all;
        TSM_RETURN_IF_ERROR(add_values(face_colors_, extra, 0, extra.count, true));
      }
    } else {
      if (face_line_without_ == 0) face_line_without_ = cur_.line();
      if (face_state_ == FaceColors::all) {
        face_state_ = FaceColors::mixed;
        face_colors_ = Values();
      } else if (face_state_ == FaceColors::unknown) {
        face_state_ = FaceColors::none;
      }
    }
    cur_.next_line();
  }
  finish(mesh, info);
  return Status::Ok();
}

}  // namespace

Status read_off(std::string_view bytes, const std::string& name, Mesh& out, const ReadOptions& options,
                ReadInfo* info) {
  if (info) {
    *info = ReadInfo();
    info->format = MeshFormat::off;
  }
  Mesh mesh;
  OffReader reader(bytes, name, options);
  Status st = reader.run(mesh, info);
  if (!st.ok()) {
    out.clear();
    return st;
  }
  out = std::move(mesh);
  return Status::Ok();
}

namespace {

// Shortest text that reads back to x; with `mark_float`, a ".0" is added to
// integer-looking text so that a colour reads back as f32, not u8.
char* put_number(char* p, char* end, float x, bool mark_float) {
  char* s = p;
  p = std::to_chars(p, end, x).ptr;
  if (mark_float) {
    bool plain = true;
    for (const char* q = s; q < p; ++q)
      if (!((*q >= '0' && *q <= '9') || *q == '-')) plain = false;
    if (plain) {
      *p++ = '.';
      *p++ = '0';
    }
  }
  return p;
}

}  // namespace

Status write_off(const Mesh& mesh, const WriteOptions& /*options*/, std::string& out, WriteInfo* info) {
  TSM_RETURN_IF_ERROR(check_faces_writable(mesh, "OFF"));
  // What OFF holds: one vertex normal, colour and texture coordinate pair,
  // and a face colour.
  const Attribute* nrm = nullptr;
  const Attribute* col = nullptr;
  const Attribute* tex = nullptr;
  const Attribute* fcol = nullptr;
  for (const Attribute& a : mesh.attributes) {
    if (a.domain == AttributeDomain::vertex) {
      if (!nrm && a.kind == AttributeKind::normal && a.components == 3) nrm = &a;
      if (!col && a.kind == AttributeKind::color && (a.components == 3 || a.components == 4)) col = &a;
      if (!tex && a.kind == AttributeKind::texcoord && a.components == 2) tex = &a;
    } else if (a.domain == AttributeDomain::face) {
      if (!fcol && a.kind == AttributeKind::color && (a.components == 3 || a.components == 4)) fcol = &a;
    }
  }
  if (info) {
    std::string dropped;
    for (const Attribute& a : mesh.attributes)
      if (&a != nrm && &a != col && &a != tex && &a != fcol) dropped += (dropped.empty() ? "" : ", ") + attribute_words(a);
    note_not_written(mesh, "OFF", dropped, nullptr, info);
  }

  out.clear();
  out.reserve(16 + mesh.vertex_count() * (36 + (nrm ? 36 : 0) + (col ? 24 : 0) + (tex ? 24 : 0)) +
              mesh.corner_count() * 8 + mesh.face_count() * (fcol ? 28 : 4));
  out += tex ? "ST" : "";
  out += col ? "C" : "";
  out += nrm ? "N" : "";
  out += "OFF\n";
  out += std::to_string(mesh.vertex_count()) + " " + std::to_string(mesh.face_count()) + " 0\n";
  char buf[512];
  char* const bend = buf + sizeof buf;
  // A colour's values: u8 as integers, u16 as 0..1 fractions, others (f32,
  // i32) as floats marked as such.
  auto put_color = [&](char* p, const Attribute& a, size_t item) {
    for (uint32_t c = 0; c < a.components; ++c) {
      *p++ = ' ';
      const float x = a.values[item * a.components + c];
      if (a.type == AttributeType::u8 && x >= 0.0f && x <= 255.0f && x == std::floor(x))
        p = std::to_chars(p, bend, static_cast<int>(x)).ptr;
      else if (a.type == AttributeType::u16)
        p = put_number(p, bend, static_cast<float>(static_cast<double>(x) / 65535.0), true);
      else
        p = put_number(p, bend, x, true);
    }
    return p;
  };
  auto put_values = [&](char* p, const Attribute& a, size_t item) {
    for (uint32_t c = 0; c < a.components; ++c) {
      *p++ = ' ';
      p = put_number(p, bend, a.values[item * a.components + c], false);
    }
    return p;
  };
  for (size_t v = 0; v < mesh.vertex_count(); ++v) {
    char* p = buf;
    for (int a = 0; a < 3; ++a) {
      if (a) *p++ = ' ';
      p = put_number(p, bend, mesh.positions[3 * v + static_cast<size_t>(a)], false);
    }
    if (nrm) p = put_values(p, *nrm, v);
    if (col) p = put_color(p, *col, v);
    if (tex) p = put_values(p, *tex, v);
    *p++ = '\n';
    out.append(buf, static_cast<size_t>(p - buf));
  }
  for (size_t f = 0; f < mesh.face_count(); ++f) {
    const uint32_t n = mesh.face_size(f);
    const uint32_t* c = mesh.face(f);
    out.append(buf, std::to_chars(buf, bend, n).ptr);
    for (uint32_t j = 0; j < n; ++j) {
      buf[0] = ' ';
      out.append(buf, std::to_chars(buf + 1, bend, c[j]).ptr);
    }
    if (fcol) out.append(buf, put_color(buf, *fcol, f));
    out += '\n';
  }
  return Status::Ok();
}

}  // namespace tsm

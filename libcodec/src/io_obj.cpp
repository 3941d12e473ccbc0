// Wavefront OBJ reading and writing (file-format stage, not part of the
// compression method): turns `v` and `f` records into a Mesh and back.
//
// Reader: one pass over the bytes with TextCursor and std::from_chars, no
// allocation per line. Positions are parsed straight to float (correctly
// rounded, no double-to-float double rounding). Faces are kept exactly as
// written: polygons of any size, faces of 1 or 2 corners, repeated corners.
// Vertices no face references are kept. Texture and normal indices in the
// `i/t`, `i//n` and `i/t/n` corner forms are checked for syntax and ignored
// for now; `vt`, `vn`, `vp`, grouping and material records are ignored;
// `l` and `p` records (lines and points) are skipped and counted; records
// with unknown keywords are skipped with a note. A backslash at the end of a
// line joins it with the next (except in comments).
//
// Index validation: index 0 is refused where it appears. Negative indices are
// relative to the vertices defined so far (-1 = the last one) and must land on
// one of them. Positive indices may point forward, at vertices defined later
// in the file (the OBJ spec does not forbid it and some writers do it), so
// they are checked once the whole file is read; the message names the line of
// the first face whose index is out of range and the final vertex count.
//
// Writer: `v x y z` with the shortest decimal text that reads back to the
// same float (std::to_chars), `f` lines with 1-based indices. Reading the
// result gives bit-identical positions and identical faces. (NaN payloads are
// the one exception: NaN is written as "nan" or "-nan".)
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <string_view>
#include <system_error>
#include <utility>
#include <vector>

#include "text_scan.hpp"
#include "tsm/io.hpp"

namespace tsm {

namespace {

constexpr size_t kMaxIndexableVertices = std::numeric_limits<uint32_t>::max();


bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\f' || c == '\v'; }
bool is_line_end(char c) { return c == '\n' || c == '\r'; }

class ObjReader {
 public:
  ObjReader(std::string_view bytes, const std::string& name, const ReadOptions& options)
      : cur_(bytes, name), end_(bytes.data() + bytes.size()), options_(options) {}

  Status run(Mesh& mesh, ReadInfo* info);

 private:
  // Skips blanks; a backslash followed only by blanks up to the line end
  // joins the next line.
  void skip_blanks_joined() {
    for (;;) {
      cur_.skip_blanks();
      const char* p = cur_.position();
      if (p >= end_ || *p != '\\') return;
      const char* q = p + 1;
      while (q < end_ && is_blank(*q)) ++q;
      if (q < end_ && !is_line_end(*q)) return;
      cur_.set_position(q, cur_.line());
      cur_.consume_line_end();
    }
  }
  // Moves past the rest of a record, following backslash continuations.
  void skip_record() {
    for (;;) {
      std::string_view rest = cur_.rest_of_line();
      size_t n = rest.size();
      while (n > 0 && is_blank(rest[n - 1])) --n;
      bool joined = n > 0 && rest[n - 1] == '\\';
      if (!cur_.consume_line_end() || !joined) return;
    }
  }
  // The blank-separated token at p (for messages).
  std::string_view token_at(const char* p) const {
    const char* q = p;
    while (q < end_ && !TextCursor::is_space(*q)) ++q;
    return std::string_view(p, static_cast<size_t>(q - p));
  }
  // End of the line's content: line end, end of text or a '#' comment.
  bool at_content_end() const {
    const char* p = cur_.position();
    return p >= end_ || is_line_end(*p) || *p == '#';
  }

  Status parse_vertex(Mesh& mesh);
  Status parse_face(Mesh& mesh);
  // Parses an optional-sign integer at p; returns the end or nullptr.
  const char* parse_index(const char* p, int64_t& v, bool& overflow) const {
    overflow = false;
    const char* s = p;
    if (s < end_ && *s == '+') ++s;
    auto r = std::from_chars(s, end_, v);
    if (r.ec == std::errc::result_out_of_range) {
      overflow = true;
      return r.ptr;
    }
    if (r.ec != std::errc()) return nullptr;
    return r.ptr;
  }
  Status limit_error(const char* what, size_t limit) const {
    return Status(ErrorCode::limit_exceeded, cur_.name() + ": line " + std::to_string(cur_.line()) +
                                                 ": more than " + std::to_string(limit) + " " + what +
                                                 " (the limit given for this read)");
  }

  TextCursor cur_;
  const char* end_;
  const ReadOptions& options_;
  std::vector<uint32_t> corners_;  // reused for every face
  // Faces holding a positive index beyond the vertices seen at that point:
  // (face number, line), checked at the end.
  std::vector<std::pair<size_t, size_t>> forward_faces_;
  size_t lines_ = 0, points_ = 0;
  std::vector<std::pair<std::string, size_t>> unknown_;  // first few unknown keywords
  size_t unknown_other_ = 0;
};

Status ObjReader::parse_vertex(Mesh& mesh) {
  static const char* const kAxis[3] = {"x", "y", "z"};
  float xyz[3];
  for (int a = 0; a < 3; ++a) {
    skip_blanks_joined();
    const char* s = cur_.position();
    size_t line = cur_.line();
    if (at_content_end())
      return cur_.error(std::string("vertex has no ") + kAxis[a] + " coordinate (expected 'v x y z')");
    if (!cur_.parse_float(xyz[a])) {
      cur_.set_position(s, line);
      return cur_.error(std::string("bad number ") + quote(token_at(s)) + " for the " + kAxis[a] +
                        " coordinate of a vertex");
    }
    if (!options_.allow_nonfinite && !std::isfinite(xyz[a]))
      return cur_.error("non-finite coordinate " + quote(std::string_view(s, cur_.position() - s)) +
                        " (NaN or infinity); use --allow-nonfinite to accept it");
  }
  const size_t n = mesh.vertex_count();
  if (options_.max_vertices != 0 && n >= options_.max_vertices) return limit_error("vertices", options_.max_vertices);
  if (n >= kMaxIndexableVertices) return limit_error("vertices", kMaxIndexableVertices);
  mesh.add_vertex(xyz[0], xyz[1], xyz[2]);
  skip_record();  // w, colours, comments
  return Status::Ok();
}

Status ObjReader::parse_face(Mesh& mesh) {
  corners_.clear();
  const size_t nv = mesh.vertex_count();
  bool forward = false;
  for (;;) {
    skip_blanks_joined();
    if (at_content_end()) break;
    const char* s = cur_.position();
    int64_t v = 0;
    bool overflow = false;
    const char* p = parse_index(s, v, overflow);
    if (!p) return cur_.error("bad vertex index " + quote(token_at(s)) + " in a face");
    if (overflow) return cur_.error("vertex index " + quote(token_at(s)) + " is out of range");
    // Optional /t, //n or /t/n: integers, checked for syntax only.
    if (p < end_ && *p == '/') {
      ++p;
      if (p < end_ && *p != '/' && !TextCursor::is_space(*p)) {
        int64_t t;
        p = parse_index(p, t, overflow);
        if (!p || overflow) return cur_.error("bad texture index in face corner " + quote(token_at(s)));
      }
      if (p < end_ && *p == '/') {
        ++p;
        int64_t nn;
        p = parse_index(p, nn, overflow);
        if (!p || overflow) return cur_.error("bad normal index in face corner " + quote(token_at(s)));
      }
    }
    if (p < end_ && !TextCursor::is_space(*p))
      return cur_.error("malformed face corner " + quote(token_at(s)) + " (expected i, i/t, i//n or i/t/n)");
    uint32_t index;
    if (v == 0) {
      return cur_.error("vertex index 0 in a face (OBJ indices start at 1; negative ones count back from the "
                        "last vertex)");
    } else if (v < 0) {
      // -1 is the last vertex defined so far.
      uint64_t back = static_cast<uint64_t>(-(v + 1)) + 1;
      if (back > nv)
        return cur_.error("relative vertex index " + std::to_string(v) + " reaches before the first vertex (" +
                          std::to_string(nv) + " vertices defined so far)");
      index = static_cast<uint32_t>(nv - back);
    } else {
      if (static_cast<uint64_t>(v) > kMaxIndexableVertices)
        return cur_.error("vertex index " + std::to_string(v) + " is out of range");
      index = static_cast<uint32_t>(v - 1);
      if (index >= nv) forward = true;
    }
    corners_.push_back(index);
    cur_.set_position(p, cur_.line());
  }
  if (corners_.empty()) return cur_.error("face with no vertex indices");
  const size_t f = mesh.face_count();
  if (options_.max_faces != 0 && f >= options_.max_faces) return limit_error("faces", options_.max_faces);
  if (mesh.indices.size() + corners_.size() > std::numeric_limits<uint32_t>::max())
    return limit_error("face corners in all", std::numeric_limits<uint32_t>::max());
  if (forward) forward_faces_.emplace_back(f, cur_.line());
  mesh.add_face(corners_.data(), corners_.size());
  skip_record();  // a trailing comment, the line end
  return Status::Ok();
}

Status ObjReader::run(Mesh& mesh, ReadInfo* info) {
  while (!cur_.at_end()) {
    cur_.skip_blanks();
    if (cur_.at_end()) break;
    const char c = *cur_.position();
    if (is_line_end(c)) {
      cur_.consume_line_end();
      continue;
    }
    if (c == '#') {
      cur_.next_line();
      continue;
    }
    const std::string_view key = cur_.token();
    if (key == "v") {
      TSM_RETURN_IF_ERROR(parse_vertex(mesh));
    } else if (key == "f") {
      TSM_RETURN_IF_ERROR(parse_face(mesh));
    } else if (key == "vt" || key == "vn" || key == "vp" || key == "o" || key == "g" || key == "s" ||
               key == "usemtl" || key == "mtllib" || key == "mg" || key == "usemap" || key == "maplib" ||
               key == "lod" || key == "bevel" || key == "c_interp" || key == "d_interp" ||
               key == "shadow_obj" || key == "trace_obj" || key == "ctech" || key == "stech") {
      skip_record();
    } else if (key == "l") {
      ++lines_;
      skip_record();
    } else if (key == "p") {
      ++points_;
      skip_record();
    } else {
      bool found = false;
      for (auto& u : unknown_)
        if (u.first == key) {
          ++u.second;
          found = true;
          break;
        }
      if (!found) {
        if (unknown_.size() < 8)
          unknown_.emplace_back(std::string(key), 1);
        else
          ++unknown_other_;
      }
      skip_record();
    }
  }

  // Positive indices were allowed to point forward; check them now.
  const size_t nv = mesh.vertex_count();
  for (const auto& ff : forward_faces_) {
    const uint32_t* c = mesh.face(ff.first);
    for (uint32_t i = 0; i < mesh.face_size(ff.first); ++i)
      if (c[i] >= nv)
        return Status(ErrorCode::parse_error,
                      cur_.name() + ": line " + std::to_string(ff.second) + ": vertex index " +
                          std::to_string(static_cast<uint64_t>(c[i]) + 1) + " is out of range (the file has " +
                          std::to_string(nv) + " vertices)");
  }

  if (info) {
    info->skipped_elements = lines_ + points_;
    std::string notes;
    auto add = [&](const std::string& s) {
      if (!notes.empty()) notes += "; ";
      notes += s;
    };
    if (lines_ + points_ > 0) {
      std::string s = "skipped ";
      if (lines_) s += std::to_string(lines_) + " 'l' records";
      if (lines_ && points_) s += " and ";
      if (points_) s += std::to_string(points_) + " 'p' records";
      add(s + " (lines and points are not faces)");
    }
    for (const auto& u : unknown_)
      add("skipped " + std::to_string(u.second) + " record" + (u.second == 1 ? "" : "s") +
          " with unknown keyword " + quote(u.first));
    if (unknown_other_) add("skipped " + std::to_string(unknown_other_) + " more records with other unknown keywords");
    info->notes = notes;
  }
  return Status::Ok();
}

char* put_float(char* p, char* end, float x) {
  auto r = std::to_chars(p, end, x);  // shortest text that reads back to x
  return r.ptr;
}

}  // namespace

Status read_obj(std::string_view bytes, const std::string& name, Mesh& out, const ReadOptions& options,
                ReadInfo* info) {
  if (info) {
    *info = ReadInfo();
    info->format = MeshFormat::obj;
    info->binary = false;
  }
  Mesh mesh;
  ObjReader reader(bytes, name, options);
  Status st = reader.run(mesh, info);
  if (!st.ok()) {
    out.clear();
    return st;
  }
  out = std::move(mesh);
  return Status::Ok();
}

Status write_obj(const Mesh& mesh, std::string& out) {
  std::string why;
  if (!mesh.valid(&why)) return Status(ErrorCode::invalid_argument, "cannot write OBJ: invalid mesh: " + why);
  for (size_t f = 0; f < mesh.face_count(); ++f)
    if (mesh.face_size(f) == 0)
      return Status(ErrorCode::invalid_argument,
                    "cannot write OBJ: face " + std::to_string(f) + " has no corners (OBJ cannot express it)");
  out.clear();
  out.reserve(mesh.vertex_count() * 36 + mesh.corner_count() * 8 + mesh.face_count() * 3 + 64);
  out += "# tsm: " + std::to_string(mesh.vertex_count()) + " vertices, " + std::to_string(mesh.face_count()) +
         " faces\n";
  char buf[128];
  char* const bend = buf + sizeof buf;
  const float* pos = mesh.positions.data();
  for (size_t v = 0; v < mesh.vertex_count(); ++v) {
    char* p = buf;
    *p++ = 'v';
    for (int a = 0; a < 3; ++a) {
      *p++ = ' ';
      p = put_float(p, bend, pos[3 * v + static_cast<size_t>(a)]);
    }
    *p++ = '\n';
    out.append(buf, static_cast<size_t>(p - buf));
  }
  for (size_t f = 0; f < mesh.face_count(); ++f) {
    const uint32_t* c = mesh.face(f);
    const uint32_t n = mesh.face_size(f);
    out.push_back('f');
    for (uint32_t i = 0; i < n; ++i) {
      char* p = buf;
      *p++ = ' ';
      p = std::to_chars(p, bend, static_cast<uint64_t>(c[i]) + 1).ptr;
      out.append(buf, static_cast<size_t>(p - buf));
    }
    out.push_back('\n');
  }
  return Status::Ok();
}

}  // namespace tsm

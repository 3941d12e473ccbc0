// Wavefront OBJ reading and writing (file-format stage, not part of the
// compression method): turns `v`, `vt`, `vn` and `f` records into a Mesh and
// back.
//
// Reader: one pass over the bytes with TextCursor and std::from_chars, no
// allocation per line. Positions are parsed straight to float (correctly
// rounded, no double-to-float double rounding). Faces are kept exactly as
// written: polygons of any size, faces of 1 or 2 corners, repeated corners.
// Vertices no face references are kept. `o`, `g`, `usemtl`, `s` and
// `mtllib` records are kept (below); `l` and `p` records (lines and points)
// are skipped and counted; `vp`, `mg`, map, level-of-detail and render
// records and records with unknown keywords are skipped with a note naming
// the keyword. A backslash at the end of a line joins it with the next
// (except in comments).
//
// Objects, groups, materials, smoothing groups: each kind of record the file
// has gives a face attribute ('obj:object', 'obj:group', 'obj:material',
// 'obj:smoothing', generic i32) numbering, per face, the text in force when
// the face was read among the distinct texts of that kind, in order of first
// appearance (left out when there is one text: every face has entry 0); the texts and the `mtllib` file names go into the metadata
// entry "obj" (format in io.hpp). The codec codes face attributes exactly
// and carries metadata through, so the faces' groups and materials survive
// encoding, whatever order the decoder gives the faces.
//
// Attributes (Mesh::attributes):
//  - `vt u [v [w]]` and `vn x y z` lists, named by the `i/t`, `i//n` and
//    `i/t/n` corner forms, become corner-domain attributes 'texcoord' (kind
//    texcoord, 2 components) and 'normal' (kind normal, 3), type f32, with
//    the file's value lists kept whole (file order, values no corner uses
//    included) and one index per corner. When some vt has a w other than 0,
//    the texture coordinates are kept whole as a generic corner attribute
//    'texcoord3' of 3 components (u, v, w) instead, and a note says so.
//  - OBJ lets some corners name a vt (or vn) and others not; Mesh has no
//    "none" value, so such a list cannot be kept: it is dropped with a note
//    naming a line of each kind (refusing the file would lose the whole
//    mesh). vt / vn lists no corner names are dropped with a note.
//  - `v x y z r g b` (exactly three numbers after x y z, a common extension)
//    on every `v` line gives a vertex 'color' attribute (kind color, f32, 3
//    components, the values as written). When only some `v` lines have them
//    they are dropped with a note; other trailing numbers (w) are ignored.
//  - vt / vn / colour values must be numbers (a missing u or a short vn is
//    an error naming the line); NaN and infinity are refused unless
//    ReadOptions::allow_nonfinite, as for positions. Indices follow the rules
//    of vertex indices below, checked (at the end, naming the line) only for
//    the lists that are kept.
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
// the one exception: NaN is written as "nan" or "-nan".) Attributes: the
// first texcoord attribute (or a 3-component 'texcoord3') becomes the `vt`
// list and the first normal attribute the `vn` list, written as `f v/t/n`,
// `v/t` or `v//n`: a corner-domain attribute with its value list as it is
// and its indices, a vertex-domain one with one value per vertex (indexed by
// the vertex), a face-domain one with one value per face. (They read back as
// corner-domain attributes with the same value at every corner.) The first
// vertex-domain colour is written as `v x y z r g b`: f32 values as they are,
// u8 / u16 ones scaled to 0..1 (v / 255, v / 65535; OBJ colours are 0..1),
// alpha dropped. Whatever OBJ cannot hold (other attributes, alpha) is named
// in a `# tsm: not written` comment line and in WriteInfo::notes, as are
// metadata entries other than "obj". The 'obj:*' face attributes become `o`,
// `g`, `usemtl` and `s` records written before each face whose entry differs
// from the one in force (the empty text as the bare keyword, `s off` for
// `s`), after `mtllib` lines at the top; faces keep the mesh's order. A mesh
// without attributes gives the same bytes as before attributes existed.
#include <array>
#include <charconv>
#include <cstddef>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <string_view>
#include <system_error>
#include <unordered_map>
#include <utility>
#include <vector>

#include "text_scan.hpp"
#include "tsm/io.hpp"
#include "write_notes.hpp"

namespace tsm {

namespace {

constexpr size_t kMaxIndexableVertices = std::numeric_limits<uint32_t>::max();


bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\f' || c == '\v'; }
bool is_line_end(char c) { return c == '\n' || c == '\r'; }

// One kind of OBJ state record (`o`, `g`, `usemtl` or `s`): the distinct
// texts in order of first appearance and, once a record of the kind has been
// seen, each face's entry. Faces before the first record have the empty
// text, as does a record with nothing after its keyword.
struct FaceLabels {
  const char* keyword;    // "o", "g", "usemtl", "s"
  const char* list;       // "object", "group", "material", "smoothing" (metadata lines, attribute names)
  std::vector<std::string> texts;
  std::unordered_map<std::string, uint32_t> index;
  std::vector<uint32_t> per_face;  // filled once `seen`
  uint32_t current = 0;            // entry of the state in force
  bool seen = false;
  bool current_set = false;        // false until a record (or a face) needs an entry

  uint32_t entry(const std::string& text) {
    auto it = index.find(text);
    if (it != index.end()) return it->second;
    const uint32_t k = static_cast<uint32_t>(texts.size());
    texts.push_back(text);
    index.emplace(text, k);
    return k;
  }
  // A record of this kind with `text`; `faces` were read before it.
  void record(const std::string& text, size_t faces) {
    if (!seen) {
      seen = true;
      // Faces so far had no record: the empty text, entry 0.
      if (faces > 0) per_face.assign(faces, entry(std::string()));
    }
    current = entry(text);
    current_set = true;
  }
  void face() {
    if (!seen) return;
    per_face.push_back(current);
  }
};

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

  // Which vt (or vn) each corner names, while every corner names one.
  struct CornerRefs {
    enum class State { unknown, all, none, mixed };
    CornerRefs(const char* w, const char* r) : what(w), record(r) {}
    const char* what;    // "texture", "normal"
    const char* record;  // "vt", "vn"
    State state = State::unknown;
    std::vector<uint32_t> index;  // per corner (state all)
    size_t line_with = 0, line_without = 0;  // a line of each kind (notes)
    size_t bad_line = 0;                     // first index that names no value
    std::string bad;
    // Faces with a positive index beyond the values seen at that point:
    // (first corner, corners, line), checked at the end.
    std::vector<std::array<size_t, 3>> forward;
  };
  struct Ref {
    bool has = false;
    int64_t raw = 0;
  };

  Status parse_vertex(Mesh& mesh);
  Status parse_face(Mesh& mesh);
  // The text of an `o`, `g`, `usemtl`, `s` or `mtllib` record: the rest of
  // the line (joined lines with a blank between), blanks around it and a
  // comment that follows a blank removed.
  std::string record_text();
  void finish_labels(Mesh& mesh, std::vector<std::string>& notes);
  Status parse_values(const char* record, int min, int max, float* out, int& got);
  Status parse_texcoord();
  Status parse_normal();
  void commit_refs(CornerRefs& r, const std::vector<Ref>& refs, size_t first_corner, size_t count);
  Status check_refs(const CornerRefs& r, size_t count) const;
  void finish_attributes(Mesh& mesh, std::vector<std::string>& notes);
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
  std::vector<std::pair<std::string, size_t>> ignored_;  // known keywords tsm does not keep

  // Object, group, material and smoothing group of each face; mtllib texts.
  FaceLabels labels_[4] = {{"o", "object", {}, {}, {}, 0, false, false},
                           {"g", "group", {}, {}, {}, 0, false, false},
                           {"usemtl", "material", {}, {}, {}, 0, false, false},
                           {"s", "smoothing", {}, {}, {}, 0, false, false}};
  std::vector<std::string> mtllibs_;

  std::vector<float> vt_;  // u, v, w of each vt
  bool vt_w_ = false;      // some w is not 0
  std::vector<float> vn_;  // x, y, z of each vn
  CornerRefs vt_refs_{"texture", "vt"};
  CornerRefs vn_refs_{"normal", "vn"};
  std::vector<Ref> face_t_, face_n_;  // reused for every face
  // Vertex colours: every v line so far has r g b (state all) or none has.
  CornerRefs::State color_state_ = CornerRefs::State::unknown;
  size_t color_line_with_ = 0, color_line_without_ = 0;
  std::vector<float> colors_;
};

// Numbers after a vt / vn keyword: at least min, at most max (more are ignored).
Status ObjReader::parse_values(const char* record, int min, int max, float* out, int& got) {
  static const char* const kNames[2][3] = {{"u", "v", "w"}, {"x", "y", "z"}};
  const bool tex = record[1] == 't';
  got = 0;
  for (int a = 0; a < max; ++a) {
    skip_blanks_joined();
    if (at_content_end()) break;
    const char* s = cur_.position();
    const size_t line = cur_.line();
    if (!cur_.parse_float(out[a])) {
      cur_.set_position(s, line);
      return cur_.error(std::string("bad number ") + quote(token_at(s)) + " for the " + kNames[tex ? 0 : 1][a] +
                        " of a '" + record + "' record");
    }
    if (!options_.allow_nonfinite && !std::isfinite(out[a]))
      return cur_.error(std::string("non-finite ") + (tex ? "texture coordinate " : "normal component ") +
                        quote(std::string_view(s, static_cast<size_t>(cur_.position() - s))) +
                        " (NaN or infinity); use --allow-nonfinite to accept it");
    ++got;
  }
  if (got < min)
    return cur_.error(std::string("'") + record + "' record has no " + kNames[tex ? 0 : 1][got] + " value (expected " +
                      (tex ? "'vt u [v [w]]'" : "'vn x y z'") + ")");
  return Status::Ok();
}

Status ObjReader::parse_texcoord() {
  float uvw[3] = {0, 0, 0};
  int got;
  TSM_RETURN_IF_ERROR(parse_values("vt", 1, 3, uvw, got));
  if (vt_.size() / 3 >= kMaxIndexableVertices) return limit_error("texture coordinates", kMaxIndexableVertices);
  if (uvw[2] != 0.0f) vt_w_ = true;
  vt_.insert(vt_.end(), uvw, uvw + 3);
  skip_record();
  return Status::Ok();
}

Status ObjReader::parse_normal() {
  float xyz[3];
  int got;
  TSM_RETURN_IF_ERROR(parse_values("vn", 3, 3, xyz, got));
  if (vn_.size() / 3 >= kMaxIndexableVertices) return limit_error("normals", kMaxIndexableVertices);
  vn_.insert(vn_.end(), xyz, xyz + 3);
  skip_record();
  return Status::Ok();
}

// Records the vt (vn) indices of one accepted face of `count` corners.
void ObjReader::commit_refs(CornerRefs& r, const std::vector<Ref>& refs, size_t first_corner, size_t count) {
  using State = CornerRefs::State;
  const size_t line = cur_.line();
  bool forward = false;
  for (const Ref& ref : refs) {
    if (r.state == State::mixed) return;
    if (!ref.has) {
      if (r.line_without == 0) r.line_without = line;
      if (r.state == State::all) {
        r.state = State::mixed;
        r.index.clear();
        r.index.shrink_to_fit();
        r.forward.clear();
        return;
      }
      r.state = State::none;
      continue;
    }
    if (r.line_with == 0) r.line_with = line;
    if (r.state == State::none) {
      r.state = State::mixed;
      return;
    }
    r.state = State::all;
    // Resolve like a vertex index; problems are reported only if the list is kept.
    uint32_t index = 0;
    if (ref.raw == 0) {
      if (r.bad.empty()) {
        r.bad_line = line;
        r.bad = std::string(r.what) + " index 0 in a face (OBJ indices start at 1; negative ones count back from the "
                                      "last '" + r.record + "')";
      }
    } else if (ref.raw < 0) {
      const uint64_t back = static_cast<uint64_t>(-(ref.raw + 1)) + 1;
      if (back > count) {
        if (r.bad.empty()) {
          r.bad_line = line;
          r.bad = "relative " + std::string(r.what) + " index " + std::to_string(ref.raw) + " reaches before the first '" +
                  r.record + "' (" + std::to_string(count) + " defined so far)";
        }
      } else {
        index = static_cast<uint32_t>(count - back);
      }
    } else if (static_cast<uint64_t>(ref.raw) > kMaxIndexableVertices) {
      if (r.bad.empty()) {
        r.bad_line = line;
        r.bad = std::string(r.what) + " index " + std::to_string(ref.raw) + " is out of range";
      }
    } else {
      index = static_cast<uint32_t>(ref.raw - 1);
      if (index >= count) forward = true;
    }
    r.index.push_back(index);
  }
  if (forward) r.forward.push_back({first_corner, refs.size(), line});
}

// A list that is kept: every index must name one of its `count` values.
Status ObjReader::check_refs(const CornerRefs& r, size_t count) const {
  if (!r.bad.empty())
    return Status(ErrorCode::parse_error, cur_.name() + ": line " + std::to_string(r.bad_line) + ": " + r.bad);
  for (const auto& fw : r.forward)
    for (size_t c = fw[0]; c < fw[0] + fw[1]; ++c)
      if (r.index[c] >= count)
        return Status(ErrorCode::parse_error,
                      cur_.name() + ": line " + std::to_string(fw[2]) + ": " + r.what + " index " +
                          std::to_string(static_cast<uint64_t>(r.index[c]) + 1) + " is out of range (the file has " +
                          std::to_string(count) + " '" + r.record + "' records)");
  return Status::Ok();
}

void ObjReader::finish_attributes(Mesh& mesh, std::vector<std::string>& notes) {
  using State = CornerRefs::State;
  if (color_state_ == State::all && !colors_.empty()) {
    Attribute a;
    a.name = "color";
    a.kind = AttributeKind::color;
    a.domain = AttributeDomain::vertex;
    a.components = 3;
    a.values = std::move(colors_);
    mesh.attributes.push_back(std::move(a));
  } else if (color_state_ == State::mixed) {
    notes.push_back("ignored the vertex colours: line " + std::to_string(color_line_with_) +
                    " has 'v x y z r g b' but line " + std::to_string(color_line_without_) +
                    " has no colour (kept only when every vertex has one)");
  }
  struct List {
    CornerRefs* refs;
    std::vector<float>* values;
  };
  for (List l : {List{&vt_refs_, &vt_}, List{&vn_refs_, &vn_}}) {
    CornerRefs& r = *l.refs;
    const size_t count = l.values->size() / 3;
    if (r.state == State::all) {
      Attribute a;
      a.domain = AttributeDomain::corner;
      if (l.refs == &vn_refs_) {
        a.name = "normal";
        a.kind = AttributeKind::normal;
        a.components = 3;
        a.values = std::move(*l.values);
      } else if (vt_w_) {
        a.name = "texcoord3";
        a.components = 3;
        a.values = std::move(*l.values);
        notes.push_back("texture coordinates with a w other than 0: kept as the generic 3-component corner "
                        "attribute 'texcoord3' (u, v, w)");
      } else {
        a.name = "texcoord";
        a.kind = AttributeKind::texcoord;
        a.components = 2;
        a.values.resize(2 * count);
        for (size_t i = 0; i < count; ++i) {
          a.values[2 * i] = (*l.values)[3 * i];
          a.values[2 * i + 1] = (*l.values)[3 * i + 1];
        }
      }
      a.indices = std::move(r.index);
      mesh.attributes.push_back(std::move(a));
    } else if (r.state == State::mixed) {
      notes.push_back(std::string("ignored the ") + r.what + " indices and '" + r.record + "' records: line " +
                      std::to_string(r.line_with) + " has a face corner with a " + r.what + " index but line " +
                      std::to_string(r.line_without) + " has one without (kept only when every corner has one)");
    } else if (count > 0) {
      notes.push_back("ignored " + std::to_string(count) + " '" + r.record + "' record" + (count == 1 ? "" : "s") +
                      " (no face corner uses them)");
    }
  }
}

std::string ObjReader::record_text() {
  std::string text;
  for (;;) {
    cur_.skip_blanks();
    std::string_view rest = cur_.rest_of_line();
    // A '#' after a blank (or at the start) begins a comment; inside a
    // name ("mat#2") it is part of it.
    bool comment = false;
    for (size_t i = 0; i < rest.size() && !comment; ++i)
      if (rest[i] == '#' && (i == 0 || is_blank(rest[i - 1]))) {
        rest = rest.substr(0, i);
        comment = true;
      }
    size_t n = rest.size();
    while (n > 0 && is_blank(rest[n - 1])) --n;
    const bool joined = !comment && n > 0 && rest[n - 1] == '\\';
    if (joined) --n;
    while (n > 0 && is_blank(rest[n - 1])) --n;
    if (!text.empty() && n > 0) text += ' ';
    text.append(rest.data(), n);
    if (!cur_.consume_line_end() || !joined) break;
  }
  return text;
}

// Per-face integer attributes 'obj:object', 'obj:group', 'obj:material',
// 'obj:smoothing' for the kinds of record the file has, and the texts they
// index in the metadata entry "obj" (see io.hpp).
void ObjReader::finish_labels(Mesh& mesh, std::vector<std::string>& notes) {
  std::string meta;
  for (const std::string& t : mtllibs_) meta += "mtllib " + t + "\n";
  const size_t nf = mesh.face_count();
  for (FaceLabels& l : labels_) {
    if (!l.seen) continue;
    for (const std::string& t : l.texts) meta += std::string(l.list) + " " + t + "\n";
    // One text: every face has entry 0, which the list alone says.
    if (nf == 0 || l.texts.size() == 1) continue;
    // Entries are stored as floats: exact up to 2^24.
    if (l.texts.size() > (size_t{1} << 24)) {
      notes.push_back("dropped which '" + std::string(l.keyword) + "' record each face belongs to: " +
                      std::to_string(l.texts.size()) + " distinct ones are more than tsm can number (2^24)");
      continue;
    }
    Attribute a;
    a.name = std::string("obj:") + l.list;
    a.kind = AttributeKind::generic;
    a.domain = AttributeDomain::face;
    a.type = AttributeType::i32;
    a.components = 1;
    a.values.assign(l.per_face.begin(), l.per_face.end());
    mesh.attributes.push_back(std::move(a));
  }
  if (!meta.empty()) mesh.metadata.push_back({"obj", std::move(meta)});
}

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
  // Exactly three more numbers: r g b (a common extension). Anything else
  // after x y z (a w, text) is ignored as before.
  using State = CornerRefs::State;
  float rgb[3] = {0, 0, 0};
  int extra = 0;
  bool other = false;
  const char* first_extra = nullptr;
  for (;;) {
    skip_blanks_joined();
    if (at_content_end()) break;
    if (!first_extra) first_extra = cur_.position();
    float x;
    if (extra == 3 || !cur_.parse_float(x)) {
      other = true;
      break;
    }
    rgb[extra++] = x;
  }
  const bool has_color = extra == 3 && !other;
  if (has_color) {
    if (!options_.allow_nonfinite && !(std::isfinite(rgb[0]) && std::isfinite(rgb[1]) && std::isfinite(rgb[2])))
      return cur_.error("non-finite vertex colour " +
                        quote(std::string_view(first_extra, static_cast<size_t>(cur_.position() - first_extra))) +
                        " (NaN or infinity); use --allow-nonfinite to accept it");
    if (color_line_with_ == 0) color_line_with_ = cur_.line();
    if (color_state_ == State::none) {
      color_state_ = State::mixed;
    } else if (color_state_ != State::mixed) {
      color_state_ = State::all;
      colors_.insert(colors_.end(), rgb, rgb + 3);
    }
  } else {
    if (color_line_without_ == 0) color_line_without_ = cur_.line();
    if (color_state_ == State::all) {
      color_state_ = State::mixed;
      colors_.clear();
      colors_.shrink_to_fit();
    } else if (color_state_ == State::unknown) {
      color_state_ = State::none;
    }
  }
  mesh.add_vertex(xyz[0], xyz[1], xyz[2]);
  skip_record();  // w, comments
  return Status::Ok();
}

Status ObjReader::parse_face(Mesh& mesh) {
  corners_.clear();
  face_t_.clear();
  face_n_.clear();
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
    // Optional /t, //n or /t/n (resolved once the face is accepted).
    Ref t, nn;
    if (p < end_ && *p == '/') {
      ++p;
      if (p < end_ && *p != '/' && !TextCursor::is_space(*p)) {
        p = parse_index(p, t.raw, overflow);
        if (!p || overflow) return cur_.error("bad texture index in face corner " + quote(token_at(s)));
        t.has = true;
      }
      if (p < end_ && *p == '/') {
        ++p;
        p = parse_index(p, nn.raw, overflow);
        if (!p || overflow) return cur_.error("bad normal index in face corner " + quote(token_at(s)));
        nn.has = true;
      }
    }
    face_t_.push_back(t);
    face_n_.push_back(nn);
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
  commit_refs(vt_refs_, face_t_, mesh.indices.size(), vt_.size() / 3);
  commit_refs(vn_refs_, face_n_, mesh.indices.size(), vn_.size() / 3);
  mesh.add_face(corners_.data(), corners_.size());
  for (FaceLabels& l : labels_) l.face();
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
    } else if (key == "vt") {
      TSM_RETURN_IF_ERROR(parse_texcoord());
    } else if (key == "vn") {
      TSM_RETURN_IF_ERROR(parse_normal());
    } else if (key == "o" || key == "g" || key == "usemtl" || key == "s") {
      const size_t k = key == "o" ? 0 : key == "g" ? 1 : key == "usemtl" ? 2 : 3;
      labels_[k].record(record_text(), mesh.face_count());
    } else if (key == "mtllib") {
      mtllibs_.push_back(record_text());
    } else if (key == "vp" || key == "mg" || key == "usemap" || key == "maplib" || key == "lod" ||
               key == "bevel" || key == "c_interp" || key == "d_interp" || key == "shadow_obj" ||
               key == "trace_obj" || key == "ctech" || key == "stech") {
      bool found = false;
      for (auto& u : ignored_)
        if (u.first == key) {
          ++u.second;
          found = true;
          break;
        }
      if (!found) ignored_.emplace_back(std::string(key), 1);
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

  // vt / vn indices of the lists that are kept.
  if (vt_refs_.state == CornerRefs::State::all) TSM_RETURN_IF_ERROR(check_refs(vt_refs_, vt_.size() / 3));
  if (vn_refs_.state == CornerRefs::State::all) TSM_RETURN_IF_ERROR(check_refs(vn_refs_, vn_.size() / 3));
  std::vector<std::string> attribute_notes;
  finish_attributes(mesh, attribute_notes);
  finish_labels(mesh, attribute_notes);

  if (info) {
    info->skipped_elements = lines_ + points_;
    info->notes.clear();
    auto add = [&](const std::string& s) { info->add_note(s); };
    for (const std::string& n : attribute_notes) add(n);
    if (lines_ + points_ > 0) {
      std::string s = "skipped ";
      if (lines_) s += std::to_string(lines_) + " 'l' records";
      if (lines_ && points_) s += " and ";
      if (points_) s += std::to_string(points_) + " 'p' records";
      add(s + " (lines and points are not faces)");
    }
    for (const auto& u : ignored_)
      add("skipped " + std::to_string(u.second) + " " + quote(u.first) + " record" + (u.second == 1 ? "" : "s") +
          " (parameter-space vertices, merging, maps, display and render settings are not kept)");
    for (const auto& u : unknown_)
      add("skipped " + std::to_string(u.second) + " record" + (u.second == 1 ? "" : "s") +
          " with unknown keyword " + quote(u.first));
    if (unknown_other_) add("skipped " + std::to_string(unknown_other_) + " more records with other unknown keywords");
  }
  return Status::Ok();
}

char* put_float(char* p, char* end, float x) {
  auto r = std::to_chars(p, end, x);  // shortest text that reads back to x
  return r.ptr;
}

// The 'obj:*' face attributes and the texts of the "obj" metadata entry
// (see io.hpp) that the writer turns back into records.
struct LabelsOut {
  static constexpr const char* kLists[4] = {"object", "group", "material", "smoothing"};
  static constexpr const char* kKeywords[4] = {"o", "g", "usemtl", "s"};
  const Attribute* attr[4] = {nullptr, nullptr, nullptr, nullptr};
  bool single[4] = {false, false, false, false};  // no attribute, one text: every face has entry 0
  std::vector<std::string> texts[4];
  std::vector<std::string> mtllibs;

  // The attribute a writer uses for list k: face domain, one component,
  // entry numbers (integers 0..2^24).
  static bool usable(const Attribute& a) {
    if (a.domain != AttributeDomain::face || a.components != 1) return false;
    for (float x : a.values)
      if (!(x >= 0.0f && x <= 16777216.0f) || x != std::floor(x)) return false;
    return true;
  }
  void find(const Mesh& mesh) {
    for (const Attribute& a : mesh.attributes)
      for (int k = 0; k < 4; ++k)
        if (!attr[k] && a.name == std::string("obj:") + kLists[k] && usable(a)) attr[k] = &a;
    const MetadataEntry* e = mesh.find_metadata("obj");
    if (!e) return;
    // Lines "LIST TEXT"; anything else is skipped (a newer writer's items).
    std::string_view v = e->value;
    while (!v.empty()) {
      const size_t eol = v.find('\n');
      std::string_view line = v.substr(0, eol);
      v = eol == std::string_view::npos ? std::string_view() : v.substr(eol + 1);
      const size_t sp = line.find(' ');
      const std::string_view key = line.substr(0, sp);
      const std::string_view text = sp == std::string_view::npos ? std::string_view() : line.substr(sp + 1);
      if (key == "mtllib") mtllibs.emplace_back(text);
      for (int k = 0; k < 4; ++k)
        if (key == kLists[k]) texts[k].emplace_back(text);
    }
    for (int k = 0; k < 4; ++k) single[k] = !attr[k] && texts[k].size() == 1;
  }
  // The text of entry n of list k; entries the metadata lacks get a made-up
  // name ("group7"), so faces stay apart.
  std::string text(int k, size_t n) const {
    std::string t = n < texts[k].size() ? texts[k][n] : std::string(k == 3 ? "" : kLists[k]) + std::to_string(n);
    return one_line(std::move(t));
  }
  // A record's text as a line can hold it: line ends become blanks, and a
  // backslash at the end (which would join the next line) is dropped.
  static std::string one_line(std::string t) {
    for (char& c : t)
      if (c == '\n' || c == '\r') c = ' ';
    while (!t.empty() && (t.back() == '\\' || t.back() == ' ' || t.back() == '\t')) t.pop_back();
    return t;
  }
};

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

bool drop_obj_face_labels(Mesh& mesh, WriteInfo* info) {
  std::string list;
  auto& attrs = mesh.attributes;
  for (size_t k = 0; k < attrs.size();) {
    if (attrs[k].domain == AttributeDomain::face && attrs[k].name.compare(0, 4, "obj:") == 0) {
      list += (list.empty() ? "'" : ", '") + attrs[k].name + "'";
      attrs.erase(attrs.begin() + static_cast<std::ptrdiff_t>(k));
    } else {
      ++k;
    }
  }
  if (list.empty()) return false;
  for (char& c : list)
    if (c == '\n' || c == '\r') c = ' ';
  if (info)
    info->add_note("glTF cannot hold the OBJ object, group, material and smoothing group of each face (face "
                   "attributes " + list + "); not written (decode to .obj to keep them)");
  return true;
}

Status write_obj(const Mesh& mesh, std::string& out, WriteInfo* info) {
  TSM_RETURN_IF_ERROR(check_faces_writable(mesh, "OBJ"));
  // What OBJ can hold: one vt list, one vn list, r g b per vertex, and the
  // object, group, material and smoothing group of each face.
  const Attribute* tex = nullptr;
  const Attribute* nrm = nullptr;
  const Attribute* col = nullptr;
  for (const Attribute& a : mesh.attributes)
    if (!tex && a.kind == AttributeKind::texcoord) tex = &a;
  for (const Attribute& a : mesh.attributes)
    if (!tex && a.kind == AttributeKind::generic && a.name == "texcoord3" && a.components == 3) tex = &a;
  for (const Attribute& a : mesh.attributes) {
    if (!nrm && a.kind == AttributeKind::normal) nrm = &a;
    if (!col && a.kind == AttributeKind::color && a.domain == AttributeDomain::vertex) col = &a;
  }
  LabelsOut labels;
  labels.find(mesh);
  bool any_labels = false;
  for (int k = 0; k < 4; ++k) any_labels = any_labels || labels.attr[k] || labels.single[k];
  std::string dropped;
  for (size_t k = 0; k < mesh.attributes.size(); ++k) {
    const Attribute& a = mesh.attributes[k];
    if (&a == tex || &a == nrm || (&a == col && a.components == 3)) continue;
    if (&a == labels.attr[0] || &a == labels.attr[1] || &a == labels.attr[2] || &a == labels.attr[3]) continue;
    dropped += dropped.empty() ? "" : ", ";
    dropped += &a == col ? "the alpha of " : "";
    dropped += attribute_words(a);
  }
  note_not_written(mesh, "OBJ", dropped, "obj", info);

  out.clear();
  out.reserve(mesh.vertex_count() * (col ? 60 : 36) + mesh.corner_count() * (tex || nrm ? 20 : 8) +
              mesh.face_count() * 3 + 64);
  out += "# tsm: " + std::to_string(mesh.vertex_count()) + " vertices, " + std::to_string(mesh.face_count()) +
         " faces\n";
  // attribute_words keeps names on one line.
  if (!dropped.empty()) out += "# tsm: not written (OBJ cannot hold them): " + dropped + "\n";
  for (const std::string& m : labels.mtllibs) out += "mtllib " + LabelsOut::one_line(m) + "\n";
  char buf[256];
  char* const bend = buf + sizeof buf;
  const float* pos = mesh.positions.data();
  // OBJ colours are 0..1: integer types are scaled.
  const float col_scale = !col                               ? 1.0f
                          : col->type == AttributeType::u8  ? 255.0f
                          : col->type == AttributeType::u16 ? 65535.0f
                                                            : 1.0f;
  for (size_t v = 0; v < mesh.vertex_count(); ++v) {
    char* p = buf;
    *p++ = 'v';
    for (int a = 0; a < 3; ++a) {
      *p++ = ' ';
      p = put_float(p, bend, pos[3 * v + static_cast<size_t>(a)]);
    }
    if (col) {
      for (uint32_t a = 0; a < 3; ++a) {
        *p++ = ' ';
        const float x = col->values[v * col->components + a];
        p = put_float(p, bend, col_scale == 1.0f ? x : static_cast<float>(static_cast<double>(x) / col_scale));
      }
    }
    *p++ = '\n';
    out.append(buf, static_cast<size_t>(p - buf));
  }
  auto put_list = [&](const Attribute* a, const char* key) {
    if (!a) return;
    const size_t n = a->value_count();
    for (size_t i = 0; i < n; ++i) {
      char* p = buf;
      for (const char* k = key; *k; ++k) *p++ = *k;
      for (uint32_t c = 0; c < a->components; ++c) {
        *p++ = ' ';
        p = put_float(p, bend, a->values[i * a->components + c]);
      }
      *p++ = '\n';
      out.append(buf, static_cast<size_t>(p - buf));
    }
  };
  put_list(tex, "vt");
  put_list(nrm, "vn");
  // The value a vt / vn list gives corner c (of face f, vertex v), 1-based.
  auto ref = [](const Attribute* a, size_t c, size_t f, uint32_t v) -> uint64_t {
    switch (a->domain) {
      case AttributeDomain::vertex: return static_cast<uint64_t>(v) + 1;
      case AttributeDomain::face: return static_cast<uint64_t>(f) + 1;
      case AttributeDomain::corner: break;
    }
    return static_cast<uint64_t>(a->indices[c]) + 1;
  };
  // The entry of each label list in force in the written file (none yet:
  // the empty text, which is what faces before a first record have).
  size_t written[4] = {SIZE_MAX, SIZE_MAX, SIZE_MAX, SIZE_MAX};
  std::string written_text[4];
  for (size_t f = 0; f < mesh.face_count(); ++f) {
    if (any_labels) {
      for (int k = 0; k < 4; ++k) {
        if (!labels.attr[k] && !labels.single[k]) continue;
        const size_t entry = labels.attr[k] ? static_cast<size_t>(labels.attr[k]->values[f]) : 0;
        if (entry == written[k]) continue;
        written[k] = entry;
        std::string t = labels.text(k, entry);
        if (t == written_text[k]) continue;
        written_text[k] = t;
        out += LabelsOut::kKeywords[k];
        if (!t.empty()) {
          out += ' ';
          out += t;
        } else if (k == 3) {
          out += " off";  // `s` needs a value; no smoothing group is what off means
        }
        out += '\n';
      }
    }
    const uint32_t* c = mesh.face(f);
    const uint32_t n = mesh.face_size(f);
    const size_t first = mesh.face_offsets[f];
    out.push_back('f');
    for (uint32_t i = 0; i < n; ++i) {
      char* p = buf;
      *p++ = ' ';
      p = std::to_chars(p, bend, static_cast<uint64_t>(c[i]) + 1).ptr;
      if (tex || nrm) {
        *p++ = '/';
        if (tex) p = std::to_chars(p, bend, ref(tex, first + i, f, c[i])).ptr;
        if (nrm) {
          *p++ = '/';
          p = std::to_chars(p, bend, ref(nrm, first + i, f, c[i])).ptr;
        }
      }
      out.append(buf, static_cast<size_t>(p - buf));
    }
    out.push_back('\n');
  }
  return Status::Ok();
}

}  // namespace tsm

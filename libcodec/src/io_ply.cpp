// PLY reader and writer (file-format stage, not part of the Topological
// Surgery method itself): turns a PLY file (ascii, binary little or big
// endian) into a tsm::Mesh and back.
//
// Reading keeps exactly what the file holds: x, y, z of the 'vertex' element
// (any scalar type, stored as float) and the polygons of the 'face' element's
// 'vertex_indices' (or 'vertex_index') list, in file order, with degenerate
// faces and unreferenced vertices kept. Every other element and property is
// skipped. Topology is not checked here; that is the codec's job.
//
// Robustness: every count in the header is checked against the bytes that
// follow before anything is reserved, all binary reads go through memcpy or
// byte assembly (no misaligned loads), and every read is bounds-checked, so
// no input can crash the reader or make it allocate more than a small
// multiple of the input size.
//
// Writing: binary little endian (float x y z, 'list uchar uint' faces, or
// 'list uint uint' when a face has more than 255 corners), or ascii with
// shortest round-trip floats, so that both forms read back bit-identically.
#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

#include "text_scan.hpp"
#include "tsm/io.hpp"

namespace tsm {

namespace {

constexpr bool kHostLittleEndian = __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__;
constexpr uint64_t kMaxIndex = std::numeric_limits<uint32_t>::max();

// ---------------------------------------------------------------------------
// Types and header model

enum class PlyType : uint8_t { i8, u8, i16, u16, i32, u32, f32, f64 };

size_t type_size(PlyType t) {
  switch (t) {
    case PlyType::i8:
    case PlyType::u8: return 1;
    case PlyType::i16:
    case PlyType::u16: return 2;
    case PlyType::i32:
    case PlyType::u32:
    case PlyType::f32: return 4;
    case PlyType::f64: return 8;
  }
  return 1;
}

bool is_integer(PlyType t) { return t != PlyType::f32 && t != PlyType::f64; }

bool type_from_name(std::string_view s, PlyType& t) {
  static const struct {
    const char* name;
    PlyType type;
  } kTypes[] = {
      {"char", PlyType::i8},     {"int8", PlyType::i8},     {"uchar", PlyType::u8},
      {"uint8", PlyType::u8},    {"short", PlyType::i16},   {"int16", PlyType::i16},
      {"ushort", PlyType::u16},  {"uint16", PlyType::u16},  {"int", PlyType::i32},
      {"int32", PlyType::i32},   {"uint", PlyType::u32},    {"uint32", PlyType::u32},
      {"float", PlyType::f32},   {"float32", PlyType::f32}, {"double", PlyType::f64},
      {"float64", PlyType::f64},
  };
  for (const auto& k : kTypes)
    if (s == k.name) {
      t = k.type;
      return true;
    }
  return false;
}

struct Property {
  std::string name;
  bool list = false;
  PlyType type = PlyType::u8;        // scalar type, or item type of a list
  PlyType count_type = PlyType::u8;  // lists only
};

struct Element {
  std::string name;
  uint64_t count = 0;
  size_t line = 0;  // header line that declares it
  std::vector<Property> props;

  // Fewest bytes one item can take in a binary body (lists may be empty).
  uint64_t min_binary_size() const {
    uint64_t n = 0;
    for (const Property& p : props) n += type_size(p.list ? p.count_type : p.type);
    return n;
  }
  bool fixed_size() const {
    for (const Property& p : props)
      if (p.list) return false;
    return true;
  }
};

enum class Encoding { ascii, binary_le, binary_be };

// Short, printable form of a token for messages.
std::string quoted(std::string_view s) {
  std::string r = "'";
  for (char c : s.substr(0, 40)) r += (static_cast<unsigned char>(c) < 32 || c == 127) ? '?' : c;
  if (s.size() > 40) r += "...";
  return r + "'";
}

// ---------------------------------------------------------------------------
// Binary loads (endian-explicit byte assembly; compilers turn these into a
// single load, and nothing is ever read through a misaligned pointer).

template <size_t N>
uint64_t load_uint(const unsigned char* p, bool big) {
  uint64_t v = 0;
  if (big) {
    for (size_t i = 0; i < N; ++i) v = (v << 8) | p[i];
  } else {
    for (size_t i = 0; i < N; ++i) v |= static_cast<uint64_t>(p[i]) << (8 * i);
  }
  return v;
}

// Integer types only.
int64_t load_int(PlyType t, const unsigned char* p, bool big) {
  switch (t) {
    case PlyType::i8: return static_cast<int8_t>(p[0]);
    case PlyType::u8: return p[0];
    case PlyType::i16: return static_cast<int16_t>(static_cast<uint16_t>(load_uint<2>(p, big)));
    case PlyType::u16: return static_cast<int64_t>(load_uint<2>(p, big));
    case PlyType::i32: return static_cast<int32_t>(static_cast<uint32_t>(load_uint<4>(p, big)));
    case PlyType::u32: return static_cast<int64_t>(load_uint<4>(p, big));
    case PlyType::f32:
    case PlyType::f64: break;
  }
  return 0;
}

// double -> float without the undefined behaviour of an out-of-range cast:
// values beyond the float range round to +-FLT_MAX or +-inf as IEEE does.
float to_float(double d) {
  constexpr double kMax = static_cast<double>(std::numeric_limits<float>::max());
  if (std::isfinite(d) && std::fabs(d) > kMax) {
    // Halfway between FLT_MAX and 2^128 rounds to even, which is infinity.
    const double halfway = std::ldexp(1.0, 128) - std::ldexp(1.0, 103);
    float r = std::fabs(d) >= halfway ? std::numeric_limits<float>::infinity() : std::numeric_limits<float>::max();
    return d < 0 ? -r : r;
  }
  return static_cast<float>(d);
}

// A coordinate of any scalar type as float; float32 keeps its exact bits.
float load_coord(PlyType t, const unsigned char* p, bool big) {
  switch (t) {
    case PlyType::f32: {
      uint32_t b = static_cast<uint32_t>(load_uint<4>(p, big));
      float f;
      std::memcpy(&f, &b, 4);
      return f;
    }
    case PlyType::f64: {
      uint64_t b = load_uint<8>(p, big);
      double d;
      std::memcpy(&d, &b, 8);
      return to_float(d);
    }
    default: return static_cast<float>(load_int(t, p, big));
  }
}

bool finite3(const float* v) { return std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]); }

std::string coord_text(const float* v) {
  std::string s = "(";
  for (int i = 0; i < 3; ++i) {
    char buf[32];
    auto r = std::to_chars(buf, buf + sizeof buf, v[i]);
    s.append(buf, r.ptr);
    s += i < 2 ? ", " : ")";
  }
  return s;
}

// ---------------------------------------------------------------------------
// The reader

class PlyReader {
 public:
  PlyReader(std::string_view bytes, const std::string& name, Mesh& out, const ReadOptions& options,
            ReadInfo* info)
      : bytes_(bytes), name_(name), out_(out), options_(options), info_(info) {}

  Status run() {
    out_.clear();
    TSM_RETURN_IF_ERROR(parse_header());
    TSM_RETURN_IF_ERROR(find_roles());
    TSM_RETURN_IF_ERROR(check_limits());
    if (info_) {
      info_->format = MeshFormat::ply;
      info_->binary = encoding_ != Encoding::ascii;
    }
    TSM_RETURN_IF_ERROR(encoding_ == Encoding::ascii ? read_ascii_body() : read_binary_body());
    if (empty_faces_ > 0) note("skipped " + std::to_string(empty_faces_) + " face(s) with no corners");
    if (info_) {
      info_->skipped_elements += skipped_;
      if (!notes_.empty()) {
        if (!info_->notes.empty()) info_->notes += "; ";
        info_->notes += notes_;
      }
    }
    return Status::Ok();
  }

 private:
  // ----- header -----

  Status header_error(size_t line, const std::string& what) const {
    return Status(ErrorCode::parse_error, name_ + ": line " + std::to_string(line) + ": " + what);
  }

  Status parse_header() {
    TextCursor cur(bytes_, name_);
    if (bytes_.substr(0, 3) != "ply")
      return cur.error("not a PLY file: it does not start with 'ply'");
    cur.set_position(bytes_.data() + 3, 1);
    if (!cur.at_line_end() || cur.at_end())  // at_line_end() skips blanks first
      return cur.error("not a PLY file: the first line must be 'ply' alone");
    // Line-end style of the header, so that the end_header line end is
    // consumed exactly (a binary body may start with a '\n' byte after a
    // CR-only header).
    const char* q = cur.position();
    const bool cr_only = *q == '\r' && (q + 1 == bytes_.data() + bytes_.size() || q[1] != '\n');
    cur.consume_line_end();

    bool have_format = false;
    for (;;) {
      if (cur.at_end()) return cur.error("the header has no 'end_header' line (the file ends inside the header)");
      const size_t line = cur.line();
      std::string_view kw = cur.token();
      if (kw.empty()) {  // blank line
        cur.next_line();
        continue;
      }
      if (kw == "comment" || kw == "obj_info") {
        cur.next_line();
        continue;
      }
      if (kw == "format") {
        if (have_format) return cur.error("a second 'format' line");
        std::string_view f = cur.token();
        std::string_view version = cur.token();
        if (f == "ascii") {
          encoding_ = Encoding::ascii;
        } else if (f == "binary_little_endian") {
          encoding_ = Encoding::binary_le;
        } else if (f == "binary_big_endian") {
          encoding_ = Encoding::binary_be;
        } else {
          return cur.error("unknown format " + quoted(f) +
                           " (expected ascii, binary_little_endian or binary_big_endian)");
        }
        if (version != "1.0" && version != "1")
          return cur.error("unsupported PLY version " + quoted(version) + " (expected 1.0)");
        have_format = true;
      } else if (kw == "element") {
        Element e;
        e.line = line;
        std::string_view en = cur.token();
        std::string_view cnt = cur.token();
        if (en.empty() || cnt.empty()) return cur.error("'element' needs a name and a count");
        if (cnt[0] == '-') return cur.error("element " + quoted(en) + " has a negative count " + quoted(cnt));
        auto r = std::from_chars(cnt.data(), cnt.data() + cnt.size(), e.count);
        if (r.ec == std::errc::result_out_of_range)
          return cur.error("element " + quoted(en) + " count " + quoted(cnt) + " is too large");
        if (r.ec != std::errc() || r.ptr != cnt.data() + cnt.size())
          return cur.error("element " + quoted(en) + " count " + quoted(cnt) + " is not a number");
        e.name = std::string(en);
        if (e.name == "vertex" || e.name == "face")
          for (const Element& other : elements_)
            if (other.name == e.name) return cur.error("a second element '" + e.name + "'");
        elements_.push_back(std::move(e));
      } else if (kw == "property") {
        if (elements_.empty()) return cur.error("'property' before any 'element' line");
        Property p;
        std::string_view t = cur.token();
        if (t == "list") {
          p.list = true;
          std::string_view ct = cur.token();
          std::string_view it = cur.token();
          if (!type_from_name(ct, p.count_type))
            return cur.error("unknown list count type " + quoted(ct));
          if (!type_from_name(it, p.type)) return cur.error("unknown list item type " + quoted(it));
          if (!is_integer(p.count_type))
            return cur.error("list count type must be an integer type, not " + quoted(ct));
        } else if (!type_from_name(t, p.type)) {
          return cur.error("unknown property type " + quoted(t));
        }
        std::string_view pn = cur.token();
        if (pn.empty()) return cur.error("'property' has no name");
        p.name = std::string(pn);
        elements_.back().props.push_back(std::move(p));
      } else if (kw == "end_header") {
        if (!cur.at_line_end()) return cur.error("unexpected text after 'end_header'");
        if (!have_format) return cur.error("the header has no 'format' line");
        const char* p = cur.position();
        const char* end = bytes_.data() + bytes_.size();
        size_t next_line = line;
        if (p < end) {
          ++next_line;
          if (*p == '\n') {
            ++p;
          } else {  // '\r'
            ++p;
            if (!cr_only && p < end && *p == '\n') ++p;
          }
        }
        body_offset_ = static_cast<size_t>(p - bytes_.data());
        body_line_ = next_line;
        return Status::Ok();
      } else {
        return cur.error("unknown header keyword " + quoted(kw));
      }
      if (!cur.at_line_end()) return cur.error("unexpected text " + quoted(cur.token()) + " at the end of the line");
      cur.consume_line_end();
    }
  }

  // Which element and properties hold the mesh.
  Status find_roles() {
    for (size_t i = 0; i < elements_.size(); ++i) {
      const Element& e = elements_[i];
      if (e.name == "vertex") {
        vertex_elem_ = i;
        vertex_count_ = e.count;
        const char* names[3] = {"x", "y", "z"};
        for (int a = 0; a < 3; ++a) {
          for (size_t k = 0; k < e.props.size() && coord_prop_[a] < 0; ++k)
            if (e.props[k].name == names[a]) {
              if (e.props[k].list)
                return header_error(e.line, std::string("property '") + names[a] +
                                                "' of element 'vertex' is a list; expected a number");
              coord_prop_[a] = static_cast<int>(k);
            }
          if (coord_prop_[a] < 0 && e.count > 0)
            return header_error(e.line, std::string("element 'vertex' has no property '") + names[a] + "'");
        }
      } else if (e.name == "face") {
        face_elem_ = i;
        for (size_t k = 0; k < e.props.size(); ++k) {
          const Property& p = e.props[k];
          if (p.name != "vertex_indices" && p.name != "vertex_index") continue;
          if (!p.list)
            return header_error(e.line, "property '" + p.name + "' of element 'face' must be a list");
          if (!is_integer(p.type))
            return header_error(e.line, "property '" + p.name + "' of element 'face' must have an integer item type");
          index_prop_ = static_cast<int>(k);
          break;
        }
        if (index_prop_ < 0 && e.count > 0)
          return header_error(e.line, "element 'face' has no list property 'vertex_indices' or 'vertex_index'");
      }
    }
    return Status::Ok();
  }

  Status check_limits() const {
    const uint64_t faces = face_elem_ == kNone ? 0 : elements_[face_elem_].count;
    if (options_.max_vertices > 0 && vertex_count_ > options_.max_vertices)
      return Status(ErrorCode::limit_exceeded,
                    name_ + ": the file declares " + std::to_string(vertex_count_) +
                        " vertices, more than the limit of " + std::to_string(options_.max_vertices) +
                        " (ReadOptions::max_vertices)");
    if (options_.max_faces > 0 && faces > options_.max_faces)
      return Status(ErrorCode::limit_exceeded,
                    name_ + ": the file declares " + std::to_string(faces) + " faces, more than the limit of " +
                        std::to_string(options_.max_faces) + " (ReadOptions::max_faces)");
    if (vertex_count_ > kMaxIndex)
      return Status(ErrorCode::limit_exceeded, name_ + ": the file declares " + std::to_string(vertex_count_) +
                                                   " vertices; tsm handles at most " + std::to_string(kMaxIndex));
    if (faces >= kMaxIndex)
      return Status(ErrorCode::limit_exceeded, name_ + ": the file declares " + std::to_string(faces) +
                                                   " faces; tsm handles fewer than " + std::to_string(kMaxIndex));
    return Status::Ok();
  }

  // Notes stay short even for files with thousands of odd elements.
  void note(const std::string& s) {
    if (++note_count_ > 8) {
      if (note_count_ == 9) notes_ += "; ...";
      return;
    }
    if (!notes_.empty()) notes_ += "; ";
    notes_ += s;
  }

  void note_skipped(const Element& e) {
    note("skipped element '" + e.name + "' (" + std::to_string(e.count) + ")");
    skipped_ += static_cast<size_t>(std::min<uint64_t>(e.count, std::numeric_limits<size_t>::max()));
  }

  Status too_many_corners() const {
    return Status(ErrorCode::limit_exceeded,
                  name_ + ": the faces have more than " + std::to_string(kMaxIndex) + " corners in all");
  }
  Status corner_limit(size_t n) const {
    return out_.indices.size() + n > kMaxIndex ? too_many_corners() : Status::Ok();
  }

  std::string nonfinite_text(uint64_t v, const float* xyz) const {
    return "vertex " + std::to_string(v) + " has a non-finite coordinate " + coord_text(xyz) +
           "; pass --allow-nonfinite (ReadOptions::allow_nonfinite) to accept it";
  }

  std::string index_text(uint64_t f, int64_t index) const {
    return "face " + std::to_string(f) + ": vertex index " + std::to_string(index) +
           " is out of range (the file has " + std::to_string(vertex_count_) + " vertices)";
  }

  void reserve_faces(uint64_t count, uint64_t max_corners) {
    out_.face_offsets.reserve(static_cast<size_t>(count) + 1);
    out_.indices.reserve(static_cast<size_t>(std::min<uint64_t>(3 * count, max_corners)));
  }

  // ----- binary body -----

  Status bin_error(const unsigned char* at, const std::string& what) const {
    return binary_error(name_, static_cast<size_t>(at - begin_), what);
  }
  Status truncated(const unsigned char* at, const Element& e, uint64_t i) const {
    return bin_error(at, "the file ends inside " + e.name + " " + std::to_string(i) + " (element '" + e.name +
                             "' declares " + std::to_string(e.count) + ")");
  }

  Status read_binary_body() {
    begin_ = reinterpret_cast<const unsigned char*>(bytes_.data());
    end_ = begin_ + bytes_.size();
    p_ = begin_ + body_offset_;
    big_ = encoding_ == Encoding::binary_be;
    for (size_t i = 0; i < elements_.size(); ++i) {
      const Element& e = elements_[i];
      const uint64_t min = e.min_binary_size();
      const size_t remaining = static_cast<size_t>(end_ - p_);
      // Checked before anything is reserved: huge counts fail here.
      if (min > 0 && e.count > remaining / min)
        return bin_error(p_, "element '" + e.name + "' declares " + std::to_string(e.count) +
                                 " items of at least " + std::to_string(min) + " bytes each, but only " +
                                 std::to_string(remaining) + " bytes are left in the file");
      if (i == vertex_elem_) {
        TSM_RETURN_IF_ERROR(read_binary_vertices(e));
      } else if (i == face_elem_) {
        TSM_RETURN_IF_ERROR(read_binary_faces(e));
      } else {
        TSM_RETURN_IF_ERROR(skip_binary(e));
        note_skipped(e);
      }
    }
    if (p_ < end_) note("ignored " + std::to_string(end_ - p_) + " bytes after the last element");
    return Status::Ok();
  }

  // Moves past a list's items; reads its count into n.
  Status bin_list(const Property& prop, const Element& e, uint64_t i, uint64_t& n) {
    const size_t cs = type_size(prop.count_type);
    if (static_cast<size_t>(end_ - p_) < cs) return truncated(p_, e, i);
    int64_t c = load_int(prop.count_type, p_, big_);
    if (c < 0)
      return bin_error(p_, e.name + " " + std::to_string(i) + ": negative list count " + std::to_string(c) +
                               " for property '" + prop.name + "'");
    p_ += cs;
    n = static_cast<uint64_t>(c);
    if (n > static_cast<uint64_t>(end_ - p_) / type_size(prop.type)) return truncated(p_, e, i);
    return Status::Ok();
  }

  Status skip_binary(const Element& e) {
    if (e.fixed_size()) {  // size already checked against the bytes left
      p_ += static_cast<size_t>(e.count * e.min_binary_size());
      return Status::Ok();
    }
    for (uint64_t i = 0; i < e.count; ++i) {
      for (const Property& prop : e.props) {
        if (!prop.list) {
          const size_t s = type_size(prop.type);
          if (static_cast<size_t>(end_ - p_) < s) return truncated(p_, e, i);
          p_ += s;
        } else {
          uint64_t n;
          TSM_RETURN_IF_ERROR(bin_list(prop, e, i, n));
          p_ += static_cast<size_t>(n) * type_size(prop.type);
        }
      }
    }
    return Status::Ok();
  }

  Status read_binary_vertices(const Element& e) {
    const size_t count = static_cast<size_t>(e.count);
    if (count == 0) return Status::Ok();
    const PlyType tx = e.props[static_cast<size_t>(coord_prop_[0])].type;
    const PlyType ty = e.props[static_cast<size_t>(coord_prop_[1])].type;
    const PlyType tz = e.props[static_cast<size_t>(coord_prop_[2])].type;
    if (e.fixed_size()) {
      // Offsets of x, y, z inside one fixed-size item.
      size_t off[3] = {0, 0, 0};
      size_t stride = 0;
      for (size_t k = 0; k < e.props.size(); ++k) {
        for (int a = 0; a < 3; ++a)
          if (coord_prop_[a] == static_cast<int>(k)) off[a] = stride;
        stride += type_size(e.props[k].type);
      }
      const unsigned char* base = p_;
      out_.positions.resize(3 * count);
      float* dst = out_.positions.data();
      const bool all_float = tx == PlyType::f32 && ty == PlyType::f32 && tz == PlyType::f32;
      if (all_float && kHostLittleEndian && !big_ && off[1] == off[0] + 4 && off[2] == off[0] + 8) {
        if (stride == 12) {
          std::memcpy(dst, base, 12 * count);
        } else {
          const unsigned char* s = base + off[0];
          for (size_t v = 0; v < count; ++v, s += stride) std::memcpy(dst + 3 * v, s, 12);
        }
      } else {
        const unsigned char* s = base;
        for (size_t v = 0; v < count; ++v, s += stride) {
          dst[3 * v + 0] = load_coord(tx, s + off[0], big_);
          dst[3 * v + 1] = load_coord(ty, s + off[1], big_);
          dst[3 * v + 2] = load_coord(tz, s + off[2], big_);
        }
      }
      p_ += stride * count;
      if (!options_.allow_nonfinite) {
        for (size_t v = 0; v < count; ++v)
          if (!finite3(dst + 3 * v)) return bin_error(base + v * stride, nonfinite_text(v, dst + 3 * v));
      }
      return Status::Ok();
    }
    // Items with lists: walk each one.
    out_.positions.reserve(3 * count);
    for (size_t v = 0; v < count; ++v) {
      const unsigned char* start = p_;
      float xyz[3] = {0, 0, 0};
      for (size_t k = 0; k < e.props.size(); ++k) {
        const Property& prop = e.props[k];
        if (prop.list) {
          uint64_t n;
          TSM_RETURN_IF_ERROR(bin_list(prop, e, v, n));
          p_ += static_cast<size_t>(n) * type_size(prop.type);
          continue;
        }
        const size_t s = type_size(prop.type);
        if (static_cast<size_t>(end_ - p_) < s) return truncated(p_, e, v);
        for (int a = 0; a < 3; ++a)
          if (coord_prop_[a] == static_cast<int>(k)) xyz[a] = load_coord(prop.type, p_, big_);
        p_ += s;
      }
      if (!options_.allow_nonfinite && !finite3(xyz)) return bin_error(start, nonfinite_text(v, xyz));
      out_.add_vertex(xyz[0], xyz[1], xyz[2]);
    }
    return Status::Ok();
  }

  Status read_binary_faces(const Element& e) {
    const uint64_t count = e.count;
    if (count == 0) return Status::Ok();
    const Property& ip = e.props[static_cast<size_t>(index_prop_)];
    const size_t item = type_size(ip.type);
    // Index check: for signed item types a negative value shows up as a huge
    // unsigned one, so one comparison against this bound covers both.
    const uint64_t limit =
        ip.type == PlyType::i32 ? std::min<uint64_t>(vertex_count_, 0x80000000u) : vertex_count_;

    // Fast path: the face element is only 'list uchar int|uint vertex_indices'.
    // Sized once for the most corners the bytes left can hold (each face
    // also has its count byte), written in place, trimmed at the end.
    if (e.props.size() == 1 && ip.count_type == PlyType::u8 && (ip.type == PlyType::i32 || ip.type == PlyType::u32)) {
      const size_t max_corners = (static_cast<size_t>(end_ - p_) - static_cast<size_t>(count)) / 4;
      size_t w = out_.indices.size();
      size_t fw = out_.face_offsets.size();
      const size_t w_end = w + max_corners;
      out_.indices.resize(w_end);
      out_.face_offsets.resize(fw + static_cast<size_t>(count));
      uint32_t* indices = out_.indices.data();
      uint32_t* offsets = out_.face_offsets.data();
      for (uint64_t f = 0; f < count; ++f) {
        if (p_ >= end_) return truncated(p_, e, f);
        const size_t n = *p_;
        const unsigned char* list = p_ + 1;
        if (static_cast<size_t>(end_ - list) < 4 * n) return truncated(p_, e, f);
        // Beyond the bound only when the bytes left cannot hold the faces after this one.
        if (n > w_end - w)
          return bin_error(p_, "face " + std::to_string(f) + ": the file ends before the last of the " +
                                   std::to_string(count) + " items of element 'face'");
        if (w + n > kMaxIndex) return too_many_corners();
        p_ = list + 4 * n;
        if (n == 0) {
          ++empty_faces_;
          continue;
        }
        uint32_t* dst = indices + w;
        if (n == 3 && kHostLittleEndian && !big_) {  // triangles: a fixed-size copy, not a rep movs
          std::memcpy(dst, list, 12);
        } else {
          for (size_t j = 0; j < n; ++j) dst[j] = static_cast<uint32_t>(load_uint<4>(list + 4 * j, big_));
        }
        uint32_t bad = 0;
        for (size_t j = 0; j < n; ++j) bad |= dst[j] >= limit;
        if (bad) {
          for (size_t j = 0; j < n; ++j)
            if (dst[j] >= limit) {
              const int64_t shown = ip.type == PlyType::i32 ? static_cast<int64_t>(static_cast<int32_t>(dst[j]))
                                                            : static_cast<int64_t>(dst[j]);
              return bin_error(list + 4 * j, index_text(f, shown));
            }
        }
        w += n;
        offsets[fw++] = static_cast<uint32_t>(w);
      }
      out_.indices.resize(w);
      out_.face_offsets.resize(fw);
      return Status::Ok();
    }

    reserve_faces(count, static_cast<uint64_t>(end_ - p_) / item);
    // General layout: any count/item types, other properties skipped.
    for (uint64_t f = 0; f < count; ++f) {
      bool got = false;
      for (size_t k = 0; k < e.props.size(); ++k) {
        const Property& prop = e.props[k];
        if (!prop.list) {
          const size_t s = type_size(prop.type);
          if (static_cast<size_t>(end_ - p_) < s) return truncated(p_, e, f);
          p_ += s;
          continue;
        }
        uint64_t n;
        TSM_RETURN_IF_ERROR(bin_list(prop, e, f, n));
        const size_t s = type_size(prop.type);
        if (static_cast<int>(k) != index_prop_ || got) {
          p_ += static_cast<size_t>(n) * s;
          continue;
        }
        got = true;
        if (n == 0) {
          ++empty_faces_;
          continue;
        }
        TSM_RETURN_IF_ERROR(corner_limit(static_cast<size_t>(n)));
        for (uint64_t j = 0; j < n; ++j, p_ += s) {
          const int64_t index = load_int(prop.type, p_, big_);
          if (index < 0 || static_cast<uint64_t>(index) >= vertex_count_) return bin_error(p_, index_text(f, index));
          out_.indices.push_back(static_cast<uint32_t>(index));
        }
        out_.face_offsets.push_back(static_cast<uint32_t>(out_.indices.size()));
      }
    }
    return Status::Ok();
  }

  // ----- ascii body -----

  Status value_error(TextCursor& cur, const Element& e, uint64_t i, const Property& prop, const char* what) const {
    const std::string item = e.name + " " + std::to_string(i);
    if (cur.at_end())
      return cur.error("the file ends inside " + item + " (element '" + e.name + "' declares " +
                       std::to_string(e.count) + "); expected " + what + " for property '" + prop.name + "'");
    if (cur.at_line_end())
      return cur.error(item + ": the line ends before property '" + prop.name + "' (expected " + what + ")");
    std::string_view tok = cur.token();
    return cur.error(item + ": property '" + prop.name + "': " + quoted(tok) + " is not " + what);
  }

  // Reads a list count into n (>= 0).
  Status ascii_count(TextCursor& cur, const Element& e, uint64_t i, const Property& prop, uint64_t& n) const {
    int64_t c;
    if (!cur.parse_int(c)) return value_error(cur, e, i, prop, "an integer list count");
    if (c < 0)
      return cur.error(e.name + " " + std::to_string(i) + ": negative list count " + std::to_string(c) +
                       " for property '" + prop.name + "'");
    n = static_cast<uint64_t>(c);
    return Status::Ok();
  }

  Status ascii_skip_value(TextCursor& cur, const Element& e, uint64_t i, const Property& prop,
                          PlyType t) const {
    if (is_integer(t)) {
      int64_t v;
      if (!cur.parse_int(v)) {
        // Lenient for skipped values: "255.0" in a uchar column is accepted.
        double d;
        if (!cur.parse_float(d)) return value_error(cur, e, i, prop, "a number");
      }
    } else {
      double d;
      if (!cur.parse_float(d)) return value_error(cur, e, i, prop, "a number");
    }
    return Status::Ok();
  }

  Status read_ascii_body() {
    TextCursor cur(bytes_, name_);
    cur.set_position(bytes_.data() + body_offset_, body_line_);
    const char* end = bytes_.data() + bytes_.size();
    for (size_t ei = 0; ei < elements_.size(); ++ei) {
      const Element& e = elements_[ei];
      if (e.props.empty()) {  // nothing to read for any item
        if (ei != vertex_elem_ && ei != face_elem_) note_skipped(e);
        continue;
      }
      // Every value takes a digit and a separator (the last may lack one).
      const uint64_t min = 2 * static_cast<uint64_t>(e.props.size());
      const uint64_t room = static_cast<uint64_t>(end - cur.position()) + 1;
      if (e.count > room / min)
        return cur.error("element '" + e.name + "' declares " + std::to_string(e.count) + " items of " +
                         std::to_string(e.props.size()) + " values, but only " + std::to_string(room - 1) +
                         " bytes are left in the file");
      if (ei == vertex_elem_) {
        TSM_RETURN_IF_ERROR(read_ascii_vertices(cur, e));
      } else if (ei == face_elem_) {
        TSM_RETURN_IF_ERROR(read_ascii_faces(cur, e, room / 2));
      } else {
        for (uint64_t i = 0; i < e.count; ++i) {
          TSM_RETURN_IF_ERROR(start_ascii_item(cur, e, i));
          for (const Property& prop : e.props) {
            if (!prop.list) {
              TSM_RETURN_IF_ERROR(ascii_skip_value(cur, e, i, prop, prop.type));
              continue;
            }
            uint64_t n;
            TSM_RETURN_IF_ERROR(ascii_count(cur, e, i, prop, n));
            for (uint64_t j = 0; j < n; ++j) TSM_RETURN_IF_ERROR(ascii_skip_value(cur, e, i, prop, prop.type));
          }
          TSM_RETURN_IF_ERROR(end_ascii_item(cur, e, i));
        }
        note_skipped(e);
      }
    }
    cur.skip_whitespace();
    if (!cur.at_end()) note("ignored text after the last element, from line " + std::to_string(cur.line()));
    return Status::Ok();
  }

  // Each item starts on a new line (blank lines are allowed in between).
  Status start_ascii_item(TextCursor& cur, const Element& e, uint64_t i) const {
    cur.skip_whitespace();
    if (cur.at_end())
      return cur.error("the file ends after " + std::to_string(i) + " of the " + std::to_string(e.count) +
                       " items of element '" + e.name + "'");
    return Status::Ok();
  }
  // ... and ends with its line.
  Status end_ascii_item(TextCursor& cur, const Element& e, uint64_t i) const {
    if (!cur.at_line_end())
      return cur.error(e.name + " " + std::to_string(i) + ": unexpected " + quoted(cur.token()) +
                       " after the last property (element '" + e.name + "' has " + std::to_string(e.props.size()) +
                       " properties)");
    return Status::Ok();
  }

  Status read_ascii_vertices(TextCursor& cur, const Element& e) {
    out_.positions.reserve(3 * static_cast<size_t>(e.count));
    // Role of each property: 0..2 = x, y, z; -1 = skipped.
    std::vector<int> role(e.props.size(), -1);
    for (int a = 0; a < 3; ++a)
      if (coord_prop_[a] >= 0) role[static_cast<size_t>(coord_prop_[a])] = a;
    const bool simple = e.props.size() == 3 && role[0] == 0 && role[1] == 1 && role[2] == 2 &&
                        e.props[0].type == PlyType::f32 && e.props[1].type == PlyType::f32 &&
                        e.props[2].type == PlyType::f32;
    for (uint64_t v = 0; v < e.count; ++v) {
      TSM_RETURN_IF_ERROR(start_ascii_item(cur, e, v));
      float xyz[3] = {0, 0, 0};
      if (simple) {
        for (int a = 0; a < 3; ++a)
          if (!cur.parse_float(xyz[a])) return value_error(cur, e, v, e.props[static_cast<size_t>(a)], "a number");
      } else {
        for (size_t k = 0; k < e.props.size(); ++k) {
          const Property& prop = e.props[k];
          if (prop.list) {
            uint64_t n;
            TSM_RETURN_IF_ERROR(ascii_count(cur, e, v, prop, n));
            for (uint64_t j = 0; j < n; ++j) TSM_RETURN_IF_ERROR(ascii_skip_value(cur, e, v, prop, prop.type));
            continue;
          }
          const int a = role[k];
          if (a < 0) {
            TSM_RETURN_IF_ERROR(ascii_skip_value(cur, e, v, prop, prop.type));
          } else if (prop.type == PlyType::f32) {
            if (!cur.parse_float(xyz[a])) return value_error(cur, e, v, prop, "a number");
          } else {
            double d;
            if (!cur.parse_float(d)) return value_error(cur, e, v, prop, "a number");
            xyz[a] = to_float(d);
          }
        }
      }
      if (!options_.allow_nonfinite && !finite3(xyz)) return cur.error(nonfinite_text(v, xyz));
      TSM_RETURN_IF_ERROR(end_ascii_item(cur, e, v));
      out_.add_vertex(xyz[0], xyz[1], xyz[2]);
    }
    return Status::Ok();
  }

  Status read_ascii_faces(TextCursor& cur, const Element& e, uint64_t max_values) {
    const char* end = bytes_.data() + bytes_.size();
    reserve_faces(e.count, max_values);
    for (uint64_t f = 0; f < e.count; ++f) {
      TSM_RETURN_IF_ERROR(start_ascii_item(cur, e, f));
      bool got = false;
      for (size_t k = 0; k < e.props.size(); ++k) {
        const Property& prop = e.props[k];
        if (!prop.list) {
          TSM_RETURN_IF_ERROR(ascii_skip_value(cur, e, f, prop, prop.type));
          continue;
        }
        uint64_t n;
        TSM_RETURN_IF_ERROR(ascii_count(cur, e, f, prop, n));
        if (static_cast<int>(k) != index_prop_ || got) {
          for (uint64_t j = 0; j < n; ++j) TSM_RETURN_IF_ERROR(ascii_skip_value(cur, e, f, prop, prop.type));
          continue;
        }
        got = true;
        if (n == 0) {
          ++empty_faces_;
          continue;
        }
        // Each index takes at least two bytes: a count beyond that is a
        // truncated or corrupt file, not a big face.
        if (n > (static_cast<uint64_t>(end - cur.position()) + 1) / 2)
          return cur.error("face " + std::to_string(f) + ": list count " + std::to_string(n) +
                           " is more than the rest of the file can hold");
        TSM_RETURN_IF_ERROR(corner_limit(static_cast<size_t>(n)));
        for (uint64_t j = 0; j < n; ++j) {
          int64_t index;
          if (!cur.parse_int(index)) return value_error(cur, e, f, prop, "an integer vertex index");
          if (index < 0 || static_cast<uint64_t>(index) >= vertex_count_) return cur.error(index_text(f, index));
          out_.indices.push_back(static_cast<uint32_t>(index));
        }
        out_.face_offsets.push_back(static_cast<uint32_t>(out_.indices.size()));
      }
      TSM_RETURN_IF_ERROR(end_ascii_item(cur, e, f));
    }
    return Status::Ok();
  }

  static constexpr size_t kNone = static_cast<size_t>(-1);

  std::string_view bytes_;
  const std::string& name_;
  Mesh& out_;
  const ReadOptions& options_;
  ReadInfo* info_;

  Encoding encoding_ = Encoding::ascii;
  std::vector<Element> elements_;
  size_t body_offset_ = 0;
  size_t body_line_ = 1;

  size_t vertex_elem_ = kNone;
  size_t face_elem_ = kNone;
  uint64_t vertex_count_ = 0;
  int coord_prop_[3] = {-1, -1, -1};
  int index_prop_ = -1;

  const unsigned char* begin_ = nullptr;
  const unsigned char* end_ = nullptr;
  const unsigned char* p_ = nullptr;
  bool big_ = false;

  size_t empty_faces_ = 0;
  size_t skipped_ = 0;
  size_t note_count_ = 0;
  std::string notes_;
};

// ---------------------------------------------------------------------------
// Writer helpers

char* put_u32_le(char* w, uint32_t v) {
  for (int i = 0; i < 4; ++i) *w++ = static_cast<char>(v >> (8 * i));
  return w;
}

}  // namespace

Status read_ply(std::string_view bytes, const std::string& name, Mesh& out, const ReadOptions& options,
                ReadInfo* info) {
  PlyReader reader(bytes, name, out, options, info);
  Status s = reader.run();
  if (!s.ok()) out.clear();  // never hand back half a mesh
  return s;
}

Status write_ply(const Mesh& mesh, const WriteOptions& options, std::string& out) {
  std::string why;
  if (!mesh.valid(&why)) return Status(ErrorCode::invalid_argument, "cannot write PLY: the mesh is invalid: " + why);
  const size_t nv = mesh.vertex_count();
  const size_t nf = mesh.face_count();
  uint32_t largest = 0;
  for (size_t f = 0; f < nf; ++f) largest = std::max(largest, mesh.face_size(f));
  const bool wide_count = largest > 255;

  out.clear();
  out += "ply\n";
  out += options.ascii ? "format ascii 1.0\n" : "format binary_little_endian 1.0\n";
  out += "comment written by tsm\n";
  out += "element vertex " + std::to_string(nv) + "\n";
  out += "property float x\nproperty float y\nproperty float z\n";
  out += "element face " + std::to_string(nf) + "\n";
  out += wide_count ? "property list uint uint vertex_indices\n" : "property list uchar uint vertex_indices\n";
  out += "end_header\n";

  if (!options.ascii) {
    const size_t header = out.size();
    const size_t count_size = wide_count ? 4 : 1;
    out.resize(header + 12 * nv + count_size * nf + 4 * mesh.corner_count());
    char* w = &out[header];
    if (kHostLittleEndian) {
      if (nv > 0) std::memcpy(w, mesh.positions.data(), 12 * nv);
      w += 12 * nv;
    } else {
      for (float x : mesh.positions) {
        uint32_t b;
        std::memcpy(&b, &x, 4);
        w = put_u32_le(w, b);
      }
    }
    for (size_t f = 0; f < nf; ++f) {
      const uint32_t n = mesh.face_size(f);
      const uint32_t* c = mesh.face(f);
      if (wide_count) {
        w = put_u32_le(w, n);
      } else {
        *w++ = static_cast<char>(n);
      }
      if (kHostLittleEndian && n == 3) {  // a fixed-size copy, not a rep movs
        std::memcpy(w, c, 12);
        w += 12;
      } else if (kHostLittleEndian) {
        std::memcpy(w, c, 4 * static_cast<size_t>(n));
        w += 4 * static_cast<size_t>(n);
      } else {
        for (uint32_t j = 0; j < n; ++j) w = put_u32_le(w, c[j]);
      }
    }
    return Status::Ok();
  }

  out.reserve(out.size() + 30 * nv + 4 * nf + 8 * mesh.corner_count());
  char buf[64];
  for (size_t v = 0; v < nv; ++v) {
    char* w = buf;
    for (int a = 0; a < 3; ++a) {
      // Shortest text that reads back to the same float.
      w = std::to_chars(w, buf + sizeof buf, mesh.positions[3 * v + static_cast<size_t>(a)]).ptr;
      *w++ = a < 2 ? ' ' : '\n';
    }
    out.append(buf, w);
  }
  for (size_t f = 0; f < nf; ++f) {
    const uint32_t n = mesh.face_size(f);
    const uint32_t* c = mesh.face(f);
    char* w = std::to_chars(buf, buf + sizeof buf, n).ptr;
    out.append(buf, w);
    for (uint32_t j = 0; j < n; ++j) {
      buf[0] = ' ';
      w = std::to_chars(buf + 1, buf + sizeof buf, c[j]).ptr;
      out.append(buf, w);
    }
    out += '\n';
  }
  return Status::Ok();
}

}  // namespace tsm

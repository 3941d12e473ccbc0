// PLY reader and writer (file-format stage, not part of the Topological
// Surgery method itself): turns a PLY file (ascii, binary little or big
// endian) into a tsm::Mesh and back.
//
// Reading keeps exactly what the file holds: x, y, z of the 'vertex' element
// (any scalar type, stored as float) and the polygons of the 'face' element's
// 'vertex_indices' (or 'vertex_index') list, in file order, with degenerate
// faces and unreferenced vertices kept. Topology is not checked here; that is
// the codec's job. Other elements are skipped (and noted).
//
// Attributes (Mesh::attributes), from the other properties of the 'vertex'
// element (vertex domain) and of the 'face' element (face domain):
//   nx ny nz                          -> 'normal'   (kind normal, 3 components)
//   red green blue [alpha]            -> 'color'    (kind color, 3 or 4)
//   s t | u v | texture_u texture_v | texture_s texture_t
//                                     -> 'texcoord' (kind texcoord, 2; the first
//                                        complete pair in that order)
//   NAME_0 NAME_1 [NAME_2 [NAME_3]]   -> generic 'NAME' of 2..4 components (how
//                                        the writer stores generic vectors;
//                                        consecutive, same type)
//   any other scalar property         -> generic, 1 component, named after it
// The attribute type follows the property type: uchar -> u8, ushort -> u16,
// char, short, int, uint -> i32, float, double -> f32 (components of mixed
// types take the smallest type holding all of them). Values are stored as
// float: 32-bit integers beyond float precision (|v| > 2^24, e.g. 16777217)
// cannot be held exactly; such an attribute is kept as f32 with the values
// rounded, and ReadInfo::notes says so (refusing the file would make its
// geometry unreadable for the sake of one column). In ascii bodies a value
// of an integer property must be an integer (255.0 is accepted) inside the
// property type's range, else the read fails naming the line. NaN and
// infinite attribute values are refused unless ReadOptions::allow_nonfinite.
// List properties of the 'face' element other than the index list hold
// per-corner values: 'texcoord' (2 values per corner, as VCG/MeshLab write)
// becomes a corner-domain texcoord, any other list with the same 1..4 values
// per corner on every face a corner-domain attribute named after it ('normal'
// with 3 is kind normal, 'color' with 3 or 4 kind color). Corner-domain
// values are shared where equal (the same float bits). A 'texcoord' list whose
// count is not 2 per corner is an error; other lists that do not fit are
// skipped with a note. Lists of the 'vertex' element are skipped.
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
// Attributes are written as properties the reader maps back: vertex- and
// face-domain ones as scalar properties of their element (the first normal,
// colour and texcoord of a domain as nx ny nz / red green blue [alpha] / s t,
// others under their own name, or NAME_0.. NAME_k-1 for k > 1 components),
// of the property type of their AttributeType (u8 uchar, u16 ushort, i32 int,
// f32 float); corner-domain ones as face list properties after
// vertex_indices ('texcoord', 'normal', 'color' for the first of each kind,
// else the attribute's name) holding each corner's value. PLY has no shared
// value list: the reader shares equal values (same float bits) among the
// corners, in first-use order, so the lists tsm wrote (distinct values) come
// back, but values no corner uses are gone. Names that are not PLY tokens or that
// two properties of an element would share, and integer-typed values that
// are not integers of their type's range, make the writer fail. PLY has no
// place for Mesh::metadata: WriteInfo::notes names the entries left out.
#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <map>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

#include "text_scan.hpp"
#include "tsm/io.hpp"
#include "write_notes.hpp"

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
// Attribute values

const char* type_name(PlyType t) {
  switch (t) {
    case PlyType::i8: return "char";
    case PlyType::u8: return "uchar";
    case PlyType::i16: return "short";
    case PlyType::u16: return "ushort";
    case PlyType::i32: return "int";
    case PlyType::u32: return "uint";
    case PlyType::f32: return "float";
    case PlyType::f64: return "double";
  }
  return "?";
}

// Range of an integer type.
void int_range(PlyType t, int64_t& lo, int64_t& hi) {
  switch (t) {
    case PlyType::i8: lo = -128, hi = 127; return;
    case PlyType::u8: lo = 0, hi = 255; return;
    case PlyType::i16: lo = -32768, hi = 32767; return;
    case PlyType::u16: lo = 0, hi = 65535; return;
    case PlyType::i32: lo = -2147483648LL, hi = 2147483647LL; return;
    default: lo = 0, hi = 4294967295LL; return;
  }
}

// The attribute type that holds every value of a property type.
AttributeType attribute_type(PlyType t) {
  switch (t) {
    case PlyType::u8: return AttributeType::u8;
    case PlyType::u16: return AttributeType::u16;
    case PlyType::i8:
    case PlyType::i16:
    case PlyType::i32:
    case PlyType::u32: return AttributeType::i32;
    case PlyType::f32:
    case PlyType::f64: break;
  }
  return AttributeType::f32;
}

// The smallest attribute type holding the values of both.
AttributeType combine_types(AttributeType a, AttributeType b) {
  if (a == b) return a;
  if (a == AttributeType::f32 || b == AttributeType::f32) return AttributeType::f32;
  if (a == AttributeType::i32 || b == AttributeType::i32) return AttributeType::i32;
  return AttributeType::u16;  // u8 and u16
}

// An integer as float; `inexact` is set when float cannot hold it (only
// 32-bit integers beyond 2^24 can be).
float int_to_float(int64_t v, bool& inexact) {
  const float f = static_cast<float>(v);
  if (static_cast<int64_t>(f) != v) inexact = true;
  return f;
}

// One attribute value of any scalar type; float32 keeps its exact bits.
float load_value(PlyType t, const unsigned char* p, bool big, bool& inexact) {
  if (!is_integer(t)) return load_coord(t, p, big);
  return int_to_float(load_int(t, p, big), inexact);
}

std::string float_text(float x) {
  char buf[32];
  return std::string(buf, std::to_chars(buf, buf + sizeof buf, x).ptr);
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
    plan_attributes();
    if (info_) {
      info_->format = MeshFormat::ply;
      info_->binary = encoding_ != Encoding::ascii;
    }
    TSM_RETURN_IF_ERROR(encoding_ == Encoding::ascii ? read_ascii_body() : read_binary_body());
    finish_attributes();
    if (empty_faces_ > 0) note("skipped " + std::to_string(empty_faces_) + " face(s) with no corners");
    if (info_) {
      info_->skipped_elements += skipped_;
      info_->add_note(notes_);
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
        if (pn.size() > kMaxAttributeNameBytes)
          return cur.error("a property name of " + std::to_string(pn.size()) + " bytes; tsm keeps names of at most " +
                           std::to_string(kMaxAttributeNameBytes) + " bytes (rename the property)");
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

  // ----- attributes -----

  // An attribute being read: where its values come from and what was seen.
  struct AttrBuild {
    Attribute a;
    size_t first_prop = 0;       // for the order of Mesh::attributes
    bool corner_list = false;    // a face list property: values per corner
    uint32_t fixed_k = 0;        // corner lists: values per corner if the name fixes it ('texcoord': 2)
    uint32_t k = 0;              // corner lists: values per corner, from the first face with corners
    bool dropped = false;        // a corner list that does not fit: skipped (noted)
    bool empty_lists = false;    // a 'texcoord' list that is empty on (some) faces with corners
    bool had_values = false;     // ... and one that is not
    uint64_t first_empty = 0, first_values = 0;  // the first such faces
    size_t inexact = 0;          // integers float cannot hold
    uint64_t inexact_item = 0;   // the first of them: item and property
    std::string inexact_prop;
    size_t item_start = 0;       // face element: values.size() when the current face began
    size_t list_at = 0;          // binary: byte offset of the current face's list (messages)
  };

  // Which attribute (and component) a property of the vertex or face element feeds.
  struct Column {
    int attr = -1;
    uint32_t comp = 0;
  };

  // Maps the properties of the vertex and face elements to attributes.
  void plan_attributes() {
    columns_.assign(elements_.size(), {});
    for (size_t ei = 0; ei < elements_.size(); ++ei) {
      if (ei != vertex_elem_ && ei != face_elem_) continue;
      const Element& e = elements_[ei];
      columns_[ei].assign(e.props.size(), Column());
      const bool face = ei == face_elem_;
      std::vector<char> claimed(e.props.size(), 0);
      if (face) {
        if (index_prop_ >= 0) claimed[static_cast<size_t>(index_prop_)] = 1;
      } else {
        for (int a = 0; a < 3; ++a)
          if (coord_prop_[a] >= 0) claimed[static_cast<size_t>(coord_prop_[a])] = 1;
      }
      std::vector<AttrBuild> planned;
      auto find = [&](const std::string& n) -> int {
        for (size_t k = 0; k < e.props.size(); ++k)
          if (!claimed[k] && !e.props[k].list && e.props[k].name == n) return static_cast<int>(k);
        return -1;
      };
      auto add = [&](std::vector<int> ks, const std::string& name, AttributeKind kind) {
        AttrBuild b;
        b.a.name = name;
        b.a.kind = kind;
        b.a.domain = face ? AttributeDomain::face : AttributeDomain::vertex;
        b.a.components = static_cast<uint32_t>(ks.size());
        b.a.type = attribute_type(e.props[static_cast<size_t>(ks[0])].type);
        b.first_prop = e.props.size();
        for (size_t c = 0; c < ks.size(); ++c) {
          const size_t k = static_cast<size_t>(ks[c]);
          claimed[k] = 1;
          b.a.type = combine_types(b.a.type, attribute_type(e.props[k].type));
          b.first_prop = std::min(b.first_prop, k);
          // The column's attribute number is set once the order is known.
          columns_[ei][k].comp = static_cast<uint32_t>(c);
        }
        planned.push_back(std::move(b));
        group_props_.push_back(std::move(ks));
      };
      group_props_.clear();
      auto group = [&](std::initializer_list<const char*> names, const char* optional, AttributeKind kind,
                       const char* name) {
        std::vector<int> ks;
        for (const char* n : names) {
          const int k = find(n);
          if (k < 0) return false;
          ks.push_back(k);
        }
        if (optional) {
          const int k = find(optional);
          if (k >= 0) ks.push_back(k);
        }
        add(std::move(ks), name, kind);
        return true;
      };
      group({"nx", "ny", "nz"}, nullptr, AttributeKind::normal, "normal");
      group({"red", "green", "blue"}, "alpha", AttributeKind::color, "color");
      if (!group({"s", "t"}, nullptr, AttributeKind::texcoord, "texcoord") &&
          !group({"u", "v"}, nullptr, AttributeKind::texcoord, "texcoord") &&
          !group({"texture_u", "texture_v"}, nullptr, AttributeKind::texcoord, "texcoord"))
        group({"texture_s", "texture_t"}, nullptr, AttributeKind::texcoord, "texcoord");
      // NAME_0 NAME_1 ...: a generic vector.
      for (size_t k = 0; k < e.props.size(); ++k) {
        const Property& p = e.props[k];
        if (claimed[k] || p.list || p.name.size() < 3 || p.name.compare(p.name.size() - 2, 2, "_0") != 0) continue;
        const std::string base = p.name.substr(0, p.name.size() - 2);
        std::vector<int> ks{static_cast<int>(k)};
        for (size_t j = 1; j < 4 && k + j < e.props.size(); ++j) {
          const Property& q = e.props[k + j];
          if (claimed[k + j] || q.list || q.type != p.type || q.name != base + "_" + std::to_string(j)) break;
          ks.push_back(static_cast<int>(k + j));
        }
        if (ks.size() >= 2) add(std::move(ks), base, AttributeKind::generic);
      }
      for (size_t k = 0; k < e.props.size(); ++k)
        if (!claimed[k] && !e.props[k].list) add({static_cast<int>(k)}, e.props[k].name, AttributeKind::generic);
      if (face) {
        for (size_t k = 0; k < e.props.size(); ++k) {
          if (claimed[k] || !e.props[k].list) continue;
          add({static_cast<int>(k)}, e.props[k].name, AttributeKind::generic);
          AttrBuild& b = planned.back();
          b.corner_list = true;
          b.a.domain = AttributeDomain::corner;
          if (b.a.name == "texcoord") {
            b.a.kind = AttributeKind::texcoord;
            b.fixed_k = 2;
          }
        }
      }
      // Attributes in the order of their first property.
      std::vector<size_t> order(planned.size());
      for (size_t i = 0; i < order.size(); ++i) order[i] = i;
      std::stable_sort(order.begin(), order.end(),
                       [&](size_t x, size_t y) { return planned[x].first_prop < planned[y].first_prop; });
      for (size_t i : order) {
        const int id = static_cast<int>(attrs_.size());
        for (int k : group_props_[i]) columns_[ei][static_cast<size_t>(k)].attr = id;
        attrs_.push_back(std::move(planned[i]));
      }
    }
  }

  // Vertex attributes get their room once the vertex count has been
  // checked against the bytes left.
  void size_vertex_attributes(size_t count) {
    for (AttrBuild& b : attrs_)
      if (b.a.domain == AttributeDomain::vertex) b.a.values.assign(count * b.a.components, 0.0f);
  }

  // Attribute values are finite unless the options allow otherwise.
  Status check_value(float x, const Element& e, uint64_t item, const Property& prop, const unsigned char* at,
                     const TextCursor* cur) const {
    if (options_.allow_nonfinite || std::isfinite(x)) return Status::Ok();
    const std::string what = e.name + " " + std::to_string(item) + " has a non-finite value " + float_text(x) +
                             " in property '" + prop.name +
                             "'; pass --allow-nonfinite (ReadOptions::allow_nonfinite) to accept it";
    return cur ? cur->error(what) : bin_error(at, what);
  }

  void note_inexact(AttrBuild& b, uint64_t item, const Property& prop) {
    if (b.inexact++ == 0) {
      b.inexact_item = item;
      b.inexact_prop = prop.name;
    }
  }

  // Face element: a face item begins (its values may be taken back when the
  // face turns out to have no corners).
  void begin_face_item() {
    for (AttrBuild& b : attrs_)
      if (b.a.domain != AttributeDomain::vertex && !b.dropped) {
        b.item_start = b.a.values.size();
        if (!b.corner_list) b.a.values.resize(b.item_start + b.a.components);
      }
  }

  // Face element: the face item ended with n corners kept (0: skipped).
  // Returns an error text (empty when fine) and the attribute it is about.
  std::string end_face_item(uint64_t f, size_t n, const AttrBuild*& about) {
    for (AttrBuild& b : attrs_) {
      if (b.a.domain == AttributeDomain::vertex || b.dropped) continue;
      const size_t got = b.a.values.size() - b.item_start;
      if (n == 0) {
        b.a.values.resize(b.item_start);
        continue;
      }
      if (!b.corner_list) continue;
      if (b.fixed_k) {
        if (got == 0) {
          if (!b.empty_lists) b.first_empty = f;
          b.empty_lists = true;
        } else {
          if (got != b.fixed_k * n) {
            about = &b;
            return "face " + std::to_string(f) + ": property '" + b.a.name + "' holds " + std::to_string(got) +
                   " values; expected " + std::to_string(b.fixed_k) + " per corner (" + std::to_string(b.fixed_k * n) +
                   " for its " + std::to_string(n) + " corners)";
          }
          if (!b.had_values) b.first_values = f;
          b.had_values = true;
        }
        if (b.empty_lists && b.had_values) {
          // Faces without texture coordinates among faces with them: Mesh
          // has no "none" value, so the attribute cannot be kept.
          note("skipped list property '" + b.a.name + "' of element 'face': face " + std::to_string(b.first_empty) +
               " has none while face " + std::to_string(b.first_values) +
               " has some (a per-corner attribute needs values on every face)");
          b.dropped = true;
          b.a.values.clear();
          b.a.values.shrink_to_fit();
        }
        continue;
      }
      const size_t k = got % n == 0 ? got / n : 0;
      if (k >= 1 && k <= 4 && (b.k == 0 || b.k == k)) {
        b.k = static_cast<uint32_t>(k);
        continue;
      }
      note("skipped list property '" + b.a.name + "' of element 'face': face " + std::to_string(f) + " has " +
           std::to_string(got) + " values for " + std::to_string(n) +
           " corners (a per-corner attribute needs the same 1 to 4 values per corner on every face)");
      b.dropped = true;
      b.a.values.clear();
      b.a.values.shrink_to_fit();
    }
    return std::string();
  }

  // A corner list's values, one per corner as read, shared where equal
  // (the same float bits), in the order the corners first use them: the
  // value lists of the mesh tsm wrote, so it re-encodes to the same bytes.
  static void share_corner_values(Attribute& a, size_t corners) {
    const size_t k = a.components;
    std::map<std::vector<uint32_t>, uint32_t> id;
    std::vector<uint32_t> bits(k);
    std::vector<float> values;
    a.indices.resize(corners);
    for (size_t i = 0; i < corners; ++i) {
      std::memcpy(bits.data(), &a.values[k * i], 4 * k);
      auto it = id.emplace(bits, static_cast<uint32_t>(id.size())).first;
      if (it->second == values.size() / k)
        values.insert(values.end(), a.values.begin() + static_cast<std::ptrdiff_t>(k * i),
                      a.values.begin() + static_cast<std::ptrdiff_t>(k * (i + 1)));
      a.indices[i] = it->second;
    }
    a.values = std::move(values);
  }

  // Hands the attributes read to the mesh.
  void finish_attributes() {
    for (AttrBuild& b : attrs_) {
      if (b.dropped) continue;
      Attribute& a = b.a;
      if (b.corner_list) {
        if (b.fixed_k) {
          if (!b.had_values) {
            if (b.empty_lists) note("ignored the empty '" + a.name + "' lists of element 'face'");
            continue;
          }
          b.k = b.fixed_k;
        }
        if (b.k == 0) continue;  // no face with corners: nothing to keep
        a.components = b.k;
        if (a.name == "normal" && b.k == 3) a.kind = AttributeKind::normal;
        if (a.name == "color" && b.k >= 3) a.kind = AttributeKind::color;
        share_corner_values(a, out_.indices.size());
      }
      if (b.inexact > 0) {
        a.type = AttributeType::f32;
        const std::string elem = a.domain == AttributeDomain::vertex ? "vertex" : "face";
        note("property '" + b.inexact_prop + "' of element '" + elem + "': " + std::to_string(b.inexact) +
             " integer value(s) beyond float precision (first at " + elem + " " + std::to_string(b.inexact_item) +
             "); attribute '" + a.name + "' is kept as f32, rounded");
      }
      out_.attributes.push_back(std::move(a));
    }
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
    size_vertex_attributes(count);
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
      // Attribute columns, one at a time.
      size_t at = 0;
      for (size_t k = 0; k < e.props.size(); ++k) {
        const Property& prop = e.props[k];
        const Column col = columns_[vertex_elem_][k];
        if (col.attr >= 0) {
          AttrBuild& b = attrs_[static_cast<size_t>(col.attr)];
          const size_t n = b.a.components;
          float* vals = b.a.values.data();
          const unsigned char* s = base + at;
          for (size_t v = 0; v < count; ++v, s += stride) {
            bool inexact = false;
            const float x = load_value(prop.type, s, big_, inexact);
            if (inexact) note_inexact(b, v, prop);
            TSM_RETURN_IF_ERROR(check_value(x, e, v, prop, s, nullptr));
            vals[v * n + col.comp] = x;
          }
        }
        at += type_size(prop.type);
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
        const Column col = columns_[vertex_elem_][k];
        if (col.attr >= 0) {
          AttrBuild& b = attrs_[static_cast<size_t>(col.attr)];
          bool inexact = false;
          const float x = load_value(prop.type, p_, big_, inexact);
          if (inexact) note_inexact(b, v, prop);
          TSM_RETURN_IF_ERROR(check_value(x, e, v, prop, p_, nullptr));
          b.a.values[v * b.a.components + col.comp] = x;
        }
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
    // General layout: any count/item types, other properties read as
    // attributes or skipped.
    const std::vector<Column>& columns = columns_[face_elem_];
    for (uint64_t f = 0; f < count; ++f) {
      bool got = false;
      const size_t corners_before = out_.indices.size();
      begin_face_item();
      for (size_t k = 0; k < e.props.size(); ++k) {
        const Property& prop = e.props[k];
        AttrBuild* b = columns[k].attr >= 0 ? &attrs_[static_cast<size_t>(columns[k].attr)] : nullptr;
        if (b && b->dropped) b = nullptr;
        if (!prop.list) {
          const size_t s = type_size(prop.type);
          if (static_cast<size_t>(end_ - p_) < s) return truncated(p_, e, f);
          if (b) {
            bool inexact = false;
            const float x = load_value(prop.type, p_, big_, inexact);
            if (inexact) note_inexact(*b, f, prop);
            TSM_RETURN_IF_ERROR(check_value(x, e, f, prop, p_, nullptr));
            b->a.values[b->item_start + columns[k].comp] = x;
          }
          p_ += s;
          continue;
        }
        const unsigned char* list_start = p_;
        uint64_t n;
        TSM_RETURN_IF_ERROR(bin_list(prop, e, f, n));
        const size_t s = type_size(prop.type);
        if (static_cast<int>(k) != index_prop_ || got) {
          if (b) {  // a per-corner list (n items fit in the bytes left: bin_list checked)
            b->list_at = static_cast<size_t>(list_start - begin_);
            for (uint64_t j = 0; j < n; ++j, p_ += s) {
              bool inexact = false;
              const float x = load_value(prop.type, p_, big_, inexact);
              if (inexact) note_inexact(*b, f, prop);
              TSM_RETURN_IF_ERROR(check_value(x, e, f, prop, p_, nullptr));
              b->a.values.push_back(x);
            }
            continue;
          }
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
      const AttrBuild* about = nullptr;
      const std::string what = end_face_item(f, out_.indices.size() - corners_before, about);
      if (!what.empty()) return binary_error(name_, about->list_at, what);
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

  // Reads one attribute value of property type t into x (integer types:
  // an integer of that type's range; "255.0" is accepted).
  Status ascii_value(TextCursor& cur, const Element& e, uint64_t i, const Property& prop, PlyType t, AttrBuild& b,
                     float& x) {
    if (!is_integer(t)) {
      if (t == PlyType::f32) {
        if (!cur.parse_float(x)) return value_error(cur, e, i, prop, "a number");
      } else {
        double d;
        if (!cur.parse_float(d)) return value_error(cur, e, i, prop, "a number");
        x = to_float(d);
      }
      return check_value(x, e, i, prop, nullptr, &cur);
    }
    cur.skip_blanks();
    const char* start = cur.position();
    const size_t line = cur.line();
    int64_t v;
    if (!cur.parse_int(v)) {
      double d;
      if (!cur.parse_float(d)) return value_error(cur, e, i, prop, "a number");
      if (!(d == std::floor(d)) || std::fabs(d) > 9e18) {
        cur.set_position(start, line);
        return value_error(cur, e, i, prop, (std::string("an integer (the property is ") + type_name(t) + ")").c_str());
      }
      v = static_cast<int64_t>(d);
    }
    int64_t lo, hi;
    int_range(t, lo, hi);
    if (v < lo || v > hi) {
      cur.set_position(start, line);
      return cur.error(e.name + " " + std::to_string(i) + ": property '" + prop.name + "': " + std::to_string(v) +
                       " is out of range for " + type_name(t) + " (" + std::to_string(lo) + " to " +
                       std::to_string(hi) + ")");
    }
    bool inexact = false;
    x = int_to_float(v, inexact);
    if (inexact) note_inexact(b, i, prop);
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
    size_vertex_attributes(static_cast<size_t>(e.count));
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
          const Column col = columns_[vertex_elem_][k];
          if (col.attr >= 0) {
            AttrBuild& b = attrs_[static_cast<size_t>(col.attr)];
            float x;
            TSM_RETURN_IF_ERROR(ascii_value(cur, e, v, prop, prop.type, b, x));
            b.a.values[static_cast<size_t>(v) * b.a.components + col.comp] = x;
          } else if (a < 0) {
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
    const std::vector<Column>& columns = columns_[face_elem_];
    for (uint64_t f = 0; f < e.count; ++f) {
      TSM_RETURN_IF_ERROR(start_ascii_item(cur, e, f));
      bool got = false;
      const size_t corners_before = out_.indices.size();
      begin_face_item();
      for (size_t k = 0; k < e.props.size(); ++k) {
        const Property& prop = e.props[k];
        AttrBuild* b = columns[k].attr >= 0 ? &attrs_[static_cast<size_t>(columns[k].attr)] : nullptr;
        if (b && b->dropped) b = nullptr;
        if (!prop.list) {
          if (b) {
            float x;
            TSM_RETURN_IF_ERROR(ascii_value(cur, e, f, prop, prop.type, *b, x));
            b->a.values[b->item_start + columns[k].comp] = x;
          } else {
            TSM_RETURN_IF_ERROR(ascii_skip_value(cur, e, f, prop, prop.type));
          }
          continue;
        }
        uint64_t n;
        TSM_RETURN_IF_ERROR(ascii_count(cur, e, f, prop, n));
        if (static_cast<int>(k) != index_prop_ || got) {
          for (uint64_t j = 0; j < n; ++j) {
            if (b) {  // a per-corner list
              float x;
              TSM_RETURN_IF_ERROR(ascii_value(cur, e, f, prop, prop.type, *b, x));
              b->a.values.push_back(x);
            } else {
              TSM_RETURN_IF_ERROR(ascii_skip_value(cur, e, f, prop, prop.type));
            }
          }
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
      const AttrBuild* about = nullptr;
      const std::string what = end_face_item(f, out_.indices.size() - corners_before, about);
      if (!what.empty()) return cur.error(what);
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

  std::vector<AttrBuild> attrs_;
  std::vector<std::vector<Column>> columns_;  // [element][property]
  std::vector<std::vector<int>> group_props_;  // planning scratch: properties of each planned attribute

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

const char* ply_type_name(AttributeType t) {
  switch (t) {
    case AttributeType::u8: return "uchar";
    case AttributeType::u16: return "ushort";
    case AttributeType::i32: return "int";
    case AttributeType::f32: break;
  }
  return "float";
}

size_t value_size(AttributeType t) {
  switch (t) {
    case AttributeType::u8: return 1;
    case AttributeType::u16: return 2;
    case AttributeType::i32:
    case AttributeType::f32: break;
  }
  return 4;
}

// One value, little endian (integer types hold integers of their range:
// checked before writing starts).
char* put_value(char* w, AttributeType t, float x) {
  switch (t) {
    case AttributeType::u8: *w++ = static_cast<char>(static_cast<uint8_t>(x)); return w;
    case AttributeType::u16: {
      const uint16_t v = static_cast<uint16_t>(x);
      *w++ = static_cast<char>(v & 0xff);
      *w++ = static_cast<char>(v >> 8);
      return w;
    }
    case AttributeType::i32: return put_u32_le(w, static_cast<uint32_t>(static_cast<int32_t>(x)));
    case AttributeType::f32: break;
  }
  uint32_t b;
  std::memcpy(&b, &x, 4);
  return put_u32_le(w, b);
}

// One value as ascii text: shortest round-trip float, or an integer.
char* put_value_text(char* w, char* end, AttributeType t, float x) {
  if (t == AttributeType::f32) return std::to_chars(w, end, x).ptr;
  return std::to_chars(w, end, static_cast<int64_t>(x)).ptr;
}

// How the attributes are laid out in the file.
struct OutScalar {
  const Attribute* a;
  uint32_t comp;
};
struct OutList {
  const Attribute* a;
  bool wide;  // uint count instead of uchar
};
struct OutLayout {
  std::vector<OutScalar> vertex, face;
  std::vector<OutList> corner;
  std::string vertex_props, face_props, corner_props;  // header lines
};

// A property name the header can hold: one word of printable characters.
bool is_token(const std::string& s) {
  if (s.empty()) return false;
  for (char c : s)
    if (static_cast<unsigned char>(c) <= 0x20 || static_cast<unsigned char>(c) >= 0x7f) return false;
  return true;
}

std::string attribute_label(const Attribute& a, size_t k) {
  return "attribute " + std::to_string(k) + " (" + quoted(a.name) + ")";
}

// Integer types must hold integers of their range, or the file could not
// say them.
Status check_integer_values(const Attribute& a, size_t k) {
  double lo = 0, hi = 0;
  switch (a.type) {
    case AttributeType::f32: return Status::Ok();
    case AttributeType::u8: hi = 255; break;
    case AttributeType::u16: hi = 65535; break;
    case AttributeType::i32: lo = -2147483648.0, hi = 2147483647.0; break;
  }
  for (size_t i = 0; i < a.values.size(); ++i) {
    const double x = a.values[i];
    if (!(x >= lo && x <= hi) || x != std::floor(x))
      return Status(ErrorCode::invalid_argument,
                    "cannot write PLY: " + attribute_label(a, k) + " is of type " + ply_type_name(a.type) +
                        " but its value " + std::to_string(i) + " is " + float_text(a.values[i]) +
                        ", not an integer from " + std::to_string(static_cast<int64_t>(lo)) + " to " +
                        std::to_string(static_cast<int64_t>(hi)));
  }
  return Status::Ok();
}

Status plan_layout(const Mesh& mesh, OutLayout& out) {
  std::vector<std::string> vertex_names{"x", "y", "z"}, face_names{"vertex_indices"};
  bool first_done[3][4] = {};  // [domain][kind]: the conventional names are taken
  for (size_t k = 0; k < mesh.attributes.size(); ++k) {
    const Attribute& a = mesh.attributes[k];
    TSM_RETURN_IF_ERROR(check_integer_values(a, k));
    const size_t d = static_cast<size_t>(a.domain);
    const size_t kind = static_cast<size_t>(a.kind);
    const bool conventional = a.kind != AttributeKind::generic && !first_done[d][kind];
    if (conventional) first_done[d][kind] = true;
    std::vector<std::string> names;
    if (a.domain == AttributeDomain::corner) {
      names.push_back(!conventional                         ? a.name
                      : a.kind == AttributeKind::texcoord ? "texcoord"
                      : a.kind == AttributeKind::normal   ? "normal"
                                                          : "color");
    } else if (conventional && a.kind == AttributeKind::normal) {
      names = {"nx", "ny", "nz"};
    } else if (conventional && a.kind == AttributeKind::color) {
      names = {"red", "green", "blue"};
      if (a.components == 4) names.push_back("alpha");
    } else if (conventional && a.kind == AttributeKind::texcoord) {
      names = {"s", "t"};
    } else if (a.components == 1) {
      names.push_back(a.name);
    } else {
      for (uint32_t c = 0; c < a.components; ++c) names.push_back(a.name + "_" + std::to_string(c));
    }
    const bool on_vertex = a.domain == AttributeDomain::vertex;
    std::vector<std::string>& used = on_vertex ? vertex_names : face_names;
    for (const std::string& n : names) {
      if (!is_token(n))
        return Status(ErrorCode::invalid_argument, "cannot write PLY: " + attribute_label(a, k) +
                                                       " cannot be a PLY property: " + quoted(n) +
                                                       " is not one word of printable characters");
      if (std::find(used.begin(), used.end(), n) != used.end())
        return Status(ErrorCode::invalid_argument,
                      "cannot write PLY: " + attribute_label(a, k) + " would be written as property " + quoted(n) +
                          " of element '" + (on_vertex ? "vertex" : "face") + "', which another property has");
      used.push_back(n);
    }
    const std::string type = ply_type_name(a.type);
    if (a.domain == AttributeDomain::corner) {
      size_t most = 0;
      for (size_t f = 0; f < mesh.face_count(); ++f)
        most = std::max(most, static_cast<size_t>(mesh.face_size(f)) * a.components);
      const bool wide = most > 255;
      out.corner.push_back({&a, wide});
      out.corner_props += std::string("property list ") + (wide ? "uint " : "uchar ") + type + " " + names[0] + "\n";
    } else {
      for (uint32_t c = 0; c < a.components; ++c) {
        (on_vertex ? out.vertex : out.face).push_back({&a, c});
        (on_vertex ? out.vertex_props : out.face_props) += "property " + type + " " + names[c] + "\n";
      }
    }
  }
  return Status::Ok();
}

// The header both writers share: positions, then `vertex_props`; the face
// list, then `face_props`. Returns whether face sizes need a uint count
// (some face has more than 255 corners).
bool write_header(const Mesh& mesh, const WriteOptions& options, const std::string& vertex_props,
                  const std::string& face_props, std::string& out) {
  uint32_t largest = 0;
  for (size_t f = 0; f < mesh.face_count(); ++f) largest = std::max(largest, mesh.face_size(f));
  const bool wide_count = largest > 255;
  out.clear();
  out += "ply\n";
  out += options.ascii ? "format ascii 1.0\n" : "format binary_little_endian 1.0\n";
  out += "comment written by tsm\n";
  out += "element vertex " + std::to_string(mesh.vertex_count()) + "\n";
  out += "property float x\nproperty float y\nproperty float z\n";
  out += vertex_props;
  out += "element face " + std::to_string(mesh.face_count()) + "\n";
  out += wide_count ? "property list uint uint vertex_indices\n" : "property list uchar uint vertex_indices\n";
  out += face_props;
  out += "end_header\n";
  return wide_count;
}

// write_ply for a mesh with attributes (the plain layout keeps its fast path).
Status write_ply_with_attributes(const Mesh& mesh, const WriteOptions& options, std::string& out) {
  OutLayout L;
  TSM_RETURN_IF_ERROR(plan_layout(mesh, L));
  const size_t nv = mesh.vertex_count();
  const size_t nf = mesh.face_count();
  const bool wide_count = write_header(mesh, options, L.vertex_props, L.face_props + L.corner_props, out);

  // Value of attribute a at vertex v, face f, or corner c (component j).
  auto scalar = [](const OutScalar& s, size_t item) { return s.a->values[item * s.a->components + s.comp]; };

  if (!options.ascii) {
    size_t vertex_record = 12, face_fixed = wide_count ? 4 : 1;
    for (const OutScalar& s : L.vertex) vertex_record += value_size(s.a->type);
    for (const OutScalar& s : L.face) face_fixed += value_size(s.a->type);
    size_t per_corner = 4;
    for (const OutList& l : L.corner) {
      face_fixed += l.wide ? 4 : 1;
      per_corner += value_size(l.a->type) * l.a->components;
    }
    const size_t header = out.size();
    out.resize(header + vertex_record * nv + face_fixed * nf + per_corner * mesh.corner_count());
    char* w = &out[header];
    for (size_t v = 0; v < nv; ++v) {
      for (int a = 0; a < 3; ++a) w = put_value(w, AttributeType::f32, mesh.positions[3 * v + static_cast<size_t>(a)]);
      for (const OutScalar& s : L.vertex) w = put_value(w, s.a->type, scalar(s, v));
    }
    for (size_t f = 0; f < nf; ++f) {
      const uint32_t n = mesh.face_size(f);
      const uint32_t* c = mesh.face(f);
      if (wide_count) {
        w = put_u32_le(w, n);
      } else {
        *w++ = static_cast<char>(n);
      }
      for (uint32_t j = 0; j < n; ++j) w = put_u32_le(w, c[j]);
      for (const OutScalar& s : L.face) w = put_value(w, s.a->type, scalar(s, f));
      for (const OutList& l : L.corner) {
        const Attribute& a = *l.a;
        const uint32_t count = n * a.components;
        if (l.wide) {
          w = put_u32_le(w, count);
        } else {
          *w++ = static_cast<char>(count);
        }
        for (uint32_t j = 0; j < n; ++j) {
          const size_t value = a.indices[mesh.face_offsets[f] + j];
          for (uint32_t q = 0; q < a.components; ++q) w = put_value(w, a.type, a.values[value * a.components + q]);
        }
      }
    }
    return Status::Ok();
  }

  char buf[64];
  char* const bend = buf + sizeof buf;
  auto put = [&](AttributeType t, float x) {
    buf[0] = ' ';
    out.append(buf, put_value_text(buf + 1, bend, t, x));
  };
  for (size_t v = 0; v < nv; ++v) {
    out.append(buf, std::to_chars(buf, bend, mesh.positions[3 * v]).ptr);
    put(AttributeType::f32, mesh.positions[3 * v + 1]);
    put(AttributeType::f32, mesh.positions[3 * v + 2]);
    for (const OutScalar& s : L.vertex) put(s.a->type, scalar(s, v));
    out += '\n';
  }
  for (size_t f = 0; f < nf; ++f) {
    const uint32_t n = mesh.face_size(f);
    const uint32_t* c = mesh.face(f);
    out.append(buf, std::to_chars(buf, bend, n).ptr);
    for (uint32_t j = 0; j < n; ++j) {
      buf[0] = ' ';
      out.append(buf, std::to_chars(buf + 1, bend, c[j]).ptr);
    }
    for (const OutScalar& s : L.face) put(s.a->type, scalar(s, f));
    for (const OutList& l : L.corner) {
      const Attribute& a = *l.a;
      buf[0] = ' ';
      out.append(buf, std::to_chars(buf + 1, bend, n * a.components).ptr);
      for (uint32_t j = 0; j < n; ++j) {
        const size_t value = a.indices[mesh.face_offsets[f] + j];
        for (uint32_t q = 0; q < a.components; ++q) put(a.type, a.values[value * a.components + q]);
      }
    }
    out += '\n';
  }
  return Status::Ok();
}

}  // namespace

Status read_ply(std::string_view bytes, const std::string& name, Mesh& out, const ReadOptions& options,
                ReadInfo* info) {
  PlyReader reader(bytes, name, out, options, info);
  Status s = reader.run();
  if (!s.ok()) out.clear();  // never hand back half a mesh
  return s;
}

Status write_ply(const Mesh& mesh, const WriteOptions& options, std::string& out, WriteInfo* info) {
  std::string why;
  if (!mesh.valid(&why)) return Status(ErrorCode::invalid_argument, "cannot write PLY: the mesh is invalid: " + why);
  note_not_written(mesh, "PLY", "", nullptr, info);
  if (!mesh.attributes.empty()) return write_ply_with_attributes(mesh, options, out);
  const size_t nv = mesh.vertex_count();
  const size_t nf = mesh.face_count();
  const bool wide_count = write_header(mesh, options, "", "", out);

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

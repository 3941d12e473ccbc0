// OFF (Object File Format) reading (file-format stage, not part of the
// compression method): turns an OFF file into a Mesh.
//
// Accepted: the header keyword OFF with the optional prefixes of the
// Geomview family in their order, ST (texture coordinates), C (colours),
// N (normals) -- "OFF", "COFF", "NOFF", "STOFF", "CNOFF", "STCNOFF" -- then the
// counts "V F E" (E ignored, may be missing), V vertices and F faces
// "n i0 .. i(n-1)" with 0-based indices. The counts may follow the keyword on
// its line, also glued to it ("OFF8 6 0", as some exporters write).
// Coordinates and indices may span lines; after a vertex's x y z and after a
// face's n indices the rest of that line is skipped, which is how colours,
// normals and texture coordinates are ignored safely (each record sits on one
// line in practice, and this holds whatever their number). "#" starts a
// comment. 4OFF (homogeneous), nOFF (any dimension) and OFF BINARY are
// refused as unsupported. Faces are kept as read (polygons, 1 or 2 corners).
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "text_scan.hpp"
#include "tsm/io.hpp"

namespace tsm {

namespace {

constexpr uint64_t kMaxIndexableVertices = std::numeric_limits<uint32_t>::max();


class OffReader {
 public:
  OffReader(std::string_view bytes, const std::string& name, const ReadOptions& options)
      : cur_(bytes, name), end_(bytes.data() + bytes.size()), options_(options) {}

  Status run(Mesh& mesh);

 private:
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
};

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
  take("ST");
  take("C");
  take("N");
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

Status OffReader::run(Mesh& mesh) {
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
    cur_.next_line();  // normals, colours, texture coordinates
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
    cur_.next_line();  // face colour
  }
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
  Status st = reader.run(mesh);
  if (!st.ok()) {
    out.clear();
    return st;
  }
  out = std::move(mesh);
  return Status::Ok();
}

}  // namespace tsm

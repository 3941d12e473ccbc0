// glTF 2.0 reader and writer (file-format stage, not part of the compression
// method): .gltf (JSON with data-URI or external buffers) and .glb (binary
// container) to a tsm::Mesh and back, through Debian's tinygltf (JSON and
// container parsing) with nlohmann-json (the pass-through document). Images
// are never decoded (no stb): tinygltf is built here without image loading;
// their bytes travel untouched in the pass-through entry (below).
//
// Reading: the geometry
//   - The meshes instanced by the nodes of the default scene (`scene`, else
//     scene 0; every mesh when the file has no scene), each mesh once however
//     many nodes use it, in the order the node tree (depth first) meets them.
//     Node transforms are NOT applied: positions are kept as stored (the
//     transforms stay in the document). Several meshes / primitives are
//     concatenated into one tsm::Mesh (noted).
//   - Triangles (mode 4) as stored, degenerate ones included; strips (5) and
//     fans (6) become triangles with the winding the spec gives, dropping the
//     degenerate triangles strips use for stitching (noted). Points and lines
//     (modes 0..3): their vertices are kept (as vertices no face uses, like
//     OBJ's `v` records next to `l` ones), the points and lines are skipped
//     and counted in ReadInfo::skipped_elements.
//   - POSITION -> positions; NORMAL -> vertex attribute "normal";
//     TEXCOORD_n -> "texcoord<n>"; COLOR_0 -> "color", COLOR_n -> "color<n>"
//     (normalized unsigned byte / short -> type u8 / u16 holding 0..255 /
//     0..65535, float -> f32); any other attribute (TANGENT, JOINTS_n,
//     WEIGHTS_n, _CUSTOM) -> a generic vertex attribute under its glTF name
//     (float -> f32, unsigned byte / short -> u8 / u16 integers, byte / short
//     -> i32 integers). Normalized or integer normals and texture
//     coordinates (KHR_mesh_quantization) become floats as the spec decodes
//     them. Morph targets: each displacement (POSITION / NORMAL / TANGENT of
//     target t) -> the float vertex attribute "_gltf_target<t>_<SEMANTIC>".
//     Primitives with the same vertex accessors (attributes and targets)
//     share vertices: they form one "vertex group". When groups disagree on
//     attributes, missing values are filled (zeros; colours opaque white) and
//     differing types widened (noted).
//   - Indices of any unsigned type; none: 0..n-1.
//
// Reading: everything else (the pass-through entry)
//   The reader adds Mesh::metadata "gltf", which the codec stores and gives
//   back unchanged, holding the whole document but the geometry it turned
//   into mesh data. Its value (version 1, all integers little endian):
//       "tsmG"  u32 version = 1  u32 J  J bytes of JSON  BIN (the rest)
//   The JSON (compact, member order of the input, deterministic) is
//       {"tsm_gltf": 1,
//        "vertex_groups": [vertex count of group 0, ...],
//        "face_sets": [[group, triangle count], ...],
//        "accessors": [fill, ...],
//        "document": the glTF JSON}
//   A face set is the triangles of one primitive (a primitive repeating
//   another one's data shares its face set). The mesh holds group 0's
//   vertices, then group 1's, ..., and face set 0's triangles, then 1's, ...;
//   the codec reorders both, so two tags travel as integer attributes: the
//   vertex attribute "_gltf_group" (u16; i32 past 65536 groups) when there
//   are two groups or more, and the face attribute "_gltf_primitive" (the
//   face set) when a group has two face sets or more. Without a tag the
//   answer is unique (group 0; the only face set of the face's group).
//   A fill names an accessor of the document the writer fills from the mesh:
//       {"accessor": i, "group": g, "semantic": "POSITION"}
//       {"accessor": i, "group": g, "semantic": "NORMAL", "attribute": "normal",
//        "components": 3}                      (a vertex attribute)
//       {"accessor": i, "group": g, "semantic": "POSITION", "target": t,
//        "attribute": "_gltf_target<t>_POSITION", "components": 3}
//       {"accessor": i, "face_set": k}         (indices)
//   The document is the input JSON (nlohmann ordered_json, so numbers,
//   strings, member order, extensions and extras are as given) where:
//     - accessors keep their indices, so every reference to an accessor
//       (animations, skins, EXT_mesh_gpu_instancing, extensions tsm does
//       not know) stays valid. A geometry accessor only the primitives read
//       use becomes a placeholder (name, extras, extensions kept; data
//       fields removed) that the writer fills; a second use of it (another
//       vertex group, a strip's indices) gets a new accessor after the last.
//       Accessors anything else uses (meshes outside the scene, animation,
//       skin, instancing data, unused ones) keep their bytes.
//     - the primitives read name their fills: attributes and targets the
//       reader kept (ones it did not, e.g. NORMAL as VEC4, are left out of
//       the primitive, noted), indices, mode 4 for triangles, strips and
//       fans, mode 0 (points, no indices) for points and lines primitives
//       and triangle primitives without a triangle; a
//       KHR_draco_mesh_compression extension is removed (its data is the
//       mesh's now; Draco-only primitives are refused as before).
//     - the buffer views still used (by kept accessors, sparse data,
//       images, Draco data of meshes outside the scene) are copied, in their
//       order and each at its old offset modulo 4, into one buffer (BIN),
//       and renumbered; the others are gone. All buffers become that one
//       buffer (external .bin files and data URIs included); images as data
//       URIs or external URIs keep their URI.
//     - extensionsUsed loses EXT_meshopt_compression (its fallback views are
//       kept uncompressed) and KHR_draco_mesh_compression when no primitive
//       uses it any more.
//   Meshes outside the default scene are not mesh data: they are kept with
//   their bytes in BIN, not compressed by the codec. A mesh used by several
//   nodes stays one mesh (nodes are untouched).
//
// Compressed data (KHR_draco_mesh_compression, EXT/KHR_meshopt_compression,
// TSM_mesh_compression): a primitive that offers an uncompressed copy is
// read from the copy; when the document needs its compressed data, the
// transcoder (gltf_transcode.hpp) decodes it into a plain document first
// (Draco and meshopt only when tsm was built with them). NaN / infinite
// float values are refused unless ReadOptions::allow_nonfinite.
//
// Robustness: the GLB container is checked here before tinygltf sees it, the
// JSON nesting depth is bounded (tinygltf walks `extras` recursively), and
// every accessor (dense and sparse) is checked against its buffer view and
// buffer before a byte is read: types, strides, offsets, counts, sparse
// indices, vertex indices; every buffer view copied to the pass-through
// entry likewise. What the primitives produce is bounded by a small
// multiple of the input's bytes (accessors reused by many primitives cannot
// blow up memory), and by ReadOptions::max_vertices / max_faces. External
// buffer files are read only from ReadOptions::external_files_dir (set by
// read_mesh to the file's folder), only regular files, never otherwise.
//
// Writing with a "gltf" entry (a mesh read from glTF, or decoded from a .tsm
// made from one): the entry's document with the mesh's geometry put back.
// The vertices of each group in mesh order make its accessors (POSITION
// with min / max, morph target POSITION too; u8 / u16 integer attributes
// as unsigned byte / short, normalized for COLOR_n and WEIGHTS_n; the rest
// float), the triangles of each face set in mesh order its indices (uint16
// when the group has at most 65535 vertices, else uint32), appended to the
// entry's BIN as new buffer views; the tags are not written. GLB: the
// buffer is the BIN chunk; .gltf: a base64 data URI. The entry is checked
// before use and never trusted: a wrong magic, version or length, JSON that
// does not parse or nests too deep, a fill naming no accessor or one twice,
// counts or tags that do not match the mesh (vertex and triangle counts
// per group and face set, a triangle using another group's vertex, an
// attribute missing) give ErrorCode::corrupt_data (the entry is damaged) or
// invalid_argument (the mesh is not the one the entry describes), never a
// crash; nothing is allocated beyond the mesh's and the entry's own sizes.
// Polygons, corner attributes, face attributes other than the tag and
// non-finite positions are refused as below.
//
// Writing without one: one mesh, one primitive, one buffer (GLB: the BIN
// chunk; .gltf: a base64 data URI). Triangles only: a mesh with other faces
// is refused (write PLY or OBJ to keep polygons) rather than silently
// triangulated. A mesh with vertices but no faces is written as a points
// primitive (which reads back as the same vertices). POSITION with min /
// max, NORMAL, TEXCOORD_0.. (numbered in order), COLOR_0.. (u8 / u16
// colours as normalized unsigned byte / short, padded to 4-byte elements),
// other vertex attributes as custom `_name` semantics (names that are glTF
// semantics already, or start with '_', are kept; f32 and i32 as float, u8 /
// u16 as unsigned byte / short, normalized for WEIGHTS_n only). The empty
// mesh is written as a file without scene or mesh (glTF has no empty
// primitive). Indices are uint16 when every vertex index fits (< 65535),
// else uint32. Face and corner attributes cannot be expressed without
// splitting vertices, which tsm does not do silently: they are refused (PLY
// or OBJ keep them), as are non-finite positions (POSITION min / max must be
// numbers).
//
// Limits of the pass-through: primitives with different vertex accessors
// that share some of them (the same POSITION, another NORMAL) are separate
// groups, so their shared accessors are written twice; lines come back as
// points; buffer views named only inside unknown extensions are not kept
// (accessors are, by index); a mesh edited between reading and writing must
// keep the tags and the per-group counts, or the writer refuses it.
// Our copy of tinygltf lives in a namespace of its own. Draco's shared
// library (linked into `tsm bench`) carries another tinygltf, of another
// version, under the name `tinygltf`: with the same names, the dynamic linker
// binds Draco's calls to our functions (the executable's definitions win),
// and Draco's glTF reader frees our Model layout as its own (heap
// corruption). With this name nothing of ours can stand in for Draco's.
#define tinygltf tsm_tinygltf
#define TINYGLTF_IMPLEMENTATION
#define TINYGLTF_NO_STB_IMAGE
#define TINYGLTF_NO_STB_IMAGE_WRITE
#define TINYGLTF_NO_EXTERNAL_IMAGE
#define TINYGLTF_NO_FS  // file access only through the callbacks below
#include <fstream>      // tinygltf 2.7's file writers need it even without its file system
#include <tiny_gltf.h>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#if defined(__linux__) && __has_include(<linux/openat2.h>)
#include <linux/openat2.h>  // openat2 and RESOLVE_BENEATH: external buffers stay inside their folder
#include <sys/syscall.h>
#if defined(SYS_openat2)
#define TSM_HAVE_OPENAT2 1
#endif
#endif

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <map>
#include <new>
#include <set>
#include <sstream>
#include <string>
#include <string_view>
#include <tuple>
#include <vector>

#include "gltf_types.hpp"
#include "gltf_files.hpp"
#include "tsm/gltf_transcode.hpp"
#include "tsm/io.hpp"

#ifndef TSM_VERSION
#define TSM_VERSION "unknown"
#endif

namespace tsm {

namespace {

constexpr int kByte = TINYGLTF_COMPONENT_TYPE_BYTE;
constexpr int kUByte = TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE;
constexpr int kShort = TINYGLTF_COMPONENT_TYPE_SHORT;
constexpr int kUShort = TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT;
constexpr int kUInt = TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT;
constexpr int kFloat = TINYGLTF_COMPONENT_TYPE_FLOAT;

constexpr uint32_t kGlbMagic = 0x46546C67;  // "glTF"
constexpr uint32_t kChunkJson = 0x4E4F534A;
constexpr uint32_t kChunkBin = 0x004E4942;
constexpr size_t kMaxJsonDepth = 128;
constexpr uint64_t kMaxIndex = std::numeric_limits<uint32_t>::max();

// The pass-through entry (Mesh::metadata "gltf"): see the top of the file.
using ojson = nlohmann::ordered_json;
const char* const kPassKey = "gltf";
const char kPassMagic[4] = {'t', 's', 'm', 'G'};
constexpr uint32_t kPassVersion = 1;
const char* const kGroupTag = "_gltf_group";
const char* const kPrimitiveTag = "_gltf_primitive";

const char* component_name(int ct) {
  switch (ct) {
    case kByte: return "byte";
    case kUByte: return "unsigned byte";
    case kShort: return "short";
    case kUShort: return "unsigned short";
    case TINYGLTF_COMPONENT_TYPE_INT: return "int";
    case kUInt: return "unsigned int";
    case kFloat: return "float";
    case TINYGLTF_COMPONENT_TYPE_DOUBLE: return "double";
    default: return "unknown";
  }
}

// Components of an accessor type; 0 for matrices and unknown types.
uint32_t type_components(int type) {
  switch (type) {
    case TINYGLTF_TYPE_SCALAR: return 1;
    case TINYGLTF_TYPE_VEC2: return 2;
    case TINYGLTF_TYPE_VEC3: return 3;
    case TINYGLTF_TYPE_VEC4: return 4;
    default: return 0;
  }
}

const char* type_name(int type) {
  switch (type) {
    case TINYGLTF_TYPE_SCALAR: return "SCALAR";
    case TINYGLTF_TYPE_VEC2: return "VEC2";
    case TINYGLTF_TYPE_VEC3: return "VEC3";
    case TINYGLTF_TYPE_VEC4: return "VEC4";
    case TINYGLTF_TYPE_MAT2: return "MAT2";
    case TINYGLTF_TYPE_MAT3: return "MAT3";
    case TINYGLTF_TYPE_MAT4: return "MAT4";
    default: return "unknown";
  }
}

int type_for_components(uint32_t c) {
  switch (c) {
    case 1: return TINYGLTF_TYPE_SCALAR;
    case 2: return TINYGLTF_TYPE_VEC2;
    case 3: return TINYGLTF_TYPE_VEC3;
    default: return TINYGLTF_TYPE_VEC4;
  }
}

uint32_t load_u32(const unsigned char* p) {
  return static_cast<uint32_t>(p[0]) | static_cast<uint32_t>(p[1]) << 8 | static_cast<uint32_t>(p[2]) << 16 |
         static_cast<uint32_t>(p[3]) << 24;
}
uint16_t load_u16(const unsigned char* p) { return static_cast<uint16_t>(p[0] | p[1] << 8); }

void store_u32(unsigned char* p, uint32_t v) {
  for (int i = 0; i < 4; ++i) p[i] = static_cast<unsigned char>(v >> (8 * i));
}
void store_u16(unsigned char* p, uint16_t v) {
  p[0] = static_cast<unsigned char>(v);
  p[1] = static_cast<unsigned char>(v >> 8);
}
void store_f32(unsigned char* p, float f) {
  uint32_t b;
  std::memcpy(&b, &f, 4);
  store_u32(p, b);
}

// The bytes of a buffer view the writers add: `elements` elements of `elem`
// bytes each, appended to `data` at a multiple of 4 and filled by
// put(i, dst). Vertex data (ARRAY_BUFFER) gets a stride that is a multiple
// of 4 (the spec's alignment rule: u8 RGB colours take 4 bytes each);
// indices are packed. Returns the view's offset and stride.
struct ViewBytes {
  size_t offset, stride;
};
template <class Bytes, class Put>
ViewBytes append_view_bytes(Bytes& data, size_t elements, size_t elem, int target, Put put) {
  const size_t stride = target == TINYGLTF_TARGET_ARRAY_BUFFER ? (elem + 3) & ~size_t{3} : elem;
  while (data.size() % 4) data.push_back(0);
  const size_t at = data.size();
  data.resize(at + elements * stride, 0);
  for (size_t i = 0; i < elements; ++i) put(i, reinterpret_cast<unsigned char*>(&data[at + i * stride]));
  return {at, stride};
}

// One component as float: floats keep their exact bits; integers are their
// value, or the spec's normalized decoding.
float load_value(int ct, bool normalized, const unsigned char* p) {
  switch (ct) {
    case kFloat: {
      uint32_t b = load_u32(p);
      float f;
      std::memcpy(&f, &b, 4);
      return f;
    }
    case kByte: {
      const int v = static_cast<int8_t>(p[0]);
      return normalized ? static_cast<float>(std::max(v / 127.0, -1.0)) : static_cast<float>(v);
    }
    case kUByte: return normalized ? static_cast<float>(p[0] / 255.0) : static_cast<float>(p[0]);
    case kShort: {
      const int v = static_cast<int16_t>(load_u16(p));
      return normalized ? static_cast<float>(std::max(v / 32767.0, -1.0)) : static_cast<float>(v);
    }
    case kUShort: {
      const unsigned v = load_u16(p);
      return normalized ? static_cast<float>(v / 65535.0) : static_cast<float>(v);
    }
    case kUInt: return static_cast<float>(load_u32(p));
    default: return 0.0f;
  }
}

uint32_t load_index(int ct, const unsigned char* p) {
  switch (ct) {
    case kUByte: return p[0];
    case kUShort: return load_u16(p);
    default: return load_u32(p);
  }
}

std::string float_text(float x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.9g", static_cast<double>(x));
  return buf;
}

std::string hex32(uint32_t v) {
  char buf[16];
  std::snprintf(buf, sizeof buf, "0x%08X", v);
  return buf;
}

// Short, printable form of a name for messages.
std::string shown_name(std::string_view s) {
  std::string r = "'";
  for (char c : s.substr(0, 40)) r += (static_cast<unsigned char>(c) < 32 || c == 127) ? '?' : c;
  if (s.size() > 40) r += "...";
  return r + "'";
}

// Deepest nesting of JSON arrays and objects (outside strings); stops
// counting once past `limit`.
size_t json_depth(std::string_view s, size_t limit) {
  size_t depth = 0, deepest = 0;
  bool in_string = false;
  for (size_t i = 0; i < s.size(); ++i) {
    const char c = s[i];
    if (in_string) {
      if (c == '\\') {
        ++i;
      } else if (c == '"') {
        in_string = false;
      }
    } else if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      if (++depth > deepest && (deepest = depth) > limit) return deepest;
    } else if ((c == ']' || c == '}') && depth > 0) {
      --depth;
    }
  }
  return deepest;
}

// tinygltf's messages: several lines, each ending in '\n'.
std::string clean_message(const std::string& s) {
  std::string r;
  bool line_end = false;
  for (char c : s) {
    if (c == '\n' || c == '\r') {
      line_end = true;
      continue;
    }
    if (line_end && !r.empty()) r += "; ";
    line_end = false;
    r += c;
  }
  while (!r.empty() && (r.back() == ' ' || r.back() == ';')) r.pop_back();
  if (r.size() > 400) r = r.substr(0, 400) + "...";
  return r.empty() ? "tinygltf gave no reason" : r;
}

// ---------------------------------------------------------------------------
// External buffer files (tinygltf's file system callbacks)
//
// A .gltf file names its external buffers by relative URI. Only files in the
// .gltf file's folder or below it are read, whatever the spelling: tinygltf
// percent-decodes the URI before it reaches these callbacks (so "%2e%2e" is
// seen as ".."), and the decoded reference must be a plain relative path
// ('/' separated, no ".." component, no backslash, no scheme such as
// "file:", not absolute). The file is then opened relative to the folder
// with the kernel's RESOLVE_BENEATH (openat2), so a symbolic link that leads
// out of the folder is refused too; where openat2 is not available, the
// link-resolved path (realpath) must lie inside the link-resolved folder
// and the last component must not be a link. Only regular files are read.

struct FsContext {
  std::string dir;     // empty: external files are refused
  std::string prefix;  // dir + '/'
  std::string error;   // why a file was refused or could not be read
  std::string refused_reference;  // the decoded URI that was refused (to find its spelling)
  int dir_fd = -1;     // the folder, opened once (O_PATH)
  ~FsContext() {
    if (dir_fd >= 0) ::close(dir_fd);
  }
};

// A URI or path for messages: quoted, control bytes and non-ASCII escaped
// as \xNN, cut after 200 bytes.
std::string shown_uri(std::string_view s) {
  std::string r = "\"";
  for (char c : s.substr(0, 200)) {
    const auto u = static_cast<unsigned char>(c);
    if (u < 32 || u >= 127 || c == '"') {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\x%02X", u);
      r += buf;
    } else {
      r += c;
    }
  }
  if (s.size() > 200) r += "...";
  return r + "\"";
}

// Why a decoded relative reference may not be opened, or "" when it may.
std::string unsafe_reference(const std::string& rel) {
  if (rel.empty()) return "is empty";
  if (rel.find('\0') != std::string::npos) return "contains a NUL byte";
  if (rel.find('\\') != std::string::npos)
    return "contains a backslash (glTF URIs separate folders with '/'; a backslash is not read as a path)";
  // RFC 3986: a scheme ("file:", "http:", a Windows drive "C:") is letters,
  // digits, '+', '-', '.' before the first ':' that comes before any '/'.
  const size_t colon = rel.find(':');
  if (colon != std::string::npos && colon < rel.find('/')) {
    const std::string scheme = rel.substr(0, colon);
    if (scheme.size() == 4 && (scheme[0] | 0x20) == 'f' && (scheme[1] | 0x20) == 'i' && (scheme[2] | 0x20) == 'l' &&
        (scheme[3] | 0x20) == 'e')
      return "is a file: URI (only relative references to files beside the .gltf file are read)";
    return "is an absolute URI or a drive path (scheme or drive " + shown_uri(scheme) +
           "; only relative references to files beside the .gltf file are read)";
  }
  if (rel[0] == '/') return "is an absolute path";
  size_t start = 0;
  for (;;) {
    const size_t end = rel.find('/', start);
    const std::string_view part = std::string_view(rel).substr(start, end == std::string::npos ? std::string::npos : end - start);
    if (part == "..") return "goes up a folder ('..')";
    if (end == std::string::npos) break;
    start = end + 1;
  }
  return "";
}

// Opens `rel` for reading inside ctx->dir (see above). Returns the file
// descriptor, or -1 with ctx->error set.
int open_beneath(FsContext* ctx, const std::string& rel) {
  auto fail = [&](const std::string& why) {
    if (ctx->error.empty()) ctx->error = why;
    return -1;
  };
  if (ctx->dir_fd < 0) {
    ctx->dir_fd = ::open(ctx->dir.c_str(), O_PATH | O_DIRECTORY | O_CLOEXEC);
    if (ctx->dir_fd < 0) return fail("buffer folder " + ctx->dir + ": " + std::strerror(errno));
  }
  const std::string outside =
      "buffer uri " + shown_uri(rel) +
      " leads outside the .gltf file's folder through a symbolic link; refused: external buffers are read only "
      "from that folder and its subfolders (copy the file there, or embed the buffer: a .glb or a data: URI)";
  int fd = -1;
#ifdef TSM_HAVE_OPENAT2
  struct open_how how = {};
  how.flags = O_RDONLY | O_CLOEXEC | O_NOCTTY | O_NONBLOCK;  // O_NONBLOCK: a FIFO must not hang the open
  how.resolve = RESOLVE_BENEATH | RESOLVE_NO_MAGICLINKS;
  fd = static_cast<int>(::syscall(SYS_openat2, ctx->dir_fd, rel.c_str(), &how, sizeof how));
  if (fd < 0 && errno == EXDEV) {
    ctx->refused_reference = rel;
    return fail(outside);
  }
  if (fd < 0 && errno != ENOSYS && errno != EPERM && errno != E2BIG && errno != EINVAL)
    return fail("buffer file " + ctx->prefix + rel + ": " + std::strerror(errno));
#endif
  if (fd < 0) {
    // No openat2 (old kernel, or a sandbox that filters it): compare the
    // link-resolved paths instead.
    char* real_dir = ::realpath(ctx->dir.c_str(), nullptr);
    if (!real_dir) return fail("buffer folder " + ctx->dir + ": " + std::strerror(errno));
    const std::string base = std::string(real_dir) == "/" ? std::string("/") : std::string(real_dir) + "/";
    std::free(real_dir);
    const std::string path = ctx->prefix + rel;
    char* real = ::realpath(path.c_str(), nullptr);
    if (!real) return fail("buffer file " + path + ": " + std::strerror(errno));
    const std::string resolved = real;
    std::free(real);
    if (resolved.compare(0, base.size(), base) != 0) {
      ctx->refused_reference = rel;
      return fail(outside);
    }
    fd = ::open(resolved.c_str(), O_RDONLY | O_CLOEXEC | O_NOCTTY | O_NONBLOCK | O_NOFOLLOW);
    if (fd < 0) return fail("buffer file " + path + ": " + std::strerror(errno));
  }
  struct stat st = {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    ::close(fd);
    return fail("buffer file " + ctx->prefix + rel + " is not a regular file");
  }
  return fd;
}

// The part of a path tinygltf built (folder + '/' + decoded URI) after the
// folder, or "" with false when the path is not in the folder (tinygltf
// also tries the current directory: never that).
bool reference_in_dir(const FsContext* ctx, const std::string& path, std::string& rel) {
  if (path.compare(0, ctx->prefix.size(), ctx->prefix) != 0) return false;
  rel = path.substr(ctx->prefix.size());
  return true;
}

bool fs_exists(const std::string& path, void* user) {
  auto* ctx = static_cast<FsContext*>(user);
  if (ctx->dir.empty()) {
    if (ctx->error.empty())
      ctx->error = "buffer file " + shown_uri(path) +
                   ": external files are not read here (the glTF did not come from a file: give the .gltf file's "
                   "path, or set ReadOptions::external_files_dir)";
    return false;
  }
  std::string rel;
  if (!reference_in_dir(ctx, path, rel)) return false;
  const std::string why = unsafe_reference(rel);
  if (!why.empty()) {
    if (ctx->error.empty()) {
      ctx->refused_reference = rel;
      ctx->error = "buffer uri " + shown_uri(rel) + " " + why +
                   "; refused: external buffers are read only from the .gltf file's folder and its subfolders, by "
                   "relative URI (copy the file there and name it relative to the .gltf file, or embed the buffer: "
                   "a .glb or a data: URI)";
    }
    return false;
  }
  const int fd = open_beneath(ctx, rel);
  if (fd < 0) return false;
  ::close(fd);
  return true;
}

std::string fs_expand(const std::string& path, void*) { return path; }

// tinygltf's URI decoding (dlib::urldecode): '+' is a space, "%XX" a byte.
std::string uri_decoded(const std::string& s) {
  auto hex = [](char c) -> int {
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    if (c >= 'A' && c <= 'F') return c - 'A' + 10;
    return 0;
  };
  std::string r;
  for (size_t i = 0; i < s.size(); ++i) {
    if (s[i] == '+') {
      r += ' ';
    } else if (s[i] == '%' && s.size() > i + 2) {
      r += static_cast<char>(hex(s[i + 1]) * 16 + hex(s[i + 2]));
      i += 2;
    } else {
      r += s[i];
    }
  }
  return r;
}

// Where a refused reference comes from, for the message: " (buffers[i],
// written as URI)" when the JSON spells it differently (percent-encoded),
// " (buffers[i])" otherwise, "" when it cannot be found.
std::string reference_origin(std::string_view json, const std::string& decoded) {
  try {
    const ojson doc = ojson::parse(json.begin(), json.end());
    const auto it = doc.find("buffers");
    if (it == doc.end() || !it->is_array()) return "";
    for (size_t i = 0; i < it->size(); ++i) {
      const ojson& b = (*it)[i];
      if (!b.is_object() || !b.contains("uri") || !b["uri"].is_string()) continue;
      const std::string uri = b["uri"].get<std::string>();
      if (uri_decoded(uri) != decoded) continue;
      if (uri == decoded) return " (buffers[" + std::to_string(i) + "])";
      return " (buffers[" + std::to_string(i) + "], written as " + shown_uri(uri) + ")";
    }
  } catch (const std::exception&) {
  }
  return "";
}

bool fs_read(std::vector<unsigned char>* out, std::string* err, const std::string& path, void* user) {
  auto* ctx = static_cast<FsContext*>(user);
  std::string rel;
  // fs_exists accepted this path; checked again, as the file is opened anew.
  const int fd = reference_in_dir(ctx, path, rel) && unsafe_reference(rel).empty() ? open_beneath(ctx, rel) : -1;
  if (fd < 0) {
    if (ctx->error.empty()) ctx->error = "buffer file " + shown_uri(path) + " refused";
    if (err) *err += ctx->error;
    return false;
  }
  out->clear();
  unsigned char buf[1 << 16];
  for (;;) {
    const ssize_t n = ::read(fd, buf, sizeof buf);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      const std::string why = std::strerror(errno);
      ::close(fd);
      if (ctx->error.empty()) ctx->error = "buffer file " + path + ": read failed: " + why;
      if (err) *err += ctx->error;
      return false;
    }
    if (n == 0) break;
    out->insert(out->end(), buf, buf + n);
  }
  ::close(fd);
  return true;
}

bool fs_write(std::string* err, const std::string&, const std::vector<unsigned char>&, void*) {
  if (err) *err += "tsm does not write files through tinygltf";
  return false;
}

// Images are never decoded; their bytes are dropped.
bool skip_image(tinygltf::Image*, const int, std::string*, std::string*, int, int, const unsigned char*, int, void*) {
  return true;
}

bool is_identity(const tinygltf::Node& n) {
  static const double kIdentity[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  if (!n.matrix.empty() && !std::equal(n.matrix.begin(), n.matrix.end(), kIdentity, kIdentity + 16)) return false;
  for (double t : n.translation)
    if (t != 0) return false;
  for (double s : n.scale)
    if (s != 1) return false;
  if (!n.rotation.empty() && !(n.rotation.size() == 4 && n.rotation[0] == 0 && n.rotation[1] == 0 &&
                               n.rotation[2] == 0 && n.rotation[3] == 1))
    return false;
  return true;
}

// Parses "PREFIX<digits>" (no sign, no leading '+'); -1 otherwise.
long semantic_index(const std::string& s, const char* prefix) {
  const size_t n = std::strlen(prefix);
  if (s.size() <= n || s.size() > n + 6 || s.compare(0, n, prefix) != 0) return -1;
  long v = 0;
  for (size_t i = n; i < s.size(); ++i) {
    if (s[i] < '0' || s[i] > '9') return -1;
    v = v * 10 + (s[i] - '0');
  }
  if (s.size() > n + 1 && s[n] == '0') return -1;  // "TEXCOORD_01"
  return v;
}

// ---------------------------------------------------------------------------
// The reader

// One attribute of one vertex group, as read.
struct RawAttribute {
  std::string slot;  // the tsm name ("normal", "texcoord0", "color", "TANGENT", "_gltf_target0_POSITION")
  std::string semantic;  // the glTF semantic ("NORMAL"; for a morph target: "target 0 POSITION")
  std::string gltf_semantic;  // the key in the primitive's attributes / target ("NORMAL", "POSITION")
  int accessor = -1;
  int target = -1;  // morph target number, -1 for a vertex attribute
  AttributeKind kind = AttributeKind::generic;
  AttributeType type = AttributeType::f32;
  uint32_t components = 1;
  std::vector<float> values;
};

// Vertices of the primitives sharing one set of vertex accessors.
struct VertexGroup {
  uint32_t base = 0;
  uint32_t count = 0;
  int position_accessor = -1;
  std::vector<RawAttribute> attributes;
};

// The vertex accessors of a primitive: attributes and morph targets.
using GroupKey = std::pair<std::map<std::string, int>, std::vector<std::map<std::string, int>>>;

// A primitive turned into mesh data: its vertices are vertex group `group`,
// its triangles face set `face_set` (-1: none, written back as points).
struct PrimitiveRecord {
  int mesh = 0;
  size_t primitive = 0;
  size_t group = 0;
  int face_set = -1;
};

// The triangles of one primitive (a repeated primitive shares them).
struct FaceSet {
  size_t group = 0;
  uint32_t first = 0;  // first face in the mesh
  uint32_t count = 0;
  int accessor = -1;  // the indices accessor it came from (-1: none, or a strip / fan)
};

// A checked accessor: every byte it names lies inside its buffer.
struct AccessorView {
  int component_type = 0;
  bool normalized = false;
  uint32_t components = 0;
  size_t count = 0;
  size_t csize = 0;
  size_t stride = 0;
  const unsigned char* data = nullptr;  // nullptr: all zeros
  // sparse substitution
  size_t sparse_count = 0;
  int sparse_index_type = 0;
  const unsigned char* sparse_indices = nullptr;
  const unsigned char* sparse_values = nullptr;
};

class GltfReader {
 public:
  GltfReader(std::string_view bytes, const std::string& name, Mesh& out, const ReadOptions& options, ReadInfo* info)
      : bytes_(bytes), name_(name), out_(out), options_(options), info_(info) {}

  Status run() {
    out_.clear();
    Status s;
    try {
      s = parse();
      if (s.ok()) s = build();
    } catch (const std::bad_alloc&) {
      s = Status(ErrorCode::limit_exceeded, name_ + ": out of memory while reading the glTF");
    } catch (const std::exception& e) {
      s = error(std::string("invalid glTF: ") + e.what());
    }
    if (!s.ok()) {
      out_.clear();
      return s;
    }
    if (info_) {
      info_->format = binary_ ? MeshFormat::glb : MeshFormat::gltf;
      info_->binary = binary_;
      info_->skipped_elements += skipped_;
      info_->add_note(notes_);
    }
    return Status::Ok();
  }

 private:
  Status error(const std::string& what) const { return Status(ErrorCode::parse_error, name_ + ": " + what); }
  Status limit(const std::string& what) const { return Status(ErrorCode::limit_exceeded, name_ + ": " + what); }

  void note(const std::string& s) {
    if (++note_count_ > 12) {
      if (note_count_ == 13) notes_ += "; ...";
      return;
    }
    if (!notes_.empty()) notes_ += "; ";
    notes_ += s;
  }

  // ----- container and JSON -----

  Status parse() {
    const auto* u = reinterpret_cast<const unsigned char*>(bytes_.data());
    std::string_view json;
    size_t glb_size = 0;
    if (bytes_.size() >= 4 && load_u32(u) == kGlbMagic) {
      binary_ = true;
      TSM_RETURN_IF_ERROR(check_glb(json, glb_size));
    } else {
      size_t i = 0;
      if (bytes_.substr(0, 3) == "\xEF\xBB\xBF") i = 3;  // UTF-8 byte order mark
      while (i < bytes_.size() && (bytes_[i] == ' ' || bytes_[i] == '\t' || bytes_[i] == '\n' || bytes_[i] == '\r')) ++i;
      if (i == bytes_.size() || bytes_[i] != '{')
        return error("not a glTF file: a .gltf file is a JSON object (starts with '{') and a .glb file starts with "
                     "'glTF'");
      json = bytes_;
    }
    if (json.size() > std::numeric_limits<unsigned int>::max())
      return limit("the glTF JSON is larger than 4 GiB");
    if (json_depth(json, kMaxJsonDepth) > kMaxJsonDepth)
      return error("the JSON nests arrays and objects more than " + std::to_string(kMaxJsonDepth) +
                   " deep; refused (no glTF needs that)");
    json_ = json;

    FsContext fs;
    fs.dir = options_.external_files_dir;
    if (!fs.dir.empty()) fs.prefix = fs.dir.back() == '/' ? fs.dir : fs.dir + "/";
    tinygltf::TinyGLTF loader;
    loader.SetFsCallbacks(tinygltf::FsCallbacks{&fs_exists, &fs_expand, &fs_read, &fs_write, &fs});
    loader.SetImageLoader(&skip_image, nullptr);
    std::string err, warn;
    bool ok;
    if (binary_) {
      ok = loader.LoadBinaryFromMemory(&model_, &err, &warn, reinterpret_cast<const unsigned char*>(bytes_.data()),
                                       static_cast<unsigned int>(glb_size), fs.dir);
    } else {
      ok = loader.LoadASCIIFromString(&model_, &err, &warn, json.data(), static_cast<unsigned int>(json.size()),
                                      fs.dir);
    }
    if (!ok) {
      if (!fs.error.empty() && !fs.refused_reference.empty()) {
        // Name the buffer and its spelling in the file ("%2e%2e/x.bin" is "../x.bin").
        const std::string quoted = shown_uri(fs.refused_reference);
        std::string why = fs.error;
        const size_t at = why.find(quoted);
        if (at != std::string::npos)
          why.insert(at + quoted.size(), reference_origin(json, fs.refused_reference));
        return error(why);
      }
      if (!fs.error.empty()) return error(fs.error);
      return error("invalid glTF: " + clean_message(err));
    }
    if (model_.asset.version.empty() || model_.asset.version[0] != '2')
      return error("asset.version is " + shown_name(model_.asset.version) + "; only glTF 2.0 is read");
    input_bytes_ = bytes_.size();
    for (const tinygltf::Buffer& b : model_.buffers) input_bytes_ += b.data.size();
    return Status::Ok();
  }

  Status check_glb(std::string_view& json, size_t& glb_size) {
    const auto* u = reinterpret_cast<const unsigned char*>(bytes_.data());
    const size_t size = bytes_.size();
    if (size < 12)
      return error("truncated GLB: " + std::to_string(size) + " bytes, and its header alone takes 12");
    const uint32_t version = load_u32(u + 4);
    if (version != 2)
      return error("byte 4: GLB version " + std::to_string(version) + "; only version 2 (glTF 2.0) is read");
    const uint32_t length = load_u32(u + 8);
    if (length > size)
      return error("truncated GLB: its header says " + std::to_string(length) + " bytes but there are only " +
                   std::to_string(size));
    if (length < 20) return error("byte 8: GLB length " + std::to_string(length) + " leaves no room for the JSON chunk");
    if (length < size) note(std::to_string(size - length) + " bytes after the end of the GLB ignored");
    const uint32_t json_length = load_u32(u + 12);
    const uint32_t json_type = load_u32(u + 16);
    if (json_type != kChunkJson)
      return error("byte 16: the first GLB chunk must be JSON (type 0x4E4F534A), not " + hex32(json_type));
    if (json_length == 0) return error("byte 12: the GLB's JSON chunk is empty");
    if (json_length > length - 20)
      return error("byte 12: the JSON chunk's length " + std::to_string(json_length) + " runs past the end of the GLB (" +
                   std::to_string(length) + " bytes)");
    const size_t bin_at = 20 + static_cast<size_t>(json_length);
    if (bin_at < length) {
      if (length - bin_at < 8)
        return error("byte " + std::to_string(bin_at) + ": truncated chunk header after the JSON chunk");
      const uint32_t bin_length = load_u32(u + bin_at);
      const uint32_t bin_type = load_u32(u + bin_at + 4);
      if (bin_type != kChunkBin)
        return error("byte " + std::to_string(bin_at + 4) + ": the second GLB chunk must be BIN (type 0x004E4942), not " +
                     hex32(bin_type));
      if (bin_length > length - bin_at - 8)
        return error("byte " + std::to_string(bin_at) + ": the BIN chunk's length " + std::to_string(bin_length) +
                     " runs past the end of the GLB (" + std::to_string(length) + " bytes)");
      if (bin_length < 4 || bin_length % 4 != 0)
        return error("byte " + std::to_string(bin_at) + ": the BIN chunk's length " + std::to_string(bin_length) +
                     " is not a positive multiple of 4");
    }
    json = bytes_.substr(20, json_length);
    glb_size = length;
    return Status::Ok();
  }

  // ----- scene -----

  // Meshes of the default scene, each once, in the order the node tree meets them.
  Status collect_meshes(std::vector<int>& order) {
    const size_t nmeshes = model_.meshes.size();
    std::vector<size_t> uses(nmeshes, 0);
    if (model_.scenes.empty()) {
      for (size_t m = 0; m < nmeshes; ++m) order.push_back(static_cast<int>(m));
      if (nmeshes > 0 && !model_.nodes.empty()) note("no scene: read all " + std::to_string(nmeshes) + " mesh(es)");
      return Status::Ok();
    }
    int scene = model_.defaultScene;
    if (scene < 0) scene = 0;
    if (static_cast<size_t>(scene) >= model_.scenes.size())
      return error("scene " + std::to_string(scene) + " is the default scene, but there are " +
                   std::to_string(model_.scenes.size()) + " scenes");
    if (model_.scenes.size() > 1)
      note("read scene " + std::to_string(scene) + " of " + std::to_string(model_.scenes.size()));
    const size_t nnodes = model_.nodes.size();
    std::vector<bool> seen(nnodes, false);
    size_t transformed = 0, repeated = 0;
    const std::vector<int>& roots = model_.scenes[static_cast<size_t>(scene)].nodes;
    std::vector<int> stack(roots.rbegin(), roots.rend());  // depth first, in order
    while (!stack.empty()) {
      const int n = stack.back();
      stack.pop_back();
      if (n < 0 || static_cast<size_t>(n) >= nnodes)
        return error("scene " + std::to_string(scene) + " uses node " + std::to_string(n) + ", but there are " +
                     std::to_string(nnodes) + " nodes");
      if (seen[static_cast<size_t>(n)]) {  // a node with two parents, or a cycle: the spec forbids both
        ++repeated;
        continue;
      }
      seen[static_cast<size_t>(n)] = true;
      const tinygltf::Node& node = model_.nodes[static_cast<size_t>(n)];
      if (!is_identity(node)) ++transformed;
      if (node.mesh >= 0) {
        if (static_cast<size_t>(node.mesh) >= nmeshes)
          return error("node " + std::to_string(n) + " uses mesh " + std::to_string(node.mesh) + ", but there are " +
                       std::to_string(nmeshes) + " meshes");
        if (uses[static_cast<size_t>(node.mesh)]++ == 0) order.push_back(node.mesh);
      } else if (node.mesh < -1) {
        return error("node " + std::to_string(n) + " uses mesh " + std::to_string(node.mesh));
      }
      for (auto it = node.children.rbegin(); it != node.children.rend(); ++it) {
        if (*it < 0 || static_cast<size_t>(*it) >= nnodes)
          return error("node " + std::to_string(n) + " has child " + std::to_string(*it) + ", but there are " +
                       std::to_string(nnodes) + " nodes");
        stack.push_back(*it);
      }
    }
    if (repeated > 0) note(std::to_string(repeated) + " repeated node reference(s) (not a tree) read once");
    if (transformed > 0)
      note("node transforms not applied (" + std::to_string(transformed) +
           " node(s) have one): positions as stored, the transforms kept in the document");
    size_t instanced = 0, unused = 0;
    for (size_t m = 0; m < nmeshes; ++m) {
      if (uses[m] > 1) ++instanced;
      if (uses[m] == 0) ++unused;
    }
    if (instanced > 0) note(std::to_string(instanced) + " mesh(es) used by several nodes read once");
    if (unused > 0) note(std::to_string(unused) + " mesh(es) not in the scene kept as stored (not compressed)");
    return Status::Ok();
  }

  // ----- accessors -----

  Status check_view(int view_index, const std::string& what, const tinygltf::BufferView*& view,
                    const tinygltf::Buffer*& buffer) const {
    if (view_index < 0 || static_cast<size_t>(view_index) >= model_.bufferViews.size())
      return error(what + ": buffer view " + std::to_string(view_index) + " does not exist (there are " +
                   std::to_string(model_.bufferViews.size()) + ")");
    view = &model_.bufferViews[static_cast<size_t>(view_index)];
    if (view->buffer < 0 || static_cast<size_t>(view->buffer) >= model_.buffers.size())
      return error(what + ": buffer view " + std::to_string(view_index) + " names buffer " +
                   std::to_string(view->buffer) + ", which does not exist (there are " +
                   std::to_string(model_.buffers.size()) + ")");
    buffer = &model_.buffers[static_cast<size_t>(view->buffer)];
    const size_t size = buffer->data.size();
    if (view->byteOffset > size || view->byteLength > size - view->byteOffset)
      return error(what + ": buffer view " + std::to_string(view_index) + " (bytes " + std::to_string(view->byteOffset) +
                   " + " + std::to_string(view->byteLength) + ") runs past the end of buffer " +
                   std::to_string(view->buffer) + " (" + std::to_string(size) + " bytes)");
    return Status::Ok();
  }

  // Bytes [offset, offset + (count - 1) * stride + elem) inside a view of `length` bytes.
  static bool fits(size_t offset, size_t count, size_t stride, size_t elem, size_t length) {
    if (count == 0) return offset <= length;
    if (offset > length || elem > length - offset) return false;
    const size_t room = length - offset - elem;
    return stride == 0 || count - 1 <= room / stride;
  }

  // Charges `n` produced values against the budget (a multiple of the input's bytes).
  Status charge(uint64_t n, const std::string& what) {
    const uint64_t budget = 8 * static_cast<uint64_t>(input_bytes_) + (1u << 16);
    if (n > budget || produced_ > budget - n)
      return limit(what + ": the primitives would produce more than " + std::to_string(budget) +
                   " values from " + std::to_string(input_bytes_) +
                   " bytes of data (accessors reused many times?); refused");
    produced_ += n;
    return Status::Ok();
  }

  Status view_accessor(int index, const std::string& what, AccessorView& v) {
    if (index < 0 || static_cast<size_t>(index) >= model_.accessors.size())
      return error(what + ": accessor " + std::to_string(index) + " does not exist (there are " +
                   std::to_string(model_.accessors.size()) + ")");
    const tinygltf::Accessor& a = model_.accessors[static_cast<size_t>(index)];
    const std::string at = what + " (accessor " + std::to_string(index) + ")";
    v = AccessorView();
    v.component_type = a.componentType;
    v.normalized = a.normalized;
    v.components = type_components(a.type);
    v.count = a.count;
    v.csize = gltf::component_bytes(a.componentType);
    if (v.csize == 0)
      return error(at + ": component type " + std::to_string(a.componentType) + " (" +
                   component_name(a.componentType) + ") is not a glTF 2.0 accessor type");
    if (v.components == 0) return error(at + ": type " + type_name(a.type) + " is not a vector or scalar");
    if (a.count > kMaxIndex)
      return limit(at + ": " + std::to_string(a.count) + " elements; tsm handles at most " + std::to_string(kMaxIndex));
    const size_t elem = v.csize * v.components;
    if (a.bufferView >= 0) {
      const tinygltf::BufferView* view;
      const tinygltf::Buffer* buffer;
      TSM_RETURN_IF_ERROR(check_view(a.bufferView, at, view, buffer));
      v.stride = view->byteStride ? view->byteStride : elem;
      if (view->byteStride != 0 && view->byteStride < elem)
        return error(at + ": buffer view " + std::to_string(a.bufferView) + " has byteStride " +
                     std::to_string(view->byteStride) + ", less than the " + std::to_string(elem) + "-byte element");
      if (!fits(a.byteOffset, a.count, v.stride, elem, view->byteLength))
        return error(at + ": " + std::to_string(a.count) + " elements of " + std::to_string(elem) + " bytes (stride " +
                     std::to_string(v.stride) + ") from byte " + std::to_string(a.byteOffset) +
                     " run past the end of buffer view " + std::to_string(a.bufferView) + " (" +
                     std::to_string(view->byteLength) + " bytes)");
      v.data = buffer->data.data() + view->byteOffset + a.byteOffset;
    } else if (a.bufferView < -1) {
      return error(at + ": buffer view " + std::to_string(a.bufferView) + " does not exist");
    }
    if (a.sparse.isSparse) {
      const auto& sp = a.sparse;
      const std::string sat = at + ": sparse";
      if (sp.count < 1 || static_cast<size_t>(sp.count) > a.count)
        return error(sat + " count " + std::to_string(sp.count) + " is not in 1.." + std::to_string(a.count));
      v.sparse_count = static_cast<size_t>(sp.count);
      v.sparse_index_type = sp.indices.componentType;
      if (v.sparse_index_type != kUByte && v.sparse_index_type != kUShort && v.sparse_index_type != kUInt)
        return error(sat + " indices have component type " + std::to_string(v.sparse_index_type) +
                     "; expected unsigned byte, short or int");
      if (sp.indices.byteOffset < 0 || sp.values.byteOffset < 0) return error(sat + " byteOffset is negative");
      const tinygltf::BufferView* view;
      const tinygltf::Buffer* buffer;
      TSM_RETURN_IF_ERROR(check_view(sp.indices.bufferView, sat + " indices", view, buffer));
      const size_t isize = gltf::component_bytes(v.sparse_index_type);
      if (!fits(static_cast<size_t>(sp.indices.byteOffset), v.sparse_count, isize, isize, view->byteLength))
        return error(sat + " indices run past the end of buffer view " + std::to_string(sp.indices.bufferView));
      v.sparse_indices = buffer->data.data() + view->byteOffset + static_cast<size_t>(sp.indices.byteOffset);
      TSM_RETURN_IF_ERROR(check_view(sp.values.bufferView, sat + " values", view, buffer));
      if (!fits(static_cast<size_t>(sp.values.byteOffset), v.sparse_count, elem, elem, view->byteLength))
        return error(sat + " values run past the end of buffer view " + std::to_string(sp.values.bufferView));
      v.sparse_values = buffer->data.data() + view->byteOffset + static_cast<size_t>(sp.values.byteOffset);
      for (size_t k = 0; k < v.sparse_count; ++k) {
        const uint32_t i = load_index(v.sparse_index_type, v.sparse_indices + k * isize);
        if (i >= a.count)
          return error(sat + " index " + std::to_string(k) + " is " + std::to_string(i) + ", but the accessor has " +
                       std::to_string(a.count) + " elements");
      }
    }
    return Status::Ok();
  }

  // Appends the accessor's values (count * components floats) to `out`.
  Status read_floats(const AccessorView& v, bool normalized, const std::string& what, std::vector<float>& out) {
    TSM_RETURN_IF_ERROR(charge(static_cast<uint64_t>(v.count) * v.components, what));
    const size_t start = out.size();
    out.resize(start + v.count * v.components, 0.0f);
    float* dst = out.data() + start;
    if (v.data) {
      for (size_t i = 0; i < v.count; ++i) {
        const unsigned char* p = v.data + i * v.stride;
        for (uint32_t c = 0; c < v.components; ++c)
          dst[i * v.components + c] = load_value(v.component_type, normalized, p + c * v.csize);
      }
    }
    const size_t isize = gltf::component_bytes(v.sparse_index_type);
    for (size_t k = 0; k < v.sparse_count; ++k) {
      const uint32_t i = load_index(v.sparse_index_type, v.sparse_indices + k * isize);
      const unsigned char* p = v.sparse_values + k * v.csize * v.components;
      for (uint32_t c = 0; c < v.components; ++c)
        dst[static_cast<size_t>(i) * v.components + c] = load_value(v.component_type, normalized, p + c * v.csize);
    }
    if (!options_.allow_nonfinite && v.component_type == kFloat) {
      for (size_t i = 0; i < v.count * v.components; ++i)
        if (!std::isfinite(dst[i])) {
          const size_t e = i / v.components;
          std::string vals;
          for (uint32_t c = 0; c < v.components; ++c)
            vals += (c ? ", " : "(") + float_text(dst[e * v.components + c]);
          return error(what + ": element " + std::to_string(e) + " is " + vals +
                       "), not finite; pass --allow-nonfinite (ReadOptions::allow_nonfinite) to accept it");
        }
    }
    return Status::Ok();
  }

  Status read_indices(const AccessorView& v, const std::string& what, std::vector<uint32_t>& out) {
    if (v.components != 1) return error(what + ": indices must be SCALAR");
    if (v.component_type != kUByte && v.component_type != kUShort && v.component_type != kUInt)
      return error(what + ": indices have component type " + component_name(v.component_type) +
                   "; expected unsigned byte, short or int");
    TSM_RETURN_IF_ERROR(charge(v.count, what));
    out.assign(v.count, 0);
    if (v.data)
      for (size_t i = 0; i < v.count; ++i) out[i] = load_index(v.component_type, v.data + i * v.stride);
    const size_t isize = gltf::component_bytes(v.sparse_index_type);
    for (size_t k = 0; k < v.sparse_count; ++k) {
      const uint32_t i = load_index(v.sparse_index_type, v.sparse_indices + k * isize);
      out[i] = load_index(v.component_type, v.sparse_values + k * v.csize);
    }
    return Status::Ok();
  }

  // ----- primitives -----

  Status read_attribute(const std::string& semantic, int accessor, size_t vertex_count, const std::string& where,
                        VertexGroup& g) {
    const std::string what = where + " " + semantic.substr(0, 64);
    if (semantic.size() > kMaxAttributeNameBytes)
      return error(what + "...: an attribute name of " + std::to_string(semantic.size()) +
                   " bytes; tsm keeps names of at most " + std::to_string(kMaxAttributeNameBytes) + " bytes");
    AccessorView v;
    TSM_RETURN_IF_ERROR(view_accessor(accessor, what, v));
    if (v.count != vertex_count)
      return error(what + " (accessor " + std::to_string(accessor) + ") has " + std::to_string(v.count) +
                   " elements, but POSITION has " + std::to_string(vertex_count));
    RawAttribute r;
    r.semantic = semantic;
    r.gltf_semantic = semantic;
    r.accessor = accessor;
    r.components = v.components;
    const std::string shape = std::string(type_name(model_.accessors[static_cast<size_t>(accessor)].type)) + " of " +
                              component_name(v.component_type);
    bool normalized = v.normalized;
    const long texcoord = semantic_index(semantic, "TEXCOORD_");
    const long color = semantic_index(semantic, "COLOR_");
    if (semantic == "NORMAL") {
      if (v.components != 3) {
        note(where + " NORMAL is " + shape + ", not VEC3: not kept");
        return Status::Ok();
      }
      r.slot = "normal";
      r.kind = AttributeKind::normal;
    } else if (texcoord >= 0) {
      if (v.components != 2) {
        note(what + " is " + shape + ", not VEC2: not kept");
        return Status::Ok();
      }
      r.slot = "texcoord" + std::to_string(texcoord);
      r.kind = AttributeKind::texcoord;
    } else if (color >= 0) {
      if (v.components < 3) {
        note(what + " is " + shape + ", not VEC3 or VEC4: not kept");
        return Status::Ok();
      }
      r.slot = color == 0 ? "color" : "color" + std::to_string(color);
      r.kind = AttributeKind::color;
      if (v.normalized && v.component_type == kUByte) {
        r.type = AttributeType::u8;
        normalized = false;  // the integers 0..255
      } else if (v.normalized && v.component_type == kUShort) {
        r.type = AttributeType::u16;
        normalized = false;
      }
    } else {
      r.slot = semantic;
      r.kind = AttributeKind::generic;
      switch (v.component_type) {
        case kUByte: r.type = AttributeType::u8; break;
        case kUShort: r.type = AttributeType::u16; break;
        case kByte:
        case kShort: r.type = AttributeType::i32; break;
        case kUInt:
          note(what + " is unsigned int (not a glTF vertex attribute type): not kept");
          return Status::Ok();
        default: break;
      }
      if (r.type != AttributeType::f32) {
        if (normalized && semantic_index(semantic, "WEIGHTS_") < 0)
          note(what + ": kept as the stored integers; its 'normalized' flag is not kept");
        normalized = false;
      }
    }
    TSM_RETURN_IF_ERROR(read_floats(v, normalized, what + " (accessor " + std::to_string(accessor) + ")", r.values));
    g.attributes.push_back(std::move(r));
    return Status::Ok();
  }

  // A morph target's displacement (POSITION, NORMAL, TANGENT: VEC3 of
  // float, or normalized byte / short) as the float vertex attribute
  // "_gltf_target<t>_<SEMANTIC>".
  Status read_target_attribute(size_t t, const std::string& semantic, int accessor, size_t vertex_count,
                               const std::string& where, VertexGroup& g) {
    const std::string what = where + " target " + std::to_string(t) + " " + semantic;
    AccessorView v;
    TSM_RETURN_IF_ERROR(view_accessor(accessor, what, v));
    if (v.count != vertex_count)
      return error(what + " (accessor " + std::to_string(accessor) + ") has " + std::to_string(v.count) +
                   " elements, but POSITION has " + std::to_string(vertex_count));
    const bool known = semantic == "POSITION" || semantic == "NORMAL" || semantic == "TANGENT";
    const bool numeric = v.component_type == kFloat ||
                         (v.normalized && (v.component_type == kByte || v.component_type == kShort));
    if (!known || v.components != 3 || !numeric) {
      note(what + " is not a VEC3 of float or normalized byte / short displacements: not kept");
      return Status::Ok();
    }
    RawAttribute r;
    r.slot = "_gltf_target" + std::to_string(t) + "_" + semantic;
    r.semantic = "target " + std::to_string(t) + " " + semantic;
    r.gltf_semantic = semantic;
    r.accessor = accessor;
    r.target = static_cast<int>(t);
    r.components = 3;
    TSM_RETURN_IF_ERROR(read_floats(v, v.normalized, what + " (accessor " + std::to_string(accessor) + ")", r.values));
    g.attributes.push_back(std::move(r));
    return Status::Ok();
  }

  Status read_group(const GroupKey& key, const std::string& where, size_t& group_index) {
    const std::map<std::string, int>& attributes = key.first;
    const std::string what = where + " POSITION";
    AccessorView pv;
    TSM_RETURN_IF_ERROR(view_accessor(attributes.at("POSITION"), what, pv));
    if (pv.components != 3)
      return error(what + " (accessor " + std::to_string(attributes.at("POSITION")) + ") is " +
                   type_name(model_.accessors[static_cast<size_t>(attributes.at("POSITION"))].type) + "; expected VEC3");
    const uint64_t total = static_cast<uint64_t>(out_.vertex_count()) + pv.count;
    if (options_.max_vertices > 0 && total > options_.max_vertices)
      return limit("the primitives hold " + std::to_string(total) + " or more vertices, more than the limit of " +
                   std::to_string(options_.max_vertices) + " (ReadOptions::max_vertices)");
    if (total > kMaxIndex)
      return limit("the primitives hold " + std::to_string(total) + " or more vertices; tsm handles at most " +
                   std::to_string(kMaxIndex));
    VertexGroup g;
    g.base = static_cast<uint32_t>(out_.vertex_count());
    g.count = static_cast<uint32_t>(pv.count);
    g.position_accessor = attributes.at("POSITION");
    TSM_RETURN_IF_ERROR(read_floats(pv, pv.normalized, what + " (accessor " + std::to_string(attributes.at("POSITION")) + ")",
                                    out_.positions));
    for (const auto& [semantic, accessor] : attributes)
      if (semantic != "POSITION") TSM_RETURN_IF_ERROR(read_attribute(semantic, accessor, pv.count, where, g));
    for (size_t t = 0; t < key.second.size(); ++t)
      for (const auto& [semantic, accessor] : key.second[t])
        TSM_RETURN_IF_ERROR(read_target_attribute(t, semantic, accessor, pv.count, where, g));
    group_index = groups_.size();
    groups_.push_back(std::move(g));
    return Status::Ok();
  }

  Status read_primitive(int mesh_index, size_t prim_index) {
    const tinygltf::Mesh& mesh = model_.meshes[static_cast<size_t>(mesh_index)];
    const tinygltf::Primitive& p = mesh.primitives[prim_index];
    std::string where = "mesh " + std::to_string(mesh_index);
    if (!mesh.name.empty()) where += " " + shown_name(mesh.name);
    where += " primitive " + std::to_string(prim_index);
    if (p.mode < 0 || p.mode > 6)
      return error(where + ": unknown primitive mode " + std::to_string(p.mode) + " (glTF has 0..6)");
    auto pos = p.attributes.find("POSITION");
    if (pos == p.attributes.end()) {
      note(where + " has no POSITION: skipped");
      ++skipped_;
      return Status::Ok();
    }
    if (p.extensions.count("KHR_draco_mesh_compression")) {
      // Not required by the file: the accessors must hold an uncompressed copy.
      const int a = pos->second;
      if (a < 0 || static_cast<size_t>(a) >= model_.accessors.size() ||
          model_.accessors[static_cast<size_t>(a)].bufferView < 0)
        return Status(ErrorCode::unsupported, name_ + ": " + where +
                                                  " is Draco-compressed (KHR_draco_mesh_compression) without an "
                                                  "uncompressed copy, and tsm does not decode Draco");
      note(where + ": read the uncompressed copy of a Draco-compressed primitive");
    }
    const GroupKey key(p.attributes, p.targets);
    PrimitiveRecord record;
    record.mesh = mesh_index;
    record.primitive = prim_index;
    auto seen = seen_primitives_.find(std::make_tuple(key, p.indices, p.mode));
    if (seen != seen_primitives_.end()) {  // the same data again: the same vertices and faces
      ++repeated_primitives_;
      record.group = seen->second.first;
      record.face_set = seen->second.second;
      records_.push_back(record);
      return Status::Ok();
    }
    size_t gi = 0;
    auto found = group_of_.find(key);
    if (found != group_of_.end()) {
      gi = found->second;
    } else {
      TSM_RETURN_IF_ERROR(read_group(key, where, gi));
      group_of_[key] = gi;
    }
    record.group = gi;
    const uint32_t base = groups_[gi].base;
    const uint32_t n = groups_[gi].count;

    std::vector<uint32_t> idx;
    if (p.indices >= 0) {
      const std::string what = where + " indices";
      AccessorView iv;
      TSM_RETURN_IF_ERROR(view_accessor(p.indices, what, iv));
      TSM_RETURN_IF_ERROR(read_indices(iv, what + " (accessor " + std::to_string(p.indices) + ")", idx));
      for (size_t i = 0; i < idx.size(); ++i)
        if (idx[i] >= n)
          return error(what + " (accessor " + std::to_string(p.indices) + "): index " + std::to_string(i) + " is " +
                       std::to_string(idx[i]) + ", but POSITION has " + std::to_string(n) + " vertices");
    } else if (p.indices < -1) {
      return error(where + ": indices accessor " + std::to_string(p.indices) + " does not exist");
    } else if (p.mode >= TINYGLTF_MODE_TRIANGLES) {
      TSM_RETURN_IF_ERROR(charge(n, where));
      idx.resize(n);
      for (uint32_t i = 0; i < n; ++i) idx[i] = i;
    }

    if (p.mode < TINYGLTF_MODE_TRIANGLES) {
      static const char* kModes[] = {"points", "lines", "line loop", "line strip"};
      const size_t count = p.indices >= 0 ? idx.size() : n;
      const size_t elements = p.mode == 0 ? count : p.mode == 1 ? count / 2 : p.mode == 2 ? count : count ? count - 1 : 0;
      skipped_ += elements;
      if (elements > 0)
        note(where + ": " + std::to_string(elements) + " " + kModes[p.mode] +
             (p.mode == 0 ? "" : " segment(s)") + " skipped (their vertices are kept)");
      if (p.mode != TINYGLTF_MODE_POINTS) ++lines_as_points_;
      seen_primitives_[std::make_tuple(key, p.indices, p.mode)] = {gi, -1};
      records_.push_back(record);
      return Status::Ok();
    }
    size_t tris = 0;
    if (p.mode == TINYGLTF_MODE_TRIANGLES) {
      if (idx.size() % 3 != 0)
        return error(where + ": " + std::to_string(idx.size()) + " triangle corners, not a multiple of 3");
      tris = idx.size() / 3;
    } else {
      tris = idx.size() >= 3 ? idx.size() - 2 : 0;
    }
    const uint64_t faces = static_cast<uint64_t>(out_.face_count()) + tris;
    if (options_.max_faces > 0 && faces > options_.max_faces)
      return limit("the primitives hold " + std::to_string(faces) + " or more faces, more than the limit of " +
                   std::to_string(options_.max_faces) + " (ReadOptions::max_faces)");
    if (static_cast<uint64_t>(out_.corner_count()) + 3 * static_cast<uint64_t>(tris) > kMaxIndex)
      return limit("the primitives hold more than " + std::to_string(kMaxIndex) + " face corners; tsm handles at most that");
    TSM_RETURN_IF_ERROR(charge(4 * static_cast<uint64_t>(tris), where));
    out_.indices.reserve(out_.indices.size() + 3 * tris);
    out_.face_offsets.reserve(out_.face_offsets.size() + tris);
    size_t dropped = 0;
    for (size_t t = 0; t < tris; ++t) {
      uint32_t a, b, c;
      if (p.mode == TINYGLTF_MODE_TRIANGLES) {
        a = idx[3 * t], b = idx[3 * t + 1], c = idx[3 * t + 2];
      } else if (p.mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
        a = idx[t];
        b = idx[t + 1 + t % 2];
        c = idx[t + 2 - t % 2];
      } else {  // fan
        a = idx[t + 1], b = idx[t + 2], c = idx[0];
      }
      if (p.mode != TINYGLTF_MODE_TRIANGLES && (a == b || b == c || a == c)) {
        ++dropped;
        continue;
      }
      out_.add_triangle(base + a, base + b, base + c);
    }
    if (dropped > 0) note(where + ": " + std::to_string(dropped) + " degenerate strip/fan triangle(s) dropped");
    const uint32_t first = static_cast<uint32_t>(out_.face_count() - (tris - dropped));
    if (tris > dropped) {
      FaceSet fs;
      fs.group = gi;
      fs.first = first;
      fs.count = static_cast<uint32_t>(tris - dropped);
      fs.accessor = p.mode == TINYGLTF_MODE_TRIANGLES ? p.indices : -1;
      record.face_set = static_cast<int>(face_sets_.size());
      face_sets_.push_back(fs);
    } else {
      ++empty_triangles_;
    }
    seen_primitives_[std::make_tuple(key, p.indices, p.mode)] = {gi, record.face_set};
    records_.push_back(record);
    return Status::Ok();
  }

  // ----- attributes of all groups into the mesh -----

  static int kind_rank(AttributeKind k) {
    switch (k) {
      case AttributeKind::normal: return 0;
      case AttributeKind::texcoord: return 1;
      case AttributeKind::color: return 2;
      default: return 3;
    }
  }

  static float type_max(AttributeType t) { return t == AttributeType::u8 ? 255.0f : t == AttributeType::u16 ? 65535.0f : 1.0f; }

  Status merge_attributes() {
    struct Slot {
      const RawAttribute* first = nullptr;
      long number = 0;
      size_t present = 0;
      bool same = true;  // every group stores the same type and components
      uint32_t components = 0;
      bool any_float = false, any_u16 = false, any_i32 = false;
    };
    std::map<std::string, Slot> slots;
    for (const VertexGroup& g : groups_)
      for (const RawAttribute& r : g.attributes) {
        Slot& s = slots[r.slot];
        if (!s.first) {
          s.first = &r;
          s.number = std::max({semantic_index(r.semantic, "TEXCOORD_"), semantic_index(r.semantic, "COLOR_"), 0L});
        } else if (s.first->type != r.type || s.first->components != r.components) {
          s.same = false;
        }
        ++s.present;
        s.components = std::max(s.components, r.components);
        s.any_float |= r.type == AttributeType::f32;
        s.any_u16 |= r.type == AttributeType::u16;
        s.any_i32 |= r.type == AttributeType::i32;
      }
    std::vector<std::pair<std::string, Slot*>> order;
    for (auto& [name, s] : slots) order.emplace_back(name, &s);
    std::sort(order.begin(), order.end(), [](const auto& x, const auto& y) {
      return std::make_tuple(kind_rank(x.second->first->kind), x.second->number, x.first) <
             std::make_tuple(kind_rank(y.second->first->kind), y.second->number, y.first);
    });
    const size_t nv = out_.vertex_count();
    for (auto& [name, sp] : order) {
      const Slot& s = *sp;
      Attribute a;
      a.name = name;
      a.kind = s.first->kind;
      a.domain = AttributeDomain::vertex;
      a.components = s.components;
      if (s.same) {
        a.type = s.first->type;
      } else if (a.kind == AttributeKind::color) {
        a.type = s.any_float || s.any_i32 ? AttributeType::f32 : s.any_u16 ? AttributeType::u16 : AttributeType::u8;
      } else {
        a.type = s.any_float ? AttributeType::f32 : s.any_i32 ? AttributeType::i32 : s.any_u16 ? AttributeType::u16 : AttributeType::u8;
      }
      if (!s.same) note(s.first->semantic + ": primitives store it differently; kept as " +
                        std::to_string(a.components) + " component(s) of " +
                        (a.type == AttributeType::f32 ? "float" : a.type == AttributeType::u16 ? "u16" : a.type == AttributeType::u8 ? "u8" : "i32"));
      if (s.present < groups_.size())
        note(s.first->semantic + " missing in " + std::to_string(groups_.size() - s.present) + " of " +
             std::to_string(groups_.size()) + " vertex group(s): filled with " +
             (a.kind == AttributeKind::color ? "opaque white" : "zeros"));
      // Default value: zeros, colours opaque white.
      const float full = type_max(a.type);
      std::vector<float> fill(a.components, a.kind == AttributeKind::color ? full : 0.0f);
      TSM_RETURN_IF_ERROR(charge(static_cast<uint64_t>(nv) * a.components, "attribute " + name));
      a.values.assign(nv * a.components, 0.0f);
      for (const VertexGroup& g : groups_) {
        const RawAttribute* r = nullptr;
        for (const RawAttribute& x : g.attributes)
          if (x.slot == name) r = &x;
        float* dst = a.values.data() + static_cast<size_t>(g.base) * a.components;
        for (uint32_t v = 0; v < g.count; ++v)
          for (uint32_t c = 0; c < a.components; ++c) {
            float x;
            if (!r) {
              x = fill[c];
            } else if (c >= r->components) {
              x = a.kind == AttributeKind::color ? full : 0.0f;  // alpha of an RGB colour
            } else {
              x = r->values[static_cast<size_t>(v) * r->components + c];
              if (a.kind == AttributeKind::color && r->type != a.type) {
                if (a.type == AttributeType::f32) {
                  x /= type_max(r->type);  // u8 / u16 to 0..1
                } else if (a.type == AttributeType::u16 && r->type == AttributeType::u8) {
                  x *= 257.0f;  // 255 -> 65535 exactly
                }
              }
            }
            dst[static_cast<size_t>(v) * a.components + c] = x;
          }
      }
      out_.attributes.push_back(std::move(a));
    }
    return Status::Ok();
  }

  Status build() {
    {
      bool meshopt = false;
      for (const std::string& e : model_.extensionsRequired) {
        if (e == "KHR_draco_mesh_compression")
          return Status(ErrorCode::unsupported, name_ + ": the file requires Draco compression "
                                                        "(KHR_draco_mesh_compression), which tsm does not decode");
        if (e.find("meshopt_compression") != std::string::npos) meshopt = true;
      }
      if (meshopt)
        return Status(ErrorCode::unsupported, name_ + ": the file requires meshopt compression "
                                                      "(EXT_meshopt_compression), which tsm does not decode");
    }
    std::vector<int> order;
    TSM_RETURN_IF_ERROR(collect_meshes(order));
    size_t prims = 0;
    for (int m : order) {
      const tinygltf::Mesh& mesh = model_.meshes[static_cast<size_t>(m)];
      for (size_t p = 0; p < mesh.primitives.size(); ++p) TSM_RETURN_IF_ERROR(read_primitive(m, p));
      prims += mesh.primitives.size();
    }
    if (prims > 1)
      note(std::to_string(prims) + " primitives of " + std::to_string(order.size()) + " mesh(es) concatenated");
    if (repeated_primitives_ > 0)
      note(std::to_string(repeated_primitives_) + " primitive(s) repeating another one read once");
    TSM_RETURN_IF_ERROR(merge_attributes());

    if (lines_as_points_ > 0)
      note(std::to_string(lines_as_points_) + " line primitive(s) kept as points primitives (their vertices)");
    if (empty_triangles_ > 0)
      note(std::to_string(empty_triangles_) + " triangle primitive(s) without a triangle kept as points primitives");
    return build_passthrough();
  }

  // ----- pass-through: the document without the geometry -----

  // The JSON array `key` of `doc` (`where` in messages, default `key`), which
  // must have the `n` elements tinygltf read (absent when n is 0).
  Status json_array(ojson& doc, const char* key, size_t n, ojson*& arr, const std::string& where = "") const {
    arr = nullptr;
    auto it = doc.find(key);
    if (it == doc.end()) {
      if (n == 0) return Status::Ok();
    } else if (it->is_array() && it->size() == n) {
      arr = &*it;
      return Status::Ok();
    } else if (!it->is_array()) {
      return error("'" + (where.empty() ? std::string(key) : where) +
                   "' is not an array, as glTF requires: fix the file or export it again");
    }
    return error(std::string("the JSON's '") + key + "' does not match what tinygltf read (" + std::to_string(n) +
                 " elements)");
  }

  Status build_passthrough() {
    ojson doc;
    try {
      doc = ojson::parse(json_.begin(), json_.end());
    } catch (const std::exception& e) {
      return error(std::string("invalid JSON: ") + clean_message(e.what()));
    }
    if (!doc.is_object()) return error("the glTF JSON is not an object");
    const size_t na = model_.accessors.size(), nviews = model_.bufferViews.size();
    ojson *accessors, *views, *images, *meshes;
    TSM_RETURN_IF_ERROR(json_array(doc, "accessors", na, accessors));
    TSM_RETURN_IF_ERROR(json_array(doc, "bufferViews", nviews, views));
    TSM_RETURN_IF_ERROR(json_array(doc, "images", model_.images.size(), images));
    TSM_RETURN_IF_ERROR(json_array(doc, "meshes", model_.meshes.size(), meshes));
    for (size_t m = 0; m < model_.meshes.size(); ++m) {
      ojson* prims;
      TSM_RETURN_IF_ERROR(json_array((*meshes)[m], "primitives", model_.meshes[m].primitives.size(), prims,
                                     "meshes[" + std::to_string(m) + "].primitives"));
    }

    // Accessors something other than the primitives read uses keep their bytes.
    std::set<std::pair<int, size_t>> read_primitives;
    for (const PrimitiveRecord& r : records_) read_primitives.insert({r.mesh, r.primitive});
    std::vector<char> other_use(na, 0);
    auto mark = [&](int a) {
      if (a >= 0 && static_cast<size_t>(a) < na) other_use[static_cast<size_t>(a)] = 1;
    };
    for (size_t m = 0; m < model_.meshes.size(); ++m)
      for (size_t p = 0; p < model_.meshes[m].primitives.size(); ++p) {
        if (read_primitives.count({static_cast<int>(m), p})) continue;
        const tinygltf::Primitive& prim = model_.meshes[m].primitives[p];
        for (const auto& kv : prim.attributes) mark(kv.second);
        mark(prim.indices);
        for (const auto& target : prim.targets)
          for (const auto& kv : target) mark(kv.second);
      }
    for (const tinygltf::Animation& a : model_.animations)
      for (const tinygltf::AnimationSampler& s : a.samplers) {
        mark(s.input);
        mark(s.output);
      }
    for (const tinygltf::Skin& s : model_.skins) mark(s.inverseBindMatrices);
    if (auto nodes = doc.find("nodes"); nodes != doc.end() && nodes->is_array())
      for (const ojson& node : *nodes) {
        const ojson* at = &node;
        for (const char* key : {"extensions", "EXT_mesh_gpu_instancing", "attributes"}) {
          if (!at->is_object() || !at->contains(key)) {
            at = nullptr;
            break;
          }
          at = &(*at)[key];
        }
        if (at && at->is_object())
          for (const auto& kv : at->items())
            if (kv.value().is_number_unsigned() && kv.value().get<uint64_t>() < na) mark(kv.value().get<int>());
      }

    // Accessor slots of the geometry: an accessor only the primitives read
    // use keeps its index (the first role to claim it); other roles get new
    // accessors after the last one.
    std::vector<char> claimed(na, 0);
    std::vector<ojson> appended;
    size_t next = na;
    auto placeholder = [&](int orig) {
      ojson a = ojson::object();
      if (orig >= 0 && static_cast<size_t>(orig) < na && (*accessors)[static_cast<size_t>(orig)].is_object()) {
        a = (*accessors)[static_cast<size_t>(orig)];
        for (const char* k : {"bufferView", "byteOffset", "componentType", "normalized", "count", "type", "max", "min",
                              "sparse"})
          a.erase(k);
      }
      return a;
    };
    auto slot_for = [&](int orig) -> size_t {
      if (orig >= 0 && static_cast<size_t>(orig) < na && !other_use[static_cast<size_t>(orig)] &&
          !claimed[static_cast<size_t>(orig)]) {
        claimed[static_cast<size_t>(orig)] = 1;
        (*accessors)[static_cast<size_t>(orig)] = placeholder(orig);
        return static_cast<size_t>(orig);
      }
      appended.push_back(placeholder(orig));
      return next++;
    };
    ojson fills = ojson::array();
    std::vector<std::map<std::string, size_t>> attribute_slot(groups_.size());
    std::vector<std::vector<std::map<std::string, size_t>>> target_slot(groups_.size());
    for (size_t g = 0; g < groups_.size(); ++g) {
      const VertexGroup& group = groups_[g];
      size_t slot = slot_for(group.position_accessor);
      attribute_slot[g]["POSITION"] = slot;
      fills.push_back({{"accessor", slot}, {"group", g}, {"semantic", "POSITION"}});
      for (const RawAttribute& r : group.attributes) {
        slot = slot_for(r.accessor);
        ojson f = {{"accessor", slot}, {"group", g}, {"semantic", r.gltf_semantic}};
        if (r.target >= 0) {
          const size_t t = static_cast<size_t>(r.target);
          if (target_slot[g].size() <= t) target_slot[g].resize(t + 1);
          target_slot[g][t][r.gltf_semantic] = slot;
          f["target"] = t;
        } else {
          attribute_slot[g][r.gltf_semantic] = slot;
        }
        f["attribute"] = r.slot;
        f["components"] = r.components;
        fills.push_back(std::move(f));
      }
    }
    std::vector<size_t> face_set_slot(face_sets_.size());
    for (size_t k = 0; k < face_sets_.size(); ++k) {
      face_set_slot[k] = slot_for(face_sets_[k].accessor);
      fills.push_back({{"accessor", face_set_slot[k]}, {"face_set", k}});
    }

    // The primitives read name their new accessors.
    for (const PrimitiveRecord& r : records_) {
      ojson& prim = (*meshes)[static_cast<size_t>(r.mesh)]["primitives"][r.primitive];
      if (!prim.is_object()) return error("the JSON's primitives do not match what tinygltf read");
      ojson attributes = ojson::object();
      if (prim.contains("attributes") && prim["attributes"].is_object())
        for (const auto& kv : prim["attributes"].items())
          if (auto it = attribute_slot[r.group].find(kv.key()); it != attribute_slot[r.group].end())
            attributes[kv.key()] = it->second;
      prim["attributes"] = std::move(attributes);
      if (prim.contains("targets") && prim["targets"].is_array()) {
        ojson& targets = prim["targets"];
        for (size_t t = 0; t < targets.size(); ++t) {
          ojson kept = ojson::object();
          if (targets[t].is_object() && t < target_slot[r.group].size())
            for (const auto& kv : targets[t].items())
              if (auto it = target_slot[r.group][t].find(kv.key()); it != target_slot[r.group][t].end())
                kept[kv.key()] = it->second;
          targets[t] = std::move(kept);
        }
      }
      if (r.face_set >= 0) {
        prim["indices"] = face_set_slot[static_cast<size_t>(r.face_set)];
        if (prim.contains("mode")) prim["mode"] = TINYGLTF_MODE_TRIANGLES;
      } else {
        prim.erase("indices");
        prim["mode"] = TINYGLTF_MODE_POINTS;
      }
      if (prim.contains("extensions") && prim["extensions"].is_object()) {
        prim["extensions"].erase("KHR_draco_mesh_compression");  // its data is the mesh's now
        if (prim["extensions"].empty()) prim.erase("extensions");
      }
    }

    // Buffer views the kept content uses, copied into one buffer (each at
    // its old offset modulo 4, so that accessors stay aligned).
    std::vector<char> needed(nviews, 0);
    auto need = [&](int v) {
      if (v >= 0 && static_cast<size_t>(v) < nviews) needed[static_cast<size_t>(v)] = 1;
    };
    for (size_t i = 0; i < na; ++i) {
      if (claimed[i]) continue;
      const tinygltf::Accessor& a = model_.accessors[i];
      need(a.bufferView);
      if (a.sparse.isSparse) {
        need(a.sparse.indices.bufferView);
        need(a.sparse.values.bufferView);
      }
    }
    for (const tinygltf::Image& image : model_.images) need(image.bufferView);
    // Draco data of primitives not read (meshes outside the scene).
    std::vector<ojson*> draco;
    if (meshes)
      for (size_t m = 0; m < meshes->size(); ++m) {
        // find, not operator[]: that would add "primitives": null to a mesh
        // without any (the written document was then refused on reading).
        auto prims = (*meshes)[m].find("primitives");
        if (prims == (*meshes)[m].end() || !prims->is_array()) continue;
        for (ojson& prim : *prims) {
          if (!prim.is_object() || !prim.contains("extensions") || !prim["extensions"].is_object()) continue;
          ojson& ext = prim["extensions"];
          if (!ext.contains("KHR_draco_mesh_compression")) continue;
          ojson& d = ext["KHR_draco_mesh_compression"];
          if (d.is_object() && d.contains("bufferView") && d["bufferView"].is_number_unsigned() &&
              d["bufferView"].get<uint64_t>() < nviews) {
            need(d["bufferView"].get<int>());
            draco.push_back(&d);
          }
        }
      }
    std::string bin;
    std::vector<size_t> new_view(nviews, 0);
    ojson kept_views = ojson::array();
    for (size_t v = 0; v < nviews; ++v) {
      if (!needed[v]) continue;
      const tinygltf::BufferView& bv = model_.bufferViews[v];
      const tinygltf::BufferView* view;
      const tinygltf::Buffer* buffer;
      TSM_RETURN_IF_ERROR(check_view(static_cast<int>(v), "buffer view " + std::to_string(v), view, buffer));
      while (bin.size() % 4 != bv.byteOffset % 4) bin.push_back('\0');
      ojson j = (*views)[v].is_object() ? (*views)[v] : ojson::object();
      j["buffer"] = 0;
      j["byteOffset"] = bin.size();
      if (j.contains("extensions") && j["extensions"].is_object()) {
        j["extensions"].erase("EXT_meshopt_compression");  // the view holds the uncompressed fallback
        if (j["extensions"].empty()) j.erase("extensions");
      }
      bin.append(reinterpret_cast<const char*>(buffer->data.data()) + bv.byteOffset, bv.byteLength);
      new_view[v] = kept_views.size();
      kept_views.push_back(std::move(j));
    }
    while (bin.size() % 4) bin.push_back('\0');
    auto renumber = [&](ojson& obj, int old) {
      if (old >= 0 && static_cast<size_t>(old) < nviews && obj.is_object())
        obj["bufferView"] = new_view[static_cast<size_t>(old)];
    };
    for (size_t i = 0; i < na; ++i) {
      if (claimed[i]) continue;
      const tinygltf::Accessor& a = model_.accessors[i];
      ojson& j = (*accessors)[i];
      renumber(j, a.bufferView);
      if (a.sparse.isSparse && j.is_object() && j.contains("sparse") && j["sparse"].is_object()) {
        ojson& sp = j["sparse"];
        if (sp.contains("indices")) renumber(sp["indices"], a.sparse.indices.bufferView);
        if (sp.contains("values")) renumber(sp["values"], a.sparse.values.bufferView);
      }
    }
    for (size_t i = 0; i < model_.images.size(); ++i) renumber((*images)[i], model_.images[i].bufferView);
    for (ojson* d : draco) renumber(*d, (*d)["bufferView"].get<int>());

    if (accessors) {
      for (ojson& a : appended) accessors->push_back(std::move(a));
    } else if (!appended.empty()) {
      doc["accessors"] = ojson(std::move(appended));
    }
    if (kept_views.empty()) {
      doc.erase("bufferViews");
    } else {
      doc["bufferViews"] = std::move(kept_views);
    }
    if (bin.empty()) {
      doc.erase("buffers");
    } else {
      doc["buffers"] = ojson::array({ojson{{"byteLength", bin.size()}}});
    }
    // Extensions whose data is gone.
    if (doc.contains("extensionsUsed") && doc["extensionsUsed"].is_array()) {
      bool draco_left = !draco.empty();
      ojson used = ojson::array();
      for (const ojson& e : doc["extensionsUsed"])
        if (!(e == "EXT_meshopt_compression" || (e == "KHR_draco_mesh_compression" && !draco_left))) used.push_back(e);
      if (used.empty()) {
        doc.erase("extensionsUsed");
      } else {
        doc["extensionsUsed"] = std::move(used);
      }
    }

    // Which vertex group each vertex, which primitive each face belongs to.
    const auto tag_type = [&](size_t n, AttributeType& type) -> Status {
      if (n > (size_t{1} << 24)) return limit(std::to_string(n) + " vertex groups or primitives; tsm keeps at most 2^24");
      type = n <= 65536 ? AttributeType::u16 : AttributeType::i32;
      return Status::Ok();
    };
    if (groups_.size() > 1) {
      Attribute a;
      a.name = kGroupTag;
      TSM_RETURN_IF_ERROR(tag_type(groups_.size(), a.type));
      a.values.resize(out_.vertex_count());
      for (size_t g = 0; g < groups_.size(); ++g)
        std::fill_n(a.values.begin() + groups_[g].base, groups_[g].count, static_cast<float>(g));
      out_.attributes.push_back(std::move(a));
    }
    std::vector<size_t> sets_of_group(groups_.size(), 0);
    bool shared = false;
    for (const FaceSet& fs : face_sets_) shared |= ++sets_of_group[fs.group] > 1;
    if (shared) {
      Attribute a;
      a.name = kPrimitiveTag;
      a.domain = AttributeDomain::face;
      TSM_RETURN_IF_ERROR(tag_type(face_sets_.size(), a.type));
      a.values.resize(out_.face_count());
      for (size_t k = 0; k < face_sets_.size(); ++k)
        std::fill_n(a.values.begin() + face_sets_[k].first, face_sets_[k].count, static_cast<float>(k));
      out_.attributes.push_back(std::move(a));
    }

    ojson w = ojson::object();
    w["tsm_gltf"] = 1;
    ojson counts = ojson::array();
    for (const VertexGroup& g : groups_) counts.push_back(g.count);
    w["vertex_groups"] = std::move(counts);
    ojson sets = ojson::array();
    for (const FaceSet& fs : face_sets_) sets.push_back(ojson::array({fs.group, fs.count}));
    w["face_sets"] = std::move(sets);
    w["accessors"] = std::move(fills);
    w["document"] = std::move(doc);
    const std::string text = w.dump();
    if (text.size() + bin.size() > std::numeric_limits<uint32_t>::max() - 16u)
      return limit("the glTF content besides the geometry takes 4 GiB or more; refused");
    std::string value(kPassMagic, 4);
    value.resize(12);
    store_u32(reinterpret_cast<unsigned char*>(&value[4]), kPassVersion);
    store_u32(reinterpret_cast<unsigned char*>(&value[8]), static_cast<uint32_t>(text.size()));
    value += text;
    value += bin;
    out_.metadata.push_back({kPassKey, std::move(value)});
    return Status::Ok();
  }

  std::string_view bytes_;
  const std::string& name_;
  Mesh& out_;
  const ReadOptions& options_;
  ReadInfo* info_;
  tinygltf::Model model_;
  bool binary_ = false;
  size_t input_bytes_ = 0;
  uint64_t produced_ = 0;
  std::vector<VertexGroup> groups_;
  std::map<GroupKey, size_t> group_of_;
  std::map<std::tuple<GroupKey, int, int>, std::pair<size_t, int>> seen_primitives_;  // -> group, face set
  std::vector<PrimitiveRecord> records_;
  std::vector<FaceSet> face_sets_;
  std::string_view json_;  // the glTF JSON (GLB: its JSON chunk)
  size_t repeated_primitives_ = 0;
  size_t lines_as_points_ = 0;
  size_t empty_triangles_ = 0;
  size_t skipped_ = 0;
  std::string notes_;
  size_t note_count_ = 0;
};

// ---------------------------------------------------------------------------
// The writer

const char* type_text(AttributeType t) {
  switch (t) {
    case AttributeType::f32: return "f32";
    case AttributeType::u8: return "u8";
    case AttributeType::u16: return "u16";
    case AttributeType::i32: return "i32";
  }
  return "?";
}

// What every glTF this writer makes needs: triangles, vertex attributes
// only (the pass-through writer takes its own face tag), finite positions.
Status check_writable(const Mesh& mesh, bool passthrough) {
  std::string why;
  if (!mesh.valid(&why)) return Status(ErrorCode::invalid_argument, "cannot write glTF: the mesh is invalid: " + why);
  size_t other = 0, first = 0;
  for (size_t f = mesh.face_count(); f-- > 0;)
    if (mesh.face_size(f) != 3) {
      ++other;
      first = f;
    }
  if (other > 0)
    return Status(ErrorCode::unsupported,
                  "cannot write glTF: it stores triangles only, and " + std::to_string(other) + " of the mesh's " +
                      std::to_string(mesh.face_count()) + " faces are not triangles (face " + std::to_string(first) +
                      " has " + std::to_string(mesh.face_size(first)) +
                      " corners); write PLY or OBJ to keep polygons, or triangulate the mesh first");
  for (const Attribute& a : mesh.attributes) {
    if (a.domain == AttributeDomain::corner)
      return Status(ErrorCode::unsupported,
                    "cannot write glTF: attribute " + shown_name(a.name) +
                        " is per face corner (seams), and glTF has per-vertex attributes only; tsm does not split "
                        "vertices silently: write PLY or OBJ to keep it");
    if (a.domain == AttributeDomain::face && !(passthrough && a.name == kPrimitiveTag))
      return Status(ErrorCode::unsupported,
                    "cannot write glTF: attribute " + shown_name(a.name) +
                        " is per face, and glTF has per-vertex attributes only; tsm does not split vertices "
                        "silently: write PLY or OBJ to keep it");
  }
  for (size_t i = 0; i < mesh.positions.size(); ++i)
    if (!std::isfinite(mesh.positions[i]))
      return Status(ErrorCode::unsupported, "cannot write glTF: vertex " + std::to_string(i / 3) +
                                                " has a non-finite coordinate, and glTF needs the POSITION bounds "
                                                "(min / max) as finite numbers");
  return Status::Ok();
}

class GltfWriter {
 public:
  explicit GltfWriter(const Mesh& mesh) : mesh_(mesh) {}

  Status run(bool binary, std::string& out) {
    TSM_RETURN_IF_ERROR(check());
    model_.asset.version = "2.0";
    model_.asset.generator = "tsm " TSM_VERSION;
    const size_t nv = mesh_.vertex_count();
    if (nv > 0) {  // else: no scene, no mesh (an empty scene would be written as null)
      tinygltf::Primitive prim;
      prim.mode = mesh_.face_count() > 0 ? TINYGLTF_MODE_TRIANGLES : TINYGLTF_MODE_POINTS;
      prim.attributes["POSITION"] = add_positions();
      TSM_RETURN_IF_ERROR(add_attributes(prim));
      if (mesh_.face_count() > 0) prim.indices = add_indices();
      tinygltf::Mesh m;
      m.primitives.push_back(std::move(prim));
      model_.meshes.push_back(std::move(m));
      tinygltf::Node node;
      node.mesh = 0;
      model_.nodes.push_back(std::move(node));
      model_.scenes.emplace_back();
      model_.scenes[0].nodes.push_back(0);
      model_.defaultScene = 0;
      if (data_.size() > std::numeric_limits<uint32_t>::max() - (1u << 24))
        return Status(ErrorCode::limit_exceeded, "cannot write glTF: the mesh needs " + std::to_string(data_.size()) +
                                                     " bytes of buffer; a glTF buffer holds less than 4 GiB");
      tinygltf::Buffer buffer;
      buffer.data = std::move(data_);
      model_.buffers.push_back(std::move(buffer));
    }
    tinygltf::TinyGLTF writer;
    std::ostringstream os;
    if (!writer.WriteGltfSceneToStream(&model_, os, !binary, binary) || !os)
      return Status(ErrorCode::internal, "cannot write glTF: tinygltf failed to serialize the model");
    out = os.str();
    return Status::Ok();
  }

 private:
  Status check() const { return check_writable(mesh_, false); }

  // Appends a buffer view (append_view_bytes); returns its index.
  template <typename Put>
  int add_view(size_t elements, size_t elem, int target, Put put) {
    const auto [at, stride] = append_view_bytes(data_, elements, elem, target, put);
    tinygltf::BufferView view;
    view.buffer = 0;
    view.byteOffset = at;
    view.byteLength = elements * stride;
    view.byteStride = target == TINYGLTF_TARGET_ARRAY_BUFFER && stride != elem ? stride : 0;
    view.target = target;
    model_.bufferViews.push_back(std::move(view));
    return static_cast<int>(model_.bufferViews.size() - 1);
  }

  int add_accessor(int view, int component_type, bool normalized, uint32_t components, size_t count) {
    tinygltf::Accessor a;
    a.bufferView = view;
    a.componentType = component_type;
    a.normalized = normalized;
    a.type = type_for_components(components);
    a.count = count;
    model_.accessors.push_back(std::move(a));
    return static_cast<int>(model_.accessors.size() - 1);
  }

  int add_positions() {
    const size_t nv = mesh_.vertex_count();
    const float* p = mesh_.positions.data();
    const int view = add_view(nv, 12, TINYGLTF_TARGET_ARRAY_BUFFER, [&](size_t i, unsigned char* d) {
      for (size_t c = 0; c < 3; ++c) store_f32(d + 4 * c, p[3 * i + c]);
    });
    const int acc = add_accessor(view, kFloat, false, 3, nv);
    tinygltf::Accessor& a = model_.accessors.back();
    a.minValues.assign(3, 0.0);
    a.maxValues.assign(3, 0.0);
    for (size_t c = 0; c < 3; ++c) {
      float lo = p[c], hi = p[c];
      for (size_t i = 1; i < nv; ++i) {
        lo = std::min(lo, p[3 * i + c]);
        hi = std::max(hi, p[3 * i + c]);
      }
      a.minValues[c] = lo;
      a.maxValues[c] = hi;
    }
    return acc;
  }

  int add_indices() {
    const size_t n = mesh_.corner_count();
    const bool small = mesh_.vertex_count() <= 0xFFFF;  // 0xFFFF itself is the restart value, never used
    const uint32_t* idx = mesh_.indices.data();
    const int view =
        small ? add_view(n, 2, TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER,
                         [&](size_t i, unsigned char* d) { store_u16(d, static_cast<uint16_t>(idx[i])); })
              : add_view(n, 4, TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER, [&](size_t i, unsigned char* d) { store_u32(d, idx[i]); });
    return add_accessor(view, small ? kUShort : kUInt, false, 1, n);
  }

  static bool is_gltf_semantic(const Attribute& a) {
    if (!a.name.empty() && a.name[0] == '_') return true;
    if (a.name == "TANGENT") return a.components == 4 && a.type == AttributeType::f32;
    if (semantic_index(a.name, "JOINTS_") >= 0)
      return a.components == 4 && (a.type == AttributeType::u8 || a.type == AttributeType::u16);
    if (semantic_index(a.name, "WEIGHTS_") >= 0) return a.components == 4 && a.type != AttributeType::i32;
    return false;
  }

  Status add_attributes(tinygltf::Primitive& prim) {
    // Semantics: NORMAL for the first normal, TEXCOORD_n / COLOR_n numbered
    // in order (texcoord0, texcoord1, ... by their number first), the rest
    // as custom attributes.
    std::vector<const Attribute*> texcoords, colors;
    std::vector<std::pair<std::string, const Attribute*>> named;
    bool have_normal = false;
    for (const Attribute& a : mesh_.attributes) {
      if (a.kind == AttributeKind::normal && !have_normal && a.components == 3) {
        have_normal = true;
        named.emplace_back("NORMAL", &a);
      } else if (a.kind == AttributeKind::texcoord && a.components == 2) {
        texcoords.push_back(&a);
      } else if (a.kind == AttributeKind::color && a.components >= 3) {
        colors.push_back(&a);
      } else {
        named.emplace_back(is_gltf_semantic(a) ? a.name : "_" + a.name, &a);
      }
    }
    auto by_number = [](const char* prefix) {
      return [prefix](const Attribute* x, const Attribute* y) {
        long nx = semantic_index(x->name, prefix), ny = semantic_index(y->name, prefix);
        if (nx < 0) nx = std::numeric_limits<long>::max();
        if (ny < 0) ny = std::numeric_limits<long>::max();
        return nx < ny;
      };
    };
    std::stable_sort(texcoords.begin(), texcoords.end(), by_number("texcoord"));
    std::stable_sort(colors.begin(), colors.end(), [](const Attribute* x, const Attribute* y) {
      auto number = [](const Attribute* a) {
        if (a->name == "color") return 0L;
        long n = semantic_index(a->name, "color");
        return n < 0 ? std::numeric_limits<long>::max() : n;
      };
      return number(x) < number(y);
    });
    for (size_t i = 0; i < texcoords.size(); ++i) named.emplace_back("TEXCOORD_" + std::to_string(i), texcoords[i]);
    for (size_t i = 0; i < colors.size(); ++i) named.emplace_back("COLOR_" + std::to_string(i), colors[i]);

    for (auto& [semantic, a] : named) {
      if (prim.attributes.count(semantic))
        return Status(ErrorCode::invalid_argument, "cannot write glTF: two attributes would both be " + shown_name(semantic) +
                                                       "; rename attribute " + shown_name(a->name));
      int ct = kFloat;
      bool normalized = false;
      const bool is_color = semantic.compare(0, 6, "COLOR_") == 0;
      const bool is_weights = semantic_index(semantic, "WEIGHTS_") >= 0;
      if (a->type == AttributeType::u8 || a->type == AttributeType::u16) {
        if (a->kind == AttributeKind::color || a->kind == AttributeKind::generic) {
          ct = a->type == AttributeType::u8 ? kUByte : kUShort;
          normalized = is_color || is_weights;
          const float top = a->type == AttributeType::u8 ? 255.0f : 65535.0f;
          for (size_t i = 0; i < a->values.size(); ++i) {
            const float x = a->values[i];
            if (!(x >= 0 && x <= top && x == std::floor(x)))
              return Status(ErrorCode::invalid_argument,
                            "cannot write glTF: attribute " + shown_name(a->name) + " has type " + type_text(a->type) +
                                " but value " + float_text(x) + " (vertex " + std::to_string(i / a->components) +
                                ") is not an integer in 0.." + float_text(top));
          }
        }
      }
      const size_t csize = gltf::component_bytes(ct);
      const uint32_t comps = a->components;
      const float* src = a->values.data();
      const int view = add_view(mesh_.vertex_count(), csize * comps, TINYGLTF_TARGET_ARRAY_BUFFER,
                                [&](size_t i, unsigned char* d) {
                                  for (uint32_t c = 0; c < comps; ++c) {
                                    const float x = src[i * comps + c];
                                    if (ct == kFloat) {
                                      store_f32(d + 4 * c, x);
                                    } else if (ct == kUByte) {
                                      d[c] = static_cast<unsigned char>(x);
                                    } else {
                                      store_u16(d + 2 * c, static_cast<uint16_t>(x));
                                    }
                                  }
                                });
      prim.attributes[semantic] = add_accessor(view, ct, normalized, comps, mesh_.vertex_count());
    }
    return Status::Ok();
  }

  const Mesh& mesh_;
  tinygltf::Model model_;
  std::vector<unsigned char> data_;
};

// ---------------------------------------------------------------------------
// The pass-through writer: the document of the "gltf" metadata entry with the
// geometry of the mesh put back into its accessors.

std::string base64_encode(std::string_view in) {
  static const char* k = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((in.size() + 2) / 3 * 4);
  size_t i = 0;
  const auto* u = reinterpret_cast<const unsigned char*>(in.data());
  for (; i + 2 < in.size(); i += 3) {
    const uint32_t v = static_cast<uint32_t>(u[i]) << 16 | static_cast<uint32_t>(u[i + 1]) << 8 | u[i + 2];
    for (int sh = 18; sh >= 0; sh -= 6) out += k[(v >> sh) & 63];
  }
  if (i < in.size()) {
    uint32_t v = static_cast<uint32_t>(u[i]) << 16;
    if (i + 1 < in.size()) v |= static_cast<uint32_t>(u[i + 1]) << 8;
    out += k[(v >> 18) & 63];
    out += k[(v >> 12) & 63];
    out += i + 1 < in.size() ? k[(v >> 6) & 63] : '=';
    out += '=';
  }
  return out;
}

class PassThroughWriter {
 public:
  PassThroughWriter(const Mesh& mesh, const std::string& value) : mesh_(mesh), value_(value) {}

  Status run(bool binary, std::string& out) {
    TSM_RETURN_IF_ERROR(parse());
    TSM_RETURN_IF_ERROR(check_writable(mesh_, true));
    TSM_RETURN_IF_ERROR(assign_vertices());
    TSM_RETURN_IF_ERROR(assign_faces());
    TSM_RETURN_IF_ERROR(fill_accessors());
    return serialize(binary, out);
  }

  // The image URIs of the document that name files (not data: URIs): a
  // written .gltf/.glb refers to them relative to its own folder.
  std::vector<std::string> image_files() const {
    std::vector<std::string> files;
    const ojson& doc = wrapper_["document"];
    auto images = doc.find("images");
    if (images == doc.end() || !images->is_array()) return files;
    for (const ojson& image : *images) {
      if (!image.is_object()) continue;
      auto uri = image.find("uri");
      if (uri != image.end() && uri->is_string() && uri->get<std::string>().rfind("data:", 0) != 0)
        files.push_back(uri->get<std::string>());
    }
    return files;
  }

 private:
  static Status damaged(const std::string& what) {
    return Status(ErrorCode::corrupt_data,
                  "cannot write glTF: the mesh's glTF pass-through data (metadata 'gltf') is damaged: " + what);
  }
  static Status mismatch(const std::string& what) {
    return Status(ErrorCode::invalid_argument,
                  "cannot write glTF: the mesh does not match its glTF pass-through data (metadata 'gltf'): " + what);
  }

  // An unsigned integer member below `bound`.
  static bool get_index(const ojson& obj, const char* key, uint64_t bound, uint64_t& v) {
    if (!obj.is_object()) return false;
    auto it = obj.find(key);
    if (it == obj.end() || !it->is_number_unsigned()) return false;
    v = it->get<uint64_t>();
    return v < bound;
  }

  Status parse() {
    const auto* u = reinterpret_cast<const unsigned char*>(value_.data());
    if (value_.size() < 12 || std::memcmp(value_.data(), kPassMagic, 4) != 0)
      return damaged("it does not start with 'tsmG' and its 12-byte header");
    const uint32_t version = load_u32(u + 4);
    if (version != kPassVersion)
      return damaged("version " + std::to_string(version) + "; this tsm reads version " + std::to_string(kPassVersion));
    const uint32_t json_length = load_u32(u + 8);
    if (json_length > value_.size() - 12)
      return damaged("its JSON (" + std::to_string(json_length) + " bytes) runs past its end (" +
                     std::to_string(value_.size()) + " bytes)");
    const std::string_view text(value_.data() + 12, json_length);
    bin_ = std::string_view(value_).substr(12 + static_cast<size_t>(json_length));
    if (bin_.size() % 4 != 0) return damaged("its binary part is not a multiple of 4 bytes");
    if (json_depth(text, kMaxJsonDepth + 2) > kMaxJsonDepth + 2) return damaged("its JSON nests too deep");
    try {
      wrapper_ = ojson::parse(text.begin(), text.end());
    } catch (const std::exception& e) {
      return damaged(std::string("its JSON does not parse: ") + clean_message(e.what()));
    }
    if (!wrapper_.is_object() || wrapper_.value("tsm_gltf", ojson()) != 1)
      return damaged("its JSON is not a version 1 description");
    for (const char* key : {"vertex_groups", "face_sets", "accessors"})
      if (!wrapper_.contains(key) || !wrapper_[key].is_array()) return damaged(std::string("no '") + key + "' list");
    if (!wrapper_.contains("document") || !wrapper_["document"].is_object()) return damaged("no glTF document");
    for (const ojson& c : wrapper_["vertex_groups"]) {
      if (!c.is_number_unsigned() || c.get<uint64_t>() > kMaxIndex) return damaged("a vertex group's size is not a count");
      groups_.push_back(c.get<uint64_t>());
    }
    for (const ojson& fs : wrapper_["face_sets"]) {
      if (!fs.is_array() || fs.size() != 2 || !fs[0].is_number_unsigned() || fs[0].get<uint64_t>() >= groups_.size() ||
          !fs[1].is_number_unsigned() || fs[1].get<uint64_t>() > kMaxIndex)
        return damaged("a face set is not [vertex group, face count]");
      sets_.emplace_back(static_cast<size_t>(fs[0].get<uint64_t>()), fs[1].get<uint64_t>());
    }
    return Status::Ok();
  }

  // An attribute of the mesh by name in `domain` with one component (a tag).
  const Attribute* tag(const char* name, AttributeDomain domain) const {
    for (const Attribute& a : mesh_.attributes)
      if (a.name == name && a.domain == domain && a.components == 1) return &a;
    return nullptr;
  }

  static bool tag_value(const Attribute& a, size_t i, size_t bound, size_t& v) {
    const float x = a.values[i];
    if (!(x >= 0 && x < static_cast<float>(bound) && x == std::floor(x))) return false;
    v = static_cast<size_t>(x);
    return v < bound;
  }

  Status assign_vertices() {
    const size_t nv = mesh_.vertex_count();
    uint64_t total = 0;
    for (uint64_t c : groups_) total += c;
    if (total != nv)
      return mismatch("it describes " + std::to_string(total) + " vertices, and the mesh has " + std::to_string(nv));
    group_of_.assign(nv, 0);
    local_.assign(nv, 0);
    if (groups_.size() > 1) {
      const Attribute* t = tag(kGroupTag, AttributeDomain::vertex);
      if (!t)
        return mismatch(std::string("no vertex attribute '") + kGroupTag + "' tells its " +
                        std::to_string(groups_.size()) + " vertex groups apart");
      for (size_t v = 0; v < nv; ++v) {
        size_t g;
        if (!tag_value(*t, v, groups_.size(), g))
          return mismatch(std::string("vertex ") + std::to_string(v) + ": '" + kGroupTag + "' is " +
                          float_text(t->values[v]) + ", not a vertex group (0.." + std::to_string(groups_.size() - 1) +
                          ")");
        group_of_[v] = static_cast<uint32_t>(g);
      }
    }
    members_.assign(groups_.size(), {});
    for (size_t v = 0; v < nv; ++v) {
      std::vector<uint32_t>& m = members_[group_of_[v]];
      local_[v] = static_cast<uint32_t>(m.size());
      m.push_back(static_cast<uint32_t>(v));
    }
    for (size_t g = 0; g < groups_.size(); ++g)
      if (members_[g].size() != groups_[g])
        return mismatch("vertex group " + std::to_string(g) + " has " + std::to_string(members_[g].size()) +
                        " vertices; it had " + std::to_string(groups_[g]));
    return Status::Ok();
  }

  Status assign_faces() {
    const size_t nf = mesh_.face_count();
    uint64_t total = 0;
    for (const auto& fs : sets_) total += fs.second;
    if (total != nf)
      return mismatch("it describes " + std::to_string(total) + " triangles, and the mesh has " + std::to_string(nf));
    faces_.assign(sets_.size(), {});
    const Attribute* t = tag(kPrimitiveTag, AttributeDomain::face);
    // Without the tag, a vertex group has at most one face set.
    std::vector<long> only(groups_.size(), -1);
    for (size_t k = 0; k < sets_.size(); ++k) only[sets_[k].first] = only[sets_[k].first] == -1 ? static_cast<long>(k) : -2;
    for (size_t f = 0; f < nf; ++f) {
      const uint32_t* c = mesh_.face(f);
      size_t k;
      if (t) {
        if (!tag_value(*t, f, sets_.size(), k))
          return mismatch(std::string("face ") + std::to_string(f) + ": '" + kPrimitiveTag + "' is " +
                          float_text(t->values[f]) + ", not a primitive (0.." + std::to_string(sets_.size()) + ")");
      } else {
        const long o = only[group_of_[c[0]]];
        if (o < 0)
          return mismatch(std::string("face ") + std::to_string(f) + " is in vertex group " +
                          std::to_string(group_of_[c[0]]) + ", which has " + (o == -1 ? "no" : "several") +
                          " triangle primitives, and no face attribute '" + kPrimitiveTag + "' says which");
        k = static_cast<size_t>(o);
      }
      for (int i = 0; i < 3; ++i)
        if (group_of_[c[i]] != sets_[k].first)
          return mismatch("face " + std::to_string(f) + " of primitive " + std::to_string(k) + " uses vertex " +
                          std::to_string(c[i]) + " of vertex group " + std::to_string(group_of_[c[i]]) +
                          ", and that primitive's vertices are group " + std::to_string(sets_[k].first));
      faces_[k].push_back(static_cast<uint32_t>(f));
    }
    for (size_t k = 0; k < sets_.size(); ++k)
      if (faces_[k].size() != sets_[k].second)
        return mismatch("primitive " + std::to_string(k) + " has " + std::to_string(faces_[k].size()) +
                        " triangles; it had " + std::to_string(sets_[k].second));
    return Status::Ok();
  }

  // Appends a buffer view (append_view_bytes); returns its index, or
  // kNoView for no elements (a buffer view holds at least one byte; an
  // accessor without a view reads as zeros, here none).
  static constexpr size_t kNoView = ~size_t{0};
  template <typename Put>
  size_t add_view(size_t elements, size_t elem, int target, Put put) {
    if (elements == 0) return kNoView;
    const auto [at, stride] = append_view_bytes(data_, elements, elem, target, put);
    ojson view = {{"buffer", 0}, {"byteOffset", at}, {"byteLength", elements * stride}};
    if (target == TINYGLTF_TARGET_ARRAY_BUFFER && stride != elem) view["byteStride"] = stride;
    view["target"] = target;
    views_->push_back(std::move(view));
    return views_->size() - 1;
  }

  // The accessor `slot` with its data fields first, then what it kept (name, extras, ...).
  static void set_accessor(ojson& slot, size_t view, int ct, bool normalized, size_t count, uint32_t comps,
                           const std::vector<double>* lo, const std::vector<double>* hi) {
    ojson a = ojson::object();
    if (view != kNoView) a["bufferView"] = view;
    a["componentType"] = ct;
    if (normalized) a["normalized"] = true;
    a["count"] = count;
    a["type"] = type_name(type_for_components(comps));
    if (lo && hi && count > 0) {
      a["min"] = *lo;
      a["max"] = *hi;
    }
    for (const auto& kv : slot.items())
      if (!a.contains(kv.key())) a[kv.key()] = kv.value();
    slot = std::move(a);
  }

  Status fill_accessors() {
    ojson& doc = wrapper_["document"];
    if (!doc.contains("bufferViews")) doc["bufferViews"] = ojson::array();
    if (!doc["bufferViews"].is_array()) return damaged("the document's bufferViews are not a list");
    views_ = &doc["bufferViews"];
    const ojson& fills = wrapper_["accessors"];
    if (!fills.empty() && (!doc.contains("accessors") || !doc["accessors"].is_array()))
      return damaged("the document has no accessors list");
    data_.assign(bin_.begin(), bin_.end());
    std::vector<char> filled(fills.empty() ? 0 : doc["accessors"].size(), 0);
    for (const ojson& e : fills) {
      uint64_t slot;
      if (!get_index(e, "accessor", filled.size(), slot) || filled[slot] || !doc["accessors"][slot].is_object())
        return damaged("an entry names no accessor of the document, or one already filled");
      filled[slot] = 1;
      ojson& acc = doc["accessors"][slot];
      uint64_t k;
      if (e.contains("face_set")) {
        if (!get_index(e, "face_set", sets_.size(), k)) return damaged("an entry names no face set");
        const std::vector<uint32_t>& faces = faces_[k];
        const bool small = groups_[sets_[k].first] <= 0xFFFF;
        const size_t n = 3 * faces.size();
        auto corner = [&](size_t i) { return local_[mesh_.face(faces[i / 3])[i % 3]]; };
        const size_t view =
            small ? add_view(n, 2, TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER,
                             [&](size_t i, unsigned char* d) { store_u16(d, static_cast<uint16_t>(corner(i))); })
                  : add_view(n, 4, TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER,
                             [&](size_t i, unsigned char* d) { store_u32(d, corner(i)); });
        set_accessor(acc, view, small ? kUShort : kUInt, false, n, 1, nullptr, nullptr);
        continue;
      }
      if (!get_index(e, "group", groups_.size(), k)) return damaged("an entry names no vertex group");
      const std::vector<uint32_t>& verts = members_[k];
      if (!e.contains("semantic") || !e["semantic"].is_string()) return damaged("an entry has no semantic");
      const std::string semantic = e["semantic"].get<std::string>();
      const float* src;
      uint32_t comps, stride;
      const Attribute* a = nullptr;
      if (!e.contains("attribute")) {
        if (semantic != "POSITION") return damaged("an entry without a mesh attribute is not POSITION");
        src = mesh_.positions.data();
        comps = stride = 3;
      } else {
        if (!e["attribute"].is_string()) return damaged("an entry's attribute is not a name");
        const std::string name = e["attribute"].get<std::string>();
        for (const Attribute& x : mesh_.attributes)
          if (x.name == name && x.domain == AttributeDomain::vertex) a = &x;
        if (!a) return mismatch("the mesh has no vertex attribute " + shown_name(name) + " for " + semantic);
        uint64_t c;
        if (!get_index(e, "components", 5, c) || c == 0) return damaged("an entry's component count is not 1..4");
        if (c > a->components)
          return mismatch("attribute " + shown_name(name) + " has " + std::to_string(a->components) +
                          " components; " + semantic + " had " + std::to_string(c));
        src = a->values.data();
        comps = static_cast<uint32_t>(c);
        stride = a->components;
      }
      // Component type: integers stay integers (colours and weights
      // normalized), everything else is float.
      int ct = kFloat;
      bool normalized = false;
      const bool target = e.contains("target");
      if (a && !target && (a->type == AttributeType::u8 || a->type == AttributeType::u16) &&
          (a->kind == AttributeKind::color || a->kind == AttributeKind::generic)) {
        ct = a->type == AttributeType::u8 ? kUByte : kUShort;
        normalized = semantic.compare(0, 6, "COLOR_") == 0 || semantic_index(semantic, "WEIGHTS_") >= 0;
        const float top = a->type == AttributeType::u8 ? 255.0f : 65535.0f;
        for (uint32_t v : verts)
          for (uint32_t c = 0; c < comps; ++c) {
            const float x = src[static_cast<size_t>(v) * stride + c];
            if (!(x >= 0 && x <= top && x == std::floor(x)))
              return Status(ErrorCode::invalid_argument,
                            "cannot write glTF: attribute " + shown_name(a->name) + " has type " + type_text(a->type) +
                                " but value " + float_text(x) + " (vertex " + std::to_string(v) +
                                ") is not an integer in 0.." + float_text(top));
          }
      }
      const size_t csize = gltf::component_bytes(ct);
      const size_t view = add_view(verts.size(), csize * comps, TINYGLTF_TARGET_ARRAY_BUFFER,
                                   [&](size_t i, unsigned char* d) {
                                     const float* p = src + static_cast<size_t>(verts[i]) * stride;
                                     for (uint32_t c = 0; c < comps; ++c) {
                                       if (ct == kFloat) {
                                         store_f32(d + 4 * c, p[c]);
                                       } else if (ct == kUByte) {
                                         d[c] = static_cast<unsigned char>(p[c]);
                                       } else {
                                         store_u16(d + 2 * c, static_cast<uint16_t>(p[c]));
                                       }
                                     }
                                   });
      std::vector<double> lo, hi;
      if (semantic == "POSITION") {  // required for POSITION and morph target POSITION
        lo.assign(comps, 0.0);
        hi.assign(comps, 0.0);
        for (uint32_t c = 0; c < comps; ++c) {
          float l = std::numeric_limits<float>::infinity(), h = -l;
          for (uint32_t v : verts) {
            l = std::min(l, src[static_cast<size_t>(v) * stride + c]);
            h = std::max(h, src[static_cast<size_t>(v) * stride + c]);
          }
          if (!std::isfinite(l) || !std::isfinite(h)) l = h = 0;  // a target with non-finite values: no bound
          lo[c] = l;
          hi[c] = h;
        }
      }
      set_accessor(acc, view, ct, normalized, verts.size(), comps, lo.empty() ? nullptr : &lo,
                   hi.empty() ? nullptr : &hi);
    }
    if (views_->empty()) doc.erase("bufferViews");
    return Status::Ok();
  }

  Status serialize(bool binary, std::string& out) {
    ojson& doc = wrapper_["document"];
    while (data_.size() % 4) data_.push_back(0);
    if (data_.size() > std::numeric_limits<uint32_t>::max() - (1u << 24))
      return Status(ErrorCode::limit_exceeded, "cannot write glTF: the document needs " + std::to_string(data_.size()) +
                                                   " bytes of buffer; a glTF buffer holds less than 4 GiB");
    if (data_.empty()) {
      doc.erase("buffers");
    } else {
      ojson buffer = {{"byteLength", data_.size()}};
      if (!binary) buffer["uri"] = "data:application/octet-stream;base64," + base64_encode(data_);
      doc["buffers"] = ojson::array({std::move(buffer)});
    }
    if (!binary) {
      out = doc.dump(2);
      out += '\n';
      return Status::Ok();
    }
    std::string json = doc.dump();
    while (json.size() % 4) json += ' ';
    const uint64_t total = 12 + 8 + json.size() + (data_.empty() ? 0 : 8 + data_.size());
    if (total > std::numeric_limits<uint32_t>::max())
      return Status(ErrorCode::limit_exceeded, "cannot write glTF: the GLB would take 4 GiB or more");
    std::string glb(20, '\0');
    auto* h = reinterpret_cast<unsigned char*>(&glb[0]);
    store_u32(h, kGlbMagic);
    store_u32(h + 4, 2);
    store_u32(h + 8, static_cast<uint32_t>(total));
    store_u32(h + 12, static_cast<uint32_t>(json.size()));
    store_u32(h + 16, kChunkJson);
    glb += json;
    if (!data_.empty()) {
      unsigned char c[8];
      store_u32(c, static_cast<uint32_t>(data_.size()));
      store_u32(c + 4, kChunkBin);
      glb.append(reinterpret_cast<const char*>(c), 8);
      glb += data_;
    }
    out = std::move(glb);
    return Status::Ok();
  }

  const Mesh& mesh_;
  const std::string& value_;
  ojson wrapper_;
  std::string_view bin_;
  std::vector<uint64_t> groups_;                    // vertex count of each group
  std::vector<std::pair<size_t, uint64_t>> sets_;   // group and triangle count of each face set
  std::vector<uint32_t> group_of_, local_;          // per mesh vertex
  std::vector<std::vector<uint32_t>> members_;      // mesh vertices of each group, in mesh order
  std::vector<std::vector<uint32_t>> faces_;        // mesh faces of each face set, in mesh order
  ojson* views_ = nullptr;
  std::string data_;
};

}  // namespace

Status read_file_beside(const std::string& dir, const std::string& uri, std::string& out) {
  if (dir.empty())
    return Status(ErrorCode::unsupported, "external file " + shown_uri(uri) +
                                              ": external files are not read here (the glTF did not come from a "
                                              "file: give the .gltf file's path)");
  FsContext ctx;
  ctx.dir = dir;
  ctx.prefix = dir + "/";
  const std::string rel = uri_decoded(uri);
  const std::string why = unsafe_reference(rel);
  if (!why.empty())
    return Status(ErrorCode::parse_error, "uri " + shown_uri(uri) + " " + why +
                                              "; refused: external files are read only from the .gltf file's "
                                              "folder and its subfolders, by relative URI");
  std::vector<unsigned char> bytes;
  std::string err;
  if (!fs_read(&bytes, &err, ctx.prefix + rel, &ctx)) return Status(ErrorCode::io_error, ctx.error);
  out.assign(bytes.begin(), bytes.end());
  return Status::Ok();
}

Status read_gltf(std::string_view bytes, const std::string& name, Mesh& out, const ReadOptions& options,
                 ReadInfo* info) {
  Status s = GltfReader(bytes, name, out, options, info).run();
  if (s.ok()) return s;
  bool compressed = false;
  for (const char* ext : {"KHR_draco_mesh_compression", "_meshopt_compression", "TSM_mesh_compression"})
    compressed = compressed || bytes.find(ext) != std::string_view::npos;
  if (!compressed) return s;
  // Primitives only a compressed copy holds (Draco, meshopt, tsm's own
  // extension): the transcoder decodes them into a plain document first
  // (its refusals name what is missing, e.g. a build without Draco).
  GltfTranscodeOptions plain_options;
  plain_options.compress = false;
  GltfOutput plain;
  TSM_RETURN_IF_ERROR(transcode_gltf(bytes, name, options.external_files_dir, plain_options, true, "", plain));
  s = GltfReader(plain.main, name, out, options, info).run();
  if (s.ok() && info) info->add_note("compressed primitives decoded first");
  return s;
}

Status write_gltf(const Mesh& mesh, const WriteOptions& options, std::string& out, bool binary, WriteInfo* info) {
  (void)options;
  out.clear();
  try {
    if (const MetadataEntry* pass = mesh.find_metadata(kPassKey)) {
      PassThroughWriter writer(mesh, pass->value);
      Status s = writer.run(binary, out);
      if (!s.ok()) {
        out.clear();
      } else if (info) {
        const std::vector<std::string> files = writer.image_files();
        if (!files.empty())
          info->add_note("the document names " + std::to_string(files.size()) +
                         (files.size() == 1 ? " image file" : " image files") + " by relative URI (first: \"" +
                         clean_message(files[0]) + "\"): copy " + (files.size() == 1 ? "it" : "them") +
                         " beside the output, or viewers show the mesh without it");
      }
      return s;
    }
    return GltfWriter(mesh).run(binary, out);
  } catch (const std::bad_alloc&) {
    out.clear();
    return Status(ErrorCode::limit_exceeded, "cannot write glTF: out of memory");
  } catch (const std::exception& e) {  // a JSON value of an unexpected type in the metadata
    out.clear();
    return Status(ErrorCode::corrupt_data,
                  std::string("cannot write glTF: the mesh's glTF pass-through data (metadata 'gltf') is damaged: ") +
                      clean_message(e.what()));
  }
}

}  // namespace tsm

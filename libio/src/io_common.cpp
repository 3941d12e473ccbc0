// Mesh file dispatch and whole-file I/O (file-format stage, outside the
// method itself): format detection, reading files into memory, and atomic
// writes (temporary file in the target's folder, fsync, rename), so that no
// failure ever leaves a partial output file behind.
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "tsm/io.hpp"

namespace tsm {

namespace {

std::string errno_text() { return std::strerror(errno); }

bool ends_with_ci(std::string_view s, std::string_view suffix) {
  if (s.size() < suffix.size()) return false;
  for (size_t i = 0; i < suffix.size(); ++i) {
    char a = s[s.size() - suffix.size() + i];
    if (a >= 'A' && a <= 'Z') a = static_cast<char>(a - 'A' + 'a');
    if (a != suffix[i]) return false;
  }
  return true;
}

bool starts_with_ci(std::string_view s, std::string_view prefix) {
  if (s.size() < prefix.size()) return false;
  for (size_t i = 0; i < prefix.size(); ++i) {
    char a = s[i];
    if (a >= 'A' && a <= 'Z') a = static_cast<char>(a - 'A' + 'a');
    if (a != prefix[i]) return false;
  }
  return true;
}

}  // namespace

const char* mesh_format_name(MeshFormat format) {
  switch (format) {
    case MeshFormat::ply: return "PLY";
    case MeshFormat::obj: return "OBJ";
    case MeshFormat::stl: return "STL";
    case MeshFormat::off: return "OFF";
    case MeshFormat::gltf: return "glTF";
    case MeshFormat::glb: return "GLB";
    case MeshFormat::unknown: break;
  }
  return "unknown";
}

MeshFormat format_from_extension(std::string_view path) {
  if (ends_with_ci(path, ".ply")) return MeshFormat::ply;
  if (ends_with_ci(path, ".obj")) return MeshFormat::obj;
  if (ends_with_ci(path, ".stl")) return MeshFormat::stl;
  if (ends_with_ci(path, ".off")) return MeshFormat::off;
  if (ends_with_ci(path, ".gltf")) return MeshFormat::gltf;
  if (ends_with_ci(path, ".glb")) return MeshFormat::glb;
  return MeshFormat::unknown;
}

MeshFormat sniff_format(std::string_view bytes) {
  if (bytes.substr(0, 4) == "glTF") return MeshFormat::glb;
  {
    // .gltf: a JSON object (after an optional UTF-8 byte order mark and
    // blanks) with an "asset" member somewhere.
    size_t k = bytes.substr(0, 3) == "\xEF\xBB\xBF" ? 3 : 0;
    while (k < bytes.size() && (bytes[k] == ' ' || bytes[k] == '\t' || bytes[k] == '\n' || bytes[k] == '\r')) ++k;
    if (k < bytes.size() && bytes[k] == '{' && bytes.find("\"asset\"", k) != std::string_view::npos)
      return MeshFormat::gltf;
  }
  if (bytes.size() >= 4 && bytes.substr(0, 3) == "ply" &&
      (bytes[3] == '\n' || bytes[3] == '\r' || bytes[3] == ' ' || bytes[3] == '\t'))
    return MeshFormat::ply;
  // Binary STL: 80-byte header, uint32 count, 50 bytes per triangle. Checked
  // before "solid" because binary headers often start with that word too.
  if (bytes.size() >= 84) {
    uint32_t n;
    std::memcpy(&n, bytes.data() + 80, 4);  // little endian hosts only (x86, ARM)
    if (84 + 50 * static_cast<uint64_t>(n) == bytes.size()) return MeshFormat::stl;
  }
  size_t i = 0;
  while (i < bytes.size() && (bytes[i] == ' ' || bytes[i] == '\t' || bytes[i] == '\n' || bytes[i] == '\r')) ++i;
  std::string_view rest = bytes.substr(i);
  if (starts_with_ci(rest, "solid")) return MeshFormat::stl;
  // OFF, COFF, NOFF, STOFF, 4OFF...: the first token ends in "OFF".
  size_t j = 0;
  while (j < rest.size() && j < 8 && rest[j] > ' ') ++j;
  if (j >= 3 && rest.substr(j - 3, 3) == "OFF") return MeshFormat::off;
  return MeshFormat::unknown;
}

void ReadInfo::add_note(const std::string& note) {
  if (note.empty()) return;
  if (!notes.empty()) notes += "; ";
  notes += note;
}

Status read_file(const std::string& path, std::string& out) {
  FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) return Status(ErrorCode::io_error, path + ": cannot open: " + errno_text());
  struct stat st = {};
  if (fstat(fileno(f), &st) != 0 || !S_ISREG(st.st_mode)) {
    std::fclose(f);
    if (S_ISDIR(st.st_mode)) return Status(ErrorCode::io_error, path + ": is a folder, not a file");
    // Pipes and devices: read until the end.
    f = std::fopen(path.c_str(), "rb");
    if (!f) return Status(ErrorCode::io_error, path + ": cannot open: " + errno_text());
    out.clear();
    char buf[1 << 16];
    size_t n;
    while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) out.append(buf, n);
    bool bad = std::ferror(f);
    std::fclose(f);
    if (bad) return Status(ErrorCode::io_error, path + ": read failed: " + errno_text());
    return Status::Ok();
  }
  out.resize(static_cast<size_t>(st.st_size));
  size_t got = out.empty() ? 0 : std::fread(out.data(), 1, out.size(), f);
  bool bad = std::ferror(f);
  std::fclose(f);
  if (bad || got != out.size())
    return Status(ErrorCode::io_error, path + ": read failed after " + std::to_string(got) + " of " +
                                           std::to_string(out.size()) + " bytes");
  return Status::Ok();
}

namespace {
// The process umask, read once: from /proc where it is shown (no window in
// which other threads would create files with a zero umask), else by setting
// and restoring it (thread-safe static initialization, once).
mode_t process_umask() {
  static const mode_t mask = [] {
    if (FILE* f = std::fopen("/proc/self/status", "r")) {
      char line[256];
      unsigned value = 0;
      bool found = false;
      while (std::fgets(line, sizeof line, f))
        if (std::sscanf(line, "Umask: %o", &value) == 1) {
          found = true;
          break;
        }
      std::fclose(f);
      if (found) return static_cast<mode_t>(value);
    }
    mode_t m = umask(0);
    umask(m);
    return m;
  }();
  return mask;
}
}  // namespace

Status write_file_atomic(const std::string& path, std::string_view bytes) {
  std::string tmpl = path + ".tmp-XXXXXX";
  int fd = mkstemp(tmpl.data());
  if (fd < 0)
    return Status(ErrorCode::io_error, path + ": cannot create a temporary file beside it: " + errno_text());
  const char* p = bytes.data();
  size_t left = bytes.size();
  while (left > 0) {
    ssize_t w = ::write(fd, p, left);
    if (w < 0) {
      if (errno == EINTR) continue;
      std::string why = errno_text();
      ::close(fd);
      ::unlink(tmpl.c_str());
      return Status(ErrorCode::io_error, path + ": write failed: " + why + " (nothing was written)");
    }
    p += w;
    left -= static_cast<size_t>(w);
  }
  // mkstemp creates 0600; give the file the usual permissions (umask applies).
  fchmod(fd, 0666 & ~process_umask());
  if (::fsync(fd) != 0 || ::close(fd) != 0) {
    std::string why = errno_text();
    ::unlink(tmpl.c_str());
    return Status(ErrorCode::io_error, path + ": write failed: " + why + " (nothing was written)");
  }
  if (std::rename(tmpl.c_str(), path.c_str()) != 0) {
    std::string why = errno_text();
    ::unlink(tmpl.c_str());
    return Status(ErrorCode::io_error, path + ": cannot rename the temporary file into place: " + why);
  }
  return Status::Ok();
}

Status read_mesh_from_memory(std::string_view bytes, const std::string& name, Mesh& out,
                             const ReadOptions& options, ReadInfo* info, MeshFormat format) {
  ReadInfo local;
  if (!info) info = &local;
  *info = ReadInfo();
  out.clear();
  MeshFormat sniffed = sniff_format(bytes);
  if (sniffed != MeshFormat::unknown) format = sniffed;  // content wins over the name
  if (format == MeshFormat::unknown) format = format_from_extension(name);
  info->format = format;
  switch (format) {
    case MeshFormat::ply: return read_ply(bytes, name, out, options, info);
    case MeshFormat::obj: return read_obj(bytes, name, out, options, info);
    case MeshFormat::stl: return read_stl(bytes, name, out, options, info);
    case MeshFormat::off: return read_off(bytes, name, out, options, info);
    case MeshFormat::gltf:
    case MeshFormat::glb: return read_gltf(bytes, name, out, options, info);
    case MeshFormat::unknown: break;
  }
  return Status(ErrorCode::parse_error,
                name + ": unknown mesh format (expected PLY, OBJ, STL, OFF or glTF; the content did not match any and "
                       "the extension did not say)");
}

Status read_mesh(const std::string& path, Mesh& out, const ReadOptions& options, ReadInfo* info) {
  std::string bytes;
  TSM_RETURN_IF_ERROR(read_file(path, bytes));
  if (options.external_files_dir.empty()) {
    // A .gltf file's buffers may be files beside it.
    ReadOptions o = options;
    const size_t slash = path.find_last_of('/');
    o.external_files_dir = slash == std::string::npos ? "." : slash == 0 ? "/" : path.substr(0, slash);
    return read_mesh_from_memory(bytes, path, out, o, info, format_from_extension(path));
  }
  return read_mesh_from_memory(bytes, path, out, options, info, format_from_extension(path));
}

Status write_mesh(const std::string& path, const Mesh& mesh, const WriteOptions& options, WriteInfo* info) {
  std::string why;
  if (!mesh.valid(&why)) return Status(ErrorCode::invalid_argument, path + ": mesh to write is invalid: " + why);
  std::string bytes;
  MeshFormat format = format_from_extension(path);
  if (format == MeshFormat::ply) {
    TSM_RETURN_IF_ERROR(write_ply(mesh, options, bytes, info));
  } else if (format == MeshFormat::obj) {
    TSM_RETURN_IF_ERROR(write_obj(mesh, bytes, info));
  } else if (format == MeshFormat::stl || format == MeshFormat::off) {
    TSM_RETURN_IF_ERROR(format == MeshFormat::stl ? write_stl(mesh, options, bytes, info) : write_off(mesh, options, bytes, info));
  } else if (format == MeshFormat::gltf || format == MeshFormat::glb) {
    // glTF has no face attributes: OBJ groups ('obj:*') are left out, noted.
    Mesh without_labels;
    const Mesh* m = &mesh;
    for (const Attribute& a : mesh.attributes)
      if (m == &mesh && a.domain == AttributeDomain::face && a.name.compare(0, 4, "obj:") == 0) m = &without_labels;
    if (m == &without_labels) drop_obj_face_labels(without_labels = mesh, info);
    Status s = write_gltf(*m, options, bytes, format == MeshFormat::glb, info);
    if (!s.ok()) return Status(s.code(), path + ": " + s.message());
  } else {
    return Status(ErrorCode::invalid_argument,
                  path + ": cannot write this format; use a .ply, .obj, .stl, .off, .gltf or .glb file name");
  }
  return write_file_atomic(path, bytes);
}

}  // namespace tsm

// tsm: mesh file readers and writers (PLY, OBJ, STL, OFF in; PLY, OBJ out).
//
// Readers report bad input with the file name, the line (text formats) or
// byte offset (binary formats) and what is wrong. Writers never leave a
// partial file: they write a temporary beside the target and rename it.
#pragma once
#include <string>
#include <string_view>

#include "tsm/mesh.hpp"
#include "tsm/status.hpp"

namespace tsm {

enum class MeshFormat { unknown, ply, obj, stl, off };

const char* mesh_format_name(MeshFormat format);
// By file extension (case-insensitive): .ply .obj .stl .off.
MeshFormat format_from_extension(std::string_view path);
// By content: "ply\n", "OFF", binary STL size check, "solid", else OBJ-like
// text. Returns unknown when nothing fits.
MeshFormat sniff_format(std::string_view bytes);

struct ReadOptions {
  // NaN or infinite coordinates are refused unless this is set.
  bool allow_nonfinite = false;
  // STL stores triangles as corner positions; weld corners whose positions
  // are bit-identical into one vertex (the only sensible mesh).
  bool stl_weld = true;
  // Upper bounds a reader checks before it allocates (0 = no bound besides
  // what the file size can hold).
  size_t max_vertices = 0;
  size_t max_faces = 0;
};

struct ReadInfo {
  MeshFormat format = MeshFormat::unknown;
  bool binary = false;
  size_t skipped_elements = 0;    // lines, points and other non-face records
  std::string notes;              // warnings worth showing ("skipped 12 'l' lines")
};

// Reads a mesh; format from content first, extension second.
Status read_mesh(const std::string& path, Mesh& out, const ReadOptions& options = {},
                 ReadInfo* info = nullptr);
// Reads from bytes already in memory; `name` is used in messages only.
Status read_mesh_from_memory(std::string_view bytes, const std::string& name, Mesh& out,
                             const ReadOptions& options = {}, ReadInfo* info = nullptr,
                             MeshFormat format = MeshFormat::unknown);

// Format-specific entry points (bytes in memory; name for messages).
Status read_ply(std::string_view bytes, const std::string& name, Mesh& out,
                const ReadOptions& options, ReadInfo* info);
Status read_obj(std::string_view bytes, const std::string& name, Mesh& out,
                const ReadOptions& options, ReadInfo* info);
Status read_stl(std::string_view bytes, const std::string& name, Mesh& out,
                const ReadOptions& options, ReadInfo* info);
Status read_off(std::string_view bytes, const std::string& name, Mesh& out,
                const ReadOptions& options, ReadInfo* info);

struct WriteOptions {
  bool ascii = false;  // PLY only: binary little endian by default
};

// Writes by extension (.ply or .obj), atomically.
Status write_mesh(const std::string& path, const Mesh& mesh, const WriteOptions& options = {});
// Serializers (to memory).
Status write_ply(const Mesh& mesh, const WriteOptions& options, std::string& out);
Status write_obj(const Mesh& mesh, std::string& out);

// Whole-file helpers used by readers, writers and the CLI.
Status read_file(const std::string& path, std::string& out);
// Writes to path + ".tmp-XXXXXX" in the same folder, fsyncs, renames over
// path. On any failure the temporary is removed and path is untouched.
Status write_file_atomic(const std::string& path, std::string_view bytes);

}  // namespace tsm

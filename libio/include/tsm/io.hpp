// tsm: mesh file readers and writers (PLY, OBJ, STL, OFF, glTF in and out).
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

// gltf: JSON (.gltf), glb: binary glTF (.glb); one reader takes both.
enum class MeshFormat { unknown, ply, obj, stl, off, gltf, glb };

const char* mesh_format_name(MeshFormat format);
// By file extension (case-insensitive): .ply .obj .stl .off .gltf .glb.
MeshFormat format_from_extension(std::string_view path);
// By content: "glTF" (GLB magic), a JSON object with an "asset" member
// (.gltf), "ply\n", "OFF", binary STL size check, "solid". Returns unknown
// when nothing fits (OBJ has no signature).
MeshFormat sniff_format(std::string_view bytes);

struct WriteInfo;

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
  // glTF: the folder in which a .gltf file's external buffers ("uri":
  // "mesh.bin", relative names only, regular files only) are looked up.
  // Empty: external buffers are refused (data-URI and GLB buffers need no
  // files), so reading from memory never touches the file system unless
  // asked to. read_mesh sets it to the folder of the file it reads.
  std::string external_files_dir;
};

struct ReadInfo {
  MeshFormat format = MeshFormat::unknown;
  bool binary = false;
  size_t skipped_elements = 0;    // lines, points and other non-face records
  std::string notes;              // warnings worth showing ("skipped 12 'l' lines")
  // Appends to `notes`, "; " between notes (nothing when `note` is empty).
  void add_note(const std::string& note);
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
// OBJ: `v` (with optional r g b), `vt`, `vn`, `f` become positions, faces and
// attributes (see io_obj.cpp). Which object, group, material and smoothing
// group each face is in is kept: for each kind of record the file has (`o`,
// `g`, `usemtl`, `s`) a face-domain generic i32 attribute 'obj:object',
// 'obj:group', 'obj:material' or 'obj:smoothing' numbers, per face, an entry
// of the metadata entry "obj". That entry is text, one line per item:
//   mtllib TEXT      each `mtllib` record, in file order
//   object TEXT      entry 0, 1, ... of 'obj:object' (likewise group,
//   group TEXT       material, smoothing: the entries of each list in
//   material TEXT    order, numbered from 0 per list)
//   smoothing TEXT
// TEXT is what follows the keyword in the file (blanks around it and a
// trailing comment removed; a `g` with several names keeps them as one
// text). Faces before the first record of a kind get the empty text, as
// does a record with nothing after its keyword. A kind with a single text
// (one `usemtl` for the whole file, say) gets no attribute: its list alone
// says that every face has entry 0. write_obj writes them back.
Status read_obj(std::string_view bytes, const std::string& name, Mesh& out,
                const ReadOptions& options, ReadInfo* info);
// Removes the 'obj:*' face attributes (for writers without face attributes,
// glTF) and notes in `info` that they were left out; the "obj" entry stays.
// Returns whether there were any.
bool drop_obj_face_labels(Mesh& mesh, WriteInfo* info);
Status read_stl(std::string_view bytes, const std::string& name, Mesh& out,
                const ReadOptions& options, ReadInfo* info);
// OFF and its Geomview variants: vertex normals (N), colours (C) and texture
// coordinates (ST) become the vertex attributes 'normal', 'color' and
// 'texcoord'; face colours after a face's indices the face attribute
// 'color'. Colours written as integers (no '.' or exponent, 0..255) are u8,
// others f32 as written. See io_off.cpp.
Status read_off(std::string_view bytes, const std::string& name, Mesh& out,
                const ReadOptions& options, ReadInfo* info);
// glTF 2.0, .gltf or .glb (told apart by content): the triangles of the
// meshes of the default scene, concatenated, with their vertex attributes
// (NORMAL -> "normal", TEXCOORD_n -> "texcoord<n>", COLOR_0 -> "color",
// others under their glTF name); node transforms are not applied. The rest
// of the document (scenes, nodes, materials, textures, images, cameras,
// skins, animations, extensions, extras, meshes outside the scene) goes into
// Mesh::metadata "gltf", and which primitive each vertex and face came from
// into the integer attributes "_gltf_group" / "_gltf_primitive" (only when
// there are several), so that write_gltf gives the document back around the
// codec's geometry. See io_gltf.cpp.
Status read_gltf(std::string_view bytes, const std::string& name, Mesh& out,
                 const ReadOptions& options, ReadInfo* info);

struct WriteOptions {
  bool ascii = false;  // PLY and STL: binary (PLY little endian) by default
};

// What a writer left out because its format cannot hold it (attributes,
// metadata entries, unreferenced vertices...), for the caller to show: the
// tsm tool prints it on stderr. Empty when everything was written.
struct WriteInfo {
  std::string notes;
  // Appends to `notes`, "; " between notes (nothing when `note` is empty).
  void add_note(const std::string& note) {
    if (note.empty()) return;
    if (!notes.empty()) notes += "; ";
    notes += note;
  }
};

// The formats write_mesh writes, by extension, in the order tools list them.
struct WritableFormat {
  MeshFormat format;
  const char* extension;  // ".ply"
  const char* name;       // "ply", as --format takes it
};
inline constexpr WritableFormat kWritableFormats[] = {
    {MeshFormat::ply, ".ply", "ply"},   {MeshFormat::obj, ".obj", "obj"},   {MeshFormat::stl, ".stl", "stl"},
    {MeshFormat::off, ".off", "off"},   {MeshFormat::gltf, ".gltf", "gltf"}, {MeshFormat::glb, ".glb", "glb"}};

// Writes by extension (.ply, .obj, .stl, .off, .gltf or .glb), atomically.
Status write_mesh(const std::string& path, const Mesh& mesh, const WriteOptions& options = {},
                  WriteInfo* info = nullptr);
// Serializers (to memory). `info`, when given, receives what was not written.
Status write_ply(const Mesh& mesh, const WriteOptions& options, std::string& out, WriteInfo* info = nullptr);
// OBJ: positions, the first texcoord / normal attribute as `vt` / `vn`, a
// vertex colour as `v x y z r g b`, and the 'obj:*' face attributes with the
// "obj" metadata (see read_obj) as `mtllib`, `o`, `g`, `usemtl` and `s`
// records before the faces whose entry changes (faces in mesh order).
Status write_obj(const Mesh& mesh, std::string& out, WriteInfo* info = nullptr);
// STL: triangles only (polygons are split into fans from their first
// corner; faces of 1 or 2 corners are left out), binary unless
// options.ascii. The facet normals are computed from the positions. STL
// holds no attributes, metadata or unreferenced vertices: `info` says what
// was left out.
Status write_stl(const Mesh& mesh, const WriteOptions& options, std::string& out, WriteInfo* info = nullptr);
// OFF text: "OFF" with the prefixes ST, C, N for a vertex texcoord, colour
// and normal attribute ("COFF" for a coloured mesh); a face colour follows
// each face's indices. Positions, faces and those attributes read back
// bit-identically (u16 colours as f32 0..1); other attributes and metadata
// are noted in `info`.
Status write_off(const Mesh& mesh, const WriteOptions& options, std::string& out, WriteInfo* info = nullptr);
// glTF 2.0: binary (.glb) or JSON with the buffer as a data URI (.gltf).
// With a "gltf" metadata entry (from read_gltf), the document it holds with
// each primitive's geometry taken from the mesh (a damaged entry is
// corrupt_data, one that does not fit the mesh invalid_argument). Without
// one: one triangle primitive (a points primitive when there are no faces)
// with POSITION, NORMAL, TEXCOORD_n, COLOR_n (u8 / u16 colours as normalized
// unsigned byte / short) and other vertex attributes as "_name". Refuses
// (ErrorCode::unsupported) faces that are not triangles, face and corner
// attributes (glTF would need split vertices: write PLY or OBJ) and
// non-finite positions. `info` notes the image files the document names by
// relative URI, which the output needs beside it.
Status write_gltf(const Mesh& mesh, const WriteOptions& options, std::string& out, bool binary,
                  WriteInfo* info = nullptr);

// Whole-file helpers used by readers, writers and the CLI.
Status read_file(const std::string& path, std::string& out);
// Writes to path + ".tmp-XXXXXX" in the same folder, fsyncs, renames over
// path. On any failure the temporary is removed and path is untouched.
Status write_file_atomic(const std::string& path, std::string_view bytes);

}  // namespace tsm

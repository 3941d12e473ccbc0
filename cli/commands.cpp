// encode, decode and info for one file or many: output names, the rules that
// keep files safe (never the input, never an existing file without -f, never
// a partial file), stdin/stdout, and the per-file jobs run by run_batch.
#include "commands.hpp"
#include "mesh_commands.hpp"

#include <sys/stat.h>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <iterator>
#include <map>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "batch.hpp"
#include "cli_util.hpp"
#include "tsm/io.hpp"

namespace tsm::cli {

namespace {

namespace fs = std::filesystem;

int usage_error(const std::string& message) {
  std::fprintf(stderr, "tsm: error: %s\n", message.c_str());
  return kExitUsage;
}

// "-" as it appears in messages.
std::string shown_input(const std::string& p) { return p == "-" ? std::string("<stdin>") : p; }
std::string shown_output(const std::string& p) { return p == "-" ? std::string("<stdout>") : p; }

std::string with_extension(const std::string& path, const std::string& ext) {
  fs::path p(path);
  return p.replace_extension(ext).string();
}

std::string lower(std::string s) {
  for (char& c : s)
    if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
  return s;
}

unsigned effective_jobs(unsigned jobs) {
  if (jobs > 0) return jobs;
  unsigned cores = std::thread::hardware_concurrency();
  return cores > 0 ? cores : 1;
}

struct FileId {
  dev_t dev = 0;
  ino_t ino = 0;
  bool operator<(const FileId& o) const { return dev != o.dev ? dev < o.dev : ino < o.ino; }
};

bool file_id(const std::string& path, FileId& id) {
  struct stat st = {};
  if (::stat(path.c_str(), &st) != 0) return false;
  id.dev = st.st_dev;
  id.ino = st.st_ino;
  return true;
}

// Something (file, folder, even a dangling link) is at this path.
bool occupied(const std::string& path) {
  struct stat st = {};
  return ::lstat(path.c_str(), &st) == 0;
}

// One input file and where its result goes.
struct Job {
  std::string input;   // path or "-"
  std::string output;  // path or "-"
  Status refused;      // set when the file must not be processed (the reason)
};

// Why an input cannot be read at all (missing, a folder), or Ok. Such an
// input is one failure of the batch (exit code 4, like any file that cannot
// be read); the others are still processed. `pattern` is the kind of file
// the command reads, for the hint ("*.ply").
Status input_problem(const std::string& input, const char* pattern) {
  if (input == "-") return Status::Ok();
  struct stat st = {};
  if (::stat(input.c_str(), &st) != 0) {
    if (errno == ENOENT || errno == ENOTDIR)
      return Status(ErrorCode::io_error, input + ": no such file; check the name");
    return Status(ErrorCode::io_error, input + ": cannot open: " + std::strerror(errno));
  }
  if (S_ISDIR(st.st_mode))
    return Status(ErrorCode::io_error, input + ": is a folder, not a file; name the files in it (e.g. " +
                                           (fs::path(input) / pattern).string() + ")");
  return Status::Ok();
}

// An output name that says "a file" by its extension: a mesh format or .tsm.
bool file_like_name(const std::string& o) {
  return format_from_extension(o) != MeshFormat::unknown || lower(fs::path(o).extension().string()) == ".tsm";
}

// "-" may only be the only input, and stdin must not be a terminal.
int check_stdin_input(const std::vector<std::string>& inputs, const char* what) {
  const bool has_stdin = std::find(inputs.begin(), inputs.end(), "-") != inputs.end();
  if (!has_stdin) return kExitOk;
  if (inputs.size() > 1) return usage_error("'-' (stdin) can only be the only input; name the files instead");
  if (is_terminal(stdin))
    return usage_error(std::string("'-' reads ") + what +
                       " from stdin, but stdin is a terminal; pipe or redirect it (tsm ... - < FILE)");
  return kExitOk;
}

// Works out every output name and refuses what would lose data. Returns 0,
// or the exit code when the whole command is refused (message printed).
// Files that must not be written get Job::refused; the others still run.
int plan_outputs(const std::vector<std::string>& inputs, const std::string& o, const std::string& ext, bool force,
                 const char* what_in, const char* pattern, std::vector<Job>& jobs) {
  if (int rc = check_stdin_input(inputs, what_in)) return rc;
  const size_t n = inputs.size();
  const bool has_stdin = n == 1 && inputs[0] == "-";
  if (o == "-" && n > 1)
    return usage_error("-o - (stdout) takes a single input; for several files give a folder, e.g. -o out/");
  std::error_code ec;
  const bool dir_mode = !o.empty() && o != "-" && (n > 1 || o.back() == '/' || fs::is_directory(o, ec));
  if (dir_mode && occupied(o) && !fs::is_directory(o, ec))
    return usage_error(o + ": is a file, but with several inputs -o names a folder (created if missing), e.g. -o out/");
  // "-o both.obj" for several inputs would become a folder named like a file.
  if (n > 1 && !o.empty() && o.back() != '/' && !fs::is_directory(o, ec) && file_like_name(o))
    return usage_error("-o " + o + " names one file, but there are " + std::to_string(n) +
                       " inputs; give a folder for their outputs, e.g. -o " +
                       (fs::path(o).parent_path() / "out/").string());
  if (dir_mode && has_stdin)
    return usage_error("-o " + o + " is a folder, and stdin has no name to derive a file name from; give -o FILE or -o -");

  jobs.assign(n, Job());
  for (size_t i = 0; i < n; ++i) {
    Job& j = jobs[i];
    j.input = inputs[i];
    j.refused = input_problem(inputs[i], pattern);
    if (inputs[i] == "-")
      j.output = o.empty() ? "-" : o;
    else if (o.empty())
      j.output = with_extension(inputs[i], ext);
    else if (dir_mode)
      j.output = (fs::path(o) / fs::path(inputs[i]).filename().replace_extension(ext)).string();
    else
      j.output = o;
  }

  // Two inputs must not write the same file (a.ply and a.obj, or x/a.ply and y/a.ply, into one folder).
  std::map<std::string, size_t> claimed;
  std::vector<std::string> clashes;
  for (size_t i = 0; i < n; ++i) {
    if (jobs[i].output == "-" || !jobs[i].refused.ok()) continue;
    fs::path key = fs::weakly_canonical(fs::absolute(jobs[i].output, ec), ec);
    if (ec) key = fs::path(jobs[i].output).lexically_normal();
    auto [it, fresh] = claimed.emplace(key.string(), i);
    if (!fresh)
      clashes.push_back(inputs[it->second] + " and " + inputs[i] + " would both be written to " + jobs[i].output);
  }
  if (!clashes.empty()) {
    for (const std::string& c : clashes) std::fprintf(stderr, "tsm: error: %s\n", c.c_str());
    std::fprintf(stderr, "tsm: give them separate -o folders or rename one; nothing was written\n");
    return kExitUsage;
  }

  if (dir_mode && !fs::is_directory(o, ec)) {
    fs::create_directories(o, ec);
    if (ec) {
      std::fprintf(stderr, "tsm: error: %s: cannot create the output folder: %s\n", o.c_str(), ec.message().c_str());
      return kExitIo;
    }
  }

  // Never an input (any input of the batch), never an existing file without -f.
  std::map<FileId, size_t> input_ids;
  for (size_t i = 0; i < n; ++i) {
    FileId id;
    if (inputs[i] != "-" && file_id(inputs[i], id)) input_ids.emplace(id, i);
  }
  for (size_t i = 0; i < n; ++i) {
    Job& j = jobs[i];
    if (j.output == "-" || !j.refused.ok()) continue;
    FileId id;
    auto it = file_id(j.output, id) ? input_ids.find(id) : input_ids.end();
    if (it != input_ids.end()) {
      j.refused = Status(ErrorCode::invalid_argument,
                         it->second == i ? j.output + ": the output would overwrite the input; choose another -o"
                                         : j.output + ": the output would overwrite " + inputs[it->second] +
                                               ", an input of this run; choose another -o");
    } else if (!force && occupied(j.output)) {
      j.refused = Status(ErrorCode::invalid_argument, j.output + ": already exists; pass -f (--force) to overwrite it");
    }
  }

  // -o a/b/c.tsm: the folders of a single output are created, as -o a/b/ creates its folder.
  if (!dir_mode && n == 1 && jobs[0].output != "-" && jobs[0].refused.ok()) {
    const fs::path parent = fs::path(jobs[0].output).parent_path();
    if (!parent.empty() && !fs::is_directory(parent, ec)) {
      fs::create_directories(parent, ec);
      if (ec) {
        std::fprintf(stderr, "tsm: error: %s: cannot create the output's folder %s: %s\n", jobs[0].output.c_str(),
                     parent.string().c_str(), ec.message().c_str());
        return kExitIo;
      }
    }
  }
  return kExitOk;
}

// Writes a result: stdout, or atomically to the file (checked again: the
// file may have appeared while the job ran).
Status write_output(const std::string& output, std::string_view bytes, bool force) {
  if (output == "-") return write_stdout(bytes);
  if (!force && occupied(output))
    return Status(ErrorCode::invalid_argument,
                  output + ": already exists (it appeared while tsm was working); pass -f (--force) to overwrite it");
  return guarded_write_file(output, bytes);
}

Status read_input(const std::string& input, std::string& bytes) {
  return input == "-" ? read_stdin(bytes) : read_file(input, bytes);
}

MeshFormat parse_format(const std::string& s) {
  if (s == "ply") return MeshFormat::ply;
  if (s == "obj") return MeshFormat::obj;
  if (s == "stl") return MeshFormat::stl;
  if (s == "off") return MeshFormat::off;
  if (s == "gltf") return MeshFormat::gltf;
  if (s == "glb") return MeshFormat::glb;
  return MeshFormat::unknown;
}

// A mesh from bytes: the format the user named, else content, else extension.
Status parse_mesh_as(std::string_view bytes, const std::string& input, MeshFormat forced, Mesh& mesh,
                     const ReadOptions& read_options, ReadInfo& info) {
  const std::string name = shown_input(input);
  ReadOptions ro = read_options;  // a .gltf file's buffers may be files beside it
  if (input != "-" && ro.external_files_dir.empty()) {
    const std::string dir = fs::path(input).parent_path().string();
    ro.external_files_dir = dir.empty() ? "." : dir;
  }
  if (forced == MeshFormat::unknown) {
    if (input == "-" && bytes.empty())
      return Status(ErrorCode::parse_error, name + ": no data (stdin was empty)");
    if (input == "-" && sniff_format(bytes) == MeshFormat::unknown)
      return Status(ErrorCode::parse_error, name + ": cannot tell the mesh format from the content (OBJ has no "
                                                   "signature); pass --input-format ply|obj|stl|off");
    return read_mesh_from_memory(bytes, name, mesh, ro, &info, format_from_extension(input));
  }
  info = ReadInfo();
  info.format = forced;
  mesh.clear();
  switch (forced) {
    case MeshFormat::ply: return read_ply(bytes, name, mesh, ro, &info);
    case MeshFormat::obj: return read_obj(bytes, name, mesh, ro, &info);
    case MeshFormat::stl: return read_stl(bytes, name, mesh, ro, &info);
    case MeshFormat::off: return read_off(bytes, name, mesh, ro, &info);
    case MeshFormat::gltf:
    case MeshFormat::glb: return read_gltf(bytes, name, mesh, ro, &info);
    case MeshFormat::unknown: break;
  }
  return Status(ErrorCode::internal, name + ": no reader for the format");
}

// parse_mesh_as, with the library's advice replaced where the command line
// offers another remedy.
Status parse_mesh(std::string_view bytes, const std::string& input, MeshFormat forced, Mesh& mesh,
                  const ReadOptions& read_options, ReadInfo& info) {
  Status s = parse_mesh_as(bytes, input, forced, mesh, read_options, info);
  if (s.ok()) return s;
  std::string m = s.message();
  // A .gltf on stdin has no folder in which to find its buffer files.
  const size_t ext = m.find("external files are not read here");
  if (input == "-" && ext != std::string::npos)
    return Status(s.code(), m.substr(0, ext) +
                                "a .gltf read from stdin cannot name buffer files: give the .gltf file's path instead "
                                "of - (its buffers are then read from its folder), or embed the buffers (a .glb, or "
                                "data: URIs)");
  // The readers offer --allow-nonfinite for NaN / infinite values, but only
  // a lossless file keeps them: say what works.
  const size_t flag = m.find("--allow-nonfinite");
  if (flag != std::string::npos) {
    const size_t from = m.rfind("; ", flag);
    const size_t to = m.find("; ", flag);
    if (from != std::string::npos)
      return Status(s.code(), m.substr(0, from) +
                                  "; only a lossless file keeps NaN or infinite coordinates: encode with "
                                  "--lossless --allow-nonfinite, or fix or drop them in the file" +
                                  (to == std::string::npos ? std::string() : m.substr(to)));
  }
  return s;
}

// Words that begin an OBJ line (statements of the OBJ specification).
bool obj_statement(std::string_view w) {
  static const char* const kWords[] = {"v",     "vt",   "vn",      "vp",      "f",        "fo",       "l",
                                       "p",     "o",    "g",       "s",       "mg",       "mtllib",   "usemtl",
                                       "cstype", "deg", "bmat",    "step",    "curv",     "curv2",    "surf",
                                       "parm",  "trim", "hole",    "scrv",    "sp",       "end",      "con",
                                       "lod",   "usemap", "maplib", "shadow_obj", "trace_obj", "ctech", "stech",
                                       "bevel", "c_interp", "d_interp", "call", "csh"};
  for (const char* k : kWords)
    if (w == k) return true;
  return false;
}

// Bytes that no mesh text file holds (NUL and the other C0 controls but
// tab, line feed, vertical tab, form feed and carriage return; DEL): the
// offset of the first, or npos.
size_t binary_offset(std::string_view bytes) {
  for (size_t i = 0; i < bytes.size(); ++i) {
    const auto c = static_cast<unsigned char>(bytes[i]);
    if ((c < 0x20 && c != '\t' && c != '\n' && c != '\v' && c != '\f' && c != '\r') || c == 0x7F) return i;
  }
  return std::string_view::npos;
}

// A mesh read with no vertex and no face is either an empty mesh (Ok; the
// note says so) or a file that is not a mesh: text read as OBJ (which has no
// signature: anything "reads") that holds binary bytes or lines that are no
// OBJ statement (bad input: what was found, with bytes escaped).
Status check_empty_mesh(std::string_view bytes, const std::string& input, MeshFormat forced, const ReadInfo& info,
                        std::string& note) {
  const std::string name = shown_input(input);
  if (info.format != MeshFormat::obj) {
    note = name + ": empty mesh (no vertex, no face); the .tsm holds an empty mesh";
    return Status::Ok();
  }
  const std::string why_obj = forced == MeshFormat::obj ? "as --input-format obj says"
                              : format_from_extension(input) == MeshFormat::obj
                                  ? "as its .obj name says"
                                  : "OBJ being the only format without a signature";
  const MeshFormat looks = sniff_format(bytes);
  const std::string looks_like =
      forced == MeshFormat::obj && looks != MeshFormat::unknown && looks != MeshFormat::obj
          ? std::string("; the content looks like ") + mesh_format_name(looks) + ": drop --input-format obj"
          : std::string("; give a mesh file (PLY, OBJ, STL, OFF, glTF/GLB)");
  const size_t bin = binary_offset(bytes);
  if (bin != std::string_view::npos) {
    return Status(ErrorCode::parse_error,
                  name + ": not a mesh: read as OBJ text (" + why_obj + "), but it holds binary data (byte " +
                      std::to_string(bin) + " is " + strf("0x%02X", static_cast<unsigned char>(bytes[bin])) +
                      "; it starts with \"" + printable(std::string(bytes.substr(0, 16))) + "\")" + looks_like);
  }
  size_t line = 0;
  for (size_t at = 0; at < bytes.size();) {
    size_t end = bytes.find('\n', at);
    if (end == std::string_view::npos) end = bytes.size();
    ++line;
    std::string_view text = bytes.substr(at, end - at);
    at = end + 1;
    const size_t b = text.find_first_not_of(" \t\r\v\f");
    if (b == std::string_view::npos || text[b] == '#') continue;
    const size_t e = text.find_first_of(" \t\r\v\f", b);
    const std::string_view word = text.substr(b, e == std::string_view::npos ? std::string_view::npos : e - b);
    if (obj_statement(word)) continue;
    std::string shown = printable(std::string(text.substr(b, 60)));
    if (text.size() - b > 60) shown += "...";
    return Status(ErrorCode::parse_error,
                  name + ": not a mesh: read as OBJ (" + why_obj + "), no vertex and no face found, and line " +
                      std::to_string(line) + " (\"" + shown + "\") is not an OBJ statement" + looks_like);
  }
  note = name + ": empty mesh: no vertex and no face in the OBJ" +
         (bytes.empty() ? std::string(" (the file is empty)") : std::string()) + "; the .tsm holds an empty mesh";
  return Status::Ok();
}

// Compression ratio, input bytes to output bytes: "8.31:1", "12.4:1".
std::string ratio_text(uint64_t in, uint64_t out) {
  if (out == 0 || in == 0) return "-";
  const double r = static_cast<double>(in) / static_cast<double>(out);
  return fixed(r, r < 10 ? 2 : 1) + ":1";
}

double bits_per_vertex(uint64_t bytes, uint64_t vertices) {
  return vertices ? 8.0 * static_cast<double>(bytes) / static_cast<double>(vertices) : 0.0;
}

// Fields every per-file JSON object starts with.
JsonObject json_head(const Job& j, const Status& s) {
  JsonObject o;
  o.str("input", j.input).str("output", j.output).str("status", s.ok() ? "ok" : "error");
  o.num("exit_code", static_cast<unsigned long long>(exit_code_for(s)));
  o.str_or_null("error", s.message());
  return o;
}

// ---------------------------------------------------------------- encode

FileResult encode_one(const EncodeArgs& a, const Job& j, MeshFormat forced, Phase& phase) {
  Stopwatch total;
  uint64_t bytes_in = 0, bytes_out = 0;
  double read_ms = 0, encode_ms = 0, write_ms = 0;
  Mesh mesh;
  ReadInfo info;
  FileResult r;
  auto finish = [&](const Status& s) {
    r.status = s;
    JsonObject o = json_head(j, s);
    o.str("input_format", info.format == MeshFormat::unknown ? std::string() : lower(mesh_format_name(info.format)));
    o.num("bytes_in", static_cast<unsigned long long>(bytes_in)).num("bytes_out", static_cast<unsigned long long>(bytes_out));
    o.num("vertices", static_cast<unsigned long long>(mesh.vertex_count()));
    o.num("faces", static_cast<unsigned long long>(mesh.face_count()));
    o.num("bits_per_vertex", bits_per_vertex(bytes_out, mesh.vertex_count()), 4);
    o.num("compression_ratio", bytes_out ? static_cast<double>(bytes_in) / static_cast<double>(bytes_out) : 0.0, 3);
    o.num("quantization_bits", static_cast<unsigned long long>(a.qbits)).num("level", static_cast<unsigned long long>(a.level));
    o.num("read_ms", read_ms, 1).num("encode_ms", encode_ms, 1).num("write_ms", write_ms, 1).num("ms", total.ms(), 1);
    r.json = o.done();
    return r;
  };
  if (!j.refused.ok()) return finish(j.refused);

  phase.set("reading");
  Stopwatch sw;
  std::string in_bytes;
  Status s = read_input(j.input, in_bytes);
  if (!s.ok()) return finish(s);
  bytes_in = in_bytes.size();
  ReadOptions ro;
  ro.allow_nonfinite = a.allow_nonfinite;
  s = parse_mesh(in_bytes, j.input, forced, mesh, ro, info);
  if (!s.ok()) return finish(s);
  std::string empty_note;
  if (mesh.vertex_count() == 0 && mesh.face_count() == 0) {
    s = check_empty_mesh(in_bytes, j.input, forced, info, empty_note);
    if (!s.ok()) return finish(s);
  }
  std::string().swap(in_bytes);
  read_ms = sw.ms();

  if (!a.max_error.empty()) {
    phase.set("simplifying");
    Mesh small;
    SimplifyReport sr;
    double units = 0;
    // Quantization then moves each vertex by at most half a step per axis,
    // so every point of a triangle by at most sqrt(3)/2 steps: the
    // simplifier gets the bound less that.
    const double step = bounding_box(mesh).largest_extent() / (std::ldexp(1.0, a.qbits) - 1);
    s = simplify_for_cli(mesh, a.max_error, 0, 0, false, small, sr, units, step * std::sqrt(3.0) / 2);
    if (!s.ok()) return finish(Status(s.code(), shown_input(j.input) + ": " + s.message()));
    mesh = std::move(small);
  }

  if (a.drop_attributes) {
    // A glTF document kept for the way back (metadata "gltf") names the
    // attributes it had: without them it cannot be rebuilt, so it goes too
    // and the decoded mesh is written as a plain mesh in any format.
    mesh.attributes.clear();
    mesh.metadata.erase(std::remove_if(mesh.metadata.begin(), mesh.metadata.end(),
                                       [](const MetadataEntry& e) { return e.key == "gltf"; }),
                        mesh.metadata.end());
  }
  phase.set("encoding");
  sw.reset();
  EncodeOptions eo;
  eo.quantization_bits = a.qbits;
  eo.level = a.level;
  eo.segment_faces = a.segment_faces;
  eo.attribute_bits = a.attribute_bits;
  eo.progressive = a.progressive;
  eo.keep_order = a.keep_order;
  eo.lossless = a.lossless;
  eo.allow_nonfinite = a.allow_nonfinite;
  // One file: its segments use the -j threads; several: the files do.
  eo.threads = a.inputs.size() == 1 ? static_cast<int>(a.jobs) : 1;
  std::string bytes;
  s = encode(mesh, eo, bytes);
  if (!s.ok()) return finish(Status(s.code(), shown_input(j.input) + ": " + s.message()));
  encode_ms = sw.ms();

  phase.set("writing");
  sw.reset();
  s = write_output(j.output, bytes, a.force);
  if (!s.ok()) return finish(s);
  write_ms = sw.ms();
  bytes_out = bytes.size();

  if (!info.notes.empty()) r.note = shown_input(j.input) + ": " + info.notes;
  if (!empty_note.empty()) r.note += (r.note.empty() ? "" : "; ") + empty_note;
  r.text = strf("%s: %s, %s -> %s: %s (ratio %s), %s bits/vertex (%s, level %d), read %s ms, encode %s ms",
                shown_input(j.input).c_str(), count_of(mesh.vertex_count(), "vertex", "vertices").c_str(),
                count_of(mesh.face_count(), "face", "faces").c_str(), shown_output(j.output).c_str(),
                count_of(bytes.size(), "byte", "bytes").c_str(), ratio_text(bytes_in, bytes.size()).c_str(),
                fixed(bits_per_vertex(bytes.size(), mesh.vertex_count()), 2).c_str(),
                a.lossless ? "lossless" : ("q=" + std::to_string(a.qbits)).c_str(), a.level,
                fixed(read_ms, 1).c_str(), fixed(encode_ms, 1).c_str());
  return finish(Status::Ok());
}

// ---------------------------------------------------------------- decode

FileResult decode_one(const DecodeArgs& a, const Job& j, MeshFormat format, Phase& phase) {
  Stopwatch total;
  uint64_t bytes_in = 0, bytes_out = 0;
  double read_ms = 0, decode_ms = 0, write_ms = 0;
  Mesh mesh;
  FileResult r;
  auto finish = [&](const Status& s) {
    r.status = s;
    JsonObject o = json_head(j, s);
    o.str("output_format", lower(mesh_format_name(format)));
    o.num("bytes_in", static_cast<unsigned long long>(bytes_in)).num("bytes_out", static_cast<unsigned long long>(bytes_out));
    o.num("vertices", static_cast<unsigned long long>(mesh.vertex_count()));
    o.num("faces", static_cast<unsigned long long>(mesh.face_count()));
    o.num("bits_per_vertex", bits_per_vertex(bytes_in, mesh.vertex_count()), 4);
    o.num("read_ms", read_ms, 1).num("decode_ms", decode_ms, 1).num("write_ms", write_ms, 1).num("ms", total.ms(), 1);
    r.json = o.done();
    return r;
  };
  if (!j.refused.ok()) return finish(j.refused);

  DecodeOptions d;
  d.max_vertices = a.max_vertices;
  d.max_faces = a.max_faces;
  d.max_corners = a.max_corners;
  d.threads = a.inputs.size() == 1 ? static_cast<int>(a.jobs) : 1;
  Stopwatch sw;
  Status s;
  if (j.input == "-") {
    // From a pipe: decode each segment as its bytes arrive (the time of
    // reading and decoding overlaps; it is all counted as decoding).
    phase.set("decoding");
    StreamDecoder sd(d);
    char buf[1 << 16];
    size_t n;
    while (s.ok() && (n = std::fread(buf, 1, sizeof buf, stdin)) > 0) {
      bytes_in += n;
      s = sd.feed(std::string_view(buf, n));
    }
    if (s.ok() && std::ferror(stdin))
      return finish(Status(ErrorCode::io_error, std::string("<stdin>: read failed: ") + std::strerror(errno)));
    if (s.ok()) s = sd.finish();
    if (!s.ok()) return finish(Status(s.code(), shown_input(j.input) + ": " + s.message()));
    mesh = sd.take_mesh();
    decode_ms = sw.ms();
  } else {
    phase.set("reading");
    std::string bytes;
    s = read_input(j.input, bytes);
    if (!s.ok()) return finish(s);
    bytes_in = bytes.size();
    read_ms = sw.ms();
    phase.set("decoding");
    sw.reset();
    if (a.partial || a.max_bytes || a.stop_error >= 0) {
      PartialOptions po;
      po.max_bytes = a.max_bytes;
      po.max_error = a.stop_error;
      s = decode_partial(bytes, mesh, po, nullptr, d);
    } else {
      s = decode(bytes, mesh, d);
    }
    if (!s.ok()) return finish(Status(s.code(), shown_input(j.input) + ": " + s.message()));
    decode_ms = sw.ms();
  }

  phase.set("writing");
  sw.reset();
  std::string why;
  if (!mesh.valid(&why))
    return finish(Status(ErrorCode::internal, shown_input(j.input) + ": decoded mesh is invalid: " + why));
  std::string out;
  WriteOptions wo;
  wo.ascii = a.ascii;
  WriteInfo wi;
  if (format == MeshFormat::obj) {
    s = write_obj(mesh, out, &wi);
  } else if (format == MeshFormat::stl) {
    s = write_stl(mesh, wo, out, &wi);
  } else if (format == MeshFormat::off) {
    s = write_off(mesh, wo, out, &wi);
  } else if (format == MeshFormat::gltf || format == MeshFormat::glb) {
    // glTF has no face attributes: the OBJ groups and materials per face
    // ('obj:*', from an OBJ input) would make the writer refuse the mesh.
    drop_obj_face_labels(mesh, &wi);
    s = write_gltf(mesh, WriteOptions(), out, format == MeshFormat::glb, &wi);
  } else {
    s = write_ply(mesh, wo, out, &wi);
  }
  if (!s.ok()) return finish(Status(s.code(), shown_output(j.output) + ": " + s.message()));
  if (!wi.notes.empty()) r.note = shown_output(j.output) + ": " + wi.notes;
  s = write_output(j.output, out, a.force);
  if (!s.ok()) return finish(s);
  write_ms = sw.ms();
  bytes_out = out.size();

  r.text = strf("%s: %s -> %s: %s, %s, decode %s ms", shown_input(j.input).c_str(),
                count_of(bytes_in, "byte", "bytes").c_str(), shown_output(j.output).c_str(),
                count_of(mesh.vertex_count(), "vertex", "vertices").c_str(),
                count_of(mesh.face_count(), "face", "faces").c_str(), fixed(decode_ms, 1).c_str());
  return finish(Status::Ok());
}

// ---------------------------------------------------------------- info

// What `tsm info` says about one attribute: the file's description of it
// (FileInfo::attributes) and, from the decoded mesh, how many values it has.
struct AttributeSummary {
  const char* kind;
  const char* domain;
  const char* type;
  std::string coding;  // "exact", "grid, 12 bits", "octahedral, 10 bits" (+ ", tables")
};

AttributeSummary summarize(const AttributeInfo& a) {
  static const char* const kKinds[4] = {"generic", "normal", "color", "texcoord"};
  static const char* const kDomains[3] = {"vertex", "face", "corner"};
  static const char* const kTypes[4] = {"f32", "u8", "u16", "i32"};
  AttributeSummary s;
  s.kind = kKinds[static_cast<size_t>(a.kind) % 4];
  s.domain = kDomains[static_cast<size_t>(a.domain) % 3];
  s.type = kTypes[static_cast<size_t>(a.type) % 4];
  s.coding = a.coding;
  if (a.bits > 0) s.coding += strf(", %d bits", a.bits);
  if (a.tables) s.coding += ", tables";
  return s;
}

FileResult info_one(const std::string& input) {
  FileResult r;
  const std::string name = shown_input(input);
  auto failed = [&](const Status& s) {
    r.status = s;
    JsonObject o;
    o.str("file", input).str("status", "error");
    o.num("exit_code", static_cast<unsigned long long>(exit_code_for(s))).str("error", s.message());
    r.json = o.done();
    return r;
  };
  std::string bytes;
  Status s = read_input(input, bytes);
  if (!s.ok()) return failed(s);
  FileInfo fi;
  s = inspect(bytes, fi);
  if (!s.ok()) return failed(Status(s.code(), name + ": " + s.message()));

  // The number of values of each attribute and the metadata entries come
  // from the decoded mesh.
  Mesh mesh;
  DecodeOptions dopt;
  dopt.threads = 1;
  s = decode(bytes, mesh, dopt);
  if (!s.ok()) return failed(Status(s.code(), name + ": " + s.message()));

  const double v = fi.vertex_count ? static_cast<double>(fi.vertex_count) : 1.0;
  auto per_vertex = [v](uint64_t n) { return 8.0 * static_cast<double>(n) / v; };
  const double bpv = per_vertex(fi.file_bytes);
  // Header, framing, references, metadata and the attribute streams' headers and tables.
  uint64_t attribute_values = 0;
  for (const AttributeInfo& a : fi.attributes) attribute_values += a.coded_bytes;
  attribute_values = std::min(attribute_values, fi.attribute_bytes);
  const uint64_t side = fi.file_bytes - fi.connectivity_bytes - fi.geometry_bytes - attribute_values;
  using ull = unsigned long long;
  r.json = strf("{\"file\": \"%s\", \"status\": \"ok\", \"format_version\": %u, \"bytes\": %llu, \"vertices\": %llu, "
                "\"faces\": %llu, \"corners\": %llu, \"quantization_bits\": %d, \"lossless\": %s, \"keep_order\": %s, "
                "\"level\": %d, \"segments\": %u, "
                "\"bbox_min\": [%.9g, %.9g, %.9g], \"step\": %.9g, \"bits_per_vertex\": %.4f, "
                "\"connectivity_bits_per_vertex\": %.4f, \"geometry_bits_per_vertex\": %.4f, "
                "\"attribute_bits_per_vertex\": %.4f, \"side_bits_per_vertex\": %.4f, \"components\": %llu, \"vertex_runs\": %llu, "
                "\"triangle_runs\": %llu, \"marching_bits\": %llu, \"jump_edges\": %llu, \"stitches\": %llu, "
                "\"virtual_vertices\": %llu, \"side_faces\": %llu, \"run_table_parts\": %llu, \"table_coded_attributes\": %llu, \"geometry_predictor\": \"%s\", "
                "\"ancestors\": %d, \"lattice_planes\": [%u, %u, %u], \"sections\": [",
                json_escape(input).c_str(), fi.format_version, static_cast<ull>(fi.file_bytes),
                static_cast<ull>(fi.vertex_count), static_cast<ull>(fi.face_count), static_cast<ull>(fi.corner_count),
                fi.quantization_bits, fi.lossless ? "true" : "false", fi.keep_order ? "true" : "false", fi.level,
                fi.segment_count, fi.bbox_min[0], fi.bbox_min[1], fi.bbox_min[2],
                fi.step, bpv, per_vertex(fi.connectivity_bytes), per_vertex(fi.geometry_bytes), per_vertex(attribute_values),
                per_vertex(side),
                static_cast<ull>(fi.components), static_cast<ull>(fi.vertex_runs), static_cast<ull>(fi.triangle_runs),
                static_cast<ull>(fi.marching_bits), static_cast<ull>(fi.jump_edges), static_cast<ull>(fi.stitches),
                static_cast<ull>(fi.virtual_vertices), static_cast<ull>(fi.side_faces), static_cast<ull>(fi.run_table_parts),
                static_cast<ull>(fi.table_coded_attributes), json_escape(fi.geometry_predictor).c_str(), fi.ancestors, fi.lattice_planes[0], fi.lattice_planes[1],
                fi.lattice_planes[2]);
  for (size_t i = 0; i < fi.sections.size(); ++i) {
    const SectionInfo& si = fi.sections[i];
    r.json += strf("%s{\"id\": %u, \"name\": \"%s\", \"codec\": \"%s\", \"stored_bytes\": %llu, \"raw_bytes\": %llu}",
                   i ? ", " : "", si.id, json_escape(si.name).c_str(), json_escape(si.codec).c_str(),
                   static_cast<ull>(si.stored_bytes), static_cast<ull>(si.raw_bytes));
  }
  r.json += "], \"attributes\": [";
  for (size_t k = 0; k < fi.attributes.size(); ++k) {
    const AttributeInfo& a = fi.attributes[k];
    const AttributeSummary as = summarize(a);
    const uint64_t values = k < mesh.attributes.size() ? mesh.attributes[k].value_count() : 0;
    r.json += strf("%s{\"name\": \"%s\", \"kind\": \"%s\", \"domain\": \"%s\", \"type\": \"%s\", "
                   "\"components\": %u, \"values\": %llu, \"coding\": \"%s\", \"bits\": %d, \"tables\": %s, "
                   "\"bytes\": %llu, \"bits_per_vertex\": %.4f}",
                   k ? ", " : "", json_escape(a.name).c_str(), as.kind, as.domain, as.type, a.components,
                   static_cast<ull>(values), a.coding.c_str(), a.bits, a.tables ? "true" : "false",
                   static_cast<ull>(a.coded_bytes), per_vertex(a.coded_bytes));
  }
  if (!fi.batches.empty()) {
    r.json += strf("], \"progressive\": {\"base_vertices\": %llu, \"base_faces\": %llu, \"base_error\": %.9g, "
                   "\"loose_vertices\": %llu, \"loose_faces\": %llu, \"batches\": [",
                   static_cast<ull>(fi.vertex_count), static_cast<ull>(fi.face_count), fi.base_error,
                   static_cast<ull>(fi.loose_vertices), static_cast<ull>(fi.loose_faces));
    for (size_t k = 0; k < fi.batches.size(); ++k) {
      const FileInfo::Batch& b = fi.batches[k];
      r.json += strf("%s{\"bytes\": %llu, \"vertices\": %llu, \"faces\": %llu, \"error\": %.9g}", k ? ", " : "",
                     static_cast<ull>(b.bytes), static_cast<ull>(b.vertices), static_cast<ull>(b.faces), b.error);
    }
    r.json += "]}, \"metadata\": [";
  } else {
    r.json += "], \"metadata\": [";
  }
  for (size_t k = 0; k < mesh.metadata.size(); ++k)
    r.json += strf("%s{\"key\": \"%s\", \"bytes\": %llu}", k ? ", " : "",
                   json_escape(mesh.metadata[k].key).c_str(), static_cast<ull>(mesh.metadata[k].value.size()));
  r.json += "]}";

  std::string& t = r.text;
  t = strf("%s: tsm format version %u, %s bytes\n", name.c_str(), fi.format_version, thousands(fi.file_bytes).c_str());
  t += strf("  vertices %s, faces %s, corners %s, segments %u\n", thousands(fi.vertex_count).c_str(),
            thousands(fi.face_count).c_str(), thousands(fi.corner_count).c_str(), fi.segment_count);
  if (fi.welded_points)
    t += strf("  welded: %s points (positions and connectivity coded on them)\n", thousands(fi.welded_points).c_str());
  if (fi.lossless)
    t += strf("  lossless: every float32 coordinate exact (grid step %.6g, %d bits; the rest as exceptions), level %d\n",
              fi.step, fi.quantization_bits, fi.level);
  else
    t += strf("  quantization %d bits (step %.6g), level %d\n", fi.quantization_bits, fi.step, fi.level);
  if (fi.keep_order) t += "  keep-order: decodes in the input's vertex order, face order and first corners\n";
  if (fi.attributes.empty())
    t += strf("  bits/vertex: %.3f total = %.3f connectivity + %.3f geometry + %.3f header and side data\n", bpv,
              per_vertex(fi.connectivity_bytes), per_vertex(fi.geometry_bytes), per_vertex(side));
  else
    t += strf("  bits/vertex: %.3f total = %.3f connectivity + %.3f geometry + %.3f attributes + %.3f header and "
              "side data\n",
              bpv, per_vertex(fi.connectivity_bytes), per_vertex(fi.geometry_bytes), per_vertex(attribute_values),
              per_vertex(side));
  t += strf("  topology: %s components, %s vertex runs, %s triangle runs, %s marching bits, %s jump edges,\n"
            "            %s stitches, %s virtual vertices, %s side faces\n",
            thousands(fi.components).c_str(), thousands(fi.vertex_runs).c_str(), thousands(fi.triangle_runs).c_str(),
            thousands(fi.marching_bits).c_str(), thousands(fi.jump_edges).c_str(), thousands(fi.stitches).c_str(),
            thousands(fi.virtual_vertices).c_str(), thousands(fi.side_faces).c_str());
  if (fi.run_table_parts || fi.table_coded_attributes)
    t += strf("  tables: run values in %s of %s parts, residuals of %s attributes (summed over the parts)\n",
              thousands(fi.run_table_parts).c_str(), thousands(fi.segments.size()).c_str(),
              thousands(fi.table_coded_attributes).c_str());
  t += strf("  geometry: %s predictor", fi.geometry_predictor.c_str());
  if (fi.ancestors) t += strf(" (K = %d)", fi.ancestors);
  if (fi.lattice_planes[0] + fi.lattice_planes[1] + fi.lattice_planes[2])
    t += strf(", lattice planes x %s, y %s, z %s", thousands(fi.lattice_planes[0]).c_str(),
              thousands(fi.lattice_planes[1]).c_str(), thousands(fi.lattice_planes[2]).c_str());
  t += "\n";
  if (!fi.attributes.empty()) {
    // Names are the file's own: keep each on one line.
    auto one_line = [](std::string n) {
      for (char& c : n)
        if (static_cast<unsigned char>(c) < 0x20) c = ' ';
      return n;
    };
    size_t width = 9;
    for (const AttributeInfo& a : fi.attributes) width = std::max(width, std::min<size_t>(one_line(a.name).size(), 40));
    t += strf("  %-*s %-8s %-6s %-6s %12s %12s %8s  %s\n", static_cast<int>(width), "attribute", "kind", "domain",
              "type", "values", "bytes", "bits/v", "coded as");
    for (size_t k = 0; k < fi.attributes.size(); ++k) {
      const AttributeInfo& a = fi.attributes[k];
      const AttributeSummary as = summarize(a);
      const uint64_t values = k < mesh.attributes.size() ? mesh.attributes[k].value_count() : 0;
      t += strf("  %-*s %-8s %-6s %-6s %12s %12s %8.3f  %s\n", static_cast<int>(width), one_line(a.name).c_str(),
                as.kind, as.domain, strf("%sx%u", as.type, a.components).c_str(), thousands(values).c_str(),
                thousands(a.coded_bytes).c_str(), per_vertex(a.coded_bytes), as.coding.c_str());
    }
  }
  if (!mesh.metadata.empty()) {
    t += "  metadata:";
    for (size_t k = 0; k < mesh.metadata.size(); ++k) {
      std::string key = mesh.metadata[k].key;
      for (char& c : key)
        if (static_cast<unsigned char>(c) < 0x20) c = ' ';
      t += strf("%s '%s' (%s bytes)", k ? "," : "", key.c_str(), thousands(mesh.metadata[k].value.size()).c_str());
    }
    t += "\n";
  }
  if (!fi.batches.empty()) {
    t += strf("  progressive: base %s vertices, %s faces, error %.6g; %zu refinement batches:\n",
              thousands(fi.vertex_count).c_str(), thousands(fi.face_count).c_str(), fi.base_error, fi.batches.size());
    t += strf("  %8s %12s %12s %12s %12s\n", "batch", "bytes", "vertices", "faces", "error");
    for (size_t k = 0; k < fi.batches.size(); ++k) {
      const FileInfo::Batch& b = fi.batches[k];
      t += strf("  %8zu %12s %12s %12s %12.6g\n", k, thousands(b.bytes).c_str(), thousands(b.vertices).c_str(),
                thousands(b.faces).c_str(), b.error);
    }
    if (fi.loose_vertices || fi.loose_faces)
      t += strf("  after the last batch: %s vertices no face uses, %s triangles the levels leave out\n",
                thousands(fi.loose_vertices).c_str(), thousands(fi.loose_faces).c_str());
  }
  t += strf("  %-18s %-6s %12s %12s", "section", "codec", "stored", "raw");
  for (const SectionInfo& si : fi.sections)
    t += strf("\n  %-18s %-6s %12s %12s", si.name.c_str(), si.codec.c_str(), thousands(si.stored_bytes).c_str(),
              thousands(si.raw_bytes).c_str());
  return r;
}

std::vector<std::string> shown_inputs(const std::vector<std::string>& inputs) {
  std::vector<std::string> out;
  out.reserve(inputs.size());
  for (const std::string& s : inputs) out.push_back(shown_input(s));
  return out;
}

}  // namespace

// -o NAME for a single input that is a file name (not -, not a folder).
bool single_file_output(const std::vector<std::string>& inputs, const std::string& o) {
  std::error_code ec;
  return inputs.size() == 1 && !o.empty() && o != "-" && o.back() != '/' && !fs::is_directory(o, ec);
}

// The formats decode writes (kWritableFormats in tsm/io.hpp).
const WritableFormat* writable_format(MeshFormat f) {
  for (const WritableFormat& w : kWritableFormats)
    if (w.format == f) return &w;
  return nullptr;
}

std::vector<std::string> output_format_names() {
  std::vector<std::string> out;
  for (const WritableFormat& w : kWritableFormats) out.push_back(w.name);
  return out;
}

std::string output_formats_bar() {
  std::string out;
  for (const WritableFormat& w : kWritableFormats) out += (out.empty() ? "" : "|") + std::string(w.name);
  return out;
}

namespace {
// "a, b, c or d" from the formats' fields.
template <typename Field>
std::string listed(Field field) {
  const size_t n = std::size(kWritableFormats);
  std::string out;
  for (size_t i = 0; i < n; ++i) {
    if (i > 0) out += i + 1 == n ? " or " : ", ";
    out += field(kWritableFormats[i]);
  }
  return out;
}
}  // namespace

std::string output_extensions_text() {
  return listed([](const WritableFormat& w) { return std::string(w.extension); });
}

std::string output_formats_text() {
  return listed([](const WritableFormat& w) { return std::string(mesh_format_name(w.format)); });
}

int cmd_encode(const EncodeArgs& a) {
  install_signal_guard();
  double max_error = 0;
  bool percent = false;
  if (!a.max_error.empty() && !parse_max_error(a.max_error, max_error, percent))
    return usage_error("--max-error " + a.max_error +
                       ": give a positive number in model units, or a percentage of the bounding-box diagonal such "
                       "as 0.5%");
  if (a.fallback && format_from_extension(a.output) != MeshFormat::gltf &&
      format_from_extension(a.output) != MeshFormat::glb)
    return usage_error(
        "--fallback keeps an uncompressed copy inside a glTF output; give -o NAME.glb or NAME.gltf, "
        "or drop it");
  // A glTF name: a glTF with TSM_mesh_compression, from one input file.
  const MeshFormat output_format = format_from_extension(a.output);
  if (output_format == MeshFormat::gltf || output_format == MeshFormat::glb) {
    if (gltf_output(a, a.output)) return gltf_encode(a);
    return usage_error(a.output +
                       ": a glTF output (TSM_mesh_compression) takes one input file (not stdin); run "
                       "once per file, or give -o DIR/ for .tsm files");
  }
  // encode writes .tsm data: a mesh file name for it would be a lie.
  if (single_file_output(a.inputs, a.output)) {
    const MeshFormat f = format_from_extension(a.output);
    const std::string tsm_name = with_extension(a.output, ".tsm");
    if (f != MeshFormat::unknown)
      return usage_error(a.output + ": encode writes .tsm files, not " + mesh_format_name(f) + "; give -o " +
                         tsm_name + " (tsm decode turns the .tsm back into " + mesh_format_name(f) + ")");
  }
  std::vector<Job> jobs;
  if (int rc = plan_outputs(a.inputs, a.output, ".tsm", a.force, "a mesh", "*.ply", jobs)) return rc;
  const bool to_stdout = jobs.size() == 1 && jobs[0].output == "-";
  if (to_stdout && a.json)
    return usage_error("--json prints to stdout, which already carries the .tsm data; give -o FILE or drop --json");
  if (to_stdout && is_terminal(stdout))
    return usage_error("refusing to write binary .tsm data to a terminal; redirect stdout (> out.tsm), pipe it, "
                       "or give -o FILE");
  const MeshFormat forced = parse_format(lower(a.input_format));
  BatchOptions bo;
  bo.jobs = effective_jobs(a.jobs);
  bo.quiet = a.quiet;
  bo.json = a.json;
  bo.text_to_stderr = to_stdout;
  bo.verb = "encoded";
  return run_batch(shown_inputs(a.inputs), bo,
                   [&](size_t i, Phase& phase) { return encode_one(a, jobs[i], forced, phase); });
}

int cmd_decode(const DecodeArgs& a) {
  install_signal_guard();
  const MeshFormat wanted = parse_format(lower(a.format));
  // A compressed glTF in, a plain glTF out.
  if (a.inputs.size() == 1 && (format_from_extension(a.inputs[0]) == MeshFormat::gltf ||
                               format_from_extension(a.inputs[0]) == MeshFormat::glb)) {
    if (gltf_output(a, a.output)) return gltf_decode(a);
    return usage_error(a.inputs[0] + ": decode of a glTF writes a plain glTF: give -o NAME.glb or NAME.gltf");
  }
  // Every writable format has one extension; PLY is the default.
  const std::string ext = writable_format(wanted) ? writable_format(wanted)->extension : ".ply";
  // One output format for the run: --format, else the extension of a single
  // -o FILE, else PLY. A name is checked before anything is created.
  MeshFormat format = wanted == MeshFormat::unknown ? MeshFormat::ply : wanted;
  if (single_file_output(a.inputs, a.output)) {
    const MeshFormat by_name = format_from_extension(a.output);
    if (by_name != MeshFormat::unknown && !writable_format(by_name))
      return usage_error(a.output + ": tsm does not write " + mesh_format_name(by_name) + " files; name the output " +
                         with_extension(a.output, ".ply") + " (or end it in " + output_extensions_text() + ")");
    if (wanted != MeshFormat::unknown && by_name != MeshFormat::unknown && by_name != wanted)
      return usage_error(a.output + ": the name says " + mesh_format_name(by_name) + " but --format says " +
                         mesh_format_name(wanted) + "; drop one of them");
    if (wanted == MeshFormat::unknown) {
      if (by_name == MeshFormat::unknown)
        return usage_error(a.output + ": the name does not say which format to write; end it in " + output_extensions_text() +
                           ", or pass --format " + output_formats_bar());
      format = by_name;
    }
  }
  if (a.ascii && format != MeshFormat::ply && format != MeshFormat::stl) {
    const char* why = format == MeshFormat::glb ? "GLB is binary only: drop --ascii, or write .gltf for JSON text"
                      : format == MeshFormat::gltf ? ".gltf is JSON text already: drop --ascii"
                      : format == MeshFormat::off  ? "OFF is text already: drop --ascii"
                      : format == MeshFormat::obj  ? "OBJ is text already: drop --ascii"
                                                   : nullptr;
    if (why) return usage_error(std::string("--ascii chooses ASCII PLY or STL output, but the output is ") +
                                mesh_format_name(format) + "; " + why);
  }
  std::vector<Job> jobs;
  if (int rc = plan_outputs(a.inputs, a.output, ext, a.force, "a .tsm file", "*.tsm", jobs)) return rc;
  const bool to_stdout = jobs.size() == 1 && jobs[0].output == "-";
  if (to_stdout && a.json)
    return usage_error("--json prints to stdout, which already carries the mesh; give -o FILE or drop --json");
  if (to_stdout && format == MeshFormat::ply && !a.ascii && is_terminal(stdout))
    return usage_error("refusing to write binary PLY to a terminal; redirect stdout (> out.ply), pipe it, or pass "
                       "--ascii or --format obj for text");
  if (to_stdout && format == MeshFormat::stl && !a.ascii && is_terminal(stdout))
    return usage_error("refusing to write binary STL to a terminal; redirect stdout (> out.stl), pipe it, or pass "
                       "--ascii for text");
  if (to_stdout && format == MeshFormat::glb && is_terminal(stdout))
    return usage_error("refusing to write binary GLB to a terminal; redirect stdout (> out.glb), pipe it, or pass "
                       "--format gltf for text");
  BatchOptions bo;
  bo.jobs = effective_jobs(a.jobs);
  bo.quiet = a.quiet;
  bo.json = a.json;
  bo.text_to_stderr = to_stdout;
  bo.verb = "decoded";
  return run_batch(shown_inputs(a.inputs), bo,
                   [&](size_t i, Phase& phase) { return decode_one(a, jobs[i], format, phase); });
}

int cmd_info(const InfoArgs& a) {
  install_signal_guard();
  if (int rc = check_stdin_input(a.inputs, "a .tsm file")) return rc;
  BatchOptions bo;
  bo.jobs = effective_jobs(a.jobs);
  bo.quiet = a.quiet;
  bo.json = a.json;
  bo.verb = "inspected";
  return run_batch(shown_inputs(a.inputs), bo, [&](size_t i, Phase& phase) {
    phase.set("reading");
    // A missing file or a folder is one failed input; the others go on.
    const Status problem = input_problem(a.inputs[i], "*.tsm");
    if (problem.ok()) return info_one(a.inputs[i]);
    FileResult r;
    r.status = problem;
    JsonObject o;
    o.str("file", a.inputs[i]).str("status", "error");
    o.num("exit_code", static_cast<unsigned long long>(exit_code_for(problem))).str("error", problem.message());
    r.json = o.done();
    return r;
  });
}

}  // namespace tsm::cli

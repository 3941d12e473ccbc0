// `tsm bench` on meshes with attributes (see bench_attribute_files.hpp).
// Draco's readers weld positions in OBJ and PLY and its glTF reader does not,
// so the same values are given to draco_encoder in each layout an exporter
// writes (one vertex per split vertex as glTF has them, or welded positions
// with shared value lists as OBJ has them) and its smallest file counts.
#include "bench_attribute_files.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <map>
#include <set>

#include "bench_assets.hpp"
#include "cli_util.hpp"
#include "tsm/compare.hpp"
#include "tsm/io.hpp"
#include "tsm/tsm.hpp"

namespace tsm::cli {

namespace fs = std::filesystem;
using ojson = nlohmann::ordered_json;

namespace {

constexpr int kNormalBits = 8, kTexcoordBits = 10, kColorBits = 8;

bool is_common(const Attribute& a) {
  const bool kind = a.kind == AttributeKind::normal || a.kind == AttributeKind::texcoord || a.kind == AttributeKind::color;
  return kind && a.domain != AttributeDomain::face;
}

const char* kind_name(AttributeKind k) {
  return k == AttributeKind::normal ? "normal" : k == AttributeKind::texcoord ? "texcoord" : "color";
}

uint32_t float_bits(float f) {
  uint32_t u;
  std::memcpy(&u, &f, sizeof u);
  return u;
}

// The value a corner has (its index into the attribute's values).
uint32_t corner_value(const Attribute& a, size_t corner, uint32_t vertex) {
  return a.domain == AttributeDomain::corner ? a.indices[corner] : vertex;
}

std::vector<uint32_t> value_key(const Attribute& a, uint32_t value) {
  std::vector<uint32_t> key(a.components);
  for (uint32_t c = 0; c < a.components; ++c) key[c] = float_bits(a.values[size_t{value} * a.components + c]);
  return key;
}

// One vertex per distinct (vertex, its corners' values): the layout glTF has.
Mesh split_vertices(const Mesh& m) {
  Mesh out;
  out.face_offsets = m.face_offsets;
  std::map<std::vector<uint32_t>, uint32_t> ids;
  std::vector<std::vector<uint32_t>> values_of;  // new vertex -> its value per attribute
  for (size_t f = 0; f < m.face_count(); ++f)
    for (size_t k = m.face_offsets[f]; k < m.face_offsets[f + 1]; ++k) {
      const uint32_t v = m.indices[k];
      std::vector<uint32_t> key{v};
      for (const Attribute& a : m.attributes) key.push_back(corner_value(a, k, v));
      auto [it, added] = ids.emplace(key, static_cast<uint32_t>(out.vertex_count()));
      if (added) {
        out.add_vertex(m.positions[3 * size_t{v}], m.positions[3 * size_t{v} + 1], m.positions[3 * size_t{v} + 2]);
        values_of.emplace_back(key.begin() + 1, key.end());
      }
      out.indices.push_back(it->second);
    }
  for (size_t i = 0; i < m.attributes.size(); ++i) {
    const Attribute& a = m.attributes[i];
    Attribute b = a;
    b.domain = AttributeDomain::vertex;
    b.indices.clear();
    b.values.clear();
    for (const auto& vals : values_of)
      for (uint32_t c = 0; c < a.components; ++c) b.values.push_back(a.values[size_t{vals[i]} * a.components + c]);
    out.attributes.push_back(std::move(b));
  }
  return out;
}

// Positions welded by their float bits, each attribute per corner with its
// distinct values listed once: the layout OBJ exporters write.
Mesh shared_lists(const Mesh& m) {
  Mesh out;
  out.face_offsets = m.face_offsets;
  std::map<std::vector<uint32_t>, uint32_t> points;
  std::vector<uint32_t> point_of(m.vertex_count());
  for (size_t v = 0; v < m.vertex_count(); ++v) {
    const float* p = &m.positions[3 * v];
    auto [it, added] =
        points.emplace(std::vector<uint32_t>{float_bits(p[0]), float_bits(p[1]), float_bits(p[2])},
                       static_cast<uint32_t>(out.vertex_count()));
    if (added) out.add_vertex(p[0], p[1], p[2]);
    point_of[v] = it->second;
  }
  for (uint32_t v : m.indices) out.indices.push_back(point_of[v]);
  for (const Attribute& a : m.attributes) {
    Attribute b = a;
    b.domain = AttributeDomain::corner;
    b.values.clear();
    b.indices.clear();
    std::map<std::vector<uint32_t>, uint32_t> ids;
    for (size_t k = 0; k < m.indices.size(); ++k) {
      const uint32_t value = corner_value(a, k, m.indices[k]);
      auto [it, added] = ids.emplace(value_key(a, value), static_cast<uint32_t>(b.value_count()));
      if (added)
        b.values.insert(b.values.end(), a.values.begin() + static_cast<std::ptrdiff_t>(size_t{value} * a.components),
                        a.values.begin() + static_cast<std::ptrdiff_t>((size_t{value} + 1) * a.components));
      b.indices.push_back(it->second);
    }
    out.attributes.push_back(std::move(b));
  }
  return out;
}

// Float colours as 8-bit integers (Draco's PLY reader takes uchar colours only).
Mesh with_byte_colors(Mesh m) {
  for (Attribute& a : m.attributes)
    if (a.kind == AttributeKind::color && a.type == AttributeType::f32) {
      a.type = AttributeType::u8;
      for (float& x : a.values) x = std::round(std::clamp(x, 0.0f, 1.0f) * 255.0f);
    }
  return m;
}

std::set<AttributeKind> kinds_of(const Mesh& m) {
  std::set<AttributeKind> kinds;
  for (const Attribute& a : m.attributes)
    if (is_common(a)) kinds.insert(a.kind);
  return kinds;
}

std::string lower_extension(const std::string& path) {
  std::string e = fs::path(path).extension().string();
  std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return e;
}

// draco_encoder on `in`: the .drc's bytes when Draco kept every kind in
// `want` (checked by decoding it to OBJ, which carries texture coordinates,
// and to PLY, which carries colours), else 0 and `note` says why.
// Its files are `out` + .drc, .log, .drc.obj and .drc.ply.
size_t draco_file_bytes(const std::string& in, const std::string& out, int q, const std::set<AttributeKind>& want,
                        std::string& note) {
  const std::string drc = out + ".drc", log = out + ".log";
  const std::string qs = std::to_string(q);
  const int rc = run_program({"draco_encoder", "-i", in, "-o", drc, "-cl", "10", "-qp", qs, "-qn",
                              std::to_string(kNormalBits), "-qt", std::to_string(kTexcoordBits), "-qg", "8"},
                             log);
  if (rc == -1) {
    note = "draco_encoder is not installed (scripts/setup.sh installs it)";
    return 0;
  }
  if (rc != 0) {
    note = "refused: " + last_line(log);
    return 0;
  }
  std::set<AttributeKind> kept;
  for (const char* ext : {".obj", ".ply"}) {
    const std::string back = drc + ext;
    Mesh m;
    if (run_program({"draco_decoder", "-i", drc, "-o", back}, log) == 0 && read_mesh(back, m).ok())
      for (AttributeKind k : kinds_of(m)) kept.insert(k);
  }
  for (AttributeKind k : want)
    if (!kept.count(k)) {
      note = std::string("no ") + kind_name(k) + "s";
      return 0;
    }
  std::error_code ec;
  const auto n = fs::file_size(drc, ec);
  return ec ? 0 : static_cast<size_t>(n);
}

std::string describe(const Mesh& m) {
  std::string s;
  for (const Attribute& a : m.attributes)
    s += (s.empty() ? "" : ", ") + a.name + (a.domain == AttributeDomain::corner ? " (corner)" : " (vertex)");
  return s;
}

size_t distinct_points(const Mesh& m) {
  std::set<std::vector<uint32_t>> points;
  for (size_t v = 0; v < m.vertex_count(); ++v)
    points.insert({float_bits(m.positions[3 * v]), float_bits(m.positions[3 * v + 1]), float_bits(m.positions[3 * v + 2])});
  return points.size();
}

// The tsm file's bytes by part, from tsm::inspect.
std::string parts_of(const std::string& bytes) {
  FileInfo info;
  if (!inspect(bytes, info).ok()) return "-";
  std::string s = "connectivity " + thousands(info.connectivity_bytes) + ", geometry " + thousands(info.geometry_bytes);
  uint64_t named = info.connectivity_bytes + info.geometry_bytes;
  for (const AttributeInfo& a : info.attributes) {
    s += ", " + a.name + " " + thousands(a.coded_bytes);
    named += a.coded_bytes;
  }
  if (info.file_bytes > named) s += ", other " + thousands(info.file_bytes - named);
  return s;
}

}  // namespace

bool has_common_attributes(const Mesh& mesh) {
  for (const Attribute& a : mesh.attributes)
    if (is_common(a)) return true;
  return false;
}

AttributeFileRow bench_attribute_file(const std::string& path, const Mesh& input, int q, int level, bool quiet,
                                      const std::string& work_dir) {
  AttributeFileRow row;
  row.name = fs::path(path).filename().string();
  row.q = q;
  Mesh m = input;
  m.metadata.clear();
  m.attributes.erase(std::remove_if(m.attributes.begin(), m.attributes.end(), [](const Attribute& a) { return !is_common(a); }),
                     m.attributes.end());
  row.vertices = m.vertex_count();
  row.points = distinct_points(m);
  row.faces = m.face_count();
  row.attributes = describe(m);
  if (!quiet) std::fprintf(stderr, "tsm bench: %s q=%d: attributes, tsm and draco_encoder\n", row.name.c_str(), q);

  EncodeOptions eo;
  eo.quantization_bits = q;
  eo.level = level;
  eo.threads = 1;
  eo.attribute_bits.normal = kNormalBits;
  eo.attribute_bits.texcoord = kTexcoordBits;
  eo.attribute_bits.color = kColorBits;
  std::string bytes;
  Status s = encode(m, eo, bytes);
  Mesh back;
  if (s.ok()) s = decode(bytes, back);
  if (!s.ok()) {
    row.error = s.message();
    return row;
  }
  row.tsm_bytes = bytes.size();
  row.tsm_parts = parts_of(bytes);
  const CompareResult cr = compare_meshes(m, back, q, eo.attribute_bits);
  row.tsm_exact = cr.equal;
  row.tsm_diff = cr.difference;

  // Draco: the file itself (when its reader takes it), then the two layouts.
  const std::set<AttributeKind> want = kinds_of(m);
  std::vector<std::pair<std::string, std::string>> inputs;  // (what, file)
  const std::string ext = lower_extension(path);
  if (ext == ".obj" || ext == ".ply") inputs.push_back({"the file", path});
  const std::string stem = (fs::path(work_dir) / ("attr_" + std::to_string(q) + "_" + fs::path(path).stem().string())).string();
  // Colours go through PLY (Draco's OBJ reader has none), the rest through OBJ.
  const std::string split_ext = want.count(AttributeKind::color) ? ".ply" : ".obj";
  WriteOptions wo;
  wo.ascii = true;
  if (write_mesh(stem + "_split" + split_ext, with_byte_colors(split_vertices(m)), wo).ok())
    inputs.push_back({"split vertices", stem + "_split" + split_ext});
  if (write_mesh(stem + "_shared.obj", shared_lists(m), wo).ok()) inputs.push_back({"shared lists", stem + "_shared.obj"});
  for (size_t i = 0; i < inputs.size(); ++i) {
    const auto& [what, file] = inputs[i];
    std::string note;
    const size_t n = draco_file_bytes(file, stem + "_draco" + std::to_string(i), q, want, note);
    if (n && (!row.draco_bytes || n < row.draco_bytes)) row.draco_bytes = n;
    row.draco_inputs += (row.draco_inputs.empty() ? "" : "; ") + what + ": " + (n ? thousands(n) : note);
  }
  return row;
}

void print_attribute_file_table(const std::vector<AttributeFileRow>& rows) {
  std::printf(
      "\nAttributes: normals, texture coordinates and colours (other attributes dropped, as Draco's readers drop "
      "them); positions q bits, normals 8, texture coordinates 10, colours 8 in both tools (draco_encoder -cl 10). "
      "Draco: the smallest of its files from the input itself (OBJ, PLY), the mesh written with one vertex per "
      "split vertex (OBJ, or PLY with colours), and with welded positions and shared value lists (OBJ), among "
      "those keeping every attribute (\"no normals\": its reader dropped them). "
      "V = vertices as read, points = distinct positions.\n\n");
  std::printf("| mesh | q | V | points | T | attributes | tsm bytes | tsm bytes by part | Draco cl10 bytes | Draco's inputs "
              "| tsm/Draco | exact: tsm |\n|---|---:|---:|---:|---:|---|---:|---|---:|---|---:|---|\n");
  for (const AttributeFileRow& r : rows) {
    if (!r.error.empty()) {
      std::printf("| %s | %d | %s | %s | %s | %s | - | failed: %s | - | - | - | - |\n", r.name.c_str(), r.q,
                  thousands(r.vertices).c_str(), thousands(r.points).c_str(), thousands(r.faces).c_str(),
                  r.attributes.c_str(), printable(r.error).c_str());
      continue;
    }
    std::printf("| %s | %d | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s |\n", r.name.c_str(), r.q,
                thousands(r.vertices).c_str(), thousands(r.points).c_str(), thousands(r.faces).c_str(),
                r.attributes.c_str(), thousands(r.tsm_bytes).c_str(), r.tsm_parts.c_str(),
                r.draco_bytes ? thousands(r.draco_bytes).c_str() : "-",
                printable(r.draco_inputs).c_str(),
                r.draco_bytes ? fixed(static_cast<double>(r.tsm_bytes) / static_cast<double>(r.draco_bytes), 2).c_str()
                              : "-",
                r.tsm_exact ? "yes" : "NO");
  }
  for (const AttributeFileRow& r : rows)
    if (r.error.empty() && !r.tsm_exact)
      std::printf("\n%s q=%d: round trip with attributes NOT exact: %s\n", r.name.c_str(), r.q, r.tsm_diff.c_str());
}

ojson attribute_file_rows_json(const std::vector<AttributeFileRow>& rows) {
  ojson out = ojson::array();
  for (const AttributeFileRow& r : rows) {
    ojson o = ojson::object();
    o["mesh"] = r.name;
    o["q"] = r.q;
    o["vertices"] = r.vertices;
    o["points"] = r.points;
    o["faces"] = r.faces;
    o["attributes"] = r.attributes;
    if (!r.error.empty()) {
      o["error"] = r.error;
    } else {
      o["tsm_bytes"] = r.tsm_bytes;
      o["tsm_parts"] = r.tsm_parts;
      o["tsm_exact"] = r.tsm_exact;
    }
    if (r.draco_bytes) o["draco_cl10_bytes"] = r.draco_bytes;
    o["draco_inputs"] = r.draco_inputs;
    out.push_back(std::move(o));
  }
  return out;
}

}  // namespace tsm::cli

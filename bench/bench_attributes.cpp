// Attributes beside Draco (issue 8's table): per mesh, the total bytes of tsm
// and of Draco's encoder (Debian's draco_encoder, -cl 10, the same
// quantization bits: positions 14, normals 10, texture coordinates 12,
// generic 16) and the bytes each attribute costs (the file with it minus the
// file without it). Meshes: the corpus files that carry attributes, and the
// bunny with smooth vertex normals (area-weighted, from its faces) and
// spherical texture coordinates added. Usage:
//   tsm_bench_attributes [MESH...]
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "tsm/tsm.hpp"
#include "tsm/io.hpp"

namespace fs = std::filesystem;

namespace {

size_t tsm_bytes(const tsm::Mesh& m) {
  tsm::EncodeOptions eo;
  eo.quantization_bits = 14;
  std::string bytes;
  if (!tsm::encode(m, eo, bytes).ok()) return 0;
  return bytes.size();
}

// Draco reads texture coordinates and per-corner values from OBJ (vt / vn),
// colours from PLY.
bool wants_obj(const tsm::Mesh& m) {
  for (const tsm::Attribute& a : m.attributes)
    if (a.domain != tsm::AttributeDomain::vertex || a.kind == tsm::AttributeKind::texcoord) return true;
  return false;
}

// Draco's bytes for the mesh written as PLY or OBJ; 0 when Draco refuses it.
size_t draco_bytes(const tsm::Mesh& m, const fs::path& dir, const std::string& name) {
  const fs::path in = dir / (name + (wants_obj(m) ? ".obj" : ".ply"));
  const fs::path out = dir / (name + ".drc");
  tsm::WriteOptions wo;
  wo.ascii = true;
  if (!tsm::write_mesh(in.string(), m, wo).ok()) return 0;
  const std::string cmd = "draco_encoder -i '" + in.string() + "' -o '" + out.string() +
                          "' -cl 10 -qp 14 -qn 10 -qt 12 -qg 16 >/dev/null 2>&1";
  if (std::system(cmd.c_str()) != 0) return 0;
  std::error_code ec;
  const auto n = fs::file_size(out, ec);
  return ec ? 0 : static_cast<size_t>(n);
}

tsm::Mesh bunny_with_normals_and_uvs(const std::string& path) {
  tsm::Mesh m;
  if (!tsm::read_mesh(path, m).ok()) return m;
  tsm::Attribute n, t;
  n.name = "normal";
  n.kind = tsm::AttributeKind::normal;
  n.components = 3;
  n.values.assign(3 * m.vertex_count(), 0.0f);
  std::vector<double> sum(3 * m.vertex_count(), 0.0);
  for (size_t f = 0; f < m.face_count(); ++f) {
    if (m.face_size(f) < 3) continue;
    const float* a = &m.positions[3 * m.face(f)[0]];
    const float* b = &m.positions[3 * m.face(f)[1]];
    const float* c = &m.positions[3 * m.face(f)[2]];
    const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    const double x[3] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
    for (uint32_t k = 0; k < m.face_size(f); ++k)
      for (int i = 0; i < 3; ++i) sum[3 * m.face(f)[k] + i] += x[i];
  }
  tsm::BoundingBox box = tsm::bounding_box(m);
  t.name = "texcoord";
  t.kind = tsm::AttributeKind::texcoord;
  t.components = 2;
  for (size_t v = 0; v < m.vertex_count(); ++v) {
    const double l = std::sqrt(sum[3 * v] * sum[3 * v] + sum[3 * v + 1] * sum[3 * v + 1] + sum[3 * v + 2] * sum[3 * v + 2]);
    for (int i = 0; i < 3; ++i) n.values[3 * v + i] = l > 0 ? static_cast<float>(sum[3 * v + i] / l) : (i == 2 ? 1.0f : 0.0f);
    double c[3];
    for (int i = 0; i < 3; ++i) c[i] = m.positions[3 * v + i] - 0.5 * (box.min[i] + box.max[i]);
    t.values.push_back(static_cast<float>(0.5 + std::atan2(c[1], c[0]) / (2 * M_PI)));
    t.values.push_back(static_cast<float>(0.5 + std::atan2(c[2], std::hypot(c[0], c[1])) / M_PI));
  }
  m.attributes = {n, t};
  return m;
}

// The same texture coordinates per corner, with a seam where u wraps from 1
// to 0 (corners of faces across it get u + 1, a value of their own, as an
// unwrapped atlas would have), and the normals per vertex.
tsm::Mesh with_corner_uvs(const tsm::Mesh& m) {
  tsm::Mesh out = m;
  const tsm::Attribute& t = m.attributes[1];
  tsm::Attribute c;
  c.name = t.name;
  c.kind = t.kind;
  c.components = 2;
  c.domain = tsm::AttributeDomain::corner;
  c.values = t.values;  // value v = vertex v's; wrapped copies appended
  std::vector<uint32_t> wrapped(m.vertex_count(), UINT32_MAX);
  for (size_t f = 0; f < m.face_count(); ++f) {
    float lo = 2, hi = -1;
    for (uint32_t k = 0; k < m.face_size(f); ++k) {
      lo = std::min(lo, t.values[2 * m.face(f)[k]]);
      hi = std::max(hi, t.values[2 * m.face(f)[k]]);
    }
    for (uint32_t k = 0; k < m.face_size(f); ++k) {
      const uint32_t v = m.face(f)[k];
      if (hi - lo > 0.5f && t.values[2 * v] < 0.5f) {
        if (wrapped[v] == UINT32_MAX) {
          wrapped[v] = static_cast<uint32_t>(c.values.size() / 2);
          c.values.push_back(t.values[2 * v] + 1.0f);
          c.values.push_back(t.values[2 * v + 1]);
        }
        c.indices.push_back(wrapped[v]);
      } else {
        c.indices.push_back(v);
      }
    }
  }
  out.attributes[1] = c;
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> files;
  for (int i = 1; i < argc; ++i) files.push_back(argv[i]);
  const std::string corpus = TSM_CORPUS_DIR;
  if (files.empty())
    for (const char* f : {"edge/cube_att.obj", "edge/cube_att.ply", "edge/sphere.obj", "edge/test_nm.obj", "edge/Box.ply",
                          "edge/test_pos_color.ply", "edge/test_generic.ply", "edge/test_more_datatypes.ply"})
      files.push_back(corpus + "/" + f);
  const fs::path dir = fs::temp_directory_path() / "tsm_bench_attributes";
  fs::create_directories(dir);
  std::printf("Attributes beside Draco (draco_encoder -cl 10 -qp 14 -qn 10 -qt 12 -qg 16; tsm q 14, normals 10-bit "
              "octahedral, texture coordinates 12, float colours 10, generic 16 bits, integers exact). Bytes per "
              "attribute = the file with it minus the file without it.\n\n");
  std::printf("| mesh | V | attributes | tsm bytes | Draco bytes | tsm/Draco | per attribute: tsm / Draco bytes |\n");
  std::printf("|---|---:|---|---:|---:|---:|---|\n");
  std::vector<std::pair<std::string, tsm::Mesh>> meshes;
  for (const std::string& f : files) {
    tsm::Mesh m;
    tsm::Status s = tsm::read_mesh(f, m);
    if (!s.ok()) {
      std::fprintf(stderr, "%s: %s\n", f.c_str(), s.to_string().c_str());
      continue;
    }
    meshes.push_back({fs::path(f).filename().string(), std::move(m)});
  }
  tsm::Mesh bunny = bunny_with_normals_and_uvs(corpus + "/bun_zipper.ply");
  if (bunny.vertex_count()) {
    meshes.push_back({"bun_zipper.ply + normals + uv (per corner, seam)", with_corner_uvs(bunny)});
    meshes.push_back({"bun_zipper.ply + normals + uv", std::move(bunny)});
  }
  int k = 0;
  for (auto& [name, m] : meshes) {
    const std::string tag = "m" + std::to_string(k++);
    const size_t t_all = tsm_bytes(m), d_all = draco_bytes(m, dir, tag);
    std::string attrs, per;
    for (size_t i = 0; i < m.attributes.size(); ++i) {
      const tsm::Attribute& a = m.attributes[i];
      const char* dom = a.domain == tsm::AttributeDomain::vertex ? "vertex" : a.domain == tsm::AttributeDomain::face ? "face" : "corner";
      attrs += (attrs.empty() ? "" : ", ") + a.name + " (" + dom + ")";
      tsm::Mesh without = m;
      without.attributes.erase(without.attributes.begin() + static_cast<std::ptrdiff_t>(i));
      const size_t t = tsm_bytes(without), d = draco_bytes(without, dir, tag + "_" + std::to_string(i));
      char buf[128];
      std::snprintf(buf, sizeof buf, "%s%s %lld / %s", per.empty() ? "" : "; ", a.name.c_str(),
                    static_cast<long long>(t_all) - static_cast<long long>(t),
                    d && d_all ? std::to_string(static_cast<long long>(d_all) - static_cast<long long>(d)).c_str() : "-");
      per += buf;
    }
    std::printf("| %s | %zu | %s | %zu | %s | %s | %s |\n", name.c_str(), m.vertex_count(), attrs.empty() ? "-" : attrs.c_str(),
                t_all, d_all ? std::to_string(d_all).c_str() : "refused", d_all ? std::to_string(static_cast<double>(t_all) / static_cast<double>(d_all)).substr(0, 5).c_str() : "-",
                per.empty() ? "-" : per.c_str());
    std::fflush(stdout);
  }
  fs::remove_all(dir);
  return 0;
}

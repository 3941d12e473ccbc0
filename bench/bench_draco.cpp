// Draco comparison adapter for `tsm bench` (not part of the library).
#include "bench_draco.hpp"
#include "bench_timing.hpp"

#include <algorithm>
#include <chrono>
#include <vector>

#ifdef TSM_HAVE_DRACO
#include <draco/attributes/attribute_quantization_transform.h>
#include <draco/compression/decode.h>
#include <draco/core/quantization_utils.h>
#include <draco/compression/encode.h>
#include <draco/compression/mesh/mesh_edgebreaker_encoder.h>
#include <draco/io/mesh_io.h>
#include <draco/mesh/mesh.h>
#endif

namespace tsm::bench {

namespace {
[[maybe_unused]] double ms_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}
}  // namespace

#ifdef TSM_HAVE_DRACO

bool draco_available() { return true; }
const char* draco_version() { return "1.5 (system)"; }

namespace {

std::unique_ptr<draco::Mesh> to_draco(const Mesh& mesh) {
  auto dm = std::make_unique<draco::Mesh>();
  const size_t nv = mesh.vertex_count();
  dm->set_num_points(static_cast<uint32_t>(nv));
  for (size_t f = 0; f < mesh.face_count(); ++f) {
    const uint32_t* c = mesh.face(f);
    for (uint32_t i = 1; i + 1 < mesh.face_size(f); ++i) {
      draco::Mesh::Face face;
      face[0] = c[0];
      face[1] = c[i];
      face[2] = c[i + 1];
      dm->AddFace(face);
    }
  }
  draco::GeometryAttribute ga;
  ga.Init(draco::GeometryAttribute::POSITION, nullptr, 3, draco::DT_FLOAT32, false, sizeof(float) * 3, 0);
  int id = dm->AddAttribute(ga, true, static_cast<uint32_t>(nv));
  draco::PointAttribute* pa = dm->attribute(id);
  for (size_t v = 0; v < nv; ++v)
    pa->SetAttributeValue(draco::AttributeValueIndex(static_cast<uint32_t>(v)), &mesh.positions[3 * v]);
  return dm;
}

Mesh from_draco(const draco::Mesh& dm) {
  Mesh m;
  const draco::PointAttribute* pa = dm.GetNamedAttribute(draco::GeometryAttribute::POSITION);
  m.positions.resize(3 * dm.num_points());
  for (uint32_t p = 0; p < dm.num_points(); ++p) {
    float xyz[3] = {0, 0, 0};
    if (pa) pa->ConvertValue<float, 3>(pa->mapped_index(draco::PointIndex(p)), xyz);
    std::copy(xyz, xyz + 3, &m.positions[3 * p]);
  }
  for (uint32_t f = 0; f < dm.num_faces(); ++f) {
    const auto& face = dm.face(draco::FaceIndex(f));
    m.add_triangle(face[0].value(), face[1].value(), face[2].value());
  }
  return m;
}

}  // namespace

DracoRun draco_roundtrip(const Mesh& mesh, int qbits, int level, int runs) {
  DracoRun r;
  std::unique_ptr<draco::Mesh> dm = to_draco(mesh);
  draco::Encoder enc;
  enc.SetSpeedOptions(10 - level, 10 - level);
  enc.SetAttributeQuantization(draco::GeometryAttribute::POSITION, qbits);
  std::vector<double> et, dt;
  draco::EncoderBuffer buf;
  for (int i = 0; i < std::max(1, runs); ++i) {
    buf.Clear();
    auto t0 = std::chrono::steady_clock::now();
    draco::Status s = enc.EncodeMeshToBuffer(*dm, &buf);
    et.push_back(ms_since(t0));
    if (!s.ok()) {
      r.error = "Draco encode failed: " + s.error_msg_string();
      return r;
    }
  }
  r.bytes = buf.size();
  std::unique_ptr<draco::Mesh> out;
  for (int i = 0; i < std::max(1, runs); ++i) {
    draco::DecoderBuffer in;
    in.Init(buf.data(), buf.size());
    draco::Decoder dec;
    auto t0 = std::chrono::steady_clock::now();
    auto so = dec.DecodeMeshFromBuffer(&in);
    dt.push_back(ms_since(t0));
    if (!so.ok()) {
      r.error = "Draco decode failed: " + so.status().error_msg_string();
      return r;
    }
    out = std::move(so).value();
  }
  r.encode_ms = median(et);
  r.decode_ms = median(dt);
  // Once more, untimed, with the positions left as the grid indices read.
  draco::DecoderBuffer in;
  in.Init(buf.data(), buf.size());
  draco::Decoder dec;
  dec.SetSkipAttributeTransform(draco::GeometryAttribute::POSITION);
  auto so = dec.DecodeMeshFromBuffer(&in);
  if (!so.ok()) {
    r.error = "Draco decode failed: " + so.status().error_msg_string();
    return r;
  }
  r.decoded_grid = from_draco(*so.value());
  r.ok = true;
  return r;
}

Mesh draco_grid(const Mesh& mesh, int qbits) {
  std::unique_ptr<draco::Mesh> dm = to_draco(mesh);
  const draco::PointAttribute* pa = dm->GetNamedAttribute(draco::GeometryAttribute::POSITION);
  draco::AttributeQuantizationTransform t;
  Mesh out = from_draco(*dm);
  if (!pa || !t.ComputeParameters(*pa, qbits)) return out;
  draco::Quantizer quantizer;
  quantizer.Init(t.range(), (1 << qbits) - 1);
  for (size_t i = 0; i < out.positions.size(); ++i)
    out.positions[i] = static_cast<float>(quantizer.QuantizeFloat(out.positions[i] - t.min_value(static_cast<int>(i % 3))));
  return out;
}

namespace {

// Draco's edgebreaker encoder with its connectivity step measured: the
// container writes the header, then this step, then the attributes.
class ConnectivityProbe : public draco::MeshEdgebreakerEncoder {
 public:
  size_t connectivity_bytes = 0;

 protected:
  draco::Status EncodeConnectivity() override {
    const size_t before = buffer()->size();
    draco::Status s = MeshEdgebreakerEncoder::EncodeConnectivity();
    connectivity_bytes = buffer()->size() - before;
    return s;
  }
};

}  // namespace

size_t draco_connectivity_bytes(const Mesh& mesh, int qbits, int level, size_t* file_bytes, std::string& error) {
  std::unique_ptr<draco::Mesh> dm = to_draco(mesh);
  draco::EncoderOptions options = draco::EncoderOptions::CreateDefaultOptions();
  options.SetSpeed(10 - level, 10 - level);
  options.SetAttributeInt(0, "quantization_bits", qbits);
  ConnectivityProbe enc;
  enc.SetMesh(*dm);
  draco::EncoderBuffer buf;
  draco::Status s = enc.Encode(options, &buf);
  if (!s.ok()) {
    error = "Draco encode failed: " + s.error_msg_string();
    return 0;
  }
  if (file_bytes) *file_bytes = buf.size();
  return enc.connectivity_bytes;
}

bool draco_read(const std::string& path, double& ms, size_t& vertices, size_t& faces, std::string& error) {
  auto t0 = std::chrono::steady_clock::now();
  auto so = draco::ReadMeshFromFile(path);
  ms = ms_since(t0);
  if (!so.ok()) {
    error = so.status().error_msg_string();
    return false;
  }
  vertices = so.value()->num_points();
  faces = so.value()->num_faces();
  return true;
}

#else

bool draco_available() { return false; }
const char* draco_version() { return "not built in"; }
DracoRun draco_roundtrip(const Mesh&, int, int, int) {
  DracoRun r;
  r.error = "Draco is not built in (install libdraco-dev and reconfigure)";
  return r;
}
Mesh draco_grid(const Mesh&, int) { return Mesh(); }
size_t draco_connectivity_bytes(const Mesh&, int, int, size_t*, std::string& error) {
  error = "Draco is not built in";
  return 0;
}
bool draco_read(const std::string&, double&, size_t&, size_t&, std::string& error) {
  error = "Draco is not built in";
  return false;
}

#endif

}  // namespace tsm::bench

// tsmcodec._tsmcodec: the Python binding of tsm (pybind11, numpy arrays).
// Positions are float32 (N, 3), faces (M, k) integer arrays or a flat
// `indices` with `face_offsets` for mixed polygons. Errors raise
// tsmcodec.Error with the library's message. The GIL is released while the
// library codes, reads or writes.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>
#include <stdexcept>
#include <string>

#include "tsm/distance.hpp"
#include "tsm/io.hpp"
#include "tsm/simplify.hpp"
#include "tsm/tsm.hpp"
#include "tsm/version.h"

namespace py = pybind11;

namespace {

struct TsmError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

void check(const tsm::Status& status) {
  if (!status.ok()) throw TsmError(status.message());
}

const char* kind_name(tsm::AttributeKind k) {
  switch (k) {
    case tsm::AttributeKind::normal: return "normal";
    case tsm::AttributeKind::color: return "color";
    case tsm::AttributeKind::texcoord: return "texcoord";
    default: return "generic";
  }
}
tsm::AttributeKind kind_from(const std::string& s) {
  if (s == "normal") return tsm::AttributeKind::normal;
  if (s == "color") return tsm::AttributeKind::color;
  if (s == "texcoord") return tsm::AttributeKind::texcoord;
  if (s == "generic") return tsm::AttributeKind::generic;
  throw py::value_error("attribute kind must be 'generic', 'normal', 'color' or 'texcoord', not '" + s + "'");
}
const char* domain_name(tsm::AttributeDomain d) {
  switch (d) {
    case tsm::AttributeDomain::face: return "face";
    case tsm::AttributeDomain::corner: return "corner";
    default: return "vertex";
  }
}
tsm::AttributeDomain domain_from(const std::string& s) {
  if (s == "vertex") return tsm::AttributeDomain::vertex;
  if (s == "face") return tsm::AttributeDomain::face;
  if (s == "corner") return tsm::AttributeDomain::corner;
  throw py::value_error("attribute domain must be 'vertex', 'face' or 'corner', not '" + s + "'");
}
const char* type_name(tsm::AttributeType t) {
  switch (t) {
    case tsm::AttributeType::u8: return "u8";
    case tsm::AttributeType::u16: return "u16";
    case tsm::AttributeType::i32: return "i32";
    default: return "f32";
  }
}
tsm::AttributeType type_from(const std::string& s) {
  if (s == "f32") return tsm::AttributeType::f32;
  if (s == "u8") return tsm::AttributeType::u8;
  if (s == "u16") return tsm::AttributeType::u16;
  if (s == "i32") return tsm::AttributeType::i32;
  throw py::value_error("attribute type must be 'f32', 'u8', 'u16' or 'i32', not '" + s + "'");
}

template <typename T>
py::array_t<T> to_array(const std::vector<T>& v, size_t cols) {
  size_t rows = cols ? v.size() / cols : 0;
  py::array_t<T> a = cols == 1 ? py::array_t<T>(rows) : py::array_t<T>({rows, cols});
  if (!v.empty()) std::memcpy(a.mutable_data(), v.data(), v.size() * sizeof(T));
  return a;
}

// Integer indices of any numpy integer type, checked to fit uint32.
std::vector<uint32_t> to_indices(const py::handle& obj, const char* what, py::ssize_t* cols) {
  auto a = py::array_t<int64_t, py::array::c_style | py::array::forcecast>::ensure(obj);
  if (!a) throw py::type_error(std::string(what) + " must be an integer array");
  if (cols) {
    if (a.ndim() != 2) throw py::value_error(std::string(what) + " must be 2-dimensional (faces, corners)");
    *cols = a.shape(1);
  } else if (a.ndim() != 1) {
    throw py::value_error(std::string(what) + " must be 1-dimensional");
  }
  std::vector<uint32_t> out(size_t(a.size()));
  const int64_t* p = a.data();
  for (size_t i = 0; i < out.size(); ++i) {
    if (p[i] < 0 || p[i] > int64_t(UINT32_MAX))
      throw py::value_error(std::string(what) + ": index " + std::to_string(p[i]) + " out of range");
    out[i] = uint32_t(p[i]);
  }
  return out;
}

std::vector<float> to_floats(const py::handle& obj, const char* what, py::ssize_t want_cols, py::ssize_t* cols) {
  auto a = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(obj);
  if (!a) throw py::type_error(std::string(what) + " must be a float array");
  py::ssize_t c = a.ndim() == 1 ? 1 : a.ndim() == 2 ? a.shape(1) : -1;
  if (c < 0) throw py::value_error(std::string(what) + " must be 1- or 2-dimensional");
  if (want_cols && (a.ndim() != 2 || c != want_cols))
    throw py::value_error(std::string(what) + " must have shape (n, " + std::to_string(want_cols) + ")");
  if (cols) *cols = c;
  return std::vector<float>(a.data(), a.data() + a.size());
}

tsm::Mesh make_mesh(const py::handle& positions, const py::handle& faces, const py::handle& face_offsets) {
  tsm::Mesh mesh;
  mesh.positions = to_floats(positions, "positions", 3, nullptr);
  if (face_offsets.is_none()) {
    py::ssize_t k = 0;
    mesh.indices = to_indices(faces, "faces", &k);
    if (k < 3 && !mesh.indices.empty()) throw py::value_error("faces need at least 3 corners each");
    size_t m = k ? mesh.indices.size() / size_t(k) : 0;
    mesh.face_offsets.resize(m + 1);
    for (size_t f = 0; f <= m; ++f) mesh.face_offsets[f] = uint32_t(f * size_t(k));
  } else {
    mesh.indices = to_indices(faces, "indices", nullptr);
    mesh.face_offsets = to_indices(face_offsets, "face_offsets", nullptr);
  }
  return mesh;
}

void add_attribute(tsm::Mesh& mesh, const std::string& name, const py::handle& values, const std::string& kind,
                   const std::string& domain, const std::string& type, const py::handle& indices) {
  tsm::Attribute a;
  a.name = name;
  a.kind = kind_from(kind);
  a.domain = domain_from(domain);
  a.type = type_from(type);
  py::ssize_t cols = 1;
  a.values = to_floats(values, "attribute values", 0, &cols);
  a.components = uint32_t(cols);
  if (!indices.is_none()) a.indices = to_indices(indices, "attribute indices", nullptr);
  mesh.attributes.push_back(std::move(a));
}

std::string_view view_of(const py::buffer_info& b) {
  return std::string_view(static_cast<const char*>(b.ptr), size_t(b.size * b.itemsize));
}

tsm::EncodeOptions encode_options(int quantization_bits, int level, uint32_t segment_faces, int threads,
                                  bool keep_order, bool lossless, bool allow_nonfinite) {
  tsm::EncodeOptions o;
  o.keep_order = keep_order;
  o.lossless = lossless;
  o.allow_nonfinite = allow_nonfinite;
  o.quantization_bits = quantization_bits;
  o.level = level;
  o.segment_faces = segment_faces;
  o.threads = threads;
  return o;
}

// Encodes with the GIL released; tsmcodec.Error on failure.
std::string encode_released(const tsm::Mesh& mesh, const tsm::EncodeOptions& options,
                            tsm::EncodeMapping* mapping = nullptr) {
  std::string out;
  py::gil_scoped_release release;
  check(tsm::encode(mesh, options, out, mapping));
  return out;
}

}  // namespace

PYBIND11_MODULE(_tsmcodec, m) {
  m.doc() = "tsm triangle-mesh compression (binding of the C++ library)";
  m.attr("__version__") = TSM_VERSION_STRING;
  py::register_exception<TsmError>(m, "Error");

  py::class_<tsm::Attribute>(m, "Attribute")
      .def_readonly("name", &tsm::Attribute::name)
      .def_property_readonly("kind", [](const tsm::Attribute& a) { return kind_name(a.kind); })
      .def_property_readonly("domain", [](const tsm::Attribute& a) { return domain_name(a.domain); })
      .def_property_readonly("type", [](const tsm::Attribute& a) { return type_name(a.type); })
      .def_readonly("components", &tsm::Attribute::components)
      .def_property_readonly("values", [](const tsm::Attribute& a) { return to_array(a.values, a.components); })
      .def_property_readonly("indices", [](const tsm::Attribute& a) { return to_array(a.indices, 1); })
      .def("__repr__", [](const tsm::Attribute& a) {
        return "<tsmcodec.Attribute '" + a.name + "' " + kind_name(a.kind) + " " + domain_name(a.domain) + " x" +
               std::to_string(a.components) + ">";
      });

  py::class_<tsm::Mesh>(m, "Mesh")
      .def(py::init([](const py::handle& positions, const py::handle& faces, const py::handle& face_offsets) {
             return make_mesh(positions, faces, face_offsets);
           }),
           py::arg("positions"), py::arg("faces"), py::arg("face_offsets") = py::none(),
           "Mesh(positions (N,3) float, faces (M,k) int) or Mesh(positions, indices, face_offsets) for mixed polygons")
      .def("add_attribute", &add_attribute, py::arg("name"), py::arg("values"), py::arg("kind") = "generic",
           py::arg("domain") = "vertex", py::arg("type") = "f32", py::arg("indices") = py::none())
      .def_property_readonly("vertex_count", [](const tsm::Mesh& mm) { return mm.vertex_count(); })
      .def_property_readonly("face_count", [](const tsm::Mesh& mm) { return mm.face_count(); })
      .def_property_readonly("positions", [](const tsm::Mesh& mm) { return to_array(mm.positions, 3); })
      .def_property_readonly("indices", [](const tsm::Mesh& mm) { return to_array(mm.indices, 1); })
      .def_property_readonly("face_offsets", [](const tsm::Mesh& mm) { return to_array(mm.face_offsets, 1); })
      .def_property_readonly(
          "faces",
          [](const tsm::Mesh& mm) {
            size_t f = mm.face_count();
            size_t k = f ? mm.face_offsets[1] - mm.face_offsets[0] : 3;
            for (size_t i = 0; i < f; ++i)
              if (mm.face_offsets[i + 1] - mm.face_offsets[i] != k)
                throw py::value_error("faces of different sizes: use indices and face_offsets");
            return to_array(mm.indices, k);
          },
          "(M, k) uint32 when every face has k corners (k = 3: triangles)")
      .def_readonly("attributes", &tsm::Mesh::attributes)
      .def_property_readonly("metadata",
                             [](const tsm::Mesh& mm) {
                               py::dict d;
                               for (const auto& e : mm.metadata) d[py::str(e.key)] = py::bytes(e.value);
                               return d;
                             })
      .def("__repr__", [](const tsm::Mesh& mm) {
        return "<tsmcodec.Mesh " + std::to_string(mm.vertex_count()) + " vertices, " + std::to_string(mm.face_count()) +
               " faces, " + std::to_string(mm.attributes.size()) + " attributes>";
      });

  m.def(
      "encode",
      [](const tsm::Mesh& mesh, int quantization_bits, int level, uint32_t segment_faces, int threads, bool keep_order,
         bool lossless, bool allow_nonfinite) {
        return py::bytes(encode_released(
            mesh, encode_options(quantization_bits, level, segment_faces, threads, keep_order, lossless, allow_nonfinite)));
      },
      py::arg("mesh"), py::kw_only(), py::arg("quantization_bits") = tsm::kDefaultQuantizationBits,
      py::arg("level") = tsm::kDefaultLevel, py::arg("segment_faces") = 0, py::arg("threads") = 0,
      py::arg("keep_order") = false, py::arg("lossless") = false, py::arg("allow_nonfinite") = false,
      "Encodes a Mesh; returns the .tsm bytes (keep_order: decoded in the input's order; lossless: positions bit "
      "for bit, with allow_nonfinite NaN and infinities too)");
  m.def(
      "encode_mapped",
      [](const tsm::Mesh& mesh, int quantization_bits, int level, uint32_t segment_faces, int threads, bool keep_order,
         bool lossless, bool allow_nonfinite) {
        tsm::EncodeMapping map;
        const std::string out = encode_released(
            mesh, encode_options(quantization_bits, level, segment_faces, threads, keep_order, lossless, allow_nonfinite),
            &map);
        py::dict d;
        d["vertex_from"] = to_array(map.vertex_from, 1);
        d["face_from"] = to_array(map.face_from, 1);
        d["first_corner"] = to_array(map.first_corner, 1);
        return py::make_tuple(py::bytes(out), d);
      },
      py::arg("mesh"), py::kw_only(), py::arg("quantization_bits") = tsm::kDefaultQuantizationBits,
      py::arg("level") = tsm::kDefaultLevel, py::arg("segment_faces") = 0, py::arg("threads") = 0,
      py::arg("keep_order") = false, py::arg("lossless") = false, py::arg("allow_nonfinite") = false,
      "As encode, and where the decoded mesh comes from in the input: (bytes, {'vertex_from', 'face_from', "
      "'first_corner'}): decoded vertex v is input vertex vertex_from[v], decoded face f input face face_from[f] "
      "starting at its corner first_corner[f]");
  m.def(
      "encode",
      [](const py::handle& positions, const py::handle& faces, const py::handle& attributes, int quantization_bits,
         int level, uint32_t segment_faces, int threads, bool keep_order, bool lossless, bool allow_nonfinite) {
        tsm::Mesh mesh = make_mesh(positions, faces, py::none());
        if (!attributes.is_none()) {
          for (auto item : py::reinterpret_borrow<py::dict>(attributes)) {
            std::string name = py::str(item.first);
            std::string kind = name == "normal" || name == "color" || name == "texcoord" ? name : "generic";
            add_attribute(mesh, name, item.second, kind, "vertex", "f32", py::none());
          }
        }
        return py::bytes(encode_released(
            mesh, encode_options(quantization_bits, level, segment_faces, threads, keep_order, lossless, allow_nonfinite)));
      },
      py::arg("positions"), py::arg("faces"), py::arg("attributes") = py::none(), py::kw_only(),
      py::arg("quantization_bits") = tsm::kDefaultQuantizationBits, py::arg("level") = tsm::kDefaultLevel,
      py::arg("segment_faces") = 0, py::arg("threads") = 0, py::arg("keep_order") = false, py::arg("lossless") = false,
      py::arg("allow_nonfinite") = false,
      "Encodes positions (N,3) and faces (M,k), with optional per-vertex attributes {name: (N,c) array} "
      "('normal', 'color', 'texcoord' by name, others generic)");

  m.def(
      "decode",
      [](py::buffer data, int threads, uint64_t max_vertices, uint64_t max_faces) {
        py::buffer_info b = data.request();
        tsm::DecodeOptions o;
        o.threads = threads;
        o.max_vertices = max_vertices;
        o.max_faces = max_faces;
        tsm::Mesh mesh;
        {
          py::gil_scoped_release release;
          check(tsm::decode(view_of(b), mesh, o));
        }
        return mesh;
      },
      py::arg("data"), py::kw_only(), py::arg("threads") = 0, py::arg("max_vertices") = 0, py::arg("max_faces") = 0,
      "Decodes .tsm bytes into a Mesh");

  py::class_<tsm::StreamDecoder>(m, "StreamDecoder",
                                 "Decodes while the bytes arrive: feed() chunks of any size; each segment is "
                                 "decoded as soon as its bytes are in and mesh grows (segment k's vertices and "
                                 "faces after those of the segments before it)")
      .def(py::init([](int threads, uint64_t max_vertices, uint64_t max_faces) {
             tsm::DecodeOptions o;
             o.threads = threads;
             o.max_vertices = max_vertices;
             o.max_faces = max_faces;
             return std::make_unique<tsm::StreamDecoder>(o);
           }),
           py::kw_only(), py::arg("threads") = 0, py::arg("max_vertices") = 0, py::arg("max_faces") = 0)
      .def(
          "feed",
          [](tsm::StreamDecoder& d, py::buffer chunk) {
            py::buffer_info b = chunk.request();
            py::gil_scoped_release release;
            check(d.feed(view_of(b)));
          },
          py::arg("chunk"), "Adds bytes; raises tsmcodec.Error when they are not a valid .tsm stream")
      .def(
          "finish",
          [](tsm::StreamDecoder& d) {
            py::gil_scoped_release release;
            check(d.finish());
          },
          "The input is over: raises tsmcodec.Error unless the whole file was decoded")
      .def_property_readonly("segment_count", &tsm::StreamDecoder::segment_count, "0 until the header is in")
      .def_property_readonly("segments_done", &tsm::StreamDecoder::segments_done)
      .def_property_readonly("done", &tsm::StreamDecoder::done, "the end marker was read, no error")
      .def_property_readonly(
          "mesh", [](const tsm::StreamDecoder& d) { return d.mesh(); },
          "a copy of the mesh decoded so far (the segments done)")
      .def("take_mesh", &tsm::StreamDecoder::take_mesh, "moves the decoded mesh out (call when done)");

  m.def(
      "read",
      [](const std::string& path) {
        tsm::Mesh mesh;
        {
          py::gil_scoped_release release;
          check(tsm::read_mesh(path, mesh));
        }
        return mesh;
      },
      py::arg("path"), "Reads a PLY, OBJ, STL, OFF or glTF/GLB file into a Mesh (format from content, then extension)");
  m.def(
      "write",
      [](const std::string& path, const tsm::Mesh& mesh, bool ascii) {
        tsm::WriteOptions o;
        o.ascii = ascii;
        py::gil_scoped_release release;
        check(tsm::write_mesh(path, mesh, o));
      },
      py::arg("path"), py::arg("mesh"), py::kw_only(), py::arg("ascii") = false,
      "Writes a Mesh by extension (.ply, .obj, .stl, .off, .gltf, .glb)");

  m.def(
      "simplify",
      [](const tsm::Mesh& mesh, double max_error, double max_error_percent, uint64_t faces, double ratio) {
        if (max_error < 0 || max_error_percent < 0 || ratio < 0 || ratio > 1)
          throw py::value_error("max_error and max_error_percent must be >= 0, ratio within [0, 1]");
        if (max_error > 0 && max_error_percent > 0)
          throw py::value_error("give max_error (model units) or max_error_percent (of the diagonal), not both");
        if (max_error == 0 && max_error_percent == 0 && faces == 0 && ratio == 0)
          throw py::value_error("say how far to simplify: max_error, max_error_percent, faces or ratio");
        tsm::SimplifyOptions o;
        o.max_error = max_error > 0 ? max_error : max_error_percent * tsm::bounding_box(mesh).diagonal() / 100;
        o.target_faces = faces;
        if (ratio > 0) {
          uint64_t triangles = 0;
          for (size_t f = 0; f < mesh.face_count(); ++f)
            triangles += mesh.face_size(f) >= 3 ? mesh.face_size(f) - 2 : 0;
          o.target_faces = std::max<uint64_t>(o.target_faces, static_cast<uint64_t>(std::llround(
                                                                  ratio * static_cast<double>(triangles))));
        }
        tsm::Mesh out;
        tsm::SimplifyReport r;
        {
          py::gil_scoped_release release;
          check(tsm::simplify(mesh, o, out, &r));
        }
        return out;
      },
      py::arg("mesh"), py::kw_only(), py::arg("max_error") = 0.0, py::arg("max_error_percent") = 0.0,
      py::arg("faces") = 0, py::arg("ratio") = 0.0,
      "Simplifies a Mesh: collapses while the symmetric Hausdorff distance to the input stays within max_error "
      "(model units) or max_error_percent (of the bounding-box diagonal), guaranteed; faces / ratio stop earlier");
  m.def(
      "distance",
      [](const tsm::Mesh& a, const tsm::Mesh& b, uint64_t samples) {
        tsm::DistanceOptions o;
        o.target_samples = samples;
        tsm::DistanceReport r;
        {
          py::gil_scoped_release release;
          check(tsm::measure_distance(a, b, o, r));
        }
        auto side = [](const tsm::OneSidedDistance& s) {
          py::dict d;
          d["max"] = s.max;
          d["bound"] = s.bound;
          d["mean"] = s.mean;
          d["rms"] = s.rms;
          d["samples"] = s.samples;
          return d;
        };
        py::dict d;
        d["hausdorff"] = r.hausdorff;
        d["hausdorff_bound"] = r.hausdorff_bound;
        d["diagonal"] = r.diagonal;
        d["a_to_b"] = side(r.a_to_b);
        d["b_to_a"] = side(r.b_to_a);
        d["spacing"] = r.spacing;
        d["area_a"] = r.area_a;
        d["area_b"] = r.area_b;
        d["volume_a"] = r.volume_a;
        d["volume_b"] = r.volume_b;
        d["normal_mean_deg"] = r.normal_mean_deg;
        d["normal_max_deg"] = r.normal_max_deg;
        return d;
      },
      py::arg("a"), py::arg("b"), py::kw_only(), py::arg("samples") = 1000000,
      "Metro-style distances between two meshes as a dict (what `tsm compare` prints): symmetric Hausdorff "
      "distance (sampled, and a guaranteed upper bound), one-sided max/mean/RMS, areas, volumes, normal "
      "deviation; diagonal is A's bounding-box diagonal");

  m.def(
      "info",
      [](py::buffer data) {
        py::buffer_info b = data.request();
        tsm::FileInfo fi;
        {
          py::gil_scoped_release release;
          check(tsm::inspect(view_of(b), fi));
        }
        py::dict d;
        d["format_version"] = fi.format_version;
        d["vertex_count"] = fi.vertex_count;
        d["face_count"] = fi.face_count;
        d["corner_count"] = fi.corner_count;
        d["quantization_bits"] = fi.quantization_bits;
        d["level"] = fi.level;
        d["segment_count"] = fi.segment_count;
        d["file_bytes"] = fi.file_bytes;
        d["connectivity_bytes"] = fi.connectivity_bytes;
        d["geometry_bytes"] = fi.geometry_bytes;
        d["attribute_bytes"] = fi.attribute_bytes;
        py::list attrs;
        for (const auto& a : fi.attributes) {
          py::dict ad;
          ad["name"] = a.name;
          ad["kind"] = kind_name(a.kind);
          ad["domain"] = domain_name(a.domain);
          ad["components"] = a.components;
          ad["coding"] = a.coding;
          ad["bits"] = a.bits;
          attrs.append(ad);
        }
        d["attributes"] = attrs;
        return d;
      },
      py::arg("data"), "What a .tsm file holds (counts, options, sizes), as a dict");
}

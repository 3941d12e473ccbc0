// `tsm bench`: tsm beside Draco (cl7, cl10) on each mesh, in one process:
// sizes, bits per vertex, encode/decode medians (tsm on one thread against
// Draco, which has none; tsm on every core in extra columns), maximum error,
// exactness of each round trip (the oracle; Draco's on the grid Draco used),
// and reader speed (tsm's reader vs Draco's). glTF files get a table of
// their own (bench_assets.cpp): whole assets through tsm, Draco and gltfpack.
#include <nlohmann/json.hpp>

#include <stdlib.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include "bench_assets.hpp"
#include "bench_attribute_files.hpp"
#include "bench_draco.hpp"
#include "bench_simplify.hpp"
#include "bench_timing.hpp"
#include "cli_util.hpp"
#include "tsm/compare.hpp"
#include "tsm/io.hpp"
#include "tsm/tsm.hpp"

namespace tsm::cli {

namespace {

using tsm::bench::median;

struct Row {
  std::string mesh;
  size_t vertices = 0, faces = 0;
  int q = 0;
  size_t tsm_bytes = 0;
  double tsm_enc = 0, tsm_dec = 0, tsm_err = 0;  // one thread
  double tsm_enc_mt = -1, tsm_dec_mt = -1;       // every core (-1: one core only)
  bool tsm_exact = false;
  std::string tsm_diff;
  bench::DracoRun cl10, cl7;
  bool draco_exact = false;
  std::string draco_diff;  // why Draco's round trip is not exact
};

struct ReadRow {
  std::string mesh;
  double tsm_ms = 0, draco_ms = -1;
  std::string draco_error;
};

std::vector<std::string> default_meshes() {
  std::vector<std::string> out;
  std::string dir = default_corpus_dir();
  if (!dir.empty()) {
    for (const char* name :
         {"bun_zipper.ply", "dragon_vrip_res4.ply", "dragon_vrip_res3.ply", "dragon_vrip_res2.ply", "dragon_vrip.ply"})
      if (std::filesystem::exists(dir + "/" + name)) out.push_back(dir + "/" + name);
    // Then Draco's edge-case files, by name (those no reader takes are listed as failures).
    std::vector<std::string> edge;
    std::error_code ec;
    for (const auto& e : std::filesystem::directory_iterator(dir + "/edge", ec))
      if (e.is_regular_file()) edge.push_back(e.path().string());
    std::sort(edge.begin(), edge.end());
    out.insert(out.end(), edge.begin(), edge.end());
    // The real glTF assets (those already compressed by Draco are left out:
    // gltfpack does not read them).
    std::vector<std::string> assets;
    for (const auto& e : std::filesystem::recursive_directory_iterator(dir + "/assets", ec)) {
      const std::string p = e.path().string();
      if (e.is_regular_file() && is_gltf_path(p) && p.find("Draco") == std::string::npos) assets.push_back(p);
    }
    std::sort(assets.begin(), assets.end());
    out.insert(out.end(), assets.begin(), assets.end());
  }
  if (out.empty()) {
    std::string m = default_mesh_path();
    if (!m.empty()) out.push_back(m);
  }
  return out;
}

// A generated mesh (UV sphere) when no file is at hand.
Mesh generated_sphere(int rings, int segments) {
  Mesh m;
  m.add_vertex(0, 0, 1);
  for (int r = 1; r < rings; ++r)
    for (int s = 0; s < segments; ++s) {
      double th = 3.141592653589793 * r / rings, ph = 2 * 3.141592653589793 * s / segments;
      m.add_vertex(static_cast<float>(std::sin(th) * std::cos(ph)), static_cast<float>(std::sin(th) * std::sin(ph)),
                   static_cast<float>(std::cos(th)));
    }
  m.add_vertex(0, 0, -1);
  auto id = [&](int r, int s) { return static_cast<uint32_t>(1 + (r - 1) * segments + (s % segments)); };
  uint32_t south = static_cast<uint32_t>(m.vertex_count() - 1);
  for (int s = 0; s < segments; ++s) m.add_triangle(0, id(1, s), id(1, s + 1));
  for (int r = 1; r + 1 < rings; ++r)
    for (int s = 0; s < segments; ++s) {
      m.add_triangle(id(r, s), id(r + 1, s), id(r + 1, s + 1));
      m.add_triangle(id(r, s), id(r + 1, s + 1), id(r, s + 1));
    }
  for (int s = 0; s < segments; ++s) m.add_triangle(south, id(rings - 1, s + 1), id(rings - 1, s));
  return m;
}

}  // namespace

int run_bench(const std::vector<std::string>& meshes_in, bool json, const std::vector<int>& qbits, int runs, int level,
              bool quiet, bool browser, const std::vector<double>& simplify_bounds) {
  std::vector<std::string> meshes = meshes_in.empty() ? default_meshes() : with_folders_expanded(meshes_in);
  std::vector<Row> rows;
  std::vector<ReadRow> reads;
  std::vector<AssetRow> assets;
  std::vector<AttributeFileRow> attribute_files;
  std::vector<SimplifyRow> simplified;
  // The compressed glTF files, kept until the browser has decoded them.
  std::string work_dir = (std::filesystem::temp_directory_path() / "tsm-bench-XXXXXX").string();
  if (!mkdtemp(work_dir.data())) work_dir = ".";
  struct RemoveAtExit {
    std::string dir;
    ~RemoveAtExit() {
      std::error_code ec;
      if (dir != ".") std::filesystem::remove_all(dir, ec);
    }
  } remove_work_dir{work_dir};
  std::vector<std::string> failures;
  const bool have_draco = bench::draco_available();
  const int cores = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  if (meshes.empty() && !quiet)
    std::fprintf(stderr, "tsm bench: no corpus and no default mesh found; using a generated sphere\n");
  std::vector<std::string> names = meshes.empty() ? std::vector<std::string>{"(generated sphere)"} : meshes;

  for (const std::string& path : names) {
    Mesh mesh;
    ReadRow rr;
    rr.mesh = std::filesystem::path(path).filename().string();
    if (meshes.empty()) {
      mesh = generated_sphere(200, 400);
    } else {
      if (!quiet) std::fprintf(stderr, "tsm bench: reading %s\n", path.c_str());
      Stopwatch sw;
      Status s = read_mesh(path, mesh);
      rr.tsm_ms = sw.ms();
      if (!s.ok()) {
        failures.push_back(s.message());
        std::fprintf(stderr, "tsm bench: skipped: %s\n", printable(s.message()).c_str());
        continue;
      }
      if (has_common_attributes(mesh))
        for (int q : qbits) {
          attribute_files.push_back(bench_attribute_file(path, mesh, q, level, quiet, work_dir));
          const AttributeFileRow& a = attribute_files.back();
          if (!a.error.empty()) failures.push_back(rr.mesh + ": with attributes: " + a.error);
          else if (!a.tsm_exact) failures.push_back(rr.mesh + ": with attributes: round trip not exact");
        }
      // Positions and faces only from here, as the in-process Draco adapter codes them.
      mesh.attributes.clear();
      if (have_draco && gltf_has_node_cycle(path)) {
        rr.draco_ms = -1;
        rr.draco_error = "not read: its nodes form a cycle, on which Draco's glTF reader recurses until the stack overflows";
      } else if (have_draco) {
        size_t v = 0, f = 0;
        if (!bench::draco_read(path, rr.draco_ms, v, f, rr.draco_error)) rr.draco_ms = -1;
      }
      reads.push_back(rr);
      if (is_gltf_path(path)) {
        for (int q : qbits) {
          assets.push_back(bench_asset(path, q, level, runs, quiet, work_dir));
          if (!assets.back().tsm.ok) failures.push_back(rr.mesh + ": " + assets.back().tsm.error);
        }
        continue;
      }
    }
    for (int q : qbits) {
      Row row;
      row.mesh = rr.mesh;
      row.vertices = mesh.vertex_count();
      row.faces = mesh.face_count();
      row.q = q;
      if (!quiet) std::fprintf(stderr, "tsm bench: %s q=%d: tsm\n", rr.mesh.c_str(), q);
      EncodeOptions eo;
      eo.quantization_bits = q;
      eo.level = level;
      eo.threads = 1;
      DecodeOptions dopt;
      dopt.threads = 1;
      std::string bytes;
      std::vector<double> et, dt;
      Status s;
      Mesh back;
      // Medians of `runs` encodes, then decodes, of `bytes` with `threads`.
      auto time_runs = [&](int threads, double& enc_ms, double& dec_ms) {
        eo.threads = dopt.threads = threads;
        et.clear();
        dt.clear();
        for (int i = 0; i < runs && s.ok(); ++i) {
          Stopwatch sw;
          s = encode(mesh, eo, bytes);
          et.push_back(sw.ms());
        }
        if (!s.ok()) {
          failures.push_back(rr.mesh + ": encode: " + s.message());
          return false;
        }
        for (int i = 0; i < runs && s.ok(); ++i) {
          Stopwatch sw;
          s = decode(bytes, back, dopt);
          dt.push_back(sw.ms());
        }
        if (!s.ok()) {
          failures.push_back(rr.mesh + ": decode: " + s.message());
          return false;
        }
        enc_ms = median(et);
        dec_ms = median(dt);
        return true;
      };
      if (cores > 1 && !time_runs(cores, row.tsm_enc_mt, row.tsm_dec_mt)) continue;
      if (!time_runs(1, row.tsm_enc, row.tsm_dec)) continue;
      row.tsm_bytes = bytes.size();
      CompareResult cr = compare_meshes(mesh, back, q);
      row.tsm_exact = cr.equal;
      row.tsm_diff = cr.difference;
      row.tsm_err = cr.max_position_error;
      if (have_draco) {
        if (!quiet) std::fprintf(stderr, "tsm bench: %s q=%d: Draco cl10, cl7\n", rr.mesh.c_str(), q);
        row.cl10 = bench::draco_roundtrip(mesh, q, 10, runs);
        row.cl7 = bench::draco_roundtrip(mesh, q, 7, runs);
        // On Draco's own grid (its float quantization can put a vertex
        // one step from where tsm's grid does): its indices compared exactly.
        if (row.cl10.ok) {
          const CompareResult dr = compare_meshes(bench::draco_grid(mesh, q), row.cl10.decoded_grid, 0);
          row.draco_exact = dr.equal;
          row.draco_diff = dr.difference;
        }
        row.cl10.decoded_grid = Mesh();
        row.cl7.decoded_grid = Mesh();
      }
      rows.push_back(std::move(row));
    }
    for (double pct : simplify_bounds) {
      simplified.push_back(bench_simplify(mesh, rr.mesh, pct, quiet));
      if (!simplified.back().error.empty()) failures.push_back(rr.mesh + ": " + simplified.back().error);
    }
  }

  if (browser && !assets.empty()) {
    if (!quiet) std::fprintf(stderr, "tsm bench: the glTF files in headless Chromium\n");
    std::string why;
    if (!browser_times(assets, work_dir, runs, why)) failures.push_back("--browser: " + why);
  }
  auto bpv = [](size_t bytes, size_t v) { return v ? 8.0 * static_cast<double>(bytes) / static_cast<double>(v) : 0.0; };
  if (json) {
    // Built with the JSON library: a mesh name that is not UTF-8 still gives valid JSON (U+FFFD).
    using ojson = nlohmann::ordered_json;
    auto rounded = [](double v, double scale) {
      return std::isfinite(v) ? ojson(std::round(v * scale) / scale) : ojson();
    };
    ojson doc = ojson::object();
    doc["draco"] = have_draco;
    doc["threads"] = 1;    // tsm_encode_ms and tsm_decode_ms: one thread, as Draco
    doc["cores"] = cores;  // the *_all_cores timings: this many threads
    doc["rows"] = ojson::array();
    for (const Row& r : rows) {
      ojson o = ojson::object();
      o["mesh"] = r.mesh;
      o["vertices"] = r.vertices;
      o["faces"] = r.faces;
      o["q"] = r.q;
      o["tsm_bytes"] = r.tsm_bytes;
      o["tsm_bpv"] = rounded(bpv(r.tsm_bytes, r.vertices), 1e4);
      o["tsm_encode_ms"] = rounded(r.tsm_enc, 1e3);
      o["tsm_decode_ms"] = rounded(r.tsm_dec, 1e3);
      if (r.tsm_enc_mt >= 0) {
        o["tsm_encode_ms_all_cores"] = rounded(r.tsm_enc_mt, 1e3);
        o["tsm_decode_ms_all_cores"] = rounded(r.tsm_dec_mt, 1e3);
      }
      o["tsm_exact"] = r.tsm_exact;
      o["tsm_max_error_steps"] = rounded(r.tsm_err, 1e4);
      for (const auto& [name, d] :
           {std::pair<std::string, const bench::DracoRun*>{"draco_cl10", &r.cl10}, {"draco_cl7", &r.cl7}})
        if (d->ok) {
          o[name + "_bytes"] = d->bytes;
          o[name + "_bpv"] = rounded(bpv(d->bytes, r.vertices), 1e4);
          o[name + "_encode_ms"] = rounded(d->encode_ms, 1e3);
          o[name + "_decode_ms"] = rounded(d->decode_ms, 1e3);
        }
      if (have_draco) o["draco_cl10_exact"] = r.draco_exact;
      doc["rows"].push_back(std::move(o));
    }
    doc["reads"] = ojson::array();
    for (const ReadRow& r : reads)
      doc["reads"].push_back(
          {{"mesh", r.mesh}, {"tsm_ms", rounded(r.tsm_ms, 1e3)}, {"draco_ms", rounded(r.draco_ms, 1e3)}});
    doc["assets"] = asset_rows_json(assets);
    doc["attribute_files"] = attribute_file_rows_json(attribute_files);
    if (!simplify_bounds.empty()) doc["simplify"] = simplify_rows_json(simplified);
    doc["failures"] = failures.size();
    std::printf("%s\n", doc.dump(2, ' ', false, ojson::error_handler_t::replace).c_str());
    return failures.empty() ? kExitOk : kExitBadInput;
  }

  if (!rows.empty() || assets.empty()) {
    std::printf("Times: medians of %d run%s, ms; tsm on one thread against Draco (which has no threads)", runs,
                runs == 1 ? "" : "s");
    if (cores > 1) std::printf("; the last two columns: tsm with %d threads (segments in parallel)", cores);
    std::printf(".\n\n");
    std::printf(
        "| mesh | V | q | tsm bytes | tsm bits/v | Draco cl10 bytes | cl10 bits/v | Draco cl7 bytes | tsm/cl10 "
        "| tsm enc ms | tsm dec ms | cl10 enc ms | cl10 dec ms | enc tsm/cl10 | dec tsm/cl10 | max err (steps) "
        "| exact: tsm | exact: Draco |");
    if (cores > 1) std::printf(" tsm enc ms, %d thr | tsm dec ms, %d thr |", cores, cores);
    std::printf("\n|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|---|%s\n",
                cores > 1 ? "---:|---:|" : "");
    for (const Row& r : rows) {
      auto dbytes = [](const bench::DracoRun& d) { return d.ok ? thousands(d.bytes) : std::string("-"); };
      auto ratio = [](double a, double b) { return b > 0 ? fixed(a / b, 2) : std::string("-"); };
      std::printf(
          "| %s | %s | %d | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s |", r.mesh.c_str(),
          thousands(r.vertices).c_str(), r.q, thousands(r.tsm_bytes).c_str(),
          fixed(bpv(r.tsm_bytes, r.vertices), 2).c_str(), dbytes(r.cl10).c_str(),
          r.cl10.ok ? fixed(bpv(r.cl10.bytes, r.vertices), 2).c_str() : "-", dbytes(r.cl7).c_str(),
          r.cl10.ok ? fixed(static_cast<double>(r.tsm_bytes) / static_cast<double>(r.cl10.bytes), 3).c_str() : "-",
          fixed(r.tsm_enc, 1).c_str(), fixed(r.tsm_dec, 1).c_str(),
          r.cl10.ok ? fixed(r.cl10.encode_ms, 1).c_str() : "-", r.cl10.ok ? fixed(r.cl10.decode_ms, 1).c_str() : "-",
          r.cl10.ok ? ratio(r.tsm_enc, r.cl10.encode_ms).c_str() : "-",
          r.cl10.ok ? ratio(r.tsm_dec, r.cl10.decode_ms).c_str() : "-", fixed(r.tsm_err, 3).c_str(),
          r.tsm_exact ? "yes" : "NO", have_draco ? (r.draco_exact ? "yes" : "no") : "-");
      if (cores > 1) std::printf(" %s | %s |", fixed(r.tsm_enc_mt, 1).c_str(), fixed(r.tsm_dec_mt, 1).c_str());
      std::printf("\n");
    }
  }
  if (!assets.empty()) print_asset_table(assets, browser);
  if (!attribute_files.empty()) print_attribute_file_table(attribute_files);
  if (!simplified.empty()) print_simplify_table(simplified);
  if (!reads.empty()) {
    std::printf("\n| mesh | tsm read ms | Draco read ms | Draco/tsm |\n|---|---:|---:|---:|\n");
    for (const ReadRow& r : reads)
      std::printf("| %s | %s | %s | %s |\n", r.mesh.c_str(), fixed(r.tsm_ms, 1).c_str(),
                  r.draco_ms >= 0 ? fixed(r.draco_ms, 1).c_str() : "-",
                  r.draco_ms >= 0 && r.tsm_ms > 0 ? fixed(r.draco_ms / r.tsm_ms, 2).c_str() : "-");
  }
  if (!have_draco) std::printf("\nDraco is not built in: install libdraco-dev and reconfigure for its columns.\n");
  for (const Row& r : rows)
    if (!r.tsm_exact) std::printf("\n%s q=%d: round trip NOT exact: %s\n", r.mesh.c_str(), r.q, r.tsm_diff.c_str());
  for (const Row& r : rows)
    if (r.cl10.ok && !r.draco_exact)
      std::printf("\n%s q=%d: Draco cl10's round trip, on its grid, is not exact: %s\n", r.mesh.c_str(), r.q,
                  r.draco_diff.c_str());
  for (const std::string& f : failures) std::printf("\nfailed: %s\n", f.c_str());
  return failures.empty() ? kExitOk : kExitBadInput;
}

}  // namespace tsm::cli

// tsm simplify: error-bounded mesh reduction (tsm/simplify.hpp), written in
// any format tsm writes, or as .tsm.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "batch.hpp"
#include "cli_util.hpp"
#include "mesh_commands.hpp"
#include "tsm/io.hpp"
#include "tsm/simplify.hpp"
#include "tsm/tsm.hpp"

namespace tsm::cli {

bool parse_max_error(const std::string& text, double& value, bool& percent) {
  if (text.empty()) return false;
  percent = text.back() == '%';
  const std::string num = percent ? text.substr(0, text.size() - 1) : text;
  char* end = nullptr;
  value = std::strtod(num.c_str(), &end);
  return !num.empty() && end && *end == '\0' && std::isfinite(value) && value > 0;
}

namespace {

struct ProgressState {
  Stopwatch sw;
  double last_ms = 0;
  bool shown = false;
};

// After half a second, at most ten times a second.
void draw_progress(uint64_t now, uint64_t in, void* user) {
  auto* p = static_cast<ProgressState*>(user);
  const double ms = p->sw.ms();
  if (ms < 500 || ms - p->last_ms < 100) return;
  p->last_ms = ms;
  std::fprintf(stderr, "\rsimplifying: %s of %s triangles  %.1f s\x1b[K", thousands(now).c_str(), thousands(in).c_str(),
               p->sw.ms() / 1000.0);
  std::fflush(stderr);
  p->shown = true;
}

}  // namespace

Status simplify_for_cli(const Mesh& in, const std::string& max_error, uint64_t faces, double ratio, bool progress,
                        Mesh& out, SimplifyReport& report, double& error_units, double reserve) {
  SimplifyOptions o;
  error_units = 0;
  if (!max_error.empty()) {
    bool percent = false;
    if (!parse_max_error(max_error, error_units, percent))
      return Status(ErrorCode::invalid_argument, "--max-error " + max_error +
                                                     ": give a positive number in model units, or a percentage of the "
                                                     "bounding-box diagonal such as 0.5%");
    if (percent) error_units *= bounding_box(in).diagonal() / 100;
    if (!(error_units > reserve))
      return Status(ErrorCode::invalid_argument, "--max-error " + max_error +
                                                     " is below the error the quantization "
                                                     "alone causes (" +
                                                     strf("%.3g", reserve) + "): raise it or -q");
    o.max_error = error_units - reserve;
  }
  uint64_t triangles = 0;
  for (size_t f = 0; f < in.face_count(); ++f) triangles += in.face_size(f) >= 3 ? in.face_size(f) - 2 : 0;
  if (faces > 0) o.target_faces = faces;
  if (ratio > 0)
    o.target_faces =
        std::max<uint64_t>(o.target_faces, static_cast<uint64_t>(std::llround(ratio * static_cast<double>(triangles))));
  ProgressState ps;
  if (progress && is_terminal(stderr)) {
    o.progress = draw_progress;
    o.progress_user = &ps;
  }
  Status s = simplify(in, o, out, &report);
  if (ps.shown) std::fputs("\r\x1b[K", stderr);
  return s;
}

int cmd_simplify(const SimplifyArgs& a) {
  if (a.max_error.empty() && a.faces == 0 && a.ratio <= 0) {
    std::fprintf(stderr,
                 "tsm: error: say how far to simplify: --max-error E (model units, or E%% of the diagonal), "
                 "--faces N or --ratio R\n");
    return kExitUsage;
  }
  if (!a.force && std::filesystem::exists(a.output)) {
    std::fprintf(stderr, "tsm: error: %s exists; pass -f to replace it\n", printable(a.output).c_str());
    return kExitIo;
  }
  const MeshFormat format = format_from_extension(a.output);
  const bool to_tsm = a.output.size() >= 4 && a.output.compare(a.output.size() - 4, 4, ".tsm") == 0;
  if (format == MeshFormat::unknown && !to_tsm) {
    std::fprintf(stderr,
                 "tsm: error: %s: the name does not say which format to write; end it in .ply, .obj, .stl, "
                 ".off, .gltf, .glb or .tsm\n",
                 printable(a.output).c_str());
    return kExitUsage;
  }
  Mesh in, out;
  Status s = load_any_mesh(a.input, in);
  if (!s.ok()) {
    std::fprintf(stderr, "tsm: error: %s\n", printable(s.message()).c_str());
    return exit_code_for(s);
  }
  SimplifyReport r;
  double err = 0;
  Stopwatch sw;
  // A .tsm output is quantized (default grid): its share comes off the bound.
  const double reserve =
      to_tsm ? bounding_box(in).largest_extent() / (std::ldexp(1.0, kDefaultQuantizationBits) - 1) * std::sqrt(3.0) / 2
             : 0;
  s = simplify_for_cli(in, a.max_error, a.faces, a.ratio, !a.quiet && !a.json, out, r, err, reserve);
  const double ms = sw.ms();
  if (!s.ok()) {
    std::fprintf(stderr, "tsm: error: %s: %s\n", printable(a.input).c_str(), s.message().c_str());
    return s.code() == ErrorCode::invalid_argument && s.message().find("--max-error") == 0 ? kExitUsage
                                                                                           : exit_code_for(s);
  }
  if (to_tsm) {
    std::string bytes;
    s = encode(out, EncodeOptions{}, bytes);
    if (s.ok()) s = write_file_atomic(a.output, bytes);
  } else {
    s = write_mesh(a.output, out);
  }
  if (!s.ok()) {
    std::fprintf(stderr, "tsm: error: %s\n", printable(s.message()).c_str());
    return exit_code_for(s);
  }
  const double diag = bounding_box(in).diagonal();
  if (a.json) {
    JsonObject j;
    j.str("input", a.input).str("output", a.output);
    j.num("faces_in", static_cast<unsigned long long>(r.faces_in))
        .num("faces_out", static_cast<unsigned long long>(r.faces_out));
    j.num("vertices_in", static_cast<unsigned long long>(r.vertices_in));
    j.num("vertices_out", static_cast<unsigned long long>(r.vertices_out));
    if (err > 0)
      j.num("max_error", err, 9).num("max_error_percent", diag > 0 ? 100 * err / diag : 0.0, 6);
    else
      j.null("max_error").null("max_error_percent");
    j.num("collapses", static_cast<unsigned long long>(r.collapses))
        .num("rejected", static_cast<unsigned long long>(r.rejected));
    j.num("locked_vertices", static_cast<unsigned long long>(r.locked_vertices));
    j.num("ms", ms, 1);
    std::printf("%s\n", j.done().c_str());
  } else if (!a.quiet) {
    std::printf("%s -> %s: %s -> %s triangles (%.2f%%)%s in %s\n", printable(a.input).c_str(),
                printable(a.output).c_str(), thousands(r.faces_in).c_str(), thousands(r.faces_out).c_str(),
                r.faces_in ? 100.0 * static_cast<double>(r.faces_out) / static_cast<double>(r.faces_in) : 0.0,
                err > 0 ? strf(", within %.6g (%.4f%% of the diagonal)", err, 100 * err / diag).c_str() : "",
                duration_text(ms).c_str());
  }
  return kExitOk;
}

}  // namespace tsm::cli

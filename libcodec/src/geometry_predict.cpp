// Geometry prediction and residual coding (seed 004 §3.2, design notes §6).
// Positions are quantized on the Draco grid and visited in decoded vertex
// order (vertex-tree pre-order). Each vertex is predicted from its tree
// parent (the K = 1 case of the paper's ancestor predictor); roots are
// predicted from the previous root. Residuals are coded per axis with an
// adaptive signed-integer model whose context is the magnitude class of the
// parent's own residual on that axis.
#include "geometry_predict.hpp"

#include "connectivity.hpp"
#include "range_coder.hpp"

namespace tsm {

namespace {

constexpr int kClasses = 4;

int magnitude_class(int64_t r) {
  uint64_t a = static_cast<uint64_t>(r < 0 ? -r : r);
  return a == 0 ? 0 : a < 4 ? 1 : a < 64 ? 2 : 3;
}

struct GeometryModels {
  SIntModel axis[3][kClasses];
};

}  // namespace

std::string encode_geometry(const std::vector<uint32_t>& q, const std::vector<uint32_t>& parent, int bits) {
  (void)bits;
  RangeEncoder e;
  GeometryModels gm;
  const size_t n = parent.size();
  std::vector<uint8_t> cls(3 * n, 0);
  size_t prev_root = kNone;
  for (size_t v = 0; v < n; ++v) {
    size_t p = parent[v] != kNone ? parent[v] : prev_root;
    if (parent[v] == kNone) prev_root = v;
    for (int a = 0; a < 3; ++a) {
      int64_t pred = p != kNone ? q[3 * p + a] : 0;
      int64_t r = static_cast<int64_t>(q[3 * v + a]) - pred;
      int ctx = p != kNone ? cls[3 * p + a] : 0;
      gm.axis[a][ctx].encode(e, static_cast<int32_t>(r));
      cls[3 * v + a] = static_cast<uint8_t>(magnitude_class(r));
    }
  }
  return e.finish();
}

Status decode_geometry(const std::string& bytes, const std::vector<uint32_t>& parent, int bits,
                       std::vector<uint32_t>& q) {
  RangeDecoder d(bytes);
  GeometryModels gm;
  const size_t n = parent.size();
  const int64_t qmax = (int64_t{1} << bits) - 1;
  q.resize(3 * n);
  std::vector<uint8_t> cls(3 * n, 0);
  size_t prev_root = kNone;
  for (size_t v = 0; v < n; ++v) {
    if (parent[v] != kNone && parent[v] >= v) return Status(ErrorCode::corrupt_data, "geometry: bad tree parent");
    size_t p = parent[v] != kNone ? parent[v] : prev_root;
    if (parent[v] == kNone) prev_root = v;
    for (int a = 0; a < 3; ++a) {
      int64_t pred = p != kNone ? q[3 * p + a] : 0;
      int ctx = p != kNone ? cls[3 * p + a] : 0;
      int64_t r = gm.axis[a][ctx].decode(d);
      int64_t x = pred + r;
      if (x < 0 || x > qmax) return Status(ErrorCode::corrupt_data, "geometry: coordinate outside the grid");
      q[3 * v + a] = static_cast<uint32_t>(x);
      cls[3 * v + a] = static_cast<uint8_t>(magnitude_class(r));
    }
    if ((v & 1023) == 0 && d.overrun() > RangeDecoder::kMaxOverrun)
      return Status(ErrorCode::corrupt_data, "geometry stream is truncated");
  }
  if (d.overrun() > RangeDecoder::kMaxOverrun) return Status(ErrorCode::corrupt_data, "geometry stream is truncated");
  return Status::Ok();
}

}  // namespace tsm

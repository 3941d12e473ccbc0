// The position grid (tsm/quantization.hpp): the one Draco uses, so sizes
// compare at equal precision.
#include "tsm/quantization.hpp"

#include <cmath>
#include <limits>

namespace tsm {

Grid Grid::for_mesh(const Mesh& mesh, int bits) {
  Grid g;
  g.bits = bits;
  if (bits <= 0) return g;
  BoundingBox box = bounding_box(mesh);
  // + 0.0 makes a -0 minimum +0: the decoder gives back +0 for it (origin
  // + 0 x step), so a decoded file re-encodes to the same bytes.
  for (int a = 0; a < 3; ++a) g.origin[a] = box.min[a] + 0.0;
  double extent = box.largest_extent();
  double cells = std::ldexp(1.0, bits) - 1.0;
  g.step = extent > 0 && std::isfinite(extent) ? extent / cells : 0.0;
  return g;
}

int64_t Grid::quantize(double x, int axis) const {
  if (!std::isfinite(x)) return std::numeric_limits<int64_t>::min();
  if (step <= 0) return 0;
  double q = std::floor((x - origin[axis]) / step + 0.5);
  if (q > 9.0e18) q = 9.0e18;
  if (q < -9.0e18) q = -9.0e18;
  return static_cast<int64_t>(q);
}

double Grid::dequantize(int64_t q, int axis) const { return origin[axis] + static_cast<double>(q) * step; }

}  // namespace tsm

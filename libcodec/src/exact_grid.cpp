// Lossless positions (FORMAT.md §5.1; EncodeOptions::lossless): coordinates
// read from text files are decimals of a few digits (the bunny's
// -0.0378297), so most are exactly the float32 of k x 10^-d for one d. The
// encoder finds the spacing (decimal or binary) whose grid holds the most
// coordinates in the fewest bits, codes the grid indices with the usual
// geometry coder, and lists the coordinates the grid misses (and NaN or
// infinities, when allowed) with their bits in an exceptions section.
#include "exact_grid.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "byte_io.hpp"

namespace tsm {

namespace {

uint32_t bits_of(float x) {
  uint32_t b;
  std::memcpy(&b, &x, 4);
  return b;
}

// The float bits as an integer in the order of the values (-0.0 just below
// +0.0, NaNs beyond the infinities), and back.
int64_t ordered(uint32_t b) { return (b & 0x80000000u) ? int64_t{0x7FFFFFFF} - int64_t{b} : int64_t{b}; }
uint32_t from_ordered(int64_t o) { return static_cast<uint32_t>(o >= 0 ? o : int64_t{0x7FFFFFFF} - o); }

// An exception's correction: the actual float's ordered bits minus its grid value's.
int64_t correction(float actual, float grid) { return ordered(bits_of(actual)) - ordered(bits_of(grid)); }

int zigzag_bits(int64_t d) {
  const uint64_t z = (static_cast<uint64_t>(d) << 1) ^ static_cast<uint64_t>(d >> 63);
  int n = 0;
  for (uint64_t x = z; x; x >>= 1) ++n;
  return n;
}

constexpr double kMaxBase = 4.0e18;  // |base| and |x / step| stay well inside int64

int bit_length(uint64_t x) {
  int n = 0;
  while (x) ++n, x >>= 1;
  return n;
}

// The grid with spacing `step` over the finite coordinates; false when it
// needs more than 30 bits or indices beyond int64.
bool grid_for(const Mesh& mesh, double step, ExactGrid& g) {
  double lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
  for (size_t i = 0; i < mesh.positions.size(); ++i) {
    const double x = mesh.positions[i];
    if (!std::isfinite(x)) continue;
    lo[i % 3] = std::min(lo[i % 3], x);
    hi[i % 3] = std::max(hi[i % 3], x);
  }
  g.step = step;
  uint64_t top = 0;
  for (int a = 0; a < 3; ++a) {
    if (lo[a] > hi[a]) lo[a] = hi[a] = 0;  // no finite coordinate on this axis
    const double b = std::floor(lo[a] / step), t = std::floor(hi[a] / step + 0.5);
    if (!(std::fabs(b) < kMaxBase) || !(std::fabs(t) < kMaxBase)) return false;
    g.base[a] = static_cast<int64_t>(b);
    top = std::max(top, static_cast<uint64_t>(static_cast<int64_t>(t) - g.base[a]));
  }
  g.bits = std::max(1, bit_length(top));
  return g.bits <= 30;
}

// About the bits the exceptions take: a gap byte and the correction's bits.
double exception_bits(const Mesh& mesh, const ExactGrid& g) {
  double n = 0;
  for (size_t i = 0; i < mesh.positions.size(); ++i) {
    const float x = mesh.positions[i];
    const int a = static_cast<int>(i % 3);
    const float v = exact_value(g.step, g.base[a], exact_index(g, x, a));
    if (bits_of(v) != bits_of(x)) n += 10 + zigzag_bits(correction(x, v));
  }
  return n;
}

}  // namespace

float exact_value(double step, int64_t base, uint32_t q) {
  constexpr double kFloatMax = static_cast<double>(std::numeric_limits<float>::max());
  double x = static_cast<double>(base + static_cast<int64_t>(q)) * step;
  x = x > kFloatMax ? kFloatMax : x < -kFloatMax ? -kFloatMax : x;
  return static_cast<float>(x);
}

uint32_t exact_index(const ExactGrid& g, float x, int axis) {
  if (!std::isfinite(x)) return 0;
  const double k = std::floor(static_cast<double>(x) / g.step + 0.5) - static_cast<double>(g.base[axis]);
  const double top = std::ldexp(1.0, g.bits) - 1;
  return static_cast<uint32_t>(k < 0 ? 0 : k > top ? top : k);
}

ExactGrid choose_exact_grid(const Mesh& mesh) {
  std::vector<double> steps = {1.0, 1e-1, 1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12};
  for (int e = -60; e <= 20; ++e) steps.push_back(std::ldexp(1.0, e));
  ExactGrid best;
  double best_cost = HUGE_VAL;
  const double coords = static_cast<double>(mesh.positions.size());
  for (double s : steps) {
    ExactGrid g;
    if (!grid_for(mesh, s, g)) continue;
    const double cost = coords * g.bits + exception_bits(mesh, g);
    if (cost < best_cost) best_cost = cost, best = g;
  }
  if (best_cost == HUGE_VAL) {
    // Coordinates too far apart for 30 bits at any of those spacings: the
    // coarsest power of two that fits, the rest as exceptions.
    for (int e = 21; e <= 1000 && best_cost == HUGE_VAL; ++e)
      if (grid_for(mesh, std::ldexp(1.0, e), best)) best_cost = 0;
  }
  return best;
}

std::string encode_exceptions(const ExactGrid& g, const std::vector<float>& positions) {
  std::string list;
  ByteWriter w(list);
  uint64_t count = 0, last = 0;
  for (size_t i = 0; i < positions.size(); ++i) {
    const float x = positions[i];
    const int a = static_cast<int>(i % 3);
    const float v = exact_value(g.step, g.base[a], exact_index(g, x, a));
    if (bits_of(v) == bits_of(x)) continue;
    const int64_t d = correction(x, v);
    w.varint(i - last);
    w.varint((static_cast<uint64_t>(d) << 1) ^ static_cast<uint64_t>(d >> 63));
    last = i + 1;
    ++count;
  }
  std::string out;
  ByteWriter head(out);
  head.varint(count);
  return out + list;
}

Status apply_exceptions(std::string_view payload, std::vector<float>& positions) {
  auto corrupt = [](const std::string& what) { return Status(ErrorCode::corrupt_data, "exceptions section: " + what); };
  ByteReader r(payload);
  uint64_t count = 0;
  if (!r.varint(count)) return corrupt("the count is cut off");
  if (count > positions.size() || count > r.remaining() / 2)
    return corrupt("more exceptions than coordinates or bytes");
  uint64_t at = 0;
  for (uint64_t k = 0; k < count; ++k) {
    uint64_t gap = 0, z = 0;
    if (!r.varint(gap) || !r.varint(z)) return corrupt("cut off");
    if (gap >= positions.size() - at) return corrupt("a coordinate past the last vertex");
    at += gap;
    const int64_t d = static_cast<int64_t>(z >> 1) ^ -static_cast<int64_t>(z & 1);
    const int64_t o = ordered(bits_of(positions[at]));
    if (d < int64_t{-0x80000000LL} - o || d > int64_t{0x7FFFFFFF} - o) return corrupt("a correction past the floats");
    const uint32_t b = from_ordered(o + d);
    std::memcpy(&positions[at], &b, 4);
    ++at;
  }
  if (r.remaining() != 0) return corrupt("bytes after the last exception");
  return Status::Ok();
}

}  // namespace tsm

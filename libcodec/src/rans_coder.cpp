// Static per-context tables with interleaved rANS: see rans_coder.hpp
// (entropy coding stage; FORMAT.md §8.5.12).
#include "rans_coder.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>

#include "byte_io.hpp"

namespace tsm {

RansDecoder::SymbolTable::SymbolTable() : s() {
  for (int k = 0; k < kRansSymbols; ++k) {
    if (k <= 2 * kRansDirect) {
      const int r = k - kRansDirect;
      s[k] = {static_cast<uint32_t>(r < 0 ? -r : r), 0, static_cast<uint8_t>(r < 0)};
      continue;
    }
    const int m = k - (2 * kRansDirect + 1), n = m / 8 + 4, t = m & 3;
    s[k] = {static_cast<uint32_t>(4 | t) << (n - 3), static_cast<uint8_t>(n - 3), static_cast<uint8_t>((m >> 2) & 1)};
  }
}
const RansDecoder::SymbolTable RansDecoder::kInfo;

namespace {

// A frequency as the tables store it: its bit length e, then the (up to)
// two bits below its leading one; lower bits are zero.
int exponent_of(uint32_t f) { return bit_length(f); }
int mantissa_bits(int e) { return std::min(e - 1, 2); }
uint32_t representable_below(uint32_t f) {  // the largest storable value <= f (f >= 1)
  const int e = exponent_of(f), drop = e - 1 - mantissa_bits(e);
  return (f >> drop) << drop;
}
uint32_t representable_above(uint32_t f) {  // the smallest storable value >= f (f <= 4095)
  const uint32_t b = representable_below(f);
  if (b == f) return f;
  const int e = exponent_of(f), drop = e - 1 - mantissa_bits(e);
  return b + (1u << drop);
}

// The most frequent symbol (the first on a tie): its frequency is implied.
int implied_symbol(const std::array<uint32_t, kRansSymbols>& c) {
  return static_cast<int>(std::max_element(c.begin(), c.end()) - c.begin());
}

// Frequencies summing to 4096, every counted symbol at least 1, every one
// but the implied symbol storable; near count * 4096 / total.
std::vector<uint16_t> normalize(const std::array<uint32_t, kRansSymbols>& c, uint64_t total, int top) {
  int used = kRansSymbols;
  while (used > 0 && c[static_cast<size_t>(used - 1)] == 0) --used;
  std::vector<uint32_t> f(static_cast<size_t>(used), 0);
  uint32_t sum = 0;
  for (int s = 0; s < used; ++s) {
    if (s == top || c[static_cast<size_t>(s)] == 0) continue;
    const double ideal = static_cast<double>(c[static_cast<size_t>(s)]) * kRansScale / static_cast<double>(total);
    uint32_t x = std::max<uint32_t>(1, static_cast<uint32_t>(std::lround(ideal)));
    x = std::min<uint32_t>(x, kRansScale - 1);
    const uint32_t lo = representable_below(x), hi = representable_above(x);
    f[static_cast<size_t>(s)] = (ideal - lo <= hi - ideal || hi >= kRansScale) ? lo : hi;
    sum += f[static_cast<size_t>(s)];
  }
  // The implied symbol takes the rest; while that is not at least 1, the
  // largest other frequency steps down to the next storable value.
  while (sum >= kRansScale) {
    size_t j = 0;
    for (size_t s = 0; s < f.size(); ++s)
      if (static_cast<int>(s) != top && f[s] > f[j]) j = s;
    const uint32_t down = representable_below(f[j] - 1);
    sum -= f[j] - down;
    f[j] = down;
  }
  f[static_cast<size_t>(top)] = kRansScale - sum;
  return std::vector<uint16_t>(f.begin(), f.end());
}

using Counts = std::array<uint32_t, kRansSymbols>;

// Bits to code the counted symbols with their own static model.
double entropy_bits(const Counts& c) {
  uint64_t total = 0;
  for (uint32_t n : c) total += n;
  double bits = 0;
  for (uint32_t n : c)
    if (n) bits -= n * std::log2(static_cast<double>(n) / static_cast<double>(total));
  return bits;
}

// About what a table of these counts takes to store (FORMAT.md §8.5.12).
double table_bits(const Counts& c) {
  int used = 0, S = 0;
  for (int s = 0; s < kRansSymbols; ++s)
    if (c[static_cast<size_t>(s)]) ++used, S = s + 1;
  return 12 + 4 * used + (S - used);
}

}  // namespace

void RansEncoder::build() {
  // Contexts in order: one that codes smaller with the previous table
  // (built from both contexts' counts) than with its own shares it.
  for (size_t c = 0; c < count_.size(); ++c) {
    total_[c] = 0;
    for (uint32_t n : count_[c]) total_[c] += n;
  }
  start_.assign(count_.size(), {});
  share_.assign(count_.size(), 0);
  std::vector<size_t> group_of(count_.size(), 0);
  std::vector<Counts> group;
  std::vector<uint64_t> group_total;
  double back_bits = 0, back_table = 0;  // the last group's entropy_bits and table_bits (kept, not recomputed)
  for (size_t c = 0; c < count_.size(); ++c) {
    if (total_[c] == 0) continue;
    const double own_bits = entropy_bits(count_[c]), own_table = table_bits(count_[c]);
    if (!group.empty()) {
      Counts merged = group.back();
      for (int s = 0; s < kRansSymbols; ++s) merged[static_cast<size_t>(s)] += count_[c][static_cast<size_t>(s)];
      const double apart = back_bits + back_table + own_bits + own_table;
      const double merged_bits = entropy_bits(merged), merged_table = table_bits(merged);
      if (merged_bits + merged_table + 1 < apart) {
        group.back() = merged;
        group_total.back() += total_[c];
        group_of[c] = group.size() - 1;
        share_[c] = 1;
        back_bits = merged_bits;
        back_table = merged_table;
        continue;
      }
    }
    back_bits = own_bits;
    back_table = own_table;
    group.push_back(count_[c]);
    group_total.push_back(total_[c]);
    group_of[c] = group.size() - 1;
  }
  for (size_t c = 0; c < count_.size(); ++c) {
    freq_[c].clear();
    if (total_[c] == 0) continue;
    const Counts& g = group[group_of[c]];
    const uint64_t gt = group_total[group_of[c]];
    freq_[c] = normalize(g, gt, implied_symbol(g));
    top_[c] = implied_symbol(g);
    uint32_t at = 0;
    for (uint16_t f : freq_[c]) {
      start_[c].push_back(static_cast<uint16_t>(at));
      at += f;
    }
  }
  slot_.assign(count_.size() * kRansSymbols, 0);
  for (size_t c = 0; c < count_.size(); ++c)
    for (size_t s = 0; s < freq_[c].size(); ++s)
      slot_[c * kRansSymbols + s] = uint32_t{start_[c][s]} << 16 | freq_[c][s];
}

// FORMAT.md §8.5.12: per context a used flag; per used context the symbol
// count S - 1, the implied symbol, then per other symbol below S its
// frequency's exponent (in the context of the previous symbol's exponent
// and of the same symbol's in the previous table) and mantissa bits.
void RansEncoder::write_tables(RangeEncoder& e) const {
  auto m = std::make_unique<RansTableModels>();
  std::vector<uint16_t> above;
  for (size_t c = 0; c < freq_.size(); ++c) {
    const std::vector<uint16_t>& f = freq_[c];
    e.bit(m->used, !f.empty());
    if (f.empty()) continue;
    if (!above.empty()) e.bit(m->same, share_[c]);
    if (share_[c]) continue;
    const int S = static_cast<int>(f.size()), top = top_[c];
    m->count.encode(e, static_cast<uint32_t>(S - 1));
    m->top.encode(e, static_cast<uint32_t>(top));
    int prev = 0;
    for (int s = 0; s < S; ++s) {
      if (s == top) continue;
      const int up = s < static_cast<int>(above.size())
                         ? std::min(exponent_of(above[static_cast<size_t>(s)]), kRansMaxExponent)
                         : 0;
      const int ex = exponent_of(f[static_cast<size_t>(s)]);
      m->exponent[prev][up].encode(e, static_cast<uint32_t>(ex));
      if (ex >= 2) {
        const int mb = mantissa_bits(ex);
        e.direct((f[static_cast<size_t>(s)] >> (ex - 1 - mb)) & ((1u << mb) - 1), mb);
      }
      prev = ex;
    }
    above = f;
  }
}

void RansEncoder::put(BitWriter& bits, int ctx, int64_t r) {
  const RansSymbol s = rans_symbol(r);
  coded_.push_back(static_cast<uint32_t>(ctx) * kRansSymbols + static_cast<uint32_t>(s.symbol));
  if (s.raw_bits) bits.put(s.raw, s.raw_bits);
}

std::string RansEncoder::finish() {
  // rANS codes last in, first out: the residuals in reverse, the k-th with
  // state k mod 2; the words come out in reverse reading order.
  uint32_t x[2] = {kRansLow, kRansLow};
  // At most one word per residual, written from the end backwards.
  std::vector<uint16_t> words(coded_.size());
  size_t w_at = words.size();
  const uint32_t* slot = slot_.data();
  for (size_t k = coded_.size(); k-- > 0;) {
    const uint32_t fs = slot[coded_[k]], f = fs & 0xFFFF, st = fs >> 16;
    uint32_t& y = x[k & 1];
    if (uint64_t{y} >= uint64_t{f} << 20) {
      words[--w_at] = static_cast<uint16_t>(y);
      y >>= 16;
    }
    y = ((y / f) << kRansScaleBits) + (y % f) + st;
  }
  std::string out;
  out.reserve(8 + 2 * (words.size() - w_at));
  ByteWriter w(out);
  w.u32(x[0]);
  w.u32(x[1]);
  for (size_t k = w_at; k < words.size(); ++k) w.u16(words[k]);
  coded_.clear();
  return out;
}

bool RansDecoder::read_tables(RangeDecoder& d, int contexts, std::string& why) {
  auto m = std::make_unique<RansTableModels>();
  table_.assign(static_cast<size_t>(contexts), kNoTable);
  slot_symbol_.clear();
  freq_start_.clear();
  std::vector<uint16_t> above, f;
  uint32_t tables = 0;
  for (int c = 0; c < contexts; ++c) {
    if (!d.bit(m->used)) continue;
    if (tables > 0 && d.bit(m->same)) {  // the previous table
      table_[static_cast<size_t>(c)] = tables - 1;
      continue;
    }
    const uint32_t S = m->count.decode(d) + 1, top = m->top.decode(d);
    if (S == 0 || S > kRansSymbols || top >= S) {
      why = "residual table " + std::to_string(c) + ": bad symbol count or implied symbol";
      return false;
    }
    f.assign(S, 0);
    uint32_t sum = 0;
    int prev = 0;
    for (uint32_t s = 0; s < S; ++s) {
      if (s == top) continue;
      const int up = s < above.size() ? std::min(exponent_of(above[s]), kRansMaxExponent) : 0;
      const int ex = static_cast<int>(m->exponent[prev][up].decode(d));
      if (ex > kRansMaxExponent) {
        why = "residual table " + std::to_string(c) + ": frequency out of range";
        return false;
      }
      uint32_t x = ex ? 1 : 0;
      if (ex >= 2) {
        const int mb = mantissa_bits(ex);
        x = ((1u << mb) | d.direct(mb)) << (ex - 1 - mb);
      }
      f[s] = static_cast<uint16_t>(x);
      sum += x;
      prev = ex;
    }
    if (sum >= kRansScale) {
      why = "residual table " + std::to_string(c) + ": frequencies sum above 4095 before the implied one";
      return false;
    }
    if (d.overrun() > RangeDecoder::kMaxOverrun) {
      why = "residual tables are truncated";
      return false;
    }
    f[top] = static_cast<uint16_t>(kRansScale - sum);
    table_[static_cast<size_t>(c)] = tables++;
    slot_symbol_.resize(size_t{tables} << kRansScaleBits);
    freq_start_.resize(size_t{tables} * kRansSymbols, 0);
    uint8_t* slots = &slot_symbol_[size_t{tables - 1} << kRansScaleBits];
    uint32_t* fs = &freq_start_[size_t{tables - 1} * kRansSymbols];
    uint32_t at = 0;
    for (uint32_t s = 0; s < S; ++s) {
      fs[s] = at << 16 | f[s];
      std::fill(slots + at, slots + at + f[s], static_cast<uint8_t>(s));
      at += f[s];
    }
    above = f;
  }
  return true;
}

bool RansDecoder::init(std::string_view stream) {
  if (stream.size() < 8) return false;
  const uint8_t* b = reinterpret_cast<const uint8_t*>(stream.data());
  for (int i = 0; i < 2; ++i) {
    state_[i] =
        uint32_t{b[4 * i]} | uint32_t{b[4 * i + 1]} << 8 | uint32_t{b[4 * i + 2]} << 16 | uint32_t{b[4 * i + 3]} << 24;
    if (state_[i] < kRansLow) return false;
  }
  p_ = b + 8;
  end_ = b + stream.size();
  turn_ = 0;
  overrun_ = false;
  return true;
}

}  // namespace tsm

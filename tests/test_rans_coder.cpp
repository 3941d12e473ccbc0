// The rANS-coded residuals (rans_coder.hpp, FORMAT.md §8.5.12): symbols,
// tables, the interleaved states, and hostile tables and streams.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "rans_coder.hpp"

namespace {

struct Coded {
  std::string tables, rans, bits;
};

// Codes (context, residual) pairs as the geometry coder does: count, build,
// tables into a range coder, residuals in order.
Coded encode(const std::vector<std::pair<int, int64_t>>& values, int contexts) {
  tsm::RansEncoder enc(contexts);
  for (const auto& [c, r] : values) enc.count(c, r);
  enc.build();
  tsm::RangeEncoder e;
  enc.write_tables(e);
  tsm::BitWriter w;
  for (const auto& [c, r] : values) enc.put(w, c, r);
  Coded out;
  out.rans = enc.finish();
  out.bits = w.finish();
  out.tables = e.finish();
  return out;
}

struct Reader {
  tsm::RangeDecoder d;
  tsm::RansDecoder rans;
  tsm::BitReader bits;
  std::string why;
  bool open(const Coded& c, int contexts) {
    d.init(c.tables);
    bits.init(c.bits);
    return rans.read_tables(d, contexts, why) && rans.init(c.rans);
  }
};

std::vector<std::pair<int, int64_t>> sample(size_t n, int contexts, uint32_t seed) {
  std::mt19937 rng(seed);
  std::geometric_distribution<int> g(0.15);
  std::vector<std::pair<int, int64_t>> v;
  for (size_t i = 0; i < n; ++i) {
    const int c = static_cast<int>(rng() % static_cast<uint32_t>(contexts));
    const int64_t mag = g(rng) * (c + 1);
    v.push_back({c, rng() & 1 ? -mag : mag});
  }
  return v;
}

// Every residual of |r| < 2^30 is one symbol (0..230) plus its low bits,
// and decodes back, whatever the context's table looks like.
TEST(RansCoder, EveryBitLengthRoundTrips) {
  std::vector<std::pair<int, int64_t>> values = sample(5000, 7, 1);
  for (int64_t r = -7; r <= 7; ++r) values.push_back({static_cast<int>(r + 7) % 7, r});
  for (int n = 4; n <= 30; ++n)  // bit length n, the two bits below the leading one t, low bits all 0 or all 1
    for (int64_t t = 0; t < 4; ++t) {
      const int64_t r = ((4 | t) << (n - 3)) | (t & 1 ? (int64_t{1} << (n - 3)) - 1 : 0);
      values.push_back({n % 7, r});
      values.push_back({(n + 3) % 7, -r});
    }
  std::vector<int> seen(tsm::kRansSymbols, 0);
  for (const auto& v : values) {
    const tsm::RansSymbol s = tsm::rans_symbol(v.second);
    ASSERT_GE(s.symbol, 0);
    ASSERT_LT(s.symbol, tsm::kRansSymbols);
    seen[static_cast<size_t>(s.symbol)] = 1;
  }
  EXPECT_EQ(std::count(seen.begin(), seen.end(), 1), tsm::kRansSymbols);  // every symbol used
  const Coded c = encode(values, 7);
  Reader r;
  ASSERT_TRUE(r.open(c, 7)) << r.why;
  for (const auto& [ctx, want] : values) {
    int32_t got = 0;
    ASSERT_TRUE(r.rans.decode(r.bits, ctx, got));
    ASSERT_EQ(got, want);
  }
  EXPECT_FALSE(r.rans.overrun());
  EXPECT_FALSE(r.bits.overrun());
  EXPECT_TRUE(r.rans.finished());
}

// A skewed source costs near its entropy (static tables: the empirical
// entropy plus the tables and the rounding of the frequencies).
TEST(RansCoder, SkewedResidualsCostNearTheirEntropy) {
  std::mt19937 rng(3);
  std::geometric_distribution<int> g(0.6);
  std::vector<std::pair<int, int64_t>> values;
  std::vector<double> count(8, 0);
  for (int i = 0; i < 100000; ++i) {
    const int x = std::min(g(rng), 7);
    values.push_back({0, x});
    ++count[static_cast<size_t>(x)];
  }
  double bits = 0;
  for (double n : count)
    if (n > 0) bits -= n * std::log2(n / 100000.0);
  const Coded c = encode(values, 1);
  EXPECT_LE(static_cast<double>(c.rans.size() + c.tables.size()), bits / 8 * 1.01 + 32);
  EXPECT_TRUE(c.bits.empty());
}

// The tables of one used context, forged: symbol count S, implied symbol
// top, and per other symbol its exponent (mantissa bits zero).
std::string forged(uint32_t S, uint32_t top, const std::vector<uint32_t>& exponent, int contexts = 1) {
  auto m = std::make_unique<tsm::RansTableModels>();
  tsm::RangeEncoder e;
  e.bit(m->used, 1);
  m->count.encode(e, S - 1);
  m->top.encode(e, top);
  uint32_t prev = 0;
  for (uint32_t s = 0; s < exponent.size(); ++s) {
    if (s == top) continue;
    m->exponent[prev][0].encode(e, exponent[s]);
    if (exponent[s] >= 2) e.direct(0, std::min<int>(static_cast<int>(exponent[s]) - 1, 2));
    prev = std::min<uint32_t>(exponent[s], 12);
  }
  for (int c = 1; c < contexts; ++c) e.bit(m->used, 0);
  return e.finish();
}

bool reads(const std::string& tables, int contexts = 1) {
  tsm::RangeDecoder d(tables);
  tsm::RansDecoder r;
  std::string why;
  const bool ok = r.read_tables(d, contexts, why);
  EXPECT_EQ(ok, why.empty()) << why;
  return ok;
}

// Hostile tables are refused: frequencies reaching 4096 before the implied
// one (so it would be 0 or less), an exponent above 12, more than 231
// symbols, an implied symbol past the count, a table stream cut short.
TEST(RansCoder, HostileTablesAreRefused) {
  EXPECT_TRUE(reads(forged(3, 0, {0, 12, 11})));   // 2048 + 1024, implied 1024
  EXPECT_FALSE(reads(forged(3, 0, {0, 12, 12})));  // 2048 + 2048
  EXPECT_FALSE(reads(forged(2, 1, {13, 0})));      // exponent 13
  EXPECT_TRUE(reads(forged(231, 0, std::vector<uint32_t>(231, 1))));
  EXPECT_FALSE(reads(forged(232, 0, std::vector<uint32_t>(232, 1))));
  EXPECT_FALSE(reads(forged(3, 3, {1, 1, 1})));  // implied symbol 3 of 3
  const Coded c = encode(sample(20000, 40, 5), 40);
  ASSERT_TRUE(reads(c.tables, 40));
  EXPECT_FALSE(reads(c.tables.substr(0, c.tables.size() / 3), 40));
}

// Hostile streams: states below 2^16 or a stream too short for them are
// refused; a context without a table fails; words past the end are counted
// (truncated); a damaged word leaves the states off their start or gives
// other residuals, never a crash.
TEST(RansCoder, HostileStreamsAreRefused) {
  const std::vector<std::pair<int, int64_t>> values = sample(20000, 3, 9);
  const Coded c = encode(values, 4);  // context 3 never used: no table
  Reader r;
  ASSERT_TRUE(r.open(c, 4));
  int32_t x;
  EXPECT_FALSE(r.rans.decode(r.bits, 3, x));
  tsm::RansDecoder bad;
  EXPECT_FALSE(bad.init(c.rans.substr(0, 7)));
  std::string low = c.rans;
  low[2] = low[3] = 0;  // x[0] < 2^16
  EXPECT_FALSE(bad.init(low));
  auto run = [&](const std::string& rans, bool& overrun, bool& finished) {
    Reader k;
    Coded d = c;
    d.rans = rans;
    if (!k.open(d, 4)) return false;
    for (const auto& [ctx, want] : values) {
      int32_t got = 0;
      if (!k.rans.decode(k.bits, ctx, got)) return false;
    }
    overrun = k.rans.overrun();
    finished = k.rans.finished();
    return true;
  };
  bool overrun = false, finished = false;
  ASSERT_TRUE(run(c.rans, overrun, finished));
  EXPECT_FALSE(overrun);
  EXPECT_TRUE(finished);
  ASSERT_TRUE(run(c.rans.substr(0, c.rans.size() - 2), overrun, finished));
  EXPECT_TRUE(overrun);
  std::string damaged = c.rans;
  damaged[damaged.size() / 2] = static_cast<char>(damaged[damaged.size() / 2] ^ 0x40);
  ASSERT_TRUE(run(damaged, overrun, finished));
  EXPECT_FALSE(finished && !overrun);
}

}  // namespace

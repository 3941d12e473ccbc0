#include <gtest/gtest.h>

#include <random>

#include "range_coder.hpp"

using namespace tsm;

TEST(RangeCoder, BitsRoundTripAndCompressSkewedData) {
  std::mt19937 rng(1);
  std::vector<int> bits(100000);
  for (int& b : bits) b = (rng() % 100) < 5;  // 5% ones
  RangeEncoder e;
  Prob p;
  for (int b : bits) e.bit(p, b);
  std::string out = e.finish();
  // Entropy of p=0.05 is 0.286 bits/bit: 100000 bits -> ~3.6 KB.
  EXPECT_LT(out.size(), 4000u);
  RangeDecoder d(out);
  Prob q;
  for (size_t i = 0; i < bits.size(); ++i) ASSERT_EQ(d.bit(q), bits[i]) << i;
  EXPECT_LE(d.overrun(), RangeDecoder::kMaxOverrun);
}

TEST(RangeCoder, MixedModelsRoundTrip) {
  std::mt19937 rng(2);
  std::vector<uint32_t> u(20000);
  std::vector<int32_t> s(20000);
  std::vector<uint32_t> raw(20000);
  for (size_t i = 0; i < u.size(); ++i) {
    int shift = static_cast<int>(rng() % 33);
    u[i] = shift == 32 ? 0xFFFFFFFEu : static_cast<uint32_t>(rng() & ((uint64_t{1} << shift) - 1));
    s[i] = static_cast<int32_t>(rng() % 2001) - 1000;
    if (i % 1000 == 0) s[i] = (i % 2000 == 0) ? 0x7FFFFFFF : -0x7FFFFFFF;
    raw[i] = rng() & 0x1FFFF;
  }
  RangeEncoder e;
  UIntModel um;
  SIntModel sm;
  BitTreeModel<3> tm;
  for (size_t i = 0; i < u.size(); ++i) {
    um.encode(e, u[i]);
    sm.encode(e, s[i]);
    e.direct(raw[i], 17);
    tm.encode(e, static_cast<uint32_t>(i % 8));
  }
  std::string out = e.finish();
  RangeDecoder d(out);
  UIntModel um2;
  SIntModel sm2;
  BitTreeModel<3> tm2;
  for (size_t i = 0; i < u.size(); ++i) {
    ASSERT_EQ(um2.decode(d), u[i]) << i;
    ASSERT_EQ(sm2.decode(d), s[i]) << i;
    ASSERT_EQ(d.direct(17), raw[i]) << i;
    ASSERT_EQ(tm2.decode(d), i % 8) << i;
  }
  EXPECT_LE(d.overrun(), RangeDecoder::kMaxOverrun);
}

TEST(RangeCoder, GarbageInputNeverFailsHard) {
  std::mt19937 rng(3);
  for (int t = 0; t < 200; ++t) {
    std::string junk(rng() % 64, '\0');
    for (char& c : junk) c = static_cast<char>(rng());
    RangeDecoder d(junk);
    UIntModel um;
    for (int i = 0; i < 1000; ++i) (void)um.decode(d);
    if (junk.size() < 16) {
      EXPECT_GT(d.overrun(), 0u);
    }
  }
}

TEST(RangeCoder, EmptyStreamDecodesAsOverrun) {
  RangeEncoder e;
  std::string out = e.finish();
  EXPECT_LE(out.size(), 5u);
  RangeDecoder d(std::string_view{});
  Prob p;
  (void)d.bit(p);
  EXPECT_GT(d.overrun(), 0u);
}

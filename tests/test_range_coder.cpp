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

// Logistic mixing (FORMAT.md §8.1.1): squash and stretch are monotone and
// inverse to each other; mixed signed integers round trip over the whole
// int32 range (the decoder clamps like SIntModelT); and two models whose
// contexts each know half of what decides a value code it in fewer bytes
// mixed than either alone.
TEST(RangeCoder, SquashAndStretch) {
  EXPECT_EQ(squash(0), 2048);
  EXPECT_EQ(squash(-5000), 1);
  EXPECT_EQ(squash(5000), 4095);
  for (int d = -2047; d < 2047; ++d) ASSERT_LE(squash(d), squash(d + 1)) << d;
  for (int p = 1; p < 4096; ++p) {
    ASSERT_LE(kStretch.v[p - 1], kStretch.v[p]) << p;
    ASSERT_GE(squash(kStretch.v[p]), p) << p;  // the smallest d that reaches p ...
    if (kStretch.v[p] > -2047) {
      ASSERT_LT(squash(kStretch.v[p] - 1), p) << p;  // ... and no smaller one does
    }
  }
}

TEST(RangeCoder, MixedSignedIntegersRoundTripAndBeatOneContext) {
  std::mt19937 rng(3);
  const size_t n = 60000;
  std::vector<int> ca(n), cb(n);
  std::vector<int32_t> v(n);
  for (size_t i = 0; i < n; ++i) {
    ca[i] = static_cast<int>(rng() % 4);
    cb[i] = static_cast<int>(rng() % 4);
    const int scale = 1 << (ca[i] + 2 * cb[i]);  // each context knows part of the scale
    v[i] = static_cast<int32_t>(rng() % (2 * scale + 1)) - scale;
    if (i % 5000 == 7) v[i] = (i % 10000 == 7) ? 0x7FFFFFFF : -0x7FFFFFFF;
  }
  auto mixed = [&] {
    RangeEncoder e;
    std::vector<SIntModelT<6>> A(4), B(4);
    std::vector<MixWeights> w(4 * kMixKinds<6>);
    MixEncodeOp op{e};
    for (size_t i = 0; i < n; ++i) code_mixed_sint(op, A[ca[i]], B[cb[i]], &w[ca[i] * kMixKinds<6>], v[i]);
    return e.finish();
  };
  const std::string bytes = mixed();
  EXPECT_EQ(mixed(), bytes);  // deterministic
  {
    RangeDecoder d(bytes);
    std::vector<SIntModelT<6>> A(4), B(4);
    std::vector<MixWeights> w(4 * kMixKinds<6>);
    MixDecodeOp op{d};
    for (size_t i = 0; i < n; ++i)
      ASSERT_EQ(code_mixed_sint(op, A[ca[i]], B[cb[i]], &w[ca[i] * kMixKinds<6>], 0), v[i]) << i;
    EXPECT_LE(d.overrun(), RangeDecoder::kMaxOverrun);
  }
  for (const std::vector<int>* ctx : {&ca, &cb}) {
    RangeEncoder e;
    std::vector<SIntModelT<6>> M(4);
    for (size_t i = 0; i < n; ++i) M[(*ctx)[i]].encode(e, v[i]);
    EXPECT_LT(bytes.size(), e.finish().size());
  }
}

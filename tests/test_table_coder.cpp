// The static prefix codes (table_coder.hpp, FORMAT.md
// §8.5.11): symbols, code lengths, canonical codes and the table block.
#include <gtest/gtest.h>

#include <random>
#include <string>
#include <vector>

#include "byte_io.hpp"
#include "table_coder.hpp"

namespace {

using tsm::CodeLengths;
using tsm::kTableSymbols;

std::array<uint32_t, kTableSymbols> zero_counts() { return std::array<uint32_t, kTableSymbols>{}; }

// Codes values in context 0 (its lengths from their own counts) and reads them back.
std::vector<int32_t> round_trip(const std::vector<int64_t>& values, size_t* bytes = nullptr) {
  auto count = zero_counts();
  for (int64_t v : values) ++count[tsm::table_symbol(v).symbol];
  std::vector<CodeLengths> lengths(1, tsm::table_code_lengths(count));
  const auto code = tsm::canonical_codes(lengths[0]);
  tsm::BitWriter w;
  for (int64_t v : values) {
    const tsm::TableSymbol t = tsm::table_symbol(v);
    w.put(code[t.symbol], lengths[0][t.symbol]);
    if (t.raw_bits) w.put(t.raw, t.raw_bits);
  }
  const std::string bits = w.finish();
  if (bytes) *bytes = bits.size();
  const std::string block = tsm::write_tables(lengths);
  tsm::ByteReader r(block);
  tsm::TableSet set;
  std::string why;
  EXPECT_TRUE(set.read(r, 1, why)) << why;
  EXPECT_EQ(r.remaining(), 0u);
  tsm::BitReader br;
  br.init(bits);
  std::vector<int32_t> out;
  for (size_t i = 0; i < values.size(); ++i) {
    int32_t x = 0;
    EXPECT_TRUE(set.decode(br, 0, x));
    out.push_back(x);
  }
  EXPECT_FALSE(br.overrun());
  return out;
}

TEST(TableCoder, SymbolsCoverEveryResidual) {
  std::vector<int64_t> values;
  for (int64_t v = -70; v <= 70; ++v) values.push_back(v);
  for (int n = 3; n <= 30; ++n)
    for (int64_t v : {int64_t{1} << (n - 1), (int64_t{1} << n) - 1}) {
      values.push_back(v);
      values.push_back(-v);
    }
  const std::vector<int32_t> back = round_trip(values);
  ASSERT_EQ(back.size(), values.size());
  for (size_t i = 0; i < values.size(); ++i) EXPECT_EQ(back[i], values[i]) << i;
  EXPECT_EQ(tsm::table_symbol(-3).symbol, 0);
  EXPECT_EQ(tsm::table_symbol(3).symbol, 6);
  EXPECT_EQ(tsm::table_symbol(4).symbol, 7);
  EXPECT_EQ(tsm::table_symbol(-4).symbol, 8);
  EXPECT_EQ(tsm::table_symbol(-((int64_t{1} << 30) - 1)).symbol, kTableSymbols - 1);
}

TEST(TableCoder, LengthsAreLimitedAndCanonicalCodesArePrefixFree) {
  // Fibonacci counts make the unlimited Huffman code as deep as it gets.
  auto count = zero_counts();
  uint32_t a = 1, b = 1;
  for (int s = 0; s < 40; ++s) {
    count[s] = a;
    const uint32_t c = a + b;
    a = b;
    b = c;
  }
  const CodeLengths len = tsm::table_code_lengths(count);
  uint32_t kraft = 0;
  for (int s = 0; s < kTableSymbols; ++s) {
    EXPECT_LE(len[s], tsm::kTableMaxLength);
    EXPECT_EQ(len[s] != 0, count[s] != 0) << s;
    if (len[s]) kraft += 1u << (tsm::kTableMaxLength - len[s]);
  }
  EXPECT_EQ(kraft, 1u << tsm::kTableMaxLength);  // complete
  const auto code = tsm::canonical_codes(len);
  for (int s = 0; s < kTableSymbols; ++s)
    for (int t = 0; t < kTableSymbols; ++t) {
      if (s == t || !len[s] || !len[t] || len[s] > len[t]) continue;
      EXPECT_NE(code[t] >> (len[t] - len[s]), code[s]) << s << " is a prefix of " << t;
    }
  // One symbol: a 1-bit code.
  auto one = zero_counts();
  one[5] = 100;
  EXPECT_EQ(tsm::table_code_lengths(one)[5], 1);
  const std::vector<int32_t> back = round_trip(std::vector<int64_t>(50, 2));
  EXPECT_EQ(back, std::vector<int32_t>(50, 2));
}

TEST(TableCoder, SkewedResidualsCostNearTheirEntropy) {
  std::mt19937 rng(7);
  std::geometric_distribution<int> geo(0.3);
  std::vector<int64_t> values;
  for (int i = 0; i < 20000; ++i) values.push_back((rng() & 1) ? geo(rng) : -geo(rng));
  size_t bytes = 0;
  const std::vector<int32_t> back = round_trip(values, &bytes);
  for (size_t i = 0; i < values.size(); ++i) ASSERT_EQ(back[i], values[i]);
  // A few bits each (about 3.4 of entropy), nowhere near 8.
  EXPECT_LT(bytes, values.size() * 4 / 8);
}

// Every malformed table block is refused with a reason, never read.
TEST(TableCoder, MalformedTableBlocksAreRefused) {
  auto refused = [](const std::string& block, int contexts = 4) {
    tsm::ByteReader r(block);
    tsm::TableSet set;
    std::string why;
    const bool ok = set.read(r, contexts, why);
    return !ok && !why.empty();
  };
  std::string map(tsm::kTableMapBytes, '\0');
  map[0] = 1;  // context 0
  EXPECT_FALSE(refused(map + std::string("\x02\x11", 2)));          // lengths 1, 1: complete
  EXPECT_FALSE(refused(map + std::string("\x01\x10", 2)));          // one symbol of length 1
  EXPECT_TRUE(refused(map));                                        // its table is missing
  EXPECT_TRUE(refused(map + std::string("\x00", 1)));               // no symbols
  EXPECT_TRUE(refused(map + std::string("\x40", 1)));               // 64 symbols
  EXPECT_TRUE(refused(map + std::string("\x02\x00", 2)));           // every length 0
  EXPECT_TRUE(refused(map + std::string("\x03\x11\x10", 3)));       // three of length 1: Kraft > 1
  EXPECT_TRUE(refused(map + std::string("\x01\xC0", 2)));           // length 12
  EXPECT_TRUE(refused(map + std::string("\x01\x11", 2)));           // padding nibble not zero
  EXPECT_TRUE(refused(map.substr(0, 10)));                          // the map itself cut
  std::string far = std::string(tsm::kTableMapBytes, '\0');
  far[1] = 1;  // context 8, of 4
  EXPECT_TRUE(refused(far + std::string("\x01\x10", 2)));
  // A code word no symbol has (an incomplete code) is refused when read.
  const std::string block = map + std::string("\x01\x10", 2);
  tsm::ByteReader r(block);
  tsm::TableSet set;
  std::string why;
  ASSERT_TRUE(set.read(r, 4, why));
  tsm::BitReader br;
  const std::string ones("\xFF", 1);
  br.init(ones);
  int32_t x;
  EXPECT_FALSE(set.decode(br, 0, x));
  // Reading past the end is seen.
  tsm::BitReader empty;
  empty.init(std::string_view());
  EXPECT_TRUE(set.decode(empty, 0, x));
  EXPECT_TRUE(empty.overrun());
}

// The reader's refill takes 8 bytes at a time while 8 are left and single
// bytes near the end: fields of every width at every bit offset read back,
// and past the end come zero bits, flagged.
TEST(TableCoder, BitReaderReadsEveryWidthAtEveryOffset) {
  std::mt19937 rng(7);
  for (int round = 0; round < 200; ++round) {
    std::vector<std::pair<uint32_t, int>> fields;
    tsm::BitWriter w;
    const int count = static_cast<int>(rng() % 40);
    for (int i = 0; i < count; ++i) {
      const int n = 1 + static_cast<int>(rng() % 32);
      const uint32_t v = n == 32 ? static_cast<uint32_t>(rng()) : static_cast<uint32_t>(rng()) & ((1u << n) - 1);
      fields.push_back({v, n});
      w.put(v, n);
    }
    const std::string bytes = w.finish();
    tsm::BitReader r;
    r.init(bytes);
    for (const auto& [v, n] : fields) {
      r.refill();
      if (n <= 16 && (rng() & 1)) {  // the table decoder's two-step read
        const uint32_t hi = r.peek(n);
        r.skip(n);
        ASSERT_EQ(hi, v);
        continue;
      }
      const int first = n / 2;
      uint32_t got = first ? r.peek(first) : 0;
      if (first) r.skip(first);
      r.refill();
      got = static_cast<uint32_t>((uint64_t{got} << (n - first)) | r.peek(n - first));
      r.skip(n - first);
      ASSERT_EQ(got, v) << "round " << round;
    }
    EXPECT_FALSE(r.overrun());
    const size_t pad = 8 * bytes.size() - [&] {
      size_t bits = 0;
      for (const auto& f : fields) bits += static_cast<size_t>(f.second);
      return bits;
    }();
    r.refill();
    if (pad) {
      EXPECT_EQ(r.peek(static_cast<int>(pad)), 0u);
      r.skip(static_cast<int>(pad));
    }
    EXPECT_FALSE(r.overrun());
    r.refill();
    EXPECT_EQ(r.peek(32), 0u);  // past the end: zeros
    r.skip(1);
    EXPECT_TRUE(r.overrun());
  }
}

// Code words longer than the primary lookup (kTablePrimary bits) go through
// a second table: a code with every length 1..11 decodes every symbol, and
// an unassigned long code word is refused.
TEST(TableCoder, LongCodeWordsDecodeThroughTheSecondTable) {
  static_assert(tsm::kTablePrimary < tsm::kTableMaxLength, "the test needs code words past the primary table");
  // Lengths 1, 2, ..., 10, 11, 11: a complete code (Kraft sum 1) over 12
  // symbols; then the same without the last symbol (incomplete).
  for (const bool complete : {true, false}) {
    CodeLengths len{};
    for (int s = 0; s < 11; ++s) len[static_cast<size_t>(s)] = static_cast<uint8_t>(s + 1);
    if (complete) len[11] = 11;
    const auto code = tsm::canonical_codes(len);
    const std::string block = tsm::write_tables(std::vector<CodeLengths>{len});
    tsm::ByteReader br(block);
    tsm::TableSet set;
    std::string why;
    ASSERT_TRUE(set.read(br, 1, why)) << why;
    tsm::BitWriter w;
    const int symbols = complete ? 12 : 11;
    std::vector<int32_t> want;
    for (int rep = 0; rep < 3; ++rep)
      for (int s = 0; s < symbols; ++s) {
        w.put(code[static_cast<size_t>(s)], len[static_cast<size_t>(s)]);
        // Symbols 0..6 are the residuals -3..3; 7.. are escapes with raw bits.
        int32_t r = s - tsm::kTableDirect;
        if (s > 2 * tsm::kTableDirect) {
          const int m = s - (2 * tsm::kTableDirect + 1), n = (m >> 1) + tsm::kTableEscapeLength;
          const uint32_t raw = static_cast<uint32_t>(rep) & ((1u << (n - 1)) - 1);
          w.put(raw, n - 1);
          r = static_cast<int32_t>((1u << (n - 1)) | raw);
          if (m & 1) r = -r;
        }
        want.push_back(r);
      }
    if (!complete) w.put(0x7FF, 11);  // the one code word of 11 ones is unassigned
    const std::string bits = w.finish();
    tsm::BitReader r;
    r.init(bits);
    for (int32_t expected : want) {
      int32_t x = 0;
      ASSERT_TRUE(set.decode(r, 0, x));
      EXPECT_EQ(x, expected);
    }
    int32_t x = 0;
    if (!complete) {
      EXPECT_FALSE(set.decode(r, 0, x));
    }
  }
}

// A context the map leaves without a table decodes nothing (the decoder
// reads it as a code with no code words), while its neighbours decode.
TEST(TableCoder, ContextWithoutATableIsRefused) {
  std::string block(tsm::kTableMapBytes, '\0');
  block[0] = 2;                             // context 1 only, of 4
  block += std::string("\x02\x11", 2);      // lengths 1, 1: residuals -3 ("0") and -2 ("1")
  tsm::ByteReader br(block);
  tsm::TableSet set;
  std::string why;
  ASSERT_TRUE(set.read(br, 4, why)) << why;
  EXPECT_FALSE(set.has(0));
  EXPECT_TRUE(set.has(1));
  const std::string bits("\x40", 1);  // 0, 1, then zeros
  for (int ctx : {0, 2, 3}) {
    tsm::BitReader r;
    r.init(bits);
    int32_t x = 0;
    EXPECT_FALSE(set.decode(r, ctx, x)) << "context " << ctx;
  }
  tsm::BitReader r;
  r.init(bits);
  int32_t x = 0;
  ASSERT_TRUE(set.decode(r, 1, x));
  EXPECT_EQ(x, -3);
  ASSERT_TRUE(set.decode(r, 1, x));
  EXPECT_EQ(x, -2);
}

}  // namespace

// Static per-context frequency tables coded with interleaved rANS (entropy
// coding stage for the geometry residuals, FORMAT.md §8.5.12): the
// residuals of one context share one table of 12-bit frequencies, stored
// compactly at the start of the range-coded stream; the residual symbols
// go through two interleaved rANS states with 16-bit renormalization, the
// bits below a symbol's top mantissa bits through a plain bit stream. One
// table lookup and a multiply per residual instead of about fourteen
// adaptive binary decisions.
//
// A residual r is a symbol: -7..7 are symbols 0..14 of their own; a larger
// |r| of bit length n (4..30) is symbol 15 + 8 (n - 4) + 4 (r < 0) + t,
// where t is the two bits below its leading one; the n - 3 bits below those
// follow in the bit stream, most significant first.
#pragma once
#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "range_coder.hpp"
#include "table_coder.hpp"

namespace tsm {

constexpr int kRansDirect = 7;                                    // residuals -7..7 are symbols of their own
constexpr int kRansSymbols = 2 * kRansDirect + 1 + 8 * (30 - 3);  // 231
constexpr int kRansScaleBits = 12;                                // frequencies sum to 4096
constexpr uint32_t kRansScale = 1u << kRansScaleBits;
constexpr uint32_t kRansLow = 1u << 16;  // states stay in [2^16, 2^32)
constexpr int kRansMaxExponent = 12;     // a frequency's bit length, at most (4095)

struct RansSymbol {
  int symbol;
  int raw_bits;  // bits that follow in the bit stream
  uint32_t raw;
};
// |r| < 2^30.
inline RansSymbol rans_symbol(int64_t r) {
  if (r >= -kRansDirect && r <= kRansDirect) return {static_cast<int>(r + kRansDirect), 0, 0};
  const uint64_t mag = static_cast<uint64_t>(r < 0 ? -r : r);
  const int n = bit_length(mag);  // 4..30
  const int t = static_cast<int>((mag >> (n - 3)) & 3);
  const int symbol = 2 * kRansDirect + 1 + 8 * (n - 4) + 4 * (r < 0) + t;
  return {symbol, n - 3, static_cast<uint32_t>(mag & ((uint64_t{1} << (n - 3)) - 1))};
}

// The frequency tables' models in the range-coded stream (FORMAT.md §8.5.12).
struct RansTableModels {
  Prob used, same;
  UIntModel count, top;
  BitTreeModel<4> exponent[kRansMaxExponent + 1][kRansMaxExponent + 1];
};

// The encoder's side over `contexts` contexts: count() every residual in a
// first pass, build() the tables, write_tables() them into the range coder,
// then put() the residuals in coding order and finish() the rANS stream.
class RansEncoder {
 public:
  explicit RansEncoder(int contexts)
      : count_(static_cast<size_t>(contexts)), total_(count_.size(), 0), freq_(count_.size()), top_(count_.size(), 0) {}
  void count(int ctx, int64_t r) { ++count_[static_cast<size_t>(ctx)][static_cast<size_t>(rans_symbol(r).symbol)]; }
  void build();
  void write_tables(RangeEncoder& e) const;
  void put(BitWriter& bits, int ctx, int64_t r);
  // count() and put() at once (one pass: the encoder keeps what it puts).
  // Inline: the trial codings call it for every coordinate.
  __attribute__((always_inline)) void count_and_put(BitWriter& bits, int ctx, int64_t r) {
    const RansSymbol s = rans_symbol(r);
    const uint32_t at = static_cast<uint32_t>(ctx) * kRansSymbols + static_cast<uint32_t>(s.symbol);
    ++count_[static_cast<size_t>(ctx)][static_cast<size_t>(s.symbol)];
    coded_.push_back(at);
    if (s.raw_bits) bits.put(s.raw, s.raw_bits);
  }
  // The rANS stream: the two final states (u32 each), then 16-bit words.
  std::string finish();

 private:
  std::vector<std::array<uint32_t, kRansSymbols>> count_;
  std::vector<uint64_t> total_;              // per context: residuals counted (build() sums them)
  std::vector<std::vector<uint16_t>> freq_;  // per context: frequencies of symbols 0..S-1 (empty: unused)
  std::vector<std::vector<uint16_t>> start_;
  std::vector<uint8_t> share_;   // per context: 1 if it uses the previous table
  std::vector<int> top_;         // per context: its table's implied symbol
  std::vector<uint32_t> coded_;  // ctx * kRansSymbols + symbol, in coding order
  std::vector<uint32_t> slot_;   // per ctx * kRansSymbols + symbol: start << 16 | frequency (after build())
};

// The decoder's side: the tables read from the range coder, the two states
// and the 16-bit word stream. Past the end of the stream it reads zero
// words and counts them (overrun()); a context without a table fails.
class RansDecoder {
 public:
  // Reads the tables of `contexts` contexts; false with the reason.
  bool read_tables(RangeDecoder& d, int contexts, std::string& why);
  // Points the decoder at the rANS stream; false if it cannot hold the states.
  bool init(std::string_view stream);
  __attribute__((always_inline)) bool decode(BitReader& bits, int ctx, int32_t& r) {
    const uint32_t base = table_[static_cast<size_t>(ctx)];
    if (base == kNoTable) return false;
    uint32_t& x = state_[turn_];
    turn_ ^= 1;
    const uint32_t slot = x & (kRansScale - 1);
    const uint8_t s = slot_symbol_[(size_t{base} << kRansScaleBits) + slot];
    const uint32_t fs = freq_start_[size_t{base} * kRansSymbols + s];
    x = (fs & 0xFFFF) * (x >> kRansScaleBits) + slot - (fs >> 16);
    if (x < kRansLow) x = (x << 16) | next_word();
    const SymbolInfo& si = kInfo.s[s];
    uint32_t mag = si.base;
    if (si.raw_bits) {
      bits.refill();
      mag |= bits.peek(si.raw_bits);
      bits.skip(si.raw_bits);
    }
    r = si.negative ? -static_cast<int32_t>(mag) : static_cast<int32_t>(mag);
    return true;
  }
  bool overrun() const { return overrun_; }
  // After the last residual: both states back at their start (2^16).
  bool finished() const { return state_[0] == kRansLow && state_[1] == kRansLow; }

 private:
  struct SymbolInfo {
    uint32_t base;
    uint8_t raw_bits;
    uint8_t negative;
  };
  struct SymbolTable {
    SymbolInfo s[kRansSymbols];
    SymbolTable();
  };
  static const SymbolTable kInfo;
  static constexpr uint32_t kNoTable = 0xFFFFFFFFu;
  uint32_t next_word() {
    if (end_ - p_ >= 2) {
      const uint32_t w = uint32_t{p_[0]} | uint32_t{p_[1]} << 8;
      p_ += 2;
      return w;
    }
    overrun_ = true;
    p_ = end_;
    return 0;
  }
  std::vector<uint32_t> table_;       // per context: its table's index, or kNoTable
  std::vector<uint8_t> slot_symbol_;  // per table: 4096 slots -> symbol
  std::vector<uint32_t> freq_start_;  // per table and symbol: start << 16 | frequency
  uint32_t state_[2] = {kRansLow, kRansLow};
  int turn_ = 0;
  const uint8_t* p_ = nullptr;
  const uint8_t* end_ = nullptr;
  bool overrun_ = false;
};

}  // namespace tsm

// Static prefix codes per context (entropy coding stage; FORMAT.md
// §8.5.11; the connectivity's run values and the attribute residuals use
// them too where they pay, §8.3.1, §8.12.1). The fast levels code the geometry residuals with one
// canonical prefix code per residual context, stored in the file, instead
// of the adaptive binary models of range_coder.hpp: one table lookup per
// value instead of about ten adaptive decisions (6-9x faster to decode,
// 1-2% larger). The
// contexts are the adaptive coder's (seed 004 §3.2 predicts, the contexts
// of design notes §6 say how much was known); only the coder changes.
//
// A residual r is a symbol: -3..3 are symbols 0..6 of their own; a larger
// |r| of bit length n (3..30) is symbol 7 + 2 (n - 3) + (r < 0) followed by
// the n - 1 bits below its leading one, raw. Bits are written most
// significant first.
#pragma once
#include <array>
#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>
#include <vector>

namespace tsm {

class ByteReader;

constexpr int kTableDirect = 3;                              // residuals -3..3 are symbols of their own
constexpr int kTableEscapeLength = 3;                        // bit length of the smallest |r| not direct
constexpr int kTableMaxBitLength = 30;                       // |r| < 2^30
constexpr int kTableSymbols =
    2 * kTableDirect + 1 + 2 * (kTableMaxBitLength - kTableEscapeLength + 1);  // 63
constexpr int kTableMaxLength = 11;                          // longest code word, bits
constexpr int kTableMapBytes = 27;                           // the used-context map: 210 bits

using CodeLengths = std::array<uint8_t, kTableSymbols>;

struct TableSymbol {
  int symbol;
  int raw_bits;  // n - 1 raw bits follow (0 for the direct symbols)
  uint32_t raw;
};
// r must satisfy |r| < 2^30.
TableSymbol table_symbol(int64_t r);

// Huffman code lengths (1..kTableMaxLength, 0 for symbols never seen) for
// counts; one symbol seen gets length 1. Deterministic: the encoder's
// choice only, the file stores the lengths.
CodeLengths table_code_lengths(const std::array<uint32_t, kTableSymbols>& count);

// The canonical code words of lengths that satisfy Kraft (FORMAT.md
// §8.5.11: by length, then by symbol).
std::array<uint32_t, kTableSymbols> canonical_codes(const CodeLengths& length);

// The table block: the used-context map (map_bytes bytes: kTableMapBytes for
// the geometry residuals, kRunMapBytes for the connectivity's run values),
// then per used context its symbol count and 4-bit code lengths.
// lengths.size() <= 8 * map_bytes.
std::string write_tables(const std::vector<CodeLengths>& lengths, int map_bytes = kTableMapBytes);

class BitWriter;
class BitReader;
class TableSet;

// The encoder's side of one table-coded stream over `contexts` contexts:
// count() every value in a first pass, build() the codes from the counts,
// then put() the values in the same order. Values must satisfy |r| < 2^30.
class TableEncoder {
 public:
  explicit TableEncoder(int contexts) : count_(static_cast<size_t>(contexts)), length_(count_.size()), code_(count_.size()) {}
  void count(int ctx, int64_t r) { ++count_[static_cast<size_t>(ctx)][table_symbol(r).symbol]; }
  void build();
  void put(BitWriter& w, int ctx, int64_t r) const;
  // The code lengths, per context (all zero for a context never counted).
  const std::vector<CodeLengths>& lengths() const { return length_; }
  // After build(): bytes of the bit stream the counted values take and of
  // their tables without the used-context map.
  size_t coded_bytes() const;

 private:
  std::vector<std::array<uint32_t, kTableSymbols>> count_;
  std::vector<CodeLengths> length_;
  std::vector<std::array<uint32_t, kTableSymbols>> code_;
};

// The layout every table-coded stream shares (FORMAT.md §8.5.11, §8.3.1,
// §8.12.1): u32 bit-stream length, the table block, the bit stream.
std::string write_table_block(const std::vector<CodeLengths>& lengths, int map_bytes, const std::string& bits);
// Reads it (the table block over `contexts` contexts) and points `bits` at
// the bit stream (its length in *bit_bytes, if given); false with the reason.
bool read_table_block(ByteReader& r, int contexts, int map_bytes, TableSet& tables, BitReader& bits,
                      std::string& why, uint32_t* bit_bytes = nullptr);

class BitWriter {
 public:
  void put(uint32_t value, int n) {  // n <= 32
    acc_ = (acc_ << n) | (n == 32 ? value : value & ((uint64_t{1} << n) - 1));
    have_ += n;
    while (have_ >= 8) {
      have_ -= 8;
      out_.push_back(static_cast<char>(static_cast<uint8_t>(acc_ >> have_)));
    }
  }
  // The bytes, the last one padded with zero bits.
  std::string finish() {
    if (have_ > 0) put(0, 8 - have_);
    std::string s;
    s.swap(out_);
    return s;
  }

 private:
  uint64_t acc_ = 0;
  int have_ = 0;
  std::string out_;
};

// Reads bits most significant first; past the end it reads zero bits and
// remembers that it did (overrun()), which the caller turns into an error.
class BitReader {
 public:
  void init(std::string_view data) {
    p_ = reinterpret_cast<const uint8_t*>(data.data());
    end_ = p_ + data.size();
    buf_ = 0;
    avail_ = 0;
    consumed_ = 0;
    limit_ = 8 * static_cast<uint64_t>(data.size());
  }
  // At least 57 bits in the buffer. With 8 bytes left, one load: the
  // bytes below the buffer's valid bits are or-ed in again by the next
  // refill at the same place (the same bits), so they do no harm.
  void refill() {
    if (avail_ > 56) return;
    if (end_ - p_ >= 8) {
      uint64_t w;
      std::memcpy(&w, p_, 8);
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
      w = __builtin_bswap64(w);  // the stream is most significant bit first
#elif !defined(__BYTE_ORDER__) || __BYTE_ORDER__ != __ORDER_BIG_ENDIAN__
#error "byte order unknown"
#endif
      buf_ |= w >> avail_;
      const int take = (63 - avail_) >> 3;
      p_ += take;
      avail_ += 8 * take;
      return;
    }
    while (avail_ <= 56) {
      const uint64_t byte = p_ < end_ ? *p_++ : 0;
      buf_ |= byte << (56 - avail_);
      avail_ += 8;
    }
  }
  uint32_t peek(int n) const { return static_cast<uint32_t>(buf_ >> (64 - n)); }  // 1 <= n <= 32
  void skip(int n) {
    buf_ <<= n;
    avail_ -= n;
    consumed_ += static_cast<uint64_t>(n);
  }
  bool overrun() const { return consumed_ > limit_; }
  uint64_t bits_read() const { return consumed_; }

 private:
  const uint8_t* p_ = nullptr;
  const uint8_t* end_ = nullptr;
  uint64_t buf_ = 0;
  int avail_ = 0;
  uint64_t consumed_ = 0, limit_ = 0;
};

// The decoder's codes, two lookups deep: per used context a primary table
// of 2^kTablePrimary entries indexed by the next kTablePrimary bits, which
// resolves every code word up to that length; a longer one's prefix points
// at a secondary table indexed by the bits after it. The primary tables of
// all contexts stay small enough for the first-level cache (at most 210 x
// 256 bytes), where one flat 2^11 table per context (470 KB on the bunny)
// missed it on most lookups.
constexpr int kTablePrimary = 7;
class TableSet {
 public:
  // Reads the table block for `contexts` contexts (its map map_bytes
  // long); false with the reason.
  bool read(ByteReader& r, int contexts, std::string& why, int map_bytes = kTableMapBytes);
  bool has(int ctx) const {
    return ctx >= 0 && ctx < static_cast<int>(table_.size()) && table_[static_cast<size_t>(ctx)] != none_;
  }
  // One residual of context ctx (0 <= ctx < the read's `contexts`); false
  // on a code word the table does not assign, and for a context without a
  // table.
  __attribute__((always_inline)) bool decode(BitReader& b, int ctx, int32_t& r) const {
    b.refill();
    uint16_t e = primary_[table_[static_cast<size_t>(ctx)] + b.peek(kTablePrimary)];
    if (e & kSecondary)
      e = secondary_[(static_cast<size_t>(e & ~kSecondary) << kSecondaryBits) +
                     (b.peek(kTableMaxLength) & ((1u << kSecondaryBits) - 1))];
    if (e == 0) return false;
    b.skip(e & 15);
    const int s = (e >> 4) - 1;
    if (s <= 2 * kTableDirect) {
      r = s - kTableDirect;
      return true;
    }
    const int m = s - (2 * kTableDirect + 1), n = (m >> 1) + kTableEscapeLength;
    const uint32_t raw = b.peek(n - 1);
    b.skip(n - 1);
    const int32_t mag = static_cast<int32_t>((uint32_t{1} << (n - 1)) | raw);
    r = (m & 1) ? -mag : mag;
    return true;
  }

 private:
  static constexpr int kSecondaryBits = kTableMaxLength - kTablePrimary;
  static constexpr uint16_t kSecondary = 0x8000;  // primary entry: index of a secondary table
  std::vector<uint32_t> table_;        // per context: where its primary table starts (none_ if it has none)
  uint32_t none_ = 0;                  // where the all-zero primary table starts
  std::vector<uint16_t> primary_;      // (symbol + 1) << 4 | length, kSecondary | table, or 0: no code word
  std::vector<uint16_t> secondary_;    // (symbol + 1) << 4 | length, or 0
};

}  // namespace tsm

// Adaptive binary range coder (entropy coding stage; replaces the Huffman
// coding of seed 004 §3-4, see design notes §6 "a real entropy coder with
// adaptive contexts"; FORMAT.md §5). Probabilities are 15-bit; each model
// counts its updates and adapts by a shift that grows with the count (about
// log2(n + 2): the first bits it sees move it like a frequency count, later
// ones average over 2^7 bits), and stays within [kProbMin, kProbMax] so that
// every modelled decision costs a minimum (the stream budget below).
// Integers are coded as an adaptive bit length class followed by mantissa
// bits (the top ones modelled, the rest direct).
//
// The decoder is safe on any input: reading past the end yields zero bytes
// and counts an overrun, which callers check (overrun() > kMaxOverrun =>
// truncated). The encoder relies on that: it ends a stream on the shortest
// value its last interval holds and leaves out up to 8 trailing zero bytes.
#pragma once
#include <algorithm>
#include <cstdint>
#include <string>
#include <string_view>

namespace tsm {

constexpr int kProbBits = 15;
constexpr uint32_t kProbOne = 1u << kProbBits;
constexpr uint32_t kProbMax = kProbOne - 64;  // probability of a 0 bit, at most
constexpr uint32_t kProbMin = 64;             // and at least
constexpr int kAdaptLimit = 7;                // the slowest adaptation: by 1/128
constexpr int kAdaptCountMax = 1 << kAdaptLimit;

// A modelled decision keeps at most 1 - 64/32768 + 64/2^24 of the range
// (p within [64, 32704], and the rounding of range >> 15 with range >= 2^24),
// so it costs at least 0.0028146 bits and n coded bytes hold at most 2843 n
// decisions: the decoder refuses counts a stream is too short to code
// before it allocates for them (FORMAT.md §9, the stream budget).
constexpr uint64_t kMaxDecisionsPerByte = 2843;
inline uint64_t max_decisions(uint64_t stream_bytes) { return kMaxDecisionsPerByte * (stream_bytes + 8); }

// The shift of a model's n-th update: floor(log2(n + 2)), at most kAdaptLimit.
struct AdaptTable {
  uint8_t shift[kAdaptCountMax + 1];
  constexpr AdaptTable() : shift() {
    for (int n = 0; n <= kAdaptCountMax; ++n) {
      int s = 0;
      while ((2 << s) <= n + 2) ++s;
      shift[n] = static_cast<uint8_t>(s < kAdaptLimit ? s : kAdaptLimit);
    }
  }
};
inline constexpr AdaptTable kAdapt{};

struct Prob {
  uint16_t p = kProbOne / 2;  // probability of a 0 bit, in 1/32768
  uint16_t n = 0;             // updates so far, up to kAdaptCountMax
};

template <class P>
inline void adapt(P& prob, int b) {
  const int s = kAdapt.shift[prob.n];
  prob.n = static_cast<uint16_t>(prob.n + (prob.n < kAdaptCountMax));
  if (!b)
    prob.p = static_cast<uint16_t>(std::min<uint32_t>(prob.p + ((kProbOne - prob.p) >> s), kProbMax));
  else
    prob.p = static_cast<uint16_t>(std::max<uint32_t>(prob.p - (prob.p >> s), kProbMin));
}

// A probability its model initializes on first use (the mantissa rows of
// UIntModelT): a model set of many contexts then costs nothing to create,
// so a small mesh or segment does not pay for the contexts it never uses.
struct LazyProb {
  uint16_t p;
  uint16_t n;
};

class RangeEncoder {
 public:
  template <class P>
  void bit(P& prob, int b) {
    uint32_t bound = (range_ >> kProbBits) * prob.p;
    if (!b) {
      range_ = bound;
    } else {
      low_ += bound;
      range_ -= bound;
    }
    adapt(prob, b);
    while (range_ < (1u << 24)) {
      range_ <<= 8;
      shift_low();
    }
  }
  // Equiprobable bits, most significant first (n <= 32).
  void direct(uint32_t value, int n) {
    for (int i = n - 1; i >= 0; --i) {
      range_ >>= 1;
      if ((value >> i) & 1) low_ += range_;
      while (range_ < (1u << 24)) {
        range_ <<= 8;
        shift_low();
      }
    }
  }
  // Flushes and returns the coded bytes; the encoder is reset.
  std::string finish();

 private:
  void shift_low();
  uint64_t low_ = 0;
  uint32_t range_ = 0xFFFFFFFFu;
  uint8_t cache_ = 0;
  uint64_t cache_size_ = 1;
  std::string out_;
};

class RangeDecoder {
 public:
  RangeDecoder() = default;
  explicit RangeDecoder(std::string_view data) { init(data); }
  void init(std::string_view data);
  template <class P>
  int bit(P& prob) {
    uint32_t bound = (range_ >> kProbBits) * prob.p;
    int b;
    if (code_ < bound) {
      range_ = bound;
      b = 0;
    } else {
      code_ -= bound;
      range_ -= bound;
      b = 1;
    }
    adapt(prob, b);
    while (range_ < (1u << 24)) {
      range_ <<= 8;
      code_ = (code_ << 8) | next_byte();
    }
    return b;
  }
  uint32_t direct(int n) {
    uint32_t v = 0;
    for (int i = 0; i < n; ++i) {
      range_ >>= 1;
      uint32_t b = code_ >= range_;
      if (b) code_ -= range_;
      v = (v << 1) | b;
      while (range_ < (1u << 24)) {
        range_ <<= 8;
        code_ = (code_ << 8) | next_byte();
      }
    }
    return v;
  }
  // Bytes requested past the end of the data (a few are normal at the very
  // end of a stream; callers compare against kMaxOverrun).
  uint64_t overrun() const { return overrun_; }
  static constexpr uint64_t kMaxOverrun = 8;

 private:
  uint32_t next_byte() {
    if (p_ < end_) return *p_++;
    ++overrun_;
    return 0;
  }
  const uint8_t* p_ = nullptr;
  const uint8_t* end_ = nullptr;
  uint32_t range_ = 0xFFFFFFFFu;
  uint32_t code_ = 0;
  uint64_t overrun_ = 0;
};

// An adaptive model for a symbol of `Bits` bits (a binary tree of contexts).
template <int Bits>
struct BitTreeModel {
  Prob probs[1u << Bits];
  void encode(RangeEncoder& e, uint32_t symbol) {
    uint32_t node = 1;
    for (int i = Bits - 1; i >= 0; --i) {
      int b = (symbol >> i) & 1;
      e.bit(probs[node], b);
      node = (node << 1) | static_cast<uint32_t>(b);
    }
  }
  uint32_t decode(RangeDecoder& d) {
    uint32_t node = 1;
    for (int i = 0; i < Bits; ++i) node = (node << 1) | static_cast<uint32_t>(d.bit(probs[node]));
    return node - (1u << Bits);
  }
};

inline int bit_length(uint64_t x) { return x ? 64 - __builtin_clzll(x) : 0; }

// An adaptive model for unsigned integers up to 2^32 - 2: the bit length of
// v + 1 as a 6-bit tree symbol, then the bits below the leading one; the top
// M of them are modelled per length (a binary tree of contexts, so spiky
// distributions such as multiples of a lattice spacing are learned), the
// rest are direct bits.
template <int M>
struct UIntModelT {
  static constexpr int kModelled = M;
  // User-provided, so that value-initialization (make_unique<T>()) of a set
  // of models does not zero the mantissa rows either: they are set up on
  // first use (`ready`).
  UIntModelT() {}
  BitTreeModel<6> length;
  uint64_t ready = 0;  // bit n: mantissa row n is initialized
  LazyProb mantissa[33][1 << M];
  LazyProb* row(int n) {
    if (!((ready >> n) & 1)) {
      for (LazyProb& q : mantissa[n]) q = LazyProb{kProbOne / 2, 0};
      ready |= uint64_t{1} << n;
    }
    return mantissa[n];
  }
  void encode(RangeEncoder& e, uint32_t v) {
    uint64_t x = static_cast<uint64_t>(v) + 1;
    int n = bit_length(x) - 1;  // 0..32
    length.encode(e, static_cast<uint32_t>(n));
    int top = n < M ? n : M;
    uint32_t ctx = 1;
    LazyProb* mrow = top ? row(n) : nullptr;
    for (int i = 0; i < top; ++i) {
      int b = static_cast<int>((x >> (n - 1 - i)) & 1);
      e.bit(mrow[ctx], b);
      ctx = (ctx << 1) | static_cast<uint32_t>(b);
    }
    int rest = n - top;
    if (rest > 0) e.direct(static_cast<uint32_t>(x & ((uint64_t{1} << rest) - 1)), rest);
  }
  // Returns 0xFFFFFFFF on an impossible length.
  uint32_t decode(RangeDecoder& d) {
    int n = static_cast<int>(length.decode(d));
    if (n > 32) return 0xFFFFFFFFu;
    uint64_t x = 1;
    int top = n < M ? n : M;
    uint32_t ctx = 1;
    LazyProb* mrow = top ? row(n) : nullptr;
    for (int i = 0; i < top; ++i) {
      int b = d.bit(mrow[ctx]);
      ctx = (ctx << 1) | static_cast<uint32_t>(b);
      x = (x << 1) | static_cast<uint64_t>(b);
    }
    int rest = n - top;
    if (rest > 0) x = (x << rest) | d.direct(rest);
    uint64_t v = x - 1;
    return v >= 0xFFFFFFFFu ? 0xFFFFFFFFu : static_cast<uint32_t>(v);
  }
};

// Signed integers: zero flag, sign, magnitude - 1.
template <int M>
struct SIntModelT {
  Prob zero, sign;
  UIntModelT<M> magnitude;
  void encode(RangeEncoder& e, int32_t v) {
    e.bit(zero, v != 0);
    if (v == 0) return;
    e.bit(sign, v < 0);
    uint32_t mag = v < 0 ? static_cast<uint32_t>(-static_cast<int64_t>(v)) : static_cast<uint32_t>(v);
    magnitude.encode(e, mag - 1);
  }
  int32_t decode(RangeDecoder& d) {
    if (!d.bit(zero)) return 0;
    int neg = d.bit(sign);
    uint32_t m = magnitude.decode(d);
    if (m >= 0x7FFFFFFFu) m = 0x7FFFFFFEu;  // out of range on corrupt data; callers validate
    int32_t v = static_cast<int32_t>(m + 1);
    return neg ? -v : v;
  }
};

using UIntModel = UIntModelT<2>;
using SIntModel = SIntModelT<2>;

}  // namespace tsm

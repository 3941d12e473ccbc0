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
    bit_fixed(prob.p, b);
    adapt(prob, b);
  }
  // A bit with a given probability of 0 (kProbMin..kProbMax), nothing adapted.
  void bit_fixed(uint32_t p0, int b) {
    uint32_t bound = (range_ >> kProbBits) * p0;
    if (!b) {
      range_ = bound;
    } else {
      low_ += bound;
      range_ -= bound;
    }
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
    const int b = bit_fixed(prob.p);
    adapt(prob, b);
    return b;
  }
  // A bit with a given probability of 0, nothing adapted.
  int bit_fixed(uint32_t p0) {
    uint32_t bound = (range_ >> kProbBits) * p0;
    int b;
    if (code_ < bound) {
      range_ = bound;
      b = 0;
    } else {
      code_ -= bound;
      range_ -= bound;
      b = 1;
    }
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
  // Bytes taken from the data so far (past its end too): the coder reads 4
  // ahead, so differences between two points are exact to a few bytes.
  uint64_t bytes_read() const { return static_cast<uint64_t>(p_ - begin_) + overrun_; }

 private:
  uint32_t next_byte() {
    if (p_ < end_) return *p_++;
    ++overrun_;
    return 0;
  }
  const uint8_t* begin_ = nullptr;
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

// 0 for 0, else floor(log2 x) + 1; without a branch on x == 0 (residual
// sums are 0 often enough and at random).
inline int bit_length(uint64_t x) { return 64 - __builtin_clzll(x | 1) - (x == 0); }

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

// Logistic mixing (FORMAT.md §8.1.1): a decision coded
// with two adaptive models at once, A and B, each seeing a different
// context. Their probabilities are mapped to the logistic domain
// (stretch), weighted by a small online-trained weight vector, and mapped
// back (squash); both models then adapt as usual and the weights take a
// gradient step towards the coded bit. Integer arithmetic only, so every
// decoder computes the same probabilities.
constexpr int kSquashTable[33] = {1,    2,    4,    6,    10,   17,   27,   45,   74,   120,  194,
                                  311,  488,  747,  1102, 1546, 2048, 2550, 2994, 3349, 3608, 3785,
                                  3902, 3976, 4022, 4051, 4069, 4079, 4086, 4090, 4092, 4094, 4095};
// 1 / (1 + e^(-d/256)) in 1/4096, d clamped to [-2047, 2047]: linear
// between the table's points, which are e^(-x) at x = -8, -7.5, .., 8.
constexpr int squash(int d) {
  d = d < -2047 ? -2047 : d > 2047 ? 2047 : d;
  const int j = (d + 2048) >> 7, w = (d + 2048) & 127;
  return (kSquashTable[j] * (128 - w) + kSquashTable[j + 1] * w + 64) >> 7;
}
// The inverse: for a 12-bit probability, the smallest d whose squash
// reaches it (2047 above squash(2047)).
struct StretchTable {
  int16_t v[4096];
  constexpr StretchTable() : v() {
    int next = 0;
    for (int d = -2047; d <= 2047; ++d) {
      const int p = squash(d);
      for (; next <= p; ++next) v[next] = static_cast<int16_t>(d);
    }
    for (; next < 4096; ++next) v[next] = 2047;
  }
};
inline constexpr StretchTable kStretch{};

constexpr int kMixWeightShift = 16;        // weights in 1/65536
constexpr int kMixRateShift = 9;           // gradient step: input * error / 512
constexpr int32_t kMixWeightLimit = 1 << 22;
constexpr int kMixBias = 256;              // the third input, a constant

struct MixWeights {
  int32_t w[3] = {1 << (kMixWeightShift - 1), 1 << (kMixWeightShift - 1), 0};
};

struct MixStep {
  int x[3];  // stretched inputs
  int p;     // mixed probability of a 0 bit, 1/4096
  uint32_t coded() const {  // as the range coder's 15-bit probability
    return std::clamp<uint32_t>(static_cast<uint32_t>(p) << 3, kProbMin, kProbMax);
  }
};

// The shifts below divide by powers of two rounding towards minus infinity
// (FORMAT.md §8.1.1), which is what >> does to negative values with every
// compiler we build with (and by definition from C++20).
static_assert((-5 >> 1) == -3 && (int64_t{-5} >> 1) == -3, "arithmetic right shift");

__attribute__((always_inline)) inline MixStep mix_predict(uint32_t pa, uint32_t pb, const MixWeights& m) {
  MixStep s{{kStretch.v[pa >> 3], kStretch.v[pb >> 3], kMixBias}, 0};
  const int64_t dot = int64_t{m.w[0]} * s.x[0] + int64_t{m.w[1]} * s.x[1] + int64_t{m.w[2]} * s.x[2];
  s.p = squash(static_cast<int>(std::clamp<int64_t>(dot >> kMixWeightShift, -2047, 2047)));
  return s;
}

template <class PA, class PB>
__attribute__((always_inline)) inline void mix_update(PA& a, PB& b, MixWeights& m, const MixStep& s, int bit) {
  adapt(a, bit);
  adapt(b, bit);
  const int err = (bit ? 0 : 4095) - s.p;
  for (int k = 0; k < 3; ++k)  // |x * err| < 2^23
    m.w[k] = std::clamp(m.w[k] + ((s.x[k] * err) >> kMixRateShift), -kMixWeightLimit, kMixWeightLimit);
}

// The coder side of a mixed signed integer: the encoder passes the bits it
// codes, the decoder returns the bits it reads; code_mixed_sint below is the
// same walk for both.
struct MixEncodeOp {
  RangeEncoder& e;
  template <class PA, class PB>
  int bit(PA& a, PB& b, MixWeights& m, int bit) {
    const MixStep s = mix_predict(a.p, b.p, m);
    e.bit_fixed(s.coded(), bit);
    mix_update(a, b, m, s, bit);
    return bit;
  }
  uint32_t direct(uint32_t v, int n) {
    e.direct(v, n);
    return v;
  }
};
struct MixDecodeOp {
  RangeDecoder& d;
  template <class PA, class PB>
  int bit(PA& a, PB& b, MixWeights& m, int) {
    const MixStep s = mix_predict(a.p, b.p, m);
    const int bit = d.bit_fixed(s.coded());
    mix_update(a, b, m, s, bit);
    return bit;
  }
  uint32_t direct(uint32_t, int n) { return d.direct(n); }
};

// Weight sets of a mixed signed integer: zero flag, sign, the six levels of
// the length tree, then one per modelled mantissa bit.
template <int M>
constexpr int kMixKinds = 8 + M;

// A signed integer as SIntModelT<M> codes it (zero flag, sign, magnitude - 1
// as length and mantissa), every modelled decision mixed from A and B
// (same node in both) with weights w[kind]. v: the encoder's value.
// Returns the value (decoder: +-0x7FFFFFFF on an impossible length).
template <int M, class Op>
int32_t code_mixed_sint(Op& op, SIntModelT<M>& A, SIntModelT<M>& B, MixWeights* w, int32_t v) {
  if (!op.bit(A.zero, B.zero, w[0], v != 0)) return 0;
  const int neg = op.bit(A.sign, B.sign, w[1], v < 0);
  const uint64_t mag = v < 0 ? static_cast<uint64_t>(-static_cast<int64_t>(v)) : static_cast<uint64_t>(v);
  const int len = v ? bit_length(mag) - 1 : 0;  // the encoder's length
  uint32_t node = 1;
  for (int k = 0; k < 6; ++k) {
    const int b = op.bit(A.magnitude.length.probs[node], B.magnitude.length.probs[node], w[2 + k], (len >> (5 - k)) & 1);
    node = (node << 1) | static_cast<uint32_t>(b);
  }
  const int n = static_cast<int>(node) - 64;
  if (n > 32) return neg ? -0x7FFFFFFF : 0x7FFFFFFF;
  uint64_t x = 1;
  const int top = n < M ? n : M;
  uint32_t ctx = 1;
  LazyProb* ra = top ? A.magnitude.row(n) : nullptr;
  LazyProb* rb = top ? B.magnitude.row(n) : nullptr;
  for (int k = 0; k < top; ++k) {
    const int b = op.bit(ra[ctx], rb[ctx], w[8 + k], static_cast<int>((mag >> (n - 1 - k)) & 1));
    ctx = (ctx << 1) | static_cast<uint32_t>(b);
    x = (x << 1) | static_cast<uint64_t>(b);
  }
  const int rest = n - top;
  if (rest > 0) x = (x << rest) | op.direct(static_cast<uint32_t>(mag & ((uint64_t{1} << rest) - 1)), rest);
  const int32_t m = x >= 0x7FFFFFFFu ? 0x7FFFFFFF : static_cast<int32_t>(x);
  return neg ? -m : m;
}

using UIntModel = UIntModelT<2>;
using SIntModel = SIntModelT<2>;

}  // namespace tsm

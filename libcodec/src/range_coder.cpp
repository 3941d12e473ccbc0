// Adaptive binary range coder: see range_coder.hpp (entropy coding stage).
#include "range_coder.hpp"

namespace tsm {

void RangeEncoder::shift_low() {
  if (static_cast<uint32_t>(low_) < 0xFF000000u || (low_ >> 32) != 0) {
    uint8_t carry = static_cast<uint8_t>(low_ >> 32);
    uint8_t temp = cache_;
    do {
      out_.push_back(static_cast<char>(static_cast<uint8_t>(temp + carry)));
      temp = 0xFF;
    } while (--cache_size_ != 0);
    cache_ = static_cast<uint8_t>(low_ >> 24);
  }
  ++cache_size_;
  low_ = (low_ & 0x00FFFFFFu) << 8;
}

std::string RangeEncoder::finish() {
  for (int i = 0; i < 5; ++i) shift_low();
  // The first byte is always 0 (the cache's initial value): drop it.
  std::string out = out_.substr(1);
  *this = RangeEncoder();
  return out;
}

void RangeDecoder::init(std::string_view data) {
  p_ = reinterpret_cast<const uint8_t*>(data.data());
  end_ = p_ + data.size();
  range_ = 0xFFFFFFFFu;
  code_ = 0;
  overrun_ = 0;
  for (int i = 0; i < 4; ++i) code_ = (code_ << 8) | next_byte();
}

namespace {
int bit_length(uint64_t x) {
  int n = 0;
  while (x) {
    ++n;
    x >>= 1;
  }
  return n;
}
}  // namespace

void UIntModel::encode(RangeEncoder& e, uint32_t v) {
  uint64_t x = static_cast<uint64_t>(v) + 1;
  int n = bit_length(x) - 1;  // 0..32
  length.encode(e, static_cast<uint32_t>(n));
  int top = n < kModelled ? n : kModelled;
  uint32_t ctx = 1;
  for (int i = 0; i < top; ++i) {
    int b = static_cast<int>((x >> (n - 1 - i)) & 1);
    e.bit(mantissa[n][ctx & ((1 << kModelled) - 1)], b);
    ctx = (ctx << 1) | static_cast<uint32_t>(b);
  }
  int rest = n - top;
  if (rest > 0) e.direct(static_cast<uint32_t>(x & ((uint64_t{1} << rest) - 1)), rest);
}

uint32_t UIntModel::decode(RangeDecoder& d) {
  int n = static_cast<int>(length.decode(d));
  if (n > 32) return 0xFFFFFFFFu;
  uint64_t x = 1;
  int top = n < kModelled ? n : kModelled;
  uint32_t ctx = 1;
  for (int i = 0; i < top; ++i) {
    int b = d.bit(mantissa[n][ctx & ((1 << kModelled) - 1)]);
    ctx = (ctx << 1) | static_cast<uint32_t>(b);
    x = (x << 1) | static_cast<uint64_t>(b);
  }
  int rest = n - top;
  if (rest > 0) x = (x << rest) | d.direct(rest);
  uint64_t v = x - 1;
  return v >= 0xFFFFFFFFu ? 0xFFFFFFFFu : static_cast<uint32_t>(v);
}

void SIntModel::encode(RangeEncoder& e, int32_t v) {
  e.bit(zero, v != 0);
  if (v == 0) return;
  e.bit(sign, v < 0);
  uint32_t mag = v < 0 ? static_cast<uint32_t>(-static_cast<int64_t>(v)) : static_cast<uint32_t>(v);
  magnitude.encode(e, mag - 1);
}

int32_t SIntModel::decode(RangeDecoder& d) {
  if (!d.bit(zero)) return 0;
  int neg = d.bit(sign);
  uint32_t m = magnitude.decode(d);
  if (m >= 0x7FFFFFFFu) m = 0x7FFFFFFEu;  // out of range on corrupt data; callers validate
  int32_t v = static_cast<int32_t>(m + 1);
  return neg ? -v : v;
}

}  // namespace tsm

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
  // Any value in [low, low + range) decodes the same symbols, and the decoder
  // reads bytes past the end of a stream as zeros: take the value in that
  // interval with the most trailing zero bits (range >= 2^24, so one with 24
  // exists), shift it out, and leave its trailing zero bytes unwritten, at
  // most kMaxOverrun of them so the decoder does not take the stream for a
  // truncated one (FORMAT.md §8.1).
  for (uint64_t mask : {0xFFFFFFFFull, 0xFFFFFFull}) {
    const uint64_t v = (low_ + mask) & ~mask;
    if (v < low_ + range_) {
      low_ = v;
      break;
    }
  }
  for (int i = 0; i < 5; ++i) shift_low();
  // The first byte is always 0 (the cache's initial value): drop it.
  std::string out = out_.substr(1);
  size_t zeros = 0;
  while (zeros < RangeDecoder::kMaxOverrun && zeros < out.size() && out[out.size() - 1 - zeros] == 0) ++zeros;
  out.resize(out.size() - zeros);
  *this = RangeEncoder();
  return out;
}

void RangeDecoder::init(std::string_view data) {
  begin_ = p_ = reinterpret_cast<const uint8_t*>(data.data());
  end_ = p_ + data.size();
  range_ = 0xFFFFFFFFu;
  code_ = 0;
  overrun_ = 0;
  for (int i = 0; i < 4; ++i) code_ = (code_ << 8) | next_byte();
}

}  // namespace tsm

// Static prefix codes per context: see table_coder.hpp (entropy coding
// stage; FORMAT.md §8.5.11).
#include "table_coder.hpp"

#include <algorithm>

#include "byte_io.hpp"
#include "range_coder.hpp"  // bit_length

namespace tsm {

TableSymbol table_symbol(int64_t r) {
  if (r >= -kTableDirect && r <= kTableDirect) return {static_cast<int>(r) + kTableDirect, 0, 0};
  const uint32_t mag = static_cast<uint32_t>(r < 0 ? -r : r);
  const int n = bit_length(mag);  // kTableEscapeLength .. kTableMaxBitLength
  return {2 * kTableDirect + 1 + 2 * (n - kTableEscapeLength) + (r < 0 ? 1 : 0), n - 1, mag & ((1u << (n - 1)) - 1)};
}

namespace {

// Plain Huffman lengths (no limit) of the positive counts.
CodeLengths huffman_lengths(const std::array<uint64_t, kTableSymbols>& count) {
  CodeLengths len{};
  struct Node {
    uint64_t weight;
    int id;  // < kTableSymbols: a leaf; else an inner node
  };
  std::vector<Node> heap;
  std::vector<int> parent(2 * kTableSymbols, -1);
  for (int s = 0; s < kTableSymbols; ++s)
    if (count[s]) heap.push_back({count[s], s});
  if (heap.size() == 1) {
    len[heap[0].id] = 1;
    return len;
  }
  auto later = [](const Node& a, const Node& b) { return a.weight != b.weight ? a.weight > b.weight : a.id > b.id; };
  std::make_heap(heap.begin(), heap.end(), later);
  int next = kTableSymbols;
  while (heap.size() > 1) {
    std::pop_heap(heap.begin(), heap.end(), later);
    const Node a = heap.back();
    heap.pop_back();
    std::pop_heap(heap.begin(), heap.end(), later);
    const Node b = heap.back();
    heap.pop_back();
    parent[a.id] = parent[b.id] = next;
    heap.push_back({a.weight + b.weight, next++});
    std::push_heap(heap.begin(), heap.end(), later);
  }
  for (int s = 0; s < kTableSymbols; ++s) {
    if (!count[s]) continue;
    int d = 0;
    for (int x = s; parent[x] >= 0; x = parent[x]) ++d;
    len[s] = static_cast<uint8_t>(d);
  }
  return len;
}

}  // namespace

CodeLengths table_code_lengths(const std::array<uint32_t, kTableSymbols>& count) {
  std::array<uint64_t, kTableSymbols> c;
  for (int s = 0; s < kTableSymbols; ++s) c[s] = count[s];
  // Too long a code word: flatten the counts (halve, keeping every seen
  // symbol at 1 or more) until none is; 63 symbols fit in 6 bits, so this ends.
  for (;;) {
    CodeLengths len = huffman_lengths(c);
    if (*std::max_element(len.begin(), len.end()) <= kTableMaxLength) return len;
    for (uint64_t& x : c)
      if (x) x = std::max<uint64_t>(1, x >> 1);
  }
}

std::array<uint32_t, kTableSymbols> canonical_codes(const CodeLengths& length) {
  // The first code of each length (the codes of length l follow those of
  // length l - 1, shifted), then each symbol the next of its length, in
  // symbol order: one pass over the symbols instead of one per length.
  std::array<uint32_t, kTableSymbols> code{};
  uint32_t count[kTableMaxLength + 1] = {}, next[kTableMaxLength + 1] = {};
  for (int s = 0; s < kTableSymbols; ++s)
    if (length[s] >= 1 && length[s] <= kTableMaxLength) ++count[length[s]];
  uint32_t first = 0;
  for (int l = 1; l <= kTableMaxLength; ++l) {
    next[l] = first;
    first = (first + count[l]) << 1;
  }
  for (int s = 0; s < kTableSymbols; ++s)
    if (length[s] >= 1 && length[s] <= kTableMaxLength) code[s] = next[length[s]]++;
  return code;
}

std::string write_tables(const std::vector<CodeLengths>& lengths, int map_bytes) {
  std::string out(static_cast<size_t>(map_bytes), '\0');
  ByteWriter w(out);
  for (size_t c = 0; c < lengths.size(); ++c) {
    int S = 0;
    for (int s = 0; s < kTableSymbols; ++s)
      if (lengths[c][s]) S = s + 1;
    if (S == 0) continue;
    out[c >> 3] = static_cast<char>(static_cast<uint8_t>(out[c >> 3]) | (1u << (c & 7)));
    w.u8(static_cast<uint8_t>(S));
    for (int s = 0; s < S; s += 2)
      w.u8(static_cast<uint8_t>(lengths[c][s] << 4 | (s + 1 < S ? lengths[c][s + 1] : 0)));
  }
  return out;
}

void TableEncoder::build() {
  for (size_t c = 0; c < count_.size(); ++c) {
    length_[c] = table_code_lengths(count_[c]);  // all zero for a context never counted: no table
    code_[c] = canonical_codes(length_[c]);
  }
}

void TableEncoder::put(BitWriter& w, int ctx, int64_t r) const {
  const TableSymbol t = table_symbol(r);
  const size_t c = static_cast<size_t>(ctx);
  w.put(code_[c][t.symbol], length_[c][t.symbol]);
  if (t.raw_bits) w.put(t.raw, t.raw_bits);
}

size_t TableEncoder::coded_bytes() const {
  uint64_t bits = 0;
  size_t table_bytes = 0;
  for (size_t c = 0; c < count_.size(); ++c) {
    int S = 0;
    for (int s = 0; s < kTableSymbols; ++s) {
      if (!count_[c][s]) continue;
      S = s + 1;
      const int raw = s <= 2 * kTableDirect ? 0 : (s - (2 * kTableDirect + 1)) / 2 + kTableEscapeLength - 1;
      bits += uint64_t{count_[c][s]} * (length_[c][s] + raw);
    }
    if (S) table_bytes += 1 + (S + 1) / 2;
  }
  return static_cast<size_t>((bits + 7) / 8) + table_bytes;
}

std::string write_table_block(const std::vector<CodeLengths>& lengths, int map_bytes, const std::string& bits) {
  std::string out;
  ByteWriter(out).u32(static_cast<uint32_t>(bits.size()));
  return out + write_tables(lengths, map_bytes) + bits;
}

bool read_table_block(ByteReader& r, int contexts, int map_bytes, TableSet& tables, BitReader& bits,
                      std::string& why, uint32_t* bit_bytes_out) {
  uint32_t bit_bytes;
  std::string_view bitstream;
  if (!r.u32(bit_bytes)) {
    why = "table block is truncated";
    return false;
  }
  if (!tables.read(r, contexts, why, map_bytes)) return false;
  if (!r.bytes(bit_bytes, bitstream)) {
    why = "the table-coded bit stream has " + std::to_string(bit_bytes) + " bytes, " +
          std::to_string(r.remaining()) + " remain";
    return false;
  }
  bits.init(bitstream);
  if (bit_bytes_out) *bit_bytes_out = bit_bytes;
  return true;
}

bool TableSet::read(ByteReader& r, int contexts, std::string& why, int map_bytes) {
  std::string_view map;
  if (contexts > 8 * map_bytes || !r.bytes(static_cast<size_t>(map_bytes), map)) {
    why = "table block is truncated";
    return false;
  }
  std::vector<int> slot(static_cast<size_t>(contexts), -1);  // per context: its primary table, or -1
  int used = 0;
  for (int c = 0; c < 8 * map_bytes; ++c) {
    if (!((static_cast<uint8_t>(map[c >> 3]) >> (c & 7)) & 1)) continue;
    if (c >= contexts) {
      why = "table for context " + std::to_string(c) + ", which does not exist";
      return false;
    }
    slot[static_cast<size_t>(c)] = used++;
  }
  // One more primary table, all zeros (no code word), which the contexts
  // without a table read: decode() refuses them without a check of its own.
  primary_.assign(static_cast<size_t>(used + 1) << kTablePrimary, 0);
  none_ = static_cast<uint32_t>(used) << kTablePrimary;
  table_.resize(slot.size());
  for (size_t c = 0; c < slot.size(); ++c) table_[c] = slot[c] < 0 ? none_ : static_cast<uint32_t>(slot[c]) << kTablePrimary;
  secondary_.clear();
  for (int c = 0; c < contexts; ++c) {
    if (table_[static_cast<size_t>(c)] == none_) continue;
    uint8_t S;
    if (!r.u8(S)) {
      why = "table block is truncated";
      return false;
    }
    if (S < 1 || S > kTableSymbols) {
      why = "table of context " + std::to_string(c) + " has " + std::to_string(S) + " symbols (1.." +
            std::to_string(kTableSymbols) + ")";
      return false;
    }
    CodeLengths len{};
    for (int s = 0; s < S; s += 2) {
      uint8_t b;
      if (!r.u8(b)) {
        why = "table block is truncated";
        return false;
      }
      len[s] = b >> 4;
      if (s + 1 < S) len[s + 1] = b & 15;
      else if (b & 15) {
        why = "table of context " + std::to_string(c) + ": padding nibble is not zero";
        return false;
      }
    }
    uint32_t kraft = 0;  // in units of 2^-kTableMaxLength
    for (int s = 0; s < kTableSymbols; ++s) {
      if (len[s] > kTableMaxLength) {
        why = "table of context " + std::to_string(c) + ": code length " + std::to_string(len[s]) + " above " +
              std::to_string(kTableMaxLength);
        return false;
      }
      if (len[s]) kraft += 1u << (kTableMaxLength - len[s]);
    }
    if (kraft == 0 || kraft > (1u << kTableMaxLength)) {
      why = "table of context " + std::to_string(c) + (kraft ? " has more code words than fit" : " is empty");
      return false;
    }
    const std::array<uint32_t, kTableSymbols> code = canonical_codes(len);
    uint16_t* t = &primary_[table_[static_cast<size_t>(c)]];
    for (int s = 0; s < kTableSymbols; ++s) {
      if (!len[s]) continue;
      const uint16_t entry = static_cast<uint16_t>((s + 1) << 4 | len[s]);
      if (len[s] <= kTablePrimary) {
        const int free = kTablePrimary - len[s];
        std::fill(t + (code[s] << free), t + ((code[s] + 1) << free), entry);
        continue;
      }
      // A longer code word: its first kTablePrimary bits select a secondary
      // table (made on first use; at most 2^kTablePrimary per context, so
      // the index fits below kSecondary), the rest index it.
      uint16_t& head = t[code[s] >> (len[s] - kTablePrimary)];
      if (!head) {
        head = static_cast<uint16_t>(kSecondary | (secondary_.size() >> kSecondaryBits));
        secondary_.resize(secondary_.size() + (size_t{1} << kSecondaryBits), 0);
      }
      uint16_t* sub = &secondary_[static_cast<size_t>(head & ~kSecondary) << kSecondaryBits];
      const int free = kTableMaxLength - len[s];
      const uint32_t low = (code[s] << free) & ((1u << kSecondaryBits) - 1);
      std::fill(sub + low, sub + low + (1u << free), entry);
    }
  }
  return true;
}

}  // namespace tsm

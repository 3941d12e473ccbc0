// libFuzzer target: decoding arbitrary bytes must return a Status, never
// crash, hang or allocate beyond what the input justifies (run.sh sets
// libFuzzer's -malloc_limit_mb; the caller limits below bound the output).
//
// Each input is decoded twice: as given (the container checks: magic,
// lengths, checksums), and again with every checksum recomputed
// (container_forge.hpp), so mutations reach the stream decoders behind the
// checksums, which is where a forged file would attack. A custom mutator
// helps them get there: two times in three it mutates the parsed container
// (a header count set to an interesting value, a section payload or the
// other header fields through libFuzzer's own mutations, a section dropped,
// duplicated or its codec changed) and lays it out again with lengths and
// checksums that match. For each decode:
//   * decode() and inspect() must agree: inspect() fails only if decode()
//     fails, and a decoded mesh has the counts inspect() reports;
//   * a decoded mesh must be valid with finite positions;
//   * the stream decoder, fed the bytes in chunks, accepts exactly what
//     decode() accepts and gives the same mesh;
//   * a decoded mesh must itself round-trip: encode() accepts it, decode()
//     gives it back, and the oracle tsm::compare_meshes says equal on its
//     grid (the codec's promise holds for every mesh, including one a
//     hostile file made).
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <random>
#include <string>
#include <string_view>
#include <utility>

#include "container_forge.hpp"
#include "tsm/compare.hpp"
#include "tsm/tsm.hpp"

namespace {

[[noreturn]] void fail(const char* what, const tsm::Status& s) {
  std::fprintf(stderr, "fuzz_decode: %s (%s)\n", what, s.to_string().c_str());
  __builtin_trap();
}

void check(std::string_view bytes) {
  tsm::Mesh mesh;
  tsm::DecodeOptions options;
  options.max_vertices = 1u << 20;
  options.max_faces = 1u << 21;
  const tsm::Status s = tsm::decode(bytes, mesh, options);
  if (s.code() == tsm::ErrorCode::internal) fail("decode reported an internal error", s);
  if (!s.ok() && s.message().empty()) fail("decode failed without a message", s);
  {
    tsm::StreamDecoder sd(options);
    const size_t chunk = 1 + bytes.size() % 97;
    tsm::Status ss;
    for (size_t at = 0; ss.ok() && at < bytes.size(); at += chunk) ss = sd.feed(bytes.substr(at, chunk));
    if (ss.ok()) ss = sd.finish();
    if (ss.code() == tsm::ErrorCode::internal) fail("the stream decoder reported an internal error", ss);
    if (ss.ok() != s.ok()) fail(s.ok() ? "the stream decoder refuses what decode() accepts" : "the stream decoder accepts what decode() refuses", s.ok() ? ss : s);
    if (s.ok() && (sd.mesh().positions != mesh.positions || sd.mesh().indices != mesh.indices ||
                   sd.mesh().face_offsets != mesh.face_offsets))
      fail("streamed and whole decoding differ", s);
  }
  tsm::FileInfo info;
  const tsm::Status si = tsm::inspect(bytes, info);
  if (si.code() == tsm::ErrorCode::internal) fail("inspect reported an internal error", si);
  if (!s.ok()) return;
  std::string why;
  if (!mesh.valid(&why)) fail(("decoded an invalid mesh: " + why).c_str(), s);
  if (!mesh.all_finite()) fail("decoded non-finite positions", s);
  if (!si.ok()) fail("decode accepted what inspect refuses", si);
  // A progressive file's header counts the base; its batches the levels.
  const bool progressive = !info.batches.empty();
  const uint64_t vertices = (progressive ? info.batches.back().vertices : info.vertex_count) + info.loose_vertices;
  const uint64_t faces = progressive ? info.batches.back().faces : info.face_count;
  if (vertices != mesh.vertex_count() || faces != mesh.face_count() ||
      (!progressive && info.corner_count != mesh.corner_count()))
    fail("inspect's counts differ from the decoded mesh", s);
  if (mesh.vertex_count() > (1u << 14) || mesh.corner_count() > (1u << 16)) return;  // keep executions fast
  // At level 0: the connectivity coder (the same at every level) sees the
  // hostile mesh; the higher levels' geometry trials are fuzz_roundtrip's,
  // and here they took three quarters of the time of an execution.
  std::string again;
  const int bits = info.quantization_bits;
  tsm::Status se = tsm::encode(mesh, tsm::EncodeOptions{bits, 0}, again);
  if (!se.ok()) fail("the encoder refuses a mesh the decoder produced", se);
  tsm::Mesh back;
  tsm::Status sd = tsm::decode(again, back);
  if (!sd.ok()) fail("a decoded mesh does not survive encode + decode", sd);
  tsm::CompareResult cr = tsm::compare_meshes(mesh, back, bits);
  if (!cr.equal) fail(("oracle: decoded mesh re-encoded differs: " + cr.difference).c_str(), sd);
}

}  // namespace

extern "C" size_t LLVMFuzzerMutate(uint8_t* data, size_t size, size_t max_size);

// Mutates s in place through libFuzzer's mutators, allowing it to grow a
// little (libFuzzer's mutators are not meant for empty data: seed it).
static void mutate_bytes(std::string& s, size_t grow, char seed) {
  if (s.empty()) {
    s.push_back(seed);
    return;
  }
  const size_t size = s.size();
  s.resize(size + grow + 1);
  s.resize(LLVMFuzzerMutate(reinterpret_cast<uint8_t*>(s.data()), size, size + grow + 1));
}

extern "C" size_t LLVMFuzzerCustomMutator(uint8_t* data, size_t size, size_t max_size, unsigned int seed) {
  std::minstd_rand rng(seed);
  tsm_fuzz::Container c;
  if (rng() % 3 == 0 || !tsm_fuzz::parse_container(std::string_view(reinterpret_cast<const char*>(data), size), c))
    return LLVMFuzzerMutate(data, size, max_size);
  static const uint64_t interesting[] = {
      0, 1, 2, 3, 255, 256, 65535, 65536, 1u << 20, (1u << 30) - 2, 1u << 30, 0xFFFFFFFFu, 1ull << 32, ~0ull};
  switch (rng() % 6) {
    case 0: {  // a count
      uint64_t& n = c.counts[rng() % 3];
      switch (rng() % 4) {
        case 0:
          n = interesting[rng() % (sizeof interesting / sizeof interesting[0])];
          break;
        case 1:
          n += 1 + rng() % 4;
          break;
        case 2:
          n -= n > 4 ? 1 + rng() % 4 : n;
          break;
        default:
          n *= 2 + rng() % 1000;
          break;
      }
      break;
    }
    case 1:
    case 2:
    case 3:  // a section payload
      if (!c.sections.empty()) mutate_bytes(c.sections[rng() % c.sections.size()].stored, 64, static_cast<char>(rng()));
      break;
    case 4:  // the other header fields
      mutate_bytes(c.other_fields, 8, static_cast<char>(rng()));
      break;
    default:  // the section list or a section's codec
      if (c.sections.empty()) break;
      const size_t i = rng() % c.sections.size();
      switch (rng() % 4) {
        case 0:
          c.sections.erase(c.sections.begin() + static_cast<std::ptrdiff_t>(i));
          break;
        case 1:
          c.sections.push_back(c.sections[i]);
          break;
        case 2:
          std::swap(c.sections[i], c.sections[rng() % c.sections.size()]);
          break;
        default:
          c.sections[i].codec = static_cast<uint8_t>(rng() % 3);
          c.sections[i].raw_length = c.sections[i].stored.size() * (1 + rng() % 1024);
          break;
      }
      break;
  }
  const std::string out = tsm_fuzz::build_container(c);
  if (out.size() > max_size) return LLVMFuzzerMutate(data, size, max_size);
  std::memcpy(data, out.data(), out.size());
  return out.size();
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  check(bytes);
  std::string fixed(bytes);
  if (tsm_fuzz::fix_checksums(fixed) > 0 && fixed != bytes) check(fixed);
  return 0;
}

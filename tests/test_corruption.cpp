// Hostile and damaged .tsm input through the public API (tsm::encode, decode,
// inspect): every truncation, thousands of bit flips and byte overwrites,
// damage behind recomputed checksums, forged headers with huge counts, and a
// ceiling on the memory the decoder may take for a given input.
//
// Format-agnostic: the tests damage whatever encode() produces. They know
// only the container framing (format-spec/FORMAT.md §2-4: magic, version,
// header fields starting with the three count varints, then id and codec /
// stored length / raw length (zstd only) / payload / XXH32 per section, the
// first section's checksum covering the header too, end marker), which the
// geometry rewrite does not change; the payloads are treated as opaque bytes.
//
// This file is its own test binary (tsm_corruption_tests): it replaces the
// global operator new / delete to count the bytes the decoder holds, and can
// arm a ceiling at which operator new throws std::bad_alloc instead of
// allocating, so a decoder that would take gigabytes for a forged input is
// caught cheaply and reported instead of exhausting the machine.
#include <gtest/gtest.h>
#include <malloc.h>
#include <xxhash.h>
#include <zstd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <new>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "container_forge.hpp"
#include "mesh_gen.hpp"
#include "test_util.hpp"
#include "tsm/io.hpp"
#include "tsm/tsm.hpp"

// --- Counting allocator -----------------------------------------------------

namespace heap {

// Bytes held through operator new (malloc_usable_size of each block), all the
// time; memory taken with malloc directly (zstd's contexts) is not counted.
std::atomic<size_t> live{0};
std::atomic<bool> armed{false};
size_t baseline = 0, peak = 0, ceiling = 0, refused_request = 0;

size_t held_since_armed() {
  const size_t l = live.load(std::memory_order_relaxed);
  return l > baseline ? l - baseline : 0;  // blocks from before may be freed meanwhile
}

void* take(size_t n, size_t align) {
  if (n == 0) n = 1;
  if (armed.load(std::memory_order_relaxed)) {
    if (n > ceiling || held_since_armed() + n > ceiling) {
      refused_request = std::max(refused_request, n);
      return nullptr;
    }
  }
  void* p =
      align > alignof(std::max_align_t) ? std::aligned_alloc(align, (n + align - 1) / align * align) : std::malloc(n);
  if (!p) return nullptr;
  live.fetch_add(malloc_usable_size(p), std::memory_order_relaxed);
  if (armed.load(std::memory_order_relaxed)) peak = std::max(peak, held_since_armed());
  return p;
}

void give(void* p) {
  if (!p) return;
  live.fetch_sub(malloc_usable_size(p), std::memory_order_relaxed);
  std::free(p);
}

void* take_or_throw(size_t n, size_t align) {
  void* p = take(n, align);
  if (!p) throw std::bad_alloc();
  return p;
}

}  // namespace heap

void* operator new(std::size_t n) { return heap::take_or_throw(n, 0); }
void* operator new[](std::size_t n) { return heap::take_or_throw(n, 0); }
void* operator new(std::size_t n, const std::nothrow_t&) noexcept { return heap::take(n, 0); }
void* operator new[](std::size_t n, const std::nothrow_t&) noexcept { return heap::take(n, 0); }
void* operator new(std::size_t n, std::align_val_t a) { return heap::take_or_throw(n, static_cast<size_t>(a)); }
void* operator new[](std::size_t n, std::align_val_t a) { return heap::take_or_throw(n, static_cast<size_t>(a)); }
void* operator new(std::size_t n, std::align_val_t a, const std::nothrow_t&) noexcept {
  return heap::take(n, static_cast<size_t>(a));
}
void* operator new[](std::size_t n, std::align_val_t a, const std::nothrow_t&) noexcept {
  return heap::take(n, static_cast<size_t>(a));
}
void operator delete(void* p) noexcept { heap::give(p); }
void operator delete[](void* p) noexcept { heap::give(p); }
void operator delete(void* p, std::size_t) noexcept { heap::give(p); }
void operator delete[](void* p, std::size_t) noexcept { heap::give(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { heap::give(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { heap::give(p); }
void operator delete(void* p, std::align_val_t) noexcept { heap::give(p); }
void operator delete[](void* p, std::align_val_t) noexcept { heap::give(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { heap::give(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { heap::give(p); }
void operator delete(void* p, std::align_val_t, const std::nothrow_t&) noexcept { heap::give(p); }
void operator delete[](void* p, std::align_val_t, const std::nothrow_t&) noexcept { heap::give(p); }

namespace {

using tsm::ErrorCode;
using tsm::Mesh;
using tsm_test::random_bytes;

// The memory a decoder may hold for an input of n bytes. Every decoded
// element has to be paid for with coded bits; the range coder's cheapest
// modelled decision still costs about 0.0028 bits (FORMAT.md §9, the stream
// budget), so how far a file may expand is bounded, but the bound is large:
// the most compressible genuine files measured (flat grids at q = 1) decode
// to ~23 KB of decoder memory per input byte for a million vertices (29 KB
// measured in GenuineFilesDecodeUnderTheCeiling, which prints its largest
// ratio), slowly more as they grow, and a forged header around the genuine connectivity
// streams of such a grid (ForgedCountsAroundGenuineStreams, there at a
// smaller size) reaches ~31 KB per byte. A zstd section
// may expand 1024 times (FORMAT.md §4.1). 64 KiB per input byte plus a fixed
// allowance covers all of that; a decoder that sizes anything by a header
// count it has not paid for goes far past it at once (the regression inputs
// asked for gigabytes from under 300 bytes).
size_t memory_bound(size_t input_bytes) { return (size_t{8} << 20) + (size_t{64} << 10) * input_bytes; }

// What one guarded call did.
struct Guarded {
  tsm::Status status;
  bool over_ceiling = false;   // operator new refused a request (std::bad_alloc reached us)
  size_t peak = 0;             // most bytes held at once during the call
  size_t refused_request = 0;  // the largest request refused
  double ms = 0;
};

// Runs f() with the ceiling armed (bytes held by operator new beyond what was
// held before the call). Nothing in f may keep memory past the call.
template <class F>
Guarded guarded(size_t ceiling, F&& f) {
  Guarded g;
  heap::baseline = heap::live.load();
  heap::peak = 0;
  heap::refused_request = 0;
  heap::ceiling = ceiling;
  const auto t0 = std::chrono::steady_clock::now();
  heap::armed = true;
  try {
    g.status = f();
  } catch (const std::bad_alloc&) {
    g.over_ceiling = true;
  }
  heap::armed = false;
  g.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  g.peak = heap::peak;
  g.refused_request = heap::refused_request;
  return g;
}

// decode() under the ceiling for this input's size; the mesh is checked and
// released inside, so the ceiling covers everything the call held.
struct DecodeResult : Guarded {
  bool mesh_valid = false, mesh_finite = false;
  size_t vertices = 0, faces = 0, corners = 0;
};

DecodeResult guarded_decode(const std::string& bytes, const tsm::DecodeOptions& options = {}) {
  DecodeResult r;
  static_cast<Guarded&>(r) = guarded(memory_bound(bytes.size()), [&] {
    Mesh m;
    tsm::Status s = tsm::decode(bytes, m, options);
    r.mesh_valid = m.valid();
    r.mesh_finite = m.all_finite();
    r.vertices = m.vertex_count();
    r.faces = m.face_count();
    r.corners = m.corner_count();
    return s;
  });
  return r;
}

Guarded guarded_inspect(const std::string& bytes) {
  return guarded(memory_bound(bytes.size()), [&] {
    tsm::FileInfo fi;
    return tsm::inspect(bytes, fi);
  });
}

std::string describe(const Guarded& g) {
  std::string s = g.over_ceiling ? "ran over the memory ceiling (refused a request of " +
                                       std::to_string(g.refused_request) + " bytes)"
                                 : g.status.to_string();
  return s + ", peak " + std::to_string(g.peak) + " bytes, " + std::to_string(g.ms) + " ms";
}

std::string encode_ok(const Mesh& m, int q = 12, int level = tsm::kDefaultLevel, uint32_t segment_faces = 0) {
  std::string bytes;
  tsm::EncodeOptions eo;
  eo.quantization_bits = q;
  eo.level = level;
  eo.segment_faces = segment_faces;
  tsm::Status s = tsm::encode(m, eo, bytes);
  EXPECT_TRUE(s.ok()) << s.to_string();
  return bytes;
}

Mesh point_set(int n) {
  Mesh m;
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> d(-2, 3);
  for (int i = 0; i < n; ++i) m.add_vertex(d(rng), d(rng), d(rng));
  return m;
}

// Small files of different kinds (a few hundred bytes to a few kilobytes).
std::vector<std::string> small_files() {
  Mesh cube = tsm_test::cube_quads();
  cube.add_vertex(9, 9, 9);  // and an unreferenced vertex
  std::vector<std::string> out;
  out.push_back(encode_ok(cube, 8));
  out.push_back(encode_ok(tsm_test::icosphere(1), 12));
  out.push_back(encode_ok(tsm_test::grid_with_holes(7, 1), 14));
  out.push_back(encode_ok(tsm_test::book(4), 10));
  out.push_back(encode_ok(tsm_test::bowtie(), 16));
  out.push_back(encode_ok(tsm_test::moebius(6), 11));
  out.push_back(encode_ok(tsm_test::ngon(9), 20));
  out.push_back(encode_ok(point_set(12), 14));
  out.push_back(encode_ok(Mesh(), 14));
  out.push_back(encode_ok(tsm_test::icosphere(1), 12, tsm::kDefaultLevel, 20));  // 4 segments
  Mesh with_metadata = tsm_test::icosphere(1);
  with_metadata.metadata = {{"gltf", std::string(300, 'x') + "materials"}, {"k", std::string("\0\1\2", 3)}};
  out.push_back(encode_ok(with_metadata, 12));
  return out;
}

// Larger files for the random damage (more payload than framing).
std::vector<std::string> damage_files() {
  std::vector<std::string> out;
  out.push_back(encode_ok(tsm_test::icosphere(2), 12));
  out.push_back(encode_ok(tsm_test::genus_surface(1, 1), 14));
  out.push_back(encode_ok(tsm_test::random_soup(60, 90, 5), 10));
  out.push_back(encode_ok(tsm_test::copies(tsm_test::cube_quads(), 3), 9));
  out.push_back(encode_ok(tsm_test::flipped_face_sphere(1), 16));
  // Welded, with a split stream and wedge values (FORMAT.md §8.12-§8.13).
  out.push_back(encode_ok(tsm_test::flat_shaded_textured_sphere(1), 12));
  // Split vertices with points out (an indexed vn list, §8.13).
  out.push_back(encode_ok(tsm_test::indexed_flat_sphere(1), 12));
  out.push_back(encode_ok(tsm_test::icosphere(2), 12, tsm::kDefaultLevel, 40));  // 8 segments
  out.push_back(encode_ok(tsm_test::copies(tsm_test::cube_quads(), 4), 9, tsm::kDefaultLevel, 5));
  Mesh with_metadata = tsm_test::icosphere(2);
  std::mt19937 rng(5);
  with_metadata.metadata = {{"notes", "a few words of text, and more of them"}, {"blob", random_bytes(rng, 200)}};
  out.push_back(encode_ok(with_metadata, 12, tsm::kDefaultLevel, 100));
  return out;
}

// --- The container framing (FORMAT.md §2-4), fuzz/container_forge.hpp -----------

using tsm_fuzz::Container;
using tsm_fuzz::Section;

// Parses an encoder-made file (throws on anything unexpected: these are the
// encoder's own bytes).
Container parse(const std::string& file) {
  Container c;
  if (!tsm_fuzz::parse_container(file, c) || !c.trailer.empty())
    throw std::runtime_error("the encoder's output does not parse as a container");
  return c;
}

// Lays a container out again with every length and checksum recomputed.
std::string build(const Container& c) { return tsm_fuzz::build_container(c); }

// True when every checksum the framing walk reaches matches its bytes.
bool checksums_match(const std::string& file) {
  std::string fixed = file;
  return tsm_fuzz::fix_checksums(fixed) > 0 && fixed == file;
}

// A decode of damaged input must fail cleanly (corrupt_data; unsupported only
// when the version field changed; limit_exceeded only when limits were given)
// or give a valid mesh, within the memory ceiling and quickly.
void expect_clean(const DecodeResult& r, const std::string& what, bool version_touched = false, bool limits = false) {
  ASSERT_FALSE(r.over_ceiling) << what << ": " << describe(r);
  EXPECT_LT(r.ms, 1000.0) << what << ": " << describe(r);
  if (r.status.ok()) {
    EXPECT_TRUE(r.mesh_valid) << what << ": decoded an invalid mesh";
    EXPECT_TRUE(r.mesh_finite) << what << ": decoded non-finite positions";
    return;
  }
  EXPECT_FALSE(r.status.message().empty()) << what;
  const ErrorCode c = r.status.code();
  const bool allowed = c == ErrorCode::corrupt_data || (version_touched && c == ErrorCode::unsupported) ||
                       (limits && c == ErrorCode::limit_exceeded);
  EXPECT_TRUE(allowed) << what << ": " << r.status.to_string();
}

// --- The helpers themselves ----------------------------------------------------

TEST(Corruption, HelpersRebuildTheEncodersBytes) {
  for (const std::string& f : small_files()) {
    Container c = parse(f);
    EXPECT_EQ(build(c), f);
    EXPECT_TRUE(checksums_match(f));
    EXPECT_GE(c.sections.size(), 1u);
  }
  Mesh m = tsm_test::icosphere(1);
  Container c = parse(encode_ok(m));
  EXPECT_EQ(c.counts[0], m.vertex_count());
  EXPECT_EQ(c.counts[1], m.face_count());
  EXPECT_EQ(c.counts[2], m.corner_count());
}

TEST(Corruption, AllocatorCountsAndRefuses) {
  // The ceiling machinery, so a pass below means something.
  Guarded g = guarded(1 << 20, [] {
    std::vector<char> v(512 << 10);
    return tsm::Status::Ok();
  });
  EXPECT_FALSE(g.over_ceiling);
  EXPECT_GE(g.peak, size_t{512} << 10);
  g = guarded(1 << 20, [] {
    std::vector<char> v(size_t{1} << 30);
    return tsm::Status::Ok();
  });
  EXPECT_TRUE(g.over_ceiling);
  EXPECT_EQ(g.refused_request, size_t{1} << 30);
}

// --- Truncation ----------------------------------------------------------------

TEST(Corruption, EveryTruncationFails) {
  for (const std::string& f : small_files()) {
    ASSERT_LT(f.size(), 4096u);
    for (size_t n = 0; n < f.size(); ++n) {
      const std::string cut = f.substr(0, n);
      DecodeResult r = guarded_decode(cut);
      ASSERT_FALSE(r.over_ceiling) << "prefix " << n << " of " << f.size() << ": " << describe(r);
      EXPECT_EQ(r.status.code(), ErrorCode::corrupt_data)
          << "prefix " << n << " of " << f.size() << ": " << r.status.to_string();
      EXPECT_FALSE(r.status.message().empty());
      Guarded gi = guarded_inspect(cut);
      EXPECT_FALSE(gi.over_ceiling) << "inspect, prefix " << n << ": " << describe(gi);
      EXPECT_FALSE(gi.status.ok()) << "inspect accepted a prefix of " << n << " of " << f.size() << " bytes";
    }
    EXPECT_TRUE(guarded_decode(f).status.ok());
  }
}

// --- Random damage, checksums left as they are -----------------------------------

TEST(Corruption, RandomBitFlips) {
  std::mt19937 rng(20240601);
  int decoded = 0, runs = 0;
  for (const std::string& f : damage_files()) {
    std::uniform_int_distribution<size_t> at(0, f.size() - 1);
    for (int i = 0; i < 700; ++i, ++runs) {
      std::string bad = f;
      const int flips = 1 + static_cast<int>(rng() % 3);
      bool version = false;
      for (int k = 0; k < flips; ++k) {
        const size_t p = at(rng);
        bad[p] = static_cast<char>(bad[p] ^ (1 << (rng() % 8)));
        version = version || p == 4;
      }
      if (bad == f) continue;
      DecodeResult r = guarded_decode(bad);
      expect_clean(r, "flip run " + std::to_string(i), version);
      if (r.status.ok()) {
        ++decoded;
        EXPECT_TRUE(checksums_match(bad)) << "run " << i << ": decoded although a checksum does not match";
      }
      Guarded gi = guarded_inspect(bad);
      EXPECT_FALSE(gi.over_ceiling) << "inspect, flip run " << i << ": " << describe(gi);
    }
  }
  // Only a change the checksums do not cover (framing) could decode at all.
  EXPECT_LE(decoded, runs / 100) << decoded << " of " << runs << " damaged files decoded";
}

TEST(Corruption, RandomByteOverwritesInsertionsAndDeletions) {
  std::mt19937 rng(77);
  int decoded = 0, runs = 0;
  for (const std::string& f : damage_files()) {
    for (int i = 0; i < 500; ++i, ++runs) {
      std::string bad = f;
      const size_t p = rng() % bad.size();
      const size_t n = 1 + rng() % 8;
      switch (rng() % 5) {
        case 0:  // random bytes over a run
          for (size_t k = p; k < std::min(bad.size(), p + n); ++k) bad[k] = static_cast<char>(rng() & 0xff);
          break;
        case 1:  // zeros or ones over a run
          std::fill(bad.begin() + static_cast<std::ptrdiff_t>(p),
                    bad.begin() + static_cast<std::ptrdiff_t>(std::min(bad.size(), p + n)), rng() % 2 ? '\xff' : '\0');
          break;
        case 2:
          bad.insert(p, random_bytes(rng, n));
          break;
        case 3:
          bad.erase(p, n);
          break;
        default:  // a chunk of the file copied over another place
          bad.replace(p, n, f.substr(rng() % f.size(), n));
          break;
      }
      if (bad == f) continue;
      DecodeResult r = guarded_decode(bad);
      expect_clean(r, "overwrite run " + std::to_string(i), p <= 4);
      if (r.status.ok()) {
        ++decoded;
        EXPECT_TRUE(checksums_match(bad)) << "run " << i << ": decoded although a checksum does not match";
      }
    }
  }
  EXPECT_LE(decoded, runs / 100) << decoded << " of " << runs << " damaged files decoded";
}

// --- Damage behind valid checksums (what a forger can do) -------------------------

// Payloads changed and every checksum recomputed: the stream decoders
// themselves must refuse or give a valid mesh, within the memory ceiling.
TEST(Corruption, PayloadDamageBehindValidChecksums) {
  std::mt19937 rng(4242);
  int decoded = 0, runs = 0;
  for (const std::string& f : damage_files()) {
    const Container good = parse(f);
    for (int i = 0; i < 160; ++i, ++runs) {
      Container c = good;
      Section& s = c.sections[rng() % c.sections.size()];
      std::string& b = s.stored;
      const size_t p = b.empty() ? 0 : rng() % b.size();
      switch (rng() % 6) {
        case 0:
        case 1:
          if (!b.empty()) b[p] = static_cast<char>(b[p] ^ (1 << (rng() % 8)));
          break;
        case 2:
          if (!b.empty()) b[p] = static_cast<char>(rng() & 0xff);
          break;
        case 3:
          b.resize(p);  // truncated stream
          break;
        case 4:
          b.insert(p, random_bytes(rng, 1 + rng() % 16));
          break;
        default:
          b = random_bytes(rng, b.size());  // a whole stream of noise
          break;
      }
      const std::string bad = build(c);
      if (bad == f) continue;
      DecodeResult r = guarded_decode(bad);
      expect_clean(r, "section " + std::to_string(s.id) + ", run " + std::to_string(i));
      if (r.status.ok()) ++decoded;
      Guarded gi = guarded_inspect(bad);
      EXPECT_FALSE(gi.over_ceiling) << "inspect, run " << i << ": " << describe(gi);
    }
  }
  RecordProperty("decoded", decoded);
  RecordProperty("runs", runs);
}

// Header fields changed (checksum recomputed): counts, and the opaque rest.
TEST(Corruption, HeaderDamageBehindValidChecksum) {
  std::mt19937 rng(99);
  for (const std::string& f : damage_files()) {
    const Container good = parse(f);
    for (int i = 0; i < 100; ++i) {
      Container c = good;
      if (rng() % 2) {
        uint64_t& n = c.counts[rng() % 3];
        const uint64_t deltas[] = {1, 2, 3, 64, n, uint64_t{1} << (rng() % 64)};
        n = rng() % 2 ? n + deltas[rng() % 6] : n - std::min(n, deltas[rng() % 6]);
      } else if (!c.other_fields.empty()) {
        std::string& o = c.other_fields;
        o[rng() % o.size()] = static_cast<char>(rng() & 0xff);
      }
      DecodeResult r = guarded_decode(build(c));
      expect_clean(r, "header run " + std::to_string(i));
    }
  }
}

// --- Forged headers with huge counts ---------------------------------------------

TEST(Corruption, ForgedHugeCountsFailFast) {
  const uint64_t huge[] = {uint64_t{1} << 24, (uint64_t{1} << 30) - 2, uint64_t{1} << 30,
                           4000000000ull,     uint64_t{1} << 40,       ~uint64_t{0}};
  for (const std::string& f :
       {encode_ok(tsm_test::icosphere(1), 9), encode_ok(tsm_test::cube_quads(), 9), encode_ok(point_set(5), 9)}) {
    const Container good = parse(f);
    for (uint64_t n : huge)
      for (int which = 0; which < 4; ++which) {  // vertices, faces, corners, all three
        Container c = good;
        for (int k = 0; k < 3; ++k)
          if (which == 3 || which == k) c.counts[k] = n;
        const std::string forged = build(c);
        const std::string what = "count " + std::to_string(which) + " = " + std::to_string(n);
        DecodeResult r = guarded_decode(forged);
        ASSERT_FALSE(r.over_ceiling) << what << ": " << describe(r);
        EXPECT_EQ(r.status.code(), ErrorCode::corrupt_data) << what << ": " << r.status.to_string();
        EXPECT_LT(r.ms, 250.0) << what;
        Guarded gi = guarded_inspect(forged);
        ASSERT_FALSE(gi.over_ceiling) << "inspect, " << what << ": " << describe(gi);
        EXPECT_LT(gi.ms, 250.0) << what;
        // With caller limits below the claim, the limit is what is reported.
        tsm::DecodeOptions o;
        o.max_vertices = 100000;
        o.max_faces = 100000;
        o.max_corners = 1600000;
        r = guarded_decode(forged, o);
        ASSERT_FALSE(r.over_ceiling) << "with limits, " << what << ": " << describe(r);
        EXPECT_EQ(r.status.code(), ErrorCode::limit_exceeded) << what << ": " << r.status.to_string();
      }
  }
}

// --- The memory ceiling: hostile streams behind forged headers --------------------
//
// A forger writes header counts as large as the decoder accepts and streams
// of noise (every checksum valid). Whatever the streams say, the decoder may
// not take more memory than the input size justifies: each decoded element
// has to be paid for with input bits.

std::vector<Container> hostile_inputs(uint32_t seed, int count, uint64_t vertices, uint64_t faces, uint64_t corners) {
  std::mt19937 rng(seed);
  const Container good = parse(encode_ok(tsm_test::icosphere(1), 12));
  std::vector<Container> out;
  for (int i = 0; i < count; ++i) {
    Container c = good;
    c.counts[0] = vertices;
    c.counts[1] = faces;
    c.counts[2] = corners;
    for (Section& s : c.sections) {
      if (rng() % 4 == 0) continue;  // keep some genuine streams
      s.codec = 0;
      s.stored = random_bytes(rng, 8 + rng() % 120);
    }
    out.push_back(std::move(c));
  }
  return out;
}

TEST(Corruption, MemoryCeilingForgedStreams) {
  // Counts as large as the container accepts (just under 2^30), and in the
  // proportions a real mesh would have.
  const uint64_t big = (uint64_t{1} << 30) - 2;
  struct Claim {
    uint64_t v, f, c;
  } claims[] = {{big, big, big}, {big / 3, big / 2, big}, {1000, 1000, big}, {big, 0, 0}, {big / 2, big, big}};
  size_t worst = 0;
  for (size_t k = 0; k < sizeof claims / sizeof claims[0]; ++k) {
    int i = 0;
    for (const Container& c :
         hostile_inputs(1000 + static_cast<uint32_t>(k), 60, claims[k].v, claims[k].f, claims[k].c)) {
      const std::string bytes = build(c);
      DecodeResult r = guarded_decode(bytes);
      const std::string what = "claim " + std::to_string(k) + " input " + std::to_string(i++) + " (" +
                               std::to_string(bytes.size()) + " bytes)";
      EXPECT_FALSE(r.over_ceiling) << what << ": the decoder wanted more than " << memory_bound(bytes.size())
                                   << " bytes: " << describe(r);
      if (r.over_ceiling) return;  // one report is enough
      expect_clean(r, what);
      worst = std::max(worst, r.peak);
    }
  }
  RecordProperty("worst_peak_bytes", static_cast<int>(std::min<size_t>(worst, 1u << 30)));
}

TEST(Corruption, MemoryCeilingWithCallerLimits) {
  // A client that sets limits, with claims within them: the default corner
  // limit (16 x max_faces), and a client that allows any corner count.
  const uint64_t big = (uint64_t{1} << 30) - 2;
  for (uint64_t max_corners : {uint64_t{0}, big}) {
    tsm::DecodeOptions o;
    o.max_vertices = 1000;
    o.max_faces = 2000;
    o.max_corners = max_corners;
    int i = 0;
    for (const Container& c : hostile_inputs(555, 60, 1000, 2000, max_corners ? big : 16 * 2000)) {
      const std::string bytes = build(c);
      DecodeResult r = guarded_decode(bytes, o);
      const std::string what = "max_corners " + std::to_string(max_corners) + ", input " + std::to_string(i++);
      EXPECT_FALSE(r.over_ceiling) << what << ": " << describe(r);
      if (r.over_ceiling) return;
      expect_clean(r, what, false, true);
    }
  }
}

// Genuine connectivity streams of a big mesh under a header that lies about
// the vertex count, with the largest section (the geometry) cut to 8 bytes:
// the streams are consistent, so the decoder only finds the lie after
// decoding the whole connectivity. Memory must stay within the ceiling, and
// within the caller's limits when it sets them.
TEST(Corruption, ForgedCountsAroundGenuineStreams) {
  const std::string genuine = encode_ok(tsm_test::grid_with_holes(200, 0), 14);
  Container c = parse(genuine);
  size_t largest = 0;
  for (size_t i = 0; i < c.sections.size(); ++i)
    if (c.sections[i].stored.size() > c.sections[largest].stored.size()) largest = i;
  std::mt19937 rng(8);
  c.sections[largest].stored = random_bytes(rng, 8);
  for (uint64_t vertices : {uint64_t{1000}, uint64_t{3000}}) {
    c.counts[0] = vertices;
    const std::string forged = build(c);
    const std::string what =
        std::to_string(vertices) + " vertices claimed, " + std::to_string(forged.size()) + " bytes";
    DecodeResult r = guarded_decode(forged);
    ASSERT_FALSE(r.over_ceiling) << what << ": " << describe(r);
    EXPECT_EQ(r.status.code(), ErrorCode::corrupt_data) << what << ": " << r.status.to_string();
    tsm::DecodeOptions o;
    o.max_vertices = 5000;
    o.max_faces = 10000;
    r = guarded_decode(forged, o);
    ASSERT_FALSE(r.over_ceiling) << what << ", with limits: " << describe(r);
    EXPECT_EQ(r.status.code(), ErrorCode::limit_exceeded) << what << ": " << r.status.to_string();
    EXPECT_LT(r.peak, size_t{1} << 20) << what << ": limits refused late";
  }
}

// A zstd section may expand 1024 times (FORMAT.md §4.1) and no more.
TEST(Corruption, ZstdExpansionBounded) {
  const Container good = parse(encode_ok(tsm_test::icosphere(1), 12));
  const std::string zeros(1 << 20, '\0');
  std::string frame(ZSTD_compressBound(zeros.size()), '\0');
  frame.resize(ZSTD_compress(frame.data(), frame.size(), zeros.data(), zeros.size(), 19));
  ASSERT_LT(frame.size() * 1024, zeros.size() * 4) << "zstd should squeeze a megabyte of zeros well";
  for (uint64_t raw :
       {uint64_t{zeros.size()}, uint64_t{frame.size()} * 1024, uint64_t{frame.size()} * 1024 + 1, uint64_t{1} << 40}) {
    for (size_t k = 0; k < good.sections.size(); ++k) {
      Container c = good;
      c.sections[k].codec = 1;
      c.sections[k].stored = frame;
      c.sections[k].raw_length = raw;
      const std::string bytes = build(c);
      DecodeResult r = guarded_decode(bytes);
      const std::string what = "section " + std::to_string(k) + " raw " + std::to_string(raw);
      ASSERT_FALSE(r.over_ceiling) << what << ": " << describe(r);
      EXPECT_EQ(r.status.code(), ErrorCode::corrupt_data) << what << ": " << r.status.to_string();
      EXPECT_LE(r.peak, 1024 * frame.size() + (size_t{1} << 20)) << what;
    }
  }
}

// The ceiling is not too tight: genuine files, including highly compressible
// ones, decode under it.
TEST(Corruption, GenuineFilesDecodeUnderTheCeiling) {
  std::vector<std::string> files = small_files();
  for (const std::string& f : damage_files()) files.push_back(f);
  // The most compressible kinds: a big flat grid, coincident points, many
  // copies of one small mesh, all at very coarse quantization.
  files.push_back(encode_ok(tsm_test::grid_with_holes(150, 0), 1));
  Mesh same_point;
  for (int i = 0; i < 20000; ++i) same_point.add_vertex(1, 2, 3);
  files.push_back(encode_ok(same_point, 1));
  files.push_back(encode_ok(tsm_test::copies(tsm_test::icosphere(0), 300), 2));
  double most = 0;  // decoder memory per input byte, the largest seen
  for (const std::string& f : files) {
    DecodeResult r = guarded_decode(f);
    EXPECT_TRUE(r.status.ok()) << describe(r);
    EXPECT_FALSE(r.over_ceiling) << f.size() << " bytes: " << describe(r);
    most = std::max(most, static_cast<double>(r.peak) / static_cast<double>(f.size()));
  }
  std::cout << "most decoder memory per input byte: " << static_cast<int>(most) << " bytes\n";
}

// --- Real meshes (../shared/corpus) ----------------------------------------------

// The small corpus files and a reduced dragon, encoded and damaged: flips as
// stored, and payload damage behind recomputed checksums.
TEST(Corruption, CorpusFilesDamaged) {
  TSM_REQUIRE_CORPUS();
  namespace fs = std::filesystem;
  std::vector<fs::path> paths;
  for (const auto& e : fs::directory_iterator(tsm_test::corpus_file("edge")))
    if (e.is_regular_file() && e.file_size() <= 16384) paths.push_back(e.path());
  std::sort(paths.begin(), paths.end());
  paths.push_back(tsm_test::corpus_file("dragon_vrip_res4.ply"));
  std::mt19937 rng(31337);
  int files = 0;
  for (const fs::path& p : paths) {
    Mesh m;
    if (!tsm::read_mesh(p.string(), m).ok()) continue;  // the corpus has files made to be refused
    std::string bytes;
    if (!tsm::encode(m, tsm::EncodeOptions{}, bytes).ok()) continue;
    ++files;
    const Container good = parse(bytes);
    const int runs = m.vertex_count() > 1000 ? 10 : 40;
    for (int i = 0; i < runs; ++i) {
      std::string bad = bytes;
      const size_t at = rng() % bad.size();
      bad[at] = static_cast<char>(bad[at] ^ (1 << (rng() % 8)));
      DecodeResult r = guarded_decode(bad);
      expect_clean(r, p.filename().string() + " flip at " + std::to_string(at), at == 4 || at == 5);
      if (r.status.ok()) {
        EXPECT_TRUE(checksums_match(bad)) << p.filename().string();
      }
      Container c = good;
      std::string& b = c.sections[rng() % c.sections.size()].stored;
      if (b.empty()) continue;
      if (rng() % 2)
        b[rng() % b.size()] = static_cast<char>(rng() & 0xff);
      else
        b.resize(rng() % b.size());
      expect_clean(guarded_decode(build(c)), p.filename().string() + " payload damage " + std::to_string(i));
    }
  }
  EXPECT_GE(files, 10);
}

// --- Inputs that once broke the decoder ----------------------------------------

// tests/regressions/*.bin (see the README there): each must now fail cleanly
// or decode, within the memory ceiling, with and without caller limits.
TEST(Corruption, RegressionFiles) {
  namespace fs = std::filesystem;
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(TSM_REGRESSIONS_DIR))
    if (e.path().extension() == ".bin") files.push_back(e.path());
  std::sort(files.begin(), files.end());
  ASSERT_FALSE(files.empty()) << "no regression inputs in " << TSM_REGRESSIONS_DIR;
  for (const fs::path& p : files) {
    std::ifstream in(p, std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    ASSERT_FALSE(bytes.empty()) << p;
    tsm::DecodeOptions limits;
    limits.max_vertices = 1000;
    limits.max_faces = 2000;
    expect_clean(guarded_decode(bytes), p.filename().string(), true);
    expect_clean(guarded_decode(bytes, limits), p.filename().string() + " with limits", true, true);
    Guarded gi = guarded_inspect(bytes);
    EXPECT_FALSE(gi.over_ceiling) << "inspect " << p.filename().string() << ": " << describe(gi);
  }
}

}  // namespace

// The metadata section (FORMAT.md §4.6) forged every way a payload can be
// wrong: each is refused with corrupt_data, quickly and within the ceiling.
TEST(Corruption, ForgedMetadataRefused) {
  Mesh m = tsm_test::icosphere(1);
  m.metadata = {{"a", "one"}};
  const Container good = parse(encode_ok(m, 12));
  size_t at = good.sections.size();
  for (size_t i = 0; i < good.sections.size(); ++i)
    if (good.sections[i].id == 9) at = i;
  ASSERT_LT(at, good.sections.size()) << "no metadata section";
  auto entry = [](const std::string& key, const std::string& value) {
    std::string e(1, static_cast<char>(key.size()));
    e += key;
    tsm_fuzz::put_varint(e, value.size());
    return e + value;
  };
  auto count = [](uint64_t n) {
    std::string s;
    tsm_fuzz::put_varint(s, n);
    return s;
  };
  const std::vector<std::pair<std::string, std::string>> forged = {
      {"duplicate keys", count(2) + entry("a", "1") + entry("a", "2")},
      {"empty key", count(1) + entry("", "1")},
      {"huge count", count(uint64_t{1} << 40) + entry("a", "1")},
      {"count above the entries", count(3) + entry("a", "1") + entry("b", "2")},
      {"bytes after the entries", count(1) + entry("a", "1") + "zz"},
      {"value longer than the payload", count(1) + std::string("\1a") + count(uint64_t{1} << 33) + "abc"},
      {"key cut off", count(1) + std::string("\tab")},
      {"empty payload", ""},
  };
  for (const auto& [what, payload] : forged) {
    Container c = good;
    c.sections[at].codec = 0;
    c.sections[at].stored = payload;
    const DecodeResult r = guarded_decode(build(c));
    expect_clean(r, what);
    EXPECT_EQ(r.status.code(), ErrorCode::corrupt_data) << what << ": " << describe(r);
    // The stream decoder refuses it too.
    tsm::StreamDecoder sd;
    const std::string bytes = build(c);
    tsm::Status s = sd.feed(bytes);
    if (s.ok()) s = sd.finish();
    EXPECT_EQ(s.code(), ErrorCode::corrupt_data) << what << " (stream): " << s.to_string();
  }
  Container twice = good;
  twice.sections.insert(twice.sections.begin() + static_cast<std::ptrdiff_t>(at), good.sections[at]);
  EXPECT_EQ(guarded_decode(build(twice)).status.code(), ErrorCode::corrupt_data) << "two metadata sections";
}

// The bytes of an attribute grid (FORMAT.md §8.12) of `components` values
// at `at`: its grid byte, then each origin and the top, one byte when the
// grid byte marks it short, else four.
size_t grid_bytes(const std::string& payload, size_t at, uint32_t components) {
  const uint32_t grid = static_cast<uint8_t>(payload.at(at));
  size_t n = 1;
  for (uint32_t c = 0; c < components; ++c) n += (grid >> (2 + c) & 1) ? 1 : 4;
  return n + ((grid >> 6 & 1) ? 1 : 4);
}

// An attribute's type and quantization pair one way only (FORMAT.md §8.12):
// integer types are coded exactly, f32 on a grid or octahedrally. fuzz_decode
// found a forged file whose u8 attribute said "octahedral" and decoded to
// fractions, a mesh the encoder then refused; both forged pairings are now
// refused by the decoder, whole and streamed.
TEST(Corruption, AttributeTypeAndQuantizationMustPair) {
  Mesh m = tsm_test::icosphere(1);
  tsm::Attribute color;
  color.name = "COLOR";  // not a common name (FORMAT.md §8.12): spelt out in the header
  color.kind = tsm::AttributeKind::color;
  color.type = tsm::AttributeType::u8;
  color.components = 3;
  tsm::Attribute temp;
  temp.name = "temp";
  for (size_t v = 0; v < m.vertex_count(); ++v) {
    for (int c = 0; c < 3; ++c) color.values.push_back(static_cast<float>((v * 37 + 11 * c) % 256));
    temp.values.push_back(0.25f * static_cast<float>(v));
  }
  m.attributes = {color, temp};
  const Container good = parse(encode_ok(m, 12));
  ASSERT_EQ(guarded_decode(build(good)).status.code(), ErrorCode::ok);
  size_t at = good.sections.size();
  for (size_t i = 0; i < good.sections.size(); ++i)
    if (good.sections[i].id == 10) at = i;
  ASSERT_LT(at, good.sections.size()) << "no mesh section";
  ASSERT_EQ(good.sections[at].codec, 0);
  const std::string& payload = good.sections[at].stored;
  // Header (FORMAT.md §8.12): name (10 + length, bytes), layout (kind | domain << 2 | type << 4 |
  // components - 1 << 6), coding (quant | bits << 2)[, axis, origin f32 x components, top f32].
  const size_t c_at = payload.find(std::string("\x0f" "COLOR\x92\x00", 8));
  const size_t t_at = payload.find(std::string("\x0e" "temp\x00", 6));
  ASSERT_NE(c_at, std::string::npos) << "colour header not found";
  ASSERT_NE(t_at, std::string::npos) << "temp header not found";
  ASSERT_EQ(payload[t_at + 6] & 3, 1) << "temp not on a grid";
  struct Case {
    const char* what;
    std::string payload;
    const char* message;
  };
  std::vector<Case> cases;
  std::string octahedral_u8 = payload;  // u8 colour as octahedral, 8 bits
  octahedral_u8[c_at + 7] = 2 | 8 << 2;
  cases.push_back({"u8 octahedral", octahedral_u8, "integer attribute not coded as exact"});
  std::string grid_u8 = payload;  // u8 colour on a grid, 8 bits: axis, origin and top added
  grid_u8[c_at + 7] = 1 | 8 << 2;
  grid_u8.insert(c_at + 8, std::string(1 + 3 * 4 + 4, '\0'));
  cases.push_back({"u8 grid", grid_u8, "integer attribute not coded as exact"});
  std::string exact_f32 = payload;  // f32 temp as exact integers: the grid byte, origin and top dropped
  exact_f32[t_at + 6] = 0;
  exact_f32.erase(t_at + 7, grid_bytes(payload, t_at + 7, 1));
  cases.push_back({"f32 exact", exact_f32, "f32 attribute coded as exact integers"});
  for (const Case& k : cases) {
    Container c = good;
    c.sections[at].stored = k.payload;
    const std::string bytes = build(c);
    const DecodeResult r = guarded_decode(bytes);
    expect_clean(r, k.what);
    EXPECT_EQ(r.status.code(), ErrorCode::corrupt_data) << k.what << ": " << describe(r);
    EXPECT_TRUE(tsm_test::contains(r.status.message(), k.message)) << k.what << ": " << describe(r);
    tsm::StreamDecoder sd;
    tsm::Status s = sd.feed(bytes);
    if (s.ok()) s = sd.finish();
    EXPECT_EQ(s.code(), ErrorCode::corrupt_data) << k.what << " (stream): " << s.to_string();
  }
}

// FORMAT.md §8.12: bit 4 of a predictor byte (coded per vertex) is for
// corner attributes only.
TEST(Corruption, PerVertexCodingOfAVertexAttributeRefused) {
  Mesh m = tsm_test::icosphere(1);
  tsm::Attribute temp;
  temp.name = "temp";
  for (size_t v = 0; v < m.vertex_count(); ++v) temp.values.push_back(0.25f * static_cast<float>(v));
  m.attributes = {temp};
  const Container good = parse(encode_ok(m, 12));
  ASSERT_EQ(guarded_decode(build(good)).status.code(), ErrorCode::ok);
  size_t at = good.sections.size();
  for (size_t i = 0; i < good.sections.size(); ++i)
    if (good.sections[i].id == 10) at = i;
  ASSERT_LT(at, good.sections.size()) << "no mesh section";
  ASSERT_EQ(good.sections[at].codec, 0);
  // Header: name (5 bytes), layout, coding, the grid (byte, origin, top); then the predictor byte.
  const size_t t_at = good.sections[at].stored.find(std::string("\x0e" "temp\x00", 6));
  ASSERT_NE(t_at, std::string::npos) << "temp header not found";
  Container c = good;
  const size_t predictor_at = t_at + 7 + grid_bytes(good.sections[at].stored, t_at + 7, 1);
  c.sections[at].stored[predictor_at] = static_cast<char>(c.sections[at].stored[predictor_at] | 0x10);
  const DecodeResult r = guarded_decode(build(c));
  expect_clean(r, "per-vertex bit on a vertex attribute");
  EXPECT_EQ(r.status.code(), ErrorCode::corrupt_data) << describe(r);
  EXPECT_TRUE(tsm_test::contains(r.status.message(), "is coded per vertex but is not a corner attribute"))
      << describe(r);
}

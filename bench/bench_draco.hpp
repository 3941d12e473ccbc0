// Draco, run in the same process as tsm, for the comparisons in `tsm bench`.
// Draco is optional at build time: without it draco_available() is false and
// every call reports that Draco is not built in.
#pragma once
#include <string>

#include "tsm/mesh.hpp"

namespace tsm::bench {

bool draco_available();
const char* draco_version();

struct DracoRun {
  bool ok = false;
  std::string error;
  size_t bytes = 0;
  double encode_ms = 0;       // median over runs
  double decode_ms = 0;       // median over runs
  // Draco's decoded mesh on its own grid: positions are the grid indices its
  // decoder reads (the dequantization skipped), in its vertex order,
  // polygons as triangles. Compare with draco_grid(original) (bits = 0).
  Mesh decoded_grid;
};

// The mesh as Draco's encoder puts it on its grid: polygons fan-triangulated
// as Draco is given them, positions replaced by the grid indices Draco
// computes for them (its quantization transform: float minimum and range,
// Draco's quantizer). Empty when Draco is not built in.
Mesh draco_grid(const Mesh& mesh, int qbits);

// Encodes `mesh` with Draco's edgebreaker/sequential choice at compression
// level `level` (0..10, speed = 10 - level) and `qbits` position bits, then
// decodes it; `runs` timed repetitions each. Polygons are fan-triangulated
// for Draco (it takes triangles only).
DracoRun draco_roundtrip(const Mesh& mesh, int qbits, int level, int runs);

// Draco's connectivity alone, exactly: the bytes its edgebreaker encoder
// writes while it codes the connectivity (traversal symbols, splits, valence
// contexts), measured around that step of an encode at `level` and `qbits`.
// *file_bytes gets the whole file's size. 0 when Draco is not built in or
// fails (then `error` says why).
size_t draco_connectivity_bytes(const Mesh& mesh, int qbits, int level, size_t* file_bytes, std::string& error);

// Loads a file with Draco's own reader (for the reader-speed comparison).
bool draco_read(const std::string& path, double& ms, size_t& vertices, size_t& faces, std::string& error);

}  // namespace tsm::bench

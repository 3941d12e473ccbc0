// The tool's file commands: encode, decode, info (one file or many).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "tsm/tsm.hpp"

namespace tsm::cli {

// Common to the commands that take many files.
struct BatchArgs {
  std::vector<std::string> inputs;  // paths; "-" is stdin (alone only)
  unsigned jobs = 0;                // worker threads; 0 = number of cores
  bool json = false;                // JSON lines on stdout, one per input
  bool quiet = false;               // no reports, notes, progress bar or summary
};

struct EncodeArgs : BatchArgs {
  std::string output;               // file, folder (DIR/), "-" (stdout), or "" (beside the input)
  std::string input_format;         // "", ply, obj, stl, off
  int qbits = kDefaultQuantizationBits;
  int level = kDefaultLevel;
  uint32_t segment_faces = 0;       // 0 = the library's default
  AttributeQuantization attribute_bits;
  bool force = false, allow_nonfinite = false;
  bool keep_order = false;          // EncodeOptions::keep_order
  bool lossless = false;            // EncodeOptions::lossless
  // Simplify first, within this distance of the input ("E" model units or
  // "E%" of the bounding-box diagonal; "" = no simplification).
  std::string max_error;
  bool fallback = false;  // glTF output: an uncompressed copy beside each stream
  bool progressive = false;  // a progressive file (base mesh, then batches of vertex splits)
  bool drop_attributes = false;  // code positions and faces only
};

struct DecodeArgs : BatchArgs {
  std::string output;
  std::string format;               // "" or one of output_format_names()
  bool ascii = false, force = false;
  uint64_t max_vertices = 0, max_faces = 0, max_corners = 0;
  // Progressive files: the finest level a truncated file holds (partial),
  // the levels within the first max_bytes bytes, or the first level within
  // stop_error (model units; negative = none).
  bool partial = false;
  uint64_t max_bytes = 0;
  double stop_error = -1;
};

struct InfoArgs : BatchArgs {};

// The formats decode writes (tsm::kWritableFormats), as the help text and
// the messages list them: {"ply", "obj", ...}; "ply|obj|..."; ".ply, .obj,
// ... or .glb"; "PLY, OBJ, ... or GLB".
std::vector<std::string> output_format_names();
std::string output_formats_bar();
std::string output_extensions_text();
std::string output_formats_text();

int cmd_encode(const EncodeArgs& a);
// glTF to glTF (gltf_command.cpp): one input file and a .glb / .gltf output.
bool gltf_output(const BatchArgs& a, const std::string& output);
int gltf_encode(const EncodeArgs& a);
int gltf_decode(const DecodeArgs& a);
int cmd_decode(const DecodeArgs& a);
int cmd_info(const InfoArgs& a);

}  // namespace tsm::cli

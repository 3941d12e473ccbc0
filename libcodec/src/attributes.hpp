// Internal: attributes (normals, colours, texture coordinates, generic
// values) per vertex, face and corner (see attributes.cpp).
#pragma once
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "tsm/quantization.hpp"
#include "tsm/mesh.hpp"
#include "tsm/status.hpp"

namespace tsm {

// How an attribute's values become integers (FORMAT.md §8.12).
enum class AttributeQuant : uint8_t {
  exact = 0,       // integer types: the values are the integers
  grid = 1,        // a uniform grid over the attribute's own bounding box (bits per component)
  octahedral = 2,  // normals: two grid indices on the octahedron (bits each)
};

// What every part of a file states about an attribute (the same for all).
struct AttributeHeader {
  std::string name;
  AttributeKind kind = AttributeKind::generic;
  AttributeDomain domain = AttributeDomain::vertex;
  AttributeType type = AttributeType::f32;
  uint32_t components = 1;
  AttributeQuant quant = AttributeQuant::exact;
  int bits = 0;                  // grid and octahedral
  float origin[4] = {0, 0, 0, 0};  // grid
  double extent = 0;             // grid: largest extent of the values
};

using AttributeBits = AttributeQuantization;

// The headers for a mesh's attributes (grids from all of their values).
std::vector<AttributeHeader> attribute_headers(const Mesh& mesh, const AttributeBits& bits);

// Encoder, one part: `part` is the part's input mesh (its faces and
// attributes), `order` maps output vertex ids to part input vertex ids, `own`
// marks output vertices coded in this part (empty: all), `faces` are the
// part's faces as the decoder will output them (output vertex ids), `q` the
// quantized positions of the own vertices (3 each, own-rank order) for
// normal prediction. Vertex attributes cover the own vertices only.
struct AttributeInput {
  const Mesh* part = nullptr;
  const std::vector<uint32_t>* order = nullptr;
  const std::vector<uint8_t>* is_ref = nullptr;  // per output vertex, 1 = reference (may be empty)
  const Mesh* faces = nullptr;
  const std::vector<uint32_t>* q = nullptr;
  // Segments (FORMAT.md §8.12, "values of earlier segments"): per attribute,
  // per part input value of a corner attribute, its id in the file's value
  // list when an earlier segment holds it, else kNone (null: none).
  bool segmented = false;
  const std::vector<std::vector<uint32_t>>* imported = nullptr;
  // Out (optional): per attribute, the part input values that this part adds
  // to the file's value list, in the order the decoder appends them.
  std::vector<std::vector<uint32_t>>* own_values = nullptr;
  // The fast levels: residuals through static prefix codes where
  // they cost at most 9/8 of the adaptive models (FORMAT.md §8.12.1).
  bool tables = false;
  // Bit i: corner attribute i has one value per vertex, every corner using
  // its vertex's (FORMAT.md §8.12, predictor bit 4): `part` then holds it as
  // a vertex attribute's values (no indices) and it is coded as one.
  uint64_t per_vertex = 0;
};
Status encode_attributes(const std::vector<AttributeHeader>& headers, const AttributeInput& in, std::string& out);

// The corner a face's cycle starts at in its lexicographically smallest
// rotation (the face's key when faces are matched or ordered by corners).
uint32_t smallest_rotation(const uint32_t* corners, uint32_t n);

// Decoder, one part: the attributes of its own vertices (output order), its
// faces and corners (output order), each corner attribute with the part's own
// value list.
// What one attribute of a part cost (tsm info): its header and the bits its
// values took in the coded stream (range-coded bytes read while decoding
// it, exact to a few bytes, plus its table-coded bits).
struct AttributeCost {
  AttributeHeader header;
  bool tables = false;
  uint64_t coded_bits = 0;
};

struct AttributePart {
  const Mesh* faces = nullptr;                     // the part's decoded faces (part output ids)
  const std::vector<uint32_t>* global = nullptr;   // per part vertex: kNone own, else a reference
  const std::vector<uint32_t>* q = nullptr;        // own vertices' grid indices
  bool segmented = false;                          // a segment's payload (may name earlier values)
  uint32_t* table_coded = nullptr;                 // out (optional): attributes with table-coded residuals
  std::vector<AttributeCost>* costs = nullptr;     // out (optional): what each attribute cost, in file order
  uint64_t* header_bytes = nullptr;                // out (optional): bytes before the coded values
  uint64_t* per_vertex = nullptr;                  // out (optional): bit i, corner attribute i coded per vertex
};
// `alias` (optional) gets per attribute, per value of the part's value list,
// the id in the file's value list of an earlier segment's value it stands
// for, or kNone (empty for vertex and face attributes).
Status decode_attributes(std::string_view bytes, const AttributePart& in, std::vector<Attribute>& out,
                         std::vector<std::vector<uint32_t>>* alias = nullptr);

// The integers a value is coded as (2 for octahedral, else the components):
// the oracle compares attributes through them.
uint32_t attribute_key_size(const AttributeHeader& h);
void attribute_key(const AttributeHeader& h, const float* value, int32_t* out);

// An attribute's description (name, kind, domain, type, components) with
// no values; whether two attributes have the same description.
Attribute described_like(const Attribute& a);
bool same_description(const Attribute& a, const Attribute& b);

// Float value of grid index x on component c of a grid attribute.
float attribute_grid_value(const AttributeHeader& h, int c, int64_t x);

}  // namespace tsm

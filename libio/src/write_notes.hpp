// Internal: the notes writers give (WriteInfo::notes) about what their
// format cannot hold, in the same words for every writer.
#pragma once
#include <string>

#include "tsm/io.hpp"

namespace tsm {

inline const char* domain_word(AttributeDomain d) {
  switch (d) {
    case AttributeDomain::vertex: return "vertex";
    case AttributeDomain::face: return "face";
    case AttributeDomain::corner: return "corner";
  }
  return "unknown";
}

// The check every text writer starts with: a valid mesh whose every face
// has a corner (a face of none has no line to be written as).
inline Status check_faces_writable(const Mesh& mesh, const char* format) {
  std::string why;
  if (!mesh.valid(&why))
    return Status(ErrorCode::invalid_argument, std::string("cannot write ") + format + ": invalid mesh: " + why);
  for (size_t f = 0; f < mesh.face_count(); ++f)
    if (mesh.face_size(f) == 0)
      return Status(ErrorCode::invalid_argument, std::string("cannot write ") + format + ": face " + std::to_string(f) +
                                                     " has no corners (" + format + " cannot express it)");
  return Status::Ok();
}

// "vertex attribute 'confidence'", with line ends shown as blanks so that a
// note stays on one line.
inline std::string attribute_words(const Attribute& a) {
  std::string name = a.name;
  for (char& c : name)
    if (c == '\n' || c == '\r') c = ' ';
  return std::string(domain_word(a.domain)) + " attribute '" + name + "'";
}

// Notes what a writer leaves out: `attributes` (attribute_words joined by
// ", ", may be empty) and the metadata entries but `kept` (the key the
// writer uses, or nullptr), as "FORMAT cannot hold ...; not written".
inline void note_not_written(const Mesh& mesh, const char* format, const std::string& attributes, const char* kept,
                             WriteInfo* info) {
  if (!info) return;
  std::string what = attributes;
  for (const MetadataEntry& e : mesh.metadata) {
    if (kept && e.key == kept) continue;
    std::string key = e.key;
    for (char& c : key)
      if (c == '\n' || c == '\r') c = ' ';
    what += (what.empty() ? "metadata '" : ", metadata '") + key + "'";
    if (e.key == "gltf")
      what += " (the glTF document: nodes and their transforms, instances, materials, textures, animations; "
              "decode to .gltf or .glb to keep it)";
    else if (e.key == "obj")
      what += " (the names of the OBJ objects, groups, materials and smoothing groups and the mtllib files; "
              "decode to .obj to keep them)";
  }
  if (!what.empty()) info->add_note(std::string(format) + " cannot hold the " + what + "; not written");
}

}  // namespace tsm

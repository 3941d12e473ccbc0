// Reading the files a .gltf names by relative URI (buffers, images), shared
// by the glTF reader (io_gltf.cpp) and the glTF transcoder
// (gltf_document.cpp): only files in `dir` or below it, never through a
// symbolic link leading out of it (see io_gltf.cpp).
#pragma once
#include <string>

#include "tsm/status.hpp"

namespace tsm {

// Reads the file `uri` (percent-encoded, relative) names inside `dir`.
// Refuses empty dirs, "..", absolute paths, schemes, backslashes, links out
// of the folder and anything but regular files, with a message saying why.
Status read_file_beside(const std::string& dir, const std::string& uri, std::string& out);

}  // namespace tsm

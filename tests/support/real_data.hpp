#pragma once
// The real scanned meshes Debian's libcgal-demo ships, unpacked at configure time (TETCUT_REAL_DATA).

#include <tetcut/io.hpp>

#include <string>

namespace tetcut::testing {

/// The scan `name` (e.g. "bunny00"), read from its OFF file.
inline TriangleSurface scan(const std::string& name) { return read_surface(std::string(TETCUT_REAL_DATA) + "/" + name + ".off"); }

}  // namespace tetcut::testing

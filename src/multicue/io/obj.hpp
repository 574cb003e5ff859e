#pragma once
/// \file Wavefront OBJ mesh reader (v, vn, f with v, v/vt, v//vn, v/vt/vn and negative indices;
/// polygons fan-triangulated; `o`/`g` names recorded as per-vertex labels).

#include <filesystem>
#include <string>
#include <vector>

#include "multicue/core/triangle_mesh.hpp"

namespace multicue::io {

struct ObjMesh {
    TriangleMesh mesh;
    /// Names of the `o`/`g` groups in file order; a triangle's group is triangle_groups[t], an
    /// index into this list (0 = the unnamed group before any `o`/`g` line if there is one).
    std::vector<std::string> group_names;
    std::vector<std::uint32_t> triangle_groups;
};

/// Reads an OBJ file. Throws IoError / FormatError with the file name and line number.
ObjMesh ReadObj(const std::filesystem::path& path);

}  // namespace multicue::io

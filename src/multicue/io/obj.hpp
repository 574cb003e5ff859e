#pragma once
/// \file Wavefront OBJ mesh reader (v, vn, f with v, v/vt, v//vn, v/vt/vn and negative indices;
/// polygons fan-triangulated; `o`/`g` groups recorded per triangle).

#include <cstdint>
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

/// Reads an OBJ file. Per-vertex colours (`v x y z r g b`, 0..1; 0..255 if any value exceeds 1)
/// are kept when every `v` line has them. Vertex normals are filled only when every face corner
/// names a `vn` and each vertex gets a single normal (NaN for vertices used by no face); otherwise
/// they are left empty. Texture coordinates, materials, lines and points are ignored.
/// Throws IoError / FormatError with the file name and line number.
ObjMesh ReadObj(const std::filesystem::path& path);

}  // namespace multicue::io

#pragma once
/// \file PLY reader and writer (ascii, binary_little_endian, binary_big_endian) for point clouds
/// and triangle meshes.

#include <filesystem>

#include "multicue/core/point_cloud.hpp"
#include "multicue/core/triangle_mesh.hpp"

namespace multicue::io {

enum class PlyEncoding { kAscii, kBinaryLittleEndian, kBinaryBigEndian };

struct PlyWriteOptions {
    PlyEncoding encoding = PlyEncoding::kBinaryLittleEndian;
};

/// Reads the vertex element of a PLY file as a point cloud: x y z; nx ny nz (or normal_x...);
/// red green blue [alpha] (or r g b / diffuse_*; uchar, or float 0..1; also a packed PCL-style
/// rgb/rgba); label; intensity; confidence; curvature. Other scalar vertex properties are kept in
/// extra_fields (char/short/int -> 'I', uchar/ushort/uint -> 'U', float/double -> 'F'); vertex
/// list properties are skipped with a warning; other elements (faces, materials) are skipped.
/// The cloud is unorganized. Throws IoError / FormatError naming the file (and, for ascii data,
/// the line).
PointCloud ReadPly(const std::filesystem::path& path);

/// Reads a PLY mesh: vertices (with normals, colours, labels when present) and faces
/// (vertex_indices or vertex_index lists; polygons are fan-triangulated, faces with fewer than
/// three vertices are skipped with a warning). Other vertex and face properties are ignored.
/// Throws FormatError naming the file when a face refers to a vertex that does not exist.
TriangleMesh ReadPlyMesh(const std::filesystem::path& path);

/// Writes a cloud as a PLY vertex element (atomically): x y z, nx ny nz, red green blue (uchar;
/// alpha only if some colour is not opaque), label (uint), intensity, confidence, curvature
/// (float), then extra fields with count 1 as scalar properties (others are skipped with a
/// warning). Ascii floats use the shortest text that reads back bit-exact ("nan", "inf").
/// PLY has no organization or sensor pose: they are not written. Throws DataError, IoError.
void WritePly(const std::filesystem::path& path, const PointCloud& cloud,
              const PlyWriteOptions& options = {});

/// Writes a triangle mesh (atomically): vertices as WritePly (with normals, colours, labels when
/// present) and faces as "property list uchar int vertex_indices".
void WritePlyMesh(const std::filesystem::path& path, const TriangleMesh& mesh,
                  const PlyWriteOptions& options = {});

}  // namespace multicue::io

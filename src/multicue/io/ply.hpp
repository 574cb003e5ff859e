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
/// red green blue [alpha] (or r g b / diffuse_*); label; intensity; confidence; curvature.
/// Other vertex properties are kept in extra_fields; other elements (faces, materials) are skipped.
PointCloud ReadPly(const std::filesystem::path& path);

/// Reads a PLY mesh: vertices (with normals, colours, labels when present) and faces
/// (vertex_indices or vertex_index lists; polygons are fan-triangulated).
TriangleMesh ReadPlyMesh(const std::filesystem::path& path);

/// Writes a cloud as a PLY vertex element (atomically).
void WritePly(const std::filesystem::path& path, const PointCloud& cloud,
              const PlyWriteOptions& options = {});

/// Writes a triangle mesh (atomically).
void WritePlyMesh(const std::filesystem::path& path, const TriangleMesh& mesh,
                  const PlyWriteOptions& options = {});

}  // namespace multicue::io

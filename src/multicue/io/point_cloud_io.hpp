#pragma once
/// \file Format-independent entry points: the file extension (.pcd, .ply) picks the format.

#include <filesystem>

#include "multicue/core/point_cloud.hpp"
#include "multicue/core/triangle_mesh.hpp"

namespace multicue::io {

/// Encoding requested independently of the format: ascii, binary, or compressed (PCD
/// binary_compressed; PLY has no compression and writes binary little endian).
enum class Encoding { kAscii, kBinary, kCompressed };

/// Parses "ascii", "binary" or "compressed"; throws InvalidArgument otherwise.
Encoding ParseEncoding(const std::string& name);

/// Reads a .pcd or .ply point cloud. Throws IoError for an unknown extension.
PointCloud ReadPointCloud(const std::filesystem::path& path);

/// Writes a .pcd or .ply point cloud (atomically).
void WritePointCloud(const std::filesystem::path& path, const PointCloud& cloud,
                     Encoding encoding = Encoding::kBinary);

/// Reads a .ply or .obj triangle mesh.
TriangleMesh ReadTriangleMesh(const std::filesystem::path& path);

}  // namespace multicue::io

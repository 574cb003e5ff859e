#pragma once
/// \file PCD v0.7 reader and writer, compatible with what PCL 1.x writes and reads.

#include <filesystem>

#include "multicue/core/point_cloud.hpp"

namespace multicue::io {

enum class PcdEncoding { kAscii, kBinary, kBinaryCompressed };

struct PcdWriteOptions {
    PcdEncoding encoding = PcdEncoding::kBinaryCompressed;  ///< DATA ascii|binary|binary_compressed
};

/// Reads a PCD file (DATA ascii, binary or binary_compressed; any field layout PCL writes).
/// Known fields map to PointCloud vectors (x y z; rgb/rgba; normal_x/y/z; curvature; label;
/// intensity; confidence); unknown fields are kept in extra_fields. Organized clouds keep their
/// WIDTH/HEIGHT and NaN points; VIEWPOINT sets the sensor pose.
/// Throws IoError / FormatError with the file name and the problem.
PointCloud ReadPcd(const std::filesystem::path& path);

/// Writes every present field of `cloud` (atomically). Throws IoError or DataError.
void WritePcd(const std::filesystem::path& path, const PointCloud& cloud,
              const PcdWriteOptions& options = {});

}  // namespace multicue::io

#pragma once
/// \file Voxel-grid downsampling: one point per occupied voxel at the centroid of its points.

#include "multicue/core/point_cloud.hpp"

namespace multicue {

struct VoxelGridParams {
    float leaf_size = 0.01f;       ///< voxel edge length [m]
    int min_points_per_voxel = 1;  ///< voxels with fewer points give no output point [points]
    int num_threads = 0;           ///< threads (0 = all cores); never changes the result
};

/// Replaces the finite points of every voxel by one point at their centroid. Voxels are those of
/// search/voxel_hash_map.hpp (floor(p / leaf_size) computed as PCL does); NaN points are ignored.
/// Per output point, over the finite points of its voxel:
///   - colours: the per-channel mean (alpha included), rounded to the nearest integer;
///   - normals: the mean of the finite normals, renormalised; NaN if there are none or the mean is
///     zero;
///   - curvature, intensity, confidence: the mean of the finite values, NaN if there are none;
///   - labels: the most frequent label, ties going to the smallest label.
/// Extra fields are dropped (logged at debug level). Output points come in ascending voxel key
/// order (lexicographic in the integer voxel coordinates y, x, z; see voxel_hash_map.hpp),
/// identical for any thread count. The
/// result is unorganized and keeps the sensor pose; an input without finite points gives an empty
/// cloud. Throws InvalidArgument if leaf_size is not > 0 and finite or too small for the cloud's
/// extent (more than 2^64 voxels, or voxel coordinates beyond 32 bits), if min_points_per_voxel or
/// num_threads is negative; DataError if the cloud's fields have inconsistent sizes.
PointCloud VoxelGrid(const PointCloud& cloud, const VoxelGridParams& params);

}  // namespace multicue

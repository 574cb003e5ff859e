#pragma once
/// \file Preparing a scan for registration: a voxel grid evens out the density (a depth camera
/// samples near surfaces far more densely than far ones, and ICP would weigh them so), and
/// normals oriented towards the sensor give the point-to-plane residuals, the normal gate and
/// the plane patches. Organized frames may keep their pixel grid for projective correspondences.

#include "multicue/core/point_cloud.hpp"
#include "multicue/surface/normals.hpp"

namespace multicue {

struct PreprocessParams {
    float voxel_size = 0.01f;  ///< voxel grid edge [m]; 0 = keep every finite point
    /// Normals of the downsampled cloud: k-d tree PCA (k nearest, or a radius).
    NormalParams normals{.k = 20};
    /// Organized frames keep their layout (no downsampling, NaN pixels kept) and get image-space
    /// normals: the projective path of ICP needs the pixel grid.
    bool keep_organized = false;
    OrganizedNormalParams organized_normals{.half_window = 7};  ///< normals of kept frames
    int num_threads = 0;  ///< 0 = all cores; never changes the result
    /// Throws InvalidArgument naming the first out-of-range field.
    void Validate() const;
};

/// The cloud voxel-downsampled (NaN points removed; unorganized) with normals and curvature
/// oriented towards its sensor_origin, or, with keep_organized and an organized input, the frame
/// itself with image-space normals. Existing normals are recomputed. Throws InvalidArgument for
/// bad parameters; an empty or NaN-only cloud gives an empty cloud.
PointCloud PreprocessForRegistration(const PointCloud& cloud, const PreprocessParams& params);

}  // namespace multicue

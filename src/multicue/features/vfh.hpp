#pragma once
/// \file Viewpoint Feature Histogram, VFH (Rusu et al., 2010), one 308-bin descriptor per cluster,
/// a comparison feature of thesis Table 2.2. Computed as PCL 1.13's VFHEstimation.
///
/// The cluster's centroid c and mean normal m (the plain average of the normals, not
/// renormalised, as PCL uses it) form the source of the Darboux-frame pair features with every
/// point (detail::PairFeatures). Layout (FeatureVector of 308):
/// - bins 0-44: f1 (angle in [-pi, pi]), 45-89: f2, 90-134: f3 (45 equal bins each), each pair
///   adding 100 / (n - 1) for n usable points, so each block sums to 100 n / (n - 1) (PCL's
///   factor; the centroid is not one of the points);
/// - bins 135-179: f4, the distance from the centroid: with normalize_distances, 45 bins over
///   [0, largest distance from the centroid], else bin round(100 d) (1 cm bins); it receives
///   counts only with size_component (PCL's default leaves it zero, and so does ours);
/// - bins 180-307: the viewpoint component, 128 bins of (n . v + 1) / 2 with v the unit vector
///   from the centroid to the viewpoint, each point adding 100 / n (sums to 100).
/// Points whose position or normal is not finite are skipped. Fewer than 2 usable points give a
/// zero vector.

#include <optional>

#include "multicue/features/feature_common.hpp"

namespace multicue {

inline constexpr int kVfhSize = 308;

struct VfhParams {
    /// Viewpoint [m]; default: the cloud's sensor_origin.
    std::optional<Eigen::Vector3f> viewpoint = std::nullopt;
    bool normalize_distances = false;  ///< f4 bins over [0, max distance] instead of 1 cm bins
    bool size_component = false;       ///< fill the f4 block (PCL's setFillSizeComponent)
    /// Reproduce PCL 1.13's VFHEstimation, quirks included: (1) f2 and f3 are binned like the
    /// angle f1, floor(45 (f + pi) / (2 pi)), so their values in [-1, 1] fill only bins 15-29
    /// of their blocks; (2) the centroid's homogeneous coordinate 1 enters two norms: the
    /// viewpoint direction is (v - c) / sqrt(|v - c|^2 + 1) (so n . v spans less than [-1, 1],
    /// in a way that depends on the unit of length) and the distance normalisation is
    /// sqrt(d_max^2 + 1). Off (default): 45 bins over [-1, 1] for f2 and f3, a unit viewpoint
    /// direction and d_max.
    bool pcl_compatible = false;
};

/// VFH of the whole cloud (one cluster). Throws InvalidArgument if the cloud has no normals
/// (and is not empty) or the viewpoint is not finite.
FeatureVector ComputeVfh(const PointCloud& cluster, const VfhParams& params = {});

}  // namespace multicue

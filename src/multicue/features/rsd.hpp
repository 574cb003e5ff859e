#pragma once
/// \file Radius-based Surface Descriptor, RSD (thesis section 2.5.1, Eq. 2.6-2.7).
///
/// For a reference point and each neighbour within `radius`, the distance d and the angle alpha
/// in [0, pi/2] between the two normal lines (orientation ignored) lie on d = r alpha for a circle
/// of radius r through both points (Eq. 2.7, the first Taylor term of Eq. 2.6). The neighbours are
/// split into `num_bins` distance bins of equal width; the smallest and the largest angle of each
/// bin, paired with the bin's centre distance, give two least-squares lines through the origin
/// whose slopes are r_max (smallest angles) and r_min (largest angles):
///     r = sum_b f_b alpha_b / sum_b alpha_b^2,   f_b = (b + 0.5) radius / num_bins.
/// Distances are measured from the query point, angles against the reference normal (the query
/// point's own; for voxels that of the point nearest to the voxel centroid). The reference lies
/// in bin 0 with angle 0. A radius is capped at `plane_radius` (all angles 0, a plane, gives
/// plane_radius).
///
/// Bias correction (section 2.5.1: "r_min is typically under- and r_max over-estimated"): the
/// largest angle of a bin belongs to its far end but is paired with the bin centre, so on a
/// sphere of radius R the fit gives r_min = R sum_b (b+0.5)(b+1) / sum_b (b+1)^2 = 0.864 R for
/// 5 bins, and r_max = R sum_b (b+0.5) b / sum_b b^2 = 1.167 R. With `correct_bias` r_min is
/// scaled by 1.1 and r_max by 0.9 (0.95 R and 1.05 R remain), then both are capped at
/// plane_radius, so a plane gives (plane_radius, plane_radius).
///
/// PCL compatibility: pcl::computeRSD uses the same two factors but applies 1.1 to the radius of
/// the smallest angles (the larger one) and 0.9 to that of the largest angles, so it scales r_max
/// up and r_min down, and it caps before scaling (a plane gives r_min = 0.18, r_max = 0.22 for a
/// 0.2 cap; a sphere r_min = 0.78 R). `pcl_compatible` reproduces PCL step by step (the oracle
/// test checks it); the default corrects in the direction section 2.5.1 describes.
/// The two radii are swapped if r_min > r_max.
///
/// Layout: FeatureMatrix n x 2, columns (r_min, r_max) [m], one row per point; NaN rows for
/// points that are not finite or have no finite normal. A point without any other neighbour gets
/// (0, 0) as in PCL.

#include <cstdint>
#include <vector>

#include "multicue/features/feature_common.hpp"
#include "multicue/features/surface_types.hpp"

namespace multicue {

struct RsdParams {
    /// Neighbourhood radius [m]. 2 cm keeps the angles of the 2 cm spheres of section 2.5.1
    /// below pi/2 and matches the 2.5 cm voxels of section 2.5.2 (their half diagonal is 2.17 cm).
    float radius = 0.02f;
    int num_bins = 5;             ///< distance bins (section 2.5.1 uses 5), >= 1
    float plane_radius = 0.2f;    ///< cap on both radii [m] (Figure 2.23 caps at 0.2 m)
    bool correct_bias = true;     ///< scale r_min by 1.1 and r_max by 0.9 (see above)
    bool pcl_compatible = false;  ///< PCL's factor assignment and order (see above)
    int num_threads = 0;          ///< 0 = all cores; never changes the result
    /// Which angle of a bin counts as its largest: the one this share of the bin's neighbours
    /// does not exceed (and the smallest symmetrically, 1 - share), in (0, 1]. 1 (default) takes
    /// the extreme angles as section 2.5.1 and PCL do; below 1 the tails of the normal noise of
    /// a real sensor no longer make planes look curved (docs/part-graph.md).
    float angle_quantile = 1.0f;
    /// Throws InvalidArgument naming the first out-of-range field.
    void Validate() const;
    /// Its parameters once each: configuration key (the field's name), field, meaning. A
    /// visitor reads or records them (io::ConfigSection::operator(); ReadPerceiveParams).
    template <typename V>
    void VisitParams(V& v) {
        v("radius", radius, "RSD neighbourhood radius [m]");
    }
};

/// RSD of every point of `cloud` (with normals) from neighbourhoods in `tree` (built from this
/// cloud). Throws InvalidArgument if the cloud has no normals, radius or plane_radius is not > 0,
/// num_bins < 1 or num_threads < 0. An empty cloud gives a 0 x 2 matrix.
FeatureMatrix ComputeRsd(const PointCloud& cloud, const KdTree& tree, const RsdParams& params);

/// Radii of one neighbourhood: distances are measured from `reference`, angles against
/// `reference_normal`; `neighbours` are cloud indices.
Eigen::Vector2f RsdOfNeighbourhood(const PointCloud& cloud, const Eigen::Vector3f& reference,
                                   const Eigen::Vector3f& reference_normal,
                                   const Indices& neighbours, const RsdParams& params);

/// Parameters of RSD per voxel (section 2.5.2: "we label voxels directly instead of individual
/// points").
struct VoxelRsdParams {
    float voxel_size = 0.025f;  ///< voxel edge length [m] (section 2.5.2)
    /// RSD settings. The neighbourhood radius used is max(rsd.radius, sqrt(3)/2 voxel_size), so
    /// that the sphere covers the voxel (PCL's GRSDEstimation does the same).
    RsdParams rsd = {};
    SurfaceTypeThresholds thresholds = {};
};

/// RSD and surface type of every occupied voxel.
struct VoxelRsdResult {
    float voxel_size = 0.0f;
    std::vector<Eigen::Vector3i> coordinates;  ///< integer voxel coordinates, floor(p / size)
    std::vector<Eigen::Vector3f> centroids;    ///< mean of the voxel's points [m]
    FeatureMatrix radii;                       ///< V x 2: (r_min, r_max) [m]; NaN if undefined
    std::vector<SurfaceType> types;            ///< surface type per voxel
    std::vector<std::uint32_t> point_voxel;    ///< voxel of every cloud point, or kNoVoxel
    static constexpr std::uint32_t kNoVoxel = 0xffffffffu;

    std::size_t size() const { return coordinates.size(); }
};

/// RSD per voxel: the cloud's finite points are grouped into voxels (in the order of
/// VoxelHashMap, ascending (y, x, z)); each voxel's radii are those of the neighbourhood of its
/// centroid (distances from the centroid, angles against the normal of the cloud point nearest
/// to it), as PCL's
/// GRSDEstimation computes them. Costs one neighbourhood per voxel instead of one per point.
/// Same errors as ComputeRsd, and InvalidArgument if voxel_size is not > 0.
VoxelRsdResult ComputeVoxelRsd(const PointCloud& cloud, const KdTree& tree,
                               const VoxelRsdParams& params);

}  // namespace multicue

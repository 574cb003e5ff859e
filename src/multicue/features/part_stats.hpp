#pragma once
/// \file The 24 statistical features of a part (thesis section 4.2.3.1).
///
/// Layout of the FeatureVector (24 values). Eigenvalues e1 <= e2 <= e3 of the part's covariance
/// are taken in ascending order, so that every ratio below lies in [0, 1]; eigenvector k belongs
/// to e_k, so axis 1 is the part's normal direction and axis 3 its longest extent.
///   0      boundary point proportion (Rusu et al., 2008c: a point is on the boundary when the
///          directions to its neighbours, projected on its tangent plane, leave a gap wider
///          than boundary_angle)
///   1      mean curvature: the surface variation lambda0 / (lambda0 + lambda1 + lambda2) of
///          each point's neighbourhood (the cloud's curvature field when present, else computed
///          with `radius`), averaged over the part
///   2      occupied volume: number of voxels of size voxel_size holding points, times
///          voxel_size^3 [m^3]
///   3-8    e1/e2, e2/e3, e1/e3, e1/sum, e2/sum, e3/sum (sum = e1 + e2 + e3)
///   9-11   v1, v2, v3: standard deviation of the points projected on each eigenvector [m]
///          ("metric variances", used instead of e_k)
///   12     orientation: |cos| of the angle between eigenvector 1 (smallest eigenvalue: the
///          part's normal) and `up`; 1 for a horizontal part, 0 for a vertical one
///   13-15  extents L_k = l_k^+ + l_k^- along each eigenvector, l^+ and l^- the distances of
///          the farthest points from the mean in both directions [m]
///   16-18  min(l_k^+, l_k^-) / max(l_k^+, l_k^-): the thesis's l^1/l^2 with the two sides
///          ordered, since the sign of an eigenvector is arbitrary (0 if both are 0)
///   19     L_1 / L_2
///   20-22  v_k / L_k
///   23     occupied volume / volume of the oriented bounding box, whose sides are
///          L_k + voxel_size (the voxels' own thickness), so the ratio is in (0, 1]
/// A ratio whose denominator is 0 is 0. The thesis scales every feature to [0, 1] over the
/// training set; that is a dataset step (min-max normalisation), not done per part here.

#include "multicue/features/feature_common.hpp"

namespace multicue {

inline constexpr int kPartStatsSize = 24;

struct PartStatsParams {
    float radius = 0.02f;      ///< neighbourhood radius for boundary points and curvature [m]
    float voxel_size = 0.01f;  ///< voxel size for the occupied volume [m]
    float boundary_angle = 1.5707964f;  ///< angular gap marking a boundary point [rad] (pi/2)
    Eigen::Vector3f up = Eigen::Vector3f::UnitZ();  ///< the world's up direction (unit length)
    int num_threads = 0;                            ///< 0 = all cores; never changes the result
};

/// The 24 features of one part (the whole cloud, with normals). Fewer than 3 finite points give
/// zeros. Throws InvalidArgument without normals, for radius, voxel_size or boundary_angle not
/// > 0, or an `up` that is not a finite non-zero vector.
FeatureVector ComputePartStatistics(const PointCloud& part, const PartStatsParams& params = {});

/// Boundary flag (Rusu et al., 2008c) of every point from neighbourhoods in `tree`: 1 on the
/// boundary, 0 inside, 0 for points without a finite position and normal.
std::vector<std::uint8_t> EstimateBoundaryPoints(const PointCloud& cloud, const KdTree& tree,
                                                 float radius, float angle, int num_threads);

}  // namespace multicue

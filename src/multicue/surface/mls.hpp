#pragma once
/// \file Robust moving least squares (RMLS, thesis section 2.3.1): every output point is projected
/// onto a local polynomial surface fitted over a neighbourhood of the input.
///
/// Per output point q (an input point, or a point of the resampling grid of Eq. 2.1):
///   1. neighbours P_k of q within `radius`, weighted by W = exp(-d(p, q)^2 / h^2) (Eq. 2.2);
///   2. a reference plane: in robust mode a weighted RANSAC plane (the plane whose inliers carry
///      the largest summed weight), refined by a weighted PCA of its inliers; in plain mode the
///      weighted least-squares plane of the whole neighbourhood (what weighted MLS does, and what
///      a patch of outliers with surface-like density pulls towards it, Figure 2.4);
///   3. a bivariate polynomial height field of order 2 or 3 (Eq. 2.3) fitted by weighted least
///      squares to the inliers in the plane's (u, v, n) frame, origin at q's projection;
///   4. the output point is the polynomial at (0, 0), its normal the cross product of the two
///      partial derivatives there (Eq. 2.4), its curvature the surface variation of the inliers and
///      its colour their weighted mean colour.
///
/// Results do not depend on the thread count: RANSAC samples come from a generator seeded with
/// (seed, output index), and every point is computed independently.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "multicue/core/point_cloud.hpp"
#include "multicue/search/kdtree.hpp"

namespace multicue {

/// How the reference plane of a neighbourhood is found.
enum class MlsPlaneFit {
    kWeightedRansac,       ///< robust: weighted RANSAC + weighted PCA of its inliers (RMLS)
    kWeightedLeastSquares  ///< plain: weighted PCA of the whole neighbourhood (classic MLS)
};

struct MlsParams {
    float radius = 0.0f;  ///< neighbourhood radius [m]; must be > 0
    /// h of Eq. (2.2) [m]; 0 = radius / 2 (a neighbour at the radius weighs exp(-4) = 0.018).
    float gaussian = 0.0f;
    int polynomial_order = 2;  ///< 0 (plane projection only), 1, 2 or 3 (Eq. 2.3)
    MlsPlaneFit plane_fit = MlsPlaneFit::kWeightedRansac;
    /// Distance of a RANSAC inlier from its plane [m]; 0 = radius / 10.
    float inlier_distance = 0.0f;
    int max_iterations = 100;  ///< RANSAC samples per point at most (fewer once confident)
    float confidence = 0.99f;  ///< stop sampling when a better plane is this unlikely to exist
    /// Fewest neighbours (query point included) for a fit; output points with fewer are dropped.
    int min_neighbors = 5;
    /// Resampling step s of Eq. (2.1) [m]: 0 = one output point per finite input point (the
    /// input is smoothed in place); > 0 = one output point per occupied voxel floor(p / s),
    /// started at the voxel's centre (up- or down-sampling to an even density).
    float resample_step = 0.0f;
    /// Density adapted to curvature (Figure 2.13; with resample_step > 0): a point whose surface
    /// variation c (PCA within `radius`) exceeds the cloud's mean c0 asks for the step
    /// resample_step / (1 + curvature_slope * (c - c0) / c0), rounded to resample_step / 2^l with
    /// l in {0, 1, 2} (finer grids are nested in coarser ones, so the levels do not overlap
    /// much). 0 = the same step everywhere.
    float curvature_slope = 0.0f;
    /// Orientation of output normals where the input has none [m]; default: sensor_origin.
    std::optional<Eigen::Vector3f> viewpoint = std::nullopt;
    std::uint64_t seed = 0;  ///< RANSAC sampling seed (per point: seed and output index)
    int num_threads = 0;     ///< 0 = all cores
};

struct MlsResult {
    /// Projected points with unit normals (from Eq. 2.4), curvature, and colours and labels when
    /// the input has them (colour: weighted mean over the inliers; label: nearest inlier's).
    /// Unorganized.
    PointCloud cloud;
    /// For every output point, the input point nearest its starting position.
    Indices source;
    std::size_t dropped = 0;  ///< starting points with fewer than min_neighbors neighbours
    /// Points whose polynomial fit was singular and that were projected onto the plane instead.
    std::size_t plane_only = 0;
    double mean_inlier_fraction = 0.0;  ///< mean fraction of neighbours kept as plane inliers
};

/// Robust (or plain) MLS of `cloud`, neighbours found in `tree` (built from `cloud`).
/// Throws InvalidArgument naming the parameter for radius <= 0 or not finite, gaussian < 0,
/// polynomial_order outside [0, 3], inlier_distance < 0, max_iterations < 1, confidence outside
/// (0, 1), min_neighbors < 3, resample_step < 0, curvature_slope < 0, num_threads < 0, or a tree
/// of another cloud.
/// An empty cloud gives an empty result.
MlsResult MovingLeastSquares(const PointCloud& cloud, const KdTree& tree, const MlsParams& params);

/// Fast MLS for organized RGB-D frames (section 2.3.1, last paragraph; Figure 2.8): the
/// neighbourhood of a pixel is its image-space window limited to `radius` in 3D, the plane is
/// the weighted PCA plane (no RANSAC), and points and normals are re-fitted with the polynomial.
struct OrganizedMlsParams {
    float radius = 0.02f;      ///< 3D neighbourhood radius [m]
    int half_window = 5;       ///< half-size of the pixel window [pixels]
    int polynomial_order = 2;  ///< 0..3
    float gaussian = 0.0f;     ///< h of Eq. (2.2) [m]; 0 = radius / 2
    int min_neighbors = 5;     ///< fewer valid neighbours: the pixel becomes NaN
    /// Orientation of normals [m]; default: the cloud's sensor_origin.
    std::optional<Eigen::Vector3f> viewpoint = std::nullopt;
    int num_threads = 0;  ///< 0 = all cores
};

/// The organized cloud with smoothed points, normals and curvature in place (same width, height
/// and field order; pixels without a fit become NaN). `source` is the identity over the pixels.
/// Throws InvalidArgument for an unorganized non-empty cloud or bad parameters.
MlsResult MovingLeastSquaresOrganized(const PointCloud& organized,
                                      const OrganizedMlsParams& params);

}  // namespace multicue

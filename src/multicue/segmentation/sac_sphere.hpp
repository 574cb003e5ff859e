#pragma once
/// \file Robust sphere fitting (RANSAC/MSAC): balls, fruit and the (half) spheres of the shape
/// categories in section 5.1.

#include <limits>

#include <Eigen/Core>

#include "multicue/core/point_cloud.hpp"
#include "multicue/core/types.hpp"
#include "multicue/segmentation/sample_consensus.hpp"

namespace multicue {

struct SphereFitParams {
    SacParams sac{};          ///< sampling, threshold, stopping and refinement
    float min_radius = 0.0f;  ///< smallest accepted radius [m]
    float max_radius = std::numeric_limits<float>::infinity();  ///< largest accepted radius [m]
    /// Hypotheses from two points and their normals (the centre where the normal lines come
    /// closest) instead of four points: a sample is all inliers with probability w^2 instead of
    /// w^4, so far fewer samples reach the same confidence on objects that are partly spherical.
    /// Needs normals.
    bool oriented_samples = false;
};

struct SphereFit {
    bool found = false;  ///< a sphere with at least 4 inliers (2 with oriented samples) was found
    Eigen::Vector3f center = Eigen::Vector3f::Zero();  ///< centre [m]
    float radius = 0.0f;                               ///< radius [m]
    Indices inliers;         ///< points within the threshold, in input order
    int iterations = 0;      ///< samples drawn [samples]
    bool converged = false;  ///< stopped by Eq. (4.6) before max_iterations
    float rmse = 0.0f;       ///< root mean square point-to-surface distance of the inliers [m]
};

/// Fits a sphere to the points `indices` of `cloud` (all points when empty); non-finite points are
/// skipped. The distance of a point is | |p - centre| - r |; with normal_distance_weight > 0 the
/// normal is compared with the radial direction. The refinement minimises the sum of squared
/// distances of the inliers (Levenberg-Marquardt, started at the sample's sphere). Spheres outside
/// [min_radius, max_radius] are rejected.
/// Throws InvalidArgument for bad parameters or an index out of range, DataError when normals are
/// needed but missing (normal weight or oriented samples). Fewer than 4 usable points (2 with
/// oriented samples) give found = false.
SphereFit FitSphere(const PointCloud& cloud, const Indices& indices, const SphereFitParams& params);

}  // namespace multicue

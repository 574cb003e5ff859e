#pragma once
/// \file Robust 3D line fitting (RANSAC/MSAC): handles and edges (section 4.1 fits RANSAC lines to
/// the clusters in front of furniture faces to tell handles from knobs).

#include <optional>

#include <Eigen/Core>

#include "multicue/core/point_cloud.hpp"
#include "multicue/core/types.hpp"
#include "multicue/segmentation/sample_consensus.hpp"

namespace multicue {

struct LineFitParams {
    SacParams sac{};  ///< sampling, threshold, stopping and refinement
    /// Constraint axis (any non-zero length): the direction must lie within max_angle of it.
    std::optional<Eigen::Vector3f> axis = std::nullopt;
    float max_angle = 0.17453293f;  ///< allowed angle between direction and axis, [0, pi/2] [rad]
};

struct LineFit {
    bool found = false;  ///< a line with at least 2 inliers was found
    /// Point on the line: the projection of the inliers' centroid onto it [m].
    Eigen::Vector3f point = Eigen::Vector3f::Zero();
    /// Unit direction; points along the constraint axis when one is given, else its
    /// largest-magnitude component is positive.
    Eigen::Vector3f direction = Eigen::Vector3f::UnitX();
    Indices inliers;         ///< points within the threshold, in input order
    int iterations = 0;      ///< samples drawn [samples]
    bool converged = false;  ///< stopped by Eq. (4.6) before max_iterations
    float rmse = 0.0f;       ///< root mean square point-to-line distance of the inliers [m]
};

/// Fits a 3D line to the points `indices` of `cloud` (all points when empty); non-finite points
/// are skipped. The refinement is the least-squares line of the inliers: through their centroid
/// along the eigenvector of the largest eigenvalue of their covariance.
/// Throws InvalidArgument for bad parameters or an index out of range. Fewer than 2 usable points
/// give found = false.
LineFit FitLine(const PointCloud& cloud, const Indices& indices, const LineFitParams& params);

}  // namespace multicue

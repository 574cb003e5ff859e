#pragma once
/// \file Robust plane fitting (RANSAC/MSAC), optionally constrained to an axis: the support plane
/// of a table-top scene is the near-horizontal plane (normal along "up") of section 2.4; walls are
/// planes whose normal is perpendicular to "up" (section 4.1).

#include <optional>

#include <Eigen/Core>

#include "multicue/core/point_cloud.hpp"
#include "multicue/core/types.hpp"
#include "multicue/segmentation/sample_consensus.hpp"

namespace multicue {

/// How a plane's normal must relate to PlaneFitParams::axis.
enum class PlaneAxisMode {
    kParallel,       ///< normal within max_angle of the axis (axis = up: a horizontal table)
    kPerpendicular,  ///< normal within max_angle of perpendicular to it (axis = up: a wall)
};

struct PlaneFitParams {
    SacParams sac{};  ///< sampling, threshold, stopping and refinement
    /// Constraint axis (any non-zero length); none = any orientation.
    std::optional<Eigen::Vector3f> axis = std::nullopt;
    float max_angle = 0.17453293f;  ///< allowed deviation from the axis relation, [0, pi/2] [rad]
    PlaneAxisMode axis_mode = PlaneAxisMode::kParallel;  ///< relation of the normal to the axis
    /// The normal points to this side of the plane; none = the cloud's sensor_origin. With a
    /// kParallel axis the normal points along the axis instead.
    std::optional<Eigen::Vector3f> viewpoint = std::nullopt;
};

struct PlaneFit {
    bool found = false;  ///< a plane with at least 3 inliers was found
    /// (a, b, c, d): unit normal (a, b, c) and a x + b y + c z + d = 0; the normal is oriented
    /// along the kParallel axis when one is given, else towards the viewpoint.
    Eigen::Vector4f plane = Eigen::Vector4f::Zero();
    Indices inliers;         ///< points within the threshold, in input order
    int iterations = 0;      ///< samples drawn [samples]
    bool converged = false;  ///< stopped by Eq. (4.6) before max_iterations
    float rmse = 0.0f;       ///< root mean square point-to-plane distance of the inliers [m]
};

/// Fits a plane to the points `indices` of `cloud` (all points when empty); non-finite points are
/// skipped. The refinement is the least-squares (PCA) plane of the inliers: the eigenvector of the
/// smallest eigenvalue of their covariance, through their centroid.
/// Throws InvalidArgument for bad parameters (see ValidateSacParams; a zero or non-finite axis,
/// max_angle outside [0, pi/2]) or an index out of range. Fewer than 3 usable points give
/// found = false.
PlaneFit FitPlane(const PointCloud& cloud, const Indices& indices, const PlaneFitParams& params);

}  // namespace multicue

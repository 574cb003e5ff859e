#pragma once
/// \file Robust circle fitting (RANSAC/MSAC): in the xy plane (a cylinder seen from above, a plate
/// rim projected onto the table) and in 3D (knobs, rims; section 4.1 tells handles from knobs by
/// fitting lines and circles).

#include <limits>
#include <optional>

#include <Eigen/Core>

#include "multicue/core/point_cloud.hpp"
#include "multicue/core/types.hpp"
#include "multicue/segmentation/sample_consensus.hpp"

namespace multicue {

struct Circle2dFitParams {
    SacParams sac{};          ///< sampling, threshold, stopping and refinement
    float min_radius = 0.0f;  ///< smallest accepted radius [m]
    float max_radius = std::numeric_limits<float>::infinity();  ///< largest accepted radius [m]
};

struct Circle2dFit {
    bool found = false;  ///< a circle with at least 3 inliers was found
    Eigen::Vector2f center = Eigen::Vector2f::Zero();  ///< centre in the xy plane [m]
    float radius = 0.0f;                               ///< radius [m]
    Indices inliers;         ///< points within the threshold, in input order
    int iterations = 0;      ///< samples drawn [samples]
    bool converged = false;  ///< stopped by Eq. (4.6) before max_iterations
    float rmse = 0.0f;       ///< root mean square distance of the inliers to the circle in xy [m]
};

/// Fits a circle to the xy coordinates of the points `indices` of `cloud` (all points when empty;
/// z is ignored); non-finite points are skipped. The distance of a point is | |xy - centre| - r |.
/// The refinement minimises the sum of squared distances of the inliers (Levenberg-Marquardt,
/// started at the sample's circle). Circles outside [min_radius, max_radius] are rejected.
/// Throws InvalidArgument for bad parameters or an index out of range. Fewer than 3 usable points
/// give found = false.
Circle2dFit FitCircle2d(const PointCloud& cloud, const Indices& indices,
                        const Circle2dFitParams& params);

struct Circle3dFitParams {
    SacParams sac{};          ///< sampling, threshold, stopping and refinement
    float min_radius = 0.0f;  ///< smallest accepted radius [m]
    float max_radius = std::numeric_limits<float>::infinity();  ///< largest accepted radius [m]
    /// The normal points to this side of the circle's plane; none = the cloud's sensor_origin.
    std::optional<Eigen::Vector3f> viewpoint = std::nullopt;
};

struct Circle3dFit {
    bool found = false;  ///< a circle with at least 3 inliers was found
    Eigen::Vector3f center = Eigen::Vector3f::Zero();   ///< centre [m]
    Eigen::Vector3f normal = Eigen::Vector3f::UnitZ();  ///< unit normal of the circle's plane
    float radius = 0.0f;                                ///< radius [m]
    Indices inliers;         ///< points within the threshold, in input order
    int iterations = 0;      ///< samples drawn [samples]
    bool converged = false;  ///< stopped by Eq. (4.6) before max_iterations
    float rmse = 0.0f;       ///< root mean square point-to-circle distance of the inliers [m]
};

/// Fits a circle in 3D to the points `indices` of `cloud` (all points when empty); non-finite
/// points are skipped. The distance of a point is its Euclidean distance to the nearest point of
/// the circle, sqrt(h^2 + (rho - r)^2) with h its height above the circle's plane and rho its
/// distance from the axis. The refinement minimises the sum of squared distances of the inliers
/// (Levenberg-Marquardt over centre, normal and radius). Circles outside [min_radius, max_radius]
/// are rejected.
/// Throws InvalidArgument for bad parameters or an index out of range. Fewer than 3 usable points
/// give found = false.
Circle3dFit FitCircle3d(const PointCloud& cloud, const Indices& indices,
                        const Circle3dFitParams& params);

}  // namespace multicue

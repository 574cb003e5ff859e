#pragma once
/// \file Robust cylinder fitting (RANSAC/MSAC) from points with normals, section 5.4.2.1: on a
/// cylinder every normal is orthogonal to the axis and intersects it, so two points with their
/// normals give the axis direction (the cross product of the normals), a point on the axis (the
/// closest approach of the two point/normal lines) and the radius.

#include <limits>
#include <optional>

#include <Eigen/Core>

#include "multicue/core/point_cloud.hpp"
#include "multicue/core/types.hpp"
#include "multicue/segmentation/sample_consensus.hpp"

namespace multicue {

struct CylinderFitParams {
    SacParams sac{};          ///< sampling, threshold, stopping and refinement
    float min_radius = 0.0f;  ///< smallest accepted radius [m]
    float max_radius = std::numeric_limits<float>::infinity();  ///< largest accepted radius [m]
    /// Constraint axis (any non-zero length): the cylinder's axis must lie within max_angle of it
    /// (an upright mug: axis = up; section 5.4.2.1 notes that upright axes are more robust).
    std::optional<Eigen::Vector3f> axis = std::nullopt;
    float max_angle = 0.17453293f;  ///< allowed angle between the two axes, [0, pi/2] [rad]
};

struct CylinderFit {
    bool found = false;  ///< a cylinder with at least 2 inliers was found
    /// Point on the axis: the projection of the inliers' centroid onto it [m].
    Eigen::Vector3f point = Eigen::Vector3f::Zero();
    /// Unit axis direction; points along the constraint axis when one is given, else its
    /// largest-magnitude component is positive.
    Eigen::Vector3f axis = Eigen::Vector3f::UnitZ();
    float radius = 0.0f;     ///< radius [m]
    Indices inliers;         ///< points within the threshold, in input order
    int iterations = 0;      ///< samples drawn [samples]
    bool converged = false;  ///< stopped by Eq. (4.6) before max_iterations
    float rmse = 0.0f;       ///< root mean square point-to-surface distance of the inliers [m]
};

/// Fits a cylinder to the points `indices` of `cloud` (all points when empty). Needs normals;
/// points with a non-finite position or normal are skipped. The distance of a point is
/// | dist(p, axis) - r |; with normal_distance_weight > 0 the normal is compared with the radial
/// direction. The refinement minimises the sum of squared distances of the inliers
/// (Levenberg-Marquardt over axis direction, axis position and radius). Cylinders outside
/// [min_radius, max_radius] or the axis constraint are rejected.
/// Throws InvalidArgument for bad parameters or an index out of range, DataError if the cloud has
/// no normals (unless it is empty). Fewer than 2 usable points give found = false.
CylinderFit FitCylinder(const PointCloud& cloud, const Indices& indices,
                        const CylinderFitParams& params);

}  // namespace multicue

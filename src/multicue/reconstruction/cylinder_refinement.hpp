#pragma once
/// \file Internal to the reconstruction module: least-squares refinement of a cylinder on the
/// points of its side (used by FitObjectCylinder), with the axis fixed, turning about "up" only,
/// or free.

#include <Eigen/Core>

#include "multicue/core/point_cloud.hpp"
#include "multicue/core/types.hpp"

namespace multicue::detail {

struct CylinderState {
    Eigen::Vector3d point = Eigen::Vector3d::Zero();  ///< on the axis [m]
    Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();  ///< unit direction
    double radius = 0.0;                              ///< [m]
};

/// How the axis direction may move in the refinement.
enum class AxisFreedom {
    kFixed,    ///< upright: the axis is the support plane's normal
    kAboutUp,  ///< lying: the axis turns within the plane
    kFree,     ///< any direction
};

/// The points of `usable` within max_distance of the cylinder's side whose normals are within
/// acos(min_cos) of radial (sign-free), in input order.
Indices SidePoints(const PointCloud& cloud, const Indices& usable, const CylinderState& x,
                   double max_distance, double min_cos);

/// Levenberg-Marquardt on the residuals e = |q| - r (q = w - (w.a) a, w = p - p0) of `points`,
/// over the axis tilt (two, one or no directions depending on `freedom`; `up` is the unit plane
/// normal for kAboutUp), the axis position across the axis and the radius. The axis point is
/// first moved to the projection of the points' centroid so the tilt is well conditioned.
/// Returns false if the start is not finite; `x` is never made worse.
bool RefineCylinder(const PointCloud& cloud, const Indices& points, const Eigen::Vector3d& up,
                    AxisFreedom freedom, CylinderState& x);

}  // namespace multicue::detail

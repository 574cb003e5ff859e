#pragma once
/// \file Internal to the reconstruction module: the side points of a cylinder and the start of
/// their least-squares refinement (used by FitObjectCylinder; the refinement itself is
/// RefineCylinder of the segmentation module).

#include "multicue/core/point_cloud.hpp"
#include "multicue/core/types.hpp"
#include "multicue/segmentation/cylinder_least_squares.hpp"

namespace multicue::detail {

/// The points of `usable` within max_distance of the cylinder's side whose normals are within
/// acos(min_cos) of radial (sign-free), in input order.
Indices SidePoints(const PointCloud& cloud, const Indices& usable, const CylinderEstimate& x,
                   double max_distance, double min_cos);

/// Moves the axis point to the projection of the centroid of `points` (not empty) onto the axis,
/// so that the axis tilts about the middle of the points and the tilt is well conditioned.
void CentreOnPoints(const PointCloud& cloud, const Indices& points, CylinderEstimate& x);

}  // namespace multicue::detail

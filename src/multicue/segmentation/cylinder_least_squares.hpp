#pragma once
/// \file Least-squares refinement of a cylinder on given points (Levenberg-Marquardt on the
/// point-to-surface distances), with the axis direction free, turning about one direction only,
/// or fixed. Used by the cylinder sample-consensus model and by the object models of the
/// reconstruction module.

#include <span>

#include <Eigen/Core>

#include "multicue/core/point_cloud.hpp"
#include "multicue/core/types.hpp"

namespace multicue {

/// A cylinder in double precision, so that small refinement steps are not lost to rounding.
struct CylinderEstimate {
    Eigen::Vector3d point = Eigen::Vector3d::Zero();  ///< on the axis [m]
    Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();  ///< unit direction
    double radius = 0.0;                              ///< [m]
};

/// How the axis direction may move in the refinement.
enum class CylinderAxisFreedom {
    kFree,  ///< any direction
    /// Turns about `up` only (the axis must not be parallel to `up`): an axis orthogonal to `up`
    /// stays orthogonal to it.
    kAboutUp,
    kFixed,  ///< kept as given
};

struct CylinderRefineParams {
    CylinderAxisFreedom freedom = CylinderAxisFreedom::kFree;  ///< how the axis may move
    Eigen::Vector3d up = Eigen::Vector3d::UnitZ();  ///< turning direction for kAboutUp (non-zero)
    int max_iterations = 50;                        ///< Levenberg-Marquardt steps, >= 0 [steps]
};

/// Minimises the sum of squared residuals e = |q| - r (q = w - (w.a) a, w = p - p0) of `points`
/// over the axis tilt (two, one or no directions depending on `freedom`), the axis position
/// across the axis and the radius, starting from `x`. Moving the axis point along the axis
/// changes nothing, so it is not a parameter.
/// Returns false, leaving `x` unchanged, if the residuals at the start are not finite; otherwise
/// `x` is the last accepted state, never worse than the start.
/// Throws InvalidArgument if max_iterations < 0, or for kAboutUp if `up` is not finite and
/// non-zero, or if a point index is out of range.
bool RefineCylinder(const PointCloud& cloud, std::span<const Index> points,
                    const CylinderRefineParams& params, CylinderEstimate& x);

}  // namespace multicue

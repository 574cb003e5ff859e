#pragma once
/// \file Crop box: the points inside (or outside) an oriented box.

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "multicue/core/point_cloud.hpp"
#include "multicue/core/types.hpp"

namespace multicue {

struct CropBoxParams {
    Eigen::Vector3f min = Eigen::Vector3f::Constant(-1.0f);  ///< box corner in the box frame [m];
                                                             ///< -infinity leaves an axis open
    Eigen::Vector3f max = Eigen::Vector3f::Constant(1.0f);   ///< box corner in the box frame [m];
                                                             ///< +infinity leaves an axis open
    Eigen::Isometry3f T_box_cloud = Eigen::Isometry3f::Identity();  ///< maps cloud coordinates
                                                                    ///< into the box frame
    bool negative = false;  ///< return the finite points outside the box instead
};

/// Indices of the finite points p with min <= T_box_cloud * p <= max on every axis (bounds
/// included), or of the finite points failing that test when `negative` is set; ascending.
/// Non-finite points are never returned. Throws InvalidArgument if a corner coordinate is NaN,
/// min > max on an axis, or the transform is not finite.
Indices CropBox(const PointCloud& cloud, const CropBoxParams& params);

}  // namespace multicue

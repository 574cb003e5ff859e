#pragma once
/// \file Removal of points whose coordinates are NaN or infinite (invalid pixels of RGB-D frames).

#include "multicue/core/point_cloud.hpp"
#include "multicue/core/types.hpp"

namespace multicue {

/// Indices of the points whose three coordinates are finite, ascending.
Indices FiniteIndices(const PointCloud& cloud);

/// The finite points with all their fields, in their original order. The result is unorganized;
/// the sensor pose is kept. Throws DataError if the cloud's fields have inconsistent sizes.
PointCloud RemoveNonFinite(const PointCloud& cloud);

}  // namespace multicue

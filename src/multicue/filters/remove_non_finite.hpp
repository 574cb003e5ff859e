#pragma once
/// \file Removal of points whose coordinates are NaN or infinite (invalid pixels of RGB-D frames).

#include "multicue/core/point_cloud.hpp"
#include "multicue/core/types.hpp"

namespace multicue {

/// Indices of the points whose three coordinates are finite, ascending; `num_threads` (0 = all
/// cores) does not change them.
Indices FiniteIndices(const PointCloud& cloud, int num_threads = 1);

/// The finite points with all their fields, in their original order. The result is unorganized;
/// the sensor pose is kept. Throws DataError if the cloud's fields have inconsistent sizes.
PointCloud RemoveNonFinite(const PointCloud& cloud);

}  // namespace multicue

#pragma once
/// \file Statistical and radius outlier removal over a prebuilt k-d tree.
///
/// Both return the indices of the points to keep, ascending, for use with SelectByIndex. The tree
/// must index `cloud` (or a subset of it): neighbour indices are compared with the query's own
/// index to leave the query point out. Non-finite points are never kept. Results do not depend on
/// num_threads.

#include "multicue/core/point_cloud.hpp"
#include "multicue/core/types.hpp"
#include "multicue/search/kdtree.hpp"

namespace multicue {

struct StatisticalOutlierParams {
    int k = 50;  ///< neighbours per point for its mean distance, itself excluded [points]
    float std_ratio = 1.0f;  ///< keep mean distances <= mean + std_ratio * stddev [stddevs]
    int num_threads = 0;     ///< threads (0 = all cores)
};

/// Statistical outlier removal as in PCL: for every finite point the mean distance d_i to its k
/// nearest neighbours in the tree (the point itself excluded); over all points that have
/// neighbours, the mean m and sample standard deviation s of d_i; points with d_i <= m +
/// std_ratio * s are kept. A point without neighbours is dropped and left out of m and s.
/// Throws InvalidArgument if k < 1, std_ratio < 0 or not finite, or num_threads < 0.
Indices StatisticalOutlierRemoval(const PointCloud& cloud, const KdTree& tree,
                                  const StatisticalOutlierParams& params);

struct RadiusOutlierParams {
    float radius = 0.05f;   ///< neighbourhood radius [m]
    int min_neighbors = 2;  ///< neighbours within radius, the point itself excluded, needed to keep
                            ///< a point [points]
    int num_threads = 0;    ///< threads (0 = all cores)
};

/// Keeps the finite points with at least min_neighbors other indexed points within `radius`
/// (distance <= radius, as KdTree::SearchRadius). Throws InvalidArgument if radius is not > 0 and
/// finite, min_neighbors < 0, or num_threads < 0.
Indices RadiusOutlierRemoval(const PointCloud& cloud, const KdTree& tree,
                             const RadiusOutlierParams& params);

}  // namespace multicue

#pragma once
/// \file Types and helpers shared by the feature estimators (thesis section 2.5).
///
/// Every per-point estimator returns a FeatureMatrix with one row per input point (row i belongs
/// to cloud point i) and one column per feature dimension. A row is NaN where the feature is
/// undefined: the point or its normal is not finite, or it has no usable neighbour. Per-cluster
/// estimators return one FeatureVector.

#include <cmath>
#include <cstddef>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "multicue/core/point_cloud.hpp"
#include "multicue/core/types.hpp"
#include "multicue/search/kdtree.hpp"

namespace multicue {

/// One row per point, one column per feature dimension, row-major (a row is contiguous).
using FeatureMatrix = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
/// One descriptor of a whole cluster or part.
using FeatureVector = Eigen::VectorXf;

/// Parameters of the radius-neighbourhood histograms (PFH, FPFH, PFHRGB).
struct PairFeatureParams {
    float radius = 0.03f;  ///< neighbourhood radius [m]; larger than the normals' radius
    int num_threads = 0;   ///< 0 = all cores; never changes the result
};

/// Number of points whose row is defined (not NaN) in a feature matrix.
std::size_t CountDefinedRows(const FeatureMatrix& features);

/// Mean of the defined rows (a cluster summary of a per-point feature); zeros if none is defined.
FeatureVector MeanOfDefinedRows(const FeatureMatrix& features);

namespace detail {

/// Throws InvalidArgument naming `what` unless value is > 0 and finite.
void CheckPositive(float value, const char* what);
/// Throws InvalidArgument if num_threads < 0.
void CheckThreads(int num_threads);
/// Throws InvalidArgument if the cloud has no normals (naming the feature) or DataError if their
/// count differs from the point count.
void CheckNormals(const PointCloud& cloud, const char* feature);
/// Throws InvalidArgument if the tree cannot have been built from this cloud.
void CheckTree(const PointCloud& cloud, const KdTree& tree);

/// True when the point and its normal are finite.
inline bool IsUsable(const PointCloud& cloud, std::size_t i) {
    return cloud.points[i].allFinite() && cloud.normals[i].allFinite();
}

/// All indexed points within `radius` of `query` (distance <= radius), in tree order (not sorted
/// by distance), appended to `indices` and `squared_distances` after clearing them. Cheaper than
/// KdTree::SearchRadius, which sorts: nodes wholly inside the sphere are copied without a test.
void RadiusNeighbours(const KdTree& tree, const Eigen::Vector3f& query, float radius,
                      Indices& indices, std::vector<float>& squared_distances);

/// The Darboux-frame pair features of PCL's computePairFeatures (Rusu et al., 2008a): the source
/// of the frame is the point whose normal makes the smaller angle with the line joining the two
/// points. f1 in [-pi, pi], f2, f3 in [-1, 1], f4 = distance [m]. Returns false (features 0) for
/// coincident points or a normal parallel to the joining line.
bool PairFeatures(const Eigen::Vector3f& p1, const Eigen::Vector3f& n1, const Eigen::Vector3f& p2,
                  const Eigen::Vector3f& n2, float& f1, float& f2, float& f3, float& f4);

/// Bin of a value in [lo, lo + span) split into `bins`, clamped to [0, bins - 1], computed as PCL
/// does: floor(bins * (value - lo) / span).
inline int ClampedBin(double scaled, int bins) {
    int b = static_cast<int>(std::floor(scaled));
    if (b < 0) b = 0;
    if (b >= bins) b = bins - 1;
    return b;
}

}  // namespace detail
}  // namespace multicue

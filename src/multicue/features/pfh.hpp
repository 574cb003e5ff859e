#pragma once
/// \file Point Feature Histograms: PFH (125), FPFH (33) and PFHRGB (250), the comparison features
/// of thesis Table 2.2 (Rusu et al., 2008a, 2009b), computed as PCL 1.13 computes them.
///
/// Every pair of points (p1, n1), (p2, n2) gives the Darboux-frame features f1 = atan2(w.n2,
/// u.n2) in [-pi, pi], f2 = v.n2 in [-1, 1] and f3 = u.(p2 - p1)/|p2 - p1| in [-1, 1], with
/// u the source normal, v = (p2 - p1) x u normalised, w = u x v (detail::PairFeatures). A
/// neighbourhood is every point within `radius` of the query point, the query point included.
/// Points whose position or normal is not finite get a NaN row and are never used as neighbours.
///
/// Layouts and normalisation (the sums hold for points with at least one usable pair):
/// - PFH, n x 125: bin f1_bin + 5 f2_bin + 25 f3_bin over 5 equal bins per feature, one count
///   per unordered pair of the neighbourhood, each adding 100 / (m (m - 1) / 2) for a
///   neighbourhood of m points: the row sums to 100 when every pair is usable.
/// - FPFH, n x 33: bins 0-10 f1, 11-21 f2, 22-32 f3 (11 equal bins each). The simplified PFH
///   (SPFH) of a point counts the pairs (point, neighbour), 100 / (m - 1) each; the FPFH of a
///   point is the sum of its neighbours' SPFHs weighted by 1 / squared distance (the point's own
///   SPFH is left out, as in PCL), each 11-bin block rescaled to sum to 100: rows sum to 300.
/// - PFHRGB, n x 250: bins 0-124 as PFH but over ordered pairs without swapping the source, and
///   bins 125-249 the colour ratios r1/r2, g1/g2, b1/b2 (a ratio above 1 becomes -1/ratio, so
///   each lies in [-1, 1]) on the same 5 x 5 x 5 grid; each ordered pair adds
///   100 / (m (m - 1) / 2) to both halves, so each half sums to 200. Needs colours.

#include "multicue/features/feature_common.hpp"

namespace multicue {

inline constexpr int kPfhSize = 125;
inline constexpr int kFpfhSize = 33;
inline constexpr int kPfhRgbSize = 250;

/// PFH of every point. Throws InvalidArgument if the cloud has no normals, radius is not > 0 or
/// num_threads < 0. An empty cloud gives a 0 x 125 matrix.
FeatureMatrix ComputePfh(const PointCloud& cloud, const KdTree& tree,
                         const PairFeatureParams& params);

/// FPFH of every point. Same errors as ComputePfh.
FeatureMatrix ComputeFpfh(const PointCloud& cloud, const KdTree& tree,
                          const PairFeatureParams& params);

/// PFHRGB of every point. Same errors as ComputePfh, and InvalidArgument without colours.
FeatureMatrix ComputePfhRgb(const PointCloud& cloud, const KdTree& tree,
                            const PairFeatureParams& params);

}  // namespace multicue

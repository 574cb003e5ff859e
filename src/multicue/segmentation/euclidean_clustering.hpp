#pragma once
/// \file Euclidean clustering: connected components of the graph that joins points closer than a
/// tolerance. Applied to the points above a support plane, each component is one object hypothesis
/// (thesis section 2.4, "Planar Support").
///
/// Two entry points share one result type:
/// - EuclideanClustering works on any cloud with a prebuilt k-d tree;
/// - EuclideanClusteringOrganized works on organized clouds (RGB-D frames) in image space with a
///   union-find over pixels. It needs no tree and touches only a few neighbouring pixels per point,
///   which makes it much faster on 640x480 frames. It joins two points only if they are close in
///   3D *and* close in the image, so it can split a cluster that the k-d tree version keeps whole:
///   when a row or column of invalid pixels (a thin shadow, a specular hole) cuts through a surface
///   whose two sides are still closer than the tolerance in 3D. A window larger than the immediate
///   neighbours (half_window > 1) bridges gaps up to half_window - 1 pixels wide.

#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include "multicue/core/point_cloud.hpp"
#include "multicue/core/types.hpp"
#include "multicue/search/kdtree.hpp"

namespace multicue {

/// Per-point label of a point that is in no (kept) cluster.
inline constexpr std::int32_t kNoCluster = -1;

struct EuclideanClusteringParams {
    float tolerance = 0.02f;           ///< points closer than this are neighbours [m]; must be > 0
    std::size_t min_cluster_size = 1;  ///< smaller clusters are dropped [points]
    std::size_t max_cluster_size =
        std::numeric_limits<std::size_t>::max();  ///< larger clusters are dropped [points]
    Indices subset = {};          ///< points to cluster (duplicates ignored); empty = all points
    bool compute_labels = false;  ///< also fill ClusteringResult::labels
};

struct OrganizedClusteringParams {
    float tolerance = 0.02f;  ///< neighbouring pixels closer than this in 3D are joined [m]; > 0
    std::size_t min_cluster_size = 1;  ///< smaller clusters are dropped [points]
    std::size_t max_cluster_size =
        std::numeric_limits<std::size_t>::max();  ///< larger clusters are dropped [points]
    Indices subset = {};  ///< pixels to cluster (duplicates ignored); empty = all (or `mask`)
    std::vector<std::uint8_t> mask = {};  ///< per pixel, non-zero = cluster it; empty = no mask.
                                          ///< At most one of `subset` and `mask` may be given
    int connectivity = 8;  ///< 4: pixels within city-block distance half_window are neighbours;
                           ///< 8: pixels within chessboard distance half_window [pixels]
    int half_window = 1;   ///< pixel reach of a neighbourhood; 1 = the 4 or 8 adjacent pixels,
                           ///< h > 1 bridges invalid gaps up to h - 1 pixels wide [pixels]
    bool compute_labels = false;  ///< also fill ClusteringResult::labels
    /// Blocks of rows are linked in parallel (0 = all cores); never changes the result.
    int num_threads = 1;
};

struct ClusteringResult {
    /// Kept clusters, largest first; equal sizes are ordered by their smallest index. The indices
    /// of each cluster are in ascending order.
    std::vector<Indices> clusters;
    /// Only when compute_labels: one entry per cloud point, the position of its cluster in
    /// `clusters`, or kNoCluster (not clustered, not finite, or in a dropped cluster).
    std::vector<std::int32_t> labels;
    std::size_t num_points = 0;     ///< finite points that were clustered
    std::size_t num_too_small = 0;  ///< clusters dropped for having < min_cluster_size points
    std::size_t num_too_large = 0;  ///< clusters dropped for having > max_cluster_size points
};

/// Connected components of the finite points in `params.subset` (all points when empty) under the
/// relation "at most params.tolerance apart". Non-finite points are skipped.
///
/// `tree` must index every point to be clustered; it may index more (for example the whole cloud
/// when clustering a subset), those extra points are ignored and never link two clusters.
///
/// Throws InvalidArgument if tolerance is not > 0 and finite, max_cluster_size is 0,
/// min_cluster_size > max_cluster_size, a subset index is out of range, or the tree lacks a point
/// to be clustered. Throws DataError if the cloud's fields are inconsistent.
/// An empty cloud (or no finite point) gives an empty result.
ClusteringResult EuclideanClustering(const PointCloud& cloud, const KdTree& tree,
                                     const EuclideanClusteringParams& params);

/// The clusters of EuclideanClustering without a k-d tree: the points are binned into a grid of
/// cells of edge tolerance / sqrt(3) (all points of a cell are neighbours), and a union-find over
/// cells joins two cells within reach as soon as one pair of their points is within the tolerance.
/// The result is identical to EuclideanClustering with a tree over the same points; on dense
/// scans it runs several times faster, since it needs no radius query per point.
///
/// A cloud that spans more than about 2 * 10^6 cells along an axis (kilometres at centimetre
/// tolerances) is clustered with a k-d tree instead, with the same result. Same errors as
/// EuclideanClustering.
ClusteringResult EuclideanClusteringGrid(const PointCloud& cloud,
                                         const EuclideanClusteringParams& params);

/// Clusters of an organized cloud in image space: union-find over pixels, joining each finite
/// pixel with the finite pixels of its neighbourhood (see OrganizedClusteringParams) that are
/// closer than params.tolerance in 3D. Same result conventions as EuclideanClustering.
///
/// Every cluster is a subset of a cluster of EuclideanClustering with the same tolerance; the two
/// agree whenever every pair of points closer than the tolerance is also linked through a chain
/// of such pairs between neighbouring pixels (see the file comment for when this fails).
///
/// Throws InvalidArgument if the cloud is not organized (unless it is empty), on the parameter
/// errors of EuclideanClustering, if connectivity is not 4 or 8, half_window < 1, the mask size
/// differs from the cloud size, or both subset and mask are given.
ClusteringResult EuclideanClusteringOrganized(const PointCloud& organized,
                                              const OrganizedClusteringParams& params);

/// Object hypotheses: the clusters of a region of a frame (thesis section 2.4, the points above
/// a table).
struct ObjectClusteringParams {
    float tolerance = 0.015f;         ///< points closer than this are one object [m]; > 0
    std::size_t min_points = 150;     ///< smaller clusters are not objects [points]
    std::size_t max_points = 200000;  ///< larger clusters are not objects [points]; >= min_points
    /// Organized frames: pixel reach of a neighbourhood; 2 bridges one-pixel gaps [pixels]; >= 1.
    int organized_half_window = 2;
    int num_threads = 1;  ///< organized frames: rows linked in parallel (0 = all cores)
    /// Throws InvalidArgument naming the first out-of-range field.
    void Validate() const;
    /// Its parameters once each: configuration key (the field's name), field, meaning. A
    /// visitor reads or records them (io::ConfigSection::operator(); ReadPerceiveParams).
    template <typename V>
    void VisitParams(V& v) {
        v("tolerance", tolerance, "points closer than this are one object [m]");
        v("min_points", min_points, "smaller clusters (and pieces of splits) are not objects");
        v("max_points", max_points, "larger clusters are not objects");
        v("organized_half_window", organized_half_window,
          "organized clustering reach in pixels; 2 bridges one-pixel gaps");
    }
};

/// Clusters of the points `region` (indices into `cloud`): organized frames by pixel adjacency
/// (EuclideanClusteringOrganized, 8-connected within organized_half_window pixels), other clouds
/// on a k-d tree of the region (EuclideanClustering). An empty region has no clusters. Throws
/// InvalidArgument for bad parameters or indices out of range.
ClusteringResult ClusterObjects(const PointCloud& cloud, const Indices& region,
                                const ObjectClusteringParams& params);

}  // namespace multicue

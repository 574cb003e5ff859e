#pragma once
/// \file k-d tree over the finite points of a cloud. Build it once and pass it to every algorithm
/// that needs neighbours; queries are const and safe to run from many threads.
///
/// Layout: the tree keeps its own copy of the points, reordered so that every node covers one
/// contiguous range of them (leaves hold at most leaf_size points). Nodes split their points at the
/// median of the axis along which their tight bounding box is longest and are stored depth first.
/// Algorithms that aggregate over whole subtrees (normal estimation sums per-node moments) read
/// this layout through Nodes(), TreePoints() and TreeToCloud().

#include <cstddef>
#include <memory>
#include <vector>

#include <Eigen/Core>

#include "multicue/core/point_cloud.hpp"
#include "multicue/core/types.hpp"

namespace multicue {

struct KdTreeParams {
    int leaf_size = 16;  ///< maximum points per leaf; 10-20 is a good range for 3D queries
};

class KdTree {
  public:
    /// A node of the tree. Nodes are stored depth first: the first child of the node at index i is
    /// at i + 1, the second at `second_child`.
    struct Node {
        Eigen::Vector3f min;     ///< tight bounds of the node's points [m]
        Eigen::Vector3f max;     ///< tight bounds of the node's points [m]
        Index begin = 0;         ///< the node's points are TreePoints()[begin, end)
        Index end = 0;           ///< one past the node's last point
        Index second_child = 0;  ///< 0 for a leaf
        bool IsLeaf() const { return second_child == 0; }
    };

    /// Largest coordinate magnitude a tree accepts [m]: squared distances between points within
    /// it stay finite in single precision.
    static constexpr float kMaxCoordinate = 1e18f;

    /// Indexes the finite points of `cloud` (NaN points are left out). The tree keeps its own
    /// copy of the coordinates, so the cloud may change or go away afterwards. Throws DataError
    /// when a coordinate exceeds kMaxCoordinate.
    explicit KdTree(const PointCloud& cloud, const KdTreeParams& params = {});
    /// Indexes the given points of `cloud` only (non-finite ones are still left out).
    KdTree(const PointCloud& cloud, const Indices& subset, const KdTreeParams& params = {});
    ~KdTree();
    KdTree(KdTree&&) noexcept;
    KdTree& operator=(KdTree&&) noexcept;
    KdTree(const KdTree&) = delete;
    KdTree& operator=(const KdTree&) = delete;

    /// Number of indexed points.
    std::size_t size() const;
    bool empty() const { return size() == 0; }

    /// The k nearest indexed points to `query`, nearest first, as indices into the original cloud
    /// with squared distances. Returns how many were found (fewer than k if the tree is smaller).
    /// Throws InvalidArgument if k <= 0.
    std::size_t SearchKnn(const Eigen::Vector3f& query, int k, Indices& indices,
                          std::vector<float>& squared_distances) const;

    /// All indexed points within `radius` of `query` (distance <= radius), nearest first; if
    /// max_neighbors > 0 only the nearest max_neighbors are kept. Throws InvalidArgument if
    /// radius <= 0 or not finite.
    std::size_t SearchRadius(const Eigen::Vector3f& query, float radius, Indices& indices,
                             std::vector<float>& squared_distances,
                             std::size_t max_neighbors = 0) const;

    /// Original cloud index of the single nearest point (or false if the tree is empty).
    bool SearchNearest(const Eigen::Vector3f& query, Index& index, float& squared_distance) const;

    /// The nearest indexed point within `max_distance` of `query` (distance <= max_distance), or
    /// false when there is none. The search never leaves that ball, so queries far from every
    /// point (the parts of one scan that another does not overlap) cost little. Throws
    /// InvalidArgument if max_distance is not > 0 and finite.
    bool SearchNearestWithin(const Eigen::Vector3f& query, float max_distance, Index& index,
                             float& squared_distance) const;

    /// The at most k nearest indexed points within `max_distance` of `query` (distance <=
    /// max_distance), nearest first, written to `indices` (original cloud indices) and
    /// `squared_distances`, both with room for k. Returns how many were found. The nearest is the
    /// one SearchNearestWithin returns, ties included. Throws InvalidArgument if k <= 0 or
    /// max_distance is not > 0 and finite.
    std::size_t SearchKnnWithin(const Eigen::Vector3f& query, int k, float max_distance,
                                Index* indices, float* squared_distances) const;

    /// Squared distance between an indexed point and a query, computed exactly as the searches
    /// compute it.
    static float SquaredDistance(const Eigen::Vector3f& point, const Eigen::Vector3f& query) {
        const float x = point.x() - query.x(), y = point.y() - query.y(), z = point.z() - query.z();
        return x * x + (y * y + z * z);
    }

    /// The nodes, root first (empty for an empty tree).
    const std::vector<Node>& Nodes() const;
    /// The indexed points in tree order: each node covers a contiguous range.
    const std::vector<Eigen::Vector3f>& TreePoints() const;
    /// Cloud index of every tree-ordered point.
    const Indices& TreeToCloud() const;

  private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace multicue

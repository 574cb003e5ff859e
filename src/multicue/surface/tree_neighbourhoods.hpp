#pragma once
/// \file Internal to the surface module: the moments of k-d tree neighbourhoods, radius
/// neighbourhoods (RadiusMoments) and k-nearest ones (KnnBatch), found much faster than by one
/// independent search per point.

#include <cstddef>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "multicue/core/types.hpp"
#include "multicue/search/kdtree.hpp"
#include "multicue/surface/pca.hpp"

namespace multicue::detail {

/// Moments of radius neighbourhoods. Holds the mean and scatter matrix of every tree node, and
/// the tree's points once more as separate coordinate arrays (so that the loop over a leaf
/// vectorizes). A query adds up the summaries of the nodes whose boxes lie wholly inside its
/// sphere and visits single points only in the leaves cut by the sphere's surface. The
/// neighbourhood is exactly the set of points within the radius: box bounds and point distances
/// are rounded alike, so they never disagree about a point.
class RadiusMoments {
  public:
    explicit RadiusMoments(const KdTree& tree);

    /// Adds to m the moments about q of all indexed points within sqrt(r2) of q.
    void Accumulate(const Eigen::Vector3f& q, float r2, Moments& m) const;

  private:
    // Mean and scatter matrix (sum of (p - mean)(p - mean)^T, upper triangle) of a node.
    struct Summary {
        Eigen::Vector3f mean;
        float xx, xy, xz, yy, yz, zz;
    };

    const KdTree& tree_;
    std::vector<Summary> summary_;
    std::vector<float> x_, y_, z_;
};

/// The tree cut into groups for KnnBatch: the largest subtrees of at most a few hundred points
/// (or single leaves), in tree order. Group g is node groups[g] with the leaves
/// leaves[first_leaf[g]] to leaves[first_leaf[g + 1] - 1].
struct TreeGroups {
    Indices groups;
    std::vector<std::size_t> first_leaf{0};
    Indices leaves;
};
TreeGroups CutIntoGroups(const KdTree& tree);

/// k-nearest neighbourhoods of all points of a run of consecutive groups, leaf by leaf.
///
/// If the k-th neighbour of a point p is at distance r_p, the ball of radius r_p + |q - p| around
/// q holds at least k points (triangle inequality). So once one query is done, every nearby query
/// knows a radius that must hold its k nearest: it collects the points within it from the leaves
/// near its own and selects the k nearest, which gives its own r for the queries after it. One
/// ordinary k-nearest search per group, for the point nearest its centre, bounds the whole group;
/// the leaves near the group come from one tree traversal and are narrowed down to those near each
/// leaf by a linear pass.
///
/// The result does not depend on where a run starts: the k nearest are unique by (squared
/// distance, tree position), and their moments are summed in tree order, whatever bound found
/// them. `cap2` (inclusive) limits neighbourhoods to a radius; infinity for none.
class KnnBatch {
  public:
    struct Neighbourhood {
        Index position;        ///< tree position of the query point
        FloatMoments moments;  ///< of its neighbours about it
    };

    KnnBatch(const KdTree& tree, std::size_t k, float cap2);

    /// The neighbourhoods of all points of group g.
    const std::vector<Neighbourhood>& Group(const TreeGroups& groups, std::size_t g);

  private:
    void Leaf(Index leaf_id, const Eigen::Vector3f& f, float rf);
    void Tighten(std::size_t j, float kth, const Eigen::Vector3f& p);
    std::size_t NextPending() const;
    void Done(std::size_t i, float kth);
    float Query(Index t, float bound, float guess);
    void FindLeavesNear(const Eigen::Vector3f& lo, const Eigen::Vector3f& hi, float r2);
    std::size_t NarrowLeaves(const Eigen::Vector3f& lo, const Eigen::Vector3f& hi, float r2);
    void Reserve(std::size_t capacity);
    std::size_t Collect(const Eigen::Vector3f& q, float bound);
    std::size_t KeepAll(std::size_t count, float& kth2);
    std::size_t SelectNearest(std::size_t count, float bound, float& kth2);

    const KdTree& tree_;
    const std::vector<KdTree::Node>& nodes_;
    const std::vector<Eigen::Vector3f>& points_;
    std::size_t k_;
    float cap2_;
    std::vector<Neighbourhood> out_;
    Indices idx_;
    std::vector<float> d2_;
    Indices group_leaves_;                    // leaves near the current group
    Indices leaves_;                          // leaves near the current leaf
    Index done_begin_ = 0, prev_begin_ = 0;   // first positions of this leaf and the previous
    std::vector<float> done_kth_, prev_kth_;  // their k-th neighbour distances, inf if unknown
    std::vector<float> bound_, guess_;        // of this leaf's queries
    Indices pending_;                         // this leaf's queries not done yet
    // Candidates of the current query: squared distance and tree position, in tree order.
    std::vector<float> dist_;
    Indices pos_;
    std::vector<std::uint64_t> ties_;
    Indices selected_;
};

}  // namespace multicue::detail

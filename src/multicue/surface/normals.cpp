#include "multicue/surface/normals.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <utility>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/core/parallel.hpp"
#include "multicue/surface/pca.hpp"

namespace multicue {

namespace {

using detail::kNaN;
using detail::Moments;

// max(x, 0), written so that compilers emit no branch: they turn max(x, 0)^2 into one, and it
// mispredicts half the time in the box tests below, which run for every node and leaf visited.
inline float Positive(float x) { return 0.5f * (x + std::abs(x)); }

// Squared distance between the boxes [lo_a, hi_a] and [lo_b, hi_b]; 0 where they overlap.
inline float BoxGapSquared(const Eigen::Vector3f& lo_a, const Eigen::Vector3f& hi_a,
                           const Eigen::Vector3f& lo_b, const Eigen::Vector3f& hi_b) {
    float gap = 0.0f;
    for (int a = 0; a < 3; ++a) {
        // At most one of the two terms is positive.
        const float g = Positive(lo_a[a] - hi_b[a]) + Positive(lo_b[a] - hi_a[a]);
        gap += g * g;
    }
    return gap;
}

// Squared distance from q to the farthest point of the box [lo, hi].
inline float BoxReachSquared(const Eigen::Vector3f& lo, const Eigen::Vector3f& hi,
                             const Eigen::Vector3f& q) {
    float reach = 0.0f;
    for (int a = 0; a < 3; ++a) {
        const float r = std::abs(q[a] - 0.5f * (lo[a] + hi[a])) + 0.5f * (hi[a] - lo[a]);
        reach += r * r;
    }
    return reach;
}

// Mean and scatter matrix (sum of (p - mean)(p - mean)^T, upper triangle) of one tree node.
struct NodeMoments {
    Eigen::Vector3f mean;
    float xx, xy, xz, yy, yz, zz;
};

// The same in double while the tree is summarised bottom-up.
struct NodeMomentsD {
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    double xx = 0, xy = 0, xz = 0, yy = 0, yz = 0, zz = 0;
};

// Moments of every node. Nodes are stored depth first, so children follow their parent and a
// reverse sweep sees both children before the parent; parents merge their children with the
// parallel-axis rule S = Sa + Sb + delta delta^T na nb / n, which never subtracts large numbers.
std::vector<NodeMoments> SummariseNodes(const KdTree& tree) {
    const auto& nodes = tree.Nodes();
    const auto& points = tree.TreePoints();
    std::vector<NodeMomentsD> acc(nodes.size());
    for (std::size_t id = nodes.size(); id-- > 0;) {
        const KdTree::Node& node = nodes[id];
        NodeMomentsD& m = acc[id];
        if (node.IsLeaf()) {
            for (Index i = node.begin; i < node.end; ++i) m.mean += points[i].cast<double>();
            m.mean /= static_cast<double>(node.end - node.begin);
            for (Index i = node.begin; i < node.end; ++i) {
                const Eigen::Vector3d d = points[i].cast<double>() - m.mean;
                m.xx += d.x() * d.x();
                m.xy += d.x() * d.y();
                m.xz += d.x() * d.z();
                m.yy += d.y() * d.y();
                m.yz += d.y() * d.z();
                m.zz += d.z() * d.z();
            }
            continue;
        }
        const KdTree::Node& na = nodes[id + 1];
        const KdTree::Node& nb = nodes[node.second_child];
        const NodeMomentsD& a = acc[id + 1];
        const NodeMomentsD& b = acc[node.second_child];
        const double ca = na.end - na.begin, cb = nb.end - nb.begin, c = ca + cb;
        const Eigen::Vector3d delta = b.mean - a.mean;
        const double w = ca * cb / c;
        m.mean = a.mean + delta * (cb / c);
        m.xx = a.xx + b.xx + w * delta.x() * delta.x();
        m.xy = a.xy + b.xy + w * delta.x() * delta.y();
        m.xz = a.xz + b.xz + w * delta.x() * delta.z();
        m.yy = a.yy + b.yy + w * delta.y() * delta.y();
        m.yz = a.yz + b.yz + w * delta.y() * delta.z();
        m.zz = a.zz + b.zz + w * delta.z() * delta.z();
    }
    std::vector<NodeMoments> out(nodes.size());
    for (std::size_t id = 0; id < nodes.size(); ++id) {
        const NodeMomentsD& m = acc[id];
        out[id] = {m.mean.cast<float>(),     static_cast<float>(m.xx), static_cast<float>(m.xy),
                   static_cast<float>(m.xz), static_cast<float>(m.yy), static_cast<float>(m.yz),
                   static_cast<float>(m.zz)};
    }
    return out;
}

// Moments about q of all indexed points within sqrt(r2) of q. A node whose box lies wholly
// inside the sphere contributes its summary: about q its scatter is S + n d d^T and its sum n d,
// with d = mean - q. Only nodes cut by the sphere's surface are opened.
void AccumulateRadius(const KdTree& tree, const std::vector<NodeMoments>& summary,
                      const Eigen::Vector3f& q, float r2, Moments& m) {
    const auto& nodes = tree.Nodes();
    const auto& points = tree.TreePoints();
    std::array<Index, 64> stack;  // depth-first: at most one pending node per level, plus one
    std::size_t top = 0;
    stack[top++] = 0;
    while (top > 0) {
        const Index id = stack[--top];
        const KdTree::Node& node = nodes[id];
        if (BoxGapSquared(node.min, node.max, q, q) > r2) continue;
        if (BoxReachSquared(node.min, node.max, q) <= r2) {
            const NodeMoments& s = summary[id];
            const double n = node.end - node.begin;
            const Eigen::Vector3f d = s.mean - q;
            const double dx = d.x(), dy = d.y(), dz = d.z();
            m.n += n;
            m.sx += n * dx;
            m.sy += n * dy;
            m.sz += n * dz;
            m.xx += s.xx + n * dx * dx;
            m.xy += s.xy + n * dx * dy;
            m.xz += s.xz + n * dx * dz;
            m.yy += s.yy + n * dy * dy;
            m.yz += s.yz + n * dy * dz;
            m.zz += s.zz + n * dz * dz;
            continue;
        }
        if (node.IsLeaf()) {
            // About half of a cut leaf's points are inside: weights instead of a branch, and
            // float sums over a leaf's few small offsets.
            float n = 0, sx = 0, sy = 0, sz = 0, xx = 0, xy = 0, xz = 0, yy = 0, yz = 0, zz = 0;
            for (Index i = node.begin; i < node.end; ++i) {
                const Eigen::Vector3f d = points[i] - q;
                const float w = detail::WeightIfAtMost(d.squaredNorm(), r2);
                const float wx = w * d.x(), wy = w * d.y(), wz = w * d.z();
                n += w;
                sx += wx;
                sy += wy;
                sz += wz;
                xx += wx * d.x();
                xy += wx * d.y();
                xz += wx * d.z();
                yy += wy * d.y();
                yz += wy * d.z();
                zz += wz * d.z();
            }
            m.n += n;
            m.sx += sx;
            m.sy += sy;
            m.sz += sz;
            m.xx += xx;
            m.xy += xy;
            m.xz += xz;
            m.yy += yy;
            m.yz += yz;
            m.zz += zz;
            continue;
        }
        stack[top++] = node.second_child;
        stack[top++] = id + 1;
    }
}

// Tie-breaking key of a candidate neighbour: the bits of its squared distance (which, for
// non-negative floats, order like the floats) above its tree position. Ordering by both makes the
// set of the k nearest unique even when distances tie (quantized depth gives many ties).
inline std::uint64_t CandidateKey(float d, Index pos) {
    return (std::uint64_t{std::bit_cast<std::uint32_t>(d)} << 32) | pos;
}

// All k-nearest neighbourhoods of a run of consecutive groups of leaves (subtrees of a few
// hundred points), one leaf at a time.
//
// If the k-th neighbour of a point p is at distance r_p, the ball of radius r_p + |q - p| around
// q holds at least k points (triangle inequality). So once one query is done, every nearby query
// knows a radius that must contain its k nearest: it collects the points within it from the
// leaves near its own and selects the k nearest, which gives its own r for the queries after it.
// Only the first query of a run needs an ordinary k-nearest search. The leaves near a group are
// found with one tree traversal per group, and narrowed down to those near each leaf with a
// linear pass.
//
// The result does not depend on where a run starts: the k nearest are unique by (distance,
// position), and they are summed in tree order, whatever bound found them.
class KnnBatch {
  public:
    KnnBatch(const KdTree& tree, std::size_t k, float cap2)
        : tree_(tree), nodes_(tree.Nodes()), points_(tree.TreePoints()), k_(k), cap2_(cap2) {}

    // Calls emit(position, moments) for every point under node `group`, whose leaves (in tree
    // order) are [first_leaf, last_leaf).
    template <typename Emit>
    void Group(Index group, const Index* first_leaf, const Index* last_leaf, Emit&& emit) {
        // One ordinary search, for the point nearest the group's centre, bounds all queries of
        // the group and so tells which leaves they can need.
        const KdTree::Node& g = nodes_[group];
        const Eigen::Vector3f centre = 0.5f * (g.min + g.max);
        Index fi = g.begin;
        for (Index t = g.begin; t < g.end; ++t) {
            if ((points_[t] - centre).squaredNorm() < (points_[fi] - centre).squaredNorm()) fi = t;
        }
        const Eigen::Vector3f f = points_[fi];
        tree_.SearchKnn(f, static_cast<int>(k_), idx_, d2_);
        const float rf = idx_.size() == k_ ? std::sqrt(d2_.back()) : kInf;
        float spread = 0.0f;
        for (Index t = g.begin; t < g.end; ++t) spread = std::max(spread, (points_[t] - f).norm());
        FindLeavesNear(g.min, g.max, std::min(Square(rf + spread) * kMargin, cap2_));
        for (const Index* leaf = first_leaf; leaf != last_leaf; ++leaf) Leaf(*leaf, f, rf, emit);
    }

  private:
    static constexpr float kInf = std::numeric_limits<float>::infinity();
    // A relative margin far above float rounding keeps the bounds safe.
    static constexpr float kMargin = 1.0f + 1e-4f;
    // Share of |q - p| in the first guess r_p + share * |q - p| for the k-th neighbour distance
    // of q: it varies slowly along a surface, so the guess usually holds k points already (on
    // Kinect frames 19 times in 20) and leaves fewer candidates to select from.
    static constexpr float kGuessShare = 0.3f;
    // Largest bucket that SelectNearest ranks by counting rather than partitioning.
    static constexpr std::size_t kMaxRankTies = 24;

    static float Square(float x) { return x * x; }

    // One leaf of the current group; f is a point of the group with k-th neighbour distance
    // rf, which bounds every query of the group within the leaves found for it.
    template <typename Emit>
    void Leaf(Index leaf_id, const Eigen::Vector3f& f, float rf, Emit& emit) {
        const KdTree::Node& leaf = nodes_[leaf_id];
        const std::size_t size = leaf.end - leaf.begin;
        done_begin_ = leaf.begin;
        done_kth_.assign(size, kInf);
        bound_.assign(size, kInf);
        guess_.assign(size, kInf);
        pending_.resize(size);
        for (std::size_t j = 0; j < size; ++j) {
            pending_[j] = leaf.begin + static_cast<Index>(j);
            Tighten(j, rf, f);
            for (std::size_t u = 0; u < prev_kth_.size(); ++u) {
                Tighten(j, prev_kth_[u], points_[prev_begin_ + u]);
            }
        }
        // Queries go greedily in the order of smallest bound, each tightening the others. The
        // first one looks only at the leaves near itself, the others at those near the leaf
        // within the largest bound left.
        bool first = true;
        while (!pending_.empty()) {
            const std::size_t next = NextPending();
            const Index t = pending_[next];
            const std::size_t j = t - leaf.begin;
            const float bound = std::min(Square(bound_[j]) * kMargin, cap2_);
            if (first) {
                NarrowLeaves(points_[t], points_[t], bound);
            } else if (pending_.size() + 1 == size) {
                float reach = 0.0f;
                for (Index other : pending_) reach = std::max(reach, bound_[other - leaf.begin]);
                NarrowLeaves(leaf.min, leaf.max, std::min(Square(reach) * kMargin, cap2_));
            }
            first = false;
            const float kth = Query(t, bound, Square(guess_[j]) * kMargin, emit);
            Done(next, kth);
        }
        prev_begin_ = leaf.begin;
        prev_kth_.swap(done_kth_);
        done_kth_.clear();
    }

    // Tightens the bound of pending query j with a done point p whose k-th neighbour is at kth.
    void Tighten(std::size_t j, float kth, const Eigen::Vector3f& p) {
        const float d = (points_[done_begin_ + j] - p).norm();
        if (kth + d < bound_[j]) {
            bound_[j] = kth + d;
            guess_[j] = kth + kGuessShare * d;
        }
    }

    // Index in pending_ of the query with the smallest bound.
    std::size_t NextPending() const {
        std::size_t best = 0;
        for (std::size_t i = 1; i < pending_.size(); ++i) {
            if (bound_[pending_[i] - done_begin_] < bound_[pending_[best] - done_begin_]) best = i;
        }
        return best;
    }

    // Marks pending_[i] done with k-th neighbour distance kth and tightens the others.
    void Done(std::size_t i, float kth) {
        const Index t = pending_[i];
        pending_[i] = pending_.back();
        pending_.pop_back();
        done_kth_[t - done_begin_] = kth;
        if (kth == kInf) return;
        for (Index other : pending_) Tighten(other - done_begin_, kth, points_[t]);
    }

    // The k nearest of query t among the points within `bound` (squared) of it; if `guess`
    // (squared, smaller) holds k points already, they are the k nearest. Returns the k-th
    // neighbour distance, or infinity if fewer than k were found.
    template <typename Emit>
    float Query(Index t, float bound, float guess, Emit& emit) {
        const Eigen::Vector3f q = points_[t];
        std::size_t count = 0;
        bool guessed = false;
        if (guess < bound) {
            count = Collect(q, guess);
            guessed = count >= k_;
            if (guessed) bound = guess;
        }
        if (!guessed) count = Collect(q, bound);
        float kth2 = kInf;
        const std::size_t n = count > k_ ? SelectNearest(count, bound, kth2) : KeepAll(count, kth2);
        Moments m;
        for (std::size_t j = 0; j < n; ++j) m.Add(points_[selected_[j]] - q);
        emit(t, m);
        return n == k_ ? std::sqrt(kth2) : kInf;
    }

    // Leaves whose boxes come within sqrt(r2) of the box [lo, hi], in tree order, into
    // group_leaves_.
    void FindLeavesNear(const Eigen::Vector3f& lo, const Eigen::Vector3f& hi, float r2) {
        group_leaves_.clear();
        std::array<Index, 64> stack;
        std::size_t top = 0;
        stack[top++] = 0;
        std::size_t capacity = 1;  // one spare slot for the branch-free append in Collect
        while (top > 0) {
            const Index id = stack[--top];
            const KdTree::Node& node = nodes_[id];
            const float gap = BoxGapSquared(node.min, node.max, lo, hi);
            if (gap > r2) continue;
            if (node.IsLeaf()) {
                group_leaves_.push_back(id);
                capacity += node.end - node.begin;
                continue;
            }
            stack[top++] = node.second_child;
            stack[top++] = id + 1;
        }
        if (dist_.size() < capacity) {
            dist_.resize(capacity);
            pos_.resize(capacity);
            ties_.resize(capacity);
            selected_.resize(capacity);
        }
    }

    // The group's leaves within sqrt(r2) of the box [lo, hi], into leaves_ (branch-free append).
    void NarrowLeaves(const Eigen::Vector3f& lo, const Eigen::Vector3f& hi, float r2) {
        leaves_.resize(group_leaves_.size());
        std::size_t n = 0;
        for (Index id : group_leaves_) {
            const KdTree::Node& node = nodes_[id];
            const float gap = BoxGapSquared(node.min, node.max, lo, hi);
            leaves_[n] = id;
            n += gap <= r2 ? 1 : 0;
        }
        leaves_.resize(n);
    }

    // Candidates within `bound` of q, in tree order (branch-free append).
    std::size_t Collect(const Eigen::Vector3f& q, float bound) {
        std::size_t count = 0;
        for (Index id : leaves_) {
            const KdTree::Node& node = nodes_[id];
            const float gap = BoxGapSquared(node.min, node.max, q, q);
            if (gap > bound) continue;
            for (Index i = node.begin; i < node.end; ++i) {
                const float d = (points_[i] - q).squaredNorm();
                dist_[count] = d;
                pos_[count] = i;
                count += d <= bound ? 1 : 0;
            }
        }
        return count;
    }

    std::size_t KeepAll(std::size_t count, float& kth2) {
        std::copy(pos_.begin(), pos_.begin() + static_cast<std::ptrdiff_t>(count),
                  selected_.begin());
        if (count > 0) kth2 = *std::max_element(dist_.begin(), dist_.begin() + count);
        return count;
    }

    // Selects the k nearest of count > k candidates into selected_ (in tree order) and sets
    // kth2 to the k-th squared distance. Selection by buckets of squared distance: one pass
    // counts the candidates per bucket, which tells the bucket holding the k-th; only that bucket
    // (about count / 64 candidates, as squared distances are about uniform on a surface) is
    // sorted. Unlike a quickselect this has almost no data-dependent branches, and those are what
    // a selection among a few dozen elements costs.
    std::size_t SelectNearest(std::size_t count, float bound, float& kth2) {
        constexpr int kBuckets = 64;
        float top = bound;
        if (!std::isfinite(top)) {
            top = 0.0f;
            for (std::size_t j = 0; j < count; ++j) top = std::max(top, dist_[j]);
        }
        const float scale = top > 0.0f ? kBuckets / top : 0.0f;
        std::array<std::uint32_t, kBuckets + 1> histogram{};
        for (std::size_t j = 0; j < count; ++j) {
            ++histogram[static_cast<int>(dist_[j] * scale)];
        }
        // The bucket of the k-th, scanning down from the top (the k-th lies in the upper half
        // when the bound was tight).
        int bucket = kBuckets;
        std::size_t below = count - histogram[kBuckets];
        while (below >= k_) below -= histogram[--bucket];
        std::size_t ties = 0;
        for (std::size_t j = 0; j < count; ++j) {
            ties_[ties] = CandidateKey(dist_[j], pos_[j]);
            ties += static_cast<int>(dist_[j] * scale) == bucket ? 1 : 0;
        }
        // The k-th is the (k - below)-th smallest key of its bucket. Shells of equal distance on
        // the sensor's pixel grid often fill a bucket with a few points; ranking them by counting
        // costs no mispredicted branches, unlike sorting them.
        const std::size_t rank = k_ - below - 1;
        std::uint64_t kth_key = 0;
        if (ties <= kMaxRankTies) {
            for (std::size_t i = 0; i < ties; ++i) {
                std::size_t smaller = 0;
                for (std::size_t j = 0; j < ties; ++j) smaller += ties_[j] < ties_[i] ? 1 : 0;
                kth_key = smaller == rank ? ties_[i] : kth_key;
            }
        } else {
            std::nth_element(ties_.begin(), ties_.begin() + static_cast<std::ptrdiff_t>(rank),
                             ties_.begin() + static_cast<std::ptrdiff_t>(ties));
            kth_key = ties_[rank];
        }
        std::size_t n = 0;
        for (std::size_t j = 0; j < count; ++j) {
            selected_[n] = pos_[j];
            n += CandidateKey(dist_[j], pos_[j]) <= kth_key ? 1 : 0;
        }
        kth2 = std::bit_cast<float>(static_cast<std::uint32_t>(kth_key >> 32));
        return n;
    }

    const KdTree& tree_;
    const std::vector<KdTree::Node>& nodes_;
    const std::vector<Eigen::Vector3f>& points_;
    std::size_t k_;
    float cap2_;
    Indices idx_;
    std::vector<float> d2_;
    Indices group_leaves_;                    // leaves near the current group
    Indices leaves_;                          // leaves near the current leaf
    Index done_begin_ = 0, prev_begin_ = 0;   // first positions of this leaf and the previous
    std::vector<float> done_kth_, prev_kth_;  // their k-th neighbour distances, inf if unknown
    std::vector<float> bound_, guess_;        // of this leaf's queries
    Indices pending_;                         // this leaf's queries not done yet
    std::vector<float> dist_;
    Indices pos_;
    std::vector<std::uint64_t> ties_;
    Indices selected_;
};

// Cuts the tree into groups for KnnBatch: the largest subtrees of at most kGroupPoints points
// (or single leaves), in tree order, with their leaves: group g has leaves
// [group_leaves[g], group_leaves[g + 1]).
void CutIntoGroups(const KdTree& tree, Indices& groups, std::vector<std::size_t>& group_leaves,
                   Indices& leaves) {
    constexpr Index kGroupPoints = 192;
    const auto& nodes = tree.Nodes();
    if (nodes.empty()) return;
    std::vector<Index> stack{0};
    while (!stack.empty()) {
        const Index id = stack.back();
        stack.pop_back();
        const KdTree::Node& node = nodes[id];
        if (!node.IsLeaf() && node.end - node.begin > kGroupPoints) {
            stack.push_back(node.second_child);
            stack.push_back(id + 1);
            continue;
        }
        groups.push_back(id);
        // Its leaves: the nodes of its subtree, which follow it depth first up to the first node
        // beyond its points.
        for (Index sub = id; sub < nodes.size() && nodes[sub].begin < node.end; ++sub) {
            if (nodes[sub].IsLeaf()) leaves.push_back(sub);
        }
        group_leaves.push_back(leaves.size());
    }
}

void CheckParams(const NormalParams& p) {
    if (p.k < 0) throw InvalidArgument(fmt::format("k must be >= 0 (0 = default), got {}", p.k));
    if (p.k > 0 && p.k < 3) {
        throw InvalidArgument(fmt::format(
            "k must be >= 3 (a plane needs 3 points) or 0 for the default, got {}", p.k));
    }
    if (!(p.radius >= 0.0f) || !std::isfinite(p.radius)) {
        throw InvalidArgument(fmt::format("radius must be >= 0 (0 = k-NN), got {}", p.radius));
    }
    ResolveThreadCount(p.num_threads);
}

// The tree must index points of this very cloud: every tree point equals the cloud point its
// index names.
void CheckTree(const PointCloud& cloud, const KdTree& tree) {
    const auto& to_cloud = tree.TreeToCloud();
    const auto& points = tree.TreePoints();
    for (std::size_t t = 0; t < to_cloud.size(); ++t) {
        const Index i = to_cloud[t];
        if (i >= cloud.size() || points[t] != cloud.points[i]) {
            throw InvalidArgument(fmt::format(
                "the k-d tree ({} points) was not built from this cloud ({} points): its point {} "
                "does not match",
                tree.size(), cloud.size(), i));
        }
    }
}

}  // namespace

NormalsResult EstimateNormals(const PointCloud& cloud, const KdTree& tree,
                              const NormalParams& params) {
    CheckParams(params);
    CheckTree(cloud, tree);
    NormalsResult result;
    const std::size_t n = cloud.size();
    result.normals.assign(n, Eigen::Vector3f::Constant(kNaN));
    result.curvature.assign(n, kNaN);
    if (n == 0) return result;

    const Eigen::Vector3f viewpoint = params.viewpoint.value_or(cloud.sensor_origin);
    const bool use_radius = params.radius > 0.0f;
    const int k = params.k > 0 ? params.k : kDefaultNormalK;
    const float r2 = params.radius * params.radius;
    // Moment summaries pay off for uncapped radius searches; a k cap needs the k nearest points.
    const bool use_summary = use_radius && params.k == 0;
    const std::vector<NodeMoments> summary =
        use_summary ? SummariseNodes(tree) : std::vector<NodeMoments>{};

    auto store = [&](const Eigen::Vector3f& q, Index out, const Moments& m) {
        Eigen::Vector3f normal;
        float curvature = 0.0f;
        if (!detail::NormalFromMoments(m, normal, curvature)) return;
        detail::OrientTowards(normal, q, viewpoint);
        result.normals[out] = normal;
        result.curvature[out] = curvature;
    };
    const auto& tree_points = tree.TreePoints();
    const auto& to_cloud = tree.TreeToCloud();
    if (use_summary) {
        // Queries in tree order: consecutive queries are spatial neighbours and touch the same
        // nodes.
        ParallelForChunks(tree.size(), params.num_threads, [&](std::size_t begin, std::size_t end) {
            for (std::size_t t = begin; t < end; ++t) {
                Moments m;
                AccumulateRadius(tree, summary, tree_points[t], r2, m);
                store(tree_points[t], to_cloud[t], m);
            }
        });
    } else {
        // Groups of leaves in runs of consecutive groups (see KnnBatch).
        std::vector<Index> groups, leaves;
        std::vector<std::size_t> group_leaves{0};
        CutIntoGroups(tree, groups, group_leaves, leaves);
        const float cap2 = use_radius ? r2 : std::numeric_limits<float>::infinity();
        ParallelForChunks(
            groups.size(), params.num_threads,
            [&](std::size_t begin, std::size_t end) {
                KnnBatch batch(tree, static_cast<std::size_t>(k), cap2);
                for (std::size_t g = begin; g < end; ++g) {
                    batch.Group(
                        groups[g], leaves.data() + group_leaves[g],
                        leaves.data() + group_leaves[g + 1],
                        [&](Index t, const Moments& m) { store(tree_points[t], to_cloud[t], m); });
                }
            },
            8);
    }

    // Finite points the tree does not index (a tree over a subset) are queried in cloud order.
    if (tree.size() < n) {
        std::vector<std::uint8_t> indexed(n, 0);
        for (Index i : to_cloud) indexed[i] = 1;
        Indices rest;
        for (std::size_t i = 0; i < n; ++i) {
            if (!indexed[i] && cloud.points[i].allFinite()) rest.push_back(static_cast<Index>(i));
        }
        ParallelForChunks(rest.size(), params.num_threads, [&](std::size_t begin, std::size_t end) {
            Indices idx;
            std::vector<float> d2;
            for (std::size_t j = begin; j < end; ++j) {
                const Eigen::Vector3f& q = cloud.points[rest[j]];
                Moments m;
                if (use_summary) {
                    AccumulateRadius(tree, summary, q, r2, m);
                } else {
                    if (use_radius) {
                        tree.SearchRadius(q, params.radius, idx, d2,
                                          static_cast<std::size_t>(params.k));
                    } else {
                        tree.SearchKnn(q, k, idx, d2);
                    }
                    for (Index i : idx) m.Add(cloud.points[i] - q);
                }
                store(q, rest[j], m);
            }
        });
    }

    for (float c : result.curvature) result.undefined += std::isnan(c) ? 1 : 0;
    return result;
}

void SetNormals(PointCloud& cloud, NormalsResult result) {
    if (result.normals.size() != cloud.size() || result.curvature.size() != cloud.size()) {
        throw InvalidArgument(
            fmt::format("normals result has {} normals and {} curvatures for a cloud of {} points",
                        result.normals.size(), result.curvature.size(), cloud.size()));
    }
    cloud.normals = std::move(result.normals);
    cloud.curvature = std::move(result.curvature);
}

}  // namespace multicue

#include "multicue/surface/tree_neighbourhoods.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <limits>

namespace multicue::detail {

namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();
// A relative margin far above float rounding keeps the k-nearest bounds safe.
constexpr float kMargin = 1.0f + 1e-4f;
// Share of |q - p| in the first guess r_p + share * |q - p| for the k-th neighbour distance of
// q: it varies slowly along a surface, so the guess usually holds k points already (on Kinect
// frames 19 times in 20) and leaves fewer candidates to select from.
constexpr float kGuessShare = 0.3f;
// Largest bucket that SelectNearest ranks by counting rather than partitioning.
constexpr std::size_t kMaxRankTies = 24;
// Candidates beyond which the first query of a leaf takes its bound from an ordinary search.
constexpr std::size_t kMaxCandidates = 4096;
// Size of the groups of leaves that share one tree traversal [points].
constexpr Index kGroupPoints = 192;

float Square(float x) { return x * x; }

// max(x, 0), written so that compilers emit no branch: they turn max(x, 0)^2 into one, and it
// mispredicts half the time in the box tests below, which run for every node and leaf visited.
float Positive(float x) { return 0.5f * (x + std::abs(x)); }

// Squared length of (x, y, z), summed in one fixed order (the k-d tree's, and that of Eigen's
// squaredNorm()). Every point distance and box bound here uses it: rounding is monotonic, so a
// box bound never disagrees with the distance of a point in the box, not even in the last bit.
float SquaredLength(float x, float y, float z) { return x * x + (y * y + z * z); }
float SquaredLength(const Eigen::Vector3f& d) { return SquaredLength(d.x(), d.y(), d.z()); }

// Squared distance between the boxes [lo_a, hi_a] and [lo_b, hi_b]; 0 where they overlap.
float BoxGapSquared(const Eigen::Vector3f& lo_a, const Eigen::Vector3f& hi_a,
                    const Eigen::Vector3f& lo_b, const Eigen::Vector3f& hi_b) {
    // At most one of the two terms per axis is positive.
    auto gap = [&](int a) { return Positive(lo_a[a] - hi_b[a]) + Positive(lo_b[a] - hi_a[a]); };
    return SquaredLength(gap(0), gap(1), gap(2));
}

// Squared distance from q to the farthest corner of the box [lo, hi].
float BoxReachSquared(const Eigen::Vector3f& lo, const Eigen::Vector3f& hi,
                      const Eigen::Vector3f& q) {
    auto reach = [&](int a) { return std::max(std::abs(lo[a] - q[a]), std::abs(hi[a] - q[a])); };
    return SquaredLength(reach(0), reach(1), reach(2));
}

// Tie-breaking key of a candidate neighbour: the bits of its squared distance (which, for
// non-negative floats, order like the floats) above its tree position. Ordering by both makes the
// set of the k nearest unique even when distances tie (quantized depth gives many ties).
std::uint64_t CandidateKey(float d, Index pos) {
    return (std::uint64_t{std::bit_cast<std::uint32_t>(d)} << 32) | pos;
}

// Mean and scatter of a node in double while the tree is summarised.
struct SummaryD {
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    double xx = 0, xy = 0, xz = 0, yy = 0, yz = 0, zz = 0;
};

}  // namespace

// --- radius neighbourhoods ----------------------------------------------------------------------

// Node summaries: nodes are stored depth first, so children follow their parent and a reverse
// sweep sees both children before the parent. Parents merge their children with the
// parallel-axis rule S = Sa + Sb + delta delta^T na nb / n, which never subtracts large numbers.
RadiusMoments::RadiusMoments(const KdTree& tree) : tree_(tree) {
    const auto& nodes = tree.Nodes();
    const auto& points = tree.TreePoints();
    std::vector<SummaryD> acc(nodes.size());
    for (std::size_t id = nodes.size(); id-- > 0;) {
        const KdTree::Node& node = nodes[id];
        SummaryD& m = acc[id];
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
        const SummaryD& a = acc[id + 1];
        const SummaryD& b = acc[node.second_child];
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
    summary_.resize(nodes.size());
    for (std::size_t id = 0; id < nodes.size(); ++id) {
        const SummaryD& m = acc[id];
        summary_[id] = {m.mean.cast<float>(),     static_cast<float>(m.xx),
                        static_cast<float>(m.xy), static_cast<float>(m.xz),
                        static_cast<float>(m.yy), static_cast<float>(m.yz),
                        static_cast<float>(m.zz)};
    }
    x_.resize(points.size());
    y_.resize(points.size());
    z_.resize(points.size());
    for (std::size_t i = 0; i < points.size(); ++i) {
        x_[i] = points[i].x();
        y_[i] = points[i].y();
        z_[i] = points[i].z();
    }
}

// A node whose box lies wholly inside the sphere contributes its summary: about q its scatter is
// S + n d d^T and its sum n d, with d = mean - q.
void RadiusMoments::Accumulate(const Eigen::Vector3f& q, float r2, Moments& m) const {
    const auto& nodes = tree_.Nodes();
    if (nodes.empty()) return;
    std::array<Index, 64> stack;  // depth first: at most one pending node per level, plus one
    std::size_t top = 0;
    stack[top++] = 0;
    while (top > 0) {
        const Index id = stack[--top];
        const KdTree::Node& node = nodes[id];
        if (BoxGapSquared(node.min, node.max, q, q) > r2) continue;
        if (BoxReachSquared(node.min, node.max, q) <= r2) {
            const Summary& s = summary_[id];
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
            const float qx = q.x(), qy = q.y(), qz = q.z();
            float n = 0, sx = 0, sy = 0, sz = 0, xx = 0, xy = 0, xz = 0, yy = 0, yz = 0, zz = 0;
            for (Index i = node.begin; i < node.end; ++i) {
                const float dx = x_[i] - qx, dy = y_[i] - qy, dz = z_[i] - qz;
                const float w = WeightIfAtMost(SquaredLength(dx, dy, dz), r2);
                const float wx = w * dx, wy = w * dy, wz = w * dz;
                n += w;
                sx += wx;
                sy += wy;
                sz += wz;
                xx += wx * dx;
                xy += wx * dy;
                xz += wx * dz;
                yy += wy * dy;
                yz += wy * dz;
                zz += wz * dz;
            }
            m += Moments{n, sx, sy, sz, xx, xy, xz, yy, yz, zz};
            continue;
        }
        stack[top++] = node.second_child;
        stack[top++] = id + 1;
    }
}

// --- k-nearest neighbourhoods -------------------------------------------------------------------

TreeGroups CutIntoGroups(const KdTree& tree) {
    TreeGroups out;
    const auto& nodes = tree.Nodes();
    if (nodes.empty()) return out;
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
        out.groups.push_back(id);
        // Its leaves: the nodes of its subtree, which follow it depth first up to the first node
        // beyond its points.
        for (Index sub = id; sub < nodes.size() && nodes[sub].begin < node.end; ++sub) {
            if (nodes[sub].IsLeaf()) out.leaves.push_back(sub);
        }
        out.first_leaf.push_back(out.leaves.size());
    }
    return out;
}

KnnBatch::KnnBatch(const KdTree& tree, std::size_t k, float cap2)
    : tree_(tree), nodes_(tree.Nodes()), points_(tree.TreePoints()), k_(k), cap2_(cap2) {}

const std::vector<KnnBatch::Neighbourhood>& KnnBatch::Group(const TreeGroups& groups,
                                                            std::size_t g) {
    out_.clear();
    // One ordinary search, for the point nearest the group's centre, bounds all queries of the
    // group and so tells which leaves they can need.
    const KdTree::Node& group = nodes_[groups.groups[g]];
    const Eigen::Vector3f centre = 0.5f * (group.min + group.max);
    Index fi = group.begin;
    for (Index t = group.begin; t < group.end; ++t) {
        if (SquaredLength(points_[t] - centre) < SquaredLength(points_[fi] - centre)) fi = t;
    }
    const Eigen::Vector3f f = points_[fi];
    tree_.SearchKnn(f, static_cast<int>(k_), idx_, d2_);
    const float rf = idx_.size() == k_ ? std::sqrt(d2_.back()) : kInf;
    float spread = 0.0f;
    for (Index t = group.begin; t < group.end; ++t) {
        spread = std::max(spread, (points_[t] - f).norm());
    }
    if (rf == 0.0f && spread == 0.0f) {
        // Every point of the group coincides with f, which has k copies: the k nearest of each are
        // copies of itself at distance 0, and their moments are the same whichever copies they
        // are. Searching them leaf by leaf would narrow every leaf of the copies down from every
        // other: quadratic in the copies (a cloud of one point, invalid pixels written as 0 0 0).
        for (Index t = group.begin; t < group.end; ++t) {
            Neighbourhood& out = out_.emplace_back();
            out.position = t;
            for (std::size_t j = 0; j < k_; ++j) out.moments.Add(Eigen::Vector3f::Zero());
        }
        const KdTree::Node& last = nodes_[groups.leaves[groups.first_leaf[g + 1] - 1]];
        prev_begin_ = last.begin;
        prev_kth_.assign(last.end - last.begin, 0.0f);
        return out_;
    }
    FindLeavesNear(group.min, group.max, std::min(Square(rf + spread) * kMargin, cap2_));
    for (std::size_t l = groups.first_leaf[g]; l < groups.first_leaf[g + 1]; ++l) {
        Leaf(groups.leaves[l], f, rf);
    }
    return out_;
}

// One leaf of the current group; f is a point of the group with k-th neighbour distance rf,
// which bounds every query of the group within the leaves found for it.
void KnnBatch::Leaf(Index leaf_id, const Eigen::Vector3f& f, float rf) {
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
    // Queries go greedily in the order of smallest bound, each tightening the others. The first
    // one looks only at the leaves near itself, the others at those near the leaf within the
    // largest bound left.
    bool first = true;
    while (!pending_.empty()) {
        const std::size_t next = NextPending();
        const Index t = pending_[next];
        const std::size_t j = t - leaf.begin;
        float bound = std::min(Square(bound_[j]) * kMargin, cap2_);
        if (first) {
            std::size_t capacity = NarrowLeaves(points_[t], points_[t], bound);
            if (capacity > std::max<std::size_t>(kMaxCandidates, 64 * k_)) {
                // Far from every point done so far (a sparse region, a group that spans a gap):
                // the bound would take in a large part of the cloud, in time and in scratch
                // memory. An ordinary search gives the query its own k-th distance, which bounds
                // the same k nearest.
                tree_.SearchKnn(points_[t], static_cast<int>(k_), idx_, d2_);
                if (idx_.size() == k_) {
                    bound = std::min(bound, d2_.back() * kMargin);
                    capacity = NarrowLeaves(points_[t], points_[t], bound);
                }
            }
            Reserve(capacity);
        } else if (pending_.size() + 1 == size) {
            float reach = 0.0f;
            for (Index other : pending_) reach = std::max(reach, bound_[other - leaf.begin]);
            Reserve(NarrowLeaves(leaf.min, leaf.max, std::min(Square(reach) * kMargin, cap2_)));
        }
        first = false;
        Done(next, Query(t, bound, Square(guess_[j]) * kMargin));
    }
    prev_begin_ = leaf.begin;
    prev_kth_.swap(done_kth_);
    done_kth_.clear();
}

// Tightens the bound of pending query j with a done point p whose k-th neighbour is at kth.
void KnnBatch::Tighten(std::size_t j, float kth, const Eigen::Vector3f& p) {
    const float d = (points_[done_begin_ + j] - p).norm();
    const bool better = kth + d < bound_[j];
    guess_[j] = Select(better, kth + kGuessShare * d, guess_[j]);
    bound_[j] = Select(better, kth + d, bound_[j]);
}

// Index in pending_ of the query with the smallest bound.
std::size_t KnnBatch::NextPending() const {
    std::size_t best = 0;
    for (std::size_t i = 1; i < pending_.size(); ++i) {
        if (bound_[pending_[i] - done_begin_] < bound_[pending_[best] - done_begin_]) best = i;
    }
    return best;
}

// Marks pending_[i] done with k-th neighbour distance kth and tightens the others.
void KnnBatch::Done(std::size_t i, float kth) {
    const Index t = pending_[i];
    pending_[i] = pending_.back();
    pending_.pop_back();
    done_kth_[t - done_begin_] = kth;
    if (kth == kInf) return;
    for (Index other : pending_) Tighten(other - done_begin_, kth, points_[t]);
}

// The k nearest of query t among the points within `bound` (squared) of it; if `guess`
// (squared, smaller) holds k points already, they are the k nearest. Returns the k-th neighbour
// distance, or infinity if fewer than k were found.
float KnnBatch::Query(Index t, float bound, float guess) {
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
    Neighbourhood& out = out_.emplace_back();
    out.position = t;
    for (std::size_t j = 0; j < n; ++j) out.moments.Add(points_[selected_[j]] - q);
    return n == k_ ? std::sqrt(kth2) : kInf;
}

// Leaves whose boxes come within sqrt(r2) of the box [lo, hi], in tree order, into
// group_leaves_.
void KnnBatch::FindLeavesNear(const Eigen::Vector3f& lo, const Eigen::Vector3f& hi, float r2) {
    group_leaves_.clear();
    std::array<Index, 64> stack;
    std::size_t top = 0;
    stack[top++] = 0;
    while (top > 0) {
        const Index id = stack[--top];
        const KdTree::Node& node = nodes_[id];
        if (BoxGapSquared(node.min, node.max, lo, hi) > r2) continue;
        if (node.IsLeaf()) {
            group_leaves_.push_back(id);
            continue;
        }
        stack[top++] = node.second_child;
        stack[top++] = id + 1;
    }
}

// The group's leaves within sqrt(r2) of the box [lo, hi], into leaves_ (branch-free append);
// returns how many candidates they can give (Reserve).
std::size_t KnnBatch::NarrowLeaves(const Eigen::Vector3f& lo, const Eigen::Vector3f& hi, float r2) {
    leaves_.resize(group_leaves_.size());
    std::size_t n = 0;
    std::size_t capacity = 1;  // one spare slot for the branch-free append in Collect
    for (Index id : group_leaves_) {
        const KdTree::Node& node = nodes_[id];
        leaves_[n] = id;
        const bool near = BoxGapSquared(node.min, node.max, lo, hi) <= r2;
        n += near ? 1 : 0;
        capacity += near ? node.end - node.begin : 0;
    }
    leaves_.resize(n);
    return capacity;
}

// Candidate buffers for `capacity` candidates: sized for the leaves a query looks at, not for all
// the group's, which in sparse regions can hold most of the cloud (once per thread).
void KnnBatch::Reserve(std::size_t capacity) {
    if (dist_.size() < capacity) {
        dist_.resize(capacity);
        pos_.resize(capacity);
        ties_.resize(capacity);
        selected_.resize(capacity);
    }
}

// Candidates within `bound` (squared) of q, in tree order (branch-free append). Once k of them
// coincide with q, no later candidate can rank before them (the order is by distance, then tree
// position): the collection stops there, so that a point repeated many times (a sensor writing
// invalid pixels as 0 0 0, a cloud of one point) costs k candidates per query instead of all
// the copies.
std::size_t KnnBatch::Collect(const Eigen::Vector3f& q, float bound) {
    std::size_t count = 0, same = 0;
    for (Index id : leaves_) {
        const KdTree::Node& node = nodes_[id];
        if (BoxGapSquared(node.min, node.max, q, q) > bound) continue;
        for (Index i = node.begin; i < node.end; ++i) {
            const float d = SquaredLength(points_[i] - q);
            dist_[count] = d;
            pos_[count] = i;
            count += d <= bound ? 1 : 0;
            same += d == 0.0f ? 1 : 0;
        }
        if (same >= k_) break;
    }
    return count;
}

std::size_t KnnBatch::KeepAll(std::size_t count, float& kth2) {
    std::copy(pos_.begin(), pos_.begin() + static_cast<std::ptrdiff_t>(count), selected_.begin());
    if (count > 0) kth2 = *std::max_element(dist_.begin(), dist_.begin() + count);
    return count;
}

// Selects the k nearest of count > k candidates into selected_ (in tree order) and sets kth2 to
// the k-th squared distance. Selection by buckets of squared distance: one pass counts the
// candidates per bucket, which tells the bucket holding the k-th; only that bucket (about
// count / 64 candidates, as squared distances are about uniform on a surface) is ranked. Unlike
// a quickselect this has almost no data-dependent branches, and those are what a selection
// among a few dozen elements costs.
std::size_t KnnBatch::SelectNearest(std::size_t count, float bound, float& kth2) {
    constexpr int kBuckets = 64;
    float top = bound;
    if (!std::isfinite(top)) {
        top = 0.0f;
        for (std::size_t j = 0; j < count; ++j) top = std::max(top, dist_[j]);
    }
    // Squared distances of points beyond about 1.8e19 m overflow to infinity: such candidates go
    // to the top bucket (d * scale is NaN or at least kBuckets there), never past the histogram.
    const float scale = top > 0.0f && std::isfinite(top) ? kBuckets / top : 0.0f;
    const auto bucket_of = [scale](float d) {
        const float b = d * scale;
        return b < static_cast<float>(kBuckets) ? static_cast<int>(b) : kBuckets;
    };
    std::array<std::uint32_t, kBuckets + 1> histogram{};
    for (std::size_t j = 0; j < count; ++j) ++histogram[bucket_of(dist_[j])];
    // The bucket of the k-th, scanning down from the top (the k-th lies in the upper half when
    // the bound was tight).
    int bucket = kBuckets;
    std::size_t below = count - histogram[kBuckets];
    while (below >= k_) below -= histogram[--bucket];
    std::size_t ties = 0;
    for (std::size_t j = 0; j < count; ++j) {
        ties_[ties] = CandidateKey(dist_[j], pos_[j]);
        ties += bucket_of(dist_[j]) == bucket ? 1 : 0;
    }
    // The k-th is the (k - below)-th smallest key of its bucket. Shells of equal distance on the
    // sensor's pixel grid often fill a bucket with a few points; ranking them by counting costs
    // no mispredicted branches, unlike sorting them.
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

}  // namespace multicue::detail

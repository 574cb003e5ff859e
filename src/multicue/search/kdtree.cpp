#include "multicue/search/kdtree.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <utility>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"

namespace multicue {

namespace {

using Node = KdTree::Node;

// A point and its cloud index, kept together while the build partitions them.
struct Item {
    Eigen::Vector3f p;
    Index cloud;
};

// max(x, 0) without a branch: compilers turn max(x, 0)^2 into one, which mispredicts often in
// the box tests of a search.
inline float Positive(float x) { return 0.5f * (x + std::abs(x)); }

// Squared length summed in one fixed order, for point distances and box bounds alike: rounding
// is monotonic, so a box bound never exceeds the distance of a point in the box.
inline float SquaredLength(float x, float y, float z) { return x * x + (y * y + z * z); }
// Point distances as KdTree::SquaredDistance computes them for callers.
inline float SquaredDistance(const Eigen::Vector3f& a, const Eigen::Vector3f& b) {
    return KdTree::SquaredDistance(a, b);
}

// Squared distance from q to the nearest point of the node's box (0 inside).
inline float BoxDistanceSquared(const Node& node, const Eigen::Vector3f& q) {
    auto gap = [&](int a) { return Positive(node.min[a] - q[a]) + Positive(q[a] - node.max[a]); };
    return SquaredLength(gap(0), gap(1), gap(2));
}

// The k best candidates seen so far, sorted by squared distance. A candidate enters if it is
// strictly nearer than Bound(): the k-th best once full, else the initial bound.
class KnnSet {
  public:
    KnnSet(std::size_t k, float initial_bound, Index* positions, float* distances)
        : k_(k), bound_(initial_bound), pos_(positions), dist_(distances) {}

    float Bound() const { return bound_; }
    std::size_t size() const { return count_; }

    void Add(float d, Index position) {
        std::size_t i = count_ < k_ ? count_++ : k_ - 1;
        // Insertion into the sorted prefix: k is small (tens), so this beats a heap.
        while (i > 0 && dist_[i - 1] > d) {
            dist_[i] = dist_[i - 1];
            pos_[i] = pos_[i - 1];
            --i;
        }
        dist_[i] = d;
        pos_[i] = position;
        if (count_ == k_) bound_ = dist_[k_ - 1];
    }

  private:
    std::size_t k_;
    std::size_t count_ = 0;
    float bound_;
    Index* pos_;
    float* dist_;
};

// Rearranges [first, last) like std::nth_element by coordinate `axis`: *nth is the element that
// would be there if sorted, none before it is larger and none after it smaller. A quickselect
// with a branch-free partition: on real scans which side an element goes to is a coin flip, and
// std::nth_element's branches mispredict on about every other element.
void SelectMedian(Item* first, Item* nth, Item* last, int axis) {
    while (last - first > 16) {
        // Pivot: median of three.
        const float a = first->p[axis], b = first[(last - first) / 2].p[axis], c = last[-1].p[axis];
        const float pivot = std::max(std::min(a, b), std::min(std::max(a, b), c));
        // Lomuto partition without branches: [first, store) < pivot <= [store, it).
        Item* store = first;
        for (Item* it = first; it != last; ++it) {
            const Item x = *it;
            const bool less = x.p[axis] < pivot;
            *it = *store;
            *store = x;
            store += less ? 1 : 0;
        }
        if (store == first) {
            // The pivot is the minimum: split off the elements equal to it instead.
            for (Item* it = first; it != last; ++it) {
                const Item x = *it;
                const bool equal = !(pivot < x.p[axis]);
                *it = *store;
                *store = x;
                store += equal ? 1 : 0;
            }
            if (nth < store) return;  // all of [first, store) equal the pivot
            first = store;
            continue;
        }
        if (nth < store) {
            last = store;
        } else {
            first = store;
        }
    }
    std::sort(first, last, [axis](const Item& x, const Item& y) { return x.p[axis] < y.p[axis]; });
}

// The nodes a build makes for n points: a node splits at the median until it holds at most
// leaf_size points. Counted level by level (the nodes of one level have at most two sizes), so
// that the node array is allocated once at its size.
std::size_t NodeCount(std::size_t n, std::size_t leaf_size) {
    std::map<std::size_t, std::size_t> level{{n, 1}};  // node size -> nodes of that size
    std::size_t total = 0;
    while (!level.empty()) {
        std::map<std::size_t, std::size_t> next;
        for (const auto& [size, count] : level) {
            total += count;
            if (size > leaf_size) {
                next[size / 2] += count;
                next[size - size / 2] += count;
            }
        }
        level.swap(next);
    }
    return total;
}

// Median splits halve the points, so a tree of at most 2^31 points is at most 32 levels deep;
// a traversal stack holds at most one entry per level (plus one).
constexpr std::size_t kMaxDepth = 64;

}  // namespace

struct KdTree::Impl {
    std::vector<Node> nodes;
    std::vector<Eigen::Vector3f> points;  // tree order
    Indices cloud_index;                  // points[i] is cloud point cloud_index[i]

    void Build(std::vector<Item>& items, int leaf_size) {
        if (leaf_size <= 0) {
            throw InvalidArgument(fmt::format("k-d tree leaf_size must be > 0, got {}", leaf_size));
        }
        if (items.size() > std::numeric_limits<Index>::max() / 2) {
            throw InvalidArgument(
                fmt::format("a k-d tree holds at most 2^31 points, got {}", items.size()));
        }
        if (!items.empty()) {
            nodes.reserve(NodeCount(items.size(), static_cast<std::size_t>(leaf_size)));
            BuildNode(items, 0, items.size(), static_cast<std::size_t>(leaf_size));
            const float reach =
                std::max(nodes[0].min.cwiseAbs().maxCoeff(), nodes[0].max.cwiseAbs().maxCoeff());
            if (reach > KdTree::kMaxCoordinate) {
                throw DataError(fmt::format(
                    "a point lies {:.3g} m from the origin: a k-d tree searches points within "
                    "{:.0e} m of it, where squared distances stay finite (wrong units?)",
                    reach, KdTree::kMaxCoordinate));
            }
        }
        points.resize(items.size());
        cloud_index.resize(items.size());
        for (std::size_t i = 0; i < items.size(); ++i) {
            points[i] = items[i].p;
            cloud_index[i] = items[i].cloud;
        }
    }

    Index BuildNode(std::vector<Item>& items, std::size_t begin, std::size_t end,
                    std::size_t leaf_size) {
        const auto id = static_cast<Index>(nodes.size());
        nodes.emplace_back();
        Eigen::Vector3f lo = items[begin].p, hi = items[begin].p;
        for (std::size_t i = begin + 1; i < end; ++i) {
            lo = lo.cwiseMin(items[i].p);
            hi = hi.cwiseMax(items[i].p);
        }
        Index second = 0;
        if (end - begin > leaf_size) {
            int axis = 0;
            (hi - lo).maxCoeff(&axis);
            const std::size_t mid = begin + (end - begin) / 2;
            SelectMedian(items.data() + begin, items.data() + mid, items.data() + end, axis);
            BuildNode(items, begin, mid, leaf_size);
            second = BuildNode(items, mid, end, leaf_size);
        }
        Node& node = nodes[id];
        node.min = lo;
        node.max = hi;
        node.begin = static_cast<Index>(begin);
        node.end = static_cast<Index>(end);
        node.second_child = second;
        return id;
    }

    // Best-first descent: the nearer child first, the other one only if its box can still hold
    // a point nearer than the current bound.
    void Knn(const Eigen::Vector3f& query, KnnSet& set) const {
        if (nodes.empty()) return;
        // Local copies of the query and the bound: the set's writes could otherwise alias them,
        // and the compiler would reload both for every point.
        const Eigen::Vector3f q = query;
        float bound = set.Bound();
        // Left uninitialised: std::pair would zero all of it on every search.
        struct Pending {
            Index node;
            float distance;
        };
        std::array<Pending, kMaxDepth> stack;
        std::size_t top = 0;
        Index n = 0;
        float d = BoxDistanceSquared(nodes[0], q);
        for (;;) {
            if (d < bound) {
                const Node& node = nodes[n];
                if (!node.IsLeaf()) {
                    Index near = n + 1, far = node.second_child;
                    float d_near = BoxDistanceSquared(nodes[near], q);
                    float d_far = BoxDistanceSquared(nodes[far], q);
                    if (d_far < d_near) {
                        std::swap(near, far);
                        std::swap(d_near, d_far);
                    }
                    if (d_far < bound) stack[top++] = {far, d_far};
                    n = near;
                    d = d_near;
                    continue;
                }
                for (Index i = node.begin; i < node.end; ++i) {
                    const float di = SquaredDistance(points[i], q);
                    if (di < bound) {
                        set.Add(di, i);
                        bound = set.Bound();
                    }
                }
            }
            if (top == 0) return;
            --top;
            n = stack[top].node;
            d = stack[top].distance;
        }
    }

    // Every point with squared distance <= r2, unordered, as (position, squared distance).
    template <typename Out>
    void Radius(const Eigen::Vector3f& q, float r2, Out&& out) const {
        if (nodes.empty()) return;
        std::array<Index, kMaxDepth> stack;
        std::size_t top = 0;
        stack[top++] = 0;
        while (top > 0) {
            const Node& node = nodes[stack[--top]];
            if (BoxDistanceSquared(node, q) > r2) continue;
            if (!node.IsLeaf()) {
                stack[top++] = node.second_child;
                stack[top++] = static_cast<Index>(&node - nodes.data()) + 1;
                continue;
            }
            for (Index i = node.begin; i < node.end; ++i) {
                const float di = SquaredDistance(points[i], q);
                if (di <= r2) out(i, di);
            }
        }
    }
};

namespace {

void CheckRadius(float radius) {
    if (!(radius > 0.0f) || !std::isfinite(radius)) {
        throw InvalidArgument(fmt::format("radius must be > 0, got {}", radius));
    }
}

}  // namespace

KdTree::KdTree(const PointCloud& cloud, const KdTreeParams& params)
    : impl_(std::make_unique<Impl>()) {
    std::vector<Item> items;
    items.reserve(cloud.size());
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        if (cloud.points[i].allFinite()) items.push_back({cloud.points[i], static_cast<Index>(i)});
    }
    impl_->Build(items, params.leaf_size);
}

KdTree::KdTree(const PointCloud& cloud, const Indices& subset, const KdTreeParams& params)
    : impl_(std::make_unique<Impl>()) {
    std::vector<Item> items;
    items.reserve(subset.size());
    for (Index i : subset) {
        if (i >= cloud.size()) {
            throw InvalidArgument(
                fmt::format("index {} is out of range for a cloud of {} points", i, cloud.size()));
        }
        if (cloud.points[i].allFinite()) items.push_back({cloud.points[i], i});
    }
    impl_->Build(items, params.leaf_size);
}

KdTree::~KdTree() = default;
KdTree::KdTree(KdTree&&) noexcept = default;
KdTree& KdTree::operator=(KdTree&&) noexcept = default;

std::size_t KdTree::size() const { return impl_->points.size(); }

const std::vector<KdTree::Node>& KdTree::Nodes() const { return impl_->nodes; }
const std::vector<Eigen::Vector3f>& KdTree::TreePoints() const { return impl_->points; }
const Indices& KdTree::TreeToCloud() const { return impl_->cloud_index; }

std::size_t KdTree::SearchKnn(const Eigen::Vector3f& query, int k, Indices& indices,
                              std::vector<float>& squared_distances) const {
    if (k <= 0) throw InvalidArgument(fmt::format("k must be > 0, got {}", k));
    const std::size_t want = std::min<std::size_t>(static_cast<std::size_t>(k), size());
    indices.resize(want);
    squared_distances.resize(want);
    if (want == 0) return 0;
    KnnSet set(want, std::numeric_limits<float>::infinity(), indices.data(),
               squared_distances.data());
    impl_->Knn(query, set);
    const std::size_t found = set.size();
    indices.resize(found);
    squared_distances.resize(found);
    for (auto& i : indices) i = impl_->cloud_index[i];
    return found;
}

std::size_t KdTree::SearchRadius(const Eigen::Vector3f& query, float radius, Indices& indices,
                                 std::vector<float>& squared_distances,
                                 std::size_t max_neighbors) const {
    CheckRadius(radius);
    indices.clear();
    squared_distances.clear();
    if (empty()) return 0;
    const float r2 = radius * radius;
    if (max_neighbors > 0) {
        // The nearest max_neighbors within the radius: a k-nearest search whose bound starts at
        // the radius (inclusive, hence the next float up).
        const std::size_t want = std::min(max_neighbors, size());
        indices.resize(want);
        squared_distances.resize(want);
        KnnSet set(want, std::nextafter(r2, std::numeric_limits<float>::infinity()), indices.data(),
                   squared_distances.data());
        impl_->Knn(query, set);
        indices.resize(set.size());
        squared_distances.resize(set.size());
        for (auto& i : indices) i = impl_->cloud_index[i];
        return indices.size();
    }
    thread_local std::vector<std::pair<float, Index>> matches;
    matches.clear();
    impl_->Radius(query, r2, [&](Index i, float d) { matches.emplace_back(d, i); });
    std::sort(matches.begin(), matches.end());
    indices.resize(matches.size());
    squared_distances.resize(matches.size());
    for (std::size_t j = 0; j < matches.size(); ++j) {
        indices[j] = impl_->cloud_index[matches[j].second];
        squared_distances[j] = matches[j].first;
    }
    return matches.size();
}

bool KdTree::SearchNearest(const Eigen::Vector3f& query, Index& index,
                           float& squared_distance) const {
    if (empty()) return false;
    Index i = 0;
    float d = 0.0f;
    KnnSet set(1, std::numeric_limits<float>::infinity(), &i, &d);
    impl_->Knn(query, set);
    index = impl_->cloud_index[i];
    squared_distance = d;
    return true;
}

bool KdTree::SearchNearestWithin(const Eigen::Vector3f& query, float max_distance, Index& index,
                                 float& squared_distance) const {
    return SearchKnnWithin(query, 1, max_distance, &index, &squared_distance) == 1;
}

std::size_t KdTree::SearchKnnWithin(const Eigen::Vector3f& query, int k, float max_distance,
                                    Index* indices, float* squared_distances) const {
    if (k <= 0) throw InvalidArgument(fmt::format("k must be > 0, got {}", k));
    if (!(max_distance > 0.0f) || !std::isfinite(max_distance)) {
        throw InvalidArgument(
            fmt::format("nearest search max_distance must be > 0, got {}", max_distance));
    }
    if (empty()) return 0;
    // The set keeps points strictly below its bound: one step above r^2 keeps distance == r.
    KnnSet set(static_cast<std::size_t>(k),
               std::nextafter(max_distance * max_distance, std::numeric_limits<float>::infinity()),
               indices, squared_distances);
    impl_->Knn(query, set);
    for (std::size_t i = 0; i < set.size(); ++i) indices[i] = impl_->cloud_index[indices[i]];
    return set.size();
}

}  // namespace multicue

#include "multicue/search/kdtree.hpp"

#include <cmath>
#include <utility>

#include <fmt/format.h>
#include <nanoflann.hpp>

#include "multicue/core/exceptions.hpp"

namespace multicue {

struct KdTree::Impl {
    // nanoflann adaptor over our own contiguous copy of the finite points.
    struct Adaptor {
        const std::vector<Eigen::Vector3f>* pts;
        std::size_t kdtree_get_point_count() const { return pts->size(); }
        float kdtree_get_pt(std::size_t i, std::size_t d) const { return (*pts)[i][d]; }
        template <class Box>
        bool kdtree_get_bbox(Box&) const {
            return false;
        }
    };
    using Tree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<float, Adaptor>,
                                                     Adaptor, 3, Index>;

    std::vector<Eigen::Vector3f> points;  // finite points, tree order is by position here
    Indices original;                      // points[i] is cloud point original[i]
    Adaptor adaptor{&points};
    std::unique_ptr<Tree> tree;

    void Build(int leaf_size) {
        if (leaf_size <= 0) {
            throw InvalidArgument(fmt::format("k-d tree leaf_size must be > 0, got {}", leaf_size));
        }
        tree = std::make_unique<Tree>(3, adaptor,
                                      nanoflann::KDTreeSingleIndexAdaptorParams(
                                          static_cast<std::size_t>(leaf_size)));
    }
};

KdTree::KdTree(const PointCloud& cloud, const KdTreeParams& params)
    : impl_(std::make_unique<Impl>()) {
    impl_->points.reserve(cloud.size());
    impl_->original.reserve(cloud.size());
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        if (!cloud.points[i].allFinite()) continue;
        impl_->points.push_back(cloud.points[i]);
        impl_->original.push_back(static_cast<Index>(i));
    }
    impl_->Build(params.leaf_size);
}

KdTree::KdTree(const PointCloud& cloud, const Indices& subset, const KdTreeParams& params)
    : impl_(std::make_unique<Impl>()) {
    impl_->points.reserve(subset.size());
    impl_->original.reserve(subset.size());
    for (Index i : subset) {
        if (i >= cloud.size()) {
            throw InvalidArgument(
                fmt::format("index {} is out of range for a cloud of {} points", i, cloud.size()));
        }
        if (!cloud.points[i].allFinite()) continue;
        impl_->points.push_back(cloud.points[i]);
        impl_->original.push_back(i);
    }
    impl_->Build(params.leaf_size);
}

KdTree::~KdTree() = default;
KdTree::KdTree(KdTree&&) noexcept = default;
KdTree& KdTree::operator=(KdTree&&) noexcept = default;

std::size_t KdTree::size() const { return impl_->points.size(); }

std::size_t KdTree::SearchKnn(const Eigen::Vector3f& query, int k, Indices& indices,
                              std::vector<float>& squared_distances) const {
    if (k <= 0) throw InvalidArgument(fmt::format("k must be > 0, got {}", k));
    const std::size_t want = std::min<std::size_t>(static_cast<std::size_t>(k), size());
    indices.resize(want);
    squared_distances.resize(want);
    if (want == 0) return 0;
    nanoflann::KNNResultSet<float, Index> result(want);
    result.init(indices.data(), squared_distances.data());
    impl_->tree->findNeighbors(result, query.data(), nanoflann::SearchParams());
    const std::size_t found = result.size();
    indices.resize(found);
    squared_distances.resize(found);
    for (auto& i : indices) i = impl_->original[i];
    return found;
}

std::size_t KdTree::SearchRadius(const Eigen::Vector3f& query, float radius, Indices& indices,
                                 std::vector<float>& squared_distances,
                                 std::size_t max_neighbors) const {
    if (!(radius > 0.0f) || !std::isfinite(radius)) {
        throw InvalidArgument(fmt::format("radius must be > 0, got {}", radius));
    }
    indices.clear();
    squared_distances.clear();
    if (empty()) return 0;
    thread_local std::vector<std::pair<Index, float>> matches;
    matches.clear();
    impl_->tree->radiusSearch(query.data(), radius * radius, matches,
                              nanoflann::SearchParams(32, 0.0f, true));
    std::size_t n = matches.size();
    if (max_neighbors > 0 && n > max_neighbors) n = max_neighbors;
    indices.resize(n);
    squared_distances.resize(n);
    for (std::size_t j = 0; j < n; ++j) {
        indices[j] = impl_->original[matches[j].first];
        squared_distances[j] = matches[j].second;
    }
    return n;
}

bool KdTree::SearchNearest(const Eigen::Vector3f& query, Index& index,
                           float& squared_distance) const {
    if (empty()) return false;
    Index i = 0;
    float d = 0.0f;
    nanoflann::KNNResultSet<float, Index> result(1);
    result.init(&i, &d);
    impl_->tree->findNeighbors(result, query.data(), nanoflann::SearchParams());
    index = impl_->original[i];
    squared_distance = d;
    return true;
}

}  // namespace multicue

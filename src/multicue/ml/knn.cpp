#include "multicue/ml/knn.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "multicue/core/exceptions.hpp"
#include "multicue/core/parallel.hpp"
#include "multicue/ml/serialization.hpp"

namespace multicue::ml {

namespace {

// Inserts (row, d) into the ascending list `best` of at most k entries; ties by row index.
inline void Offer(std::vector<Neighbour>& best, std::size_t k, std::uint32_t row, float d) {
    auto less = [](const Neighbour& a, const Neighbour& b) {
        return a.distance < b.distance || (a.distance == b.distance && a.row < b.row);
    };
    const Neighbour n{row, d};
    if (best.size() == k) {
        if (!less(n, best.back())) return;
        best.pop_back();
    }
    best.insert(std::upper_bound(best.begin(), best.end(), n, less), n);
}

}  // namespace

std::string ToString(KnnMetric m) {
    switch (m) {
        case KnnMetric::kL1:
            return "l1";
        case KnnMetric::kL2:
            return "l2";
        case KnnMetric::kHellinger:
            return "hellinger";
        case KnnMetric::kChi2:
            return "chi2";
        case KnnMetric::kJm:
            return "jm";
    }
    return "?";
}

KnnMetric ParseKnnMetric(const std::string& name) {
    for (auto m : {KnnMetric::kL1, KnnMetric::kL2, KnnMetric::kHellinger, KnnMetric::kChi2,
                   KnnMetric::kJm}) {
        if (ToString(m) == name) return m;
    }
    throw InvalidArgument("unknown k-NN metric '" + name + "' (l1, l2, hellinger, chi2, jm)");
}

KnnParams KnnParams::FromSpec(SpecArgs& args) {
    KnnParams p;
    const long k = args.GetInt("k", 5);
    if (k < 1) throw InvalidArgument("knn spec: k must be >= 1, got " + std::to_string(k));
    p.k = static_cast<std::size_t>(k);
    p.metric = ParseKnnMetric(args.GetString("metric", "l2"));
    p.distance_weighted = args.GetInt("weighted", 0) != 0;
    const std::string index = args.GetString("index", "auto");
    if (index == "auto") {
        p.index = KnnIndex::kAuto;
    } else if (index == "kdtree") {
        p.index = KnnIndex::kKdTree;
    } else if (index == "brute") {
        p.index = KnnIndex::kBrute;
    } else {
        throw InvalidArgument("knn spec: index must be auto, kdtree or brute, got '" + index + "'");
    }
    const long leaf = args.GetInt("leaf", 16);
    if (leaf < 1) throw InvalidArgument("knn spec: leaf must be >= 1, got " + std::to_string(leaf));
    p.leaf_size = static_cast<std::size_t>(leaf);
    p.num_threads = static_cast<int>(args.GetInt("threads", 1));
    if (p.num_threads < 0) throw InvalidArgument("knn spec: threads must be >= 0");
    if (p.index == KnnIndex::kKdTree && p.metric != KnnMetric::kL2 &&
        p.metric != KnnMetric::kHellinger) {
        throw InvalidArgument("knn spec: index=kdtree needs metric l2 or hellinger");
    }
    return p;
}

// --- k-d tree ----------------------------------------------------------------------------------

KdTreeNd::KdTreeNd(const float* data, std::size_t rows, std::size_t dims, std::size_t leaf_size)
    : dims_(dims), leaf_size_(std::max<std::size_t>(1, leaf_size)) {
    if (rows > std::numeric_limits<std::uint32_t>::max()) {
        throw InvalidArgument("k-d tree supports at most 2^32 - 1 rows");
    }
    order_.resize(rows);
    std::iota(order_.begin(), order_.end(), 0u);
    points_.assign(data, data + rows * dims);
    if (rows > 0) Build(0, static_cast<std::uint32_t>(rows));
    // Store the points in tree order so that a leaf scan reads contiguous memory.
    std::vector<float> ordered(rows * dims);
    for (std::size_t i = 0; i < rows; ++i) {
        std::copy_n(data + order_[i] * dims, dims, ordered.data() + i * dims);
    }
    points_ = std::move(ordered);
}

int KdTreeNd::Build(std::uint32_t begin, std::uint32_t end) {
    const int id = static_cast<int>(nodes_.size());
    nodes_.push_back({begin, end});
    if (end - begin <= leaf_size_) return id;
    // Widest dimension of the node's points.
    std::size_t best_dim = 0;
    float best_spread = -1.0f;
    for (std::size_t d = 0; d < dims_; ++d) {
        float lo = INFINITY, hi = -INFINITY;
        for (std::uint32_t i = begin; i < end; ++i) {
            const float v = points_[order_[i] * dims_ + d];
            lo = std::min(lo, v);
            hi = std::max(hi, v);
        }
        if (hi - lo > best_spread) {
            best_spread = hi - lo;
            best_dim = d;
        }
    }
    if (best_spread <= 0.0f) return id;  // all points equal: keep one leaf
    const std::uint32_t mid = begin + (end - begin) / 2;
    std::nth_element(order_.begin() + begin, order_.begin() + mid, order_.begin() + end,
                     [&](std::uint32_t a, std::uint32_t b) {
                         return points_[a * dims_ + best_dim] < points_[b * dims_ + best_dim];
                     });
    const float split = points_[order_[mid] * dims_ + best_dim];
    const int left = Build(begin, mid);
    const int right = Build(mid, end);
    nodes_[id].left = left;
    nodes_[id].right = right;
    nodes_[id].dim = static_cast<std::uint32_t>(best_dim);
    nodes_[id].split = split;
    return id;
}

void KdTreeNd::SearchNode(int node_id, const float* q, float mindist, float* offsets,
                          std::vector<Neighbour>& best, std::size_t k) const {
    const Node& node = nodes_[static_cast<std::size_t>(node_id)];
    if (node.left < 0) {
        for (std::uint32_t i = node.begin; i < node.end; ++i) {
            const float* p = points_.data() + static_cast<std::size_t>(i) * dims_;
            float s = 0.0f;
            for (std::size_t d = 0; d < dims_; ++d) {
                const float diff = p[d] - q[d];
                s += diff * diff;
            }
            if (best.size() < k || s <= best.back().distance) Offer(best, k, order_[i], s);
        }
        return;
    }
    const float diff = q[node.dim] - node.split;
    const int first = diff < 0.0f ? node.left : node.right;
    const int second = diff < 0.0f ? node.right : node.left;
    SearchNode(first, q, mindist, offsets, best, k);
    const float cut = diff * diff;
    const float new_min = mindist - offsets[node.dim] + cut;
    if (best.size() < k || new_min <= best.back().distance) {
        const float old = offsets[node.dim];
        offsets[node.dim] = cut;
        SearchNode(second, q, new_min, offsets, best, k);
        offsets[node.dim] = old;
    }
}

void KdTreeNd::Search(const float* query, std::size_t k, std::vector<Neighbour>& out) const {
    out.clear();
    if (order_.empty() || k == 0) return;
    std::vector<float> offsets(dims_, 0.0f);
    SearchNode(0, query, 0.0f, offsets.data(), out, std::min(k, order_.size()));
}

// --- classifier --------------------------------------------------------------------------------

KnnClassifier::KnnClassifier(KnnParams params) : params_(params) {
    if (params_.k < 1) throw InvalidArgument("k-NN k must be >= 1, got 0");
}

std::string KnnClassifier::spec() const {
    const char* index[] = {"auto", "kdtree", "brute"};
    return "knn:k=" + std::to_string(params_.k) + ",metric=" + ToString(params_.metric) +
           ",weighted=" + (params_.distance_weighted ? "1" : "0") +
           ",index=" + index[static_cast<int>(params_.index)] +
           ",leaf=" + std::to_string(params_.leaf_size) +
           ",threads=" + std::to_string(params_.num_threads) + ",seed=" + std::to_string(seed);
}

bool KnnClassifier::UsesTree() const {
    const bool tree_metric =
        params_.metric == KnnMetric::kL2 || params_.metric == KnnMetric::kHellinger;
    // Measured (bench_ml, 50,000 clustered 20-d rows): the tree answers queries near the data
    // about 20 times faster than the scan; queries far from every cluster cost it about twice
    // the scan, still well under a millisecond.
    return tree_metric && params_.index != KnnIndex::kBrute;
}

void KnnClassifier::MapRow(const float* in, float* out) const {
    const auto d = static_cast<std::size_t>(train_.cols());
    const bool histogram = params_.metric == KnnMetric::kHellinger ||
                           params_.metric == KnnMetric::kChi2 || params_.metric == KnnMetric::kJm;
    for (std::size_t j = 0; j < d; ++j) {
        if (histogram && in[j] < 0.0f) {
            throw DataError("k-NN metric " + ToString(params_.metric) +
                            " needs non-negative features, got " + std::to_string(in[j]));
        }
    }
    switch (params_.metric) {
        case KnnMetric::kHellinger:
            for (std::size_t j = 0; j < d; ++j) out[j] = std::sqrt(in[j]);
            break;
        case KnnMetric::kJm: {
            double sum = 0.0;
            for (std::size_t j = 0; j < d; ++j) sum += in[j];
            const float inv = sum > 0.0 ? static_cast<float>(1.0 / sum) : 0.0f;
            for (std::size_t j = 0; j < d; ++j) out[j] = std::sqrt(in[j] * inv);
            break;
        }
        default:
            std::copy_n(in, d, out);
    }
}

void KnnClassifier::BuildIndex() {
    if (UsesTree()) {
        tree_ = KdTreeNd(train_.data(), static_cast<std::size_t>(train_.rows()),
                         static_cast<std::size_t>(train_.cols()), params_.leaf_size);
        cols_.resize(0, 0);
    } else {
        tree_ = KdTreeNd();
        cols_ = train_;  // column-major copy: one contiguous pass per feature
    }
}

void KnnClassifier::FitImpl(const FeaturesRef& x, const std::vector<int>& y, int num_classes,
                            Progress* progress) {
    train_.resize(x.rows(), x.cols());
    for (Eigen::Index r = 0; r < x.rows(); ++r) MapRow(x.row(r).data(), train_.row(r).data());
    labels_ = y;
    num_classes_ = num_classes;
    BuildIndex();
    if (progress != nullptr) progress->Advance();
}

void KnnClassifier::SearchMapped(const float* q, std::vector<Neighbour>& out,
                                 std::vector<float>& scratch) const {
    const std::size_t k = std::min<std::size_t>(params_.k, static_cast<std::size_t>(train_.rows()));
    if (UsesTree()) {
        tree_.Search(q, k, out);
        for (auto& n : out) n.distance = std::sqrt(n.distance);
        return;
    }
    const auto n = cols_.rows();
    scratch.assign(static_cast<std::size_t>(n), 0.0f);
    Eigen::Map<Eigen::ArrayXf> acc(scratch.data(), n);
    for (Eigen::Index j = 0; j < cols_.cols(); ++j) {
        const auto c = cols_.col(j).array();
        const float qj = q[j];
        switch (params_.metric) {
            case KnnMetric::kL1:
                acc += (c - qj).abs();
                break;
            case KnnMetric::kL2:
            case KnnMetric::kHellinger:
                acc += (c - qj).square();
                break;
            case KnnMetric::kChi2: {
                // Features are non-negative: a + b = 0 only where a = b = 0, and then the
                // numerator is 0 too, so a tiny offset replaces a branch per element.
                acc += (c - qj).square() / (c + (qj + 1e-30f));
                break;
            }
            case KnnMetric::kJm:
                acc += c * qj;
                break;
        }
    }
    out.clear();
    for (Eigen::Index i = 0; i < n; ++i) {
        float d = scratch[static_cast<std::size_t>(i)];
        if (params_.metric == KnnMetric::kJm) d = 1.0f - d;  // monotone in the JM distance
        if (out.size() < k || d <= out.back().distance) {
            Offer(out, k, static_cast<std::uint32_t>(i), d);
        }
    }
    for (auto& nb : out) {
        if (params_.metric == KnnMetric::kL2 || params_.metric == KnnMetric::kHellinger) {
            nb.distance = std::sqrt(nb.distance);
        } else if (params_.metric == KnnMetric::kJm) {
            nb.distance = std::sqrt(std::max(0.0f, 2.0f * nb.distance));
        }
    }
}

std::vector<Neighbour> KnnClassifier::Neighbours(std::span<const float> query) const {
    if (!fitted()) throw InvalidArgument("knn classifier is used before it was trained");
    if (query.size() != static_cast<std::size_t>(train_.cols())) {
        throw InvalidArgument("query has " + std::to_string(query.size()) + " features, expected " +
                              std::to_string(train_.cols()));
    }
    std::vector<float> scaled(query.begin(), query.end()), q(query.size()), scratch;
    if (scales_input()) ScaleRow(scaled.data());
    MapRow(scaled.data(), q.data());
    std::vector<Neighbour> out;
    SearchMapped(q.data(), out, scratch);
    return out;
}

FeatureMatrix KnnClassifier::PredictImpl(const FeaturesRef& x) const {
    FeatureMatrix scores = FeatureMatrix::Zero(x.rows(), num_classes_);
    // Check the whole input first: no exceptions inside the parallel loop.
    FeatureMatrix mapped(x.rows(), x.cols());
    for (Eigen::Index r = 0; r < x.rows(); ++r) MapRow(x.row(r).data(), mapped.row(r).data());
    ParallelForChunks(
        static_cast<std::size_t>(x.rows()), params_.num_threads,
        [&](std::size_t begin, std::size_t end) {
            std::vector<Neighbour> nb;
            std::vector<float> scratch;
            for (std::size_t r = begin; r < end; ++r) {
                const auto ri = static_cast<Eigen::Index>(r);
                SearchMapped(mapped.row(ri).data(), nb, scratch);
                for (const auto& n : nb) {
                    const float w = params_.distance_weighted ? 1.0f / (n.distance + 1e-6f) : 1.0f;
                    scores(ri, labels_[n.row]) += w;
                }
            }
        },
        16);
    return scores;
}

void KnnClassifier::WriteModel(ByteWriter& w) const {
    w.Put<std::uint64_t>(static_cast<std::uint64_t>(train_.rows()));
    w.Put<std::uint64_t>(static_cast<std::uint64_t>(train_.cols()));
    w.PutArray(train_.data(), static_cast<std::size_t>(train_.size()));
    w.PutVector(labels_);
    w.Put<std::int32_t>(num_classes_);
}

void KnnClassifier::ReadModel(ByteReader& r) {
    const auto rows = r.Get<std::uint64_t>();
    const auto cols = r.Get<std::uint64_t>();
    const auto values = r.GetVector<float>();
    if (values.size() != rows * cols || cols != num_features()) r.Fail("bad k-NN training matrix");
    train_ = Eigen::Map<const FeatureMatrix>(values.data(), static_cast<Eigen::Index>(rows),
                                             static_cast<Eigen::Index>(cols));
    labels_ = r.GetVector<int>();
    num_classes_ = r.Get<std::int32_t>();
    if (labels_.size() != rows || num_classes_ != static_cast<int>(num_classes())) {
        r.Fail("bad k-NN labels");
    }
    for (int l : labels_) {
        if (l < 0 || l >= num_classes_) r.Fail("bad k-NN label");
    }
    BuildIndex();
}

}  // namespace multicue::ml

#include "multicue/recognition/part_vocabulary.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

#include <Eigen/Eigenvalues>

#include "multicue/core/exceptions.hpp"
#include "multicue/features/grsd.hpp"
#include "multicue/features/vfh.hpp"
#include "multicue/ml/kmeans.hpp"

namespace multicue {

PartVocabulary PartVocabulary::Train(const FeatureMatrix& parts,
                                     const std::vector<Category>& categories,
                                     const PartVocabularyParams& params) {
    if (params.words == 0) throw InvalidArgument("vocabulary words must be >= 1");
    if (params.activations == 0) throw InvalidArgument("vocabulary activations must be >= 1");
    if (params.max_iterations == 0) {
        throw InvalidArgument("vocabulary max_iterations must be >= 1");
    }
    if (parts.rows() == 0 || parts.cols() == 0) {
        throw InvalidArgument("vocabulary: no training parts");
    }
    if (categories.size() != static_cast<std::size_t>(parts.rows())) {
        throw InvalidArgument("vocabulary: need one category per training part");
    }
    for (Category c : categories) {
        const auto v = static_cast<std::size_t>(c);
        if (c == Category::kNone || v >= kNumCategories) {
            throw InvalidArgument("vocabulary: training parts need a category other than none");
        }
    }
    if (!parts.allFinite()) throw DataError("vocabulary: non-finite part feature");
    PartVocabulary v;
    v.params_ = params;
    const auto d = static_cast<std::size_t>(parts.cols());
    v.lo_.assign(d, 0.0f);
    v.scale_.assign(d, 1.0f);
    if (params.normalize) {
        for (std::size_t j = 0; j < d; ++j) {
            const auto col = parts.col(static_cast<Eigen::Index>(j));
            const float lo = col.minCoeff(), hi = col.maxCoeff();
            v.lo_[j] = lo;
            v.scale_[j] = hi > lo ? 1.0f / (hi - lo) : 0.0f;
        }
    }
    FeatureMatrix x(parts.rows(), parts.cols());
    for (Eigen::Index i = 0; i < parts.rows(); ++i) {
        v.Normalize({parts.data() + i * parts.cols(), d}, x.data() + i * parts.cols());
    }
    ml::KMeansParams kp;
    kp.k = std::min<std::size_t>(params.words, static_cast<std::size_t>(parts.rows()));
    kp.max_iterations = params.max_iterations;
    kp.seed = params.seed;
    kp.num_threads = params.num_threads;
    const ml::KMeansResult km = ml::KMeans(x, kp);
    v.words_ = km.centers;
    v.word_counts_.assign(kp.k, {});
    std::array<float, kNumCategories> per_category{};
    for (std::size_t i = 0; i < categories.size(); ++i) {
        const auto c = static_cast<std::size_t>(categories[i]);
        v.word_counts_[static_cast<std::size_t>(km.assignment[i])][c] += 1.0f;
        per_category[c] += 1.0f;
    }
    const float total = static_cast<float>(categories.size());
    v.word_probabilities_.assign(kp.k, {});
    for (std::size_t w = 0; w < kp.k; ++w) {
        auto& p = v.word_probabilities_[w];
        float sum = 0.0f;
        for (std::size_t c = 1; c < kNumCategories; ++c) {
            if (per_category[c] <= 0.0f) continue;
            p[c] = v.word_counts_[w][c] * (params.balanced ? total / per_category[c] : 1.0f);
            sum += p[c];
        }
        if (sum > 0.0f) {
            for (float& x_ : p) x_ /= sum;
        }
    }
    return v;
}

void PartVocabulary::Normalize(std::span<const float> in, float* out) const {
    for (std::size_t j = 0; j < in.size(); ++j) {
        float x = (in[j] - lo_[j]) * scale_[j];
        if (params_.normalize) x = std::clamp(x, 0.0f, 1.0f);
        out[j] = x;
    }
}

std::vector<std::pair<int, float>> PartVocabulary::Activate(std::span<const float> feature) const {
    if (!trained()) throw InvalidArgument("vocabulary: Train() before use");
    if (feature.size() != dims()) {
        throw InvalidArgument("vocabulary: feature has " + std::to_string(feature.size()) +
                              " values, the words " + std::to_string(dims()));
    }
    for (float x : feature) {
        if (!std::isfinite(x)) throw DataError("vocabulary: non-finite part feature");
    }
    std::vector<float> f(dims());
    Normalize(feature, f.data());
    std::vector<std::pair<float, int>> d(num_words());
    for (std::size_t w = 0; w < num_words(); ++w) {
        const float* c = words_.data() + static_cast<Eigen::Index>(w) * words_.cols();
        float s = 0.0f;
        for (std::size_t j = 0; j < f.size(); ++j) s += (f[j] - c[j]) * (f[j] - c[j]);
        d[w] = {std::sqrt(s), static_cast<int>(w)};
    }
    const std::size_t m = std::min(params_.activations, d.size());
    std::partial_sort(d.begin(), d.begin() + static_cast<std::ptrdiff_t>(m), d.end());
    std::vector<std::pair<int, float>> out(m);
    double sum = 0.0;
    for (std::size_t i = 0; i < m; ++i) {
        const float w = 1.0f / (d[i].first + 1e-6f);
        out[i] = {d[i].second, w};
        sum += w;
    }
    for (auto& [w, p] : out) p = static_cast<float>(p / sum);
    return out;
}

std::array<float, kNumCategories> PartVocabulary::PartProbabilities(
    std::span<const float> feature) const {
    std::array<float, kNumCategories> p{};
    for (const auto& [w, a] : Activate(feature)) {
        for (std::size_t c = 0; c < kNumCategories; ++c) {
            p[c] += a * word_probabilities_[static_cast<std::size_t>(w)][c];
        }
    }
    return p;
}

FeatureVector PartVocabulary::BagOfWords(const FeatureMatrix& parts) const {
    if (!trained()) throw InvalidArgument("vocabulary: Train() before use");
    FeatureVector h = FeatureVector::Zero(static_cast<Eigen::Index>(num_words()));
    if (parts.rows() == 0) return h;
    if (static_cast<std::size_t>(parts.cols()) != dims()) {
        throw InvalidArgument("vocabulary: features have " + std::to_string(parts.cols()) +
                              " columns, the words " + std::to_string(dims()));
    }
    for (Eigen::Index i = 0; i < parts.rows(); ++i) {
        for (const auto& [w, a] : Activate({parts.data() + i * parts.cols(), dims()})) h[w] += a;
    }
    h /= h.sum();
    return h;
}

namespace {

// Unit sum, square root, times `scale` (all zero when the block is empty).
void SqrtUnitSum(const float* in, int n, float scale, float* out) {
    double sum = 0.0;
    for (int j = 0; j < n; ++j) sum += std::max(in[j], 0.0f);
    for (int j = 0; j < n; ++j) {
        out[j] =
            sum > 0.0 ? scale * static_cast<float>(std::sqrt(std::max(in[j], 0.0f) / sum)) : 0.0f;
    }
}

}  // namespace

FeatureVector ComputeClusterDescriptor(const PointCloud& cloud, const Indices& indices,
                                       const ClusterDescriptorParams& params) {
    if (!(params.size_weight >= 0.0f) || !std::isfinite(params.size_weight)) {
        throw InvalidArgument("cluster descriptor size_weight must be >= 0 and finite");
    }
    FeatureVector out = FeatureVector::Zero(kClusterDescriptorSize);
    for (Index i : indices) {
        if (i >= cloud.size()) throw InvalidArgument("cluster descriptor: index out of range");
    }
    if (indices.empty()) return out;
    if (!cloud.HasNormals() || cloud.normals.size() != cloud.size()) {
        throw DataError("cluster descriptor needs one normal per point");
    }
    PointCloud sub;
    sub.sensor_origin = cloud.sensor_origin;
    for (Index i : indices) {
        if (!cloud.points[i].allFinite()) continue;
        sub.points.push_back(cloud.points[i]);
        sub.normals.push_back(cloud.normals[i]);
    }
    sub.width = static_cast<std::uint32_t>(sub.points.size());
    sub.height = 1;
    if (sub.points.size() < 3) return out;
    GrsdParams gp;
    gp.voxels = params.voxels;
    gp.voxels.rsd.num_threads = 1;
    const FeatureVector grsd = ComputeGrsdMinus(sub, gp);
    SqrtUnitSum(grsd.data(), kGrsdSize, 1.0f, out.data());
    const FeatureVector vfh = ComputeVfh(sub);
    // Blocks f1, f2, f3, f4 (45 each) and the viewpoint component (128).
    const int begin[5] = {0, 45, 90, 135, 180}, count[5] = {45, 45, 45, 45, 128};
    for (int b = 0; b < 5; ++b) {
        SqrtUnitSum(vfh.data() + begin[b], count[b], 0.5f, out.data() + kGrsdSize + begin[b]);
    }
    if (params.size_weight > 0.0f) {
        Eigen::Vector3d mean = Eigen::Vector3d::Zero();
        for (const auto& p : sub.points) mean += p.cast<double>();
        mean /= static_cast<double>(sub.points.size());
        Eigen::Matrix3d c = Eigen::Matrix3d::Zero();
        for (const auto& p : sub.points) {
            const Eigen::Vector3d q = p.cast<double>() - mean;
            c += q * q.transpose();
        }
        c /= static_cast<double>(sub.points.size());
        const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(c, Eigen::EigenvaluesOnly);
        for (int j = 0; j < 3; ++j) {
            out[kGrsdSize + kVfhSize + j] = static_cast<float>(
                std::sqrt(12.0 * std::max(es.eigenvalues()[2 - j], 0.0)) * params.size_weight);
        }
    }
    return out;
}

}  // namespace multicue

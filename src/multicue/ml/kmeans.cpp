#include "multicue/ml/kmeans.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <tuple>

#include "multicue/core/exceptions.hpp"
#include "multicue/core/parallel.hpp"

namespace multicue::ml {

namespace {

// Nearest center and its squared distance, for one row.
std::pair<int, float> Nearest(const float* row, const FeatureMatrix& centers) {
    const auto d = centers.cols();
    int best = 0;
    float best_d = INFINITY;
    for (Eigen::Index c = 0; c < centers.rows(); ++c) {
        const float* ctr = centers.data() + c * d;
        float s = 0.0f;
        for (Eigen::Index j = 0; j < d; ++j) {
            const float diff = row[j] - ctr[j];
            s += diff * diff;
        }
        if (s < best_d) {
            best_d = s;
            best = static_cast<int>(c);
        }
    }
    return {best, best_d};
}

}  // namespace

std::vector<int> AssignClusters(const FeaturesRef& x, const FeatureMatrix& centers,
                                int num_threads) {
    if (x.cols() != centers.cols()) {
        throw InvalidArgument("features have " + std::to_string(x.cols()) +
                              " columns, the codebook " + std::to_string(centers.cols()));
    }
    if (centers.rows() == 0) throw InvalidArgument("codebook is empty");
    std::vector<int> out(static_cast<std::size_t>(x.rows()));
    ParallelFor(
        out.size(), num_threads,
        [&](std::size_t i) {
            out[i] =
                Nearest(x.data() + static_cast<Eigen::Index>(i) * x.outerStride(), centers).first;
        },
        256);
    return out;
}

KMeansResult KMeans(const FeaturesRef& x, const KMeansParams& params) {
    const auto n = static_cast<std::size_t>(x.rows());
    const auto d = x.cols();
    if (params.k == 0) throw InvalidArgument("k-means k must be >= 1, got 0");
    if (params.k > n) {
        throw InvalidArgument("k-means k (" + std::to_string(params.k) + ") exceeds the " +
                              std::to_string(n) + " rows");
    }
    if (!x.allFinite()) throw DataError("k-means input holds non-finite values");
    const FeatureMatrix data = x;
    std::mt19937 rng(params.seed);

    // k-means++ seeding (Arthur and Vassilvitskii, 2007): next center drawn with probability
    // proportional to the squared distance to the nearest chosen center.
    KMeansResult res;
    res.centers.resize(static_cast<Eigen::Index>(params.k), d);
    std::vector<double> dist(n, INFINITY);
    std::size_t first = std::uniform_int_distribution<std::size_t>(0, n - 1)(rng);
    res.centers.row(0) = data.row(static_cast<Eigen::Index>(first));
    for (std::size_t c = 1; c < params.k; ++c) {
        const auto prev = res.centers.row(static_cast<Eigen::Index>(c - 1));
        double total = 0.0;
        for (std::size_t i = 0; i < n; ++i) {
            dist[i] = std::min(
                dist[i],
                static_cast<double>((data.row(static_cast<Eigen::Index>(i)) - prev).squaredNorm()));
            total += dist[i];
        }
        std::size_t pick = 0;
        if (total > 0.0) {
            double u = std::uniform_real_distribution<double>(0.0, total)(rng);
            for (pick = 0; pick + 1 < n; ++pick) {
                u -= dist[pick];
                if (u <= 0.0) break;
            }
        } else {
            pick = std::uniform_int_distribution<std::size_t>(0, n - 1)(rng);
        }
        res.centers.row(static_cast<Eigen::Index>(c)) = data.row(static_cast<Eigen::Index>(pick));
    }

    res.assignment.assign(n, 0);
    std::vector<float> d2(n);
    double prev_inertia = INFINITY;
    for (res.iterations = 1; res.iterations <= params.max_iterations; ++res.iterations) {
        ParallelFor(
            n, params.num_threads,
            [&](std::size_t i) {
                const auto [c, dd] =
                    Nearest(data.data() + static_cast<Eigen::Index>(i) * d, res.centers);
                res.assignment[i] = c;
                d2[i] = dd;
            },
            256);
        res.inertia = 0.0;
        for (float v : d2) res.inertia += v;
        // Update step; an empty cluster takes the row farthest from its center.
        Eigen::MatrixXd sums = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(params.k), d);
        std::vector<std::size_t> counts(params.k, 0);
        for (std::size_t i = 0; i < n; ++i) {
            sums.row(res.assignment[i]) += data.row(static_cast<Eigen::Index>(i)).cast<double>();
            ++counts[static_cast<std::size_t>(res.assignment[i])];
        }
        for (std::size_t c = 0; c < params.k; ++c) {
            const auto ci = static_cast<Eigen::Index>(c);
            if (counts[c] > 0) {
                res.centers.row(ci) = (sums.row(ci) / static_cast<double>(counts[c])).cast<float>();
            } else {
                const auto far =
                    static_cast<std::size_t>(std::max_element(d2.begin(), d2.end()) - d2.begin());
                res.centers.row(ci) = data.row(static_cast<Eigen::Index>(far));
                d2[far] = 0.0f;
            }
        }
        if (std::abs(prev_inertia - res.inertia) <=
            params.tolerance * std::max(res.inertia, 1e-30)) {
            res.converged = true;
            break;
        }
        prev_inertia = res.inertia;
    }
    res.iterations = std::min(res.iterations, params.max_iterations);
    res.assignment = AssignClusters(data, res.centers, params.num_threads);
    return res;
}

Dataset CodebookToDataset(const FeatureMatrix& centers, const std::vector<std::string>& names) {
    if (names.size() != static_cast<std::size_t>(centers.cols())) {
        throw InvalidArgument("codebook has " + std::to_string(centers.cols()) + " columns but " +
                              std::to_string(names.size()) + " names");
    }
    Dataset d = Dataset::WithBlocks({{"codebook", names}});
    for (Eigen::Index r = 0; r < centers.rows(); ++r) {
        d.AppendRow(std::span<const float>(centers.data() + r * centers.cols(),
                                           static_cast<std::size_t>(centers.cols())),
                    "");
    }
    return d;
}

Dataset BagOfWords(const Dataset& local, const FeatureMatrix& codebook, const std::string& block,
                   int num_threads) {
    local.CheckFinite("local features");
    const auto words = AssignClusters(local.features(), codebook, num_threads);
    const auto k = static_cast<std::size_t>(codebook.rows());
    std::vector<std::string> names(k);
    for (std::size_t i = 0; i < k; ++i) names[i] = IndexedName("w", i);
    Dataset out = Dataset::WithBlocks({{block, names}});
    // Bags in order of first appearance.
    using Key = std::tuple<std::string, std::int64_t, std::int64_t>;
    std::map<Key, std::size_t> bag_of;
    std::vector<std::size_t> first_row;
    std::vector<std::vector<float>> hist;
    for (std::size_t r = 0; r < local.rows(); ++r) {
        const Key key{local.sources[r], local.groups[r], local.views[r]};
        auto [it, inserted] = bag_of.emplace(key, hist.size());
        if (inserted) {
            hist.emplace_back(k, 0.0f);
            first_row.push_back(r);
        }
        hist[it->second][static_cast<std::size_t>(words[r])] += 1.0f;
    }
    for (std::size_t b = 0; b < hist.size(); ++b) {
        float total = 0.0f;
        for (float v : hist[b]) total += v;
        for (float& v : hist[b]) v /= total;
        const std::size_t r = first_row[b];
        const int l = local.labels[r];
        out.AppendRow(hist[b], l == kNoLabel ? "" : local.class_names[l], local.groups[r],
                      local.views[r], local.sources[r], static_cast<std::int64_t>(b));
    }
    return out;
}

}  // namespace multicue::ml

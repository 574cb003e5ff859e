#include "multicue/filters/outlier_removal.hpp"

#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/core/parallel.hpp"

namespace multicue {
namespace {

// Neighbour queries cost far more than a task, so chunks are small for load balance.
constexpr std::size_t kGrain = 256;

Indices Compact(const std::vector<std::uint8_t>& keep) {
    Indices out;
    for (std::size_t i = 0; i < keep.size(); ++i) {
        if (keep[i] != 0) out.push_back(static_cast<Index>(i));
    }
    return out;
}

}  // namespace

Indices StatisticalOutlierRemoval(const PointCloud& cloud, const KdTree& tree,
                                  const StatisticalOutlierParams& params) {
    if (params.k < 1 || params.k == std::numeric_limits<int>::max()) {
        throw InvalidArgument(fmt::format("k must be > 0, got {}", params.k));
    }
    if (!(params.std_ratio >= 0.0f) || !std::isfinite(params.std_ratio)) {
        throw InvalidArgument(fmt::format("std_ratio must be >= 0, got {}", params.std_ratio));
    }
    ResolveThreadCount(params.num_threads);
    const std::size_t n = cloud.size();
    const auto k = static_cast<std::size_t>(params.k);

    // Mean distance to the k nearest other points; infinity when there are none or the point is
    // not finite. Written per index, so the thread count cannot change it.
    constexpr float kNone = std::numeric_limits<float>::infinity();
    std::vector<float> mean_distance(n, kNone);
    ParallelForChunks(
        n, params.num_threads,
        [&](std::size_t begin, std::size_t end) {
            Indices idx;
            std::vector<float> d2;
            for (std::size_t i = begin; i < end; ++i) {
                const Eigen::Vector3f& p = cloud.points[i];
                if (!p.allFinite()) continue;
                tree.SearchKnn(p, params.k + 1, idx, d2);
                double sum = 0.0;
                std::size_t used = 0;
                for (std::size_t j = 0; j < idx.size() && used < k; ++j) {
                    if (idx[j] == i) continue;
                    sum += std::sqrt(d2[j]);
                    ++used;
                }
                if (used > 0)
                    mean_distance[i] = static_cast<float>(sum / static_cast<double>(used));
            }
        },
        kGrain);

    // Statistics over the points with neighbours, summed serially in index order.
    double sum = 0.0;
    std::size_t count = 0;
    for (float d : mean_distance) {
        if (d == kNone) continue;
        sum += d;
        ++count;
    }
    if (count == 0) return {};
    const double mean = sum / static_cast<double>(count);
    double squares = 0.0;
    for (float d : mean_distance) {
        if (d != kNone) squares += (d - mean) * (d - mean);
    }
    const double stddev = count > 1 ? std::sqrt(squares / static_cast<double>(count - 1)) : 0.0;
    const double threshold = mean + params.std_ratio * stddev;

    Indices out;
    for (std::size_t i = 0; i < n; ++i) {
        if (mean_distance[i] != kNone && mean_distance[i] <= threshold) {
            out.push_back(static_cast<Index>(i));
        }
    }
    return out;
}

Indices RadiusOutlierRemoval(const PointCloud& cloud, const KdTree& tree,
                             const RadiusOutlierParams& params) {
    if (!(params.radius > 0.0f) || !std::isfinite(params.radius)) {
        throw InvalidArgument(fmt::format("radius must be > 0, got {}", params.radius));
    }
    if (params.min_neighbors < 0) {
        throw InvalidArgument(
            fmt::format("min_neighbors must be >= 0, got {}", params.min_neighbors));
    }
    ResolveThreadCount(params.num_threads);
    const std::size_t n = cloud.size();
    const auto needed = static_cast<std::size_t>(params.min_neighbors);
    std::vector<std::uint8_t> keep(n, 0);
    ParallelForChunks(
        n, params.num_threads,
        [&](std::size_t begin, std::size_t end) {
            Indices idx;
            std::vector<float> d2;
            for (std::size_t i = begin; i < end; ++i) {
                const Eigen::Vector3f& p = cloud.points[i];
                if (!p.allFinite()) continue;
                tree.SearchRadius(p, params.radius, idx, d2);
                std::size_t others = 0;
                for (Index j : idx) others += j != i;
                keep[i] = others >= needed;
            }
        },
        kGrain);
    return Compact(keep);
}

}  // namespace multicue

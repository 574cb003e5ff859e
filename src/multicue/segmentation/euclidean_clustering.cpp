#include "multicue/segmentation/euclidean_clustering.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/segmentation/disjoint_sets.hpp"

namespace multicue {
namespace {

void CheckClusterParams(float tolerance, std::size_t min_size, std::size_t max_size) {
    if (!(tolerance > 0.0f) || !std::isfinite(tolerance)) {
        throw InvalidArgument(fmt::format("cluster tolerance must be > 0, got {}", tolerance));
    }
    if (max_size == 0) throw InvalidArgument("max_cluster_size must be >= 1, got 0");
    if (min_size > max_size) {
        throw InvalidArgument(fmt::format(
            "min_cluster_size ({}) must not exceed max_cluster_size ({})", min_size, max_size));
    }
}

// Marks with 1 the finite points to cluster: those of `subset` (or of `mask`), or all when both
// are empty. Returns how many were marked.
std::size_t MarkPoints(const PointCloud& cloud, const Indices& subset,
                       const std::vector<std::uint8_t>& mask, std::vector<std::uint8_t>& marked) {
    const std::size_t n = cloud.size();
    marked.assign(n, 0);
    std::size_t count = 0;
    auto mark = [&](std::size_t i) {
        if (marked[i] == 0 && cloud.IsFinite(i)) {
            marked[i] = 1;
            ++count;
        }
    };
    if (!subset.empty()) {
        for (Index i : subset) {
            if (i >= n) {
                throw InvalidArgument(
                    fmt::format("subset index {} is out of range for a cloud of {} points", i, n));
            }
            mark(i);
        }
    } else if (!mask.empty()) {
        for (std::size_t i = 0; i < n; ++i) {
            if (mask[i] != 0) mark(i);
        }
    } else {
        for (std::size_t i = 0; i < n; ++i) mark(i);
    }
    return count;
}

// Applies the size filters, orders the clusters (largest first, then by smallest index) and
// fills the labels. Each component must already be sorted ascending.
ClusteringResult Finish(std::vector<Indices> components, std::size_t cloud_size,
                        std::size_t num_points, std::size_t min_size, std::size_t max_size,
                        bool compute_labels) {
    ClusteringResult result;
    result.num_points = num_points;
    for (auto& c : components) {
        if (c.size() < min_size) {
            ++result.num_too_small;
        } else if (c.size() > max_size) {
            ++result.num_too_large;
        } else {
            result.clusters.push_back(std::move(c));
        }
    }
    std::sort(result.clusters.begin(), result.clusters.end(),
              [](const Indices& a, const Indices& b) {
                  if (a.size() != b.size()) return a.size() > b.size();
                  return a.front() < b.front();
              });
    if (compute_labels) {
        result.labels.assign(cloud_size, kNoCluster);
        for (std::size_t c = 0; c < result.clusters.size(); ++c) {
            for (Index i : result.clusters[c]) result.labels[i] = static_cast<std::int32_t>(c);
        }
    }
    return result;
}

}  // namespace

ClusteringResult EuclideanClustering(const PointCloud& cloud, const KdTree& tree,
                                     const EuclideanClusteringParams& params) {
    CheckClusterParams(params.tolerance, params.min_cluster_size, params.max_cluster_size);
    const std::size_t n = cloud.size();
    // 0: not clustered, 1: waiting, 2: taken by a cluster.
    std::vector<std::uint8_t> state;
    const std::size_t num_points = MarkPoints(cloud, params.subset, {}, state);

    std::vector<Indices> components;
    Indices neighbors;
    std::vector<float> squared_distances;
    for (std::size_t seed = 0; seed < n; ++seed) {
        if (state[seed] != 1) continue;
        // Breadth-first flood fill; the component doubles as the queue.
        Indices component{static_cast<Index>(seed)};
        state[seed] = 2;
        for (std::size_t head = 0; head < component.size(); ++head) {
            const Index q = component[head];
            tree.SearchRadius(cloud.points[q], params.tolerance, neighbors, squared_distances);
            bool found_self = false;
            for (Index j : neighbors) {
                if (j >= n) {
                    throw InvalidArgument(fmt::format(
                        "the k-d tree holds point {}, but the cloud has only {} points", j, n));
                }
                found_self = found_self || j == q;
                if (state[j] == 1) {
                    state[j] = 2;
                    component.push_back(j);
                }
            }
            if (!found_self) {
                throw InvalidArgument(fmt::format(
                    "point {} is to be clustered but the k-d tree does not index it", q));
            }
        }
        std::sort(component.begin(), component.end());
        components.push_back(std::move(component));
    }
    return Finish(std::move(components), n, num_points, params.min_cluster_size,
                  params.max_cluster_size, params.compute_labels);
}

ClusteringResult EuclideanClusteringOrganized(const PointCloud& organized,
                                              const OrganizedClusteringParams& params) {
    CheckClusterParams(params.tolerance, params.min_cluster_size, params.max_cluster_size);
    if (params.connectivity != 4 && params.connectivity != 8) {
        throw InvalidArgument(
            fmt::format("connectivity must be 4 or 8, got {}", params.connectivity));
    }
    if (params.half_window < 1) {
        throw InvalidArgument(
            fmt::format("half_window must be >= 1 pixel, got {}", params.half_window));
    }
    if (!params.subset.empty() && !params.mask.empty()) {
        throw InvalidArgument("give either a subset or a mask for organized clustering, not both");
    }
    const std::size_t n = organized.size();
    if (!params.mask.empty() && params.mask.size() != n) {
        throw InvalidArgument(
            fmt::format("mask has {} entries for a cloud of {} points", params.mask.size(), n));
    }
    if (n == 0) return Finish({}, 0, 0, params.min_cluster_size, params.max_cluster_size, false);
    if (!organized.IsOrganized()) {
        throw InvalidArgument(
            fmt::format("organized clustering needs an organized cloud, got {}x{} for {} points",
                        organized.width, organized.height, n));
    }

    std::vector<std::uint8_t> active;
    const std::size_t num_points = MarkPoints(organized, params.subset, params.mask, active);

    // Forward half of the neighbourhood (later rows, or the same row to the right): each pixel
    // pair is examined once.
    const int h = params.half_window;
    std::vector<std::pair<int, int>> offsets;  // (du, dv)
    for (int dv = 0; dv <= h; ++dv) {
        for (int du = -h; du <= h; ++du) {
            if (dv == 0 && du <= 0) continue;
            if (params.connectivity == 4 && std::abs(du) + dv > h) continue;
            offsets.emplace_back(du, dv);
        }
    }

    const int width = static_cast<int>(organized.width);
    const int height = static_cast<int>(organized.height);
    const float tolerance_sq = params.tolerance * params.tolerance;
    detail::DisjointSets sets(n);
    for (int v = 0; v < height; ++v) {
        for (int u = 0; u < width; ++u) {
            const auto i = static_cast<Index>(v * width + u);
            if (active[i] == 0) continue;
            const Eigen::Vector3f& p = organized.points[i];
            for (const auto& [du, dv] : offsets) {
                const int uu = u + du;
                const int vv = v + dv;
                if (uu < 0 || uu >= width || vv >= height) continue;
                const auto j = static_cast<Index>(vv * width + uu);
                if (active[j] == 0) continue;
                if ((organized.points[j] - p).squaredNorm() < tolerance_sq) sets.Unite(i, j);
            }
        }
    }

    // Roots are the smallest indices, so visiting pixels in order creates each component at its
    // root and appends its pixels in ascending order.
    std::vector<std::int32_t> component_of_root(n, -1);
    std::vector<Indices> components;
    for (std::size_t k = 0; k < n; ++k) {
        if (active[k] == 0) continue;
        const auto i = static_cast<Index>(k);
        const Index root = sets.Find(i);
        if (component_of_root[root] < 0) {
            component_of_root[root] = static_cast<std::int32_t>(components.size());
            components.emplace_back();
        }
        components[static_cast<std::size_t>(component_of_root[root])].push_back(i);
    }
    return Finish(std::move(components), n, num_points, params.min_cluster_size,
                  params.max_cluster_size, params.compute_labels);
}

void ObjectClusteringParams::Validate() const {
    CheckClusterParams(tolerance, min_points, max_points);
    if (organized_half_window < 1) {
        throw InvalidArgument(
            fmt::format("organized_half_window must be >= 1 pixel, got {}", organized_half_window));
    }
}

ClusteringResult ClusterObjects(const PointCloud& cloud, const Indices& region,
                                const ObjectClusteringParams& params) {
    params.Validate();
    if (region.empty()) return {};
    if (cloud.IsOrganized()) {
        return EuclideanClusteringOrganized(cloud, {.tolerance = params.tolerance,
                                                    .min_cluster_size = params.min_points,
                                                    .max_cluster_size = params.max_points,
                                                    .subset = region,
                                                    .half_window = params.organized_half_window});
    }
    const KdTree tree(cloud, region);
    return EuclideanClustering(cloud, tree,
                               {.tolerance = params.tolerance,
                                .min_cluster_size = params.min_points,
                                .max_cluster_size = params.max_points,
                                .subset = region});
}

}  // namespace multicue

#include "multicue/surface/normals.hpp"

#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <utility>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/core/parallel.hpp"
#include "multicue/core/params.hpp"
#include "multicue/surface/pca.hpp"
#include "multicue/surface/tree_neighbourhoods.hpp"

namespace multicue {

namespace {

using detail::kNaN;
using detail::Moments;

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

void NormalParams::Validate() const { CheckParams(*this); }

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
    const std::optional<detail::RadiusMoments> radius_moments =
        use_summary ? std::optional<detail::RadiusMoments>(std::in_place, tree) : std::nullopt;

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
                radius_moments->Accumulate(tree_points[t], r2, m);
                store(tree_points[t], to_cloud[t], m);
            }
        });
    } else {
        // Groups of leaves, in runs of consecutive groups (see KnnBatch).
        const detail::TreeGroups groups = detail::CutIntoGroups(tree);
        const float cap2 = use_radius ? r2 : std::numeric_limits<float>::infinity();
        ParallelForChunks(
            groups.groups.size(), params.num_threads,
            [&](std::size_t begin, std::size_t end) {
                detail::KnnBatch batch(tree, static_cast<std::size_t>(k), cap2);
                for (std::size_t g = begin; g < end; ++g) {
                    for (const auto& [t, m] : batch.Group(groups, g)) {
                        store(tree_points[t], to_cloud[t], m.ToDouble());
                    }
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
                    radius_moments->Accumulate(q, r2, m);
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

void FrameNormalParams::Validate() const {
    ValidateNode("organized", [&] { organized.Validate(); });
    ValidateNode("unorganized", [&] { unorganized.Validate(); });
}

NormalsResult EstimateFrameNormals(const PointCloud& cloud, const Indices& region,
                                   const FrameNormalParams& params) {
    params.Validate();
    if (cloud.IsOrganized()) {
        OrganizedNormalParams p = params.organized;
        p.mask.assign(cloud.size(), 0);
        for (Index i : region) {
            if (i >= cloud.size()) {
                throw InvalidArgument(fmt::format(
                    "region index {} is out of range for a cloud of {} points", i, cloud.size()));
            }
            p.mask[i] = 1;
        }
        return EstimateNormalsOrganized(cloud, p);
    }
    const KdTree tree(cloud);
    return EstimateNormals(cloud, tree, params.unorganized);
}

void EnsureFrameNormals(PointCloud& cloud, const Indices& region, const FrameNormalParams& params) {
    if (cloud.HasNormals() && cloud.HasCurvature()) return;
    SetNormals(cloud, EstimateFrameNormals(cloud, region, params));
}

}  // namespace multicue

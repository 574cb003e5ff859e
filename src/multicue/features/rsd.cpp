#include "multicue/features/rsd.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <vector>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/core/parallel.hpp"
#include "multicue/search/voxel_hash_map.hpp"

namespace multicue {
namespace {

constexpr int kMaxBins = 64;

void CheckRsdParams(const RsdParams& params) {
    detail::CheckPositive(params.radius, "RSD radius");
    detail::CheckPositive(params.plane_radius, "RSD plane_radius");
    if (!(params.angle_quantile > 0.0f && params.angle_quantile <= 1.0f)) {
        throw InvalidArgument(
            fmt::format("RSD angle_quantile must be in (0, 1], got {}", params.angle_quantile));
    }
    if (params.num_bins < 1 || params.num_bins > kMaxBins) {
        throw InvalidArgument(
            fmt::format("RSD num_bins must be in [1, {}], got {}", kMaxBins, params.num_bins));
    }
    detail::CheckThreads(params.num_threads);
}

// Section 2.5.1: the extreme angles per distance bin, then two regressions d = r alpha through
// the origin. Angles are tracked as |cos| (acos is decreasing, so the largest |cos| is the
// smallest angle); only 2 * num_bins arc cosines are taken per neighbourhood.
Eigen::Vector2f RadiiFromNeighbours(const PointCloud& cloud, const Eigen::Vector3f& ref,
                                    const Eigen::Vector3f& ref_normal, const Index* neighbours,
                                    std::size_t count, float max_dist, const RsdParams& params) {
    if (count < 2) return {0.0f, 0.0f};
    const int bins = params.num_bins;
    float max_abs_cos[kMaxBins];  // smallest angle per bin
    float min_abs_cos[kMaxBins];  // largest angle per bin
    for (int b = 0; b < bins; ++b) {
        max_abs_cos[b] = -1.0f;  // empty bin
        min_abs_cos[b] = 2.0f;
    }
    // The reference itself: distance 0, angle 0 (PCL starts bin 0 at angle 0 for the same reason).
    max_abs_cos[0] = 1.0f;
    min_abs_cos[0] = 1.0f;
    const float bins_per_m = static_cast<float>(bins) / max_dist;
    // With angle_quantile < 1 the |cos| of each bin are kept and their quantiles taken below:
    // the share q of the angles lies at or below the one taken as largest, 1 - q at or below
    // the one taken as smallest.
    const bool quantile = params.angle_quantile < 1.0f;
    thread_local std::array<std::vector<float>, kMaxBins> per_bin;
    if (quantile) {
        for (int b = 0; b < bins; ++b) per_bin[b].clear();
    }
    for (std::size_t k = 0; k < count; ++k) {
        const Index j = neighbours[k];
        const Eigen::Vector3f& n = cloud.normals[j];
        const float d = (cloud.points[j] - ref).norm();
        if (!(d <= max_dist) || !n.allFinite()) continue;
        const float c = std::min(1.0f, std::abs(n.dot(ref_normal)));
        const int b = std::min(bins - 1, static_cast<int>(d * bins_per_m));
        if (quantile) {
            per_bin[b].push_back(c);
        } else {
            max_abs_cos[b] = std::max(max_abs_cos[b], c);
            min_abs_cos[b] = std::min(min_abs_cos[b], c);
        }
    }
    for (int b = 0; quantile && b < bins; ++b) {
        auto& v = per_bin[b];
        if (v.empty()) continue;
        const std::size_t last = v.size() - 1;
        const auto low = static_cast<std::size_t>(
            std::lround((1.0 - params.angle_quantile) * static_cast<double>(last)));
        std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(low), v.end());
        min_abs_cos[b] = std::min(min_abs_cos[b], v[low]);  // largest angle
        const std::size_t high = last - low;
        std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(high), v.end());
        max_abs_cos[b] = std::max(max_abs_cos[b], v[high]);  // smallest angle
    }
    double aa_min = 0.0, ad_min = 0.0, aa_max = 0.0, ad_max = 0.0;
    for (int b = 0; b < bins; ++b) {
        if (max_abs_cos[b] < 0.0f) continue;
        const double angle_min = std::acos(static_cast<double>(max_abs_cos[b]));
        const double angle_max = std::acos(static_cast<double>(min_abs_cos[b]));
        const double f = (b + 0.5) * max_dist / bins;
        aa_min += angle_min * angle_min;
        ad_min += angle_min * f;
        aa_max += angle_max * angle_max;
        ad_max += angle_max * f;
    }
    const double plane = params.plane_radius;
    // Largest angles give the smallest radius. Bias factors: see RsdParams::correct_bias.
    const double min_factor = params.correct_bias ? 1.1 : 1.0;
    const double max_factor = params.correct_bias ? 0.9 : 1.0;
    float r_min, r_max;
    if (params.pcl_compatible) {
        // pcl::computeRSD: cap, then scale; its 1.1 lands on the radius of the smallest angles
        // (the larger radius) and 0.9 on that of the largest angles.
        r_max = aa_min == 0.0 ? static_cast<float>(plane)
                              : static_cast<float>(std::min(ad_min / aa_min, plane));
        r_min = aa_max == 0.0 ? static_cast<float>(plane)
                              : static_cast<float>(std::min(ad_max / aa_max, plane));
        r_max *= 1.1f;
        r_min *= 0.9f;
    } else {
        r_min = aa_max == 0.0 ? static_cast<float>(plane)
                              : static_cast<float>(std::min(min_factor * ad_max / aa_max, plane));
        r_max = aa_min == 0.0 ? static_cast<float>(plane)
                              : static_cast<float>(std::min(max_factor * ad_min / aa_min, plane));
    }
    if (r_min > r_max) std::swap(r_min, r_max);
    return {r_min, r_max};
}

}  // namespace

void RsdParams::Validate() const { CheckRsdParams(*this); }

Eigen::Vector2f RsdOfNeighbourhood(const PointCloud& cloud, const Eigen::Vector3f& reference,
                                   const Eigen::Vector3f& reference_normal,
                                   const Indices& neighbours, const RsdParams& params) {
    CheckRsdParams(params);
    detail::CheckNormals(cloud, "RSD");
    for (Index j : neighbours) {
        if (j >= cloud.size()) {
            throw InvalidArgument(
                fmt::format("RSD neighbour index {} is out of range ({} points)", j, cloud.size()));
        }
    }
    return RadiiFromNeighbours(cloud, reference, reference_normal, neighbours.data(),
                               neighbours.size(), params.radius, params);
}

FeatureMatrix ComputeRsd(const PointCloud& cloud, const KdTree& tree, const RsdParams& params) {
    CheckRsdParams(params);
    detail::CheckNormals(cloud, "RSD");
    detail::CheckTree(cloud, tree);
    const std::size_t n = cloud.size();
    FeatureMatrix out(static_cast<Eigen::Index>(n), 2);
    ParallelForChunks(
        n, params.num_threads,
        [&](std::size_t begin, std::size_t end) {
            Indices nn;
            std::vector<float> d2;
            for (std::size_t i = begin; i < end; ++i) {
                const auto row = static_cast<Eigen::Index>(i);
                if (!detail::IsUsable(cloud, i)) {
                    out.row(row).setConstant(std::numeric_limits<float>::quiet_NaN());
                    continue;
                }
                detail::RadiusNeighbours(tree, cloud.points[i], params.radius, nn, d2);
                const Eigen::Vector2f r =
                    RadiiFromNeighbours(cloud, cloud.points[i], cloud.normals[i], nn.data(),
                                        nn.size(), params.radius, params);
                out(row, 0) = r[0];
                out(row, 1) = r[1];
            }
        },
        256);
    return out;
}

VoxelRsdResult ComputeVoxelRsd(const PointCloud& cloud, const KdTree& tree,
                               const VoxelRsdParams& params) {
    detail::CheckPositive(params.voxel_size, "voxel_size");
    CheckRsdParams(params.rsd);
    detail::CheckNormals(cloud, "voxel RSD");
    detail::CheckTree(cloud, tree);
    VoxelRsdResult result;
    result.voxel_size = params.voxel_size;
    result.point_voxel.assign(cloud.size(), VoxelRsdResult::kNoVoxel);
    if (cloud.empty()) {
        result.radii.resize(0, 2);
        return result;
    }
    const VoxelPartition partition = PartitionByVoxel(
        cloud, {.leaf_size = params.voxel_size, .num_threads = params.rsd.num_threads});
    const std::size_t num_voxels = partition.num_voxels();
    result.coordinates.resize(num_voxels);
    result.centroids.resize(num_voxels);
    result.radii.resize(static_cast<Eigen::Index>(num_voxels), 2);
    result.types.resize(num_voxels);
    RsdParams rsd = params.rsd;
    rsd.radius = std::max(rsd.radius, std::sqrt(3.0f) * 0.5f * params.voxel_size);
    ParallelForChunks(
        num_voxels, rsd.num_threads,
        [&](std::size_t begin, std::size_t end) {
            Indices nn;
            std::vector<float> d2;
            for (std::size_t v = begin; v < end; ++v) {
                Eigen::Vector3d sum = Eigen::Vector3d::Zero();
                for (Index i : partition.Points(v)) {
                    sum += cloud.points[i].cast<double>();
                    result.point_voxel[i] = static_cast<std::uint32_t>(v);
                }
                const Eigen::Vector3f centroid =
                    (sum / static_cast<double>(partition.Points(v).size())).cast<float>();
                result.coordinates[v] = partition.Coordinates(v);
                result.centroids[v] = centroid;
                detail::RadiusNeighbours(tree, centroid, rsd.radius, nn, d2);
                // The reference is the nearest point with a finite normal (ties: lowest index).
                std::size_t best = nn.size();
                for (std::size_t k = 0; k < nn.size(); ++k) {
                    if (!cloud.normals[nn[k]].allFinite()) continue;
                    if (best == nn.size() || d2[k] < d2[best] ||
                        (d2[k] == d2[best] && nn[k] < nn[best])) {
                        best = k;
                    }
                }
                const auto row = static_cast<Eigen::Index>(v);
                if (best == nn.size()) {
                    result.radii.row(row).setConstant(std::numeric_limits<float>::quiet_NaN());
                    result.types[v] = SurfaceType::kUndefined;
                    continue;
                }
                const Index ref = nn[best];
                // Distances from the centroid (the query), angles against the normal of the
                // nearest point, as PCL's GRSDEstimation measures them.
                const Eigen::Vector2f r = RadiiFromNeighbours(
                    cloud, centroid, cloud.normals[ref], nn.data(), nn.size(), rsd.radius, rsd);
                result.radii(row, 0) = r[0];
                result.radii(row, 1) = r[1];
                result.types[v] = ClassifySurface(r[0], r[1], params.thresholds);
            }
        },
        16);
    return result;
}

}  // namespace multicue

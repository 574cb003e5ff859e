#include "multicue/filters/voxel_grid.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/core/logging.hpp"
#include "multicue/core/parallel.hpp"
#include "multicue/search/voxel_hash_map.hpp"

namespace multicue {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

float MeanOfFinite(std::span<const Index> idx, const std::vector<float>& values) {
    double sum = 0.0;
    std::size_t count = 0;
    for (Index i : idx) {
        const float v = values[i];
        if (!std::isfinite(v)) continue;
        sum += v;
        ++count;
    }
    return count > 0 ? static_cast<float>(sum / static_cast<double>(count)) : kNaN;
}

Eigen::Vector3f MeanNormal(std::span<const Index> idx,
                           const std::vector<Eigen::Vector3f>& normals) {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    std::size_t count = 0;
    for (Index i : idx) {
        const Eigen::Vector3f& n = normals[i];
        if (!n.allFinite()) continue;
        sum += n.cast<double>();
        ++count;
    }
    const double norm = sum.norm();
    if (count == 0 || !(norm > 0.0)) return Eigen::Vector3f::Constant(kNaN);
    return (sum / norm).cast<float>();
}

Color MeanColor(std::span<const Index> idx, const std::vector<Color>& colors) {
    if (idx.size() == 1) return colors[idx[0]];
    std::uint64_t r = 0, g = 0, b = 0, a = 0;
    for (Index i : idx) {
        const Color& c = colors[i];
        r += c.r;
        g += c.g;
        b += c.b;
        a += c.a;
    }
    // Rounded mean (sum + n/2) / n; 32-bit divisions while the sums fit, as they nearly always do.
    const std::uint64_t n = idx.size(), half = n / 2;
    if (n < (std::uint64_t{1} << 24)) {
        const auto n32 = static_cast<std::uint32_t>(n), h32 = static_cast<std::uint32_t>(half);
        const auto mean = [&](std::uint64_t sum) {
            return static_cast<std::uint8_t>((static_cast<std::uint32_t>(sum) + h32) / n32);
        };
        return {mean(r), mean(g), mean(b), mean(a)};
    }
    return {static_cast<std::uint8_t>((r + half) / n), static_cast<std::uint8_t>((g + half) / n),
            static_cast<std::uint8_t>((b + half) / n), static_cast<std::uint8_t>((a + half) / n)};
}

// Most frequent label, ties to the smallest; `scratch` is reused across voxels.
std::uint32_t MajorityLabel(std::span<const Index> idx, const std::vector<std::uint32_t>& labels,
                            std::vector<std::uint32_t>& scratch) {
    if (idx.size() == 1) return labels[idx[0]];
    scratch.clear();
    for (Index i : idx) scratch.push_back(labels[i]);
    std::sort(scratch.begin(), scratch.end());
    std::uint32_t best = scratch[0];
    std::size_t best_count = 0;
    for (std::size_t s = 0; s < scratch.size();) {
        std::size_t e = s + 1;
        while (e < scratch.size() && scratch[e] == scratch[s]) ++e;
        if (e - s > best_count) {  // strictly more: ascending runs keep the smallest on ties
            best = scratch[s];
            best_count = e - s;
        }
        s = e;
    }
    return best;
}

}  // namespace

PointCloud VoxelGrid(const PointCloud& cloud, const VoxelGridParams& params) {
    if (params.min_points_per_voxel < 0) {
        throw InvalidArgument(
            fmt::format("min_points_per_voxel must be >= 0, got {}", params.min_points_per_voxel));
    }
    ResolveThreadCount(params.num_threads);
    cloud.Validate();
    if (!cloud.extra_fields.empty()) {
        LogDebug("voxel grid drops {} extra field(s), the first is '{}'", cloud.extra_fields.size(),
                 cloud.extra_fields.front().name);
    }
    const VoxelPartition part = PartitionByVoxel(
        cloud,
        VoxelHashMapParams{.leaf_size = params.leaf_size, .num_threads = params.num_threads});

    // Voxels that give an output point, in ascending key order.
    const std::size_t min_points =
        static_cast<std::size_t>(std::max(1, params.min_points_per_voxel));
    std::vector<std::uint32_t> kept;
    std::size_t n_out = part.num_voxels();
    if (min_points > 1) {
        for (std::size_t v = 0; v < part.num_voxels(); ++v) {
            if (part.offsets[v + 1] - part.offsets[v] >= min_points) {
                kept.push_back(static_cast<std::uint32_t>(v));
            }
        }
        n_out = kept.size();
    }

    PointCloud out;
    out.points.resize(n_out);
    if (cloud.HasNormals()) out.normals.resize(n_out);
    if (cloud.HasColors()) out.colors.resize(n_out);
    if (cloud.HasCurvature()) out.curvature.resize(n_out);
    if (cloud.HasLabels()) out.labels.resize(n_out);
    if (cloud.HasIntensity()) out.intensity.resize(n_out);
    if (cloud.HasConfidence()) out.confidence.resize(n_out);

    const Eigen::Vector3f* pts = cloud.points.data();
    // Every output point is computed from its own voxel only, in a fixed order: the chunking
    // (and hence the thread count) cannot change a bit of the result.
    ParallelForChunks(
        n_out, params.num_threads,
        [&](std::size_t begin, std::size_t end) {
            std::vector<std::uint32_t> scratch;
            for (std::size_t j = begin; j < end; ++j) {
                const std::size_t v = min_points > 1 ? kept[j] : j;
                const std::span<const Index> idx = part.Points(v);
                double sx = 0.0, sy = 0.0, sz = 0.0;
                for (Index i : idx) {
                    sx += pts[i].x();
                    sy += pts[i].y();
                    sz += pts[i].z();
                }
                const auto n = static_cast<double>(idx.size());
                out.points[j] = {static_cast<float>(sx / n), static_cast<float>(sy / n),
                                 static_cast<float>(sz / n)};
                if (!out.colors.empty()) out.colors[j] = MeanColor(idx, cloud.colors);
                if (!out.normals.empty()) out.normals[j] = MeanNormal(idx, cloud.normals);
                if (!out.curvature.empty()) out.curvature[j] = MeanOfFinite(idx, cloud.curvature);
                if (!out.intensity.empty()) out.intensity[j] = MeanOfFinite(idx, cloud.intensity);
                if (!out.confidence.empty()) {
                    out.confidence[j] = MeanOfFinite(idx, cloud.confidence);
                }
                if (!out.labels.empty()) out.labels[j] = MajorityLabel(idx, cloud.labels, scratch);
            }
        },
        2048);
    out.SetUnorganized();
    out.sensor_origin = cloud.sensor_origin;
    out.sensor_orientation = cloud.sensor_orientation;
    return out;
}

}  // namespace multicue

#include "multicue/recognition/furniture_parts.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include <fmt/format.h>
#include <Eigen/Eigenvalues>

#include "multicue/core/exceptions.hpp"
#include "multicue/core/parallel.hpp"
#include "multicue/filters/voxel_grid.hpp"
#include "multicue/search/kdtree.hpp"
#include "multicue/surface/mls.hpp"
#include "multicue/surface/normals.hpp"

namespace multicue {
namespace {

double MsSince(std::chrono::steady_clock::time_point t) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count();
}

// The yaw of a part's frame (see FurniturePartFrame).
float PartFrameYaw(const PointCloud& sub, const Eigen::Vector3f& centroid, float bearing) {
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (const auto& p : sub.points) {
        const Eigen::Vector3d q = (p - centroid).cast<double>();
        cov += q * q.transpose();
    }
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
    const Eigen::Vector3d e = eig.eigenvalues().cwiseMax(0.0);  // ascending
    const Eigen::Vector3d n = eig.eigenvectors().col(0), major = eig.eigenvectors().col(2);
    const Eigen::Vector2d sight(std::cos(bearing), std::sin(bearing));
    Eigen::Vector2d x = sight;
    const bool planar = e[0] <= 0.1 * e[1];
    if (planar && n.head<2>().norm() > 0.7) {
        x = n.head<2>().normalized();  // upright plane: its normal
    } else if (std::abs(n.z()) > 0.7 && e[2] >= 2.25 * e[1] && major.head<2>().norm() > 0.7) {
        x = major.head<2>().normalized();  // lying and elongated: its long axis
    }
    if (x.dot(sight) < 0.0) x = -x;  // away from the sensor
    return static_cast<float>(std::atan2(x.y(), x.x()));
}

}  // namespace

const char* FurniturePartFrameName(FurniturePartFrame frame) {
    return frame == FurniturePartFrame::kBearing ? "bearing" : "part";
}

FurniturePartFrame ParseFurniturePartFrame(std::string_view name) {
    if (name == "bearing") return FurniturePartFrame::kBearing;
    if (name == "part") return FurniturePartFrame::kPart;
    throw InvalidArgument(fmt::format("part frame must be bearing or part, got '{}'", name));
}

void FurniturePartParams::Validate() const {
    if (!(voxel_size >= 0.0f) || !std::isfinite(voxel_size)) {
        throw InvalidArgument(
            fmt::format("furniture parts: voxel_size must be >= 0, got {}", voxel_size));
    }
    if (!(floor_margin >= 0.0f) || !std::isfinite(floor_margin)) {
        throw InvalidArgument(
            fmt::format("furniture parts: floor_margin must be >= 0, got {}", floor_margin));
    }
    if (!(max_height > floor_margin) || !std::isfinite(max_height)) {
        throw InvalidArgument(
            fmt::format("furniture parts: max_height must be > floor_margin ({}), got {}",
                        floor_margin, max_height));
    }
    if (!(normal_radius > 0.0f) || !std::isfinite(normal_radius)) {
        throw InvalidArgument(
            fmt::format("furniture parts: normal_radius must be > 0, got {}", normal_radius));
    }
    if (normal_k < 3) {
        throw InvalidArgument(
            fmt::format("furniture parts: normal_k must be >= 3, got {}", normal_k));
    }
    if (!(smoothing_radius >= 0.0f) || !std::isfinite(smoothing_radius)) {
        throw InvalidArgument(fmt::format("furniture parts: smoothing_radius must be >= 0, got {}",
                                          smoothing_radius));
    }
    region_growing.Validate();
    if (!region_growing.subset.empty()) {
        throw InvalidArgument("furniture parts: region_growing.subset must be empty");
    }
    if (min_part_points < 3) {
        throw InvalidArgument(
            fmt::format("furniture parts: min_part_points must be >= 3, got {}", min_part_points));
    }
    if (!(stats.radius > 0.0f) || !(stats.voxel_size > 0.0f)) {
        throw InvalidArgument("furniture parts: stats.radius and stats.voxel_size must be > 0");
    }
    if (num_threads < 0) {
        throw InvalidArgument(
            fmt::format("furniture parts: num_threads must be >= 0, got {}", num_threads));
    }
}

float EstimateFloorHeight(const PointCloud& cloud) {
    std::vector<float> z;
    z.reserve(cloud.size());
    for (const auto& p : cloud.points) {
        if (p.allFinite()) z.push_back(p.z());
    }
    if (z.size() < 100) return std::numeric_limits<float>::quiet_NaN();
    const auto [lo_it, hi_it] = std::minmax_element(z.begin(), z.end());
    const float lo = *lo_it, bin = 0.01f;
    const std::size_t n = static_cast<std::size_t>((*hi_it - lo) / bin) + 1;
    std::vector<std::size_t> count(n, 0);
    for (float v : z) ++count[std::min(n - 1, static_cast<std::size_t>((v - lo) / bin))];
    const std::size_t peak = *std::max_element(count.begin(), count.end());
    std::size_t b = 0;
    while (count[b] * 4 < peak) ++b;
    const float centre = lo + (static_cast<float>(b) + 0.5f) * bin;
    double sum = 0.0;
    std::size_t k = 0;
    for (float v : z) {
        if (std::abs(v - centre) <= 0.03f) sum += v, ++k;
    }
    return static_cast<float>(sum / static_cast<double>(k));
}

FurnitureParts ExtractFurnitureParts(const PointCloud& scan,
                                     const Eigen::Isometry3f& T_world_sensor,
                                     const FurniturePartParams& params) {
    params.Validate();
    if (!T_world_sensor.matrix().allFinite()) {
        throw InvalidArgument("furniture parts: the sensor pose is not finite");
    }
    const auto t0 = std::chrono::steady_clock::now();
    FurnitureParts out;
    out.sensor_origin = T_world_sensor * scan.sensor_origin;
    // The finite points in the world frame (labels and intensity kept for evaluation).
    PointCloud world;
    const bool labels = scan.labels.size() == scan.size();
    const bool intensity = scan.intensity.size() == scan.size();
    world.points.reserve(scan.size());
    for (std::size_t i = 0; i < scan.size(); ++i) {
        if (!scan.points[i].allFinite()) continue;
        world.points.push_back(T_world_sensor * scan.points[i]);
        if (labels) world.labels.push_back(scan.labels[i]);
        if (intensity) world.intensity.push_back(scan.intensity[i]);
    }
    if (params.estimate_floor) {
        const float h = EstimateFloorHeight(world);
        if (std::isfinite(h)) out.floor_height = h;
    }
    // Floor and ceiling away; the floor moved to z = 0.
    PointCloud cut;
    for (std::size_t i = 0; i < world.size(); ++i) {
        const float z = world.points[i].z() - out.floor_height;
        if (z < params.floor_margin || z > params.max_height) continue;
        cut.points.push_back(world.points[i] - Eigen::Vector3f(0, 0, out.floor_height));
        if (labels) cut.labels.push_back(world.labels[i]);
        if (intensity) cut.intensity.push_back(world.intensity[i]);
    }
    cut.width = static_cast<std::uint32_t>(cut.points.size());
    cut.height = 1;
    out.sensor_origin.z() -= out.floor_height;
    cut.sensor_origin = out.sensor_origin;
    PointCloud cloud =
        params.voxel_size > 0.0f
            ? VoxelGrid(cut, {.leaf_size = params.voxel_size, .num_threads = params.num_threads})
            : std::move(cut);
    cloud.sensor_origin = out.sensor_origin;
    if (cloud.size() < 3) {
        out.cloud = std::move(cloud);
        out.preprocess_ms = MsSince(t0);
        return out;
    }
    {
        const KdTree tree(cloud);
        if (params.smoothing_radius > 0.0f) {
            MlsParams mp;
            mp.radius = params.smoothing_radius;
            mp.polynomial_order = 2;
            mp.max_iterations = 30;
            mp.viewpoint = out.sensor_origin;
            mp.num_threads = params.num_threads;
            MlsResult mls = MovingLeastSquares(cloud, tree, mp);
            PointCloud smoothed = std::move(mls.cloud);
            if (labels) {
                smoothed.labels.resize(smoothed.size());
                for (std::size_t i = 0; i < smoothed.size(); ++i) {
                    smoothed.labels[i] = cloud.labels[mls.source[i]];
                }
            }
            cloud = std::move(smoothed);
            cloud.sensor_origin = out.sensor_origin;
        }
    }
    const KdTree tree(cloud);
    if (params.smoothing_radius <= 0.0f || cloud.normals.size() != cloud.size()) {
        NormalsResult n = EstimateNormals(cloud, tree,
                                          {.k = params.normal_k,
                                           .radius = params.normal_radius,
                                           .viewpoint = out.sensor_origin,
                                           .num_threads = params.num_threads});
        SetNormals(cloud, std::move(n));
    } else {
        // MLS normals with the PCA curvature of the smoothed points (region growing seeds).
        NormalsResult n = EstimateNormals(cloud, tree,
                                          {.k = params.normal_k,
                                           .radius = params.normal_radius,
                                           .viewpoint = out.sensor_origin,
                                           .num_threads = params.num_threads});
        cloud.curvature = std::move(n.curvature);
    }
    out.preprocess_ms = MsSince(t0);
    const auto t1 = std::chrono::steady_clock::now();
    const RegionGrowingResult rg = RegionGrowing(cloud, tree, params.region_growing);
    out.segment_ms = MsSince(t1);
    const auto t2 = std::chrono::steady_clock::now();
    std::vector<const Indices*> kept;
    for (const auto& p : rg.parts) {
        if (p.size() >= params.min_part_points) kept.push_back(&p);
    }
    out.parts.resize(kept.size());
    PartStatsParams stats = params.stats;
    stats.num_threads = 1;
    ParallelFor(
        kept.size(), params.num_threads,
        [&](std::size_t k) {
            FurniturePart& part = out.parts[k];
            part.indices = *kept[k];
            PointCloud sub;
            sub.points.reserve(part.indices.size());
            Eigen::Vector3d sum = Eigen::Vector3d::Zero();
            part.top = -std::numeric_limits<float>::infinity();
            for (Index i : part.indices) {
                sub.points.push_back(cloud.points[i]);
                sub.normals.push_back(cloud.normals[i]);
                sub.curvature.push_back(cloud.curvature[i]);
                sum += cloud.points[i].cast<double>();
                part.top = std::max(part.top, cloud.points[i].z());
            }
            sub.width = static_cast<std::uint32_t>(sub.points.size());
            sub.sensor_origin = out.sensor_origin;
            part.centroid = (sum / static_cast<double>(part.indices.size())).cast<float>();
            const Eigen::Vector2f d = (part.centroid - out.sensor_origin).head<2>();
            part.bearing = std::atan2(d.y(), d.x());
            part.frame_yaw = params.frame == FurniturePartFrame::kPart
                                 ? PartFrameYaw(sub, part.centroid, part.bearing)
                                 : part.bearing;
            part.features = ComputePartStatistics(sub, stats);
            part.extent = part.features[15];
        },
        1);
    out.features_ms = MsSince(t2);
    out.cloud = std::move(cloud);
    return out;
}

}  // namespace multicue

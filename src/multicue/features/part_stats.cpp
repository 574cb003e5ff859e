#include "multicue/features/part_stats.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include <Eigen/Eigenvalues>

#include "multicue/core/exceptions.hpp"
#include "multicue/core/parallel.hpp"
#include "multicue/search/voxel_hash_map.hpp"
#include "multicue/surface/normals.hpp"

namespace multicue {
namespace {

float Ratio(double a, double b) { return b > 0.0 ? static_cast<float>(a / b) : 0.0f; }

// Feature 1 (section 4.2.3.1): the share of the usable points on the part's boundary.
float BoundaryShare(const PointCloud& part, const KdTree& tree, const PartStatsParams& params) {
    const auto boundary = EstimateBoundaryPoints(part, tree, params.radius, params.boundary_angle,
                                                 params.num_threads);
    std::size_t usable = 0, on_boundary = 0;
    for (std::size_t i = 0; i < part.size(); ++i) {
        if (!detail::IsUsable(part, i)) continue;
        ++usable;
        on_boundary += boundary[i];
    }
    return Ratio(static_cast<double>(on_boundary), static_cast<double>(usable));
}

// Feature 2: the mean curvature (surface variation) of the points, the cloud's own when it has
// one per point, else estimated with the part radius.
float MeanCurvature(const PointCloud& part, const KdTree& tree, const PartStatsParams& params) {
    std::vector<float> curvature;
    if (part.HasCurvature() && part.curvature.size() == part.size()) {
        curvature = part.curvature;
    } else {
        curvature = EstimateNormals(part, tree,
                                    {.radius = params.radius, .num_threads = params.num_threads})
                        .curvature;
    }
    double curvature_sum = 0.0;
    std::size_t curvature_count = 0;
    for (float c : curvature) {
        if (!std::isfinite(c)) continue;
        curvature_sum += c;
        ++curvature_count;
    }
    return Ratio(curvature_sum, static_cast<double>(curvature_count));
}

// Feature 3: the volume of the occupied voxels.
double OccupiedVolume(const PointCloud& part, float voxel_size) {
    const VoxelPartition voxels =
        PartitionByVoxel(part, {.leaf_size = voxel_size, .num_threads = 1});
    const double voxel_volume = std::pow(static_cast<double>(voxel_size), 3);
    return static_cast<double>(voxels.num_voxels()) * voxel_volume;
}

// The principal axes of the finite points: their mean, the covariance's eigenvalues (ascending,
// clamped at 0) and eigenvectors.
struct PrincipalAxes {
    Eigen::Vector3d mean;
    Eigen::Vector3d e;
    Eigen::Matrix3d axes;
};

PrincipalAxes PrincipalAxesOf(const std::vector<Eigen::Vector3d>& pts) {
    PrincipalAxes pa;
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (const auto& p : pts) mean += p;
    mean /= static_cast<double>(pts.size());
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (const auto& p : pts) cov += (p - mean) * (p - mean).transpose();
    cov /= static_cast<double>(pts.size());
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
    pa.mean = mean;
    pa.e = eig.eigenvalues().cwiseMax(0.0);  // ascending
    pa.axes = eig.eigenvectors();
    return pa;
}

// Features 5, 7 and 8 of section 4.2.3.1 along each principal axis (entries 9-11, 13-18, 20-22):
// the spread, the extent, the shorter half-extent over the longer, and spread over extent;
// returns the extents.
std::array<double, 3> SetAxisStatistics(const std::vector<Eigen::Vector3d>& pts,
                                        const PrincipalAxes& pa, FeatureVector& f) {
    std::array<double, 3> extent;
    double spread[3];
    for (int k = 0; k < 3; ++k) {
        const Eigen::Vector3d axis = pa.axes.col(k);
        double lo = 0.0, hi = 0.0, sq = 0.0;
        for (const auto& p : pts) {
            const double t = axis.dot(p - pa.mean);
            lo = std::min(lo, t);
            hi = std::max(hi, t);
            sq += t * t;
        }
        spread[k] = std::sqrt(sq / static_cast<double>(pts.size()));
        extent[k] = hi - lo;
        f[9 + k] = static_cast<float>(spread[k]);
        f[13 + k] = static_cast<float>(extent[k]);
        f[16 + k] = Ratio(std::min(hi, -lo), std::max(hi, -lo));
        f[20 + k] = Ratio(spread[k], extent[k]);
    }
    return extent;
}

}  // namespace

std::vector<std::uint8_t> EstimateBoundaryPoints(const PointCloud& cloud, const KdTree& tree,
                                                 float radius, float angle, int num_threads) {
    detail::CheckPositive(radius, "boundary radius");
    detail::CheckPositive(angle, "boundary_angle");
    detail::CheckThreads(num_threads);
    detail::CheckNormals(cloud, "boundary estimation");
    detail::CheckTree(cloud, tree);
    std::vector<std::uint8_t> boundary(cloud.size(), 0);
    ParallelForChunks(
        cloud.size(), num_threads,
        [&](std::size_t begin, std::size_t end) {
            Indices nn;
            std::vector<float> d2;
            std::vector<float> angles;
            for (std::size_t i = begin; i < end; ++i) {
                if (!detail::IsUsable(cloud, i)) continue;
                const Eigen::Vector3f& p = cloud.points[i];
                const Eigen::Vector3f n = cloud.normals[i].normalized();
                // Any orthonormal basis (u, v) of the tangent plane.
                const Eigen::Vector3f u = n.unitOrthogonal();
                const Eigen::Vector3f v = n.cross(u);
                detail::RadiusNeighbours(tree, p, radius, nn, d2);
                angles.clear();
                for (std::size_t k = 0; k < nn.size(); ++k) {
                    if (d2[k] == 0.0f) continue;
                    const Eigen::Vector3f d = cloud.points[nn[k]] - p;
                    angles.push_back(std::atan2(v.dot(d), u.dot(d)));
                }
                if (angles.size() < 2) {
                    boundary[i] = 1;  // isolated: nothing around it on any side
                    continue;
                }
                std::sort(angles.begin(), angles.end());
                float gap = angles.front() + 2.0f * static_cast<float>(M_PI) - angles.back();
                for (std::size_t k = 1; k < angles.size(); ++k) {
                    gap = std::max(gap, angles[k] - angles[k - 1]);
                }
                boundary[i] = gap > angle ? 1 : 0;
            }
        },
        256);
    return boundary;
}

FeatureVector ComputePartStatistics(const PointCloud& part, const PartStatsParams& params) {
    detail::CheckPositive(params.radius, "part radius");
    detail::CheckPositive(params.voxel_size, "part voxel_size");
    detail::CheckPositive(params.boundary_angle, "boundary_angle");
    detail::CheckThreads(params.num_threads);
    if (!params.up.allFinite() || params.up.norm() == 0.0f) {
        throw InvalidArgument("part statistics: `up` must be a finite non-zero vector");
    }
    FeatureVector f = FeatureVector::Zero(kPartStatsSize);
    if (part.empty()) return f;
    detail::CheckNormals(part, "part statistics");

    std::vector<Eigen::Vector3d> pts;
    pts.reserve(part.size());
    for (const auto& p : part.points) {
        if (p.allFinite()) pts.push_back(p.cast<double>());
    }
    if (pts.size() < 3) return f;

    const KdTree tree(part);
    f[0] = BoundaryShare(part, tree, params);
    f[1] = MeanCurvature(part, tree, params);
    const double occupied = OccupiedVolume(part, params.voxel_size);
    f[2] = static_cast<float>(occupied);
    const PrincipalAxes pa = PrincipalAxesOf(pts);
    const Eigen::Vector3d& e = pa.e;
    const double sum = e.sum();
    // 3-8: eigenvalue proportions.
    f[3] = Ratio(e[0], e[1]);
    f[4] = Ratio(e[1], e[2]);
    f[5] = Ratio(e[0], e[2]);
    f[6] = Ratio(e[0], sum);
    f[7] = Ratio(e[1], sum);
    f[8] = Ratio(e[2], sum);
    const std::array<double, 3> extent = SetAxisStatistics(pts, pa, f);
    // 12: orientation of the normal direction.
    f[12] = static_cast<float>(std::abs(pa.axes.col(0).dot(params.up.cast<double>().normalized())));
    f[19] = Ratio(extent[0], extent[1]);
    // 23: occupied share of the oriented bounding box.
    const double vs = params.voxel_size;
    const double box = (extent[0] + vs) * (extent[1] + vs) * (extent[2] + vs);
    // Whole voxels can overhang a thin slanted part's box: capped at 1.
    f[23] = std::min(1.0f, Ratio(occupied, box));
    return f;
}

}  // namespace multicue

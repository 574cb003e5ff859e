#include "multicue/registration/planes.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <fmt/format.h>
#include <Eigen/Eigenvalues>

#include "multicue/core/exceptions.hpp"
#include "multicue/segmentation/region_growing.hpp"

namespace multicue {
namespace {

double DegToRad(double deg) { return deg * std::numbers::pi / 180.0; }

// Least-squares plane of the points `indices`, oriented towards `viewpoint`.
bool FitPatch(const PointCloud& cloud, Indices indices, const Eigen::Vector3d& viewpoint,
              PlanarPatch& patch) {
    if (indices.size() < 3) return false;
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (Index i : indices) mean += cloud.points[i].cast<double>();
    mean /= static_cast<double>(indices.size());
    Eigen::Matrix3d S = Eigen::Matrix3d::Zero();
    for (Index i : indices) {
        const Eigen::Vector3d e = cloud.points[i].cast<double>() - mean;
        S.noalias() += e * e.transpose();
    }
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(S);
    if (eig.info() != Eigen::Success) return false;
    Eigen::Vector3d n = eig.eigenvectors().col(0);
    if (n.dot(viewpoint - mean) < 0.0) n = -n;
    const double count = static_cast<double>(indices.size());
    patch.normal = n;
    patch.d = -n.dot(mean);
    patch.centroid = mean;
    patch.scatter = S;
    patch.extent = {std::sqrt(std::max(0.0, eig.eigenvalues()(2)) / count),
                    std::sqrt(std::max(0.0, eig.eigenvalues()(1)) / count)};
    patch.rmse = std::sqrt(std::max(0.0, eig.eigenvalues()(0)) / count);
    patch.indices = std::move(indices);
    return true;
}

}  // namespace

PlanarPatch TransformPatch(const PlanarPatch& patch, const Eigen::Isometry3d& T) {
    PlanarPatch out = patch;
    out.normal = T.linear() * patch.normal;
    out.centroid = T * patch.centroid;
    out.d = -out.normal.dot(out.centroid);
    out.scatter = T.linear() * patch.scatter * T.linear().transpose();
    return out;
}

void PlaneExtractionParams::Validate() const {
    if (!(radius > 0.0f) || !std::isfinite(radius)) {
        throw InvalidArgument(fmt::format("plane extraction radius must be > 0, got {}", radius));
    }
    if (!(max_angle_deg > 0.0f && max_angle_deg <= 90.0f)) {
        throw InvalidArgument(fmt::format(
            "plane extraction max_angle_deg must be in (0, 90], got {}", max_angle_deg));
    }
    if (min_points < 3) {
        throw InvalidArgument(
            fmt::format("plane extraction min_points must be >= 3, got {}", min_points));
    }
    if (!(max_rmse > 0.0f) || !std::isfinite(max_rmse)) {
        throw InvalidArgument(
            fmt::format("plane extraction max_rmse must be > 0, got {}", max_rmse));
    }
    if (!(min_extent >= 0.0f) || !std::isfinite(min_extent) || !(depth_noise >= 0.0f) ||
        !std::isfinite(depth_noise)) {
        throw InvalidArgument(
            fmt::format("plane extraction min_extent and depth_noise must be >= 0, got {} and {}",
                        min_extent, depth_noise));
    }
    if (max_planes < 1) {
        throw InvalidArgument(
            fmt::format("plane extraction max_planes must be >= 1, got {}", max_planes));
    }
    if (!(merge_angle_deg >= 0.0f && merge_angle_deg < 90.0f) || !(merge_distance >= 0.0f)) {
        throw InvalidArgument(fmt::format(
            "plane extraction merge_angle_deg must be in [0, 90) and merge_distance >= 0, got {} "
            "and {}",
            merge_angle_deg, merge_distance));
    }
}

std::vector<PlanarPatch> ExtractPlanarPatches(const PointCloud& cloud, const KdTree& tree,
                                              const PlaneExtractionParams& params) {
    params.Validate();
    if (cloud.empty()) return {};
    if (!cloud.HasNormals() || !cloud.HasCurvature()) {
        throw DataError("plane extraction needs normals and curvature (estimate them first)");
    }
    RegionGrowingParams growing;
    growing.radius = params.radius;
    growing.max_angle_deg = params.max_angle_deg;
    growing.min_part_size = params.min_points;
    growing.discard_small_parts = true;
    const auto regions = RegionGrowing(cloud, tree, growing);
    const Eigen::Vector3d viewpoint = cloud.sensor_origin.cast<double>();

    auto acceptable = [&](const PlanarPatch& p) {
        if (p.rmse > params.max_rmse || p.extent(1) < params.min_extent) return false;
        const double d = (p.centroid - viewpoint).norm();
        return params.depth_noise * d * d <= params.max_rmse;
    };
    std::vector<PlanarPatch> patches;
    for (const auto& part : regions.parts) {
        PlanarPatch p;
        if (part.size() >= params.min_points && FitPatch(cloud, part, viewpoint, p) &&
            acceptable(p)) {
            patches.push_back(std::move(p));
        }
    }
    // Merge patches of one plane (largest first): a table top cut into pieces by objects.
    std::stable_sort(patches.begin(), patches.end(),
                     [](const auto& a, const auto& b) { return a.size() > b.size(); });
    const double merge_cos = std::cos(DegToRad(params.merge_angle_deg));
    std::vector<PlanarPatch> merged;
    for (auto& p : patches) {
        bool joined = false;
        for (auto& m : merged) {
            if (m.normal.dot(p.normal) < merge_cos) continue;
            if (std::abs(m.normal.dot(p.centroid) + m.d) > params.merge_distance) continue;
            Indices all = m.indices;
            all.insert(all.end(), p.indices.begin(), p.indices.end());
            std::sort(all.begin(), all.end());
            PlanarPatch joint;
            if (FitPatch(cloud, std::move(all), viewpoint, joint) &&
                joint.rmse <= params.max_rmse) {
                m = std::move(joint);
                joined = true;
                break;
            }
        }
        if (!joined) merged.push_back(std::move(p));
    }
    std::stable_sort(merged.begin(), merged.end(),
                     [](const auto& a, const auto& b) { return a.size() > b.size(); });
    if (merged.size() > static_cast<std::size_t>(params.max_planes)) {
        merged.resize(static_cast<std::size_t>(params.max_planes));
    }
    return merged;
}

void PlaneMatchParams::Validate() const {
    if (!(max_angle_deg > 0.0f && max_angle_deg <= 90.0f)) {
        throw InvalidArgument(
            fmt::format("plane matching max_angle_deg must be in (0, 90], got {}", max_angle_deg));
    }
    if (!(max_offset > 0.0f) || !std::isfinite(max_offset)) {
        throw InvalidArgument(
            fmt::format("plane matching max_offset must be > 0, got {}", max_offset));
    }
    if (!(centroid_slack >= 0.0f) || !std::isfinite(centroid_slack)) {
        throw InvalidArgument(
            fmt::format("plane matching centroid_slack must be >= 0, got {}", centroid_slack));
    }
}

std::vector<PlanePair> MatchPlanes(const std::vector<PlanarPatch>& source,
                                   const std::vector<PlanarPatch>& target,
                                   const Eigen::Isometry3d& T_target_source,
                                   const PlaneMatchParams& params) {
    params.Validate();
    const double min_cos = std::cos(DegToRad(params.max_angle_deg));
    std::vector<PlanePair> pairs;
    for (std::size_t s = 0; s < source.size(); ++s) {
        const Eigen::Vector3d n = T_target_source.linear() * source[s].normal;
        const Eigen::Vector3d c = T_target_source * source[s].centroid;
        double best = std::numeric_limits<double>::infinity();
        std::size_t best_t = 0;
        for (std::size_t t = 0; t < target.size(); ++t) {
            if (n.dot(target[t].normal) < min_cos) continue;
            const double offset = std::abs(target[t].normal.dot(c) + target[t].d);
            if (offset > params.max_offset) continue;
            // 2.5 RMS spreads cover most of a patch (a uniform rectangle's half side is 1.7).
            const double reach =
                2.5 * (std::max(source[s].extent(0), target[t].extent(0))) + params.centroid_slack;
            const double dist = (c - target[t].centroid).norm();
            if (dist > reach) continue;
            // The nearest plane first (parallel planes a few centimetres apart: a box top and
            // the table), then the nearest centroid (coplanar faces side by side).
            const double score = offset / params.max_offset + dist / reach;
            if (score >= best) continue;
            best = score;
            best_t = t;
        }
        if (std::isfinite(best)) pairs.push_back({s, best_t});
    }
    return pairs;
}

double AddPlaneTerms(const std::vector<PlanarPatch>& source, const std::vector<PlanarPatch>& target,
                     const std::vector<PlanePair>& pairs, const std::vector<double>& weights,
                     const Eigen::Isometry3d& T_target_source, const Eigen::Vector3d& center,
                     Matrix6d& H, Vector6d& g) {
    if (weights.size() != pairs.size()) {
        throw InvalidArgument(
            fmt::format("plane terms: {} pairs but {} weights", pairs.size(), weights.size()));
    }
    double cost = 0.0;
    const Eigen::Matrix3d R = T_target_source.linear();
    for (std::size_t k = 0; k < pairs.size(); ++k) {
        const PlanePair& pair = pairs[k];
        const double weight = weights[k];
        const PlanarPatch& ps = source[pair.source];
        const Eigen::Vector3d& n = target[pair.target].normal;
        const double d = target[pair.target].d;
        const double N = static_cast<double>(ps.size());
        const Eigen::Vector3d u = T_target_source * ps.centroid - center;  // mean about center
        const Eigen::Matrix3d C = R * ps.scatter * R.transpose();          // scatter about mean
        const double r0 = n.dot(u + center) + d;                           // residual of the mean
        // a_i = (p_i - c) x n = -[n]x (p_i - c); sums over the patch from its moments.
        Eigen::Matrix3d Nx;
        Nx << 0, -n.z(), n.y(), n.z(), 0, -n.x(), -n.y(), n.x(), 0;
        const Eigen::Matrix3d A = Nx * (C + N * u * u.transpose()) * Nx.transpose();
        const Eigen::Vector3d sum_a = -N * (Nx * u);
        Matrix6d h;
        h.topLeftCorner<3, 3>() = A;
        h.topRightCorner<3, 3>() = sum_a * n.transpose();
        h.bottomLeftCorner<3, 3>() = n * sum_a.transpose();
        h.bottomRightCorner<3, 3>() = N * n * n.transpose();
        Vector6d gr;
        gr.head<3>() = -(Nx * (C * n + N * r0 * u));
        gr.tail<3>() = N * r0 * n;
        H += weight * h;
        g += weight * gr;
        cost += weight * (n.dot(C * n) + N * r0 * r0);
    }
    return cost;
}

}  // namespace multicue

#include "multicue/segmentation/support_plane.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/core/logging.hpp"
#include "multicue/search/kdtree.hpp"
#include "multicue/segmentation/euclidean_clustering.hpp"
#include "multicue/segmentation/polygonal_prism.hpp"
#include "multicue/segmentation/sac_plane.hpp"

namespace multicue {
namespace {

constexpr float kDegToRad = static_cast<float>(M_PI) / 180.0f;

void CheckParams(const SupportPlaneParams& p) {
    if (p.up && (!p.up->allFinite() || p.up->norm() < 1e-6f)) {
        throw InvalidArgument("support plane: up must be a finite non-zero vector");
    }
    auto angle_ok = [](float a) { return a >= 0.0f && a <= 90.0f; };
    if (!angle_ok(p.max_tilt_deg) || !angle_ok(p.camera_tilt_deg)) {
        throw InvalidArgument(
            fmt::format("support plane: tilt angles must be in [0, 90] degrees, got {} and {}",
                        p.max_tilt_deg, p.camera_tilt_deg));
    }
    if (!(p.distance_threshold > 0.0f) || !std::isfinite(p.distance_threshold)) {
        throw InvalidArgument(fmt::format("support plane: distance_threshold must be > 0, got {}",
                                          p.distance_threshold));
    }
    if (p.max_candidates < 1) {
        throw InvalidArgument(
            fmt::format("support plane: max_candidates must be >= 1, got {}", p.max_candidates));
    }
    if (!(p.min_inlier_fraction >= 0.0f && p.min_inlier_fraction <= 1.0f) ||
        !(p.size_ratio_to_compete >= 0.0f && p.size_ratio_to_compete <= 1.0f) ||
        !(p.raised_ratio >= 0.0f && p.raised_ratio <= 1.0f)) {
        throw InvalidArgument("support plane: fractions must be in [0, 1]");
    }
    if (!std::isfinite(p.raised_gap))
        throw InvalidArgument("support plane: raised_gap must be finite");
    if (p.max_samples < 3) {
        throw InvalidArgument(
            fmt::format("support plane: max_samples must be >= 3, got {}", p.max_samples));
    }
    if (!(p.cluster_tolerance > 0.0f)) {
        throw InvalidArgument(fmt::format("support plane: cluster_tolerance must be > 0, got {}",
                                          p.cluster_tolerance));
    }
}

bool IsIdentityPose(const PointCloud& c) {
    return c.sensor_origin.norm() < 1e-9f &&
           c.sensor_orientation.coeffs().isApprox(Eigen::Quaternionf::Identity().coeffs(), 1e-6f);
}

// Largest connected patch of the plane's inliers: other surfaces at the same height (a second
// table, a shelf seen through a gap) are left out.
Indices LargestPatch(const PointCloud& cloud, const Indices& inliers, float tolerance) {
    ClusteringResult clusters;
    if (cloud.IsOrganized()) {
        clusters = EuclideanClusteringOrganized(
            cloud, {.tolerance = tolerance, .subset = inliers, .half_window = 1});
    } else {
        const KdTree tree(cloud, inliers);
        clusters = EuclideanClustering(cloud, tree, {.tolerance = tolerance, .subset = inliers});
    }
    if (clusters.clusters.empty()) return {};
    return std::move(clusters.clusters.front());
}

// The cloud's finite points: the candidates and the table are taken among them.
Indices FinitePoints(const PointCloud& cloud) {
    Indices finite;
    finite.reserve(cloud.size());
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        if (cloud.IsFinite(i)) finite.push_back(static_cast<Index>(i));
    }
    return finite;
}

// Up direction and how strictly the table must follow it: the given one, else world z when the
// cloud has a sensor pose, else the camera's -y with the looser camera tilt.
struct UpPrior {
    std::optional<Eigen::Vector3f> axis;
    float max_angle = 0.0f;
    UpSource source = UpSource::kDominant;
};

UpPrior ChooseUp(const PointCloud& cloud, const SupportPlaneParams& params) {
    UpPrior up;
    up.max_angle = params.max_tilt_deg * kDegToRad;
    if (params.up) {
        up.axis = params.up->normalized();
        up.source = UpSource::kGiven;
    } else if (!IsIdentityPose(cloud)) {
        up.axis = Eigen::Vector3f::UnitZ();
        up.source = UpSource::kViewpoint;
    } else {
        up.axis = -Eigen::Vector3f::UnitY();
        up.max_angle = params.camera_tilt_deg * kDegToRad;
        up.source = UpSource::kCamera;
    }
    return up;
}

// Candidate planes along up, extracted one after another from a strided subsample (each from the
// points the previous ones left), while they hold at least min_inlier_fraction of it.
std::vector<PlaneFit> ExtractCandidates(const PointCloud& cloud, const Indices& finite,
                                        const UpPrior& up, const SupportPlaneParams& params) {
    Indices remaining;
    const std::size_t stride = (finite.size() + params.max_samples - 1) / params.max_samples;
    for (std::size_t k = 0; k < finite.size(); k += stride) remaining.push_back(finite[k]);
    const std::size_t sample_size = remaining.size();
    const auto min_inliers = static_cast<std::size_t>(
        std::max(3.0f, params.min_inlier_fraction * static_cast<float>(sample_size)));

    std::vector<PlaneFit> candidates;
    for (int c = 0; c < params.max_candidates && remaining.size() >= min_inliers; ++c) {
        PlaneFitParams fp;
        fp.sac.distance_threshold = params.distance_threshold;
        fp.sac.seed = params.seed + static_cast<std::uint64_t>(c);
        fp.sac.num_threads = params.num_threads;
        fp.axis = up.axis;
        fp.max_angle = up.max_angle;
        fp.viewpoint = cloud.sensor_origin;
        PlaneFit fit = FitPlane(cloud, remaining, fp);
        if (!fit.found || fit.inliers.size() < min_inliers) break;
        Indices rest;
        std::set_difference(remaining.begin(), remaining.end(), fit.inliers.begin(),
                            fit.inliers.end(), std::back_inserter(rest));
        remaining = std::move(rest);
        candidates.push_back(std::move(fit));
    }
    return candidates;
}

// The chosen candidate (section 2.4): the largest plane nearest the viewpoint, unless a raised
// table stands on it (see SupportPlaneParams::raised_gap).
const PlaneFit& ChooseCandidate(const std::vector<PlaneFit>& candidates, const PointCloud& cloud,
                                const SupportPlaneParams& params) {
    std::size_t largest = 0;
    for (const auto& c : candidates) largest = std::max(largest, c.inliers.size());
    const PlaneFit* best = nullptr;
    float best_distance = 0.0f;
    for (const auto& c : candidates) {
        if (static_cast<float>(c.inliers.size()) <
            params.size_ratio_to_compete * static_cast<float>(largest)) {
            continue;
        }
        const float d = std::abs(c.plane.head<3>().dot(cloud.sensor_origin) + c.plane.w());
        if (best == nullptr || d < best_distance) {
            best = &c;
            best_distance = d;
        }
    }
    if (params.raised_gap > 0.0f) {
        // A robot sees the floor around a small table: the largest parallel candidate at least
        // raised_gap nearer the viewpoint is the table standing on it.
        const PlaneFit* chosen = best;
        const float floor_distance = best_distance;
        for (const auto& c : candidates) {
            if (&c == chosen || static_cast<float>(c.inliers.size()) <
                                    params.raised_ratio * static_cast<float>(largest)) {
                continue;
            }
            const float d = std::abs(c.plane.head<3>().dot(cloud.sensor_origin) + c.plane.w());
            const bool parallel = std::abs(c.plane.head<3>().dot(chosen->plane.head<3>())) > 0.95f;
            if (parallel && d <= floor_distance - params.raised_gap &&
                (best == chosen || c.inliers.size() > best->inliers.size())) {
                best = &c;
                best_distance = d;
            }
        }
    }
    return *best;
}

// All points of the full cloud within the distance threshold of the plane.
Indices PointsOnPlane(const PointCloud& cloud, const Indices& finite, const Eigen::Vector4f& plane,
                      float distance_threshold) {
    Indices on_plane;
    for (Index i : finite) {
        if (std::abs(plane.head<3>().dot(cloud.points[i]) + plane.w()) <= distance_threshold) {
            on_plane.push_back(i);
        }
    }
    return on_plane;
}

}  // namespace

void SupportPlaneParams::Validate() const { CheckParams(*this); }

SupportPlane FindSupportPlane(const PointCloud& cloud, const SupportPlaneParams& params) {
    CheckParams(params);
    SupportPlane result;
    const Indices finite = FinitePoints(cloud);
    if (finite.size() < 3) return result;

    const UpPrior up = ChooseUp(cloud, params);
    result.up_source = up.source;
    const std::vector<PlaneFit> candidates = ExtractCandidates(cloud, finite, up, params);
    result.candidates = static_cast<int>(candidates.size());
    if (candidates.empty()) return result;
    Eigen::Vector4f plane = ChooseCandidate(candidates, cloud, params).plane;
    // Normal towards the viewpoint: objects stand on the side the sensor sees.
    if (plane.head<3>().dot(cloud.sensor_origin) + plane.w() < 0.0f) plane = -plane;

    // All points of the full cloud on the plane, then its largest connected patch.
    const Indices on_plane = PointsOnPlane(cloud, finite, plane, params.distance_threshold);
    Indices table = LargestPatch(cloud, on_plane, params.cluster_tolerance);
    if (table.size() < 3) return result;
    result.found = true;
    result.plane = plane;
    result.up = plane.head<3>();
    result.hull = PlaneConvexHull(cloud, table, plane);
    result.inliers = std::move(table);
    LogDebug("support plane ({:.3f}, {:.3f}, {:.3f}, {:.3f}) with {} points from {} candidates",
             plane.x(), plane.y(), plane.z(), plane.w(), result.inliers.size(), result.candidates);
    return result;
}

TableRegion FindTableRegion(const PointCloud& cloud, const SupportPlaneParams& support,
                            const PrismParams& prism) {
    support.Validate();
    prism.Validate();
    TableRegion region;
    region.support = FindSupportPlane(cloud, support);
    const SupportPlane& s = region.support;
    if (s.found && s.hull.size() >= 3)
        region.points = PolygonalPrism(cloud, s.plane, s.hull, prism);
    if (region.points.empty()) {
        region.support = SupportPlane{};
        region.points = FinitePoints(cloud);
    }
    return region;
}

}  // namespace multicue

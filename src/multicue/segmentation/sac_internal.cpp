#include "multicue/segmentation/sac_internal.hpp"

#include <numbers>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"

namespace multicue::sac_internal {

Moments ComputeMoments(const PointCloud& cloud, std::span<const Index> idx) {
    Moments m;
    if (idx.empty()) return m;
    const Eigen::Vector3d origin = cloud.points[idx.front()].cast<double>();
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    Eigen::Matrix3d sum_sq = Eigen::Matrix3d::Zero();
    for (Index i : idx) {
        const Eigen::Vector3d p = cloud.points[i].cast<double>() - origin;
        sum += p;
        sum_sq += p * p.transpose();
    }
    const double n = static_cast<double>(idx.size());
    const Eigen::Vector3d mean = sum / n;
    m.mean = origin + mean;
    m.covariance = sum_sq / n - mean * mean.transpose();
    return m;
}

void OrthonormalBasis(const Eigen::Vector3d& a, Eigen::Vector3d& u, Eigen::Vector3d& v) {
    // Cross with the coordinate axis least aligned with a: well conditioned for every a.
    Eigen::Index k = 0;
    a.cwiseAbs().minCoeff(&k);
    u = a.cross(Eigen::Vector3d::Unit(k)).normalized();
    v = a.cross(u);
}

Eigen::Vector3f NormalizedAxis(const Eigen::Vector3f& axis, const char* what) {
    const float norm = axis.norm();
    if (!axis.allFinite() || !(norm > 0.0f) || !std::isfinite(norm)) {
        throw InvalidArgument(fmt::format("{} axis must be finite and non-zero, got ({}, {}, {})",
                                          what, axis.x(), axis.y(), axis.z()));
    }
    return axis / norm;
}

void ValidateMaxAngle(float max_angle, const char* what) {
    if (!(max_angle >= 0.0f && max_angle <= std::numbers::pi_v<float> / 2.0f)) {
        throw InvalidArgument(
            fmt::format("{} max_angle must be in [0, pi/2] rad, got {}", what, max_angle));
    }
}

void ValidateRadiusLimits(float min_radius, float max_radius, const char* what) {
    if (!(min_radius >= 0.0f) || !std::isfinite(min_radius)) {
        throw InvalidArgument(
            fmt::format("{} min_radius must be finite and >= 0, got {}", what, min_radius));
    }
    if (!(max_radius >= min_radius)) {
        throw InvalidArgument(fmt::format("{} max_radius ({}) must be >= min_radius ({})", what,
                                          max_radius, min_radius));
    }
}

Eigen::Vector3f CanonicalDirection(const Eigen::Vector3f& v) {
    Eigen::Index k = 0;
    v.cwiseAbs().maxCoeff(&k);
    return v[k] < 0.0f ? Eigen::Vector3f(-v) : v;
}

}  // namespace multicue::sac_internal

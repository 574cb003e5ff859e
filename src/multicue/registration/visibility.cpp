#include "multicue/registration/visibility.hpp"

#include <cmath>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/registration/correspondences.hpp"

namespace multicue {

void FreeSpaceParams::Validate() const {
    if (!(tolerance > 0.0f) || !std::isfinite(tolerance)) {
        throw InvalidArgument(fmt::format("free-space tolerance must be > 0, got {}", tolerance));
    }
    if (!(depth_noise >= 0.0f) || !std::isfinite(depth_noise)) {
        throw InvalidArgument(
            fmt::format("free-space depth_noise must be >= 0, got {}", depth_noise));
    }
    if (max_points < 1) throw InvalidArgument("free-space max_points must be >= 1");
    if (!(max_gap >= 0.0f) || !std::isfinite(max_gap)) {
        throw InvalidArgument(fmt::format("free-space max_gap must be >= 0, got {}", max_gap));
    }
    if (!(max_violation > 0.0 && max_violation <= 1.0)) {
        throw InvalidArgument(
            fmt::format("free-space max_violation must be in (0, 1], got {}", max_violation));
    }
}

FreeSpaceCheck CheckFreeSpace(const PointCloud& source, const PointCloud& frame,
                              const Eigen::Isometry3d& T_frame_source,
                              const FreeSpaceParams& params) {
    params.Validate();
    FreeSpaceCheck check;
    const auto pinhole = EstimatePinhole(frame);
    if (!pinhole) return check;
    check.applicable = true;
    Indices finite;
    for (std::size_t i = 0; i < source.size(); ++i) {
        if (source.IsFinite(i)) finite.push_back(static_cast<Index>(i));
    }
    const Eigen::Isometry3f T = T_frame_source.cast<float>();
    const auto W = static_cast<long>(frame.width);
    const auto H = static_cast<long>(frame.height);
    for (Index i : EvenSubset(finite, params.max_points)) {
        const Eigen::Vector3f p = T * source.points[i];
        if (!(p.z() > 0.0f)) continue;
        const long u = std::lround(pinhole->fx * p.x() / p.z() + pinhole->cx);
        const long v = std::lround(pinhole->fy * p.y() / p.z() + pinhole->cy);
        if (u < 0 || v < 0 || u >= W || v >= H) continue;
        const Eigen::Vector3f& q = frame.points[static_cast<std::size_t>(v * W + u)];
        if (!q.allFinite()) continue;  // no return: nothing is known along this ray
        ++check.checked;
        const float sigma = params.depth_noise * q.z() * q.z();
        const float gap = q.z() - p.z() - params.tolerance - 3.0f * sigma;
        if (gap > 0.0f && (params.max_gap <= 0.0f || gap <= params.max_gap)) ++check.violations;
    }
    check.ratio = check.checked == 0
                      ? 0.0
                      : static_cast<double>(check.violations) / static_cast<double>(check.checked);
    return check;
}

}  // namespace multicue

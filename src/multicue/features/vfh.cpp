#include "multicue/features/vfh.hpp"

#include <algorithm>
#include <cmath>

#include "multicue/core/exceptions.hpp"

namespace multicue {
namespace {

constexpr int kBins = 45;
constexpr int kViewBins = 128;
const float kVfhInvTwoPi = 1.0f / (2.0f * static_cast<float>(M_PI));

}  // namespace

FeatureVector ComputeVfh(const PointCloud& cluster, const VfhParams& params) {
    FeatureVector hist = FeatureVector::Zero(kVfhSize);
    if (cluster.empty()) return hist;
    detail::CheckNormals(cluster, "VFH");
    const Eigen::Vector3f viewpoint = params.viewpoint.value_or(cluster.sensor_origin);
    if (!viewpoint.allFinite()) throw InvalidArgument("VFH viewpoint must be finite");

    // Centroid and mean normal over the usable points.
    Eigen::Vector3d centroid_sum = Eigen::Vector3d::Zero();
    Eigen::Vector3d normal_sum = Eigen::Vector3d::Zero();
    std::size_t n = 0;
    for (std::size_t i = 0; i < cluster.size(); ++i) {
        if (!detail::IsUsable(cluster, i)) continue;
        centroid_sum += cluster.points[i].cast<double>();
        normal_sum += cluster.normals[i].cast<double>();
        ++n;
    }
    if (n < 2) return hist;
    const Eigen::Vector3f centroid = (centroid_sum / static_cast<double>(n)).cast<float>();
    const Eigen::Vector3f mean_normal = (normal_sum / static_cast<double>(n)).cast<float>();

    float max_distance = 0.0f;
    if (params.normalize_distances) {
        for (std::size_t i = 0; i < cluster.size(); ++i) {
            if (!detail::IsUsable(cluster, i)) continue;
            max_distance = std::max(max_distance, (cluster.points[i] - centroid).norm());
        }
    }
    const float incr = 100.0f / static_cast<float>(n - 1);
    const float size_incr = params.size_component ? incr : 0.0f;
    Eigen::Vector3f to_view = (viewpoint - centroid).normalized();
    if (params.pcl_compatible) {
        to_view = (viewpoint - centroid) / std::sqrt((viewpoint - centroid).squaredNorm() + 1.0f);
        max_distance = std::sqrt(max_distance * max_distance + 1.0f);
    }
    const double view_incr = 100.0 / static_cast<double>(n);
    for (std::size_t i = 0; i < cluster.size(); ++i) {
        if (!detail::IsUsable(cluster, i)) continue;
        const Eigen::Vector3f& normal = cluster.normals[i];
        // Viewpoint component: every point, even when its pair with the centroid is degenerate.
        const double alpha = (normal.dot(to_view) + 1.0) * 0.5;
        hist[3 * kBins + kBins + detail::ClampedBin(alpha * kViewBins, kViewBins)] +=
            static_cast<float>(view_incr);
        float f1, f2, f3, f4;
        if (!detail::PairFeatures(centroid, mean_normal, cluster.points[i], normal, f1, f2, f3,
                                  f4)) {
            continue;
        }
        hist[detail::ClampedBin(kBins * ((f1 + M_PI) * kVfhInvTwoPi), kBins)] += incr;
        if (params.pcl_compatible) {
            hist[kBins + detail::ClampedBin(kBins * ((f2 + M_PI) * kVfhInvTwoPi), kBins)] += incr;
            hist[2 * kBins + detail::ClampedBin(kBins * ((f3 + M_PI) * kVfhInvTwoPi), kBins)] +=
                incr;
        } else {
            hist[kBins + detail::ClampedBin(kBins * ((f2 + 1.0) * 0.5), kBins)] += incr;
            hist[2 * kBins + detail::ClampedBin(kBins * ((f3 + 1.0) * 0.5), kBins)] += incr;
        }
        const int d_bin =
            params.normalize_distances && max_distance > 0.0f
                ? detail::ClampedBin(kBins * (f4 / max_distance), kBins)
                : std::clamp(static_cast<int>(std::lround(f4 * 100.0f)), 0, kBins - 1);
        hist[3 * kBins + d_bin] += size_incr;
    }
    return hist;
}

}  // namespace multicue

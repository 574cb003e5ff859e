#include "multicue/segmentation/border_features.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace multicue {
namespace {

constexpr float kHeightCap = 0.3f;  // [m]

float Capped(float v) { return std::clamp(v, -kHeightCap, kHeightCap); }

float Angle(const Eigen::Vector3f& a, const Eigen::Vector3f& b) {
    if (a.norm() == 0.0f || b.norm() == 0.0f) return 0.5f * static_cast<float>(M_PI);
    return std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.0f, 1.0f));
}

}  // namespace

std::vector<PartSummary> SummarizeParts(const std::vector<Indices>& parts,
                                        const PartBorders& borders, const Eigen::Vector4f& plane) {
    std::vector<PartSummary> out(parts.size());
    std::vector<bool> seen(parts.size(), false);
    const Eigen::Vector3f up = plane.head<3>();
    for (std::size_t k = 0; k < parts.size(); ++k) {
        out[k].points = parts[k].size();
        out[k].top = -std::numeric_limits<float>::infinity();
        out[k].bottom = std::numeric_limits<float>::infinity();
    }
    for (const SurfacePatch& p : borders.patches) {
        if (p.part < 0) continue;
        const auto k = static_cast<std::size_t>(p.part);
        const float h = up.dot(p.centroid) + plane.w();
        out[k].top = std::max(out[k].top, h);
        out[k].bottom = std::min(out[k].bottom, h);
        out[k].normal += static_cast<float>(p.count) * p.normal;
        seen[k] = true;
    }
    for (std::size_t k = 0; k < parts.size(); ++k) {
        if (!seen[k]) {
            out[k].top = out[k].bottom = 0.0f;
            continue;
        }
        if (out[k].normal.norm() > 0.0f) out[k].normal.normalize();
    }
    std::vector<double> weight(parts.size(), 0.0);
    for (const SurfacePatch& p : borders.patches) {
        if (p.part < 0) continue;
        const auto k = static_cast<std::size_t>(p.part);
        out[k].spread += static_cast<float>(p.count) * Angle(p.normal, out[k].normal);
        weight[k] += static_cast<double>(p.count);
    }
    for (std::size_t k = 0; k < parts.size(); ++k) {
        if (weight[k] > 0.0) out[k].spread = static_cast<float>(out[k].spread / weight[k]);
    }
    return out;
}

BorderFeatures ComputeBorderFeatures(const PartBorder& border, const PartBorders& borders,
                                     const std::vector<PartSummary>& parts,
                                     const Eigen::Vector3f& up) {
    const PartSummary& a = parts[border.a];
    const PartSummary& b = parts[border.b];
    // The part whose lowest point is higher rests on (or hangs over) the other one.
    const PartSummary& high = a.bottom >= b.bottom ? a : b;
    const PartSummary& low = a.bottom >= b.bottom ? b : a;
    const float ua = std::abs(a.normal.dot(up));
    const float ub = std::abs(b.normal.dot(up));
    const std::size_t small_patches =
        std::min(borders.part_patches[border.a], borders.part_patches[border.b]);
    BorderFeatures f{};
    f[0] = std::log1p(static_cast<float>(border.pairs));
    f[1] = border.ConvexShare();
    f[2] = border.median_angle_deg * static_cast<float>(M_PI) / 180.0f;
    f[3] = Angle(a.normal, b.normal);
    f[4] = std::log10(static_cast<float>(std::max<std::size_t>(1, std::min(a.points, b.points))));
    f[5] = std::log10(static_cast<float>(std::max<std::size_t>(1, std::max(a.points, b.points))));
    f[6] = Capped(std::abs(a.top - b.top));
    f[7] = Capped(high.bottom);
    f[8] = Capped(std::abs(high.bottom - low.top));
    f[9] = std::min(ua, ub);
    f[10] = std::max(ua, ub);
    f[11] = static_cast<float>(border.pairs) /
            std::sqrt(static_cast<float>(std::max<std::size_t>(1, small_patches)));
    f[12] = border.mean_gap;
    f[13] = border.mean_ray_alignment;
    f[14] = border.mean_bend;
    f[15] = border.step_share;
    f[16] = std::min(a.spread, b.spread);
    f[17] = std::max(a.spread, b.spread);
    f[18] = border.pairs == 0
                ? 0.0f
                : static_cast<float>(border.plane_convex) / static_cast<float>(border.pairs);
    f[19] = border.plane_bend;
    // Where the border lies on the two parts: the higher part by mean height.
    const float span_a = a.top - a.bottom;
    const float span_b = b.top - b.bottom;
    const bool a_upper = a.top + a.bottom >= b.top + b.bottom;
    const PartSummary& upper = a_upper ? a : b;
    const PartSummary& lower = a_upper ? b : a;
    constexpr float kMinSpan = 0.01f;  // [m]
    f[20] = (border.max_height - border.min_height) / std::max(kMinSpan, std::min(span_a, span_b));
    f[21] = (border.mean_height - upper.bottom) / std::max(kMinSpan, upper.top - upper.bottom);
    f[22] = (lower.top - border.mean_height) / std::max(kMinSpan, lower.top - lower.bottom);
    const float bend_a = border.a < borders.part_bend.size() ? borders.part_bend[border.a] : 0.0f;
    const float bend_b = border.b < borders.part_bend.size() ? borders.part_bend[border.b] : 0.0f;
    f[23] = std::min(bend_a, bend_b);
    f[24] = std::max(bend_a, bend_b);
    f[25] = f[1] * std::max(0.0f, -std::cos(f[2]));
    for (float& v : f) {
        if (!std::isfinite(v)) v = 0.0f;
    }
    return f;
}

}  // namespace multicue

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/core/parallel.hpp"
#include "multicue/surface/normals.hpp"
#include "multicue/surface/pca.hpp"

namespace multicue {

namespace {

using detail::kNaN;

// One pixel of the padded frame. Invalid pixels (NaN points and the border padding) have zero
// coordinates and infinite depth: the depth test rejects them, and their zero weight multiplies
// finite numbers, so the window loop needs neither bounds checks nor NaN branches.
struct Pixel {
    float x, y, z, depth;
};

constexpr int kMaxHalfWindow = 100;

void CheckParams(const OrganizedNormalParams& p) {
    if (p.half_window < 1 || p.half_window > kMaxHalfWindow) {
        throw InvalidArgument(fmt::format("half_window must be in [1, {}] pixels, got {}",
                                          kMaxHalfWindow, p.half_window));
    }
    if (!(p.max_depth_change > 0.0f) || !std::isfinite(p.max_depth_change)) {
        throw InvalidArgument(
            fmt::format("max_depth_change must be > 0, got {}", p.max_depth_change));
    }
    ResolveThreadCount(p.num_threads);
}

}  // namespace

NormalsResult EstimateNormalsOrganized(const PointCloud& organized,
                                       const OrganizedNormalParams& params) {
    CheckParams(params);
    NormalsResult result;
    if (organized.empty()) return result;
    if (!organized.IsOrganized()) {
        throw InvalidArgument(fmt::format(
            "organized normal estimation needs an organized cloud (height > 1, width * height == "
            "size), got {}x{} for {} points",
            organized.width, organized.height, organized.size()));
    }
    const int width = static_cast<int>(organized.width);
    const int height = static_cast<int>(organized.height);
    const int h = params.half_window;
    const int pad = params.depth_dependent_window ? 3 * h : h;
    const int padded_width = width + 2 * pad;
    const std::size_t n = organized.size();
    const Eigen::Vector3f origin = organized.sensor_origin;
    const Eigen::Vector3f viewpoint = params.viewpoint.value_or(origin);
    const float inf = std::numeric_limits<float>::infinity();

    std::vector<Pixel> image(static_cast<std::size_t>(padded_width) * (height + 2 * pad),
                             Pixel{0.0f, 0.0f, 0.0f, inf});
    ParallelFor(
        static_cast<std::size_t>(height), params.num_threads,
        [&](std::size_t v) {
            const std::size_t row = (v + pad) * static_cast<std::size_t>(padded_width) + pad;
            for (int u = 0; u < width; ++u) {
                const Eigen::Vector3f& p = organized.points[v * width + u];
                if (!p.allFinite()) continue;
                image[row + u] = {p.x(), p.y(), p.z(), (p - origin).norm()};
            }
        },
        16);

    result.normals.assign(n, Eigen::Vector3f::Constant(kNaN));
    result.curvature.assign(n, kNaN);
    ParallelForChunks(n, params.num_threads, [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i) {
            const std::size_t v = i / width, u = i % width;
            const std::size_t centre = (v + pad) * padded_width + u + pad;
            const Pixel c = image[centre];
            if (c.depth == inf) continue;
            int hw = h;
            if (params.depth_dependent_window) {
                hw = std::clamp(static_cast<int>(std::lround(h * c.depth)), 1, 3 * h);
            }
            // Finite even for absurd parameters, so that padding (infinite depth) never passes.
            const float limit = std::min(params.max_depth_change * c.depth * c.depth,
                                         std::numeric_limits<float>::max());
            // Offsets from the centre point keep the float sums small and exact enough.
            float cnt = 0, sx = 0, sy = 0, sz = 0, xx = 0, xy = 0, xz = 0, yy = 0, yz = 0, zz = 0;
            for (int dv = -hw; dv <= hw; ++dv) {
                const Pixel* row = &image[centre + dv * static_cast<std::ptrdiff_t>(padded_width)];
                for (int du = -hw; du <= hw; ++du) {
                    const Pixel& p = row[du];
                    const float w = detail::WeightIfAtMost(std::abs(p.depth - c.depth), limit);
                    const float dx = p.x - c.x, dy = p.y - c.y, dz = p.z - c.z;
                    const float wx = w * dx, wy = w * dy, wz = w * dz;
                    cnt += w;
                    sx += wx;
                    sy += wy;
                    sz += wz;
                    xx += wx * dx;
                    xy += wx * dy;
                    xz += wx * dz;
                    yy += wy * dy;
                    yz += wy * dz;
                    zz += wz * dz;
                }
            }
            detail::Moments m;
            m.n = cnt;
            m.sx = sx;
            m.sy = sy;
            m.sz = sz;
            m.xx = xx;
            m.xy = xy;
            m.xz = xz;
            m.yy = yy;
            m.yz = yz;
            m.zz = zz;
            Eigen::Vector3f normal;
            float curvature = 0.0f;
            if (!detail::NormalFromMoments(m, normal, curvature)) continue;
            const Eigen::Vector3f p(c.x, c.y, c.z);
            detail::OrientTowards(normal, p, viewpoint);
            result.normals[i] = normal;
            result.curvature[i] = curvature;
        }
    });
    for (float c : result.curvature) result.undefined += std::isnan(c) ? 1 : 0;
    return result;
}

}  // namespace multicue

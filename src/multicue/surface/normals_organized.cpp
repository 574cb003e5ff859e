#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <vector>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/core/parallel.hpp"
#include "multicue/surface/normals.hpp"
#include "multicue/surface/pca.hpp"

namespace multicue {

namespace {

using detail::FloatMoments;
using detail::kNaN;
using detail::WeightIfAtMost;

constexpr int kMaxHalfWindow = 100;
// Centre pixels processed together by the fixed-window loop: the same window offsets for all,
// so the loop over them runs on contiguous memory and vectorizes.
constexpr int kLanes = 8;

void CheckParams(const OrganizedNormalParams& p) {
    if (p.half_window < 1 || p.half_window > kMaxHalfWindow) {
        throw InvalidArgument(fmt::format("half_window must be in [1, {}] pixels, got {}",
                                          kMaxHalfWindow, p.half_window));
    }
    if (p.stride < 0 || p.stride > p.half_window) {
        throw InvalidArgument(fmt::format("stride must be in [0, half_window = {}] pixels, got {}",
                                          p.half_window, p.stride));
    }
    if (!(p.max_depth_change > 0.0f) || !std::isfinite(p.max_depth_change)) {
        throw InvalidArgument(
            fmt::format("max_depth_change must be > 0, got {}", p.max_depth_change));
    }
    ResolveThreadCount(p.num_threads);
}

// The frame as separate planes of x, y, z and depth, padded on every side. Invalid pixels (NaN
// points and the padding) have zero coordinates and infinite depth: the depth test rejects them
// and their zero weight multiplies finite numbers, so the window loops need neither bounds
// checks nor NaN branches.
struct Planes {
    int pad = 0;
    int stride = 0;  // floats per padded row
    std::vector<float> x, y, z, depth;

    std::size_t At(int u, int v) const {
        return static_cast<std::size_t>(v + pad) * static_cast<std::size_t>(stride) +
               static_cast<std::size_t>(u + pad);
    }
};

Planes MakePlanes(const PointCloud& c, int pad, int num_threads) {
    const int width = static_cast<int>(c.width), height = static_cast<int>(c.height);
    Planes p;
    p.pad = pad;
    p.stride = width + 2 * pad + kLanes;  // room for the last group of lanes in a row
    const std::size_t size = static_cast<std::size_t>(p.stride) * (height + 2 * pad);
    p.x.assign(size, 0.0f);
    p.y.assign(size, 0.0f);
    p.z.assign(size, 0.0f);
    p.depth.assign(size, std::numeric_limits<float>::infinity());
    ParallelFor(
        static_cast<std::size_t>(height), num_threads,
        [&](std::size_t v) {
            for (int u = 0; u < width; ++u) {
                const Eigen::Vector3f& q = c.points[v * c.width + u];
                if (!q.allFinite()) continue;
                const std::size_t i = p.At(u, static_cast<int>(v));
                p.x[i] = q.x();
                p.y[i] = q.y();
                p.z[i] = q.z();
                p.depth[i] = (q - c.sensor_origin).norm();
            }
        },
        16);
    return p;
}

// Window half-size of a pixel at `depth` and the step between the pixels read.
void WindowOf(const OrganizedNormalParams& params, float depth, int& reach, int& step) {
    int half = params.half_window;
    if (params.depth_dependent_window) {
        half = std::clamp(static_cast<int>(std::lround(half * depth)), 1, 3 * params.half_window);
    }
    // Automatic: read at most 7 pixels per axis.
    step = params.stride > 0 ? std::min(params.stride, half) : (half + 2) / 3;
    reach = half / step * step;
}

// Depth threshold of a centre pixel; finite even for absurd parameters, so that invalid pixels
// (infinite depth) never pass.
float DepthLimit(const OrganizedNormalParams& params, float depth) {
    return std::min(params.max_depth_change * depth * depth, std::numeric_limits<float>::max());
}

// Throws InvalidArgument unless the cloud is an image and the mask covers it.
void CheckFrame(const PointCloud& organized, const OrganizedNormalParams& params) {
    if (!organized.IsOrganized()) {
        throw InvalidArgument(fmt::format(
            "organized normal estimation needs an organized cloud (height > 1, width * height == "
            "size), got {}x{} for {} points",
            organized.width, organized.height, organized.size()));
    }
    if (!params.mask.empty() && params.mask.size() != organized.size()) {
        throw InvalidArgument(
            fmt::format("mask has {} entries for {} pixels", params.mask.size(), organized.size()));
    }
}

// Normal and curvature of pixel i from the moments of its window about the centre p, oriented
// towards the viewpoint; left NaN for a degenerate window.
void StoreNormal(std::size_t i, const Eigen::Vector3f& p, const FloatMoments& m,
                 const Eigen::Vector3f& viewpoint, NormalsResult& result) {
    Eigen::Vector3f normal;
    float curvature = 0.0f;
    if (!detail::NormalFromMoments(m.ToDouble(), normal, curvature)) return;
    detail::OrientTowards(normal, p, viewpoint);
    result.normals[i] = normal;
    result.curvature[i] = curvature;
}

// Depth-dependent windows: every pixel has its own window, so one pixel at a time.
void NormalsPerPixelWindow(const PointCloud& organized, const Planes& planes,
                           const OrganizedNormalParams& params, const Eigen::Vector3f& viewpoint,
                           NormalsResult& result) {
    const bool masked = !params.mask.empty();
    const int width = static_cast<int>(organized.width);
    const int height = static_cast<int>(organized.height);
    ParallelFor(
        static_cast<std::size_t>(height), params.num_threads,
        [&](std::size_t row) {
            const int v = static_cast<int>(row);
            for (int u = 0; u < width; ++u) {
                if (masked && params.mask[row * organized.width + u] == 0) continue;
                const std::size_t c = planes.At(u, v);
                const float depth = planes.depth[c];
                if (depth == std::numeric_limits<float>::infinity()) continue;
                int reach = 0, step = 1;
                WindowOf(params, depth, reach, step);
                const float limit = DepthLimit(params, depth);
                const Eigen::Vector3f centre(planes.x[c], planes.y[c], planes.z[c]);
                FloatMoments m;
                for (int dv = -reach; dv <= reach; dv += step) {
                    for (int du = -reach; du <= reach; du += step) {
                        const std::size_t i = planes.At(u + du, v + dv);
                        m.AddWeighted(
                            Eigen::Vector3f(planes.x[i], planes.y[i], planes.z[i]) - centre,
                            WeightIfAtMost(std::abs(planes.depth[i] - depth), limit));
                    }
                }
                StoreNormal(row * organized.width + u, centre, m, viewpoint, result);
            }
        },
        4);
}

// One row of the fixed window: kLanes neighbouring centres at a time, each offset read for all of
// them from contiguous memory. Offsets from the centre point keep the float sums small and exact
// enough. Kept in one piece: the lane loops are the vectorised core.
void NormalsFixedWindowRow(std::size_t row, int reach, int step, const PointCloud& organized,
                           const Planes& planes, const OrganizedNormalParams& params,
                           const Eigen::Vector3f& viewpoint, NormalsResult& result) {
    const bool masked = !params.mask.empty();
    const int width = static_cast<int>(organized.width);
    const int v = static_cast<int>(row);
    for (int u0 = 0; u0 < width; u0 += kLanes) {
        if (masked) {
            bool any = false;
            for (int l = 0; l < kLanes && u0 + l < width; ++l) {
                any = any || params.mask[row * organized.width + u0 + l] != 0;
            }
            if (!any) continue;
        }
        const std::size_t c = planes.At(u0, v);
        std::array<float, kLanes> cx, cy, cz, cd, limit;
        for (int l = 0; l < kLanes; ++l) {
            cx[l] = planes.x[c + l];
            cy[l] = planes.y[c + l];
            cz[l] = planes.z[c + l];
            cd[l] = planes.depth[c + l];
            limit[l] = DepthLimit(params, cd[l]);
        }
        std::array<float, kLanes> n{}, sx{}, sy{}, sz{}, xx{}, xy{}, xz{}, yy{}, yz{}, zz{};
        for (int dv = -reach; dv <= reach; dv += step) {
            for (int du = -reach; du <= reach; du += step) {
                const std::size_t i = planes.At(u0 + du, v + dv);
                const float* px = &planes.x[i];
                const float* py = &planes.y[i];
                const float* pz = &planes.z[i];
                const float* pd = &planes.depth[i];
                for (int l = 0; l < kLanes; ++l) {
                    const float w = WeightIfAtMost(std::abs(pd[l] - cd[l]), limit[l]);
                    const float dx = px[l] - cx[l], dy = py[l] - cy[l], dz = pz[l] - cz[l];
                    const float wx = w * dx, wy = w * dy, wz = w * dz;
                    n[l] += w;
                    sx[l] += wx;
                    sy[l] += wy;
                    sz[l] += wz;
                    xx[l] += wx * dx;
                    xy[l] += wx * dy;
                    xz[l] += wx * dz;
                    yy[l] += wy * dy;
                    yz[l] += wy * dz;
                    zz[l] += wz * dz;
                }
            }
        }
        for (int l = 0; l < kLanes && u0 + l < width; ++l) {
            if (cd[l] == std::numeric_limits<float>::infinity()) continue;
            if (masked && params.mask[row * organized.width + u0 + l] == 0) continue;
            StoreNormal(row * organized.width + u0 + l, {cx[l], cy[l], cz[l]},
                        {n[l], sx[l], sy[l], sz[l], xx[l], xy[l], xz[l], yy[l], yz[l], zz[l]},
                        viewpoint, result);
        }
    }
}

// The same window for all pixels (depth 1 m's): rows in parallel, lanes of centres within a row.
void NormalsFixedWindow(const PointCloud& organized, const Planes& planes,
                        const OrganizedNormalParams& params, const Eigen::Vector3f& viewpoint,
                        NormalsResult& result) {
    const int height = static_cast<int>(organized.height);
    int reach = 0, step = 1;
    WindowOf(params, 1.0f, reach, step);
    ParallelFor(
        static_cast<std::size_t>(height), params.num_threads,
        [&](std::size_t row) {
            NormalsFixedWindowRow(row, reach, step, organized, planes, params, viewpoint, result);
        },
        4);
}

}  // namespace

void OrganizedNormalParams::Validate() const { CheckParams(*this); }

NormalsResult EstimateNormalsOrganized(const PointCloud& organized,
                                       const OrganizedNormalParams& params) {
    CheckParams(params);
    NormalsResult result;
    if (organized.empty()) return result;
    CheckFrame(organized, params);
    const int pad = params.depth_dependent_window ? 3 * params.half_window : params.half_window;
    const Planes planes = MakePlanes(organized, pad, params.num_threads);
    const Eigen::Vector3f viewpoint = params.viewpoint.value_or(organized.sensor_origin);
    result.normals.assign(organized.size(), Eigen::Vector3f::Constant(kNaN));
    result.curvature.assign(organized.size(), kNaN);
    if (params.depth_dependent_window) {
        NormalsPerPixelWindow(organized, planes, params, viewpoint, result);
    } else {
        NormalsFixedWindow(organized, planes, params, viewpoint, result);
    }
    for (float c : result.curvature) result.undefined += std::isnan(c) ? 1 : 0;
    return result;
}

}  // namespace multicue

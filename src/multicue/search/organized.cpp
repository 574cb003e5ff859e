#include "multicue/search/organized.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"

namespace multicue {
namespace {

// Pixel window around a centre, clamped to the image.
struct Window {
    std::size_t u0, u1, v0, v1;  // inclusive bounds
};

Window CheckedWindow(const PointCloud& cloud, Index center, const OrganizedSearchParams& params) {
    if (!cloud.IsOrganized()) {
        throw InvalidArgument(
            fmt::format("organized search needs an organized cloud, got {}x{} with {} points",
                        cloud.width, cloud.height, cloud.size()));
    }
    if (center >= cloud.size()) {
        throw InvalidArgument(
            fmt::format("index {} is out of range for a cloud of {} points", center, cloud.size()));
    }
    if (params.half_window < 1) {
        throw InvalidArgument(
            fmt::format("half_window must be >= 1 [pixels], got {}", params.half_window));
    }
    if (!(params.radius > 0.0f)) {
        throw InvalidArgument(fmt::format("radius must be > 0, got {}", params.radius));
    }
    const std::size_t w = cloud.width, h = cloud.height;
    const std::size_t hw = static_cast<std::size_t>(params.half_window);
    const std::size_t u = center % w, v = center / w;
    return {u > hw ? u - hw : 0, std::min(w - 1, u + hw), v > hw ? v - hw : 0,
            std::min(h - 1, v + hw)};
}

// Squared radius threshold; non-finite points give NaN or inf distances and always fail `<=`.
float SquaredRadius(float radius) {
    const float r2 = radius * radius;
    return std::isfinite(r2) ? r2 : std::numeric_limits<float>::max();
}

// Up to this k, k-nearest selection inserts into a sorted array; beyond, it selects with
// nth_element over all candidates.
constexpr std::size_t kInsertionMaxK = 32;

// A candidate neighbour packed as (squared distance bits, index): for non-negative floats the bit
// pattern orders like the value, so sorting the packed words orders by distance, then by index.
inline std::uint64_t Pack(float d2, Index i) {
    return (std::uint64_t{std::bit_cast<std::uint32_t>(d2)} << 32) | i;
}

}  // namespace

std::size_t OrganizedRadiusSearch(const PointCloud& cloud, Index center,
                                  const OrganizedSearchParams& params, Indices& indices,
                                  std::vector<float>& squared_distances) {
    const Window win = CheckedWindow(cloud, center, params);
    indices.clear();
    squared_distances.clear();
    const Eigen::Vector3f c = cloud.points[center];
    if (!c.allFinite()) return 0;
    const float r2 = SquaredRadius(params.radius);
    const std::size_t w = cloud.width;
    for (std::size_t v = win.v0; v <= win.v1; ++v) {
        const Eigen::Vector3f* row = cloud.points.data() + v * w;
        for (std::size_t u = win.u0; u <= win.u1; ++u) {
            const float d2 = (row[u] - c).squaredNorm();
            if (d2 <= r2) {
                indices.push_back(static_cast<Index>(v * w + u));
                squared_distances.push_back(d2);
            }
        }
    }
    return indices.size();
}

std::size_t OrganizedKnnSearch(const PointCloud& cloud, Index center, int k,
                               const OrganizedSearchParams& params, Indices& indices,
                               std::vector<float>& squared_distances) {
    const Window win = CheckedWindow(cloud, center, params);
    if (k < 1) throw InvalidArgument(fmt::format("k must be > 0, got {}", k));
    const Eigen::Vector3f c = cloud.points[center];
    if (!c.allFinite()) {
        indices.clear();
        squared_distances.clear();
        return 0;
    }
    // Per-thread scratch that only grows: no allocation once it holds a window.
    thread_local std::vector<std::uint64_t> best;
    const std::size_t window = (win.u1 - win.u0 + 1) * (win.v1 - win.v0 + 1);
    const auto kk = static_cast<std::size_t>(k);
    const float r2 = SquaredRadius(params.radius);
    const std::size_t w = cloud.width;
    std::size_t m = 0;
    if (kk <= kInsertionMaxK) {
        // Small k: keep the best k sorted and insert the rare candidates that beat the worst.
        best.resize(std::min(kk, window));
        const std::size_t cap = best.size();
        std::uint64_t* top = best.data();
        for (std::size_t v = win.v0; v <= win.v1; ++v) {
            const Eigen::Vector3f* row = cloud.points.data() + v * w;
            for (std::size_t u = win.u0; u <= win.u1; ++u) {
                const float d2 = (row[u] - c).squaredNorm();
                if (!(d2 <= r2)) continue;
                const std::uint64_t key = Pack(d2, static_cast<Index>(v * w + u));
                std::size_t j = m;
                if (m < cap) {
                    ++m;
                } else if (key < top[cap - 1]) {
                    j = cap - 1;
                } else {
                    continue;
                }
                for (; j > 0 && top[j - 1] > key; --j) top[j] = top[j - 1];
                top[j] = key;
            }
        }
    } else {
        // Large k: collect every candidate, then select and sort the k best.
        best.clear();
        for (std::size_t v = win.v0; v <= win.v1; ++v) {
            const Eigen::Vector3f* row = cloud.points.data() + v * w;
            for (std::size_t u = win.u0; u <= win.u1; ++u) {
                const float d2 = (row[u] - c).squaredNorm();
                if (d2 <= r2) best.push_back(Pack(d2, static_cast<Index>(v * w + u)));
            }
        }
        m = std::min(kk, best.size());
        const auto mid = best.begin() + static_cast<std::ptrdiff_t>(m);
        if (m < best.size()) std::nth_element(best.begin(), mid, best.end());
        std::sort(best.begin(), mid);
    }
    indices.resize(m);
    squared_distances.resize(m);
    for (std::size_t j = 0; j < m; ++j) {
        indices[j] = static_cast<Index>(best[j]);
        squared_distances[j] = std::bit_cast<float>(static_cast<std::uint32_t>(best[j] >> 32));
    }
    return m;
}

float EstimateFocalLength(const PointCloud& cloud) {
    if (!cloud.IsOrganized()) {
        throw InvalidArgument(fmt::format(
            "focal length estimation needs an organized cloud, got {}x{} with {} points",
            cloud.width, cloud.height, cloud.size()));
    }
    constexpr std::size_t kMinPointsPerRow = 8;
    // Sensor frame: p_sensor = R^T (p - origin).
    const Eigen::Matrix3f R_cloud_sensor = cloud.sensor_orientation.normalized().toRotationMatrix();
    const Eigen::Vector3f origin = cloud.sensor_origin;
    std::vector<double> slopes;
    slopes.reserve(cloud.height);
    for (std::size_t v = 0; v < cloud.height; ++v) {
        // Least-squares line u = f * s + c with s = x/z, from running sums.
        double n = 0, sum_s = 0, sum_u = 0, sum_ss = 0, sum_su = 0;
        for (std::size_t u = 0; u < cloud.width; ++u) {
            const Eigen::Vector3f& p = cloud.points[v * cloud.width + u];
            if (!p.allFinite()) continue;
            const Eigen::Vector3f q = R_cloud_sensor.transpose() * (p - origin);
            if (q.z() == 0.0f) continue;
            const double s = static_cast<double>(q.x()) / q.z();
            const auto col = static_cast<double>(u);
            n += 1;
            sum_s += s;
            sum_u += col;
            sum_ss += s * s;
            sum_su += s * col;
        }
        if (n < kMinPointsPerRow) continue;
        const double var_s = sum_ss - sum_s * sum_s / n;
        const double cov_su = sum_su - sum_s * sum_u / n;
        if (!(var_s > 0.0)) continue;
        const double f = std::abs(cov_su / var_s);
        if (std::isfinite(f) && f > 0.0) slopes.push_back(f);
    }
    if (slopes.empty()) {
        throw DataError(fmt::format(
            "cannot estimate the focal length of a {}x{} cloud: no row has {} finite points over "
            "at least two columns",
            cloud.width, cloud.height, kMinPointsPerRow));
    }
    const auto mid = slopes.begin() + static_cast<std::ptrdiff_t>(slopes.size() / 2);
    std::nth_element(slopes.begin(), mid, slopes.end());
    return static_cast<float>(*mid);
}

int WindowHalfSizeForRadius(float radius, float depth, float focal_length) {
    if (!(radius > 0.0f) || !std::isfinite(radius)) {
        throw InvalidArgument(fmt::format("radius must be > 0, got {}", radius));
    }
    if (!(focal_length > 0.0f) || !std::isfinite(focal_length)) {
        throw InvalidArgument(
            fmt::format("focal_length must be > 0 [pixels], got {}", focal_length));
    }
    if (depth == 0.0f || !std::isfinite(depth)) {
        throw InvalidArgument(fmt::format("depth must be finite and non-zero, got {}", depth));
    }
    constexpr double kMaxHalfWindow = 1'000'000.0;
    const double pixels = std::ceil(double{radius} * focal_length / std::abs(double{depth}));
    return static_cast<int>(std::clamp(pixels, 1.0, kMaxHalfWindow));
}

}  // namespace multicue

#include "multicue/search/organized.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/core/parallel.hpp"
#include "multicue/search/nearest_keys.hpp"

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
    if (!params.mask.empty() && params.mask.size() != cloud.size()) {
        throw InvalidArgument(fmt::format("the search mask has {} entries for a cloud of {} points",
                                          params.mask.size(), cloud.size()));
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

// Pixel offsets (dv * width + du) of a whole window, by increasing pixel distance from the
// centre (rings); cached per thread for the last half-size and width.
const std::vector<std::ptrdiff_t>& RingOffsets(int half_window, std::size_t width) {
    thread_local int cached_half = -1;
    thread_local std::size_t cached_width = 0;
    thread_local std::vector<std::ptrdiff_t> offsets;
    if (cached_half == half_window && cached_width == width) return offsets;
    std::vector<std::pair<int, std::ptrdiff_t>> ring;
    const auto w = static_cast<std::ptrdiff_t>(width);
    for (int dv = -half_window; dv <= half_window; ++dv) {
        for (int du = -half_window; du <= half_window; ++du) {
            ring.emplace_back(du * du + dv * dv, std::ptrdiff_t{dv} * w + du);
        }
    }
    std::stable_sort(ring.begin(), ring.end(),
                     [](const auto& a, const auto& b) { return a.first < b.first; });
    offsets.clear();
    for (const auto& r : ring) offsets.push_back(r.second);
    cached_half = half_window;
    cached_width = width;
    return offsets;
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
    const std::uint8_t* mask = params.mask.empty() ? nullptr : params.mask.data();
    for (std::size_t v = win.v0; v <= win.v1; ++v) {
        const Eigen::Vector3f* row = cloud.points.data() + v * w;
        for (std::size_t u = win.u0; u <= win.u1; ++u) {
            if (mask != nullptr && mask[v * w + u] == 0) continue;
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
    const std::uint8_t* mask = params.mask.empty() ? nullptr : params.mask.data();
    std::size_t m = 0;
    if (kk <= kInsertionMaxK) {
        // Small k: keep the best k sorted and insert the candidates that beat the worst.
        best.resize(std::min(kk, window));
        const std::size_t cap = best.size();
        std::uint64_t* top = best.data();
        auto consider = [&](std::size_t i) {
            if (mask != nullptr && mask[i] == 0) return;
            const float d2 = (cloud.points[i] - c).squaredNorm();
            if (!(d2 <= r2)) return;
            detail::InsertNearest(detail::PackNeighbour(d2, static_cast<Index>(i)), top, m, cap);
        };
        const auto hw = static_cast<std::size_t>(params.half_window);
        if (win.u1 - win.u0 == 2 * hw && win.v1 - win.v0 == 2 * hw) {
            // A whole window: nearest pixels first, so that the first k candidates are mostly
            // the nearest in 3D too and later ones seldom displace them. The keys order
            // candidates completely, so the scan order does not change the result.
            const std::vector<std::ptrdiff_t>& offsets = RingOffsets(params.half_window, w);
            for (const std::ptrdiff_t o : offsets) {
                consider(static_cast<std::size_t>(static_cast<std::ptrdiff_t>(center) + o));
            }
        } else {
            for (std::size_t v = win.v0; v <= win.v1; ++v) {
                for (std::size_t u = win.u0; u <= win.u1; ++u) consider(v * w + u);
            }
        }
    } else {
        // Large k: collect every candidate, then select and sort the k best.
        best.clear();
        for (std::size_t v = win.v0; v <= win.v1; ++v) {
            const Eigen::Vector3f* row = cloud.points.data() + v * w;
            for (std::size_t u = win.u0; u <= win.u1; ++u) {
                if (mask != nullptr && mask[v * w + u] == 0) continue;
                const float d2 = (row[u] - c).squaredNorm();
                if (d2 <= r2)
                    best.push_back(detail::PackNeighbour(d2, static_cast<Index>(v * w + u)));
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
        indices[j] = detail::PackedIndex(best[j]);
        squared_distances[j] = detail::PackedSquaredDistance(best[j]);
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

namespace {

// The pitch and origin of a lattice of values, or nothing: distinct values (merged within a
// hundredth of the smallest gaps) and the median of the gaps between neighbours.
std::optional<std::pair<double, double>> LatticeOf(std::vector<double> values) {
    if (values.size() < 16) return std::nullopt;
    std::sort(values.begin(), values.end());
    const double span = values.back() - values.front();
    if (!(span > 0.0)) return std::nullopt;
    const double merge = span * 1e-6;
    std::vector<double> distinct{values.front()};
    for (double v : values) {
        if (v - distinct.back() > merge) distinct.push_back(v);
    }
    if (distinct.size() < 8) return std::nullopt;
    std::vector<double> gaps;
    gaps.reserve(distinct.size() - 1);
    for (std::size_t k = 1; k < distinct.size(); ++k) gaps.push_back(distinct[k] - distinct[k - 1]);
    std::nth_element(gaps.begin(), gaps.begin() + static_cast<std::ptrdiff_t>(gaps.size() / 2),
                     gaps.end());
    const double pitch = gaps[gaps.size() / 2];
    if (!(pitch > 0.0)) return std::nullopt;
    return std::make_pair(pitch, values.front());
}

}  // namespace

std::optional<ImageGrid> RecoverImageGrid(const PointCloud& cloud, int num_threads) {
    if (cloud.IsOrganized() || cloud.empty() || cloud.HasSensorPosition()) return std::nullopt;
    const std::size_t n = cloud.size();
    std::vector<double> a, b;
    a.reserve(n);
    b.reserve(n);
    Indices finite;
    finite.reserve(n);
    int side = 0;  // the sign of z: a camera looks along +z (or -z), never both ways
    for (std::size_t i = 0; i < n; ++i) {
        const Eigen::Vector3f& q = cloud.points[i];
        if (!q.allFinite()) continue;
        const int s = q.z() > 1e-6f ? 1 : q.z() < -1e-6f ? -1 : 0;
        if (s == 0 || (side != 0 && s != side)) return std::nullopt;
        side = s;
        a.push_back(static_cast<double>(q.x()) / q.z());
        b.push_back(static_cast<double>(q.y()) / q.z());
        finite.push_back(static_cast<Index>(i));
    }
    // The two lattices (each sorts its values) side by side.
    std::optional<std::pair<double, double>> la, lb;
    ParallelFor(
        2, num_threads, [&](std::size_t k) { (k == 0 ? la : lb) = LatticeOf(k == 0 ? a : b); }, 1);
    if (!la || !lb) return std::nullopt;
    const auto [pa, a0] = *la;
    const auto [pb, b0] = *lb;
    const double width = std::round((*std::max_element(a.begin(), a.end()) - a0) / pa) + 1.0;
    const double height = std::round((*std::max_element(b.begin(), b.end()) - b0) / pb) + 1.0;
    if (width > 4096.0 || height > 4096.0 || height < 2.0 ||
        width * height > 8.0 * static_cast<double>(finite.size())) {
        return std::nullopt;
    }
    const auto w = static_cast<std::uint32_t>(width);
    const auto h = static_cast<std::uint32_t>(height);
    ImageGrid grid;
    grid.input_of.assign(std::size_t{w} * h, ImageGrid::kNoPoint);
    grid.pixel_of.assign(n, ImageGrid::kNoPoint);
    std::size_t off_lattice = 0;
    for (std::size_t k = 0; k < finite.size(); ++k) {
        const double fu = (a[k] - a0) / pa, fv = (b[k] - b0) / pb;
        const double u = std::round(fu), v = std::round(fv);
        if (std::abs(fu - u) > 0.1 || std::abs(fv - v) > 0.1) ++off_lattice;
        const std::size_t pixel = static_cast<std::size_t>(v) * w + static_cast<std::size_t>(u);
        if (grid.input_of[pixel] != ImageGrid::kNoPoint) return std::nullopt;  // shared pixel
        grid.input_of[pixel] = finite[k];
        grid.pixel_of[finite[k]] = static_cast<Index>(pixel);
    }
    if (off_lattice * 100 > finite.size()) return std::nullopt;

    PointCloud& o = grid.organized;
    o.width = w;
    o.height = h;
    o.sensor_origin = cloud.sensor_origin;
    o.sensor_orientation = cloud.sensor_orientation;
    const float nan = std::numeric_limits<float>::quiet_NaN();
    o.points.assign(grid.input_of.size(), Eigen::Vector3f::Constant(nan));
    if (cloud.HasNormals()) o.normals.assign(o.points.size(), Eigen::Vector3f::Constant(nan));
    if (cloud.HasColors()) o.colors.assign(o.points.size(), Color{});
    ParallelFor(
        grid.input_of.size(), num_threads,
        [&](std::size_t p) {
            const Index i = grid.input_of[p];
            if (i == ImageGrid::kNoPoint) return;
            o.points[p] = cloud.points[i];
            if (!o.normals.empty()) o.normals[p] = cloud.normals[i];
            if (!o.colors.empty()) o.colors[p] = cloud.colors[i];
        },
        16384);
    return grid;
}

}  // namespace multicue

#include "multicue/surface/mls.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/core/parallel.hpp"
#include "multicue/search/organized.hpp"
#include "multicue/surface/mls_fit.hpp"
#include "multicue/surface/normals.hpp"

namespace multicue {
namespace {

constexpr float kMlsNaN = std::numeric_limits<float>::quiet_NaN();

void CheckCommon(float radius, float gaussian, int order, int min_neighbors, int threads) {
    if (!(radius > 0.0f) || !std::isfinite(radius))
        throw InvalidArgument(fmt::format("radius must be > 0, got {}", radius));
    if (!(gaussian >= 0.0f) || !std::isfinite(gaussian))
        throw InvalidArgument(
            fmt::format("gaussian must be >= 0 (0 = radius / 2), got {}", gaussian));
    if (order < 0 || order > 3)
        throw InvalidArgument(fmt::format("polynomial_order must be in [0, 3], got {}", order));
    if (min_neighbors < 3)
        throw InvalidArgument(fmt::format("min_neighbors must be >= 3, got {}", min_neighbors));
    ResolveThreadCount(threads);
}

void CheckParams(const MlsParams& p) {
    CheckCommon(p.radius, p.gaussian, p.polynomial_order, p.min_neighbors, p.num_threads);
    if (!(p.inlier_distance >= 0.0f) || !std::isfinite(p.inlier_distance)) {
        throw InvalidArgument(fmt::format("inlier_distance must be >= 0 (0 = radius / 10), got {}",
                                          p.inlier_distance));
    }
    if (p.max_iterations < 1)
        throw InvalidArgument(fmt::format("max_iterations must be >= 1, got {}", p.max_iterations));
    if (!(p.confidence > 0.0f && p.confidence < 1.0f))
        throw InvalidArgument(fmt::format("confidence must be in (0, 1), got {}", p.confidence));
    if (!(p.resample_step >= 0.0f) || !std::isfinite(p.resample_step)) {
        throw InvalidArgument(fmt::format(
            "resample_step must be >= 0 (0 = at the input points), got {}", p.resample_step));
    }
    if (!(p.curvature_slope >= 0.0f) || !std::isfinite(p.curvature_slope)) {
        throw InvalidArgument(
            fmt::format("curvature_slope must be >= 0 (0 = off), got {}", p.curvature_slope));
    }
}

void CheckMlsTree(const PointCloud& cloud, const KdTree& tree) {
    const auto& to_cloud = tree.TreeToCloud();
    const auto& points = tree.TreePoints();
    for (std::size_t t = 0; t < to_cloud.size(); ++t) {
        const Index i = to_cloud[t];
        if (i >= cloud.size() || points[t] != cloud.points[i]) {
            throw InvalidArgument(
                fmt::format("the k-d tree ({} points) was not built from this cloud ({} points)",
                            tree.size(), cloud.size()));
        }
    }
}

/// Grid level (0: step s, 1: s / 2, 2: s / 4) of every finite point for curvature-adapted
/// resampling; all 0 without it.
std::vector<int> Levels(const PointCloud& cloud, const KdTree& tree, const MlsParams& p) {
    std::vector<int> level(cloud.size(), 0);
    if (p.curvature_slope == 0.0f || p.resample_step == 0.0f) return level;
    const NormalsResult pca =
        EstimateNormals(cloud, tree, {.radius = p.radius, .num_threads = p.num_threads});
    double sum = 0.0;
    std::size_t n = 0;
    for (float c : pca.curvature) {
        if (std::isfinite(c)) {
            sum += c;
            ++n;
        }
    }
    const double mean = n > 0 ? sum / static_cast<double>(n) : 0.0;
    if (!(mean > 0.0)) return level;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const float c = pca.curvature[i];
        if (!std::isfinite(c)) continue;
        const double f = 1.0 + p.curvature_slope * (c - mean) / mean;  // density factor
        level[i] = f >= 3.0 ? 2 : (f >= 1.5 ? 1 : 0);                  // nearest power of two
    }
    return level;
}

/// Starting points: the finite input points, or the occupied voxel centres of Eq. (2.1), on the
/// grid of each point's level.
std::vector<Eigen::Vector3f> StartingPoints(const PointCloud& cloud, float step,
                                            const std::vector<int>& level) {
    std::vector<Eigen::Vector3f> starts;
    if (step == 0.0f) {
        starts.reserve(cloud.size());
        for (std::size_t i = 0; i < cloud.size(); ++i)
            if (cloud.IsFinite(i)) starts.push_back(cloud.points[i]);
        return starts;
    }
    // (level, cell): sorted and made unique, so the order is deterministic.
    std::vector<Eigen::Vector4i> cells;
    cells.reserve(cloud.size());
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const Eigen::Vector3f& p = cloud.points[i];
        if (!p.allFinite()) continue;
        const float s = step / static_cast<float>(1 << level[i]);
        const Eigen::Vector3f c = (p / s).array().floor();
        if (!(c.cwiseAbs().maxCoeff() < 1e9f))
            throw InvalidArgument(fmt::format("resample_step {} is too small for the cloud", step));
        cells.emplace_back(level[i], static_cast<int>(c.x()), static_cast<int>(c.y()),
                           static_cast<int>(c.z()));
    }
    std::sort(cells.begin(), cells.end(), [](const Eigen::Vector4i& a, const Eigen::Vector4i& b) {
        return std::lexicographical_compare(a.data(), a.data() + 4, b.data(), b.data() + 4);
    });
    cells.erase(std::unique(cells.begin(), cells.end()), cells.end());
    starts.reserve(cells.size());
    for (const auto& c : cells) {
        const float s = step / static_cast<float>(1 << c[0]);
        starts.push_back((c.tail<3>().cast<float>().array() + 0.5f) * s);
    }
    return starts;
}

/// Per starting point: filled in parallel, compacted afterwards in order.
struct Slot {
    Eigen::Vector3f point, normal;
    float curvature = 0.0f;
    Color color;
    Index source = 0, label_source = 0;
    int inliers = 0, neighbours = 0;
    bool valid = false, plane_only = false;
};

detail::MlsFitSettings Settings(float radius, float gaussian, int order, bool robust,
                                float inlier_distance, int max_iterations, float confidence,
                                int min_neighbors) {
    detail::MlsFitSettings s;
    s.radius = radius;
    const float h = gaussian > 0.0f ? gaussian : radius / 2.0f;
    s.inv_h2 = 1.0f / (h * h);
    s.order = order;
    s.robust = robust;
    s.inlier_distance = inlier_distance > 0.0f ? inlier_distance : radius / 10.0f;
    s.max_iterations = max_iterations;
    s.confidence = confidence;
    s.min_neighbors = min_neighbors;
    return s;
}

/// Colour (weighted mean over the inliers) and nearest inlier; offsets/indices from the scratch.
void Attributes(const PointCloud& cloud, const detail::MlsScratch& s, const Indices& idx,
                Slot& slot) {
    float best = std::numeric_limits<float>::infinity();
    double r = 0.0, g = 0.0, b = 0.0, a = 0.0, sw = 0.0;
    for (std::size_t j = 0; j < idx.size(); ++j) {
        if (!s.inlier[j]) continue;
        const float d = s.offsets[j].squaredNorm();
        if (d < best) {
            best = d;
            slot.label_source = idx[j];
        }
        if (cloud.HasColors()) {
            const Color& c = cloud.colors[idx[j]];
            const double w = s.weights[j];
            r += w * c.r;
            g += w * c.g;
            b += w * c.b;
            a += w * c.a;
            sw += w;
        }
    }
    if (sw > 0.0) {
        auto to8 = [&](double v) {
            return static_cast<std::uint8_t>(std::clamp(std::lround(v / sw), 0L, 255L));
        };
        slot.color = {to8(r), to8(g), to8(b), to8(a)};
    }
}

/// Orients a fitted normal like the input normal at `source`, or towards the viewpoint.
void Orient(const PointCloud& cloud, Index source, const Eigen::Vector3f& viewpoint, Slot& slot) {
    if (cloud.HasNormals() && cloud.normals[source].allFinite()) {
        if (slot.normal.dot(cloud.normals[source]) < 0.0f) slot.normal = -slot.normal;
    } else if (slot.normal.dot(viewpoint - slot.point) < 0.0f) {
        slot.normal = -slot.normal;
    }
}

/// Tree positions of the points within sqrt(r2) of q, in tree order (MLS needs no sorting).
void RadiusUnsorted(const KdTree& tree, const Eigen::Vector3f& q, float r2, Indices& out,
                    Indices& stack) {
    out.clear();
    const auto& nodes = tree.Nodes();
    const auto& pts = tree.TreePoints();
    if (nodes.empty()) return;
    stack.assign(1, 0);
    while (!stack.empty()) {
        const KdTree::Node& n = nodes[stack.back()];
        const Index i = stack.back();
        stack.pop_back();
        const Eigen::Vector3f d = (n.min - q).cwiseMax(Eigen::Vector3f::Zero()).cwiseMax(q - n.max);
        if (d.squaredNorm() > r2) continue;
        if (n.IsLeaf()) {
            for (Index t = n.begin; t < n.end; ++t)
                if ((pts[t] - q).squaredNorm() <= r2) out.push_back(t);
            continue;
        }
        stack.push_back(n.second_child);
        stack.push_back(i + 1);
    }
}

std::uint64_t PointSeed(std::uint64_t seed, std::size_t i) {
    return seed * 0xd1b54a32d192ed03ull + static_cast<std::uint64_t>(i) * 0x9e3779b97f4a7c15ull +
           0x632be59bd9b4e019ull;
}

}  // namespace

MlsResult MovingLeastSquares(const PointCloud& cloud, const KdTree& tree, const MlsParams& params) {
    CheckParams(params);
    CheckMlsTree(cloud, tree);
    MlsResult result;
    if (cloud.empty() || tree.empty()) return result;
    const auto settings =
        Settings(params.radius, params.gaussian, params.polynomial_order,
                 params.plane_fit == MlsPlaneFit::kWeightedRansac, params.inlier_distance,
                 params.max_iterations, params.confidence, params.min_neighbors);
    const Eigen::Vector3f viewpoint = params.viewpoint.value_or(cloud.sensor_origin);
    const std::vector<Eigen::Vector3f> starts =
        StartingPoints(cloud, params.resample_step, Levels(cloud, tree, params));
    std::vector<Slot> slots(starts.size());

    ParallelForChunks(
        starts.size(), params.num_threads,
        [&](std::size_t begin, std::size_t end) {
            detail::MlsScratch scratch;
            Indices idx, stack;
            const auto& to_cloud = tree.TreeToCloud();
            const auto& tree_points = tree.TreePoints();
            const float r2 = params.radius * params.radius;
            for (std::size_t i = begin; i < end; ++i) {
                Slot& slot = slots[i];
                const Eigen::Vector3f& q = starts[i];
                RadiusUnsorted(tree, q, r2, idx, stack);
                slot.neighbours = static_cast<int>(idx.size());
                if (idx.empty()) continue;
                // Tree order is a fixed order, so results stay deterministic.
                scratch.offsets.resize(idx.size());
                float nearest = std::numeric_limits<float>::infinity();
                for (std::size_t j = 0; j < idx.size(); ++j) {
                    scratch.offsets[j] = tree_points[idx[j]] - q;
                    const float d = scratch.offsets[j].squaredNorm();
                    if (d < nearest) {
                        nearest = d;
                        slot.source = to_cloud[idx[j]];
                    }
                    idx[j] = to_cloud[idx[j]];
                }
                detail::SplitMix64 rng(PointSeed(params.seed, i));
                detail::MlsFit fit;
                if (!detail::FitMls(scratch, settings, rng, fit)) continue;
                slot.point = q + fit.offset;
                slot.normal = fit.normal;
                slot.curvature = fit.curvature;
                slot.inliers = fit.inliers;
                slot.plane_only = fit.plane_only;
                slot.valid = slot.point.allFinite();
                Attributes(cloud, scratch, idx, slot);
                Orient(cloud, slot.source, viewpoint, slot);
            }
        },
        64);

    PointCloud& out = result.cloud;
    out.sensor_origin = cloud.sensor_origin;
    out.sensor_orientation = cloud.sensor_orientation;
    double fraction = 0.0;
    for (const Slot& s : slots) {
        if (!s.valid) {
            ++result.dropped;
            continue;
        }
        out.points.push_back(s.point);
        out.normals.push_back(s.normal);
        out.curvature.push_back(s.curvature);
        if (cloud.HasColors()) out.colors.push_back(s.color);
        if (cloud.HasLabels()) out.labels.push_back(cloud.labels[s.label_source]);
        result.source.push_back(s.source);
        result.plane_only += s.plane_only;
        fraction += static_cast<double>(s.inliers) / std::max(1, s.neighbours);
    }
    out.SetUnorganized();
    if (!out.empty()) result.mean_inlier_fraction = fraction / static_cast<double>(out.size());
    return result;
}

MlsResult MovingLeastSquaresOrganized(const PointCloud& organized,
                                      const OrganizedMlsParams& params) {
    CheckCommon(params.radius, params.gaussian, params.polynomial_order, params.min_neighbors,
                params.num_threads);
    if (params.half_window < 1 || params.half_window > 100) {
        throw InvalidArgument(
            fmt::format("half_window must be in [1, 100], got {}", params.half_window));
    }
    MlsResult result;
    if (organized.empty()) return result;
    if (!organized.IsOrganized()) {
        throw InvalidArgument(fmt::format("organized MLS needs an organized cloud, got {}x{}",
                                          organized.width, organized.height));
    }
    const auto settings = Settings(params.radius, params.gaussian, params.polynomial_order, false,
                                   0.0f, 1, 0.5f, params.min_neighbors);
    const Eigen::Vector3f viewpoint = params.viewpoint.value_or(organized.sensor_origin);
    const std::size_t n = organized.size();
    PointCloud& out = result.cloud;
    out = organized;
    out.normals.assign(n, Eigen::Vector3f::Constant(kMlsNaN));
    out.curvature.assign(n, kMlsNaN);
    std::vector<Slot> slots(n);
    const OrganizedSearchParams search{.half_window = params.half_window, .radius = params.radius};

    ParallelForChunks(
        n, params.num_threads,
        [&](std::size_t begin, std::size_t end) {
            detail::MlsScratch scratch;
            Indices idx;
            std::vector<float> d2;
            for (std::size_t i = begin; i < end; ++i) {
                if (!organized.IsFinite(i)) continue;
                Slot& slot = slots[i];
                const Eigen::Vector3f& q = organized.points[i];
                OrganizedRadiusSearch(organized, static_cast<Index>(i), search, idx, d2);
                slot.neighbours = static_cast<int>(idx.size());
                scratch.offsets.resize(idx.size());
                for (std::size_t j = 0; j < idx.size(); ++j)
                    scratch.offsets[j] = organized.points[idx[j]] - q;
                detail::SplitMix64 rng(i);
                detail::MlsFit fit;
                if (!detail::FitMls(scratch, settings, rng, fit)) continue;
                slot.point = q + fit.offset;
                slot.normal = fit.normal;
                slot.curvature = fit.curvature;
                slot.inliers = fit.inliers;
                slot.plane_only = fit.plane_only;
                slot.valid = slot.point.allFinite();
                slot.source = static_cast<Index>(i);
                Orient(organized, slot.source, viewpoint, slot);
            }
        },
        2048);

    double fraction = 0.0;
    std::size_t valid = 0;
    result.source.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
        result.source[i] = static_cast<Index>(i);
        const Slot& s = slots[i];
        if (!s.valid) {
            if (organized.IsFinite(i)) ++result.dropped;
            out.points[i] = Eigen::Vector3f::Constant(kMlsNaN);
            continue;
        }
        out.points[i] = s.point;
        out.normals[i] = s.normal;
        out.curvature[i] = s.curvature;
        result.plane_only += s.plane_only;
        fraction += static_cast<double>(s.inliers) / std::max(1, s.neighbours);
        ++valid;
    }
    if (valid > 0) result.mean_inlier_fraction = fraction / static_cast<double>(valid);
    return result;
}

}  // namespace multicue

#include "multicue/mapping/fixture_evidence.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_set>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/mapping/fixtures.hpp"

namespace multicue::mapping {
namespace {

constexpr float kNoEvidence = std::numeric_limits<float>::quiet_NaN();

/// Median of v (reordered); NaN when empty.
float MedianOf(std::vector<float>& v) {
    if (v.empty()) return kNoEvidence;
    const auto mid = v.begin() + static_cast<long>(v.size() / 2);
    std::nth_element(v.begin(), mid, v.end());
    return *mid;
}

/// The q-quantile of v (reordered); NaN when empty.
float QuantileOf(std::vector<float>& v, float q) {
    if (v.empty()) return kNoEvidence;
    const auto k = static_cast<long>(std::floor(q * static_cast<float>(v.size() - 1)));
    std::nth_element(v.begin(), v.begin() + k, v.end());
    return v[static_cast<std::size_t>(k)];
}

/// The local background of per-sample values over the grid of s: per cell the median of the
/// values of the samples `use` admits, then per cell the median of those medians over the
/// (2 radius + 1)^2 cells around it (NaN where none).
template <typename Use>
std::vector<float> LocalBackground(const FaceSamples& s, const std::vector<float>& values,
                                   int radius, Use&& use) {
    const std::size_t ncells = static_cast<std::size_t>(s.nu) * static_cast<std::size_t>(s.nv);
    std::vector<float> median(ncells, kNoEvidence), background(ncells, kNoEvidence), buffer;
    for (std::size_t c = 0; c < ncells; ++c) {
        buffer.clear();
        for (std::uint32_t k = s.start[c]; k < s.start[c + 1]; ++k) {
            const std::uint32_t j = s.order[k];
            if (use(j)) buffer.push_back(values[j]);
        }
        median[c] = MedianOf(buffer);
    }
    for (int v = 0; v < s.nv; ++v) {
        for (int u = 0; u < s.nu; ++u) {
            buffer.clear();
            for (int dv = -radius; dv <= radius; ++dv) {
                for (int du = -radius; du <= radius; ++du) {
                    const int uu = u + du, vv = v + dv;
                    if (uu < 0 || vv < 0 || uu >= s.nu || vv >= s.nv) continue;
                    const float m = median[static_cast<std::size_t>(vv * s.nu + uu)];
                    if (!std::isnan(m)) buffer.push_back(m);
                }
            }
            background[static_cast<std::size_t>(v * s.nu + u)] = MedianOf(buffer);
        }
    }
    return background;
}

}  // namespace

std::uint32_t FaceSamples::CellOf(const Eigen::Vector2f& x) const {
    const int iu = std::clamp(static_cast<int>(std::floor((x.x() - origin.x()) / cell)), 0, nu - 1);
    const int iv = std::clamp(static_cast<int>(std::floor((x.y() - origin.y()) / cell)), 0, nv - 1);
    return static_cast<std::uint32_t>(iv * nu + iu);
}

void ComputeFaceResiduals(FaceSamples& s, float cell, int radius, int passes, float exclude) {
    if (!(cell > 0.0f) || !std::isfinite(cell) || radius < 0) {
        throw InvalidArgument(fmt::format(
            "fixtures: background cell must be > 0 and radius >= 0, got {} and {}", cell, radius));
    }
    s.residual.assign(s.size(), kNoEvidence);
    s.nu = s.nv = 0;
    s.start.assign(1, 0);
    s.order.clear();
    if (s.size() == 0) return;
    Eigen::Vector2f lo = s.q.front(), hi = s.q.front();
    for (const auto& x : s.q) {
        lo = lo.cwiseMin(x);
        hi = hi.cwiseMax(x);
    }
    // A grid of at most ~4M cells: coarser cells for huge faces.
    const Eigen::Vector2f span = hi - lo;
    s.cell = std::max(cell, std::sqrt(span.x() * span.y() / 4.0e6f));
    s.origin = lo;
    s.nu = static_cast<int>(std::floor(span.x() / s.cell)) + 1;
    s.nv = static_cast<int>(std::floor(span.y() / s.cell)) + 1;
    const std::size_t ncells = static_cast<std::size_t>(s.nu) * static_cast<std::size_t>(s.nv);
    std::vector<std::uint32_t> cell_of(s.size());
    s.start.assign(ncells + 1, 0);
    for (std::size_t k = 0; k < s.size(); ++k) {
        cell_of[k] = s.CellOf(s.q[k]);
        ++s.start[cell_of[k] + 1];
    }
    for (std::size_t c = 0; c < ncells; ++c) s.start[c + 1] += s.start[c];
    s.order.assign(s.size(), 0);
    std::vector<std::uint32_t> fill(s.start.begin(), s.start.end() - 1);
    for (std::size_t k = 0; k < s.size(); ++k) {
        s.order[fill[cell_of[k]]++] = static_cast<std::uint32_t>(k);
    }
    // Median height per cell, then the median of the medians around each cell. Later passes
    // leave out the samples that stood out of the previous background: a wide handle bar, which
    // fills much of a window, no longer lifts the background of its own cells.
    for (int pass = 0; pass < std::max(1, passes); ++pass) {
        const std::vector<float> background =
            LocalBackground(s, s.height, radius, [&](std::uint32_t j) {
                return pass == 0 || s.residual[j] <= std::max(exclude, 2.0f * s.sigma[j]);
            });
        for (std::size_t k = 0; k < s.size(); ++k) {
            const float b = background[cell_of[k]];
            // A cell whose every sample stood out keeps its previous residual.
            if (!std::isnan(b)) s.residual[k] = s.height[k] - b;
        }
    }
}

std::vector<float> AppearanceContrast(const FaceSamples& s, int radius) {
    std::vector<float> contrast(s.size(), kNoEvidence);
    if (s.size() == 0 || s.start.size() != static_cast<std::size_t>(s.nu) * s.nv + 1) {
        return contrast;
    }
    std::vector<std::vector<float>> channels(1, s.appearance);
    if (!s.chroma.empty()) {
        for (int c = 0; c < 2; ++c) {
            channels.emplace_back(s.size());
            for (std::size_t k = 0; k < s.size(); ++k) channels.back()[k] = s.chroma[k][c];
        }
    }
    std::vector<std::uint32_t> cell_of(s.size());
    for (std::size_t k = 0; k < s.size(); ++k) cell_of[k] = s.CellOf(s.q[k]);
    std::vector<float> sum(s.size(), 0.0f);
    for (const auto& values : channels) {
        const std::vector<float> background = LocalBackground(
            s, values, radius, [&](std::uint32_t j) { return !std::isnan(values[j]); });
        for (std::size_t k = 0; k < s.size(); ++k) {
            const float d = values[k] - background[cell_of[k]];
            sum[k] += d * d;  // NaN where the sample or its background has no appearance
        }
    }
    for (std::size_t k = 0; k < s.size(); ++k) contrast[k] = std::sqrt(sum[k]);
    return contrast;
}

const std::vector<std::string>& FixtureFeatureNames() {
    static const std::vector<std::string> names = {"length",
                                                   "width",
                                                   "elongation",
                                                   "plane_protrusion",
                                                   "local_protrusion",
                                                   "median_residual",
                                                   "depth_extent",
                                                   "protrusion_snr",
                                                   "range",
                                                   "points",
                                                   "density",
                                                   "line_share",
                                                   "circle_share",
                                                   "verticality",
                                                   "sides",
                                                   "min_side_drop",
                                                   "attached_share",
                                                   "border",
                                                   "contrast",
                                                   "surround_spread",
                                                   "edge_distance",
                                                   "height",
                                                   "fill",
                                                   "recess_share"};
    return names;
}

std::vector<float> FixtureFeatureRow(const FixtureEvidence& e) {
    std::vector<float> row = {e.length,
                              e.width,
                              e.elongation,
                              e.plane_protrusion,
                              e.local_protrusion,
                              e.median_residual,
                              e.depth_extent,
                              e.protrusion_snr,
                              e.range,
                              e.points,
                              e.density,
                              e.line_share,
                              e.circle_share,
                              e.verticality,
                              e.sides,
                              e.min_side_drop,
                              e.attached_share,
                              e.border,
                              e.contrast,
                              e.surround_spread,
                              e.edge_distance,
                              e.height,
                              e.fill,
                              e.recess_share};
    for (float& x : row) {
        if (!std::isfinite(x)) x = 0.0f;
    }
    return row;
}

const std::vector<std::string>& FixtureClassNames() {
    static const std::vector<std::string> names = {"none", "handle", "knob"};
    return names;
}

FixtureEvidence MeasureFixtureEvidence(const FaceSamples& s,
                                       const std::vector<std::uint32_t>& members,
                                       const Fixture& shape, const PlanarComponent& face,
                                       const RoomFrame& frame, float floor_height,
                                       const FixtureParams& p) {
    FixtureEvidence e;
    if (members.empty()) return e;
    Eigen::Vector2f lo = s.q[members.front()], hi = lo;
    std::vector<float> heights, residuals;
    // Appearance channels: grey, then the two chroma channels where the samples have colour.
    const int channels = s.chroma.empty() ? 1 : 3;
    auto channel = [&](std::uint32_t k, int c) {
        return c == 0 ? s.appearance[k] : s.chroma[k][c - 1];
    };
    std::vector<float> looks[3];
    float sigma = 0.0f;
    std::unordered_set<std::uint64_t> cells;
    constexpr float kFillCell = 0.01f;
    for (const std::uint32_t k : members) {
        lo = lo.cwiseMin(s.q[k]);
        hi = hi.cwiseMax(s.q[k]);
        heights.push_back(s.height[k]);
        residuals.push_back(s.residual[k]);
        if (!std::isnan(s.appearance[k])) {
            for (int c = 0; c < channels; ++c) looks[c].push_back(channel(k, c));
        }
        sigma += s.sigma[k];
        const auto cu = static_cast<std::int64_t>(std::floor(s.q[k].x() / kFillCell));
        const auto cv = static_cast<std::int64_t>(std::floor(s.q[k].y() / kFillCell));
        cells.insert((static_cast<std::uint64_t>(cu + (1 << 30)) << 32) ^
                     static_cast<std::uint64_t>(cv + (1 << 30)));
    }
    const auto n = static_cast<float>(members.size());
    sigma /= n;
    const float top = QuantileOf(heights, 0.9f);
    // The surround: samples in a ring around the footprint's box that are not candidates.
    const float in = p.surround_inner, out = p.surround_outer;
    std::vector<float> ring_h, ring_a[3], side_h[4];
    std::vector<std::uint32_t> ring_looks;
    std::size_t ring = 0, recessed = 0;
    s.ForEachIn(lo - Eigen::Vector2f::Constant(out), hi + Eigen::Vector2f::Constant(out),
                [&](std::uint32_t k) {
                    const Eigen::Vector2f& x = s.q[k];
                    const Eigen::Vector2f d = (lo - x).cwiseMax(x - hi).cwiseMax(0.0f);
                    const float dist = std::max(d.x(), d.y());
                    if (dist < in || dist > out) return;
                    ++ring;
                    // Within the noise of the background at the sample's range.
                    const float tol = std::max(p.background_tolerance, 2.0f * s.sigma[k]);
                    if (s.residual[k] < -tol) ++recessed;
                    if (std::abs(s.residual[k]) > tol) return;
                    ring_h.push_back(s.height[k]);
                    if (!std::isnan(s.appearance[k])) {
                        ring_looks.push_back(k);
                        for (int c = 0; c < channels; ++c) ring_a[c].push_back(channel(k, c));
                    }
                    // Left, right, below, above: the side the sample lies farthest beyond.
                    if (d.x() >= d.y()) {
                        side_h[x.x() < lo.x() ? 0 : 1].push_back(s.height[k]);
                    } else {
                        side_h[x.y() < lo.y() ? 2 : 3].push_back(s.height[k]);
                    }
                });
    const float surround = MedianOf(ring_h);
    float highest_side = -std::numeric_limits<float>::infinity();
    for (auto& side : side_h) {
        if (side.size() < 3) continue;
        e.sides += 1.0f;
        highest_side = std::max(highest_side, MedianOf(side));
    }
    e.length = shape.length;
    e.width = shape.width;
    e.elongation = shape.length / std::max(shape.width, 1e-3f);
    e.plane_protrusion = shape.protrusion;
    e.local_protrusion = std::isnan(surround) ? top : top - surround;
    e.median_residual = MedianOf(residuals);
    std::vector<float> all_h;
    for (const std::uint32_t k : members) all_h.push_back(s.height[k]);
    const auto [hmin, hmax] = std::minmax_element(all_h.begin(), all_h.end());
    e.depth_extent = *hmax - *hmin;
    e.protrusion_snr = e.local_protrusion / std::max(sigma, 1e-4f);
    for (const std::uint32_t k : members) e.range += s.range[k];
    e.range /= n;
    e.points = n;
    e.density = n * e.range * e.range / std::max(shape.length * shape.width, 1e-4f);
    e.line_share = shape.line_inlier_ratio;
    e.circle_share = shape.circle_inlier_ratio;
    e.verticality = std::abs(shape.direction.dot(frame.Up()));
    e.min_side_drop = std::isfinite(highest_side) ? top - highest_side : 0.0f;
    e.contrast = 0.0f;
    if (!looks[0].empty() && !ring_looks.empty()) {
        // Per channel medians; the distances between them (and of the surround's samples from
        // its median) in grey and chroma together.
        float mine[3] = {}, theirs[3] = {}, d2 = 0.0f;
        for (int c = 0; c < channels; ++c) {
            mine[c] = MedianOf(looks[c]);
            theirs[c] = MedianOf(ring_a[c]);
            d2 += (mine[c] - theirs[c]) * (mine[c] - theirs[c]);
        }
        e.contrast = std::sqrt(d2);
        std::vector<float> spread;
        for (const std::uint32_t k : ring_looks) {
            float r2 = 0.0f;
            for (int c = 0; c < channels; ++c) {
                r2 += (channel(k, c) - theirs[c]) * (channel(k, c) - theirs[c]);
            }
            spread.push_back(std::sqrt(r2));
        }
        e.surround_spread = MedianOf(spread);
    }
    const Eigen::Vector2f c = (lo + hi) / 2;
    e.edge_distance = std::min(
        {c.x() - face.min.x(), face.max.x() - c.x(), c.y() - face.min.y(), face.max.y() - c.y()});
    e.height = std::isnan(floor_height) ? 0.0f : shape.center.dot(frame.Up()) - floor_height;
    const Eigen::Vector2f box = (hi - lo) / kFillCell + Eigen::Vector2f::Ones();
    e.fill = static_cast<float>(cells.size()) / std::max(1.0f, box.x() * box.y());
    e.recess_share = ring == 0 ? 0.0f : static_cast<float>(recessed) / static_cast<float>(ring);
    return e;
}

}  // namespace multicue::mapping

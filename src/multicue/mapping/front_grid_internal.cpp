#include "multicue/mapping/front_grid_internal.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"

namespace multicue::mapping::front_grid_internal {

OutlineGrid BuildGrid(const PointCloud& cloud, const RoomFrame& frame, const PlanarComponent& face,
                      const Indices& points, const FrontEvidence& ev,
                      const std::vector<std::uint8_t>& is_fixture, const FrontEdgeParams& p) {
    OutlineGrid g;
    g.cell = p.cell;
    Eigen::Vector2f lo = Eigen::Vector2f::Constant(std::numeric_limits<float>::infinity()),
                    hi = -lo;
    std::vector<Eigen::Vector2f> q(points.size());
    for (std::size_t k = 0; k < points.size(); ++k) {
        q[k] = PlaneCoordinates(face, frame, cloud.points[points[k]]);
        lo = lo.cwiseMin(q[k]);
        hi = hi.cwiseMax(q[k]);
    }
    if (points.empty()) return g;
    // At most ~4M cells.
    const Eigen::Vector2f span = hi - lo;
    g.cell = std::max(p.cell, std::sqrt(span.x() * span.y() / 4.0e6f));
    g.origin = lo;
    g.nu = static_cast<int>(span.x() / g.cell) + 1;
    g.nv = static_cast<int>(span.y() / g.cell) + 1;
    const auto n = static_cast<std::size_t>(g.nu) * static_cast<std::size_t>(g.nv);
    std::vector<std::uint32_t> count(n, 0), edges(n, 0), n_res(n, 0);
    std::vector<float> sum_h(n, 0.0f), sum_res(n, 0.0f), sum_a(n, 0.0f);
    std::vector<std::uint32_t> n_a(n, 0);
    const Eigen::Vector3f normal = face.plane.head<3>();
    for (std::size_t k = 0; k < points.size(); ++k) {
        const Index i = points[k];
        if (is_fixture[i]) continue;
        const auto c = static_cast<std::size_t>(std::clamp(g.V(q[k].y()), 0, g.nv - 1) * g.nu +
                                                std::clamp(g.U(q[k].x()), 0, g.nu - 1));
        ++count[c];
        sum_h[c] += normal.dot(cloud.points[i]) + face.plane.w();
        if (!ev.image_edge.empty() && ev.image_edge[i]) ++edges[c];
        if (!ev.point_residual.empty() && std::isfinite(ev.point_residual[i])) {
            sum_res[c] += ev.point_residual[i];
            ++n_res[c];
        }
        if (!ev.appearance.empty() && std::isfinite(ev.appearance[i])) {
            sum_a[c] += ev.appearance[i];
            ++n_a[c];
        }
    }
    auto mean_a = [&](int u, int v) {
        const auto c = static_cast<std::size_t>(v * g.nu + u);
        return n_a[c] ? sum_a[c] / static_cast<float>(n_a[c])
                      : std::numeric_limits<float>::quiet_NaN();
    };
    g.mark.assign(n, kUnknown);
    auto mean_h = [&](int u, int v) {
        const auto c = static_cast<std::size_t>(v * g.nu + u);
        return count[c] ? sum_h[c] / static_cast<float>(count[c])
                        : std::numeric_limits<float>::quiet_NaN();
    };
    for (int v = 0; v < g.nv; ++v) {
        for (int u = 0; u < g.nu; ++u) {
            const auto c = static_cast<std::size_t>(v * g.nu + u);
            if (count[c] == 0) continue;
            bool gap = edges[c] > 0 ||
                       (n_res[c] > 0 && sum_res[c] / static_cast<float>(n_res[c]) < -p.recess);
            const float h = mean_h(u, v), a = mean_a(u, v);
            for (const auto& [du, dv] : {std::pair{1, 0}, {0, 1}, {-1, 0}, {0, -1}}) {
                const int uu = u + du, vv = v + dv;
                if (gap || uu < 0 || vv < 0 || uu >= g.nu || vv >= g.nv) continue;
                const float o = mean_h(uu, vv), oa = mean_a(uu, vv);
                gap = (!std::isnan(o) && std::abs(o - h) > p.step) ||
                      (!std::isnan(a) && !std::isnan(oa) && std::abs(oa - a) > p.appearance_step);
            }
            g.mark[c] = gap ? kGapCell : kFaceCell;
        }
    }
    // Empty cells with face cells near on both opposite sides: a gap the sensor did not see into.
    std::vector<std::uint8_t> holes(n, 0);
    for (int v = 0; v < g.nv; ++v) {
        for (int u = 0; u < g.nu; ++u) {
            if (g.At(u, v) != kUnknown) continue;
            auto seen = [&](int du, int dv) {
                for (int s = 1; s <= p.hole_reach; ++s) {
                    if (g.At(u + s * du, v + s * dv) != kUnknown) return true;
                }
                return false;
            };
            if ((seen(1, 0) && seen(-1, 0)) || (seen(0, 1) && seen(0, -1))) {
                holes[static_cast<std::size_t>(v * g.nu + u)] = 1;
            }
        }
    }
    for (std::size_t c = 0; c < n; ++c) {
        if (holes[c]) g.mark[c] = kGapCell;
    }
    return g;
}

/// Masks what a fixture hides or shows of itself: the cells of its box grown by `margin`, and
/// the gap and empty cells connected to them within `reach` of the box (its shadow, the colour
/// edges around it), which would otherwise look like an outline next to it.
void MaskFixture(OutlineGrid& g, const Eigen::Vector2f& lo, const Eigen::Vector2f& hi, float margin,
                 float reach) {
    if (g.nu == 0) return;
    const int m = static_cast<int>(std::ceil(margin / g.cell));
    const int r = static_cast<int>(std::ceil(reach / g.cell));
    const int u0 = g.U(lo.x()), u1 = g.U(hi.x()), v0 = g.V(lo.y()), v1 = g.V(hi.y());
    std::vector<std::pair<int, int>> queue;
    std::vector<std::uint8_t> seen(g.mark.size(), 0);
    auto index = [&](int u, int v) { return static_cast<std::size_t>(v * g.nu + u); };
    for (int v = std::max(0, v0 - m); v <= std::min(g.nv - 1, v1 + m); ++v) {
        for (int u = std::max(0, u0 - m); u <= std::min(g.nu - 1, u1 + m); ++u) {
            seen[index(u, v)] = 1;
            queue.emplace_back(u, v);
        }
    }
    for (std::size_t k = 0; k < queue.size(); ++k) {
        const auto [u, v] = queue[k];
        for (int dv = -1; dv <= 1; ++dv) {
            for (int du = -1; du <= 1; ++du) {
                const int uu = u + du, vv = v + dv;
                if (uu < 0 || vv < 0 || uu >= g.nu || vv >= g.nv || seen[index(uu, vv)]) continue;
                if (uu < u0 - r || uu > u1 + r || vv < v0 - r || vv > v1 + r) continue;
                if (g.mark[index(uu, vv)] == kFaceCell) continue;
                seen[index(uu, vv)] = 1;
                queue.emplace_back(uu, vv);
            }
        }
    }
    for (const auto& [u, v] : queue) g.mark[index(u, v)] = kMasked;
}

void MaskFixtures(OutlineGrid& g, const PointCloud& cloud, const RoomFrame& frame,
                  const PlanarComponent& face, int f, const std::vector<Fixture>& fixtures,
                  const FrontEdgeParams& p) {
    for (const Fixture& fx : fixtures) {
        if (fx.face != f || fx.indices.empty()) continue;
        Eigen::Vector2f lo = Eigen::Vector2f::Constant(std::numeric_limits<float>::infinity());
        Eigen::Vector2f hi = -lo;
        for (const Index i : fx.indices) {
            const Eigen::Vector2f q = PlaneCoordinates(face, frame, cloud.points[i]);
            lo = lo.cwiseMin(q);
            hi = hi.cwiseMax(q);
        }
        MaskFixture(g, lo, hi, p.margin,
                    p.margin + p.shadow_factor * std::max(fx.protrusion, 0.0f));
    }
}

LineCount CountLine(const OutlineGrid& g, bool columns, int k, int a, int b) {
    LineCount n;
    int run = 0;
    for (int t = a; t <= b; ++t) {
        bool points = false, gap = false;
        for (int d = -1; d <= 1; ++d) {
            const std::uint8_t m = columns ? g.At(k + d, t) : g.At(t, k + d);
            points = points || m == kFaceCell || m == kGapCell;
            gap = gap || m == kGapCell;
            n.masked = n.masked || m == kMasked;
        }
        n.points += points;
        n.gap += gap;
        // Cells without points (hidden, masked) neither break a run nor add to it.
        if (points) run = gap ? run + 1 : 0;
        n.run = std::max(n.run, run);
    }
    return n;
}

OwnLineCount CountOwnLine(const OutlineGrid& g, bool columns, int k, int a, int b) {
    OwnLineCount n;
    for (int t = a; t <= b; ++t) {
        const std::uint8_t m = columns ? g.At(k, t) : g.At(t, k);
        n.points += m == kFaceCell || m == kGapCell;
        n.gap += m == kGapCell;
        n.masked += m == kMasked;
    }
    return n;
}

bool IsOutline(const LineCount& n, int length, float coverage, float support) {
    return n.points > 0 && static_cast<float>(n.points) >= coverage * static_cast<float>(length) &&
           static_cast<float>(n.gap) >= support * static_cast<float>(n.points);
}

std::vector<std::uint8_t> FixturePoints(std::size_t num_points,
                                        const std::vector<Fixture>& fixtures) {
    std::vector<std::uint8_t> is_fixture(num_points, 0);
    for (const Fixture& fx : fixtures) {
        for (const Index i : fx.indices) {
            if (i < num_points) is_fixture[i] = 1;
        }
    }
    return is_fixture;
}

std::vector<Indices> FacePoints(std::size_t num_points, const RoomStructure& s,
                                const FrontEvidence& ev) {
    std::vector<Indices> out(s.components.size());
    if (ev.point_face.empty()) {
        for (std::size_t c = 0; c < s.components.size(); ++c) out[c] = s.components[c].indices;
        return out;
    }
    for (std::size_t i = 0; i < num_points && i < ev.point_face.size(); ++i) {
        const std::int32_t f = ev.point_face[i];
        if (f >= 0 && static_cast<std::size_t>(f) < out.size())
            out[static_cast<std::size_t>(f)].push_back(static_cast<Index>(i));
    }
    return out;
}

namespace {

/// A line counts as outline when it or a line beside it holds the gap, so the first outline
/// line met walking out of a front lies a cell before the gap. The gap's own line is the one of
/// `k` and the next two (in steps of `dir`) with the most gap cells of its own (the nearest of
/// equals): the side goes there, to the middle of the gap between two fronts.
int GapLine(const OutlineGrid& g, bool columns, int k, int dir, int a, int b) {
    const int limit = columns ? g.nu : g.nv;
    int best = k, best_gap = -1;
    for (int step = 0; step <= 2; ++step) {
        const int line = k + step * dir;
        if (line < 0 || line >= limit) break;
        const int gap = CountOwnLine(g, columns, line, a, b).gap;
        if (gap > best_gap) {
            best = line;
            best_gap = gap;
        }
    }
    return best;
}

}  // namespace

/// Searches from line `start` in steps of `dir` (+1 or -1) for a side: along u (columns, over
/// rows [a, b]) when `columns`, else along v (rows, over columns [a, b]). Returns the index of
/// the side's line (or of the last line with points when the face ends first).
int FindSide(const OutlineGrid& g, bool columns, int start, int dir, int a, int b,
             const FrontEdgeParams& p) {
    const int limit = columns ? g.nu : g.nv;
    const int end_run = std::max(1, static_cast<int>(std::lround(p.face_end / g.cell)));
    a = std::max(a, 0);
    b = std::min(b, (columns ? g.nv : g.nu) - 1);
    int last_seen = std::clamp(start, 0, limit - 1), empty_run = 0;
    for (int k = start; k >= 0 && k < limit; k += dir) {
        const LineCount n = CountLine(g, columns, k, a, b);
        if (n.points == 0) {
            if (!n.masked && ++empty_run >= end_run) return last_seen;
            continue;
        }
        empty_run = 0;
        last_seen = k;
        if (IsOutline(n, std::max(1, b - a + 1), p.min_coverage, p.min_support)) return k;
    }
    return last_seen;
}

/// Like FindSide, but walks at most `max_steps` lines: the index of the first line that is mostly
/// outline, or of the last line with points when the face ends first; -1 when neither happens
/// within max_steps.
int FindSideWithin(const OutlineGrid& g, bool columns, int start, int dir, int a, int b,
                   int max_steps, const FrontEdgeParams& p) {
    const int limit = columns ? g.nu : g.nv;
    const int end_run = std::max(1, static_cast<int>(std::lround(p.face_end / g.cell)));
    a = std::max(a, 0);
    b = std::min(b, (columns ? g.nv : g.nu) - 1);
    if (start < 0 || start >= limit || b < a) return -1;
    int last_seen = start, empty_run = 0;
    for (int k = start, steps = 0; k >= 0 && k < limit && steps <= max_steps; k += dir, ++steps) {
        const LineCount n = CountLine(g, columns, k, a, b);
        if (n.points == 0) {
            if (++empty_run >= end_run) return last_seen;
            continue;
        }
        empty_run = 0;
        last_seen = k;
        if (IsOutline(n, b - a + 1, p.min_coverage, p.extend_support))
            return GapLine(g, columns, k, dir, a, b);
    }
    // The face's last points lie within reach: it ends there.
    if (last_seen != start && (last_seen + dir < 0 || last_seen + dir >= limit)) return last_seen;
    return -1;
}

void CheckEvidence(const FrontEvidence& ev, std::size_t num_points) {
    for (const std::size_t size : {ev.point_face.size(), ev.point_residual.size(),
                                   ev.image_edge.size(), ev.appearance.size()}) {
        if (size != 0 && size != num_points) {
            throw InvalidArgument(
                fmt::format("front edges: evidence of {} points for {} points", size, num_points));
        }
    }
}

}  // namespace multicue::mapping::front_grid_internal

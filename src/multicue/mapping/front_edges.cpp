#include "multicue/mapping/front_edges.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "multicue/core/exceptions.hpp"
#include "multicue/mapping/fronts.hpp"

namespace multicue::mapping {
namespace {

/// Cell marks of a face's grid.
constexpr std::uint8_t kUnknown = 0, kFaceCell = 1, kGapCell = 2;
/// Cells a fixture hides or makes look like an outline: no evidence either way.
constexpr std::uint8_t kMasked = 3;

/// A face gridded in its plane: per cell unknown, face or gap.
struct OutlineGrid {
    Eigen::Vector2f origin = Eigen::Vector2f::Zero();
    float cell = 0.01f;
    int nu = 0, nv = 0;
    std::vector<std::uint8_t> mark;

    std::uint8_t At(int u, int v) const {
        return u < 0 || v < 0 || u >= nu || v >= nv ? kUnknown
                                                    : mark[static_cast<std::size_t>(v * nu + u)];
    }
    int U(float u) const { return static_cast<int>(std::floor((u - origin.x()) / cell)); }
    int V(float v) const { return static_cast<int>(std::floor((v - origin.y()) / cell)); }
    float UAt(int iu) const { return origin.x() + (static_cast<float>(iu) + 0.5f) * cell; }
    float VAt(int iv) const { return origin.y() + (static_cast<float>(iv) + 0.5f) * cell; }
};

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
        int with_points = 0, with_gap = 0;
        bool masked = false;
        for (int t = a; t <= b; ++t) {
            bool points = false, gap = false;
            for (int d = -1; d <= 1; ++d) {
                const std::uint8_t m = columns ? g.At(k + d, t) : g.At(t, k + d);
                points = points || m == kFaceCell || m == kGapCell;
                gap = gap || m == kGapCell;
                masked = masked || m == kMasked;
            }
            with_points += points;
            with_gap += gap;
        }
        const int length = std::max(1, b - a + 1);
        if (with_points == 0) {
            if (!masked && ++empty_run >= end_run) return last_seen;
            continue;
        }
        empty_run = 0;
        last_seen = k;
        if (static_cast<float>(with_points) >= p.min_coverage * static_cast<float>(length) &&
            static_cast<float>(with_gap) >= p.min_support * static_cast<float>(with_points)) {
            return k;
        }
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
        int with_points = 0, with_gap = 0;
        for (int t = a; t <= b; ++t) {
            bool points = false, gap = false;
            for (int d = -1; d <= 1; ++d) {
                const std::uint8_t m = columns ? g.At(k + d, t) : g.At(t, k + d);
                points = points || m == kFaceCell || m == kGapCell;
                gap = gap || m == kGapCell;
            }
            with_points += points;
            with_gap += gap;
        }
        if (with_points == 0) {
            if (++empty_run >= end_run) return last_seen;
            continue;
        }
        empty_run = 0;
        last_seen = k;
        if (static_cast<float>(with_points) >= p.min_coverage * static_cast<float>(b - a + 1) &&
            static_cast<float>(with_gap) >= p.extend_support * static_cast<float>(with_points)) {
            return k;
        }
    }
    // The face's last points lie within reach: it ends there.
    if (last_seen != start && (last_seen + dir < 0 || last_seen + dir >= limit)) return last_seen;
    return -1;
}

/// Squared distance from q to the nearest point of a footprint.
float Distance2(const std::vector<Eigen::Vector2f>& footprint, const Eigen::Vector2f& q) {
    float best = std::numeric_limits<float>::infinity();
    for (const auto& f : footprint) best = std::min(best, (f - q).squaredNorm());
    return best;
}

float RectIou(const Eigen::Vector2f& a0, const Eigen::Vector2f& a1, const Eigen::Vector2f& b0,
              const Eigen::Vector2f& b1) {
    const Eigen::Vector2f lo = a0.cwiseMax(b0), hi = a1.cwiseMin(b1);
    const float inter = std::max(0.0f, hi.x() - lo.x()) * std::max(0.0f, hi.y() - lo.y());
    const float area = (a1 - a0).prod() + (b1 - b0).prod() - inter;
    return area > 0.0f ? inter / area : 0.0f;
}

}  // namespace

void ImageEdgeParams::Validate() const {
    if (!(low >= 0.0f) || !(high >= low) ||
        !(stretch_quantile >= 0.0f && stretch_quantile < 0.5f)) {
        throw InvalidArgument(fmt::format(
            "image edges: need 0 <= low <= high and stretch_quantile in [0, 0.5), got {}, {}, {}",
            low, high, stretch_quantile));
    }
}

std::vector<std::uint8_t> ImageEdges(const PointCloud& scan, const ImageEdgeParams& p) {
    p.Validate();
    std::vector<std::uint8_t> out(scan.size(), 0);
    if (!scan.IsOrganized() || (!scan.HasColors() && !scan.HasIntensity())) return out;
    const int w = static_cast<int>(scan.width), h = static_cast<int>(scan.height);
    cv::Mat grey(h, w, CV_8UC1, cv::Scalar(0));
    if (scan.HasColors()) {
        for (std::size_t i = 0; i < scan.size(); ++i) {
            const Color& c = scan.colors[i];
            if (!scan.IsFinite(i) || c.a == 0) continue;
            grey.data[i] = static_cast<std::uint8_t>(
                std::clamp(0.299f * c.r + 0.587f * c.g + 0.114f * c.b, 0.0f, 255.0f));
        }
    } else {
        std::vector<float> v;
        for (std::size_t i = 0; i < scan.size(); ++i) {
            if (scan.IsFinite(i) && std::isfinite(scan.intensity[i]))
                v.push_back(scan.intensity[i]);
        }
        if (v.empty()) return out;
        auto quantile = [&](float q) {
            const auto k = static_cast<long>(q * static_cast<float>(v.size() - 1));
            std::nth_element(v.begin(), v.begin() + k, v.end());
            return v[static_cast<std::size_t>(k)];
        };
        const float lo = quantile(p.stretch_quantile), hi = quantile(1.0f - p.stretch_quantile);
        const float scale = hi > lo ? 254.0f / (hi - lo) : 1.0f;
        for (std::size_t i = 0; i < scan.size(); ++i) {
            if (!scan.IsFinite(i) || !std::isfinite(scan.intensity[i])) continue;
            grey.data[i] = static_cast<std::uint8_t>(
                std::clamp(1.0f + (scan.intensity[i] - lo) * scale, 1.0f, 255.0f));
        }
    }
    cv::Mat edges;
    cv::Canny(grey, edges, p.low, p.high);
    for (std::size_t i = 0; i < scan.size(); ++i) out[i] = edges.data[i] ? 1 : 0;
    return out;
}

void FrontEdgeParams::Validate() const {
    auto positive = [](const char* name, float v) {
        if (!(v > 0.0f) || !std::isfinite(v)) {
            throw InvalidArgument(fmt::format("front edges: {} must be > 0, got {}", name, v));
        }
    };
    positive("cell", cell);
    positive("recess", recess);
    positive("step", step);
    positive("face_end", face_end);
    positive("min_size", min_size);
    positive("start_reach", start_reach);
    positive("max_extend", max_extend);
    positive("appearance_step", appearance_step);
    if (!(min_support > 0.0f && min_support <= 1.0f) ||
        !(min_coverage >= 0.0f && min_coverage <= 1.0f) || !(margin >= 0.0f) ||
        !(shadow_factor >= 0.0f) || hole_reach < 0 || rounds < 1 ||
        !(same_front_iou > 0.0f && same_front_iou <= 1.0f) || min_points < 1 ||
        !(extend_support > 0.0f && extend_support <= 1.0f)) {
        throw InvalidArgument(fmt::format(
            "front edges: need min_support in (0, 1], min_coverage in [0, 1], margin >= 0, "
            "shadow_factor >= 0, hole_reach >= 0, rounds >= 1, same_front_iou in (0, 1], "
            "min_points >= 1, extend_support in (0, 1] (got {}, {}, {}, {}, {}, {}, {}, {}, {})",
            min_support, min_coverage, margin, shadow_factor, hole_reach, rounds, same_front_iou,
            min_points, extend_support));
    }
}

std::vector<Front> FrontsFromEdges(const PointCloud& cloud, const RoomFrame& frame,
                                   const RoomStructure& s, const std::vector<Fixture>& fixtures,
                                   const FrontEvidence& ev, const FrontEdgeParams& p) {
    p.Validate();
    for (const std::size_t size : {ev.point_face.size(), ev.point_residual.size(),
                                   ev.image_edge.size(), ev.appearance.size()}) {
        if (size != 0 && size != cloud.size()) {
            throw InvalidArgument(fmt::format("front edges: evidence of {} points for {} points",
                                              size, cloud.size()));
        }
    }
    std::vector<Front> fronts;
    if (cloud.empty() || fixtures.empty()) return fronts;
    const std::vector<bool> panel = PanelKnobs(fixtures);
    std::vector<std::uint8_t> is_fixture(cloud.size(), 0);
    for (const Fixture& fx : fixtures) {
        for (const Index i : fx.indices) is_fixture[i] = 1;
    }
    // The points measured against each face.
    std::vector<Indices> face_points(s.components.size());
    if (ev.point_face.empty()) {
        for (std::size_t c = 0; c < s.components.size(); ++c)
            face_points[c] = s.components[c].indices;
    } else {
        for (std::size_t i = 0; i < cloud.size(); ++i) {
            const std::int32_t f = ev.point_face[i];
            if (f >= 0 && static_cast<std::size_t>(f) < face_points.size()) {
                face_points[static_cast<std::size_t>(f)].push_back(static_cast<Index>(i));
            }
        }
    }
    for (std::size_t f = 0; f < s.components.size(); ++f) {
        const PlanarComponent& face = s.components[f];
        std::vector<int> mine;
        for (std::size_t x = 0; x < fixtures.size(); ++x) {
            if (fixtures[x].face == static_cast<int>(f) && !panel[x])
                mine.push_back(static_cast<int>(x));
        }
        if (mine.empty() || face_points[f].empty()) continue;
        OutlineGrid g = BuildGrid(cloud, frame, face, face_points[f], ev, is_fixture, p);
        if (g.nu == 0) continue;
        for (std::size_t x = 0; x < fixtures.size(); ++x) {
            if (fixtures[x].face != static_cast<int>(f)) continue;
            Eigen::Vector2f lo = Eigen::Vector2f::Constant(std::numeric_limits<float>::infinity());
            Eigen::Vector2f hi = -lo;
            for (const Index i : fixtures[x].indices) {
                const Eigen::Vector2f q = PlaneCoordinates(face, frame, cloud.points[i]);
                lo = lo.cwiseMin(q);
                hi = hi.cwiseMax(q);
            }
            MaskFixture(g, lo, hi, p.margin,
                        p.margin + p.shadow_factor * std::max(fixtures[x].protrusion, 0.0f));
        }
        struct Rect {
            Eigen::Vector2f lo, hi;
            std::vector<int> fixtures;
            std::vector<Eigen::Vector2f> footprint;
        };
        std::vector<Rect> rects;
        const int margin = static_cast<int>(std::ceil(p.margin / g.cell));
        const int reach = static_cast<int>(std::ceil(p.start_reach / g.cell));
        for (const int x : mine) {
            const Fixture& fx = fixtures[static_cast<std::size_t>(x)];
            std::vector<Eigen::Vector2f> fp;
            Eigen::Vector2f flo = Eigen::Vector2f::Constant(std::numeric_limits<float>::infinity());
            Eigen::Vector2f fhi = -flo;
            for (const Index i : fx.indices) {
                fp.push_back(PlaneCoordinates(face, frame, cloud.points[i]));
                flo = flo.cwiseMin(fp.back());
                fhi = fhi.cwiseMax(fp.back());
            }
            const int u0 = g.U(flo.x()), u1 = g.U(fhi.x()), v0 = g.V(flo.y()), v1 = g.V(fhi.y());
            int left = u0 - reach, right = u1 + reach, bottom = v0 - reach, top = v1 + reach;
            // Across the handle's bar first: its nearest sides (a drawer's top and bottom).
            const bool vertical = std::abs(fx.direction.dot(PlaneV(face, frame))) >
                                  std::abs(fx.direction.dot(PlaneU(face, frame)));
            bool sides_first = fx.type != FixtureType::kHandle || vertical;
            for (int r = 0; r < 2 * p.rounds; ++r, sides_first = !sides_first) {
                if (sides_first) {
                    left = FindSide(g, true, u0 - margin, -1, bottom, top, p);
                    right = FindSide(g, true, u1 + margin, 1, bottom, top, p);
                } else {
                    bottom = FindSide(g, false, v0 - margin, -1, left, right, p);
                    top = FindSide(g, false, v1 + margin, 1, left, right, p);
                }
            }
            Rect rect{{g.UAt(left), g.VAt(bottom)}, {g.UAt(right), g.VAt(top)}, {x}, std::move(fp)};
            if ((rect.hi - rect.lo).minCoeff() < p.min_size) continue;
            bool merged = false;
            for (Rect& other : rects) {
                if (RectIou(rect.lo, rect.hi, other.lo, other.hi) >= p.same_front_iou) {
                    other.fixtures.push_back(x);
                    other.footprint.insert(other.footprint.end(), rect.footprint.begin(),
                                           rect.footprint.end());
                    merged = true;
                    break;
                }
            }
            if (!merged) rects.push_back(std::move(rect));
        }
        // The face's points inside each rectangle; a point in several goes to the nearest
        // fixture.
        std::vector<Indices> members(rects.size());
        std::vector<bool> overlapping(rects.size(), false);
        for (const Index i : face_points[f]) {
            if (is_fixture[i]) continue;
            const Eigen::Vector2f q = PlaneCoordinates(face, frame, cloud.points[i]);
            int best = -1, inside = 0;
            float bd = std::numeric_limits<float>::infinity();
            for (std::size_t r = 0; r < rects.size(); ++r) {
                if ((q.array() < rects[r].lo.array()).any() ||
                    (q.array() > rects[r].hi.array()).any()) {
                    continue;
                }
                ++inside;
                const float d = Distance2(rects[r].footprint, q);
                if (d < bd) {
                    bd = d;
                    best = static_cast<int>(r);
                }
            }
            if (best < 0) continue;
            members[static_cast<std::size_t>(best)].push_back(i);
            if (inside > 1) overlapping[static_cast<std::size_t>(best)] = true;
        }
        const Eigen::Vector3f u = PlaneU(face, frame), v = PlaneV(face, frame);
        for (std::size_t r = 0; r < rects.size(); ++r) {
            if (members[r].size() < p.min_points) continue;
            Front fr;
            fr.face = static_cast<int>(f);
            fr.fixtures = rects[r].fixtures;
            std::sort(members[r].begin(), members[r].end());
            fr.indices = std::move(members[r]);
            fr.min = rects[r].lo;
            fr.max = rects[r].hi;
            fr.u_axis = u;
            fr.v_axis = v;
            fr.normal = face.plane.head<3>();
            const Eigen::Vector2f c = (fr.min + fr.max) / 2;
            fr.center = u * c.x() + v * c.y() - fr.normal * face.plane.w();
            fr.overlapping = overlapping[r];
            fr.model_iterations = p.rounds;
            fronts.push_back(std::move(fr));
        }
    }
    return fronts;
}

}  // namespace multicue::mapping

namespace multicue::mapping {

void ExtendFrontsToOutlines(const PointCloud& cloud, const RoomFrame& frame, const RoomStructure& s,
                            const std::vector<Fixture>& fixtures, const FrontEvidence& ev,
                            std::vector<Front>& fronts, const FrontEdgeParams& p) {
    p.Validate();
    for (const std::size_t size : {ev.point_face.size(), ev.point_residual.size(),
                                   ev.image_edge.size(), ev.appearance.size()}) {
        if (size != 0 && size != cloud.size()) {
            throw InvalidArgument(fmt::format("front edges: evidence of {} points for {} points",
                                              size, cloud.size()));
        }
    }
    if (cloud.empty() || fronts.empty()) return;
    std::vector<std::uint8_t> is_fixture(cloud.size(), 0);
    for (const Fixture& fx : fixtures) {
        for (const Index i : fx.indices) {
            if (i < cloud.size()) is_fixture[i] = 1;
        }
    }
    // Which front holds each point now: extensions take no point of another front.
    std::vector<std::int32_t> owner(cloud.size(), -1);
    for (std::size_t r = 0; r < fronts.size(); ++r) {
        for (const Index i : fronts[r].indices) owner[i] = static_cast<std::int32_t>(r);
    }
    for (std::size_t f = 0; f < s.components.size(); ++f) {
        std::vector<std::size_t> mine;
        for (std::size_t r = 0; r < fronts.size(); ++r) {
            if (fronts[r].face == static_cast<int>(f)) mine.push_back(r);
        }
        if (mine.empty()) continue;
        const PlanarComponent& face = s.components[f];
        Indices grid_points;
        if (ev.point_face.empty()) {
            grid_points = face.indices;
        } else {
            for (std::size_t i = 0; i < cloud.size(); ++i) {
                if (ev.point_face[i] == static_cast<std::int32_t>(f))
                    grid_points.push_back(static_cast<Index>(i));
            }
        }
        if (grid_points.empty()) continue;
        OutlineGrid g = BuildGrid(cloud, frame, face, grid_points, ev, is_fixture, p);
        if (g.nu == 0) continue;
        for (const Fixture& fx : fixtures) {
            if (fx.face != static_cast<int>(f) || fx.indices.empty()) continue;
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
        const int steps = static_cast<int>(std::ceil(p.max_extend / g.cell));
        std::vector<std::pair<Eigen::Vector2f, Eigen::Vector2f>> grown(mine.size());
        for (std::size_t k = 0; k < mine.size(); ++k) {
            const Front& fr = fronts[mine[k]];
            Eigen::Vector2f lo = fr.min, hi = fr.max;
            const int u0 = std::clamp(g.U(lo.x()), 0, g.nu - 1);
            const int u1 = std::clamp(g.U(hi.x()), 0, g.nu - 1);
            const int v0 = std::clamp(g.V(lo.y()), 0, g.nv - 1);
            const int v1 = std::clamp(g.V(hi.y()), 0, g.nv - 1);
            if (const int l = FindSideWithin(g, true, u0, -1, v0, v1, steps, p); l >= 0)
                lo.x() = std::min(lo.x(), g.UAt(l));
            if (const int r = FindSideWithin(g, true, u1, 1, v0, v1, steps, p); r >= 0)
                hi.x() = std::max(hi.x(), g.UAt(r));
            if (const int b = FindSideWithin(g, false, v0, -1, u0, u1, steps, p); b >= 0)
                lo.y() = std::min(lo.y(), g.VAt(b));
            if (const int t = FindSideWithin(g, false, v1, 1, u0, u1, steps, p); t >= 0)
                hi.y() = std::max(hi.y(), g.VAt(t));
            // Never into another front's rectangle.
            for (const std::size_t o : mine) {
                if (o == mine[k]) continue;
                const Eigen::Vector2f olo = fronts[o].min, ohi = fronts[o].max;
                const bool rows = olo.y() < fr.max.y() && ohi.y() > fr.min.y();
                const bool cols = olo.x() < fr.max.x() && ohi.x() > fr.min.x();
                if (rows && ohi.x() <= fr.min.x()) lo.x() = std::max(lo.x(), ohi.x());
                if (rows && olo.x() >= fr.max.x()) hi.x() = std::min(hi.x(), olo.x());
                if (cols && ohi.y() <= fr.min.y()) lo.y() = std::max(lo.y(), ohi.y());
                if (cols && olo.y() >= fr.max.y()) hi.y() = std::min(hi.y(), olo.y());
            }
            grown[k] = {lo, hi};
        }
        for (std::size_t k = 0; k < mine.size(); ++k) {
            Front& fr = fronts[mine[k]];
            const auto& [lo, hi] = grown[k];
            for (const Index i : face.indices) {
                if (owner[i] >= 0 || is_fixture[i]) continue;
                const Eigen::Vector2f q = PlaneCoordinates(face, frame, cloud.points[i]);
                if ((q.array() < lo.array()).any() || (q.array() > hi.array()).any()) continue;
                owner[i] = static_cast<std::int32_t>(mine[k]);
                fr.indices.push_back(i);
            }
            std::sort(fr.indices.begin(), fr.indices.end());
            fr.min = lo;
            fr.max = hi;
            const Eigen::Vector2f c = (lo + hi) / 2;
            fr.center = fr.u_axis * c.x() + fr.v_axis * c.y() - fr.normal * face.plane.w();
        }
    }
}

}  // namespace multicue::mapping

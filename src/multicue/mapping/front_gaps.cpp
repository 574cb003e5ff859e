#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/mapping/front_edges.hpp"
#include "multicue/mapping/front_grid_internal.hpp"
#include "multicue/mapping/fronts.hpp"

namespace multicue::mapping {

using namespace front_grid_internal;

namespace {

/// Rectangles of points span their 1st to 99th percentiles (as SegmentFronts' do).
constexpr float kRectQuantile = 0.01f;

/// A rectangle of grid cells, bounds inclusive.
struct CellRect {
    int u0, u1, v0, v1;
};

/// The cells of `g` under the face rectangle [lo, hi], clamped to the grid.
CellRect CellsUnder(const OutlineGrid& g, const Eigen::Vector2f& lo, const Eigen::Vector2f& hi) {
    return {std::clamp(g.U(lo.x()), 0, g.nu - 1), std::clamp(g.U(hi.x()), 0, g.nu - 1),
            std::clamp(g.V(lo.y()), 0, g.nv - 1), std::clamp(g.V(hi.y()), 0, g.nv - 1)};
}

/// Which of disjoint cell rectangles of a grid holds a point of the face.
class CellParts {
  public:
    CellParts(const OutlineGrid& g, const std::vector<CellRect>& parts)
        : g_(g), part_(static_cast<std::size_t>(g.nu) * static_cast<std::size_t>(g.nv), -1) {
        for (std::size_t l = 0; l < parts.size(); ++l) {
            for (int v = parts[l].v0; v <= parts[l].v1; ++v) {
                for (int u = parts[l].u0; u <= parts[l].u1; ++u)
                    part_[static_cast<std::size_t>(v * g.nu + u)] = static_cast<std::int32_t>(l);
            }
        }
    }
    /// The part holding the cell of face coordinates `q`, clamped into `within`; -1: none.
    std::int32_t At(const Eigen::Vector2f& q, const CellRect& within) const {
        const int u = std::clamp(g_.U(q.x()), within.u0, within.u1);
        const int v = std::clamp(g_.V(q.y()), within.v0, within.v1);
        return part_[static_cast<std::size_t>(v * g_.nu + u)];
    }

  private:
    const OutlineGrid& g_;
    std::vector<std::int32_t> part_;
};

/// A cut: a run of lines (columns or rows, bounds inclusive) and the outline share they scored.
struct Cut {
    int first = -1, last = -1;
    float share = 0.0f;
};

/// The strongest cut of `r`: a column (`columns`) or row at least `margin` cells inside each
/// side whose line (one cell either side) is outline in the largest share of its cells with
/// points, at least p.cut_support of them, with points along p.cut_coverage of its length. A gap
/// is a few cells wide, so the lines next to it score as high: the cut is the whole run of lines
/// scoring the best. first = -1 for none.
Cut BestCut(const OutlineGrid& g, const CellRect& r, bool columns, int margin,
            const GapFrontParams& p) {
    const int lo = columns ? r.u0 : r.v0, hi = columns ? r.u1 : r.v1;
    const int first = lo + margin, last = hi - margin;
    const int a = columns ? r.v0 : r.u0, b = columns ? r.v1 : r.u1;
    const int length = b - a + 1;
    if (last < first) return {};
    std::vector<float> shares(static_cast<std::size_t>(last - first + 1), -1.0f);
    float best = -1.0f;
    for (int k = first; k <= last; ++k) {
        // The share is compared, not the count: cuts are ranked by it.
        const LineCount n = CountLine(g, columns, k, a, b);
        if (n.points == 0 ||
            static_cast<float>(n.points) < p.cut_coverage * static_cast<float>(length)) {
            continue;
        }
        const float share = static_cast<float>(n.gap) / static_cast<float>(n.points);
        if (share < p.cut_support) continue;
        if (static_cast<float>(n.run) < p.cut_run * static_cast<float>(n.points)) continue;
        shares[static_cast<std::size_t>(k - first)] = share;
        best = std::max(best, share);
    }
    if (best < 0.0f) return {};
    constexpr float kTie = 0.01f;
    std::size_t run0 = 0;
    while (shares[run0] < best - kTie) ++run0;
    std::size_t run1 = run0;
    while (run1 + 1 < shares.size() && shares[run1 + 1] >= best - kTie) ++run1;
    return {first + static_cast<int>(run0), first + static_cast<int>(run1), best};
}

/// Cuts `search` at its strongest line, recursively. A cut's run of lines is searched no more,
/// and its middle line divides the cells the two sides own (`own`, which the uncut rectangles
/// bring to `leaves`).
void Partition(const OutlineGrid& g, const CellRect& search, const CellRect& own, int margin,
               int depth, const GapFrontParams& p, std::vector<CellRect>& leaves) {
    if (depth < p.max_depth) {
        const Cut col = BestCut(g, search, true, margin, p);
        const Cut row = BestCut(g, search, false, margin, p);
        if (col.first >= 0 && col.share >= row.share) {
            const int mid = (col.first + col.last) / 2;
            Partition(g, {search.u0, col.first - 1, search.v0, search.v1},
                      {own.u0, mid, own.v0, own.v1}, margin, depth + 1, p, leaves);
            Partition(g, {col.last + 1, search.u1, search.v0, search.v1},
                      {mid + 1, own.u1, own.v0, own.v1}, margin, depth + 1, p, leaves);
            return;
        }
        if (row.first >= 0) {
            const int mid = (row.first + row.last) / 2;
            Partition(g, {search.u0, search.u1, search.v0, row.first - 1},
                      {own.u0, own.u1, own.v0, mid}, margin, depth + 1, p, leaves);
            Partition(g, {search.u0, search.u1, row.last + 1, search.v1},
                      {own.u0, own.u1, mid + 1, own.v1}, margin, depth + 1, p, leaves);
            return;
        }
    }
    leaves.push_back(own);
}

}  // namespace

void GapFrontParams::Validate() const {
    if (!(cut_support > 0.0f && cut_support <= 1.0f) ||
        !(cut_coverage >= 0.0f && cut_coverage <= 1.0f) || !(cut_run >= 0.0f && cut_run <= 1.0f) ||
        !(cut_margin >= 0.0f) || !(min_size > 0.0f) || !(max_width >= min_size) ||
        !(max_height >= min_size) || !std::isfinite(max_width) || !std::isfinite(max_height) ||
        !(min_fill >= 0.0f && min_fill <= 1.0f) || !(max_taken >= 0.0f && max_taken <= 1.0f) ||
        min_points < 1 || max_depth < 0) {
        throw InvalidArgument(
            fmt::format("gap fronts: need cut_support in (0, 1], cut_coverage and cut_run in "
                        "[0, 1], cut_margin >= 0, 0 < min_size <= max_width, max_height (finite), "
                        "min_fill and max_taken in [0, 1], min_points >= 1, "
                        "max_depth >= 0 (got {}, {}, {}, {}, {}, {}, {}, {}, {}, {}, {})",
                        cut_support, cut_coverage, cut_run, cut_margin, min_size, max_width,
                        max_height, min_fill, max_taken, min_points, max_depth));
    }
}

void AddFrontsFromGaps(const PointCloud& cloud, const RoomFrame& frame, const RoomStructure& s,
                       const std::vector<Fixture>& fixtures, const FrontEvidence& ev,
                       std::vector<Front>& fronts, const FrontEdgeParams& grid,
                       const GapFrontParams& p) {
    grid.Validate();
    p.Validate();
    CheckEvidence(ev, cloud.size());
    if (cloud.empty()) return;
    const std::vector<std::uint8_t> is_fixture = FixturePoints(cloud.size(), fixtures);
    std::vector<std::uint8_t> taken = is_fixture;
    std::vector<std::uint8_t> holders(cloud.size(), 0);  // fronts holding a point, at most 255
    for (const Front& fr : fronts) {
        for (const Index i : fr.indices) {
            if (i >= cloud.size()) continue;
            taken[i] = 1;
            holders[i] = static_cast<std::uint8_t>(std::min(255, holders[i] + 1));
        }
    }
    const std::vector<Indices> face_points = FacePoints(cloud.size(), s, ev);
    const std::size_t known = fronts.size();
    for (std::size_t f = 0; f < s.components.size(); ++f) {
        const PlanarComponent& face = s.components[f];
        if (face.label != MapClass::kFace || face.axis == 2 || face_points[f].empty()) continue;
        OutlineGrid g = BuildGrid(cloud, frame, face, face_points[f], ev, is_fixture, grid);
        if (g.nu == 0) continue;
        MaskFixtures(g, cloud, frame, face, static_cast<int>(f), fixtures, grid);
        const int margin = std::max(2, static_cast<int>(std::lround(p.cut_margin / g.cell)));
        // Fronts of fixtures that an outline parts keep the part holding their fixtures.
        for (std::size_t k = 0; k < known && p.split_fixture_fronts; ++k) {
            Front& fr = fronts[k];
            if (fr.face != static_cast<int>(f) || fr.fixtures.empty()) continue;
            const CellRect box = CellsUnder(g, fr.min, fr.max);
            std::vector<CellRect> parts;
            Partition(g, box, box, margin, 0, p, parts);
            if (parts.size() < 2) continue;
            const CellParts cell_parts(g, parts);
            auto part_of = [&](const Eigen::Vector3f& x) {
                return cell_parts.At(PlaneCoordinates(face, frame, x), box);
            };
            int keep = -1;
            for (const int x : fr.fixtures) {
                const int l = part_of(fixtures[static_cast<std::size_t>(x)].center);
                keep = keep == -1 || keep == l ? l : -2;
            }
            if (keep < 0) continue;  // fixtures in several parts (a pair's front), or none
            Indices kept;
            for (const Index i : fr.indices) {
                if (part_of(cloud.points[i]) == keep) {
                    kept.push_back(i);
                } else if (--holders[i] == 0 && !is_fixture[i]) {
                    taken[i] = 0;
                }
            }
            const CellRect& r = parts[static_cast<std::size_t>(keep)];
            const Eigen::Vector2f lo =
                fr.min.cwiseMax(g.origin + g.cell * Eigen::Vector2f(static_cast<float>(r.u0),
                                                                    static_cast<float>(r.v0)));
            const Eigen::Vector2f hi =
                fr.max.cwiseMin(g.origin + g.cell * Eigen::Vector2f(static_cast<float>(r.u1 + 1),
                                                                    static_cast<float>(r.v1 + 1)));
            fr.indices = std::move(kept);
            SetFrontRectangle(fr, face, frame, lo, hi);
        }
        std::vector<CellRect> leaves;
        const CellRect whole{0, g.nu - 1, 0, g.nv - 1};
        Partition(g, whole, whole, margin, 0, p, leaves);
        if (leaves.empty()) continue;
        // The free face points of each leaf.
        std::vector<Indices> members(leaves.size());
        const CellParts leaf_of(g, leaves);
        auto leaf_at = [&](const Eigen::Vector3f& x) {
            return leaf_of.At(PlaneCoordinates(face, frame, x), whole);
        };
        for (const Index i : face_points[f]) {
            if (taken[i]) continue;
            const std::int32_t l = leaf_at(cloud.points[i]);
            if (l >= 0) members[static_cast<std::size_t>(l)].push_back(i);
        }
        std::vector<std::uint8_t> used(leaves.size(), 0);
        // A front of a fixture takes the free points of the outline rectangle holding its
        // fixtures (of no other front's), up to a front's size: region growing stops where the
        // front's colour drifts, its outlines do not.
        if (p.grow_fixture_fronts) {
            std::vector<int> holder(leaves.size(), -1);  // -2: fixtures of several fronts
            for (std::size_t k = 0; k < known; ++k) {
                if (fronts[k].face != static_cast<int>(f)) continue;
                for (const int x : fronts[k].fixtures) {
                    const std::int32_t l = leaf_at(fixtures[static_cast<std::size_t>(x)].center);
                    if (l < 0) continue;
                    int& o = holder[static_cast<std::size_t>(l)];
                    o = (o == -1 || o == static_cast<int>(k)) ? static_cast<int>(k) : -2;
                }
            }
            for (std::size_t l = 0; l < leaves.size(); ++l) {
                const int k = holder[l];
                if (k < 0 || members[l].size() < p.min_points) continue;
                Front& fr = fronts[static_cast<std::size_t>(k)];
                const auto [leaf_lo, leaf_hi] =
                    PointsRectangle(cloud, frame, face, members[l], kRectQuantile);
                Eigen::Vector2f lo = fr.min.cwiseMin(leaf_lo), hi = fr.max.cwiseMax(leaf_hi);
                // A side already on an outline (the door's edge, a frame beyond it) stays.
                const auto [u0, u1, v0, v1] = CellsUnder(g, fr.min, fr.max);
                auto outline = [&](bool columns, int line, int from, int to) {
                    return IsOutline(CountLine(g, columns, line, from, to), to - from + 1,
                                     grid.min_coverage, grid.extend_support);
                };
                if (outline(true, u0, v0, v1)) lo.x() = fr.min.x();
                if (outline(true, u1, v0, v1)) hi.x() = fr.max.x();
                if (outline(false, v0, u0, u1)) lo.y() = fr.min.y();
                if (outline(false, v1, u0, u1)) hi.y() = fr.max.y();
                const Eigen::Vector2f size = hi - lo;
                if (size.x() > p.max_width || size.y() > p.max_height) continue;
                used[l] = 1;
                for (const Index i : members[l]) {
                    const Eigen::Vector2f q = PlaneCoordinates(face, frame, cloud.points[i]);
                    if ((q.array() >= lo.array()).all() && (q.array() <= hi.array()).all())
                        fr.indices.push_back(i);
                }
                std::sort(fr.indices.begin(), fr.indices.end());
                SetFrontRectangle(fr, face, frame, lo, hi);
            }
        }
        for (std::size_t l = 0; l < leaves.size(); ++l) {
            if (used[l]) continue;
            Indices& m = members[l];
            if (m.size() < p.min_points) continue;
            // The rectangle of its points (1st to 99th percentiles).
            const auto [lo, hi] = PointsRectangle(cloud, frame, face, m, kRectQuantile);
            const Eigen::Vector2f size = hi - lo;
            if (size.minCoeff() < p.min_size || size.x() > p.max_width || size.y() > p.max_height)
                continue;
            // Seen whole: cells of the rectangle holding points.
            const auto [cu0, cu1, cv0, cv1] = CellsUnder(g, lo, hi);
            int cells = 0, filled = 0;
            for (int v = cv0; v <= cv1; ++v) {
                for (int u = cu0; u <= cu1; ++u) {
                    ++cells;
                    const std::uint8_t mk = g.At(u, v);
                    filled += mk == kFaceCell || mk == kGapCell || mk == kMasked;
                }
            }
            if (static_cast<float>(filled) < p.min_fill * static_cast<float>(cells)) continue;
            // Not on a front found already (its rectangle may reach beyond its points).
            float on_known = 0.0f;
            for (std::size_t k = 0; k < known; ++k) {
                if (fronts[k].face != static_cast<int>(f)) continue;
                const Eigen::Vector2f a = lo.cwiseMax(fronts[k].min),
                                      b = hi.cwiseMin(fronts[k].max);
                on_known += std::max(0.0f, b.x() - a.x()) * std::max(0.0f, b.y() - a.y());
            }
            if (on_known > p.max_taken * size.prod()) continue;
            Front fr;
            fr.face = static_cast<int>(f);
            std::sort(m.begin(), m.end());
            fr.indices = std::move(m);
            SetFrontRectangle(fr, face, frame, lo, hi);
            fronts.push_back(std::move(fr));
        }
    }
}

}  // namespace multicue::mapping

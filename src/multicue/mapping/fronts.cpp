#include "multicue/mapping/fronts.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <deque>
#include <functional>
#include <limits>
#include <numeric>
#include <tuple>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/mapping/front_grid_internal.hpp"

namespace multicue::mapping {
namespace {

constexpr float kNoFrontValue = std::numeric_limits<float>::quiet_NaN();

/// Median and MAD of the values of `points` (skipping NaN).
template <typename Ids>
std::pair<float, float> MedianMad(const std::vector<float>& a, const Ids& points) {
    std::vector<float> v;
    v.reserve(points.size());
    for (const auto i : points) {
        if (!std::isnan(a[i])) v.push_back(a[i]);
    }
    if (v.empty()) return {kNoFrontValue, kNoFrontValue};
    auto median = [](std::vector<float>& x) {
        const auto mid = x.begin() + static_cast<long>(x.size() / 2);
        std::nth_element(x.begin(), mid, x.end());
        return *mid;
    };
    const float m = median(v);
    for (auto& x : v) x = std::abs(x - m);
    return {m, median(v)};
}

/// The model of a front: appearance and offset from the face, each as median and MAD.
struct Model {
    float a = 0.0f, a_mad = 0.0f;  ///< appearance
    float h = 0.0f, h_mad = 0.0f;  ///< offset from the face plane [m]
};

using Cells = std::vector<std::uint32_t>;

/// Cells reachable from `seeds` through 8-neighbours that fit the model and show no edge.
Cells Grow(const std::vector<float>& a, const std::vector<float>& h, int nu, int nv,
           const Cells& seeds, const Model& m, float alpha, float h_alpha, float local_alpha,
           std::vector<std::uint32_t>& stamp, std::uint32_t round) {
    auto fits = [&](std::uint32_t c) {
        return !std::isnan(a[c]) && std::abs(a[c] - m.a) <= alpha &&
               std::abs(h[c] - m.h) <= h_alpha;
    };
    Cells region;
    std::deque<std::uint32_t> queue;
    for (const std::uint32_t c : seeds) {
        if (stamp[c] == round || !fits(c)) continue;
        stamp[c] = round;
        queue.push_back(c);
    }
    while (!queue.empty()) {
        const std::uint32_t c = queue.front();
        queue.pop_front();
        region.push_back(c);
        const int u = static_cast<int>(c % static_cast<std::uint32_t>(nu));
        const int v = static_cast<int>(c / static_cast<std::uint32_t>(nu));
        for (int dv = -1; dv <= 1; ++dv) {
            for (int du = -1; du <= 1; ++du) {
                const int uu = u + du, vv = v + dv;
                if ((du == 0 && dv == 0) || uu < 0 || vv < 0 || uu >= nu || vv >= nv) continue;
                const auto n = static_cast<std::uint32_t>(vv * nu + uu);
                // The model, and no edge between the two cells.
                if (stamp[n] == round || !fits(n) || std::abs(a[n] - a[c]) > local_alpha) continue;
                stamp[n] = round;
                queue.push_back(n);
            }
        }
    }
    return region;
}

/// Squared distance in face coordinates from q to the nearest footprint point.
float FootprintDistance2(const std::vector<Eigen::Vector2f>& footprint, const Eigen::Vector2f& q) {
    float best = std::numeric_limits<float>::infinity();
    for (const auto& f : footprint) best = std::min(best, (f - q).squaredNorm());
    return best;
}

/// An outline between two members of a group of overlapping regions: member `a` (an index
/// into the group) lies below `at` along u (`columns`) or v, member `b` above it.
struct Separator {
    std::size_t a = 0, b = 0;
    bool columns = true;
    float at = 0.0f;
};

/// The share of gap among the cells of grid line `k` over [t0, t1] that hold points; -1 when
/// fewer than `coverage` of them hold points.
float LineGapShare(const front_grid_internal::OutlineGrid& g, bool columns, int k, int t0, int t1,
                   float coverage) {
    using namespace front_grid_internal;
    // Cells masked around a fixture hold points too, but what they show is the fixture's: they
    // count towards the line's coverage, not its share. A gap beside a door's handle runs through
    // the handle's mask over most of the door's height.
    constexpr int kMinCells = 5;
    const OwnLineCount n = CountOwnLine(g, columns, k, t0, t1);
    if (n.points < std::min(kMinCells, t1 - t0 + 1) ||
        static_cast<float>(n.points + n.masked) < coverage * static_cast<float>(t1 - t0 + 1)) {
        return -1.0f;
    }
    return static_cast<float>(n.gap) / static_cast<float>(n.points);
}

/// The lower and upper corner of a footprint.
std::pair<Eigen::Vector2f, Eigen::Vector2f> Box(const std::vector<Eigen::Vector2f>& pts) {
    Eigen::Vector2f lo = pts.front(), hi = lo;
    for (const auto& q : pts) {
        lo = lo.cwiseMin(q);
        hi = hi.cwiseMax(q);
    }
    return {lo, hi};
}

/// The outlines between the fixtures of overlapping regions: for every two members whose
/// footprints lie apart along u or v (more than twice the outline margin), the grid line between
/// them that is gap in the largest share of its cells with points (over the region's extent
/// across the line), when that share reaches `support`.
std::vector<Separator> OutlineSeparators(
    const PointCloud& cloud, const RoomFrame& frame, const PlanarComponent& face,
    const Indices& region, const front_grid_internal::OutlineGrid& g,
    const std::vector<std::vector<Eigen::Vector2f>>& footprints,
    const std::vector<std::size_t>& members, const FrontEdgeParams& ep, float support) {
    std::vector<Separator> out;
    if (g.nu == 0 || region.empty()) return out;
    Eigen::Vector2f rlo = Eigen::Vector2f::Constant(std::numeric_limits<float>::infinity());
    Eigen::Vector2f rhi = -rlo;
    for (const Index i : region) {
        const Eigen::Vector2f q = PlaneCoordinates(face, frame, cloud.points[i]);
        rlo = rlo.cwiseMin(q);
        rhi = rhi.cwiseMax(q);
    }
    auto box = [&](std::size_t m) { return Box(footprints[members[m]]); };
    for (std::size_t a = 0; a < members.size(); ++a) {
        for (std::size_t b = 0; b < members.size(); ++b) {
            if (a == b) continue;
            const auto [alo, ahi] = box(a);
            const auto [blo, bhi] = box(b);
            // b lies above a along the axis with the wider space between them.
            const Eigen::Vector2f space = blo - ahi;
            const int axis = space.x() >= space.y() ? 0 : 1;
            if (space[axis] <= 2.0f * ep.margin) continue;
            const bool columns = axis == 0;
            const int k0 = columns ? g.U(ahi.x() + ep.margin) : g.V(ahi.y() + ep.margin);
            const int k1 = columns ? g.U(blo.x() - ep.margin) : g.V(blo.y() - ep.margin);
            const int t0 = columns ? g.V(rlo.y()) : g.U(rlo.x());
            const int t1 = columns ? g.V(rhi.y()) : g.U(rhi.x());
            const float mid = (ahi[axis] + blo[axis]) / 2;
            float best = -1.0f, best_at = mid;
            for (int k = k0; k <= k1; ++k) {
                const float share = LineGapShare(g, columns, k, t0, t1, ep.min_coverage);
                if (share < 0.0f) continue;
                const float at = columns ? g.UAt(k) : g.VAt(k);
                if (share > best + 1e-6f || (std::abs(share - best) <= 1e-6f &&
                                             std::abs(at - mid) < std::abs(best_at - mid))) {
                    best = share;
                    best_at = at;
                }
            }
            if (best >= support) out.push_back({a, b, columns, best_at});
        }
    }
    return out;
}

/// FrontParams::pair_end_reach: whether two fixtures (footprints `fa`, `fb`) whose overlapping
/// regions cover `region` each lie within the reach of opposite ends of it, along the axis of the
/// wider space between them, and the region is no wider than one front. `in_row` (a group of
/// more than two regions): the two must also stand side by side in one row (their footprints,
/// grown by the seed radius, overlap in height), each be at most twice the seed radius tall, and
/// lie at least half the region's width apart.
bool OneFrontsPair(const PointCloud& cloud, const RoomFrame& frame, const PlanarComponent& face,
                   const Indices& region, const std::vector<Eigen::Vector2f>& fa,
                   const std::vector<Eigen::Vector2f>& fb, const FrontParams& p, bool in_row) {
    if (region.empty()) return false;
    auto [alo, ahi] = Box(fa);
    auto [blo, bhi] = Box(fb);
    const Eigen::Vector2f ab = blo - ahi, ba = alo - bhi;
    if (std::max(ab.maxCoeff(), ba.maxCoeff()) <= 0.0f) return false;  // they overlap
    const Eigen::Vector2f gap = ab.cwiseMax(ba);
    const float reach = 2.0f * p.seed_max;
    if (in_row && (gap.x() < gap.y() || gap.y() > reach || ahi.y() - alo.y() > reach ||
                   bhi.y() - blo.y() > reach)) {
        return false;
    }
    const auto [rlo, rhi] = PointsRectangle(cloud, frame, face, region, p.rect_percentile);
    if (in_row && gap.x() < 0.5f * (rhi.x() - rlo.x())) return false;
    if (ba.maxCoeff() > ab.maxCoeff()) {  // a is the lower one along the axis
        std::swap(alo, blo);
        std::swap(ahi, bhi);
    }
    const Eigen::Vector2f space = blo - ahi;
    const int axis = space.x() >= space.y() ? 0 : 1;
    return rhi[axis] - rlo[axis] <= p.pair_max_width && alo[axis] - rlo[axis] <= p.pair_end_reach &&
           rhi[axis] - bhi[axis] <= p.pair_end_reach;
}

/// Within a group of overlapping regions split between `members`: two members that no
/// separator parts and whose points make one front's pair (OneFrontsPair, in a row where the
/// group has more than two) become one front, the first keeping both fixtures: the two mounts
/// of a long bar across a drawer in a stack of drawers, found without the bar, while the mounts
/// of the drawers above and below are parted by their gaps. The handles of drawers in one
/// column, vertical handles of narrow doors side by side, and the centred handles of flaps side
/// by side, whose gaps no line shows, are no such pair.
void PairMembers(const PointCloud& cloud, const RoomFrame& frame, const PlanarComponent& face,
                 const std::vector<std::vector<Eigen::Vector2f>>& footprints,
                 const std::vector<Separator>& seps, const std::vector<std::size_t>& members,
                 const FrontParams& p, std::vector<Front>& grown) {
    std::vector<char> paired(members.size(), 0);
    for (std::size_t a = 0; a < members.size(); ++a) {
        for (std::size_t b = a + 1; b < members.size() && !paired[a]; ++b) {
            if (paired[b]) continue;
            const bool parted = std::any_of(seps.begin(), seps.end(), [&](const Separator& sp) {
                return (sp.a == a && sp.b == b) || (sp.a == b && sp.b == a);
            });
            if (parted) continue;
            Front& fa = grown[members[a]];
            Front& fb = grown[members[b]];
            Indices both;
            std::merge(fa.indices.begin(), fa.indices.end(), fb.indices.begin(), fb.indices.end(),
                       std::back_inserter(both));
            if (!OneFrontsPair(cloud, frame, face, both, footprints[members[a]],
                               footprints[members[b]], p, members.size() > 2)) {
                continue;
            }
            fa.indices = std::move(both);
            fa.fixtures.insert(fa.fixtures.end(), fb.fixtures.begin(), fb.fixtures.end());
            std::sort(fa.fixtures.begin(), fa.fixtures.end());
            fb.fixtures.clear();
            fb.indices.clear();
            paired[a] = paired[b] = 1;
        }
    }
}

}  // namespace

std::pair<Eigen::Vector2f, Eigen::Vector2f> PointsRectangle(const PointCloud& cloud,
                                                            const RoomFrame& frame,
                                                            const PlanarComponent& face,
                                                            const Indices& points, float quantile) {
    std::vector<float> us, vs;
    us.reserve(points.size());
    vs.reserve(points.size());
    for (const Index i : points) {
        const Eigen::Vector2f q = PlaneCoordinates(face, frame, cloud.points[i]);
        us.push_back(q.x());
        vs.push_back(q.y());
    }
    auto at = [](std::vector<float>& x, float q) {
        const auto k = static_cast<long>(std::floor(q * static_cast<float>(x.size() - 1)));
        std::nth_element(x.begin(), x.begin() + k, x.end());
        return x[static_cast<std::size_t>(k)];
    };
    return {{at(us, quantile), at(vs, quantile)},
            {at(us, 1.0f - quantile), at(vs, 1.0f - quantile)}};
}

void SetFrontRectangle(Front& front, const PlanarComponent& face, const RoomFrame& frame,
                       const Eigen::Vector2f& lo, const Eigen::Vector2f& hi) {
    front.min = lo;
    front.max = hi;
    front.u_axis = PlaneU(face, frame);
    front.v_axis = PlaneV(face, frame);
    front.normal = face.plane.head<3>();
    // The point of the plane at (u, v) = c: u * c.x + v * c.y + n * (-d).
    const Eigen::Vector2f c = (lo + hi) / 2;
    front.center = front.u_axis * c.x() + front.v_axis * c.y() - front.normal * face.plane.w();
}

std::vector<bool> PanelKnobs(const std::vector<Fixture>& fixtures) {
    std::vector<bool> panel(fixtures.size(), false);
    for (std::size_t i = 0; i < fixtures.size(); ++i) {
        if (fixtures[i].type != FixtureType::kKnob) continue;
        int near = 0;
        for (std::size_t j = 0; j < fixtures.size(); ++j) {
            if (j == i || fixtures[j].type != FixtureType::kKnob ||
                fixtures[j].face != fixtures[i].face) {
                continue;
            }
            const Eigen::Vector3f d = fixtures[j].center - fixtures[i].center;
            near += d.norm() < 0.3f && std::abs(d.z()) < 0.04f;
        }
        panel[i] = near >= 2;
    }
    return panel;
}

void FrontParams::Validate() const {
    auto positive = [](const char* name, float v) {
        if (!(v > 0.0f) || !std::isfinite(v)) {
            throw InvalidArgument(fmt::format("fronts: {} must be > 0, got {}", name, v));
        }
    };
    positive("intensity_scale", intensity_scale);
    positive("seed_max", seed_max);
    positive("cell_size", cell_size);
    if (!(min_fill >= 0.0f && min_fill <= 1.0f)) {
        throw InvalidArgument(fmt::format("fronts: min_fill must be in [0, 1], got {}", min_fill));
    }
    if (!(pair_end_reach >= 0.0f && pair_end_reach <= 1.0f) || !(pair_max_width > 0.0f) ||
        !std::isfinite(pair_max_width)) {
        throw InvalidArgument(
            fmt::format("fronts: need pair_end_reach in [0, 1] m and pair_max_width > 0 m (got {}, "
                        "{})",
                        pair_end_reach, pair_max_width));
    }
    if (!(split_support > 0.0f && split_support <= 1.0f)) {
        throw InvalidArgument(
            fmt::format("fronts: split_support must be in (0, 1], got {}", split_support));
    }
    positive("local_alpha", local_alpha);
    if (!(claim_front >= 0.0f) || !std::isfinite(claim_front) || !(claim_behind >= 0.0f) ||
        !std::isfinite(claim_behind) || !(claim_margin >= 0.0f) || !std::isfinite(claim_margin)) {
        throw InvalidArgument(fmt::format(
            "fronts: claim_front, claim_behind and claim_margin must be >= 0 m, got {}, {} and {}",
            claim_front, claim_behind, claim_margin));
    }
    positive("min_offset_alpha", min_offset_alpha);
    positive("alpha_mads", alpha_mads);
    positive("stable_change", stable_change);
    if (!(seed_min >= 0.0f && seed_min < seed_max)) {
        throw InvalidArgument(fmt::format("fronts: need 0 <= seed_min < seed_max, got {} and {}",
                                          seed_min, seed_max));
    }
    if (!(min_alpha >= 0.0f)) {
        throw InvalidArgument(fmt::format("fronts: min_alpha must be >= 0, got {}", min_alpha));
    }
    if (!(nest_share > 0.0f) || !(nest_depth >= 0.0f) || !std::isfinite(nest_depth)) {
        throw InvalidArgument(
            fmt::format("fronts: need nest_share > 0 and nest_depth >= 0 m (got {}, {})",
                        nest_share, nest_depth));
    }
    if (max_rounds < 1) {
        throw InvalidArgument(fmt::format("fronts: max_rounds must be >= 1, got {}", max_rounds));
    }
    if (!(overlap_share > 0.0f && overlap_share <= 1.0f)) {
        throw InvalidArgument(
            fmt::format("fronts: overlap_share must be in (0, 1], got {}", overlap_share));
    }
    if (!(rect_percentile >= 0.0f && rect_percentile < 0.5f)) {
        throw InvalidArgument(
            fmt::format("fronts: rect_percentile must be in [0, 0.5), got {}", rect_percentile));
    }
    if (min_points < 3) {
        throw InvalidArgument(fmt::format("fronts: min_points must be >= 3, got {}", min_points));
    }
}

std::vector<float> AppearanceValues(const PointCloud& cloud, AppearanceCue cue,
                                    float intensity_scale) {
    if (cue == AppearanceCue::kAuto) {
        cue = cloud.HasColors()      ? AppearanceCue::kColor
              : cloud.HasIntensity() ? AppearanceCue::kIntensity
                                     : AppearanceCue::kNone;
    }
    std::vector<float> a(cloud.size(), kNoFrontValue);
    if (cue == AppearanceCue::kNone) {
        std::fill(a.begin(), a.end(), 0.0f);
    } else if (cue == AppearanceCue::kColor) {
        if (!cloud.HasColors())
            throw DataError("fronts: the colour cue needs a cloud with colours");
        for (std::size_t i = 0; i < cloud.size(); ++i) {
            const Color& c = cloud.colors[i];
            // Alpha 0 marks points without a colour (a laser scan merged with camera frames).
            a[i] = c.a == 0 ? kNoFrontValue : 0.299f * c.r + 0.587f * c.g + 0.114f * c.b;
        }
    } else {
        if (!cloud.HasIntensity()) {
            throw DataError("fronts: the intensity cue needs a cloud with intensity");
        }
        for (std::size_t i = 0; i < cloud.size(); ++i) a[i] = cloud.intensity[i] * intensity_scale;
    }
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        if (!cloud.IsFinite(i) || !std::isfinite(a[i])) a[i] = kNoFrontValue;
    }
    return a;
}

std::vector<Front> SegmentFronts(const PointCloud& cloud, const RoomFrame& frame,
                                 const RoomStructure& s, const std::vector<Fixture>& fixtures,
                                 const FrontParams& p, const FrontEvidence* evidence,
                                 const FrontEdgeParams& outline) {
    p.Validate();
    if (evidence) {
        outline.Validate();
        front_grid_internal::CheckEvidence(*evidence, cloud.size());
    }
    std::vector<Front> fronts;
    if (cloud.empty() || fixtures.empty()) return fronts;
    const std::vector<float> a_raw = AppearanceValues(cloud, p.cue, p.intensity_scale);
    const std::vector<bool> panel = PanelKnobs(fixtures);
    // The outline evidence, for splitting regions that ran over the gap between two fronts.
    std::vector<Indices> face_points;
    std::vector<std::uint8_t> is_fixture;
    if (evidence) {
        face_points = front_grid_internal::FacePoints(cloud.size(), s, *evidence);
        is_fixture = front_grid_internal::FixturePoints(cloud.size(), fixtures);
    }
    for (std::size_t f = 0; f < s.components.size(); ++f) {
        const PlanarComponent& face = s.components[f];
        std::vector<int> mine;
        for (std::size_t x = 0; x < fixtures.size(); ++x) {
            if (fixtures[x].face == static_cast<int>(f) && !panel[x]) {
                mine.push_back(static_cast<int>(x));
            }
        }
        if (mine.empty()) continue;
        // The face's outline grid, built when first needed (empty without evidence).
        front_grid_internal::OutlineGrid outline_grid;
        bool have_grid = false;
        auto grid = [&]() -> const front_grid_internal::OutlineGrid& {
            if (!have_grid && evidence && !face_points[f].empty()) {
                outline_grid = front_grid_internal::BuildGrid(cloud, frame, face, face_points[f],
                                                              *evidence, is_fixture, outline);
                if (outline_grid.nu > 0) {
                    front_grid_internal::MaskFixtures(outline_grid, cloud, frame, face,
                                                      static_cast<int>(f), fixtures, outline);
                }
            }
            have_grid = true;
            return outline_grid;
        };
        // The face as a grid of cells in its plane, each with the mean appearance and offset of
        // its points: the region grows over cells, so neither the sensor's noise nor the depth
        // camera's quantisation steps (centimetres at 2-3 m) cut a front into pieces.
        const float cs = p.cell_size;
        Eigen::Vector2f lo = face.min - Eigen::Vector2f::Constant(cs);
        const auto nu = static_cast<int>(std::ceil((face.max.x() - lo.x()) / cs)) + 2;
        const auto nv = static_cast<int>(std::ceil((face.max.y() - lo.y()) / cs)) + 2;
        const std::size_t ncells = static_cast<std::size_t>(nu) * static_cast<std::size_t>(nv);
        std::vector<double> sum_a(ncells, 0.0), sum_h(ncells, 0.0);
        std::vector<std::uint32_t> n_a(ncells, 0), n_h(ncells, 0);
        std::vector<std::uint32_t> cell_of(face.indices.size());
        auto cell_at = [&](const Eigen::Vector2f& q) {
            const int iu = std::clamp(static_cast<int>((q.x() - lo.x()) / cs), 0, nu - 1);
            const int iv = std::clamp(static_cast<int>((q.y() - lo.y()) / cs), 0, nv - 1);
            return static_cast<std::uint32_t>(iv * nu + iu);
        };
        for (std::size_t k = 0; k < face.indices.size(); ++k) {
            const Index i = face.indices[k];
            const std::uint32_t c = cell_at(PlaneCoordinates(face, frame, cloud.points[i]));
            cell_of[k] = c;
            sum_h[c] += face.plane.head<3>().dot(cloud.points[i]) + face.plane.w();
            ++n_h[c];
            if (!std::isnan(a_raw[i])) {
                sum_a[c] += a_raw[i];
                ++n_a[c];
            }
        }
        std::vector<float> a(ncells, kNoFrontValue), h(ncells, kNoFrontValue);
        for (std::size_t c = 0; c < ncells; ++c) {
            if (n_a[c] > 0) a[c] = static_cast<float>(sum_a[c] / n_a[c]);
            if (n_h[c] > 0) h[c] = static_cast<float>(sum_h[c] / n_h[c]);
        }
        auto centre = [&](std::uint32_t c) {
            return Eigen::Vector2f(
                lo.x() + (static_cast<float>(c % static_cast<std::uint32_t>(nu)) + 0.5f) * cs,
                lo.y() + (static_cast<float>(c / static_cast<std::uint32_t>(nu)) + 0.5f) * cs);
        };
        std::vector<std::uint32_t> stamp(ncells, 0);
        std::uint32_t round = 0;
        std::vector<std::vector<Eigen::Vector2f>> footprints;
        std::vector<Front> grown;
        for (const int x : mine) {
            const Fixture& fx = fixtures[static_cast<std::size_t>(x)];
            std::vector<Eigen::Vector2f> fp;
            for (const Index i : fx.indices) {
                if (i < cloud.size()) fp.push_back(PlaneCoordinates(face, frame, cloud.points[i]));
            }
            if (fp.empty()) continue;  // a fixture without points of this cloud has no footprint
            // Seeds: cells in a ring around the footprint.
            const auto [flo, fhi] = Box(fp);
            Cells seeds;
            const float lo2 = p.seed_min * p.seed_min, hi2 = p.seed_max * p.seed_max;
            const std::uint32_t c0 = cell_at(flo - Eigen::Vector2f::Constant(p.seed_max));
            const std::uint32_t c1 = cell_at(fhi + Eigen::Vector2f::Constant(p.seed_max));
            const auto u0 = c0 % static_cast<std::uint32_t>(nu),
                       v0 = c0 / static_cast<std::uint32_t>(nu);
            const auto u1 = c1 % static_cast<std::uint32_t>(nu),
                       v1 = c1 / static_cast<std::uint32_t>(nu);
            for (std::uint32_t v = v0; v <= v1; ++v) {
                for (std::uint32_t u = u0; u <= u1; ++u) {
                    const std::uint32_t c = v * static_cast<std::uint32_t>(nu) + u;
                    if (std::isnan(a[c])) continue;
                    const float d2 = FootprintDistance2(fp, centre(c));
                    if (d2 >= lo2 && d2 <= hi2) seeds.push_back(c);
                }
            }
            Front front;
            front.face = static_cast<int>(f);
            front.fixtures = {x};
            Model m;
            std::tie(m.a, m.a_mad) = MedianMad(a, seeds);
            std::tie(m.h, m.h_mad) = MedianMad(h, seeds);
            if (seeds.empty() || std::isnan(m.a) || std::isnan(m.h)) continue;
            Cells region;
            for (int r = 0; r < p.max_rounds; ++r) {
                const float alpha = std::max(p.alpha_mads * m.a_mad, p.min_alpha);
                const float h_alpha = std::max(p.alpha_mads * m.h_mad, p.min_offset_alpha);
                region =
                    Grow(a, h, nu, nv, seeds, m, alpha, h_alpha, p.local_alpha, stamp, ++round);
                front.model_iterations = r + 1;
                Model next;
                std::tie(next.a, next.a_mad) = MedianMad(a, region);
                std::tie(next.h, next.h_mad) = MedianMad(h, region);
                if (std::isnan(next.a)) break;
                const bool stable = std::abs(next.a - m.a) < p.stable_change &&
                                    std::abs(next.a_mad - m.a_mad) < p.stable_change;
                m = next;
                if (stable) break;
            }
            front.appearance_median = m.a;
            front.appearance_mad = m.a_mad;
            // The region's points: the face points in its cells.
            std::vector<std::uint8_t> in(ncells, 0);
            for (const std::uint32_t c : region) in[c] = 1;
            for (std::size_t k = 0; k < face.indices.size(); ++k) {
                if (in[cell_of[k]]) front.indices.push_back(face.indices[k]);
            }
            std::sort(front.indices.begin(), front.indices.end());
            footprints.push_back(std::move(fp));
            grown.push_back(std::move(front));
        }
        // Overlapping regions: marked, merged into one set and split by the nearest footprint.
        const std::size_t g = grown.size();
        std::vector<int> group(g);
        for (std::size_t i = 0; i < g; ++i) group[i] = static_cast<int>(i);
        std::function<int(int)> find = [&](int i) {
            return group[static_cast<std::size_t>(i)] == i
                       ? i
                       : group[static_cast<std::size_t>(i)] =
                             find(group[static_cast<std::size_t>(i)]);
        };
        for (std::size_t i = 0; i < g; ++i) {
            for (std::size_t j = i + 1; j < g; ++j) {
                Indices common;
                std::set_intersection(grown[i].indices.begin(), grown[i].indices.end(),
                                      grown[j].indices.begin(), grown[j].indices.end(),
                                      std::back_inserter(common));
                const std::size_t smaller = std::max<std::size_t>(
                    1, std::min(grown[i].indices.size(), grown[j].indices.size()));
                if (static_cast<float>(common.size()) >=
                    p.overlap_share * static_cast<float>(smaller)) {
                    grown[i].overlapping = grown[j].overlapping = true;
                    group[static_cast<std::size_t>(find(static_cast<int>(i)))] =
                        find(static_cast<int>(j));
                }
            }
        }
        for (std::size_t root = 0; root < g; ++root) {
            if (find(static_cast<int>(root)) != static_cast<int>(root)) continue;
            std::vector<std::size_t> members;
            for (std::size_t i = 0; i < g; ++i) {
                if (find(static_cast<int>(i)) == static_cast<int>(root)) members.push_back(i);
            }
            if (members.size() > 1) {
                Indices all;
                for (const std::size_t i : members) {
                    all.insert(all.end(), grown[i].indices.begin(), grown[i].indices.end());
                }
                std::sort(all.begin(), all.end());
                all.erase(std::unique(all.begin(), all.end()), all.end());
                for (const std::size_t i : members) grown[i].indices.clear();
                const std::vector<Separator> seps =
                    p.split_at_outlines
                        ? OutlineSeparators(cloud, frame, face, all, grid(), footprints, members,
                                            outline, p.split_support)
                        : std::vector<Separator>{};
                for (const Index pt : all) {
                    const Eigen::Vector2f q = PlaneCoordinates(face, frame, cloud.points[pt]);
                    // The nearest of the members on whose side of every outline the point lies,
                    // or of all members where it lies on no one's side.
                    std::size_t best = members[0], best_sided = members[0];
                    float bd = std::numeric_limits<float>::infinity(), bd_sided = bd;
                    for (std::size_t m = 0; m < members.size(); ++m) {
                        const float d = FootprintDistance2(footprints[members[m]], q);
                        if (d < bd) {
                            bd = d;
                            best = members[m];
                        }
                        bool sided = true;
                        for (const Separator& sp : seps) {
                            if (sp.a != m && sp.b != m) continue;
                            const float x = sp.columns ? q.x() : q.y();
                            // Member a lies below the line, b above it.
                            sided = sided && (sp.a == m ? x <= sp.at : x >= sp.at);
                        }
                        if (sided && d < bd_sided) {
                            bd_sided = d;
                            best_sided = members[m];
                        }
                    }
                    if (bd_sided < std::numeric_limits<float>::infinity()) best = best_sided;
                    grown[best].indices.push_back(pt);
                }
                if (p.pair_end_reach > 0.0f)
                    PairMembers(cloud, frame, face, footprints, seps, members, p, grown);
            }
        }
        // Rectangles on the face plane.
        for (Front& fr : grown) {
            if (fr.indices.size() < p.min_points) continue;
            const auto [rect_lo, rect_hi] =
                PointsRectangle(cloud, frame, face, fr.indices, p.rect_percentile);
            SetFrontRectangle(fr, face, frame, rect_lo, rect_hi);
            // The rectangle stands for the front (thesis section 4.1.2: it still includes what
            // shadows kept the region from reaching): the face points inside it, when the region
            // fills most of it.
            if (p.fill_rectangle) {
                Indices inside;
                for (const Index i : face.indices) {
                    const Eigen::Vector2f q = PlaneCoordinates(face, frame, cloud.points[i]);
                    if ((q.array() >= fr.min.array()).all() &&
                        (q.array() <= fr.max.array()).all()) {
                        inside.push_back(i);
                    }
                }
                if (static_cast<float>(fr.indices.size()) >=
                    p.min_fill * static_cast<float>(inside.size())) {
                    fr.indices = std::move(inside);
                }
            }
            fronts.push_back(std::move(fr));
        }
    }
    return fronts;
}

namespace {

/// Throws InvalidArgument for a front on no face of `structure`.
void CheckFrontFaces(const RoomStructure& structure, const std::vector<Front>& fronts) {
    for (const Front& fr : fronts) {
        if (fr.face < 0 || static_cast<std::size_t>(fr.face) >= structure.components.size()) {
            throw InvalidArgument(fmt::format("fronts: a front lies on face {} of {}", fr.face,
                                              structure.components.size()));
        }
    }
}

}  // namespace

void ClaimUnexplainedPoints(const PointCloud& cloud, const RoomFrame& frame,
                            const RoomStructure& structure, const std::vector<Fixture>& fixtures,
                            std::vector<Front>& fronts, const FrontParams& p) {
    p.Validate();
    CheckFrontFaces(structure, fronts);
    if (p.claim_front <= 0.0f || fronts.empty()) return;
    const std::vector<std::uint8_t> fixture_point =
        front_grid_internal::FixturePoints(cloud.size(), fixtures);
    // Smallest rectangle first, so that a point in nested rectangles joins the inner one.
    std::vector<std::size_t> order(fronts.size());
    std::iota(order.begin(), order.end(), std::size_t{0});
    std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
        return (fronts[a].max - fronts[a].min).prod() < (fronts[b].max - fronts[b].min).prod();
    });
    // Each front's face plane and in-plane axes, once.
    struct FaceFrame {
        Eigen::Vector4f plane;
        Eigen::Vector3f u, v;
    };
    std::vector<FaceFrame> faces(fronts.size());
    for (std::size_t f = 0; f < fronts.size(); ++f) {
        const PlanarComponent& c = structure.components[static_cast<std::size_t>(fronts[f].face)];
        faces[f] = {c.plane, PlaneU(c, frame), PlaneV(c, frame)};
    }
    std::vector<Indices> claimed(fronts.size());
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        if (fixture_point[i] || !cloud.IsFinite(i) ||
            (i < structure.point_component.size() && structure.point_component[i] >= 0)) {
            continue;
        }
        const Eigen::Vector3f& x = cloud.points[i];
        // The smallest rectangle holding it, else the nearest within claim_margin.
        std::size_t best = fronts.size();
        float best_out = p.claim_margin;
        for (const std::size_t f : order) {
            const FaceFrame& face = faces[f];
            const float h = face.plane.head<3>().dot(x) + face.plane.w();
            if (h > p.claim_front || h < -p.claim_behind) continue;
            const Eigen::Vector2f q(x.dot(face.u), x.dot(face.v));
            const float out =
                std::max({fronts[f].min.x() - q.x(), q.x() - fronts[f].max.x(),
                          fronts[f].min.y() - q.y(), q.y() - fronts[f].max.y(), 0.0f});
            if (out <= 0.0f) {
                best = f;
                break;
            }
            if (out < best_out) {
                best = f;
                best_out = out;
            }
        }
        if (best < fronts.size()) claimed[best].push_back(static_cast<Index>(i));
    }
    for (std::size_t f = 0; f < fronts.size(); ++f) {
        if (claimed[f].empty()) continue;
        Indices& idx = fronts[f].indices;
        idx.insert(idx.end(), claimed[f].begin(), claimed[f].end());
        std::sort(idx.begin(), idx.end());
        idx.erase(std::unique(idx.begin(), idx.end()), idx.end());
    }
}

void MergeNestedFronts(const RoomStructure& structure, std::vector<Front>& fronts,
                       const FrontParams& p) {
    p.Validate();
    const std::size_t n = fronts.size();
    CheckFrontFaces(structure, fronts);
    if (p.nest_share > 1.0f || n < 2) return;
    auto area = [](const Front& f) { return (f.max - f.min).prod(); };
    // World corners of a front's rectangle.
    auto corners = [](const Front& f) {
        const Eigen::Vector3f du = 0.5f * (f.max.x() - f.min.x()) * f.u_axis;
        const Eigen::Vector3f dv = 0.5f * (f.max.y() - f.min.y()) * f.v_axis;
        return std::array<Eigen::Vector3f, 4>{f.center - du - dv, f.center + du - dv,
                                              f.center - du + dv, f.center + du + dv};
    };
    std::vector<std::size_t> order(n);
    for (std::size_t i = 0; i < n; ++i) order[i] = i;
    std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
        return area(fronts[a]) < area(fronts[b]);
    });
    std::vector<std::uint8_t> gone(n, 0);
    for (std::size_t oi = 0; oi < n; ++oi) {
        const std::size_t i = order[oi];
        const Front& inner = fronts[i];
        const float a_inner = area(inner);
        if (!(a_inner > 0.0f)) continue;
        const auto ci = corners(inner);
        // The smallest larger front holding it.
        for (std::size_t oj = oi + 1; oj < n; ++oj) {
            const std::size_t j = order[oj];
            Front& outer = fronts[j];
            const PlanarComponent& face =
                structure.components[static_cast<std::size_t>(outer.face)];
            // On its own face a front inside another is a neighbour the other's region ran
            // over, not a part of it.
            if (outer.face == inner.face) continue;
            const PlanarComponent& other =
                structure.components[static_cast<std::size_t>(inner.face)];
            if (other.axis != face.axis ||
                other.plane.head<3>().dot(face.plane.head<3>()) <= 0.0f ||
                std::abs(outer.normal.dot(inner.center - outer.center)) > p.nest_depth) {
                continue;
            }
            // The inner rectangle in the outer's face coordinates (relative to its centre).
            Eigen::Vector2f lo = Eigen::Vector2f::Constant(std::numeric_limits<float>::max());
            Eigen::Vector2f hi = -lo;
            for (const Eigen::Vector3f& c : ci) {
                const Eigen::Vector3f d = c - outer.center;
                const Eigen::Vector2f q(d.dot(outer.u_axis), d.dot(outer.v_axis));
                lo = lo.cwiseMin(q);
                hi = hi.cwiseMax(q);
            }
            const Eigen::Vector2f half = 0.5f * (outer.max - outer.min);
            const Eigen::Vector2f a = lo.cwiseMax(-half), b = hi.cwiseMin(half);
            const float shared = std::max(0.0f, b.x() - a.x()) * std::max(0.0f, b.y() - a.y());
            if (shared < p.nest_share * a_inner) continue;
            outer.indices.insert(outer.indices.end(), inner.indices.begin(), inner.indices.end());
            std::sort(outer.indices.begin(), outer.indices.end());
            outer.indices.erase(std::unique(outer.indices.begin(), outer.indices.end()),
                                outer.indices.end());
            outer.overlapping = outer.overlapping || inner.overlapping;
            gone[i] = 1;
            break;
        }
    }
    std::size_t kept = 0;
    for (std::size_t i = 0; i < n; ++i) {
        if (gone[i]) continue;
        if (kept != i) fronts[kept] = std::move(fronts[i]);
        ++kept;
    }
    fronts.resize(kept);
}

}  // namespace multicue::mapping

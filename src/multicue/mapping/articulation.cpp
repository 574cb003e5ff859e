#include "multicue/mapping/articulation.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <span>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/ml/classifier.hpp"
#include "multicue/search/kdtree.hpp"
#include "multicue/segmentation/sac_plane.hpp"

namespace multicue::mapping {
namespace {

constexpr float kArticulationDegToRad = 0.017453292519943295f;

/// A revolute joint about the front's edge line through `edge_point` (moved behind the surface by
/// the hinge depth), with `into_door` the in-plane direction from the edge into the front (the
/// axis runs along the edge).
Articulation Hinge(const Front& f, const Eigen::Vector3f& edge_point,
                   const Eigen::Vector3f& into_door, const ArticulationParams& p) {
    Articulation a;
    a.type = JointType::kRevolute;
    a.origin = edge_point - f.normal * p.hinge_depth;
    // A positive rotation about into_door x n moves the free edge along +n (out).
    a.axis = into_door.cross(f.normal).normalized();
    a.lower = 0.0f;
    a.upper = p.revolute_upper;
    a.source = "fixture";
    return a;
}

/// A drawer: prismatic, out of the face.
Articulation Drawer(const Front& f, const ArticulationParams& p) {
    Articulation a;
    a.type = JointType::kPrismatic;
    a.origin = f.center;
    a.axis = f.normal;
    a.lower = 0.0f;
    a.upper = p.prismatic_upper;
    a.source = "fixture";
    return a;
}

/// The `q` quantile of `values` (reordered; not empty).
float Quantile(std::vector<float>& values, float q) {
    const auto k = static_cast<std::ptrdiff_t>(q * static_cast<float>(values.size() - 1));
    std::nth_element(values.begin(), values.begin() + k, values.end());
    return values[static_cast<std::size_t>(k)];
}

/// What the opened scan could see around a front: its returns binned by direction from the
/// sensor (on the plane tangent to the direction towards the front, bins as wide as a coverage
/// cell at the front's distance), each bin holding its farthest return. A place in a bin without
/// returns (out of the field of view, no return) or behind the bin's farthest return (hidden by
/// something nearer) could not be seen.
class SeenFrom {
  public:
    SeenFrom() = default;  ///< knows nothing
    SeenFrom(const PointCloud& scan, const Eigen::Vector3f& target, float cell) {
        if (!scan.HasSensorPosition()) return;
        origin_ = scan.sensor_origin;
        const Eigen::Vector3f towards = target - origin_;
        const float distance = towards.norm();
        if (!(distance > 1e-3f) || !(cell > 0.0f)) return;
        z_ = towards / distance;
        x_ = z_.unitOrthogonal();
        y_ = z_.cross(x_);
        bin_ = cell / distance;
        // Up to 60 deg off the direction towards the front, at most 512 bins a side.
        side_ = std::clamp(static_cast<int>(std::ceil(2.0f * kHalfExtent / bin_)), 1, 512);
        bin_ = 2.0f * kHalfExtent / static_cast<float>(side_);
        farthest_.assign(static_cast<std::size_t>(side_) * static_cast<std::size_t>(side_), -1.0f);
        for (std::size_t i = 0; i < scan.size(); ++i) {
            if (!scan.IsFinite(i)) continue;
            const Eigen::Vector3f d = scan.points[i] - origin_;
            const std::ptrdiff_t b = Bin(d);
            if (b >= 0) {
                float& f = farthest_[static_cast<std::size_t>(b)];
                f = std::max(f, d.norm());
            }
        }
        valid_ = true;
    }
    bool valid() const { return valid_; }
    /// Whether the scan saw `x` or through it, within `tolerance` [m].
    bool Seen(const Eigen::Vector3f& x, float tolerance) const {
        if (!valid_) return false;
        const Eigen::Vector3f d = x - origin_;
        const std::ptrdiff_t b = Bin(d);
        return b >= 0 && farthest_[static_cast<std::size_t>(b)] >= d.norm() - tolerance;
    }

  private:
    static constexpr float kHalfExtent = 1.732f;  // tan(60 deg)
    std::ptrdiff_t Bin(const Eigen::Vector3f& d) const {
        const float z = d.dot(z_);
        if (!(z > 1e-3f)) return -1;
        const float tx = d.dot(x_) / z, ty = d.dot(y_) / z;
        const auto ix = static_cast<std::ptrdiff_t>(std::floor((tx + kHalfExtent) / bin_));
        const auto iy = static_cast<std::ptrdiff_t>(std::floor((ty + kHalfExtent) / bin_));
        if (ix < 0 || iy < 0 || ix >= side_ || iy >= side_) return -1;
        return iy * side_ + ix;
    }
    bool valid_ = false;
    Eigen::Vector3f origin_ = Eigen::Vector3f::Zero(), x_, y_, z_;
    float bin_ = 0.0f;
    int side_ = 0;
    std::vector<float> farthest_;
};

/// Closed-scan points on front `f` that the opened scan has no point near any more (the front
/// moved away, or its motion hides them), and the band of the rectangle they lie in: their 2 %
/// to 98 % quantiles along the front's vertical, grown by the change distance, across the whole
/// width. Drawers stack, and a drawer is as wide as its unit: a rectangle spanning several drawers
/// is cut along its height only (a door's vacated place can be narrower than the door, its part
/// near the hinge moving little, and a strip of it cut out would look like a slid drawer). The
/// band replaces `f` when it covers less than `vacated_max_share` of its height and at least two
/// coverage cells.
struct Vacated {
    Front part;              ///< the front, or the band of it that the motion vacated
    std::size_t points = 0;  ///< closed-scan points on the front the opened scan lost
};

Vacated VacatedPart(const KdTree& before, const PointCloud& opened, const Front& f,
                    const MotionParams& p) {
    Vacated out{f, 0};
    const float plane_d = -f.normal.dot(f.center);
    const float margin = p.change_distance;
    auto over_front = [&](const Eigen::Vector3f& x, float slack) {
        const float u = x.dot(f.u_axis), v = x.dot(f.v_axis);
        return u >= f.min.x() - slack && u <= f.max.x() + slack && v >= f.min.y() - slack &&
               v <= f.max.y() + slack;
    };
    Indices near;
    for (std::size_t i = 0; i < opened.size(); ++i) {
        if (!opened.IsFinite(i)) continue;
        const Eigen::Vector3f& x = opened.points[i];
        if (std::abs(f.normal.dot(x) + plane_d) <= p.plane_threshold + margin &&
            over_front(x, margin)) {
            near.push_back(static_cast<Index>(i));
        }
    }
    const KdTree after(opened, near);
    std::vector<float> vs;
    for (const Eigen::Vector3f& x : before.TreePoints()) {
        if (std::abs(f.normal.dot(x) + plane_d) > p.plane_threshold || !over_front(x, 0.0f)) {
            continue;
        }
        Index nn = 0;
        float d2 = 0.0f;
        if (!after.SearchNearestWithin(x, p.change_distance, nn, d2)) {
            vs.push_back(x.dot(f.v_axis));
        }
    }
    out.points = vs.size();
    if (p.vacated_max_share <= 0.0f || vs.size() < p.min_points) return out;
    // What the moved front left within change_distance of a surface that stayed (the drawer's
    // sides and bottom cross the face plane) was not counted: the band reaches that much farther.
    const float lo = std::max(f.min.y(), Quantile(vs, 0.02f) - p.change_distance);
    const float hi = std::min(f.max.y(), Quantile(vs, 0.98f) + p.change_distance);
    if (hi - lo < 2.0f * p.coverage_cell ||
        hi - lo >= p.vacated_max_share * (f.max.y() - f.min.y())) {
        return out;
    }
    out.part.min.y() = lo;
    out.part.max.y() = hi;
    out.part.center = f.center + f.v_axis * ((lo + hi - f.min.y() - f.max.y()) / 2.0f);
    return out;
}

}  // namespace

void ArticulationParams::Validate() const {
    if (!(horizontal_handle_deg > 0.0f && horizontal_handle_deg < 90.0f)) {
        throw InvalidArgument(
            fmt::format("articulation: horizontal_handle_deg must be in (0, 90), got {}",
                        horizontal_handle_deg));
    }
    if (!(pair_fixture_max_length >= 0.0f && pair_fixture_max_length <= 1.0f)) {
        throw InvalidArgument(
            fmt::format("articulation: pair_fixture_max_length must be in [0, 1] m, got {}",
                        pair_fixture_max_length));
    }
    if (!(edge_band > 0.0f && edge_band < 0.5f) || !(edge_border >= 0 && edge_border < 100)) {
        throw InvalidArgument(fmt::format(
            "articulation: need edge_band in (0, 0.5) m and edge_border in [0, 100) pixels, got "
            "{} and {}",
            edge_band, edge_border));
    }
    if (!(hinge_depth >= 0.0f && hinge_depth < 0.5f)) {
        throw InvalidArgument(
            fmt::format("articulation: hinge_depth must be in [0, 0.5) m, got {}", hinge_depth));
    }
    if (!(door_min_height > 0.0f) || !(top_share > 0.0f && top_share < 1.0f) ||
        !(revolute_upper > 0.0f) || !(prismatic_upper > 0.0f) || !(drawer_max_height > 0.0f) ||
        !(flap_min_width >= 0.0f) || !(edge_flap_min_width >= 0.0f) ||
        !(side_share >= 0.0f && side_share < 0.5f) ||
        !(stack_tolerance >= 0.0f && stack_tolerance <= 0.2f) ||
        !(stack_centre_share >= 0.0f && stack_centre_share < 0.5f)) {
        throw InvalidArgument(fmt::format(
            "articulation: need door_min_height > 0, top_share in (0, 1), limits > 0 and "
            "drawer_max_height > 0, flap_min_width and edge_flap_min_width >= 0, side_share in "
            "[0, 0.5), stack_tolerance in [0, 0.2] m, stack_centre_share in [0, 0.5) (got {}, {}, "
            "{}, {}, {}, {}, {}, {}, {}, {})",
            door_min_height, top_share, revolute_upper, prismatic_upper, drawer_max_height,
            flap_min_width, edge_flap_min_width, side_share, stack_tolerance, stack_centre_share));
    }
}

void MotionParams::Validate() const {
    if (!(change_distance > 0.0f) || !(min_offset >= 0.0f) || !(reach > 0.0f) ||
        !(plane_threshold > 0.0f) || !(parallel_deg > 0.0f && parallel_deg < 45.0f) ||
        min_points < 3) {
        throw InvalidArgument(fmt::format(
            "motion: need change_distance > 0, min_offset >= 0, reach > 0, plane_threshold > 0, "
            "parallel_deg in (0, 45), min_points >= 3 (got {}, {}, {}, {}, {}, {})",
            change_distance, min_offset, reach, plane_threshold, parallel_deg, min_points));
    }
    if (!(min_slide_coverage >= 0.0f && min_slide_coverage <= 1.0f) ||
        !(min_seen_slide_coverage >= 0.0f && min_seen_slide_coverage <= 1.0f) ||
        !(coverage_cell > 0.0f && coverage_cell <= 0.5f) ||
        !(axis_snap_deg >= 0.0f && axis_snap_deg < 45.0f) ||
        !(max_hinge_gap >= 0.0f && max_hinge_gap <= 10.0f) ||
        !(vacated_max_share >= 0.0f && vacated_max_share <= 1.0f) ||
        !(turn_reach_margin >= 0.0f && turn_reach_margin <= 1.0f) ||
        !(max_beyond_turn_share >= 0.0f && max_beyond_turn_share <= 1.0f) ||
        !(min_beyond_off_plane >= 0.0f && min_beyond_off_plane <= 1.0f) ||
        !(min_through_share >= 0.0f && min_through_share <= 100.0f) ||
        !(min_turn_coverage_for_drawer >= 0.0f && min_turn_coverage_for_drawer <= 1.0f)) {
        throw InvalidArgument(fmt::format(
            "motion: need min_slide_coverage and min_seen_slide_coverage in [0, 1], "
            "coverage_cell in (0, 0.5] m, "
            "axis_snap_deg in [0, 45), max_hinge_gap in [0, 10] m, vacated_max_share in "
            "[0, 1], turn_reach_margin in [0, 1] m, max_beyond_turn_share and "
            "min_beyond_off_plane in [0, 1], min_through_share in [0, 100], "
            "min_turn_coverage_for_drawer in [0, 1] (got {}, {}, {}, {}, {}, {}, {}, {}, {}, {}, "
            "{})",
            min_slide_coverage, min_seen_slide_coverage, coverage_cell, axis_snap_deg,
            max_hinge_gap, vacated_max_share, turn_reach_margin, max_beyond_turn_share,
            min_beyond_off_plane, min_through_share, min_turn_coverage_for_drawer));
    }
}

namespace {

/// The front's main fixture: its longest handle, else its first knob (none without fixtures),
/// or one horizontal handle between two small fixtures side by side
/// (ArticulationParams::pair_fixture_max_length).
std::optional<Fixture> MainFixture(const Front& f, const std::vector<Fixture>& fixtures,
                                   const Eigen::Vector3f& up, const ArticulationParams& p) {
    const Fixture* fx = nullptr;
    for (const int i : f.fixtures) {
        const Fixture& c = fixtures.at(static_cast<std::size_t>(i));
        if (!fx || (c.type == FixtureType::kHandle &&
                    (fx->type != FixtureType::kHandle || c.length > fx->length))) {
            fx = &c;
        }
    }
    if (!fx || p.pair_fixture_max_length <= 0.0f)
        return fx ? std::optional<Fixture>(*fx) : std::nullopt;
    const Fixture* a = nullptr;
    const Fixture* b = nullptr;
    float apart = fx->type == FixtureType::kHandle ? fx->length : 0.0f;
    const float max_rise = std::sin(p.horizontal_handle_deg * kArticulationDegToRad);
    for (std::size_t i = 0; i < f.fixtures.size(); ++i) {
        for (std::size_t j = i + 1; j < f.fixtures.size(); ++j) {
            const Fixture& c = fixtures.at(static_cast<std::size_t>(f.fixtures[i]));
            const Fixture& d = fixtures.at(static_cast<std::size_t>(f.fixtures[j]));
            if (c.length > p.pair_fixture_max_length || d.length > p.pair_fixture_max_length) {
                continue;
            }
            const Eigen::Vector3f between = d.center - c.center;
            const float n = between.norm();
            if (n > apart && std::abs(between.dot(up)) < max_rise * n) {
                apart = n;
                a = &c;
                b = &d;
            }
        }
    }
    if (!a) return *fx;
    Fixture bar;  // no points of its own
    bar.type = FixtureType::kHandle;
    bar.face = a->face;
    bar.center = 0.5f * (a->center + b->center);
    bar.direction = (b->center - a->center) / apart;
    bar.length = apart + 0.5f * (a->length + b->length);
    bar.width = std::max(a->width, b->width);
    bar.protrusion = std::max(a->protrusion, b->protrusion);
    bar.depth_extent = std::max(a->depth_extent, b->depth_extent);
    return bar;
}

bool IsHorizontalHandle(const Fixture& fx, const Eigen::Vector3f& up, const ArticulationParams& p) {
    return fx.type == FixtureType::kHandle &&
           std::abs(fx.direction.dot(up)) <
               std::sin(p.horizontal_handle_deg * kArticulationDegToRad);
}

/// Where fixture `fx` sits on front `f`: 0 at its left .. 1 at its right edge, 0 at its bottom ..
/// 1 at its top (0.5 across a side of no extent).
Eigen::Vector2f FixturePlace(const Front& f, const Fixture& fx) {
    const float width = f.max.x() - f.min.x(), height = f.max.y() - f.min.y();
    return {width > 0 ? (fx.center.dot(f.u_axis) - f.min.x()) / width : 0.5f,
            height > 0 ? (fx.center.dot(f.v_axis) - f.min.y()) / height : 0.5f};
}

/// The point (u, v) (face coordinates) of front `f`'s plane.
Eigen::Vector3f OnFrontPlane(const Front& f, float u, float v) {
    return f.u_axis * u + f.v_axis * v + f.normal * f.normal.dot(f.center);
}

/// A door hinged at the vertical edge farther from a fixture at `ru` (FixturePlace).
Articulation HingedAtSide(const Front& f, float ru, const ArticulationParams& p) {
    return ru >= 0.5f ? Hinge(f, OnFrontPlane(f, f.min.x(), f.min.y()), f.u_axis, p)
                      : Hinge(f, OnFrontPlane(f, f.max.x(), f.min.y()), -f.u_axis, p);
}

/// A flap hinged at its bottom edge.
Articulation HingedAtBottom(const Front& f, const ArticulationParams& p) {
    return Hinge(f, OnFrontPlane(f, f.min.x(), f.min.y()), f.v_axis, p);
}

/// A flap hinged at its top edge.
Articulation HingedAtTop(const Front& f, const ArticulationParams& p) {
    return Hinge(f, OnFrontPlane(f, f.min.x(), f.max.y()), -f.v_axis, p);
}

/// ArticulationFromFixtures; `bottom_hinged` (if not null) tells whether the front was hinged at
/// its bottom edge for a horizontal handle near its top.
Articulation JointFromFixtures(const Front& f, const std::vector<Fixture>& fixtures,
                               const RoomFrame& frame, float floor_height,
                               const ArticulationParams& p, bool* bottom_hinged) {
    p.Validate();
    if (bottom_hinged) *bottom_hinged = false;
    Articulation none;
    const Eigen::Vector3f up = frame.Up();
    const std::optional<Fixture> fx = MainFixture(f, fixtures, up, p);
    if (!fx) return none;
    const float width = f.max.x() - f.min.x(), height = f.max.y() - f.min.y();
    const Eigen::Vector2f place = FixturePlace(f, *fx);
    const float ru = place.x(), rv = place.y();
    const float base = std::isnan(floor_height) ? 0.0f : floor_height;
    const bool handle = fx->type == FixtureType::kHandle;
    const bool horizontal = IsHorizontalHandle(*fx, up, p);
    const bool side = ru < p.top_share || ru > 1.0f - p.top_share;
    // A door hinged at the vertical edge farther from the fixture.
    auto side_door = [&]() { return HingedAtSide(f, ru, p); };
    const bool wall = f.min.y() - base > p.flap_min_bottom;
    // A horizontal handle at a side edge: a door's free edge (flaps, drawers and appliance doors
    // carry theirs centred, or are wide).
    const bool edge_handle = horizontal && (ru < p.side_share || ru > 1.0f - p.side_share);
    if (horizontal || (!handle && !side)) {
        if (height >= p.door_min_height && rv > 1.0f - p.top_share) {
            // Hinged at the bottom edge: an oven or dishwasher door; too narrow for one, a door
            // hinged at the vertical edge farther from the fixture.
            if (width >= p.flap_min_width && (!edge_handle || width >= p.edge_flap_min_width)) {
                if (bottom_hinged) *bottom_hinged = true;
                return HingedAtBottom(f, p);
            }
            return side_door();
        }
        if (edge_handle && (wall || height >= p.door_min_height)) {
            // A door-sized front (or a wall cupboard's: no drawers there) with its handle at a
            // side edge, hinged at the other side.
            return side_door();
        }
        if (wall && rv < p.top_share && height >= 0.6f * p.door_min_height) {
            // A flap hinged at the top edge (wall cupboards).
            return HingedAtTop(f, p);
        }
        if (height > p.drawer_max_height) {
            // No drawer is that tall (a fridge's door with a horizontal handle): a door, hinged
            // at the vertical edge farther from the fixture.
            return side_door();
        }
        if (!p.wall_drawers && wall) {
            // No drawers hang on the wall: a flap, hinged at the horizontal edge farther from
            // the fixture.
            return rv >= 0.5f ? HingedAtBottom(f, p) : HingedAtTop(f, p);
        }
        return Drawer(f, p);
    }
    // Vertical handle or a knob off the centre: hinged at the farther vertical edge.
    return side_door();
}

/// Whether front `g`'s main fixture is a horizontal handle centred across front `f` (within
/// `stack_centre_share` of f's width of its middle).
bool HandleCentredOn(const Front& g, const Front& f, const std::vector<Fixture>& fixtures,
                     const Eigen::Vector3f& up, const ArticulationParams& p) {
    const std::optional<Fixture> fx = MainFixture(g, fixtures, up, p);
    if (!fx || !IsHorizontalHandle(*fx, up, p)) return false;
    const float width = f.max.x() - f.min.x();
    return std::abs(fx->center.dot(f.u_axis) - 0.5f * (f.min.x() + f.max.x())) <=
           p.stack_centre_share * width;
}

/// Whether front `index` carries a horizontal handle centred across it and a front of `fronts`
/// in the same column (on the same face, as GroupFurniture stacks fronts; overlapping all of its
/// width but twice `stack_tolerance` and no wider by more) lies directly above or below it (gap
/// within `stack_tolerance`) with a horizontal handle centred across it too. The neighbour's
/// handle is measured against this front's middle: a rectangle found a few centimetres short
/// does not move it.
bool InDrawerStack(const std::vector<Front>& fronts, std::size_t index,
                   const std::vector<Fixture>& fixtures, const Eigen::Vector3f& up,
                   const ArticulationParams& p) {
    const Front& f = fronts[index];
    if (!HandleCentredOn(f, f, fixtures, up, p)) return false;
    const float tol = p.stack_tolerance;
    const float width = f.max.x() - f.min.x();
    for (std::size_t j = 0; j < fronts.size(); ++j) {
        const Front& g = fronts[j];
        if (j == index || g.face != f.face) continue;
        const float overlap = std::min(f.max.x(), g.max.x()) - std::max(f.min.x(), g.min.x());
        if (overlap < width - 2.0f * tol || g.max.x() - g.min.x() > width + 2.0f * tol) continue;
        const float gap = std::max(g.min.y() - f.max.y(), f.min.y() - g.max.y());
        if (gap < -tol || gap > tol) continue;
        if (HandleCentredOn(g, f, fixtures, up, p)) return true;
    }
    return false;
}

}  // namespace

Articulation ArticulationFromFixtures(const Front& f, const std::vector<Fixture>& fixtures,
                                      const RoomFrame& frame, float floor_height,
                                      const ArticulationParams& p) {
    return JointFromFixtures(f, fixtures, frame, floor_height, p, nullptr);
}

Articulation ArticulationFromFixtures(const std::vector<Front>& fronts, std::size_t index,
                                      const std::vector<Fixture>& fixtures, const RoomFrame& frame,
                                      float floor_height, const ArticulationParams& p) {
    const Front& f = fronts.at(index);
    bool bottom_hinged = false;
    Articulation a = JointFromFixtures(f, fixtures, frame, floor_height, p, &bottom_hinged);
    if (bottom_hinged && p.stack_tolerance > 0.0f && f.max.y() - f.min.y() <= p.drawer_max_height &&
        InDrawerStack(fronts, index, fixtures, frame.Up(), p)) {
        return Drawer(f, p);
    }
    return a;
}

namespace {

/// HingeEdgeSeen over scans given as spans (one cloud needs no copy into a vector).
bool EdgeSeen(const Front& front, std::span<const PointCloud> scans,
              std::span<const std::size_t> scan_offsets, const ArticulationParams& p) {
    p.Validate();
    const Articulation& a = front.articulation;
    if (a.type != JointType::kRevolute || front.indices.empty()) return true;
    if (scan_offsets.size() != scans.size()) {
        throw InvalidArgument(fmt::format("articulation: {} scan offsets for {} scans",
                                          scan_offsets.size(), scans.size()));
    }
    const Eigen::Vector3f d = a.axis.normalized();
    const Eigen::Vector3f n = front.normal.normalized();
    // Within the face: from the hinge line out to a place, and the front's extent along it.
    auto across = [&](const Eigen::Vector3f& x) {
        Eigen::Vector3f r = x - a.origin;
        r -= d * d.dot(r) + n * n.dot(r);
        return r;
    };
    struct Near {
        std::size_t scan, local;
        float distance, along;
    };
    std::vector<Near> points;
    points.reserve(front.indices.size());
    float nearest = std::numeric_limits<float>::infinity();
    float t_min = nearest, t_max = -nearest;
    for (const Index i : front.indices) {
        const auto it =
            std::upper_bound(scan_offsets.begin(), scan_offsets.end(), static_cast<std::size_t>(i));
        if (it == scan_offsets.begin()) continue;
        const auto s = static_cast<std::size_t>(it - scan_offsets.begin() - 1);
        const std::size_t local = static_cast<std::size_t>(i) - scan_offsets[s];
        if (local >= scans[s].size() || !scans[s].IsFinite(local)) continue;
        const Eigen::Vector3f& x = scans[s].points[local];
        const float dist = across(x).norm();
        const float t = d.dot(x - a.origin);
        points.push_back({s, local, dist, t});
        nearest = std::min(nearest, dist);
        t_min = std::min(t_min, t);
        t_max = std::max(t_max, t);
    }
    if (points.empty()) return true;
    // Out of the front, across the hinge edge.
    const Eigen::Vector3f inward = across(front.center);
    if (!(inward.norm() > 1e-4f)) return true;
    const Eigen::Vector3f outward = -inward.normalized();
    // Along the edge in steps of `edge_band`: where a scan saw the front near the edge, and
    // where those points lie at its image border.
    const auto steps = static_cast<std::size_t>((t_max - t_min) / p.edge_band) + 1;
    const auto b = static_cast<std::size_t>(p.edge_border);
    bool told = false;
    for (std::size_t s = 0; s < scans.size(); ++s) {
        const PointCloud& scan = scans[s];
        std::vector<char> near_edge(steps, 0), at_border(steps, 0);
        for (const Near& q : points) {
            if (q.scan != s || q.distance > nearest + p.edge_band) continue;
            const auto k =
                std::min(steps - 1, static_cast<std::size_t>((q.along - t_min) / p.edge_band));
            near_edge[k] = 1;
            if (scan.IsOrganized()) {
                const std::size_t u = q.local % scan.width, v = q.local / scan.width;
                at_border[k] |= u < b || v < b || u + b >= scan.width || v + b >= scan.height;
            }
        }
        const auto seen_steps = std::count(near_edge.begin(), near_edge.end(), 1);
        if (seen_steps == 0) continue;
        if (scan.IsOrganized()) {
            told = true;
            if (std::count(at_border.begin(), at_border.end(), 1) * 2 < seen_steps) return true;
        } else if (scan.HasSensorPosition()) {
            const SeenFrom seen(scan, front.center, p.edge_band);
            if (!seen.valid()) continue;
            told = true;
            // Five places along the edge, `edge_band` beyond it, on the front's surface.
            constexpr int kPlaces = 5;
            int reached = 0;
            for (int k = 0; k < kPlaces; ++k) {
                const float t = t_min + (t_max - t_min) * (0.1f + 0.2f * static_cast<float>(k));
                const Eigen::Vector3f x =
                    a.origin + d * t + outward * p.edge_band + n * p.hinge_depth;
                reached += seen.Seen(x, p.edge_band);
            }
            if (reached * 2 > kPlaces) return true;
        }
    }
    return !told;
}

}  // namespace

bool HingeEdgeSeen(const Front& front, const std::vector<PointCloud>& scans,
                   const std::vector<std::size_t>& scan_offsets, const ArticulationParams& p) {
    return EdgeSeen(front, scans, scan_offsets, p);
}

MotionResult ArticulationFromMotion(const PointCloud& closed, const PointCloud& opened,
                                    const Front& f, const MotionParams& p) {
    p.Validate();
    if (closed.empty() || opened.empty()) return {};
    return ArticulationFromMotion(KdTree(closed), opened, f, p);
}

MotionResult ArticulationFromMotion(const KdTree& before, const PointCloud& opened,
                                    const Front& whole, const MotionParams& p) {
    p.Validate();
    MotionResult out;
    if (before.empty() || opened.empty()) return out;
    const Vacated vacated = VacatedPart(before, opened, whole, p);
    const Front& f = vacated.part;
    out.vacated_points = vacated.points;
    out.front_min = f.min;
    out.front_max = f.max;
    const float plane_d = -f.normal.dot(f.center);
    const float width = f.max.x() - f.min.x(), height = f.max.y() - f.min.y();
    // The space the front can sweep: turning about an edge, no farther from the face than its
    // size and out to the sides by as much; sliding, straight out of its outline by up to the
    // reach (a drawer may run out farther than its front is wide).
    const float swing = std::min(p.reach, std::max(width, height) + 0.05f);
    const float outline_margin = 0.05f;
    Indices moved;
    // The moved points within the front's outline, and how far each lies out of the face.
    Indices outline_moved;
    std::vector<float> outline_out;
    // New points behind the face within the outline: what the opened front lets the scan see.
    Indices behind;
    // An opened-scan point the closed scan had no point within `change_distance` of.
    auto is_new = [&](const Eigen::Vector3f& x) {
        Index nn = 0;
        float d2 = 0.0f;
        return !before.SearchNearestWithin(x, p.change_distance, nn, d2);
    };
    for (std::size_t i = 0; i < opened.size(); ++i) {
        if (!opened.IsFinite(i)) continue;
        const Eigen::Vector3f& x = opened.points[i];
        const float h = f.normal.dot(x) + plane_d;
        if (h > p.reach || h < -p.reach || std::abs(h) < p.min_offset) continue;
        const float u = x.dot(f.u_axis), v = x.dot(f.v_axis);
        const bool in_slide = u >= f.min.x() - outline_margin && u <= f.max.x() + outline_margin &&
                              v >= f.min.y() - outline_margin && v <= f.max.y() + outline_margin;
        if (h < 0.0f) {
            if (in_slide) behind.push_back(static_cast<Index>(i));
            continue;
        }
        const bool in_swing = h <= swing && u >= f.min.x() - swing && u <= f.max.x() + swing &&
                              v >= f.min.y() - swing && v <= f.max.y() + swing;
        if ((!in_swing && !in_slide) || !is_new(x)) continue;
        moved.push_back(static_cast<Index>(i));
        if (in_slide) {
            outline_moved.push_back(static_cast<Index>(i));
            outline_out.push_back(h);
        }
    }
    out.moved_points = moved.size();
    if (moved.size() < p.min_points) return out;
    PlaneFitParams pp;
    pp.sac.distance_threshold = p.plane_threshold;
    pp.sac.seed = p.seed;
    pp.sac.num_threads = 1;
    pp.viewpoint = f.center + f.normal * 2.0f;
    const PlaneFit fit = FitPlane(opened, moved, pp);
    if (!fit.found || fit.inliers.size() < p.min_points) return out;
    // A drawer shows its sides and bottom too, and the largest plane may be one of them: the
    // hypotheses "the front slid along its normal" (the best plane parallel to the closed front)
    // and "the front turned about the line where the planes meet" are each scored by the moved
    // points on the front's rectangle moved that way, and the better one wins.
    PlaneFitParams parallel = pp;
    parallel.axis = f.normal;
    parallel.axis_mode = PlaneAxisMode::kParallel;
    parallel.max_angle = p.parallel_deg * kArticulationDegToRad;
    const PlaneFit fit_parallel = FitPlane(opened, moved, parallel);
    auto centroid_of = [&](const Indices& idx) {
        Eigen::Vector3f c = Eigen::Vector3f::Zero();
        for (const Index i : idx) c += opened.points[i];
        return Eigen::Vector3f(c / static_cast<float>(std::max<std::size_t>(1, idx.size())));
    };
    // Moved points on the closed front's rectangle carried by T: how many lie on it (a small
    // margin around it), and the share of its cells (coverage_cell) they hit.
    struct OnFront {
        std::size_t points = 0;
        float cells = 0.0f;
        /// The share of the cells the opened scan could see (placed by T) that moved points hit;
        /// -1 without a sensor position or when it could see none.
        float seen_cells = -1.0f;
    };
    const SeenFrom seen =
        p.seen_coverage ? SeenFrom(opened, f.center, p.coverage_cell) : SeenFrom();
    const int nu = std::clamp(static_cast<int>(std::ceil(width / p.coverage_cell)), 1, 200);
    const int nv = std::clamp(static_cast<int>(std::ceil(height / p.coverage_cell)), 1, 200);
    std::vector<char> hit(static_cast<std::size_t>(nu * nv));
    auto on_front = [&](const Eigen::Isometry3f& T) {
        const float hu = width / 2 + 0.03f, hv = height / 2 + 0.03f;
        std::fill(hit.begin(), hit.end(), 0);
        const Eigen::Isometry3f inv = T.inverse();
        OnFront r;
        for (const Index i : moved) {
            const Eigen::Vector3f q = inv * opened.points[i];
            const Eigen::Vector3f d = q - f.center;
            if (std::abs(d.dot(f.normal)) > p.plane_threshold) continue;
            r.points += std::abs(d.dot(f.u_axis)) <= hu && std::abs(d.dot(f.v_axis)) <= hv;
            const float u = (q.dot(f.u_axis) - f.min.x()) / width * static_cast<float>(nu);
            const float v = (q.dot(f.v_axis) - f.min.y()) / height * static_cast<float>(nv);
            if (u >= 0.0f && v >= 0.0f && u < static_cast<float>(nu) && v < static_cast<float>(nv))
                hit[static_cast<std::size_t>(static_cast<int>(v) * nu + static_cast<int>(u))] = 1;
        }
        const auto hits = static_cast<std::size_t>(std::count(hit.begin(), hit.end(), 1));
        r.cells = static_cast<float>(hits) / static_cast<float>(hit.size());
        if (seen.valid()) {
            // A cell a moved point hit was seen; another one when the ray to its centre, placed
            // by T, reached it.
            std::size_t visible = hits;
            const Eigen::Vector3f corner = f.center +
                                           f.u_axis * (f.min.x() - f.center.dot(f.u_axis)) +
                                           f.v_axis * (f.min.y() - f.center.dot(f.v_axis));
            const float du = width / static_cast<float>(nu), dv = height / static_cast<float>(nv);
            for (int iv = 0; iv < nv; ++iv) {
                for (int iu = 0; iu < nu; ++iu) {
                    if (hit[static_cast<std::size_t>(iv * nu + iu)]) continue;
                    const Eigen::Vector3f c = corner +
                                              f.u_axis * ((static_cast<float>(iu) + 0.5f) * du) +
                                              f.v_axis * ((static_cast<float>(iv) + 0.5f) * dv);
                    visible += seen.Seen(T * c, 2.0f * p.plane_threshold);
                }
            }
            if (visible > 0) r.seen_cells = static_cast<float>(hits) / static_cast<float>(visible);
        }
        return r;
    };
    auto shift = [&](float d) {
        Eigen::Isometry3f T = Eigen::Isometry3f::Identity();
        T.translation() = f.normal * d;
        return T;
    };
    auto turn = [](const Eigen::Vector3f& origin, const Eigen::Vector3f& axis, float a) {
        return Eigen::Isometry3f(Eigen::Translation3f(origin) * Eigen::AngleAxisf(a, axis) *
                                 Eigen::Translation3f(-origin));
    };
    // The prismatic hypothesis: out along the face normal by `t`.
    auto slide_by = [&](float t) {
        Articulation a;
        a.type = JointType::kPrismatic;
        a.axis = f.normal;
        a.origin = f.center;
        a.upper = t;
        a.source = "motion";
        return a;
    };
    Articulation slide;
    float travel = 0.0f;
    OnFront slide_on;
    Indices slide_inliers;
    const float cos_par = std::cos(p.parallel_deg * kArticulationDegToRad);
    const PlaneFit& pf =
        std::abs(fit.plane.head<3>().dot(f.normal)) >= cos_par ? fit : fit_parallel;
    if (pf.found && pf.inliers.size() >= p.min_points) {
        travel = std::max(0.0f, f.normal.dot(centroid_of(pf.inliers)) + plane_d);
        slide = slide_by(travel);
        slide_on = on_front(shift(travel));
        slide_inliers = pf.inliers;
    }
    // The revolute hypothesis, from the best plane when it is tilted.
    Articulation hinge;
    float angle = 0.0f;
    OnFront hinge_on;
    Eigen::Vector3f nb = fit.plane.head<3>();
    if (std::abs(nb.dot(f.normal)) < cos_par) {
        const Eigen::Vector3f centroid = centroid_of(fit.inliers);
        Eigen::Vector3f dir = f.normal.cross(nb).normalized();
        // The line lies in the face plane; near the front's vertical or horizontal it is that.
        const float cos_snap = std::cos(p.axis_snap_deg * kArticulationDegToRad);
        for (const Eigen::Vector3f& a : {f.v_axis, f.u_axis}) {
            if (p.axis_snap_deg > 0.0f && std::abs(dir.dot(a)) >= cos_snap) {
                dir = dir.dot(a) >= 0.0f ? a : Eigen::Vector3f(-a);
                break;
            }
        }
        // A point on both planes: solve [n_a; n_b; dir] x = [-d_a; -d_b; dir . c].
        Eigen::Matrix3f M;
        M.row(0) = f.normal.transpose();
        M.row(1) = nb.transpose();
        M.row(2) = dir.transpose();
        const Eigen::Vector3f rhs(-plane_d, -fit.plane.w(), dir.dot(f.center));
        const Eigen::Vector3f point = M.colPivHouseholderQr().solve(rhs);
        // The sign: rotating the closed front's centre about the axis brings it towards the
        // moved front's centre.
        const Eigen::Vector3f ra = f.center - point, rb = centroid - point;
        if (ra.cross(rb).dot(dir) < 0) dir = -dir;
        // The opening: between the closed front's in-plane direction away from the axis and
        // the moved front's (more than 90 degrees when the door swung past the perpendicular).
        const Eigen::Vector3f ea = (ra - ra.dot(dir) * dir).normalized();
        const Eigen::Vector3f eb = (rb - rb.dot(dir) * dir).normalized();
        angle = std::acos(std::clamp(ea.dot(eb), -1.0f, 1.0f));
        hinge.type = JointType::kRevolute;
        hinge.axis = dir;
        hinge.origin = point;
        hinge.upper = angle;
        hinge.source = "motion";
        hinge_on = on_front(turn(point, dir, angle));
    }
    if (slide.type == JointType::kUnknown && hinge.type == JointType::kUnknown) return out;
    out.found = true;
    // The turn about the edge of the rectangle (and by the angle) under which the moved points
    // cover most of it; false when none covers any of it.
    auto edge_turn = [&](const Eigen::Vector3f* along) {
        const Eigen::Vector3f left = f.center + f.u_axis * (f.min.x() - f.center.dot(f.u_axis));
        const Eigen::Vector3f right = f.center + f.u_axis * (f.max.x() - f.center.dot(f.u_axis));
        const Eigen::Vector3f bottom = f.center + f.v_axis * (f.min.y() - f.center.dot(f.v_axis));
        const Eigen::Vector3f top = f.center + f.v_axis * (f.max.y() - f.center.dot(f.v_axis));
        const std::pair<Eigen::Vector3f, Eigen::Vector3f> edges[4] = {
            {left, f.u_axis}, {right, -f.u_axis}, {bottom, f.v_axis}, {top, -f.v_axis}};
        ArticulationParams on_surface;
        on_surface.hinge_depth = 0.0f;
        float best = -1.0f, best_angle = 0.0f;
        Articulation best_hinge;
        for (const auto& [point, into] : edges) {
            if (along && std::abs(into.dot(*along)) > 0.5f) continue;
            const Articulation a = Hinge(f, point, into, on_surface);
            for (float deg = 10.0f; deg <= 120.0f; deg += 2.5f) {
                const float c = on_front(turn(a.origin, a.axis, deg * kArticulationDegToRad)).cells;
                if (c > best) {
                    best = c;
                    best_hinge = a;
                    best_angle = deg * kArticulationDegToRad;
                }
            }
        }
        if (best <= 0.0f) return false;
        best_hinge.source = "motion";
        best_hinge.upper = best_angle;
        out.articulation = best_hinge;
        out.opening = best_angle;
        out.moved.clear();
        const Eigen::Isometry3f inv =
            turn(best_hinge.origin, best_hinge.axis, best_angle).inverse();
        for (const Index i : moved) {
            if (std::abs(f.normal.dot(inv * opened.points[i]) + plane_d) <= p.plane_threshold)
                out.moved.push_back(i);
        }
        return true;
    };
    // The turn about the tilted plane's axis, unless no moved point on that plane comes within
    // `max_hinge_gap` of the axis (a door hangs on its hinge; such a plane is the door's inside,
    // its edge or a shelf meeting the face plane far from the front): then the turn about the
    // rectangle's edge along that axis under which the moved points cover most, when there is
    // one.
    auto tilted_turn = [&]() {
        float gap = std::numeric_limits<float>::max();
        for (const Index i : fit.inliers) {
            const Eigen::Vector3f d = opened.points[i] - hinge.origin;
            gap = std::min(gap, (d - d.dot(hinge.axis) * hinge.axis).norm());
        }
        if (p.max_hinge_gap > 0.0f && gap > p.max_hinge_gap && edge_turn(&hinge.axis)) return;
        out.articulation = hinge;
        out.opening = angle;
        out.moved = fit.inliers;
    };
    // Compared by the share of the cells the opened scan could see that the moved points cover
    // when the scan has a sensor position (a drawer pulled out towards the sensor may leave the
    // field of view, or be seen over the drawers beneath it), else by the points on the front.
    const bool by_seen = p.seen_coverage && slide.type != JointType::kUnknown &&
                         slide_on.seen_cells >= 0.0f &&
                         (hinge.type == JointType::kUnknown || hinge_on.seen_cells >= 0.0f);
    if (hinge.type != JointType::kUnknown && (by_seen ? hinge_on.seen_cells >= slide_on.seen_cells
                                                      : hinge_on.points >= slide_on.points)) {
        tilted_turn();
    } else {
        out.articulation = slide;
        out.opening = travel;
        out.moved = slide_inliers;
    }
    // A drawer pulled out shows its whole front again, parallel to where it was: the moved points
    // cover much of the front's rectangle slid out, as far as the scan could see it (not all of
    // it: the rectangle may be larger than the drawer). A door seen edge-on, or by little more than
    // its free edge or handle, can make a parallel plane too, but covers a strip of the rectangle
    // only. A slide that covers less than `min_seen_slide_coverage` of the cells the scan could
    // see (`min_slide_coverage` of all of them without a sensor position) becomes a turn: about
    // the tilted plane's axis when there is one, else about the edge of the rectangle (and by
    // the angle) that covers most.
    const float slide_cover = by_seen ? slide_on.seen_cells : slide_on.cells;
    const float hinge_cover = hinge_on.cells;
    if (slide.type != JointType::kUnknown) {
        out.slide_coverage = slide_on.cells;
        out.slide_travel = travel;
        out.slide_points = slide_on.points;
        out.slide_seen_coverage = slide_on.seen_cells;
    }
    if (hinge.type != JointType::kUnknown) {
        out.turn_coverage = hinge_cover;
        out.turn_points = hinge_on.points;
        out.turn_seen_coverage = hinge_on.seen_cells;
    }
    const float min_cover = by_seen ? p.min_seen_slide_coverage : p.min_slide_coverage;
    if (out.articulation.type == JointType::kPrismatic && min_cover > 0.0f &&
        slide_cover < min_cover) {
        if (hinge.type != JointType::kUnknown) {
            tilted_turn();
        } else {
            edge_turn(nullptr);
        }
    }
    // The turn taken cannot bring any part of the rectangle farther out of the face than its
    // farthest corner from the hinge axis. Moved points straight out of the rectangle beyond that
    // are something else. Where the turn is a flap's, whose reach is the height of the band the
    // motion vacated, they are a drawer's box, pulled out so far that its front left the view,
    // whose bottom the turn explains as a flap opened downwards. So is a flap's plane that runs
    // on behind the face: a deep box pulled out less far than the flap would reach.
    out.outline_points = outline_out.size();
    if (out.articulation.type != JointType::kRevolute) return out;
    const Articulation& a = out.articulation;
    out.turn_flap = std::abs(a.axis.dot(f.u_axis)) > std::abs(a.axis.dot(f.v_axis));
    float reach_out = 0.0f;
    for (const float u : {f.min.x(), f.max.x()}) {
        for (const float v : {f.min.y(), f.max.y()}) {
            const Eigen::Vector3f c = OnFrontPlane(f, u, v);
            const Eigen::Vector3f d = c - a.origin;
            reach_out = std::max(reach_out, (d - d.dot(a.axis) * a.axis).norm());
        }
    }
    out.turn_reach = reach_out;
    // The turned front's plane: a flap's own points beyond its rectangle (the rectangle shorter
    // than the door) lie on it; a drawer's box has sides across it, and a back.
    const Eigen::Isometry3f turned = turn(a.origin, a.axis, out.opening);
    const Eigen::Vector3f turned_n = turned.linear() * f.normal;
    const float turned_d = -turned_n.dot(turned * f.center);
    // A turned front ends at its hinge, in front of the face; a drawer's box runs on behind it
    // (its bottom and sides from where the front is to the box's back). New points behind the
    // face on the turned front's plane extended.
    for (const Index i : behind) {
        const Eigen::Vector3f& x = opened.points[i];
        out.through_points +=
            std::abs(turned_n.dot(x) + turned_d) <= p.plane_threshold && is_new(x);
    }
    out.turned_points = out.moved.size();
    for (std::size_t k = 0; k < outline_out.size(); ++k) {
        if (outline_out[k] <= reach_out + p.turn_reach_margin) continue;
        ++out.beyond_turn_points;
        const Eigen::Vector3f& x = opened.points[outline_moved[k]];
        out.beyond_off_plane += std::abs(turned_n.dot(x) + turned_d) > 2.0f * p.plane_threshold;
    }
    const bool beyond = p.max_beyond_turn_share > 0.0f && out.beyond_turn_points >= p.min_points &&
                        static_cast<float>(out.beyond_turn_points) >=
                            p.max_beyond_turn_share * static_cast<float>(outline_out.size()) &&
                        static_cast<float>(out.beyond_off_plane) >=
                            p.min_beyond_off_plane * static_cast<float>(out.beyond_turn_points);
    // A box's bottom passes for a flap hinged low and opened downwards; a flap hinged high meets
    // the carcass's top behind the face.
    const bool hinged_low = a.origin.dot(f.v_axis) < 0.5f * (f.min.y() + f.max.y());
    const bool through = p.min_through_share > 0.0f && hinged_low &&
                         out.through_points >= p.min_points &&
                         static_cast<float>(out.through_points) >=
                             p.min_through_share * static_cast<float>(out.turned_points);
    // A front held for a drawer before stays one unless the turn is clearly seen: its tilted
    // plane covers enough of the front turned (none: the turn is a guess about an edge).
    const float turn_cover =
        out.turn_seen_coverage >= 0.0f ? out.turn_seen_coverage : out.turn_coverage;
    const bool weak_turn_of_drawer = p.min_turn_coverage_for_drawer > 0.0f &&
                                     f.articulation.type == JointType::kPrismatic &&
                                     turn_cover < p.min_turn_coverage_for_drawer;
    if (!weak_turn_of_drawer && (!out.turn_flap || (!beyond && !through))) return out;
    // A slide, at least as far as the box is seen out of the face (98 % of the moved points
    // within the outline; the parallel plane may be a panel inside the box).
    out.opening = outline_out.empty() ? travel : std::max(travel, Quantile(outline_out, 0.98f));
    out.articulation = slide_by(out.opening);
    out.moved = outline_moved;
    return out;
}

namespace {

/// Splits front `index` of `map` (built from `cloud`) at the part [lo, hi] of its rectangle that
/// moved: the front keeps that part, and the strips of the rest below and above it, at least
/// `min_size` tall, become fronts of their own. Points and fixtures go to the piece they lie on
/// (fixtures off every piece to the nearest); a strip with a fixture is hinged by
/// ArticulationFromFixtures, and `cloud` tells whether its hinge's edge was seen.
void SplitAtMovedPart(KitchenMap& map, const PointCloud& cloud, std::size_t index,
                      const Eigen::Vector2f& lo, const Eigen::Vector2f& hi, float min_size) {
    const Front whole = map.fronts[index];
    if ((lo - whole.min).cwiseAbs().maxCoeff() < 1e-4f &&
        (hi - whole.max).cwiseAbs().maxCoeff() < 1e-4f) {
        return;
    }
    auto piece = [&](const Eigen::Vector2f& a, const Eigen::Vector2f& b) {
        Front g = whole;
        g.min = a;
        g.max = b;
        const Eigen::Vector2f shift = (a + b - whole.min - whole.max) / 2.0f;
        g.center = whole.center + whole.u_axis * shift.x() + whole.v_axis * shift.y();
        g.indices.clear();
        g.fixtures.clear();
        g.articulation = Articulation{};
        g.furniture = -1;
        return g;
    };
    std::vector<Front> pieces = {piece(lo, hi)};
    pieces.front().articulation = whole.articulation;
    const std::pair<Eigen::Vector2f, Eigen::Vector2f> rest[2] = {
        {whole.min, {whole.max.x(), lo.y()}}, {{whole.min.x(), hi.y()}, whole.max}};
    for (const auto& [a, b] : rest) {
        if (b.y() - a.y() >= min_size) pieces.push_back(piece(a, b));
    }
    // Distance of face coordinates `q` from a piece's rectangle (0 on it).
    auto off = [](const Front& g, const Eigen::Vector2f& q) {
        return (g.min - q).cwiseMax(q - g.max).cwiseMax(0.0f).norm();
    };
    auto face_coords = [&](const Eigen::Vector3f& x) {
        return Eigen::Vector2f(x.dot(whole.u_axis), x.dot(whole.v_axis));
    };
    for (const Index i : whole.indices) {
        const Eigen::Vector2f q = face_coords(cloud.points[i]);
        for (Front& g : pieces) {
            if (off(g, q) == 0.0f) {
                g.indices.push_back(i);
                break;
            }
        }
    }
    for (const int fx : whole.fixtures) {
        const Eigen::Vector2f q = face_coords(map.fixtures[static_cast<std::size_t>(fx)].center);
        std::size_t nearest = 0;
        for (std::size_t k = 1; k < pieces.size(); ++k) {
            if (off(pieces[k], q) < off(pieces[nearest], q)) nearest = k;
        }
        pieces[nearest].fixtures.push_back(fx);
    }
    for (std::size_t k = 1; k < pieces.size(); ++k) {
        if (!pieces[k].fixtures.empty()) {
            pieces[k].articulation =
                ArticulationFromFixtures(pieces[k], map.fixtures, map.frame, map.floor_height);
            const std::size_t offset = 0;
            pieces[k].articulation.hinge_seen =
                EdgeSeen(pieces[k], std::span<const PointCloud>(&cloud, 1),
                         std::span<const std::size_t>(&offset, 1), ArticulationParams{});
        }
    }
    map.fronts[index] = std::move(pieces.front());
    for (std::size_t k = 1; k < pieces.size(); ++k) map.fronts.push_back(std::move(pieces[k]));
}

}  // namespace

int UpdateArticulationFromOpenedScan(KitchenMap& map, const PointCloud& closed,
                                     const PointCloud& opened, const MotionParams& p) {
    p.Validate();
    for (std::size_t f = 0; f < map.fronts.size(); ++f) {
        for (const Index i : map.fronts[f].indices) {
            if (static_cast<std::size_t>(i) >= closed.size()) {
                throw InvalidArgument(fmt::format(
                    "opened scan: front {} has point {}, but the closed cloud has {} points (the "
                    "map must have been built from it)",
                    f + 1, i, closed.size()));
            }
        }
    }
    int best = -1;
    std::pair<std::size_t, std::size_t> best_points{0, 0};
    MotionResult best_motion;
    if (closed.empty() || opened.empty()) return -1;
    const KdTree tree(closed);
    for (std::size_t f = 0; f < map.fronts.size(); ++f) {
        MotionResult m = ArticulationFromMotion(tree, opened, map.fronts[f], p);
        // The front that moved lost its own points; a front beside it may sweep more of the
        // moved points but kept its own.
        const std::pair<std::size_t, std::size_t> points =
            p.select_by_vacated ? std::pair{m.vacated_points, m.moved.size()}
                                : std::pair{m.moved.size(), m.vacated_points};
        if (m.found && points > best_points) {
            best_points = points;
            best = static_cast<int>(f);
            best_motion = std::move(m);
        }
    }
    if (best >= 0) {
        const auto b = static_cast<std::size_t>(best);
        map.fronts[b].articulation = best_motion.articulation;
        SplitAtMovedPart(map, closed, b, best_motion.front_min, best_motion.front_max,
                         2.0f * p.coverage_cell);
    }
    return best;
}

const std::vector<std::string>& JointClassNames() {
    static const std::vector<std::string> names = {"prismatic", "revolute_side", "revolute_bottom",
                                                   "revolute_top"};
    return names;
}

const std::vector<std::string>& JointFeatureNames() {
    static const std::vector<std::string> names = {
        "width",     "height",       "aspect",      "bottom",       "top",
        "fixtures",  "horizontal",   "length",      "length_share", "u",
        "v",         "u_off",        "knob",        "protrusion",   "above",
        "below",     "piece_fronts", "piece_width", "piece_height", "rule_prismatic",
        "rule_side", "rule_bottom",  "rule_top"};
    return names;
}

std::vector<float> JointFeatures(const KitchenMap& map, std::size_t front,
                                 const ArticulationParams& p) {
    const Front& f = map.fronts.at(front);
    const Eigen::Vector3f up = map.frame.Up();
    const float base = std::isnan(map.floor_height) ? 0.0f : map.floor_height;
    const float w = f.max.x() - f.min.x(), h = f.max.y() - f.min.y();
    const float centre = up.dot(f.center) - base;
    float horizontal = 0, length = 0, ru = 0.5f, rv = 0.5f, knob = 0, protrusion = 0;
    if (const std::optional<Fixture> fx = MainFixture(f, map.fixtures, up, p)) {
        horizontal = IsHorizontalHandle(*fx, up, p) ? 1.0f : 0.0f;
        length = fx->length;
        knob = fx->type == FixtureType::kKnob ? 1.0f : 0.0f;
        protrusion = fx->protrusion;
        const Eigen::Vector2f place = FixturePlace(f, *fx);
        ru = place.x();
        rv = place.y();
    }
    float above = 0, below = 0, piece_fronts = 0;
    for (std::size_t o = 0; o < map.fronts.size(); ++o) {
        const Front& q = map.fronts[o];
        if (o == front) continue;
        piece_fronts += f.furniture >= 0 && q.furniture == f.furniture;
        if (q.face != f.face) continue;
        const float overlap = std::min(q.max.x(), f.max.x()) - std::max(q.min.x(), f.min.x());
        if (overlap < 0.6f * w) continue;
        above += std::abs(q.min.y() - f.max.y()) < 0.06f;
        below += std::abs(q.max.y() - f.min.y()) < 0.06f;
    }
    Eigen::Vector3f piece = Eigen::Vector3f::Zero();
    if (f.furniture >= 0) piece = map.furniture.at(static_cast<std::size_t>(f.furniture)).extents;
    const float along = horizontal > 0 ? w : h;
    const std::string rule =
        JointClassOf(f.articulation.type, f.articulation.axis, f.articulation.origin, f, map.frame);
    return {w,
            h,
            h > 0 ? w / h : 0.0f,
            centre - h / 2,
            centre + h / 2,
            static_cast<float>(f.fixtures.size()),
            horizontal,
            length,
            along > 0 ? length / along : 0.0f,
            ru,
            rv,
            std::abs(ru - 0.5f),
            knob,
            protrusion,
            above,
            below,
            piece_fronts,
            piece.x(),
            piece.z(),
            rule == "prismatic" ? 1.0f : 0.0f,
            rule == "revolute_side" ? 1.0f : 0.0f,
            rule == "revolute_bottom" ? 1.0f : 0.0f,
            rule == "revolute_top" ? 1.0f : 0.0f};
}

std::string JointClassOf(JointType type, const Eigen::Vector3f& axis, const Eigen::Vector3f& point,
                         const Front& f, const RoomFrame& frame) {
    if (type == JointType::kUnknown) return "";
    if (type == JointType::kPrismatic) return "prismatic";
    const Eigen::Vector3f up = frame.Up();
    if (std::abs(axis.normalized().dot(up)) > 0.7f) return "revolute_side";
    return up.dot(point) < up.dot(f.center) ? "revolute_bottom" : "revolute_top";
}

void CheckJointClassifier(const ml::Classifier& classifier) {
    ml::CheckClassifierFor(classifier, JointFeatureNames(), JointClassNames(), "joints", "joint");
}

std::vector<std::size_t> ClassifyJoints(KitchenMap& map, const ml::Classifier& classifier,
                                        const ArticulationParams& p) {
    p.Validate();
    CheckJointClassifier(classifier);
    std::vector<std::size_t> changed;
    for (std::size_t i = 0; i < map.fronts.size(); ++i) {
        Front& f = map.fronts[i];
        if (f.articulation.source != "fixture" || f.fixtures.empty()) continue;
        const std::vector<float> x = JointFeatures(map, i, p);
        const ml::FeatureMatrix row =
            Eigen::Map<const ml::FeatureMatrix>(x.data(), 1, static_cast<Eigen::Index>(x.size()));
        const std::string& name =
            classifier.class_names()[static_cast<std::size_t>(classifier.Predict(row).front())];
        const Articulation& a = f.articulation;
        if (name == JointClassOf(a.type, a.axis, a.origin, f, map.frame)) continue;
        Articulation next =
            name == "prismatic"         ? Drawer(f, p)
            : name == "revolute_bottom" ? HingedAtBottom(f, p)
            : name == "revolute_top"
                ? HingedAtTop(f, p)
                : HingedAtSide(
                      f, FixturePlace(f, *MainFixture(f, map.fixtures, map.frame.Up(), p)).x(), p);
        next.source = "classifier";
        f.articulation = next;
        changed.push_back(i);
    }
    return changed;
}

}  // namespace multicue::mapping

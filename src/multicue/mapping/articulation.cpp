#include "multicue/mapping/articulation.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
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

}  // namespace

void ArticulationParams::Validate() const {
    if (!(horizontal_handle_deg > 0.0f && horizontal_handle_deg < 90.0f)) {
        throw InvalidArgument(
            fmt::format("articulation: horizontal_handle_deg must be in (0, 90), got {}",
                        horizontal_handle_deg));
    }
    if (!(hinge_depth >= 0.0f && hinge_depth < 0.5f)) {
        throw InvalidArgument(
            fmt::format("articulation: hinge_depth must be in [0, 0.5) m, got {}", hinge_depth));
    }
    if (!(door_min_height > 0.0f) || !(top_share > 0.0f && top_share < 1.0f) ||
        !(revolute_upper > 0.0f) || !(prismatic_upper > 0.0f)) {
        throw InvalidArgument(fmt::format(
            "articulation: need door_min_height > 0, top_share in (0, 1), limits > 0 (got {}, {}, "
            "{}, {})",
            door_min_height, top_share, revolute_upper, prismatic_upper));
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
}

Articulation ArticulationFromFixtures(const Front& f, const std::vector<Fixture>& fixtures,
                                      const RoomFrame& frame, float floor_height,
                                      const ArticulationParams& p) {
    p.Validate();
    Articulation none;
    if (f.fixtures.empty()) return none;
    // The front's main fixture: its longest handle, else its first knob.
    const Fixture* fx = nullptr;
    for (const int i : f.fixtures) {
        const Fixture& c = fixtures.at(static_cast<std::size_t>(i));
        if (!fx || (c.type == FixtureType::kHandle &&
                    (fx->type != FixtureType::kHandle || c.length > fx->length))) {
            fx = &c;
        }
    }
    const Eigen::Vector3f up = frame.Up();
    const float width = f.max.x() - f.min.x(), height = f.max.y() - f.min.y();
    const Eigen::Vector2f at(fx->center.dot(f.u_axis), fx->center.dot(f.v_axis));
    const float ru = width > 0 ? (at.x() - f.min.x()) / width : 0.5f;    // 0 left .. 1 right
    const float rv = height > 0 ? (at.y() - f.min.y()) / height : 0.5f;  // 0 bottom .. 1 top
    const float plane_d = -f.normal.dot(f.center);
    auto on_plane = [&](float u, float v) {
        return Eigen::Vector3f(f.u_axis * u + f.v_axis * v - f.normal * plane_d);
    };
    const float base = std::isnan(floor_height) ? 0.0f : floor_height;
    const bool handle = fx->type == FixtureType::kHandle;
    const bool horizontal = handle && std::abs(fx->direction.dot(up)) <
                                          std::sin(p.horizontal_handle_deg * kArticulationDegToRad);
    const bool side = ru < p.top_share || ru > 1.0f - p.top_share;
    if (horizontal || (!handle && !side)) {
        if (height >= p.door_min_height && rv > 1.0f - p.top_share) {
            // Hinged at the bottom edge: an oven or dishwasher door.
            return Hinge(f, on_plane(f.min.x(), f.min.y()), f.v_axis, p);
        }
        if (f.min.y() - base > p.flap_min_bottom && rv < p.top_share &&
            height >= 0.6f * p.door_min_height) {
            // A flap hinged at the top edge (wall cupboards).
            return Hinge(f, on_plane(f.min.x(), f.max.y()), -f.v_axis, p);
        }
        Articulation a;
        a.type = JointType::kPrismatic;
        a.origin = f.center;
        a.axis = f.normal;
        a.lower = 0.0f;
        a.upper = p.prismatic_upper;
        a.source = "fixture";
        return a;
    }
    // Vertical handle or a knob off the centre: hinged at the farther vertical edge.
    if (ru >= 0.5f) {
        return Hinge(f, on_plane(f.min.x(), f.min.y()), f.u_axis, p);
    }
    return Hinge(f, on_plane(f.max.x(), f.min.y()), -f.u_axis, p);
}

MotionResult ArticulationFromMotion(const PointCloud& closed, const PointCloud& opened,
                                    const Front& f, const MotionParams& p) {
    p.Validate();
    if (closed.empty() || opened.empty()) return {};
    return ArticulationFromMotion(KdTree(closed), opened, f, p);
}

MotionResult ArticulationFromMotion(const KdTree& before, const PointCloud& opened, const Front& f,
                                    const MotionParams& p) {
    p.Validate();
    MotionResult out;
    if (before.empty() || opened.empty()) return out;
    const float plane_d = -f.normal.dot(f.center);
    const float width = f.max.x() - f.min.x(), height = f.max.y() - f.min.y();
    const float reach = std::min(p.reach, std::max(width, height) + 0.05f);
    Indices moved;
    for (std::size_t i = 0; i < opened.size(); ++i) {
        if (!opened.IsFinite(i)) continue;
        const Eigen::Vector3f& x = opened.points[i];
        const float h = f.normal.dot(x) + plane_d;
        if (h < p.min_offset || h > reach) continue;
        // Within the space the front can sweep: its rectangle grown by its reach sideways.
        const float u = x.dot(f.u_axis), v = x.dot(f.v_axis);
        if (u < f.min.x() - reach || u > f.max.x() + reach || v < f.min.y() - reach ||
            v > f.max.y() + reach) {
            continue;
        }
        Index nn = 0;
        float d2 = 0.0f;
        if (before.SearchNearest(x, nn, d2) && d2 < p.change_distance * p.change_distance) continue;
        moved.push_back(static_cast<Index>(i));
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
    // Moved points on the closed front's rectangle carried by T (a small margin around it).
    auto support = [&](const Eigen::Isometry3f& T) {
        const Eigen::Vector3f c = T * f.center;
        const Eigen::Vector3f u = T.linear() * f.u_axis, v = T.linear() * f.v_axis,
                              n = T.linear() * f.normal;
        const float hu = (f.max.x() - f.min.x()) / 2 + 0.03f,
                    hv = (f.max.y() - f.min.y()) / 2 + 0.03f;
        std::size_t count = 0;
        for (const Index i : moved) {
            const Eigen::Vector3f d = opened.points[i] - c;
            count += std::abs(d.dot(n)) <= p.plane_threshold && std::abs(d.dot(u)) <= hu &&
                     std::abs(d.dot(v)) <= hv;
        }
        return count;
    };
    // The prismatic hypothesis.
    Articulation slide;
    float travel = 0.0f;
    std::size_t slide_support = 0;
    Indices slide_inliers;
    const float cos_par = std::cos(p.parallel_deg * kArticulationDegToRad);
    const PlaneFit& pf =
        std::abs(fit.plane.head<3>().dot(f.normal)) >= cos_par ? fit : fit_parallel;
    if (pf.found && pf.inliers.size() >= p.min_points) {
        travel = std::max(0.0f, f.normal.dot(centroid_of(pf.inliers)) + plane_d);
        slide.type = JointType::kPrismatic;
        slide.axis = f.normal;
        slide.origin = f.center;
        slide.upper = travel;
        slide.source = "motion";
        Eigen::Isometry3f T = Eigen::Isometry3f::Identity();
        T.translation() = f.normal * travel;
        slide_support = support(T);
        slide_inliers = pf.inliers;
    }
    // The revolute hypothesis, from the best plane when it is tilted.
    Articulation hinge;
    float angle = 0.0f;
    std::size_t hinge_support = 0;
    Eigen::Vector3f nb = fit.plane.head<3>();
    if (std::abs(nb.dot(f.normal)) < cos_par) {
        const Eigen::Vector3f centroid = centroid_of(fit.inliers);
        Eigen::Vector3f dir = f.normal.cross(nb).normalized();
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
        const Eigen::Isometry3f T = Eigen::Translation3f(point) * Eigen::AngleAxisf(angle, dir) *
                                    Eigen::Translation3f(-point);
        hinge_support = support(T);
    }
    if (slide.type == JointType::kUnknown && hinge.type == JointType::kUnknown) return out;
    out.found = true;
    if (hinge.type != JointType::kUnknown && hinge_support >= slide_support) {
        out.articulation = hinge;
        out.opening = angle;
        out.moved = fit.inliers;
    } else {
        out.articulation = slide;
        out.opening = travel;
        out.moved = slide_inliers;
    }
    return out;
}

int UpdateArticulationFromOpenedScan(KitchenMap& map, const PointCloud& closed,
                                     const PointCloud& opened, const MotionParams& p) {
    p.Validate();
    int best = -1;
    std::size_t best_points = 0;
    MotionResult best_motion;
    if (closed.empty() || opened.empty()) return -1;
    const KdTree tree(closed);
    for (std::size_t f = 0; f < map.fronts.size(); ++f) {
        MotionResult m = ArticulationFromMotion(tree, opened, map.fronts[f], p);
        if (m.found && m.moved.size() > best_points) {
            best_points = m.moved.size();
            best = static_cast<int>(f);
            best_motion = std::move(m);
        }
    }
    if (best >= 0)
        map.fronts[static_cast<std::size_t>(best)].articulation = best_motion.articulation;
    return best;
}

}  // namespace multicue::mapping

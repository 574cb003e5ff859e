#include "multicue/segmentation/polygonal_prism.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include <fmt/format.h>
#include <Eigen/Geometry>

#include "multicue/core/exceptions.hpp"
#include "multicue/core/parallel.hpp"

namespace multicue {
namespace {

// Orthonormal basis (u, v) of the plane with u x v = n, so counter-clockwise in (u, v) is
// counter-clockwise seen from the normal's side.
void PlaneBasis(const Eigen::Vector3f& n, Eigen::Vector3f& u, Eigen::Vector3f& v) {
    const Eigen::Vector3f helper =
        std::abs(n.x()) < 0.9f ? Eigen::Vector3f::UnitX() : Eigen::Vector3f::UnitY();
    u = n.cross(helper).normalized();
    v = n.cross(u);
}

void CheckPlane(const Eigen::Vector4f& plane) {
    const float len = plane.head<3>().norm();
    if (!plane.allFinite() || std::abs(len - 1.0f) > 1e-3f) {
        throw InvalidArgument(
            fmt::format("plane normal must be unit length, got ({}, {}, {}) of length {}",
                        plane.x(), plane.y(), plane.z(), len));
    }
}

double Cross(const Eigen::Vector2d& o, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    return (a - o).x() * (b - o).y() - (a - o).y() * (b - o).x();
}

// Akl-Toussaint pre-filter: points strictly inside the polygon of the extreme points in eight
// directions cannot be hull vertices. On a table of 150k points it leaves a few thousand to sort.
void DiscardInteriorPoints(std::vector<Eigen::Vector2d>& pts) {
    if (pts.size() < 64) return;
    const std::array<Eigen::Vector2d, 8> dirs = {Eigen::Vector2d(1, 0),  Eigen::Vector2d(1, 1),
                                                 Eigen::Vector2d(0, 1),  Eigen::Vector2d(-1, 1),
                                                 Eigen::Vector2d(-1, 0), Eigen::Vector2d(-1, -1),
                                                 Eigen::Vector2d(0, -1), Eigen::Vector2d(1, -1)};
    std::array<Eigen::Vector2d, 8> extreme;
    std::array<double, 8> best;
    best.fill(-std::numeric_limits<double>::infinity());
    for (const auto& p : pts) {
        for (std::size_t d = 0; d < dirs.size(); ++d) {
            const double v = dirs[d].dot(p);
            if (v > best[d]) {
                best[d] = v;
                extreme[d] = p;
            }
        }
    }
    // The extremes in increasing angle of their directions form a convex, counter-clockwise
    // polygon (some may coincide, which only makes a test stricter).
    auto strictly_inside = [&](const Eigen::Vector2d& q) {
        for (std::size_t k = 0; k < extreme.size(); ++k) {
            const Eigen::Vector2d& a = extreme[k];
            const Eigen::Vector2d& b = extreme[(k + 1) % extreme.size()];
            if (a == b) continue;
            if (Cross(a, b, q) <= 0.0) return false;
        }
        return true;
    };
    std::erase_if(pts, strictly_inside);
}

}  // namespace

void PrismParams::Validate() const {
    if (!(min_height <= max_height)) {
        throw InvalidArgument(fmt::format("prism min_height {} must not exceed max_height {}",
                                          min_height, max_height));
    }
    if (!(edge_reach >= 0.0f) || !std::isfinite(edge_reach)) {
        throw InvalidArgument(fmt::format("prism edge_reach must be >= 0, got {}", edge_reach));
    }
}

std::vector<Eigen::Vector3f> PlaneConvexHull(const PointCloud& cloud, const Indices& subset,
                                             const Eigen::Vector4f& plane) {
    CheckPlane(plane);
    const Eigen::Vector3f n = plane.head<3>();
    Eigen::Vector3f u, v;
    PlaneBasis(n, u, v);
    const Eigen::Vector3f origin = -plane.w() * n;  // point of the plane nearest the origin

    std::vector<Eigen::Vector2d> pts;
    auto add = [&](std::size_t i) {
        const Eigen::Vector3f& p = cloud.points[i];
        if (!p.allFinite()) return;
        const Eigen::Vector3f r = p - origin;
        pts.emplace_back(r.dot(u), r.dot(v));
    };
    if (subset.empty()) {
        for (std::size_t i = 0; i < cloud.size(); ++i) add(i);
    } else {
        for (Index i : subset) {
            if (i >= cloud.size()) {
                throw InvalidArgument(fmt::format(
                    "index {} is out of range for a cloud of {} points", i, cloud.size()));
            }
            add(i);
        }
    }
    DiscardInteriorPoints(pts);
    std::sort(pts.begin(), pts.end(), [](const auto& a, const auto& b) {
        return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
    });
    pts.erase(std::unique(pts.begin(), pts.end()), pts.end());

    // Monotone chain: lower then upper hull; collinear points dropped (strict turns only).
    std::vector<Eigen::Vector2d> hull;
    if (pts.size() < 3) {
        hull = pts;
    } else {
        hull.resize(2 * pts.size());
        std::size_t k = 0;
        for (const auto& p : pts) {
            while (k >= 2 && Cross(hull[k - 2], hull[k - 1], p) <= 0.0) --k;
            hull[k++] = p;
        }
        const std::size_t lower = k + 1;
        for (std::size_t i = pts.size() - 1; i-- > 0;) {
            while (k >= lower && Cross(hull[k - 2], hull[k - 1], pts[i]) <= 0.0) --k;
            hull[k++] = pts[i];
        }
        hull.resize(k - 1);
    }
    std::vector<Eigen::Vector3f> out;
    out.reserve(hull.size());
    for (const auto& h : hull) {
        out.push_back(origin + static_cast<float>(h.x()) * u + static_cast<float>(h.y()) * v);
    }
    return out;
}

Indices PolygonalPrism(const PointCloud& cloud, const Eigen::Vector4f& plane,
                       const std::vector<Eigen::Vector3f>& hull, const PrismParams& params,
                       int num_threads) {
    CheckPlane(plane);
    params.Validate();
    if (hull.size() < 3) {
        throw InvalidArgument(
            fmt::format("prism needs a hull of at least 3 vertices, got {}", hull.size()));
    }
    const Eigen::Vector3f n = plane.head<3>();
    Eigen::Vector3f u, v;
    PlaneBasis(n, u, v);
    // The polygon's corners and edges in the plane's basis.
    std::vector<Eigen::Vector2f> corner, edge;
    corner.reserve(hull.size());
    for (const auto& h : hull) corner.emplace_back(h.dot(u), h.dot(v));
    edge.reserve(hull.size());
    for (std::size_t k = 0; k < corner.size(); ++k)
        edge.push_back(corner[(k + 1) % corner.size()] - corner[k]);
    return ParallelSelect(cloud.size(), num_threads, [&](std::size_t i) {
        const Eigen::Vector3f& p = cloud.points[i];
        if (!p.allFinite()) return false;
        const float h = n.dot(p) + plane.w();
        if (h < params.min_height || h > params.max_height) return false;
        const Eigen::Vector2f q(p.dot(u), p.dot(v));
        for (std::size_t k = 0; k < corner.size(); ++k) {
            const Eigen::Vector2f d = q - corner[k];
            if (!(edge[k].x() * d.y() - edge[k].y() * d.x() >= 0.0f)) return false;
        }
        return true;
    });
}

}  // namespace multicue

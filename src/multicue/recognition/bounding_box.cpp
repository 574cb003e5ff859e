#include "multicue/recognition/bounding_box.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>

#include <fmt/format.h>
#include <Eigen/Eigenvalues>

#include "multicue/core/exceptions.hpp"

namespace multicue {
namespace {

constexpr double kQuarterTurn = std::numbers::pi / 2.0;

void CheckIndices(const PointCloud& cloud, const Indices& indices) {
    for (Index i : indices) {
        if (i >= cloud.size()) {
            throw InvalidArgument(
                fmt::format("index {} out of range for a cloud of {} points", i, cloud.size()));
        }
    }
}

double Cross(const Eigen::Vector2d& o, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
}

// Unit normal and a point's 2D coordinates in the basis (u, v) of the plane orthogonal to it.
struct PlaneBasis {
    Eigen::Vector3f u;
    Eigen::Vector3f v;
    explicit PlaneBasis(const Eigen::Vector3f& n) : u(n.unitOrthogonal()), v(n.cross(u)) {}
    Eigen::Vector2f Project(const Eigen::Vector3f& p) const { return {p.dot(u), p.dot(v)}; }
    Eigen::Vector3f Lift(const Eigen::Vector2f& q) const { return q.x() * u + q.y() * v; }
};

// The remainder of x by a quarter turn, as std::fmod gives it. Within two quarter turns it is x
// itself or x less one quarter turn, which is exact there (Sterbenz), so fmod is left for the
// rest.
double QuarterRemainder(double x) {
    const double m = std::abs(x);
    if (m < kQuarterTurn) return x;
    // copysign keeps fmod's sign of a zero remainder (-0 for x = -pi/2).
    if (m < 2.0 * kQuarterTurn) return std::copysign(x - std::copysign(kQuarterTurn, x), x);
    return std::fmod(x, kQuarterTurn);
}

// Azimuth of a horizontal direction modulo a quarter turn, in [0, pi/2).
double QuarterAzimuth(double x, double y) {
    double a = QuarterRemainder(std::atan2(y, x));
    if (a < 0.0) a += kQuarterTurn;
    if (a >= kQuarterTurn) a -= kQuarterTurn;
    return a;
}

// Signed offset of angle a from centre c modulo a quarter turn, in [-pi/4, pi/4).
double QuarterOffset(double a, double c) {
    double d = QuarterRemainder(a - c);
    if (d < -kQuarterTurn / 2) d += kQuarterTurn;
    if (d >= kQuarterTurn / 2) d -= kQuarterTurn;
    return d;
}

// Akl-Toussaint: the points extreme in eight directions (the axes and diagonals) lie on the hull,
// so a point strictly inside their polygon is strictly inside the hull and never one of its
// vertices. Dropping those before the sort leaves the hull as it was.
void DropInterior(std::vector<Eigen::Vector2f>& points) {
    if (points.size() < 64) return;
    // Directions counter-clockwise from -y: the extremes come out in hull order.
    constexpr std::size_t kDirections = 8;
    std::array<std::size_t, kDirections> extreme{};
    std::array<double, kDirections> best;
    best.fill(-std::numeric_limits<double>::infinity());
    for (std::size_t i = 0; i < points.size(); ++i) {
        const double x = points[i].x(), y = points[i].y();
        const std::array<double, kDirections> score = {-y, x - y, x, x + y, y, y - x, -x, -x - y};
        for (std::size_t d = 0; d < kDirections; ++d) {
            if (score[d] > best[d]) {
                best[d] = score[d];
                extreme[d] = i;
            }
        }
    }
    std::vector<Eigen::Vector2d> polygon;
    for (const std::size_t i : extreme) {
        const Eigen::Vector2d q = points[i].cast<double>();
        if (polygon.empty() || q != polygon.back()) polygon.push_back(q);
    }
    while (polygon.size() > 1 && polygon.front() == polygon.back()) polygon.pop_back();
    if (polygon.size() < 3) return;
    const std::size_t n = polygon.size();
    polygon.push_back(polygon.front());  // closed: edge j runs from vertex j to j + 1
    std::erase_if(points, [&](const Eigen::Vector2f& p) {
        const Eigen::Vector2d q = p.cast<double>();
        for (std::size_t j = 0; j < n; ++j) {
            if (!(Cross(polygon[j], polygon[j + 1], q) > 0.0)) return false;
        }
        return true;
    });
}

}  // namespace

std::vector<Eigen::Vector2f> ConvexHull2d(std::vector<Eigen::Vector2f> points) {
    std::erase_if(points, [](const Eigen::Vector2f& p) { return !p.allFinite(); });
    DropInterior(points);
    std::sort(points.begin(), points.end(), [](const Eigen::Vector2f& a, const Eigen::Vector2f& b) {
        return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
    });
    points.erase(std::unique(points.begin(), points.end()), points.end());
    if (points.size() < 3) return points;
    // Lower hull left to right, then upper hull right to left; a turn that is not strictly
    // counter-clockwise drops the middle point, so collinear points never become vertices.
    std::vector<Eigen::Vector2d> pts(points.size());
    for (std::size_t i = 0; i < points.size(); ++i) pts[i] = points[i].cast<double>();
    std::vector<std::size_t> hull(2 * pts.size());
    std::size_t k = 0;
    for (std::size_t i = 0; i < pts.size(); ++i) {
        while (k >= 2 && Cross(pts[hull[k - 2]], pts[hull[k - 1]], pts[i]) <= 0.0) --k;
        hull[k++] = i;
    }
    for (std::size_t i = pts.size() - 1, lower = k + 1; i-- > 0;) {
        while (k >= lower && Cross(pts[hull[k - 2]], pts[hull[k - 1]], pts[i]) <= 0.0) --k;
        hull[k++] = i;
    }
    std::vector<Eigen::Vector2f> out;
    out.reserve(k - 1);
    for (std::size_t i = 0; i + 1 < k; ++i) out.push_back(points[hull[i]]);
    return out;
}

float PolygonArea(const std::vector<Eigen::Vector2f>& polygon) {
    if (polygon.size() < 3) return 0.0f;
    const Eigen::Vector2d o = polygon[0].cast<double>();
    double twice = 0.0;
    for (std::size_t i = 1; i + 1 < polygon.size(); ++i) {
        twice += Cross(o, polygon[i].cast<double>(), polygon[i + 1].cast<double>());
    }
    return static_cast<float>(0.5 * twice);
}

Rectangle2d MinAreaRectangle(const std::vector<Eigen::Vector2f>& hull) {
    Rectangle2d rect;
    const std::size_t n = hull.size();
    if (n == 0) return rect;
    if (n == 1) {
        rect.center = hull[0];
        return rect;
    }
    if (n == 2) {
        const Eigen::Vector2f d = hull[1] - hull[0];
        rect.center = 0.5f * (hull[0] + hull[1]);
        if (d.norm() > 0.0f) rect.axis = d.normalized();
        rect.size = {d.norm(), 0.0f};
        return rect;
    }
    // Coordinates relative to the first vertex keep the products small.
    std::vector<Eigen::Vector2d> p(n);
    for (std::size_t i = 0; i < n; ++i) p[i] = (hull[i] - hull[0]).cast<double>();
    auto dot = [](const Eigen::Vector2d& a, const Eigen::Vector2d& b) { return a.dot(b); };
    auto next = [n](std::size_t i) { return (i + 1) % n; };

    // Calipers for edge i: the vertices extreme along the edge direction (max and min) and
    // farthest from the edge. Each only moves forward as the edge turns counter-clockwise.
    std::size_t i_max = 0, i_far = 0, i_min = 0;
    double best_area = std::numeric_limits<double>::infinity();
    Eigen::Vector2d best_d = Eigen::Vector2d::UnitX();
    double best_lo = 0.0, best_hi = 0.0, best_n_lo = 0.0, best_n_hi = 0.0;
    for (std::size_t e = 0; e < n; ++e) {
        const Eigen::Vector2d edge = p[next(e)] - p[e];
        const double len = edge.norm();
        if (!(len > 0.0)) continue;
        const Eigen::Vector2d d = edge / len;
        const Eigen::Vector2d nn(-d.y(), d.x());  // inward: the hull lies to the left
        if (e == 0) {
            for (std::size_t j = 0; j < n; ++j) {
                if (dot(p[j], d) > dot(p[i_max], d)) i_max = j;
                if (dot(p[j], nn) > dot(p[i_far], nn)) i_far = j;
                if (dot(p[j], d) < dot(p[i_min], d)) i_min = j;
            }
        } else {
            for (std::size_t s = 0; s < n && dot(p[next(i_max)], d) > dot(p[i_max], d); ++s) {
                i_max = next(i_max);
            }
            for (std::size_t s = 0; s < n && dot(p[next(i_far)], nn) > dot(p[i_far], nn); ++s) {
                i_far = next(i_far);
            }
            for (std::size_t s = 0; s < n && dot(p[next(i_min)], d) < dot(p[i_min], d); ++s) {
                i_min = next(i_min);
            }
        }
        const double lo = dot(p[i_min], d), hi = dot(p[i_max], d);
        const double n_lo = dot(p[e], nn), n_hi = dot(p[i_far], nn);
        const double area = (hi - lo) * (n_hi - n_lo);
        if (area < best_area) {
            best_area = area;
            best_d = d;
            best_lo = lo;
            best_hi = hi;
            best_n_lo = n_lo;
            best_n_hi = n_hi;
        }
    }
    const Eigen::Vector2d nn(-best_d.y(), best_d.x());
    const Eigen::Vector2d c =
        0.5 * (best_lo + best_hi) * best_d + 0.5 * (best_n_lo + best_n_hi) * nn;
    rect.center = hull[0] + c.cast<float>();
    const auto len_d = static_cast<float>(best_hi - best_lo);
    const auto len_n = static_cast<float>(best_n_hi - best_n_lo);
    if (len_d >= len_n) {
        rect.axis = best_d.cast<float>();
        rect.size = {len_d, len_n};
    } else {
        rect.axis = nn.cast<float>();
        rect.size = {len_n, len_d};
    }
    return rect;
}

std::optional<Eigen::Vector4f> NormalizeSupportPlane(const Eigen::Vector4f& plane) {
    if (!plane.allFinite()) {
        throw InvalidArgument(fmt::format("support plane must be finite, got ({}, {}, {}, {})",
                                          plane[0], plane[1], plane[2], plane[3]));
    }
    if (plane.isZero(0.0f)) return std::nullopt;
    const float norm = plane.head<3>().norm();
    if (!(norm > 0.0f)) {
        throw InvalidArgument(
            fmt::format("support plane normal must be non-zero, got ({}, {}, {}, {})", plane[0],
                        plane[1], plane[2], plane[3]));
    }
    return Eigen::Vector4f(plane / norm);
}

OrientedBox UprightBoundingBox(const PointCloud& cloud, const Indices& indices,
                               const Eigen::Vector4f& unit_plane) {
    CheckIndices(cloud, indices);
    const Eigen::Vector3f up = unit_plane.head<3>();
    const PlaneBasis basis(up);
    std::vector<Eigen::Vector2f> footprint;
    footprint.reserve(indices.size());
    float top = 0.0f;
    for (Index i : indices) {
        const Eigen::Vector3f& p = cloud.points[i];
        if (!p.allFinite()) continue;
        footprint.push_back(basis.Project(p));
        top = std::max(top, up.dot(p) + unit_plane[3]);
    }
    OrientedBox box;
    if (footprint.empty()) return box;
    const Rectangle2d rect = MinAreaRectangle(ConvexHull2d(std::move(footprint)));
    const Eigen::Vector3f x = basis.Lift(rect.axis).normalized();
    box.axes.col(0) = x;
    box.axes.col(1) = up.cross(x);
    box.axes.col(2) = up;
    box.extents = {rect.size.x(), rect.size.y(), top};
    // The point of the plane below the footprint centre: -d up lies in the plane.
    box.center = basis.Lift(rect.center) - unit_plane[3] * up + 0.5f * top * up;
    return box;
}

OrientedBox MinVolumeBoundingBox(const PointCloud& cloud, const Indices& indices) {
    CheckIndices(cloud, indices);
    std::vector<Eigen::Vector3d> pts;
    pts.reserve(indices.size());
    for (Index i : indices) {
        if (cloud.points[i].allFinite()) pts.push_back(cloud.points[i].cast<double>());
    }
    OrientedBox box;
    if (pts.empty()) return box;
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (const auto& p : pts) mean += p;
    mean /= static_cast<double>(pts.size());
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (auto& p : pts) {
        p -= mean;
        cov += p * p.transpose();
    }
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(cov);
    const Eigen::Matrix3d evec = solver.eigenvectors();

    double best_volume = std::numeric_limits<double>::infinity();
    for (int k = 0; k < 3; ++k) {
        const Eigen::Vector3d a = evec.col(k);
        const Eigen::Vector3d b = evec.col((k + 1) % 3);
        const Eigen::Vector3d c = evec.col((k + 2) % 3);
        std::vector<Eigen::Vector2f> proj(pts.size());
        double lo = std::numeric_limits<double>::infinity(), hi = -lo;
        for (std::size_t j = 0; j < pts.size(); ++j) {
            proj[j] = Eigen::Vector2f(static_cast<float>(pts[j].dot(b)),
                                      static_cast<float>(pts[j].dot(c)));
            lo = std::min(lo, pts[j].dot(a));
            hi = std::max(hi, pts[j].dot(a));
        }
        const Rectangle2d rect = MinAreaRectangle(ConvexHull2d(std::move(proj)));
        const double volume = double{rect.Area()} * (hi - lo);
        if (!(volume < best_volume) && k > 0) continue;
        best_volume = volume;
        const Eigen::Vector3d r0 = (rect.axis.x() * b + rect.axis.y() * c).normalized();
        const Eigen::Vector3d r1 = a.cross(r0);
        const Eigen::Vector3d center =
            mean + rect.center.x() * b + rect.center.y() * c + 0.5 * (lo + hi) * a;
        box.center = center.cast<float>();
        box.axes.col(0) = r0.cast<float>();
        box.axes.col(1) = r1.cast<float>();
        box.axes.col(2) = a.cast<float>();
        box.extents = {rect.size.x(), rect.size.y(), static_cast<float>(hi - lo)};
    }
    // Longest side first; the third axis is recomputed so the frame stays right-handed.
    std::array<int, 3> order{0, 1, 2};
    std::stable_sort(order.begin(), order.end(),
                     [&](int i, int j) { return box.extents[i] > box.extents[j]; });
    OrientedBox sorted;
    sorted.center = box.center;
    for (int k = 0; k < 3; ++k) {
        sorted.axes.col(k) = box.axes.col(order[static_cast<std::size_t>(k)]);
        sorted.extents[k] = box.extents[order[static_cast<std::size_t>(k)]];
    }
    sorted.axes.col(2) = sorted.axes.col(0).cross(sorted.axes.col(1)).normalized();
    return sorted;
}

FaceAlignment AlignUprightAxes(const PointCloud& cloud, const Indices& indices,
                               const Eigen::Vector3f& up, float max_angle,
                               std::size_t min_side_normals) {
    if (!(max_angle > 0.0f) || !(max_angle <= std::numbers::pi_v<float> / 4.0f)) {
        throw InvalidArgument(fmt::format("max_angle must be in (0, pi/4], got {}", max_angle));
    }
    CheckIndices(cloud, indices);
    FaceAlignment out;
    if (indices.empty()) return out;
    if (cloud.normals.size() != cloud.size()) {
        throw DataError(fmt::format("face alignment needs one normal per point, got {} for {}",
                                    cloud.normals.size(), cloud.size()));
    }
    const Eigen::Vector3f n_up = up.normalized();
    const PlaneBasis basis(n_up);
    const double sin_max = std::sin(double{max_angle});
    std::vector<double> azimuths;
    azimuths.reserve(indices.size());
    for (Index i : indices) {
        const Eigen::Vector3f& n = cloud.normals[i];
        if (!cloud.points[i].allFinite() || !n.allFinite() || !(n.norm() > 0.0f)) continue;
        const Eigen::Vector3d nd = n.cast<double>().normalized();
        if (std::abs(nd.dot(n_up.cast<double>())) > sin_max) continue;
        azimuths.push_back(
            QuarterAzimuth(nd.dot(basis.u.cast<double>()), nd.dot(basis.v.cast<double>())));
    }
    double yaw = 0.0;
    out.found = !azimuths.empty() && azimuths.size() >= min_side_normals;
    if (out.found) {
        std::sort(azimuths.begin(), azimuths.end());
        const std::size_t m = azimuths.size();
        const double width = 2.0 * double{max_angle};
        // Sliding window over the azimuths unrolled once (a + pi/2) to handle the wrap-around.
        std::size_t best_start = 0, best_count = 0, j = 0;
        auto unrolled = [&](std::size_t k) {
            return k < m ? azimuths[k] : azimuths[k - m] + kQuarterTurn;
        };
        for (std::size_t s = 0; s < m; ++s) {
            j = std::max(j, s);
            while (j < s + m && unrolled(j) <= azimuths[s] + width) ++j;
            if (j - s > best_count) {
                best_count = j - s;
                best_start = s;
            }
        }
        yaw = azimuths[best_start] + 0.5 * width;
        // Refine: mean offset of the azimuths within max_angle of the current centre.
        for (int round = 0; round < 3; ++round) {
            double sum = 0.0;
            std::size_t count = 0;
            for (double a : azimuths) {
                const double d = QuarterOffset(a, yaw);
                if (std::abs(d) <= double{max_angle}) {
                    sum += d;
                    ++count;
                }
            }
            if (count == 0) break;
            yaw += sum / static_cast<double>(count);
        }
        yaw = QuarterAzimuth(std::cos(yaw), std::sin(yaw));
    }
    const Eigen::Vector3f x =
        (static_cast<float>(std::cos(yaw)) * basis.u + static_cast<float>(std::sin(yaw)) * basis.v)
            .normalized();
    out.axes.col(0) = x;
    out.axes.col(1) = n_up.cross(x);
    out.axes.col(2) = n_up;

    const float cos_max = std::cos(max_angle);
    for (Index i : indices) {
        const Eigen::Vector3f& n = cloud.normals[i];
        if (!cloud.points[i].allFinite() || !n.allFinite() || !(n.norm() > 0.0f)) continue;
        const Eigen::Vector3f c = (out.axes.transpose() * n.normalized()).cwiseAbs();
        ++out.num_normals;
        if (c.maxCoeff() >= cos_max) ++out.num_aligned;
        if (c.z() >= cos_max) ++out.num_vertical;
    }
    out.aligned_ratio = out.num_normals > 0 ? static_cast<float>(out.num_aligned) /
                                                  static_cast<float>(out.num_normals)
                                            : 0.0f;
    return out;
}

}  // namespace multicue

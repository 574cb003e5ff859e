#include "multicue/reconstruction/primitive_models.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <utility>
#include <vector>

#include <fmt/format.h>
#include <Eigen/Eigenvalues>

#include "multicue/core/exceptions.hpp"
#include "multicue/recognition/bounding_box.hpp"
#include "multicue/reconstruction/cylinder_refinement.hpp"
#include "multicue/segmentation/sac_cylinder.hpp"

namespace multicue {
namespace {

constexpr float kDeg = std::numbers::pi_v<float> / 180.0f;

template <typename... Args>
void Require(bool ok, fmt::format_string<Args...> message, Args&&... args) {
    if (!ok) throw InvalidArgument(fmt::format(message, std::forward<Args>(args)...));
}

void CheckIndices(const PointCloud& cloud, const Indices& indices) {
    for (Index i : indices) {
        Require(i < cloud.size(), "index {} out of range for a cloud of {} points", i,
                cloud.size());
    }
}

void ValidateBoxParams(const BoxFitParams& p) {
    Require(p.inlier_threshold > 0.0f && std::isfinite(p.inlier_threshold),
            "inlier_threshold must be > 0 and finite, got {}", p.inlier_threshold);
    Require(p.face_angle_deg > 0.0f && p.face_angle_deg <= 45.0f,
            "face_angle_deg must be in (0, 45], got {}", p.face_angle_deg);
    Require(p.min_face_points >= 1, "min_face_points must be >= 1, got {}", p.min_face_points);
    Require(p.edge_window >= 0.0f && std::isfinite(p.edge_window),
            "edge_window must be >= 0 and finite, got {}", p.edge_window);
}

Indices FinitePoints(const PointCloud& cloud, const Indices& indices) {
    Indices out;
    out.reserve(indices.size());
    for (Index i : indices) {
        if (cloud.points[i].allFinite()) out.push_back(i);
    }
    return out;
}

// Median of a non-empty vector (upper median for even sizes: deterministic, no averaging).
float Median(std::vector<float> v) {
    const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
    std::nth_element(v.begin(), mid, v.end());
    return *mid;
}

// Far edge of a region sampled with roughly even density along a coordinate, from its points'
// coordinates s. The extreme point M lies beyond the edge by the largest of the noise values of
// the points there (several sigma). Instead: the density rho inside, from the points in
// [M - 2w, M - w], and the count n of points beyond M - w (the noise tail and the last strip)
// place the edge at M - w + n / rho, which is unbiased for symmetric noise as long as w exceeds
// the noise's reach. Falls back to M when the strip is empty.
float FarEdge(const std::vector<float>& s, bool upper, float w) {
    const float m =
        upper ? *std::max_element(s.begin(), s.end()) : *std::min_element(s.begin(), s.end());
    if (!(w > 0.0f)) return m;
    std::size_t inner = 0, beyond = 0;
    for (float x : s) {
        const float depth = upper ? m - x : x - m;  // distance inside the extreme
        if (depth <= w) {
            ++beyond;
        } else if (depth <= 2.0f * w) {
            ++inner;
        }
    }
    if (inner < 5) return m;
    const float reach = w * static_cast<float>(beyond) / static_cast<float>(inner);
    const float edge_depth = std::clamp(w - reach, 0.0f, w);
    return upper ? m - edge_depth : m + edge_depth;
}

float BoxInlierRatio(const PointCloud& cloud, const Indices& finite, const BoxModel& box,
                     float threshold) {
    std::size_t inliers = 0;
    for (Index i : finite) {
        if (BoxSurfaceDistance(box, cloud.points[i]) <= threshold) ++inliers;
    }
    return static_cast<float>(inliers) / static_cast<float>(finite.size());
}

void ValidateCylinderParams(const CylinderModelParams& p) {
    ValidateSacParams(p.sac);
    Require(p.min_radius >= 0.0f && p.max_radius >= p.min_radius,
            "radii must satisfy 0 <= min_radius <= max_radius, got {} and {}", p.min_radius,
            p.max_radius);
    Require(p.upright_angle_deg >= 0.0f && p.upright_angle_deg <= 90.0f,
            "upright_angle_deg must be in [0, 90], got {}", p.upright_angle_deg);
    Require(p.lying_angle_deg >= 0.0f && p.lying_angle_deg <= 90.0f,
            "lying_angle_deg must be in [0, 90], got {}", p.lying_angle_deg);
    Require(p.free_axis_gain >= 1.0f && std::isfinite(p.free_axis_gain),
            "free_axis_gain must be >= 1 and finite, got {}", p.free_axis_gain);
    Require(p.side_distance > 0.0f && std::isfinite(p.side_distance),
            "side_distance must be > 0 and finite, got {}", p.side_distance);
    Require(p.side_normal_angle_deg > 0.0f && p.side_normal_angle_deg <= 90.0f,
            "side_normal_angle_deg must be in (0, 90], got {}", p.side_normal_angle_deg);
    Require(p.refine_rounds >= 0, "refine_rounds must be >= 0, got {}", p.refine_rounds);
    Require(p.cap_angle_deg > 0.0f && p.cap_angle_deg <= 45.0f,
            "cap_angle_deg must be in (0, 45], got {}", p.cap_angle_deg);
    Require(p.min_cap_points >= 1, "min_cap_points must be >= 1, got {}", p.min_cap_points);
    Require(p.inlier_threshold > 0.0f && std::isfinite(p.inlier_threshold),
            "inlier_threshold must be > 0 and finite, got {}", p.inlier_threshold);
}

// `v` with its largest-magnitude component positive (a direction without a natural sign).
Eigen::Vector3f CanonicalAxis(const Eigen::Vector3f& v) {
    int k = 0;
    v.cwiseAbs().maxCoeff(&k);
    return v[k] < 0.0f ? Eigen::Vector3f(-v) : v;
}

// Points with a normal perpendicular to up (within the side angle), in footprint coordinates of
// the basis (u, v) of the plane, u x v = up.
struct SideFootprint {
    Eigen::Vector3f up = Eigen::Vector3f::UnitZ(), u = Eigen::Vector3f::UnitX(),
                    v = Eigen::Vector3f::UnitY();
    Indices idx;
    std::vector<Eigen::Vector2f> q;
};

SideFootprint SidePointsOf(const PointCloud& cloud, const Indices& finite,
                           const Eigen::Vector3f& up, float side_angle) {
    SideFootprint s;
    s.up = up;
    s.u = up.unitOrthogonal();
    s.v = up.cross(s.u);
    const float sin_side = std::sin(side_angle);
    for (Index i : finite) {
        const Eigen::Vector3f& n = cloud.normals[i];
        if (!n.allFinite() || !(n.squaredNorm() > 0.0f)) continue;
        if (std::abs(n.normalized().dot(up)) > sin_side) continue;
        s.idx.push_back(i);
        s.q.emplace_back(cloud.points[i].dot(s.u), cloud.points[i].dot(s.v));
    }
    return s;
}

// A footprint rectangle: orientation theta of its first axis in the (u, v) basis and the
// intervals it covers along both axes.
struct Rectangle2d {
    float theta = 0.0f;
    float lo[2] = {0.0f, 0.0f};
    float hi[2] = {0.0f, 0.0f};

    Eigen::Vector2f Axis(int k) const {
        const float c = std::cos(theta), s = std::sin(theta);
        return k == 0 ? Eigen::Vector2f(c, s) : Eigen::Vector2f(-s, c);
    }
    // Distance of q to the rectangle's boundary.
    float Distance(const Eigen::Vector2f& q) const {
        const float s0 = q.dot(Axis(0)), s1 = q.dot(Axis(1));
        const float out0 = std::max({lo[0] - s0, s0 - hi[0], 0.0f});
        const float out1 = std::max({lo[1] - s1, s1 - hi[1], 0.0f});
        if (out0 > 0.0f || out1 > 0.0f) return std::hypot(out0, out1);
        return std::min({s0 - lo[0], hi[0] - s0, s1 - lo[1], hi[1] - s1});
    }
};

// The oriented bounding rectangle of q at orientation theta, with a share `trim` of the points
// left out at each end of each axis.
Rectangle2d BoundingRectangle(const std::vector<Eigen::Vector2f>& q, float theta, float trim) {
    Rectangle2d r;
    r.theta = theta;
    std::vector<float> s(q.size());
    const auto cut = static_cast<std::size_t>(trim * static_cast<float>(q.size()));
    for (int k = 0; k < 2; ++k) {
        const Eigen::Vector2f a = r.Axis(k);
        for (std::size_t j = 0; j < q.size(); ++j) s[j] = q[j].dot(a);
        const auto first = s.begin() + static_cast<std::ptrdiff_t>(cut);
        const auto last = s.end() - 1 - static_cast<std::ptrdiff_t>(cut);
        std::nth_element(s.begin(), first, s.end());
        r.lo[k] = *first;
        std::nth_element(first, last, s.end());
        r.hi[k] = *last;
    }
    return r;
}

// Orientation of a footprint direction modulo 90 degrees, in [0, pi/2).
float QuarterAngle(const Eigen::Vector2f& d) {
    constexpr float kQuarter = 0.5f * std::numbers::pi_v<float>;
    float a = std::fmod(std::atan2(d.y(), d.x()), kQuarter);
    if (a < 0.0f) a += kQuarter;
    return a >= kQuarter ? 0.0f : a;
}

// Side points within `threshold` of the rectangle's boundary and their summed score weight.
double RectangleSupport(const SideFootprint& side, const Rectangle2d& r, float threshold,
                        const std::vector<float>& score_weights) {
    double support = 0.0;
    for (std::size_t j = 0; j < side.q.size(); ++j) {
        if (r.Distance(side.q[j]) <= threshold) {
            support += score_weights.empty() ? 1.0 : double{score_weights[side.idx[j]]};
        }
    }
    return support;
}

void ValidateRectangleParams(const FootprintRectangleParams& p) {
    ValidateSacParams(p.sac);
    Require(p.side_angle_deg > 0.0f && p.side_angle_deg <= 45.0f,
            "side_angle_deg must be in (0, 45], got {}", p.side_angle_deg);
    Require(p.trim >= 0.0f && p.trim <= 0.25f, "trim must be in [0, 0.25], got {}", p.trim);
}

// The RANSAC of FitFootprintRectangle on prepared side points; sac carries the weights.
FootprintRectangle RunRectangleRansac(const PointCloud& cloud, const SideFootprint& side,
                                      float plane_d, const FootprintRectangleParams& params,
                                      const SacParams& sac) {
    FootprintRectangle rect;
    rect.side_points = side.idx.size();
    if (side.idx.size() < 2) return rect;
    const float max_diff = params.side_angle_deg * kDeg;
    const Eigen::Vector3f u = side.u, v = side.v;
    SacModel model;
    model.sample_size = 2;
    model.needs_normals = true;
    model.fit_sample = [&](const PointCloud& c, std::span<const Index> s, SacCoefficients& coef) {
        const Eigen::Vector3f& n1 = c.normals[s[0]];
        const Eigen::Vector3f& n2 = c.normals[s[1]];
        const float t1 = QuarterAngle(Eigen::Vector2f(n1.dot(u), n1.dot(v)));
        const float t2 = QuarterAngle(Eigen::Vector2f(n2.dot(u), n2.dot(v)));
        constexpr float kQuarter = 0.5f * std::numbers::pi_v<float>;
        float diff = t2 - t1;  // wrapped to [-pi/4, pi/4)
        if (diff >= 0.5f * kQuarter) diff -= kQuarter;
        if (diff < -0.5f * kQuarter) diff += kQuarter;
        if (!(std::abs(diff) <= max_diff)) return false;
        const Rectangle2d r = BoundingRectangle(side.q, t1 + 0.5f * diff, params.trim);
        coef.resize(5);
        coef << r.theta, r.lo[0], r.hi[0], r.lo[1], r.hi[1];
        return coef.allFinite();
    };
    model.distances = [&](const PointCloud& c, const SacCoefficients& coef,
                          std::span<const Index> idx, std::span<float> dist) {
        Rectangle2d r;
        r.theta = coef[0];
        r.lo[0] = coef[1];
        r.hi[0] = coef[2];
        r.lo[1] = coef[3];
        r.hi[1] = coef[4];
        for (std::size_t k = 0; k < idx.size(); ++k) {
            const Eigen::Vector3f& p = c.points[idx[k]];
            dist[k] = r.Distance(Eigen::Vector2f(p.dot(u), p.dot(v)));
        }
    };
    const SacResult r = RunSampleConsensus(cloud, side.idx, model, sac);
    rect.iterations = r.iterations;
    rect.converged = r.converged;
    if (!r.found) return rect;
    const SacCoefficients& c = r.coefficients;
    const float theta = c[0];
    const Eigen::Vector3f a1 = std::cos(theta) * u + std::sin(theta) * v;
    const Eigen::Vector3f a2 = side.up.cross(a1);
    rect.found = true;
    rect.axis = a1;
    rect.extents = Eigen::Vector2f(c[2] - c[1], c[4] - c[3]);
    rect.center = 0.5f * (c[1] + c[2]) * a1 + 0.5f * (c[3] + c[4]) * a2 - plane_d * side.up;
    rect.inliers = r.inliers;
    rect.inlier_weight = r.inlier_weight;
    return rect;
}

// The object seen from above the support plane (section 5.4.2.1 assumes boxes stand on a side):
// footprint coordinates in a fixed basis (u, v) of the plane, u x v = up, heights above it, and
// whether the normals take part (and how close to a face axis they must be).
struct UprightFrame {
    Eigen::Vector3f up, u, v;
    float d = 0.0f;
    std::vector<Eigen::Vector2d> q;
    std::vector<float> heights;
    bool normals = false;
    float face_angle = 0.0f;
    float cos_face = 0.0f;
    /// With normals: each point's unit normal, zero where it has none (not finite or zero).
    std::vector<Eigen::Vector3f> unit;
};

UprightFrame MakeUprightFrame(const PointCloud& cloud, const Indices& finite,
                              const Eigen::Vector4f& plane, const BoxFitParams& params) {
    UprightFrame f;
    f.up = plane.head<3>();
    f.d = plane[3];
    f.u = f.up.unitOrthogonal();
    f.v = f.up.cross(f.u);
    f.q.resize(finite.size());
    f.heights.resize(finite.size());
    for (std::size_t j = 0; j < finite.size(); ++j) {
        const Eigen::Vector3f& p = cloud.points[finite[j]];
        f.q[j] = Eigen::Vector2d(p.dot(f.u), p.dot(f.v));
        f.heights[j] = f.up.dot(p) + f.d;
    }
    f.normals = params.use_normals && cloud.normals.size() == cloud.size();
    f.face_angle = params.face_angle_deg * kDeg;
    f.cos_face = std::cos(f.face_angle);
    if (f.normals) {
        f.unit.resize(finite.size());
        for (std::size_t j = 0; j < finite.size(); ++j) {
            const Eigen::Vector3f& n = cloud.normals[finite[j]];
            f.unit[j] =
                n.allFinite() && n.squaredNorm() > 0.0f ? n.normalized() : Eigen::Vector3f::Zero();
        }
    }
    return f;
}

// First footprint orientation (unit, in the (u, v) basis): the side normals (AlignUprightAxes),
// else the minimum-area footprint rectangle.
Eigen::Vector2d InitialOrientation(const PointCloud& cloud, const Indices& finite,
                                   const Eigen::Vector4f& plane, const UprightFrame& f,
                                   const BoxFitParams& params) {
    Eigen::Vector2d dir;
    bool aligned = false;
    if (f.normals) {
        const FaceAlignment fa =
            AlignUprightAxes(cloud, finite, f.up, f.face_angle, params.min_face_points);
        if (fa.found) {
            dir = Eigen::Vector2d(fa.axes.col(0).dot(f.u), fa.axes.col(0).dot(f.v));
            aligned = true;
        }
    }
    if (!aligned) {
        const OrientedBox hull_box = UprightBoundingBox(cloud, finite, plane);
        dir = Eigen::Vector2d(hull_box.axes.col(0).dot(f.u), hull_box.axes.col(0).dot(f.v));
    }
    dir.normalize();
    return dir;
}

// The footprint rectangle RANSAC (section 5.4.2.1) proposes an orientation; it replaces `dir`
// when its rectangle has more (prior-weighted) side points on its boundary.
void PreferRectangleOrientation(const PointCloud& cloud, const Indices& finite,
                                const UprightFrame& f, const BoxFitParams& params,
                                const FitGuidance& guidance, Eigen::Vector2d& dir) {
    FootprintRectangleParams rp;
    rp.sac.distance_threshold = params.inlier_threshold;
    rp.sac.max_iterations = params.rectangle_iterations;
    rp.sac.seed = params.seed;
    rp.side_angle_deg = params.face_angle_deg;
    const SideFootprint side = SidePointsOf(cloud, finite, f.up, f.face_angle);
    SacParams sac = rp.sac;
    MakeSacWeights(guidance, SampledSurface::kPlanar, cloud.size(), side.idx, sac.sample_weights,
                   sac.score_weights);
    const FootprintRectangle rect = RunRectangleRansac(cloud, side, f.d, rp, sac);
    if (rect.found) {
        // side.u, side.v are u, v: both orientations are angles in the same basis.
        const float old_theta =
            QuarterAngle(Eigen::Vector2f(static_cast<float>(dir.x()), static_cast<float>(dir.y())));
        const double old_support =
            RectangleSupport(side, BoundingRectangle(side.q, old_theta, rp.trim),
                             params.inlier_threshold, sac.score_weights);
        if (rect.inlier_weight > old_support) {
            dir = Eigen::Vector2d(rect.axis.dot(f.u), rect.axis.dot(f.v)).normalized();
        }
    }
}

// Face membership of every point for orientation a1: 0/1 = faces across the first axis
// (low/high side), 2/3 = across the second, -1 = none; the side is taken from the position
// relative to the middle, so the normals' sign does not matter.
void ClassifyFaces(const Indices& finite, const UprightFrame& f, const Eigen::Vector2d& a1,
                   std::vector<int>& face) {
    const Eigen::Vector2d a2(-a1.y(), a1.x());
    double lo[2] = {std::numeric_limits<double>::infinity(),
                    std::numeric_limits<double>::infinity()};
    double hi[2] = {-lo[0], -lo[1]};
    for (const auto& p : f.q) {
        lo[0] = std::min(lo[0], p.dot(a1));
        hi[0] = std::max(hi[0], p.dot(a1));
        lo[1] = std::min(lo[1], p.dot(a2));
        hi[1] = std::max(hi[1], p.dot(a2));
    }
    const Eigen::Vector3f a13 = static_cast<float>(a1.x()) * f.u + static_cast<float>(a1.y()) * f.v;
    const Eigen::Vector3f a23 = f.up.cross(a13);
    for (std::size_t j = 0; j < finite.size(); ++j) {
        face[j] = -1;
        if (!f.normals) continue;
        const Eigen::Vector3f& nn = f.unit[j];
        if (nn.isZero(0.0f)) continue;
        if (std::abs(nn.dot(a13)) >= f.cos_face) {
            face[j] = f.q[j].dot(a1) >= 0.5 * (lo[0] + hi[0]) ? 1 : 0;
        } else if (std::abs(nn.dot(a23)) >= f.cos_face) {
            face[j] = f.q[j].dot(a2) >= 0.5 * (lo[1] + hi[1]) ? 3 : 2;
        }
    }
}

// Refines the orientation with the seen sides: the least-squares rectangle orientation of their
// points. A side across the first axis a1 lies on a line with normal a1 and costs a1^T S a1 (S its
// scatter about its mean); one across a2 = R90 a1 costs a1^T R90^T S R90 a1; the sum is smallest
// for the eigenvector of the smallest eigenvalue of the summed matrices. Up to 3 rounds, each
// reclassifying the faces.
void RefineOrientationBySides(const Indices& finite, const UprightFrame& f,
                              std::size_t min_face_points, Eigen::Vector2d& dir,
                              std::vector<int>& face) {
    const auto& q = f.q;
    for (int round = 0; f.normals && round < 3; ++round) {
        // Every face's mean, then its scatter about it, each summed in point order (as one pass
        // per face would).
        Eigen::Vector2d means[4] = {Eigen::Vector2d::Zero(), Eigen::Vector2d::Zero(),
                                    Eigen::Vector2d::Zero(), Eigen::Vector2d::Zero()};
        std::size_t counts[4] = {0, 0, 0, 0};
        for (std::size_t j = 0; j < q.size(); ++j) {
            if (face[j] < 0) continue;
            means[face[j]] += q[j];
            ++counts[face[j]];
        }
        for (int k = 0; k < 4; ++k) {
            if (counts[k] > 0) means[k] /= static_cast<double>(counts[k]);
        }
        Eigen::Matrix2d scatters[4] = {Eigen::Matrix2d::Zero(), Eigen::Matrix2d::Zero(),
                                       Eigen::Matrix2d::Zero(), Eigen::Matrix2d::Zero()};
        for (std::size_t j = 0; j < q.size(); ++j) {
            const int k = face[j];
            if (k < 0 || counts[k] < min_face_points) continue;
            scatters[k] += (q[j] - means[k]) * (q[j] - means[k]).transpose();
        }
        Eigen::Matrix2d m = Eigen::Matrix2d::Zero();
        bool any = false;
        for (int k = 0; k < 4; ++k) {
            if (counts[k] < min_face_points) continue;
            Eigen::Matrix2d scatter = scatters[k];
            if (k >= 2) {
                Eigen::Matrix2d r90;
                r90 << 0.0, -1.0, 1.0, 0.0;
                scatter = r90.transpose() * scatter * r90;
            }
            m += scatter;
            any = true;
        }
        if (!any) break;
        Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> solver(m);
        Eigen::Vector2d next = solver.eigenvectors().col(0).normalized();
        if (next.dot(dir) < 0.0) next = -next;
        const bool stable = std::abs(next.dot(dir)) > 1.0 - 1e-12;
        dir = next;
        ClassifyFaces(finite, f, dir, face);
        if (stable) break;
    }
}

// The box's intervals along dir and its perpendicular: the median of a seen side's points, else
// the far edge of all points (FarEdge), robust to the noise at an unseen side.
void SideIntervals(const UprightFrame& f, const std::vector<int>& face, const Eigen::Vector2d& dir,
                   const BoxFitParams& params, float lo[2], float hi[2]) {
    const auto& q = f.q;
    const Eigen::Vector2d dir2(-dir.y(), dir.x());
    for (int k = 0; k < 2; ++k) {
        const Eigen::Vector2d axis = k == 0 ? dir : dir2;
        std::vector<float> all(q.size()), face_lo, face_hi;
        for (std::size_t j = 0; j < q.size(); ++j) {
            all[j] = static_cast<float>(q[j].dot(axis));
            if (face[j] == 2 * k) face_lo.push_back(all[j]);
            if (face[j] == 2 * k + 1) face_hi.push_back(all[j]);
        }
        lo[k] = face_lo.size() >= params.min_face_points ? Median(face_lo)
                                                         : FarEdge(all, false, params.edge_window);
        hi[k] = face_hi.size() >= params.min_face_points ? Median(face_hi)
                                                         : FarEdge(all, true, params.edge_window);
    }
}

// The box's top: the median height of the top face's points, else the highest point.
float TopHeight(const Indices& finite, const UprightFrame& f, std::size_t min_face_points) {
    float top = *std::max_element(f.heights.begin(), f.heights.end());
    if (f.normals) {
        std::vector<float> top_heights;
        for (std::size_t j = 0; j < finite.size(); ++j) {
            const Eigen::Vector3f& nn = f.unit[j];
            if (!nn.isZero(0.0f) && std::abs(nn.dot(f.up)) >= f.cos_face) {
                top_heights.push_back(f.heights[j]);
            }
        }
        if (top_heights.size() >= min_face_points) top = Median(top_heights);
    }
    return top;
}

// The box standing on the plane from its footprint intervals and top, longer side first.
void SetUprightBox(const UprightFrame& f, const Eigen::Vector2d& dir, const float lo[2],
                   const float hi[2], float top, BoxModel& box) {
    const Eigen::Vector3f& up = f.up;
    const Eigen::Vector3f a1 =
        static_cast<float>(dir.x()) * f.u + static_cast<float>(dir.y()) * f.v;
    const Eigen::Vector3f a2 = up.cross(a1);
    Eigen::Vector3f ext(std::max(hi[0] - lo[0], 0.0f), std::max(hi[1] - lo[1], 0.0f),
                        std::max(top, 0.0f));
    box.center =
        0.5f * (lo[0] + hi[0]) * a1 + 0.5f * (lo[1] + hi[1]) * a2 + (-f.d + 0.5f * ext.z()) * up;
    if (ext.y() > ext.x()) {
        // Longer side first; col(1) = up x col(0) keeps the frame right-handed.
        box.axes.col(0) = a2;
        box.axes.col(1) = up.cross(a2);
        std::swap(ext.x(), ext.y());
    } else {
        box.axes.col(0) = a1;
        box.axes.col(1) = up.cross(a1);
    }
    box.axes.col(2) = up;
    box.extents = ext;
}

// The points with a finite, non-zero normal: the cylinder fit samples normals.
Indices WithNormals(const PointCloud& cloud, const Indices& finite) {
    Indices usable;
    usable.reserve(finite.size());
    for (Index i : finite) {
        const Eigen::Vector3f& n = cloud.normals[i];
        if (n.allFinite() && n.squaredNorm() > 0.0f) usable.push_back(i);
    }
    return usable;
}

// The cylinder hypothesis (section 5.4.2.1): a RANSAC fit, upright when the support is known
// (upright axes are the more robust), replaced by a free-axis fit only when that one explains
// clearly more points (free_axis_gain), inliers weighted like the scoring.
CylinderFit HypothesiseCylinder(const PointCloud& cloud, const Indices& usable,
                                const std::optional<Eigen::Vector4f>& plane,
                                const CylinderModelParams& params, const FitGuidance& guidance) {
    CylinderFitParams cp{
        .sac = params.sac, .min_radius = params.min_radius, .max_radius = params.max_radius};
    if (!guidance.rsd_min_radius.empty() || !guidance.shape_prior.empty()) {
        MakeSacWeights(guidance, SampledSurface::kCurved, cloud.size(), usable,
                       cp.sac.sample_weights, cp.sac.score_weights);
    }
    // Inliers of a fit, weighted like its scoring.
    auto support = [&](const CylinderFit& f) {
        if (cp.sac.score_weights.empty()) return static_cast<double>(f.inliers.size());
        double w = 0.0;
        for (Index i : f.inliers) w += double{cp.sac.score_weights[i]};
        return w;
    };
    CylinderFit fit;
    if (plane) {
        cp.axis = plane->head<3>();
        cp.max_angle = params.upright_angle_deg * kDeg;
        fit = FitCylinder(cloud, usable, cp);
        if (params.allow_free_axis) {
            cp.axis = std::nullopt;
            CylinderFit free = FitCylinder(cloud, usable, cp);
            if (free.found &&
                (!fit.found || support(free) >= double{params.free_axis_gain} * support(fit))) {
                fit = std::move(free);
            }
        }
    } else {
        fit = FitCylinder(cloud, usable, cp);
    }
    return fit;
}

// Whether the hypothesis' axis is upright (then turned to point up), and with snap_to_support
// the axis snapped: fixed to up when upright, into the plane (free to turn about up) when lying.
bool SnapToSupport(const std::optional<Eigen::Vector4f>& plane, const CylinderModelParams& params,
                   CylinderEstimate& x, CylinderRefineParams& refine) {
    bool upright = false;
    if (plane) {
        const Eigen::Vector3d up = plane->head<3>().cast<double>();
        const double c = x.axis.dot(up);
        upright = std::abs(c) >= std::cos(double{params.upright_angle_deg * kDeg}) - 1e-9;
        if (upright && c < 0.0) x.axis = -x.axis;
        const bool lying = std::abs(c) <= std::sin(double{params.lying_angle_deg * kDeg});
        if (params.snap_to_support && upright) {
            x.axis = up;
            refine = {.freedom = CylinderAxisFreedom::kFixed};
        } else if (params.snap_to_support && lying) {
            x.axis = (x.axis - x.axis.dot(up) * up).normalized();
            refine = {.freedom = CylinderAxisFreedom::kAboutUp, .up = up};
        }
    }
    return upright;
}

// Refinement on the side points (near the surface, normal radial) until they no longer change,
// the radius staying in range; returns the final side points (the fit's inliers if none).
Indices RefineOnSidePoints(const PointCloud& cloud, const Indices& usable, const CylinderFit& fit,
                           const CylinderModelParams& params, const CylinderRefineParams& refine,
                           CylinderEstimate& x) {
    const double side_cos = std::cos(double{params.side_normal_angle_deg * kDeg});
    Indices side = detail::SidePoints(cloud, usable, x, params.side_distance, side_cos);
    for (int round = 0; round < params.refine_rounds && side.size() >= 5; ++round) {
        CylinderEstimate refined = x;
        detail::CentreOnPoints(cloud, side, refined);
        if (!RefineCylinder(cloud, side, refine, refined)) break;
        if (!(refined.radius >= params.min_radius && refined.radius <= params.max_radius)) break;
        x = refined;
        Indices next = detail::SidePoints(cloud, usable, x, params.side_distance, side_cos);
        const bool stable = next == side;
        side = std::move(next);
        if (stable) break;
    }
    if (side.empty()) side = fit.inliers;
    return side;
}

// Extent along the axis (axis through p0), [lo, hi] ascending: the side points' span, each end
// moved to the median level of a visible cap there (normals along the axis, inside the rim,
// near that end), and with extend_to_support an upright cylinder reaching down to the plane.
std::pair<float, float> AxialExtent(const PointCloud& cloud, const Indices& usable,
                                    const Indices& side, const Eigen::Vector3f& p0,
                                    const Eigen::Vector3f& axis, float radius,
                                    const std::optional<Eigen::Vector4f>& plane, bool upright,
                                    const CylinderModelParams& params) {
    float lo = std::numeric_limits<float>::infinity(), hi = -lo;
    for (Index i : side) {
        const float t = (cloud.points[i] - p0).dot(axis);
        lo = std::min(lo, t);
        hi = std::max(hi, t);
    }
    // Visible caps: normals along the axis, inside the rim, near an end of the side's extent.
    const float cos_cap = std::cos(params.cap_angle_deg * kDeg);
    const float reach = 2.0f * params.side_distance;
    std::vector<float> cap_lo, cap_hi;
    for (Index i : usable) {
        const Eigen::Vector3f w = cloud.points[i] - p0;
        const float t = w.dot(axis);
        if ((w - t * axis).norm() > radius + params.side_distance) continue;
        if (std::abs(cloud.normals[i].normalized().dot(axis)) < cos_cap) continue;
        if (std::abs(t - hi) <= reach) cap_hi.push_back(t);
        if (std::abs(t - lo) <= reach) cap_lo.push_back(t);
    }
    if (cap_hi.size() >= params.min_cap_points) hi = Median(cap_hi);
    if (cap_lo.size() >= params.min_cap_points) lo = Median(cap_lo);
    if (plane && upright && params.extend_to_support) {
        // Where the axis line meets the support plane.
        const Eigen::Vector3f upf = plane->head<3>();
        lo = -(upf.dot(p0) + (*plane)[3]) / upf.dot(axis);
    }
    if (hi < lo) std::swap(lo, hi);
    return {lo, hi};
}

// The share of the finite points within the threshold of the closed cylinder's surface.
float CylinderInlierRatio(const PointCloud& cloud, const Indices& finite,
                          const CylinderModel& model, float threshold) {
    std::size_t inliers = 0;
    for (Index i : finite) {
        if (CylinderSurfaceDistance(model, cloud.points[i]) <= threshold) ++inliers;
    }
    return static_cast<float>(inliers) / static_cast<float>(finite.size());
}
}  // namespace

void BoxFitParams::Validate() const { ValidateBoxParams(*this); }
void CylinderModelParams::Validate() const { ValidateCylinderParams(*this); }

float BoxSurfaceDistance(const BoxModel& box, const Eigen::Vector3f& p) {
    const Eigen::Vector3f q = (box.axes.transpose() * (p - box.center)).cwiseAbs();
    const Eigen::Vector3f half = 0.5f * box.extents;
    const Eigen::Vector3f outside = (q - half).cwiseMax(0.0f);
    if (outside.squaredNorm() > 0.0f) return outside.norm();
    return (half - q).minCoeff();
}

float CylinderSurfaceDistance(const CylinderModel& c, const Eigen::Vector3f& p) {
    const Eigen::Vector3f w = p - c.center;
    const float t = std::abs(w.dot(c.axis));
    const float rho = (w - w.dot(c.axis) * c.axis).norm();
    const float half = 0.5f * c.height;
    if (t <= half && rho <= c.radius) return std::min(c.radius - rho, half - t);
    return std::hypot(std::max(rho - c.radius, 0.0f), std::max(t - half, 0.0f));
}

FootprintRectangle FitFootprintRectangle(const PointCloud& cloud, const Indices& indices,
                                         const Eigen::Vector4f& support_plane,
                                         const FootprintRectangleParams& params,
                                         const FitGuidance& guidance) {
    ValidateRectangleParams(params);
    ValidateFitGuidance(guidance, cloud.size());
    const std::optional<Eigen::Vector4f> plane = NormalizeSupportPlane(support_plane);
    Require(plane.has_value(), "FitFootprintRectangle needs a support plane, got the zero vector");
    CheckIndices(cloud, indices);
    if (indices.empty()) return {};
    if (cloud.normals.size() != cloud.size()) {
        throw DataError(
            fmt::format("footprint rectangle fitting needs one normal per point, got "
                        "{} for {}",
                        cloud.normals.size(), cloud.size()));
    }
    const SideFootprint side = SidePointsOf(cloud, FinitePoints(cloud, indices), plane->head<3>(),
                                            params.side_angle_deg * kDeg);
    SacParams sac = params.sac;
    MakeSacWeights(guidance, SampledSurface::kPlanar, cloud.size(), side.idx, sac.sample_weights,
                   sac.score_weights);
    return RunRectangleRansac(cloud, side, (*plane)[3], params, sac);
}

BoxModel FitUprightBox(const PointCloud& cloud, const Indices& indices,
                       const Eigen::Vector4f& support_plane, const BoxFitParams& params,
                       const FitGuidance& guidance) {
    ValidateBoxParams(params);
    ValidateFitGuidance(guidance, cloud.size());
    const std::optional<Eigen::Vector4f> plane = NormalizeSupportPlane(support_plane);
    Require(plane.has_value(), "FitUprightBox needs a support plane, got the zero vector");
    CheckIndices(cloud, indices);
    const Indices finite = FinitePoints(cloud, indices);
    BoxModel box;
    if (finite.empty()) return box;

    // Orientation of the footprint, then the faces seen along it, then the extents.
    const UprightFrame f = MakeUprightFrame(cloud, finite, *plane, params);
    Eigen::Vector2d dir = InitialOrientation(cloud, finite, *plane, f, params);
    if (f.normals && params.rectangle_ransac) {
        PreferRectangleOrientation(cloud, finite, f, params, guidance, dir);
    }
    std::vector<int> face(finite.size(), -1);
    ClassifyFaces(finite, f, dir, face);
    RefineOrientationBySides(finite, f, params.min_face_points, dir, face);
    float lo[2] = {0.0f, 0.0f}, hi[2] = {0.0f, 0.0f};
    SideIntervals(f, face, dir, params, lo, hi);
    const float top = TopHeight(finite, f, params.min_face_points);
    SetUprightBox(f, dir, lo, hi, top, box);
    box.found = true;
    box.inlier_ratio = BoxInlierRatio(cloud, finite, box, params.inlier_threshold);
    return box;
}

BoxModel FitOrientedBoundingBox(const PointCloud& cloud, const Indices& indices,
                                const BoxFitParams& params) {
    ValidateBoxParams(params);
    CheckIndices(cloud, indices);
    const Indices finite = FinitePoints(cloud, indices);
    BoxModel box;
    if (finite.empty()) return box;
    const OrientedBox obb = MinVolumeBoundingBox(cloud, finite);
    box.center = obb.center;
    box.axes = obb.axes;
    box.extents = obb.extents;
    box.found = true;
    box.inlier_ratio = BoxInlierRatio(cloud, finite, box, params.inlier_threshold);
    return box;
}

CylinderModel FitObjectCylinder(const PointCloud& cloud, const Indices& indices,
                                const Eigen::Vector4f& support_plane,
                                const CylinderModelParams& params, const FitGuidance& guidance,
                                const std::optional<CylinderStart>& start) {
    ValidateCylinderParams(params);
    ValidateFitGuidance(guidance, cloud.size());
    const std::optional<Eigen::Vector4f> plane = NormalizeSupportPlane(support_plane);
    CheckIndices(cloud, indices);
    CylinderModel model;
    if (indices.empty()) return model;
    if (cloud.normals.size() != cloud.size()) {
        throw DataError(fmt::format("cylinder fitting needs one normal per point, got {} for {}",
                                    cloud.normals.size(), cloud.size()));
    }
    const Indices finite = FinitePoints(cloud, indices);
    const Indices usable = WithNormals(cloud, finite);
    if (usable.size() < 2) return model;

    // 1. Hypothesis: the start given, else RANSAC on an even subset of the points.
    // 2. Refinement on the side points, with the axis snapped to the support when asked.
    CylinderEstimate x;
    bool upright = false;
    Indices side;
    const auto refine_from = [&](const Eigen::Vector3f& point, const Eigen::Vector3f& axis,
                                 float radius, const CylinderFit& fit) {
        x = {point.cast<double>(), axis.cast<double>().normalized(), double{radius}};
        CylinderRefineParams refine{.freedom = CylinderAxisFreedom::kFree};
        upright = SnapToSupport(plane, params, x, refine);
        side = RefineOnSidePoints(cloud, usable, fit, params, refine, x);
    };
    if (start && start->radius >= params.min_radius && start->radius <= params.max_radius &&
        start->point.allFinite() && start->axis.allFinite() && start->axis.norm() > 0.5f) {
        refine_from(start->point, start->axis, start->radius, CylinderFit{});
        if (side.size() < 5) side.clear();  // too few side points to trust the start
    }
    if (side.empty()) {
        const Indices hypothesis_points =
            params.hypothesis_points > 0 ? EvenSubset(usable, params.hypothesis_points) : usable;
        const CylinderFit fit =
            HypothesiseCylinder(cloud, hypothesis_points, plane, params, guidance);
        if (!fit.found || fit.inliers.empty()) return model;
        refine_from(fit.point, fit.axis, fit.radius, fit);
    }

    // 3. Extent along the axis.
    const Eigen::Vector3f axis = x.axis.cast<float>();
    const Eigen::Vector3f p0 = x.point.cast<float>();
    const auto radius = static_cast<float>(x.radius);
    const auto [lo, hi] =
        AxialExtent(cloud, usable, side, p0, axis, radius, plane, upright, params);

    model.found = true;
    model.axis = axis;
    if (!upright) model.axis = CanonicalAxis(axis);
    model.radius = radius;
    model.height = hi - lo;
    model.center = p0 + 0.5f * (lo + hi) * axis;
    model.inlier_ratio = CylinderInlierRatio(cloud, finite, model, params.inlier_threshold);
    return model;
}

}  // namespace multicue

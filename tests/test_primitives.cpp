// Geometric categories (recognition) and primitive models (reconstruction) on single-view scans of
// table-top scenes: the analytic simulator for boxes and upright cylinders, and a small ray caster
// below for spheres and lying cylinders.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <map>
#include <numbers>
#include <random>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Eigenvalues>

#include "multicue/core/exceptions.hpp"
#include "multicue/recognition/bounding_box.hpp"
#include "multicue/recognition/geometric_category.hpp"
#include "multicue/reconstruction/primitive_models.hpp"
#include "multicue/search/kdtree.hpp"
#include "multicue/segmentation/region_growing.hpp"
#include "multicue/sim/tabletop_scene.hpp"

namespace multicue {
namespace {

constexpr float kPi = std::numbers::pi_v<float>;
constexpr float kDeg = kPi / 180.0f;

// ---------------------------------------------------------------------------------------------
// Scans

struct Scan {
    PointCloud cloud;  // camera frame, with normals
    Eigen::Isometry3f T_world_camera = Eigen::Isometry3f::Identity();
    Eigen::Vector4f plane = Eigen::Vector4f::Zero();  // table plane in the camera frame, up normal
};

// The plane z = h of the world, expressed in the camera frame: n_c = R^T n_w, d_c = n_w.t + d_w.
Eigen::Vector4f TablePlaneInCamera(float table_height, const Eigen::Isometry3f& T_world_camera) {
    const Eigen::Vector3f n_w = Eigen::Vector3f::UnitZ();
    Eigen::Vector4f plane;
    plane.head<3>() = T_world_camera.linear().transpose() * n_w;
    plane[3] = n_w.dot(T_world_camera.translation()) - table_height;
    return plane;
}

// Normals and curvature of the object pixels (label >= 20) of an organized cloud by PCA over 7x7
// pixel windows, leaving out neighbours whose depth differs from the centre's by more than
// 0.02 z^2 (the other side of a depth edge), oriented towards the camera at the origin. The
// tests use object normals only; the table's stay NaN.
void AddNormals(PointCloud& cloud) {
    const float nan = std::numeric_limits<float>::quiet_NaN();
    cloud.normals.assign(cloud.size(), Eigen::Vector3f::Constant(nan));
    cloud.curvature.assign(cloud.size(), nan);
    const int w = static_cast<int>(cloud.width), h = static_cast<int>(cloud.height);
    for (int v = 0; v < h; ++v) {
        for (int u = 0; u < w; ++u) {
            const std::size_t i = static_cast<std::size_t>(v) * cloud.width + u;
            const Eigen::Vector3f& p = cloud.points[i];
            if (!p.allFinite() || cloud.labels[i] < sim::ObjectLabel(1)) continue;
            const float max_dz = 0.02f * p.z() * p.z();
            Eigen::Vector3d sum = Eigen::Vector3d::Zero();
            Eigen::Matrix3d sq = Eigen::Matrix3d::Zero();
            int count = 0;
            for (int dv = -3; dv <= 3; ++dv) {
                for (int du = -3; du <= 3; ++du) {
                    const int uu = u + du, vv = v + dv;
                    if (uu < 0 || vv < 0 || uu >= w || vv >= h) continue;
                    const Eigen::Vector3f& q =
                        cloud.points[static_cast<std::size_t>(vv) * cloud.width + uu];
                    if (!q.allFinite() || std::abs(q.z() - p.z()) > max_dz) continue;
                    const Eigen::Vector3d d = (q - p).cast<double>();
                    sum += d;
                    sq += d * d.transpose();
                    ++count;
                }
            }
            if (count < 3) continue;
            const Eigen::Vector3d mean = sum / count;
            const Eigen::Matrix3d cov = sq / count - mean * mean.transpose();
            Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver;
            solver.computeDirect(cov);
            const Eigen::Vector3d l = solver.eigenvalues().cwiseMax(0.0);
            if (!(l.sum() > 0.0)) continue;
            Eigen::Vector3f n = solver.eigenvectors().col(0).cast<float>().normalized();
            if (n.dot(-p) < 0.0f) n = -n;
            cloud.normals[i] = n;
            cloud.curvature[i] = static_cast<float>(l(0) / l.sum());
        }
    }
}

Scan ScanScene(const sim::TableTopScene& scene, std::uint32_t seed = 1) {
    Scan s;
    sim::ScanParams params;
    params.T_world_camera = sim::DefaultCameraPose(scene);
    params.seed = seed;
    s.cloud = sim::ScanTableTopScene(scene, params);
    AddNormals(s.cloud);
    s.T_world_camera = params.T_world_camera;
    s.plane = TablePlaneInCamera(scene.table_height, params.T_world_camera);
    return s;
}

Indices WithLabel(const PointCloud& cloud, std::uint32_t label) {
    Indices out;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        if (cloud.labels[i] == label) out.push_back(static_cast<Index>(i));
    }
    return out;
}

/// A scan of `scene` and the points of its first object (at least 300 of them).
struct FirstObject {
    Scan scan;
    Indices points;
};
FirstObject ScanFirstObject(const sim::TableTopScene& scene) {
    FirstObject f{ScanScene(scene), {}};
    f.points = WithLabel(f.scan.cloud, sim::ObjectLabel(1));
    EXPECT_GT(f.points.size(), 300u);
    return f;
}

// A shape for the ray caster: ray origin o and direction d (world frame) -> the nearest hit
// parameter t > 0 with its outward normal, or false.
using Shape = std::function<bool(const Eigen::Vector3f& o, const Eigen::Vector3f& d, float& t,
                                 Eigen::Vector3f& normal)>;

Shape Sphere(const Eigen::Vector3f& c, float r) {
    return [=](const Eigen::Vector3f& o, const Eigen::Vector3f& d, float& t, Eigen::Vector3f& n) {
        const Eigen::Vector3f w = o - c;
        const float a = d.squaredNorm(), b = 2.0f * w.dot(d), cc = w.squaredNorm() - r * r;
        const float disc = b * b - 4.0f * a * cc;
        if (disc < 0.0f) return false;
        t = (-b - std::sqrt(disc)) / (2.0f * a);
        n = (o + t * d - c).normalized();
        return t > 0.0f;
    };
}

// Closed cylinder with centre c, unit axis a, radius r and length len.
Shape Cylinder(const Eigen::Vector3f& c, const Eigen::Vector3f& a, float r, float len) {
    return [=](const Eigen::Vector3f& o, const Eigen::Vector3f& d, float& t, Eigen::Vector3f& n) {
        const Eigen::Vector3f w = o - c;
        const Eigen::Vector3f wp = w - w.dot(a) * a, dp = d - d.dot(a) * a;
        float best = std::numeric_limits<float>::infinity();
        const float qa = dp.squaredNorm(), qb = 2.0f * wp.dot(dp), qc = wp.squaredNorm() - r * r;
        const float disc = qb * qb - 4.0f * qa * qc;
        if (qa > 1e-12f && disc >= 0.0f) {
            const float ts = (-qb - std::sqrt(disc)) / (2.0f * qa);
            if (ts > 0.0f && std::abs((w + ts * d).dot(a)) <= len / 2) {
                best = ts;
                n = (wp + ts * dp).normalized();
            }
        }
        if (std::abs(d.dot(a)) > 1e-9f) {
            for (float side : {-1.0f, 1.0f}) {
                const float tc = (side * len / 2 - w.dot(a)) / d.dot(a);
                const Eigen::Vector3f q = w + tc * d;
                if (tc > 0.0f && tc < best && (q - q.dot(a) * a).norm() <= r) {
                    best = tc;
                    n = side * a;
                }
            }
        }
        t = best;
        return std::isfinite(best);
    };
}

// Scans the default table (z = 0.75 m, 1.2 m x 0.8 m) with shapes on it, labelled 20, 30, ...,
// with the simulator's camera and Kinect-like depth noise.
Scan ScanShapes(const std::vector<Shape>& shapes, std::uint32_t seed = 1) {
    const sim::TableTopScene table;
    const sim::PinholeCamera cam;
    Scan s;
    s.T_world_camera = sim::DefaultCameraPose(table);
    s.plane = TablePlaneInCamera(table.table_height, s.T_world_camera);
    const Eigen::Matrix3f R = s.T_world_camera.linear();
    const Eigen::Vector3f eye = s.T_world_camera.translation();
    const float nan = std::numeric_limits<float>::quiet_NaN();
    PointCloud& cloud = s.cloud;
    cloud.points.assign(std::size_t{cam.width} * cam.height, Eigen::Vector3f::Constant(nan));
    cloud.labels.assign(cloud.points.size(), 0);
    cloud.width = cam.width;
    cloud.height = cam.height;
    std::mt19937 rng(seed);
    std::normal_distribution<float> gauss(0.0f, 1.0f);
    for (std::uint32_t v = 0; v < cam.height; ++v) {
        for (std::uint32_t u = 0; u < cam.width; ++u) {
            const float noise = gauss(rng);
            const Eigen::Vector3f ray((u - cam.cx) / cam.fx, (v - cam.cy) / cam.fy, 1.0f);
            const Eigen::Vector3f d = R * ray;
            float best = std::numeric_limits<float>::infinity();
            Eigen::Vector3f best_n = Eigen::Vector3f::UnitZ();
            std::uint32_t label = 0;
            if (d.z() < 0.0f) {
                const float tt = (table.table_height - eye.z()) / d.z();
                const Eigen::Vector3f p = eye + tt * d;
                if (p.x() >= table.table_min.x() && p.x() <= table.table_max.x() &&
                    p.y() >= table.table_min.y() && p.y() <= table.table_max.y()) {
                    best = tt;
                    label = sim::kTableLabel;
                }
            }
            for (std::size_t k = 0; k < shapes.size(); ++k) {
                float t = 0.0f;
                Eigen::Vector3f n;
                if (shapes[k](eye, d, t, n) && t < best) {
                    best = t;
                    best_n = n;
                    label = sim::ObjectLabel(static_cast<std::uint32_t>(k + 1));
                }
            }
            if (!std::isfinite(best)) continue;
            if (std::abs(best_n.dot(d.normalized())) < std::cos(80.0f * kDeg)) continue;
            const float z = best + 1.4e-3f * best * best * noise;
            const std::size_t i = std::size_t{v} * cam.width + u;
            cloud.points[i] = ray * z;
            cloud.labels[i] = label;
        }
    }
    AddNormals(cloud);
    return s;
}

// ---------------------------------------------------------------------------------------------
// Helpers for the checks

// The data README's box/flat rule on extents (any order).
Category ExpectedBoxCategory(Eigen::Vector3f e) {
    std::sort(e.data(), e.data() + 3, std::greater<float>());
    const float r = e[1] / e[2], s = e[0] / e[2];
    if (r >= 2.5f) return Category::kFlat;
    if (r < 2.0f) return Category::kBox;
    return s > 2.8f ? Category::kFlat : Category::kBox;
}

float AngleDeg(const Eigen::Vector3f& a, const Eigen::Vector3f& b) {
    return std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.0f, 1.0f)) / kDeg;
}

// |a - b| modulo `period` [deg].
float AngleModDeg(float a_deg, float b_deg, float period) {
    float d = std::fmod(std::abs(a_deg - b_deg), period);
    return std::min(d, period - d);
}

// Fitted box vs the scene's box: extent errors (length, width, height) and yaw error [deg].
struct BoxErrors {
    Eigen::Vector3f extents;
    float yaw_deg = 0.0f;
    float center = 0.0f;
};

BoxErrors CompareBox(const BoxModel& fit, const sim::SceneBox& truth, const Scan& scan,
                     float table_height) {
    BoxErrors e;
    const float w = truth.extents.x(), d = truth.extents.y();
    const Eigen::Vector3f expected(std::max(w, d), std::min(w, d), truth.extents.z());
    e.extents = (fit.extents - expected).cwiseAbs();
    const Eigen::Vector3f x_w = scan.T_world_camera.linear() * fit.axes.col(0);
    const float fitted_yaw = std::atan2(x_w.y(), x_w.x()) / kDeg;
    const float true_yaw = truth.yaw / kDeg + (w >= d ? 0.0f : 90.0f);
    e.yaw_deg = AngleModDeg(fitted_yaw, true_yaw, std::abs(w - d) < 1e-6f ? 90.0f : 180.0f);
    const Eigen::Vector3f c_w = scan.T_world_camera * fit.center;
    const Eigen::Vector3f c_true(truth.center_xy.x(), truth.center_xy.y(),
                                 table_height + truth.extents.z() / 2);
    e.center = (c_w - c_true).norm();
    return e;
}

// Signed volume of a closed mesh: sum of the tetrahedra to the origin.
double SignedVolume(const TriangleMesh& m) {
    double v = 0.0;
    for (const Triangle& t : m.triangles) {
        const Eigen::Vector3d a = m.vertices[t[0]].cast<double>();
        const Eigen::Vector3d b = m.vertices[t[1]].cast<double>();
        const Eigen::Vector3d c = m.vertices[t[2]].cast<double>();
        v += a.dot(b.cross(c)) / 6.0;
    }
    return v;
}

// Closed and consistently oriented: every directed edge occurs once and its reverse once.
bool ClosedAndConsistent(const TriangleMesh& m) {
    std::map<std::pair<std::uint32_t, std::uint32_t>, int> directed;
    for (const Triangle& t : m.triangles) {
        for (int k = 0; k < 3; ++k) ++directed[{t[k], t[(k + 1) % 3]}];
    }
    for (const auto& [edge, count] : directed) {
        if (count != 1) return false;
        const auto it = directed.find({edge.second, edge.first});
        if (it == directed.end() || it->second != 1) return false;
    }
    return true;
}

// Every triangle's normal points away from `inside` (convex meshes).
bool Outward(const TriangleMesh& m, const Eigen::Vector3f& inside) {
    const auto normals = m.ComputeTriangleNormals();
    for (std::size_t k = 0; k < m.triangles.size(); ++k) {
        const Triangle& t = m.triangles[k];
        const Eigen::Vector3f c = (m.vertices[t[0]] + m.vertices[t[1]] + m.vertices[t[2]]) / 3.0f;
        if (!(normals[k].dot(c - inside) > 0.0f)) return false;
    }
    return true;
}

// ---------------------------------------------------------------------------------------------
// Categories: names

TEST(Category, NamesFollowTheOutputContract) {
    const std::vector<std::string_view> contract = {"none",     "sphere", "box",  "flat",
                                                    "cylinder", "plate",  "other"};
    ASSERT_EQ(kCategoryNames.size(), contract.size());
    for (std::size_t i = 0; i < contract.size(); ++i) {
        EXPECT_EQ(kCategoryNames[i], contract[i]);
        const auto c = static_cast<Category>(i);
        EXPECT_EQ(CategoryName(c), contract[i]);
        EXPECT_EQ(ParseCategory(contract[i]), c);
    }
    EXPECT_THROW(ParseCategory("cube"), InvalidArgument);
    EXPECT_THROW(ParseCategory("Box"), InvalidArgument);
    EXPECT_THROW(CategoryName(static_cast<Category>(7)), InvalidArgument);
}

// ---------------------------------------------------------------------------------------------
// Bounding geometry

TEST(BoundingBox, MinAreaRectangleMatchesBruteForce) {
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> uni(-1.0f, 1.0f);
    for (int trial = 0; trial < 20; ++trial) {
        std::vector<Eigen::Vector2f> pts(60);
        const float angle = uni(rng) * kPi;
        const Eigen::Rotation2Df rot(angle);
        for (auto& p : pts) p = rot * Eigen::Vector2f(0.3f * uni(rng), 0.1f * uni(rng) * uni(rng));
        const auto hull = ConvexHull2d(pts);
        const Rectangle2d rect = MinAreaRectangle(hull);
        // Oracle: all directions in 0.005 degree steps.
        float brute = std::numeric_limits<float>::infinity();
        for (int s = 0; s < 18000; ++s) {
            const float a = static_cast<float>(s) * 0.005f * kDeg;
            const Eigen::Vector2f d(std::cos(a), std::sin(a)), n(-d.y(), d.x());
            float lo = 1e9f, hi = -1e9f, lo2 = 1e9f, hi2 = -1e9f;
            for (const auto& p : pts) {
                lo = std::min(lo, p.dot(d));
                hi = std::max(hi, p.dot(d));
                lo2 = std::min(lo2, p.dot(n));
                hi2 = std::max(hi2, p.dot(n));
            }
            brute = std::min(brute, (hi - lo) * (hi2 - lo2));
        }
        EXPECT_LE(rect.Area(), brute * (1.0f + 1e-4f)) << "trial " << trial;
        EXPECT_GE(rect.Area(), brute * (1.0f - 1e-3f)) << "trial " << trial;
        EXPECT_GE(rect.size.x(), rect.size.y());
        // Every point lies inside the rectangle.
        const Eigen::Vector2f n(-rect.axis.y(), rect.axis.x());
        for (const auto& p : pts) {
            EXPECT_LE(std::abs((p - rect.center).dot(rect.axis)), rect.size.x() / 2 + 1e-5f);
            EXPECT_LE(std::abs((p - rect.center).dot(n)), rect.size.y() / 2 + 1e-5f);
        }
        // Hull: counter-clockwise, contains every point.
        EXPECT_GT(PolygonArea(hull), 0.0f);
    }
}

TEST(BoundingBox, HullDropsInteriorAndCollinearPoints) {
    std::vector<Eigen::Vector2f> pts = {{0, 0}, {1, 0},    {2, 0},       {2, 1}, {1, 1},
                                        {0, 1}, {1, 0.5f}, {0.5f, 0.5f}, {0, 0}};
    const auto hull = ConvexHull2d(pts);
    EXPECT_EQ(hull.size(), 4u);
    EXPECT_NEAR(PolygonArea(hull), 2.0f, 1e-6f);
    const Rectangle2d r = MinAreaRectangle(hull);
    EXPECT_NEAR(r.size.x(), 2.0f, 1e-6f);
    EXPECT_NEAR(r.size.y(), 1.0f, 1e-6f);
    EXPECT_NEAR(r.center.x(), 1.0f, 1e-6f);
    EXPECT_NEAR(r.center.y(), 0.5f, 1e-6f);
    EXPECT_TRUE(ConvexHull2d({}).empty());
    EXPECT_EQ(MinAreaRectangle({}).Area(), 0.0f);
}

// Gift wrapping as the oracle: counter-clockwise from the lowest of the leftmost points, the
// farthest of collinear candidates, so collinear points are never vertices.
std::vector<Eigen::Vector2f> GiftWrap(const std::vector<Eigen::Vector2f>& pts) {
    auto cross = [](const Eigen::Vector2f& o, const Eigen::Vector2f& a, const Eigen::Vector2f& b) {
        const Eigen::Vector2d u = (a - o).cast<double>(), v = (b - o).cast<double>();
        return u.x() * v.y() - u.y() * v.x();
    };
    std::size_t start = 0;
    for (std::size_t i = 1; i < pts.size(); ++i) {
        const auto& p = pts[i];
        const auto& s = pts[start];
        if (p.x() < s.x() || (p.x() == s.x() && p.y() < s.y())) start = i;
    }
    std::vector<Eigen::Vector2f> hull;
    std::size_t current = start;
    do {
        hull.push_back(pts[current]);
        std::size_t next = current == 0 ? 1 : 0;
        for (std::size_t i = 0; i < pts.size(); ++i) {
            if (pts[i] == pts[current]) continue;
            const double c = cross(pts[current], pts[next], pts[i]);
            if (c < 0.0 || (c == 0.0 && (pts[i] - pts[current]).squaredNorm() >
                                            (pts[next] - pts[current]).squaredNorm())) {
                next = i;
            }
        }
        current = next;
    } while (pts[current] != pts[start] && hull.size() <= pts.size());
    return hull;
}

// The hull drops interior points before sorting: the result is still exactly the hull, on
// integer grids with many collinear boundary points and duplicates, on noisy discs and on thin
// slivers (sets large enough for the early drop to run).
TEST(BoundingBox, HullEqualsGiftWrapping) {
    std::mt19937 rng(5);
    std::uniform_int_distribution<int> grid(0, 12);
    std::uniform_real_distribution<float> uni(-1.0f, 1.0f);
    for (int trial = 0; trial < 30; ++trial) {
        std::vector<Eigen::Vector2f> pts;
        const int kind = trial % 3;
        for (int i = 0; i < 400; ++i) {
            if (kind == 0) {
                pts.emplace_back(static_cast<float>(grid(rng)), static_cast<float>(grid(rng)));
            } else if (kind == 1) {
                const float a = uni(rng) * kPi, r = std::sqrt(std::abs(uni(rng)));
                pts.emplace_back(0.3f + 0.1f * r * std::cos(a), -0.2f + 0.1f * r * std::sin(a));
            } else {
                const float t = uni(rng);
                pts.emplace_back(t, 0.01f * t + 1e-4f * uni(rng));
            }
        }
        const auto hull = ConvexHull2d(pts);
        const auto oracle = GiftWrap(pts);
        ASSERT_EQ(hull.size(), oracle.size()) << "trial " << trial;
        for (std::size_t i = 0; i < hull.size(); ++i) {
            EXPECT_EQ(hull[i], oracle[i]) << "trial " << trial << " vertex " << i;
        }
    }
}

TEST(BoundingBox, OrientedBoundingBoxOfBoxSurface) {
    // Points on all six faces of a rotated box: the oriented box is the box itself.
    const Eigen::Matrix3f R =
        (Eigen::AngleAxisf(0.4f, Eigen::Vector3f(1, 2, 3).normalized())).toRotationMatrix();
    const Eigen::Vector3f ext(0.3f, 0.2f, 0.05f), c(0.5f, -0.2f, 1.0f);
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> uni(-0.5f, 0.5f);
    PointCloud cloud;
    for (int k = 0; k < 3; ++k) {
        for (float side : {-0.5f, 0.5f}) {
            for (int j = 0; j < 400; ++j) {
                Eigen::Vector3f q(uni(rng), uni(rng), uni(rng));
                q[k] = side;
                cloud.points.push_back(c + R * q.cwiseProduct(ext));
            }
        }
    }
    cloud.SetUnorganized();
    Indices all(cloud.size());
    for (std::size_t i = 0; i < all.size(); ++i) all[i] = static_cast<Index>(i);
    const BoxModel box = FitOrientedBoundingBox(cloud, all);
    ASSERT_TRUE(box.found);
    EXPECT_NEAR(box.extents.x(), 0.3f, 2e-3f);
    EXPECT_NEAR(box.extents.y(), 0.2f, 2e-3f);
    EXPECT_NEAR(box.extents.z(), 0.05f, 2e-3f);
    EXPECT_LT((box.center - c).norm(), 2e-3f);
    for (int k = 0; k < 3; ++k) {
        EXPECT_LT(
            std::min(AngleDeg(box.axes.col(k), R.col(k)), AngleDeg(box.axes.col(k), -R.col(k))),
            1.0f);
    }
    EXPECT_NEAR(box.axes.determinant(), 1.0f, 1e-4f);
    EXPECT_GT(box.inlier_ratio, 0.99f);
}

TEST(BoundingBox, AlignUprightAxesFindsTheFaceRotation) {
    // Normals of two side faces (yaw 0.3 rad about up = z) and a top, with 3 degrees of noise,
    // plus 20% random normals.
    std::mt19937 rng(9);
    std::normal_distribution<float> gauss(0.0f, 3.0f * kDeg);
    std::uniform_real_distribution<float> uni(-1.0f, 1.0f);
    const float yaw = 0.3f;
    const Eigen::Vector3f x(std::cos(yaw), std::sin(yaw), 0.0f), y(-x.y(), x.x(), 0.0f);
    PointCloud cloud;
    for (int i = 0; i < 1000; ++i) {
        Eigen::Vector3f base = Eigen::Vector3f::UnitZ();
        if (i % 5 == 4) {
            base = Eigen::Vector3f(uni(rng), uni(rng), uni(rng));
        } else if (i % 3 == 0) {
            base = x;
        } else if (i % 3 == 1) {
            base = -y;
        }
        cloud.points.emplace_back(0.0f, 0.0f, 1.0f);
        cloud.normals.push_back(
            (base.normalized() + Eigen::Vector3f(gauss(rng), gauss(rng), gauss(rng))).normalized());
    }
    cloud.SetUnorganized();
    Indices all(cloud.size());
    for (std::size_t i = 0; i < all.size(); ++i) all[i] = static_cast<Index>(i);
    const FaceAlignment fa = AlignUprightAxes(cloud, all, Eigen::Vector3f::UnitZ(), 10.0f * kDeg);
    ASSERT_TRUE(fa.found);
    const float yaw_deg = std::atan2(fa.axes(1, 0), fa.axes(0, 0)) / kDeg;
    EXPECT_LT(AngleModDeg(yaw_deg, yaw / kDeg, 90.0f), 0.5f);
    EXPECT_NEAR(fa.axes.determinant(), 1.0f, 1e-5f);
    EXPECT_GT(fa.aligned_ratio, 0.75f);
    EXPECT_LT(fa.aligned_ratio, 0.85f);
    EXPECT_THROW(AlignUprightAxes(cloud, all, Eigen::Vector3f::UnitZ(), 0.0f), InvalidArgument);
    EXPECT_THROW(AlignUprightAxes(cloud, all, Eigen::Vector3f::UnitZ(), 1.0f), InvalidArgument);
}

// ---------------------------------------------------------------------------------------------
// Box and cylinder models from single-view scans

sim::TableTopScene BoxScene() {
    sim::TableTopScene s;
    s.boxes = {
        {{-0.35f, 0.10f}, 0.15f, {0.12f, 0.08f, 0.20f}, {}},
        {{-0.10f, -0.05f}, 1.1f, {0.20f, 0.15f, 0.05f}, {}},
        {{0.15f, 0.15f}, -0.6f, {0.05f, 0.18f, 0.24f}, {}},
        {{0.38f, -0.10f}, 2.4f, {0.10f, 0.07f, 0.07f}, {}},
    };
    return s;
}

// Scans shared by several tests: scanning and normals take most of the run time.
const Scan& DemoScan() {
    static const Scan scan = ScanScene(sim::MakeDemoScene());
    return scan;
}
const Scan& BoxSceneScan() {
    static const Scan scan = ScanScene(BoxScene());
    return scan;
}

// A can lying on the table, its axis turned 0.5 rad from the table's x axis.
struct LyingCan {
    float radius = 0.033f;
    float length = 0.12f;
    Eigen::Vector3f axis_w{std::cos(0.5f), std::sin(0.5f), 0.0f};
    Eigen::Vector3f center_w{0.05f, 0.0f, 0.75f + 0.033f};
};
const Scan& LyingCanScan() {
    static const Scan scan = [] {
        const LyingCan can;
        return ScanShapes({Cylinder(can.center_w, can.axis_w, can.radius, can.length)});
    }();
    return scan;
}

TEST(PrimitiveModels, UprightBoxesFromSingleViewScans) {
    float worst_extent = 0.0f, worst_yaw = 0.0f, sum_extent = 0.0f;
    int count = 0;
    for (const bool demo : {true, false}) {
        const sim::TableTopScene scene = demo ? sim::MakeDemoScene() : BoxScene();
        const Scan& scan = demo ? DemoScan() : BoxSceneScan();
        for (std::size_t b = 0; b < scene.boxes.size(); ++b) {
            const Indices obj =
                WithLabel(scan.cloud, sim::ObjectLabel(static_cast<std::uint32_t>(b + 1)));
            ASSERT_GT(obj.size(), 300u);
            const BoxModel fit = FitUprightBox(scan.cloud, obj, scan.plane, {});
            ASSERT_TRUE(fit.found);
            const BoxErrors e = CompareBox(fit, scene.boxes[b], scan, scene.table_height);
            EXPECT_LT(e.extents.maxCoeff(), 0.005f)
                << "box " << b << " extents " << fit.extents.transpose();
            EXPECT_LT(e.yaw_deg, 2.0f) << "box " << b;
            EXPECT_LT(e.center, 0.006f) << "box " << b;
            EXPECT_GT(fit.inlier_ratio, 0.95f) << "box " << b;
            EXPECT_NEAR(fit.axes.determinant(), 1.0f, 1e-4f);
            EXPECT_LT(AngleDeg(fit.axes.col(2), scan.plane.head<3>()), 1e-3f);
            // Without normals: the minimum-area footprint rectangle and the highest point.
            const BoxModel plain =
                FitUprightBox(scan.cloud, obj, scan.plane, {.use_normals = false});
            const BoxErrors ep = CompareBox(plain, scene.boxes[b], scan, scene.table_height);
            EXPECT_LT(ep.extents.maxCoeff(), 0.01f) << "box " << b << " without normals";
            EXPECT_LT(ep.yaw_deg, 2.0f) << "box " << b << " without normals";
            worst_extent = std::max(worst_extent, e.extents.maxCoeff());
            worst_yaw = std::max(worst_yaw, e.yaw_deg);
            sum_extent += e.extents.sum();
            count += 3;
        }
    }
    std::printf("[ boxes    ] mean extent error %.2f mm, worst %.2f mm, worst yaw %.2f deg\n",
                1e3f * sum_extent / static_cast<float>(count), 1e3f * worst_extent, worst_yaw);
}

TEST(PrimitiveModels, UprightCylindersFromSingleViewScans) {
    sim::TableTopScene scene;
    scene.cylinders = sim::MakeDemoScene().cylinders;
    scene.cylinders.push_back({{0.45f, -0.2f}, 0.03f, 0.09f, {}});
    scene.cylinders.push_back({{-0.45f, -0.15f}, 0.045f, 0.25f, {}});
    const Scan scan = ScanScene(scene);
    const Eigen::Vector3f up_cam = scan.plane.head<3>();
    float worst_r = 0.0f, worst_axis = 0.0f, worst_h = 0.0f;
    for (std::size_t c = 0; c < scene.cylinders.size(); ++c) {
        const auto& truth = scene.cylinders[c];
        const Indices obj =
            WithLabel(scan.cloud, sim::ObjectLabel(static_cast<std::uint32_t>(c) + 1));
        ASSERT_GT(obj.size(), 300u);
        // Default: the axis is snapped to up; without snapping it is refined freely.
        for (const bool snap : {true, false}) {
            const CylinderModel fit =
                FitObjectCylinder(scan.cloud, obj, scan.plane, {.snap_to_support = snap});
            ASSERT_TRUE(fit.found) << "cylinder " << c;
            const float r_err = std::abs(fit.radius - truth.radius);
            const float axis_err = AngleDeg(fit.axis, up_cam);
            const float h_err = std::abs(fit.height - truth.height);
            const Eigen::Vector3f c_w = scan.T_world_camera * fit.center;
            const Eigen::Vector3f c_true(truth.center_xy.x(), truth.center_xy.y(),
                                         scene.table_height + truth.height / 2);
            EXPECT_LT(r_err, 0.003f) << "cylinder " << c << " radius " << fit.radius;
            EXPECT_LT(axis_err, 2.0f) << "cylinder " << c;
            EXPECT_LT(h_err, 0.01f) << "cylinder " << c << " height " << fit.height;
            EXPECT_LT((c_w - c_true).norm(), 0.01f) << "cylinder " << c;
            EXPECT_GT(fit.inlier_ratio, 0.9f) << "cylinder " << c;
            worst_r = std::max(worst_r, r_err);
            worst_axis = std::max(worst_axis, axis_err);
            worst_h = std::max(worst_h, h_err);
        }
    }
    std::printf("[ cylinders] worst radius error %.2f mm, axis %.2f deg, height %.2f mm\n",
                1e3f * worst_r, worst_axis, 1e3f * worst_h);
}

TEST(PrimitiveModels, CylinderStartReplacesTheConsensusSearch) {
    sim::TableTopScene scene;
    scene.cylinders.push_back({{0.05f, 0.0f}, 0.04f, 0.15f, {}});
    const Scan scan = ScanScene(scene);
    const Indices obj = WithLabel(scan.cloud, sim::ObjectLabel(1));
    ASSERT_GT(obj.size(), 300u);
    const CylinderModel searched = FitObjectCylinder(scan.cloud, obj, scan.plane, {});
    ASSERT_TRUE(searched.found);
    // A start a few millimetres and degrees off converges to the searched cylinder.
    const Eigen::Vector3f up = scan.plane.head<3>().normalized();
    Eigen::Vector3f tilt = up.unitOrthogonal();
    const CylinderStart near{searched.center + 0.004f * tilt,
                             (searched.axis + 0.05f * tilt).normalized(), 0.036f};
    const CylinderModel started = FitObjectCylinder(scan.cloud, obj, scan.plane, {}, {}, near);
    ASSERT_TRUE(started.found);
    EXPECT_NEAR(started.radius, searched.radius, 2e-4f);
    EXPECT_LT(AngleDeg(started.axis, searched.axis), 0.2f);
    EXPECT_LT((started.center - searched.center).norm(), 0.001f);
    EXPECT_NEAR(started.height, searched.height, 0.002f);
    // A start outside the radius range, or one no point lies on, falls back to the search.
    for (const CylinderStart& bad :
         {CylinderStart{searched.center, searched.axis, 5.0f},
          CylinderStart{searched.center + 2.0f * tilt, searched.axis, 0.04f},
          CylinderStart{Eigen::Vector3f::Constant(std::nanf("")), searched.axis, 0.04f}}) {
        const CylinderModel fallback = FitObjectCylinder(scan.cloud, obj, scan.plane, {}, {}, bad);
        ASSERT_TRUE(fallback.found);
        EXPECT_EQ(fallback.radius, searched.radius);
        EXPECT_EQ(fallback.center, searched.center);
    }
}

TEST(PrimitiveModels, LyingCylinderFromSingleViewScan) {
    const LyingCan can;
    const float r = can.radius, len = can.length;
    const Eigen::Vector3f axis_w = can.axis_w, c_w = can.center_w;
    const Scan& scan = LyingCanScan();
    const Indices obj = WithLabel(scan.cloud, sim::ObjectLabel(1));
    ASSERT_GT(obj.size(), 300u);
    const CylinderModel fit = FitObjectCylinder(scan.cloud, obj, scan.plane, {});
    ASSERT_TRUE(fit.found);
    const Eigen::Vector3f axis_fit_w = scan.T_world_camera.linear() * fit.axis;
    const float axis_err = std::min(AngleDeg(axis_fit_w, axis_w), AngleDeg(axis_fit_w, -axis_w));
    EXPECT_LT(std::abs(fit.radius - r), 0.003f) << fit.radius;
    EXPECT_LT(axis_err, 2.0f);
    EXPECT_LT(std::abs(fit.height - len), 0.01f) << fit.height;
    EXPECT_LT(((scan.T_world_camera * fit.center) - c_w).norm(), 0.01f);
    std::printf("[ lying    ] radius error %.2f mm, axis %.2f deg, length error %.2f mm\n",
                1e3f * std::abs(fit.radius - r), axis_err, 1e3f * std::abs(fit.height - len));
}

// ---------------------------------------------------------------------------------------------
// Categories of scanned objects

TEST(Categorize, DemoSceneBoxesAndCylinders) {
    for (const bool demo : {true, false}) {
        const sim::TableTopScene scene = demo ? sim::MakeDemoScene() : BoxScene();
        const Scan& scan = demo ? DemoScan() : BoxSceneScan();
        const auto boxes = static_cast<std::uint32_t>(scene.boxes.size());
        for (std::uint32_t k = 1; k <= boxes + scene.cylinders.size(); ++k) {
            const Indices obj = WithLabel(scan.cloud, sim::ObjectLabel(k));
            const CategoryResult r = CategorizeObject(scan.cloud, obj, {}, scan.plane, {});
            const Category expected =
                k <= boxes ? ExpectedBoxCategory(scene.boxes[k - 1].extents) : Category::kCylinder;
            EXPECT_EQ(r.category, expected)
                << "object " << k << " got " << CategoryName(r.category) << " box " << r.box_score
                << " cyl " << r.cylinder_inlier_ratio << "+" << r.cylinder_cap_ratio << " sph "
                << r.sphere_inlier_ratio << " ext " << r.extents.transpose();
            float sum = 0.0f;
            for (float p : r.probabilities) sum += p;
            EXPECT_NEAR(sum, 1.0f, 1e-5f);
            EXPECT_EQ(r.confidence, r.probabilities[static_cast<std::size_t>(r.category)]);
            EXPECT_GT(r.confidence, 0.5f) << "object " << k;
            std::printf(
                "[ category ] object %u: %-8s p=%.2f box %.2f cyl %.2f+%.2f sph %.2f "
                "ext %.3f %.3f %.3f\n",
                k, std::string(CategoryName(r.category)).c_str(), r.confidence, r.box_score,
                r.cylinder_inlier_ratio, r.cylinder_cap_ratio, r.sphere_inlier_ratio, r.extents[0],
                r.extents[1], r.extents[2]);
        }
    }
}

TEST(Categorize, WithRegionGrowingParts) {
    const sim::TableTopScene scene = sim::MakeDemoScene();
    const Scan& scan = DemoScan();
    const auto boxes = static_cast<std::uint32_t>(scene.boxes.size());
    for (std::uint32_t k = 1; k <= boxes + scene.cylinders.size(); ++k) {
        const Indices obj = WithLabel(scan.cloud, sim::ObjectLabel(k));
        const KdTree tree(scan.cloud, obj);
        const RegionGrowingResult parts =
            RegionGrowing(scan.cloud, tree, {.radius = 0.01f, .subset = obj});
        ASSERT_FALSE(parts.parts.empty());
        const CategoryResult r = CategorizeObject(scan.cloud, obj, parts.parts, scan.plane, {});
        const Category expected =
            k <= boxes ? ExpectedBoxCategory(scene.boxes[k - 1].extents) : Category::kCylinder;
        EXPECT_EQ(r.category, expected) << "object " << k << " got " << CategoryName(r.category);
        EXPECT_GE(r.planar_part_ratio, 0.0f);
        if (k <= boxes) {
            EXPECT_GT(r.planar_part_ratio, 0.8f) << "object " << k;
        } else {
            EXPECT_LT(r.planar_part_ratio, 0.5f) << "object " << k;
        }
    }
}

// The cylinder evidence runs beside the box and sphere evidence when threads allow: every field
// of the result is the same on one thread and on two.
TEST(Categorize, TheSameOnAnyThreadCount) {
    const sim::TableTopScene scene = sim::MakeDemoScene();
    const Scan& scan = DemoScan();
    for (std::uint32_t k = 1; k <= scene.boxes.size() + scene.cylinders.size(); ++k) {
        const Indices obj = WithLabel(scan.cloud, sim::ObjectLabel(k));
        CategoryParams one, two;
        one.num_threads = 1;
        two.num_threads = 2;
        const CategoryResult a = CategorizeObject(scan.cloud, obj, {}, scan.plane, one);
        const CategoryResult b = CategorizeObject(scan.cloud, obj, {}, scan.plane, two);
        EXPECT_EQ(a.category, b.category) << "object " << k;
        EXPECT_EQ(a.probabilities, b.probabilities);
        EXPECT_EQ(a.box_score, b.box_score);
        EXPECT_EQ(a.axis_area, b.axis_area);
        EXPECT_EQ(a.cylinder_radius, b.cylinder_radius);
        EXPECT_EQ(a.cylinder_axis, b.cylinder_axis);
        EXPECT_EQ(a.cylinder_coverage, b.cylinder_coverage);
        EXPECT_EQ(a.sphere_radius, b.sphere_radius);
        EXPECT_EQ(a.sphere_inlier_ratio, b.sphere_inlier_ratio);
    }
}

TEST(Categorize, SphereIsSphere) {
    const Scan scan = ScanShapes({Sphere({0.0f, 0.0f, 0.75f + 0.05f}, 0.05f)});
    const Indices obj = WithLabel(scan.cloud, sim::ObjectLabel(1));
    ASSERT_GT(obj.size(), 300u);
    const CategoryResult r = CategorizeObject(scan.cloud, obj, {}, scan.plane, {});
    EXPECT_EQ(r.category, Category::kSphere) << CategoryName(r.category);
    EXPECT_NEAR(r.sphere_radius, 0.05f, 0.004f);
    EXPECT_GT(r.sphere_inlier_ratio, 0.8f);
    std::printf("[ category ] sphere: %s p=%.2f sph %.2f box %.2f\n",
                std::string(CategoryName(r.category)).c_str(), r.confidence, r.sphere_inlier_ratio,
                r.box_score);
}

TEST(Categorize, ThinDiscIsPlate) {
    sim::TableTopScene scene;
    scene.cylinders = {{{0.0f, 0.0f}, 0.11f, 0.02f, {}}};
    const auto [scan, obj] = ScanFirstObject(scene);
    const CategoryResult r = CategorizeObject(scan.cloud, obj, {}, scan.plane, {});
    EXPECT_EQ(r.category, Category::kPlate) << CategoryName(r.category);
    EXPECT_LT(r.footprint_fill, 0.86f);
    EXPECT_LT(r.thickness_ratio, 0.2f);
    std::printf("[ category ] disc: %s p=%.2f fill %.2f thickness %.2f\n",
                std::string(CategoryName(r.category)).c_str(), r.confidence, r.footprint_fill,
                r.thickness_ratio);
}

TEST(Categorize, FootprintCoverSeparatesASolidDiscFromOpenShapes) {
    // A lying disc covers its hull; two thin bars in a V (a clamp, open scissors) leave most of
    // theirs empty, although the V's hull is as round as the disc's by the fill measure.
    sim::TableTopScene disc;
    disc.cylinders = {{{0.0f, 0.0f}, 0.1f, 0.02f, {}}};
    const auto [a, da] = ScanFirstObject(disc);
    const CategoryResult d = CategorizeObject(a.cloud, da, {}, a.plane, {});
    EXPECT_GT(d.footprint_cover, 0.8f);
    EXPECT_LE(d.footprint_cover, 1.0f);

    sim::TableTopScene vee;
    vee.boxes = {{{0.0f, 0.08f}, 0.6f, {0.2f, 0.015f, 0.015f}, {}},
                 {{0.0f, -0.08f}, -0.6f, {0.2f, 0.015f, 0.015f}, {}}};
    const Scan b = ScanScene(vee);
    Indices bars = WithLabel(b.cloud, sim::ObjectLabel(1));
    const Indices second = WithLabel(b.cloud, sim::ObjectLabel(2));
    bars.insert(bars.end(), second.begin(), second.end());
    ASSERT_GT(bars.size(), 200u);
    const CategoryResult v = CategorizeObject(b.cloud, bars, {}, b.plane, {});
    EXPECT_LT(v.footprint_cover, 0.5f);
    EXPECT_GE(v.footprint_cover, 0.0f);
    std::printf("[ category ] footprint cover: disc %.2f, two bars %.2f\n", d.footprint_cover,
                v.footprint_cover);

    CategoryParams bad;
    bad.footprint_cell = 0.0f;
    EXPECT_THROW(CategorizeObject(a.cloud, da, {}, a.plane, bad), InvalidArgument);
}

TEST(Categorize, PlateSeenAsItsRimAndSquareDish) {
    // A real plate's bottom goes with the table's band, leaving its rim: the same disc's points
    // without their middle cover little of the hull and score as a plate fully, the solid disc
    // solid_plate times less.
    sim::TableTopScene scene;
    scene.cylinders = {{{0.0f, 0.0f}, 0.11f, 0.02f, {}}};
    const auto [scan, disc] = ScanFirstObject(scene);
    Eigen::Vector3f centre = Eigen::Vector3f::Zero();
    for (Index i : disc) centre += scan.cloud.points[i];
    centre /= static_cast<float>(disc.size());
    const Eigen::Vector3f up = scan.plane.head<3>().normalized();
    Indices rim;
    for (Index i : disc) {
        const Eigen::Vector3f d = scan.cloud.points[i] - centre;
        if ((d - d.dot(up) * up).norm() > 0.085f) rim.push_back(i);
    }
    ASSERT_GT(rim.size(), 100u);
    const auto plate = static_cast<std::size_t>(Category::kPlate);
    const CategoryResult solid = CategorizeObject(scan.cloud, disc, {}, scan.plane, {});
    const CategoryResult ring = CategorizeObject(scan.cloud, rim, {}, scan.plane, {});
    EXPECT_GT(solid.footprint_cover, 0.9f);
    EXPECT_LT(ring.footprint_cover, 0.6f);
    EXPECT_EQ(ring.category, Category::kPlate) << CategoryName(ring.category);
    EXPECT_NEAR(solid.scores[plate], 0.5f * ring.scores[plate], 0.1f);
    EXPECT_GT(ring.probabilities[plate], solid.probabilities[plate] + 0.2f);

    // A thin, low square slab is flat by its outline; counted as a dish (box score below
    // dish_box_score), the outline no longer matters.
    sim::TableTopScene slab;
    slab.boxes = {{{0.0f, 0.0f}, 0.3f, {0.15f, 0.15f, 0.02f}, {}}};
    const auto [s2, sq] = ScanFirstObject(slab);
    const CategoryResult as_slab = CategorizeObject(s2.cloud, sq, {}, s2.plane, {});
    EXPECT_GT(as_slab.footprint_fill, 0.94f);
    EXPECT_EQ(as_slab.scores[plate], 0.0f);
    CategoryParams dishes;
    dishes.dish_box_score = 0.99f;
    dishes.slab_box_score = 1.0f;
    const CategoryResult as_dish = CategorizeObject(s2.cloud, sq, {}, s2.plane, dishes);
    EXPECT_GT(as_dish.scores[plate], 0.3f);
    for (float bad : {-0.1f, 0.5f}) {
        CategoryParams p;
        p.dish_box_score = bad;  // 0.5 is not below slab_box_score
        EXPECT_THROW(CategorizeObject(s2.cloud, sq, {}, s2.plane, p), InvalidArgument);
    }
    CategoryParams p;
    p.solid_plate = 1.5f;
    EXPECT_THROW(CategorizeObject(s2.cloud, sq, {}, s2.plane, p), InvalidArgument);
    p = {};
    p.rim_cover = 0.9f;  // above solid_cover
    EXPECT_THROW(CategorizeObject(s2.cloud, sq, {}, s2.plane, p), InvalidArgument);
}

TEST(Categorize, DiscWiderThanTheLargestRadiusIsNoPlate) {
    // As thin, round and low as a plate, but 70 cm across: a piece of another surface, not a
    // dish. The same disc is a plate once the largest radius considered admits it.
    sim::TableTopScene scene;
    scene.cylinders = {{{0.0f, 0.0f}, 0.35f, 0.02f, {}}};
    const auto [scan, obj] = ScanFirstObject(scene);
    const CategoryResult r = CategorizeObject(scan.cloud, obj, {}, scan.plane, {});
    EXPECT_NE(r.category, Category::kPlate) << CategoryName(r.category);
    EXPECT_EQ(r.probabilities[static_cast<std::size_t>(Category::kPlate)], 0.0f);
    CategoryParams wide;
    wide.max_radius = 0.4f;
    const CategoryResult w = CategorizeObject(scan.cloud, obj, {}, scan.plane, wide);
    EXPECT_EQ(w.category, Category::kPlate) << CategoryName(w.category);
}

TEST(Categorize, WideLowTinIsNoPlate) {
    // As thin and round as a plate relative to its size, but 6 cm high: plates are 1.5-3 cm.
    sim::TableTopScene scene;
    scene.cylinders = {{{0.0f, 0.0f}, 0.13f, 0.06f, {}}};
    const auto [scan, obj] = ScanFirstObject(scene);
    const CategoryResult r = CategorizeObject(scan.cloud, obj, {}, scan.plane, {});
    EXPECT_NE(r.category, Category::kPlate);
    EXPECT_LT(r.probabilities[static_cast<std::size_t>(Category::kPlate)], 0.05f);
    EXPECT_LT(r.thickness_ratio, 0.3f);
    CategoryParams high_plates;
    high_plates.plate_low_height = 0.1f;
    high_plates.plate_high_height = 0.2f;
    high_plates.solid_plate = 1.0f;  // the tin's top is solid; only the height is under test
    const CategoryResult old = CategorizeObject(scan.cloud, obj, {}, scan.plane, high_plates);
    EXPECT_GT(old.probabilities[static_cast<std::size_t>(Category::kPlate)],
              r.probabilities[static_cast<std::size_t>(Category::kPlate)] + 0.1f);
}

TEST(Categorize, LargeBoxIsNoSphere) {
    // The faces of a large box fit a large sphere within the threshold; aligned normals say box.
    sim::TableTopScene scene;
    scene.boxes = {{{0.0f, 0.0f}, 0.5f, {0.15f, 0.07f, 0.25f}, {}}};
    const Scan scan = ScanScene(scene);
    const Indices obj = WithLabel(scan.cloud, sim::ObjectLabel(1));
    ASSERT_GT(obj.size(), 300u);
    const CategoryResult r = CategorizeObject(scan.cloud, obj, {}, scan.plane, {});
    EXPECT_TRUE(r.category == Category::kBox || r.category == Category::kFlat)
        << CategoryName(r.category);
    EXPECT_LT(r.probabilities[static_cast<std::size_t>(Category::kSphere)], 0.05f);
    EXPECT_GT(r.side_face_ratio, 0.2f);
}

TEST(Categorize, LyingCanIsCylinder) {
    const Scan& scan = LyingCanScan();
    const Indices obj = WithLabel(scan.cloud, sim::ObjectLabel(1));
    const CategoryResult r = CategorizeObject(scan.cloud, obj, {}, scan.plane, {});
    EXPECT_EQ(r.category, Category::kCylinder) << CategoryName(r.category);
    EXPECT_FALSE(r.cylinder_upright);
    EXPECT_NEAR(r.cylinder_radius, 0.033f, 0.004f);
    // The point given with the cylinder lies on the can's axis.
    const LyingCan can;
    const Eigen::Vector3f p_w = scan.T_world_camera * r.cylinder_point;
    const Eigen::Vector3f w = p_w - can.center_w;
    EXPECT_LT((w - w.dot(can.axis_w) * can.axis_w).norm(), 0.004f);
}

TEST(Categorize, UnknownSupportPlane) {
    const Scan& scan = DemoScan();
    // The cube (object 3) and the tall cylinder (object 5).
    const CategoryResult cube = CategorizeObject(
        scan.cloud, WithLabel(scan.cloud, sim::ObjectLabel(3)), {}, Eigen::Vector4f::Zero(), {});
    EXPECT_FALSE(cube.upright);
    EXPECT_EQ(cube.category, Category::kBox) << CategoryName(cube.category);
    const CategoryResult can = CategorizeObject(
        scan.cloud, WithLabel(scan.cloud, sim::ObjectLabel(5)), {}, Eigen::Vector4f::Zero(), {});
    EXPECT_EQ(can.category, Category::kCylinder) << CategoryName(can.category);
}

// Points in a 10 cm cube with random normals: no shape at all.
PointCloud Clutter(Indices& all) {
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> uni(-0.05f, 0.05f);
    std::normal_distribution<float> gauss(0.0f, 1.0f);
    PointCloud cloud;
    for (int i = 0; i < 2000; ++i) {
        cloud.points.emplace_back(uni(rng), uni(rng), 1.0f + uni(rng));
        cloud.normals.push_back(Eigen::Vector3f(gauss(rng), gauss(rng), gauss(rng)).normalized());
    }
    cloud.SetUnorganized();
    all.resize(cloud.size());
    for (std::size_t i = 0; i < all.size(); ++i) all[i] = static_cast<Index>(i);
    return cloud;
}

TEST(Categorize, RandomClutterIsOther) {
    Indices all;
    const PointCloud cloud = Clutter(all);
    const CategoryResult r =
        CategorizeObject(cloud, all, {}, Eigen::Vector4f(0.0f, -1.0f, 0.0f, 0.0f), {});
    EXPECT_EQ(r.category, Category::kOther) << CategoryName(r.category);
}

// ---------------------------------------------------------------------------------------------
// Meshes

TEST(PrimitiveMeshes, BoxMeshIsClosedOutwardWithTheRightVolume) {
    BoxModel box;
    box.center = {0.2f, -0.1f, 0.9f};
    box.axes = Eigen::AngleAxisf(0.7f, Eigen::Vector3f(0, 1, 1).normalized()).toRotationMatrix();
    box.extents = {0.16f, 0.1f, 0.08f};
    const TriangleMesh m = BoxMesh(box);
    EXPECT_EQ(m.vertices.size(), 8u);
    EXPECT_EQ(m.triangles.size(), 12u);
    EXPECT_NO_THROW(m.Validate());
    EXPECT_TRUE(ClosedAndConsistent(m));
    EXPECT_TRUE(Outward(m, box.center));
    EXPECT_NEAR(SignedVolume(m), 0.16 * 0.1 * 0.08, 0.01 * 0.16 * 0.1 * 0.08);
    // A left-handed frame still gives outward triangles.
    box.axes.col(2) = -box.axes.col(2);
    const TriangleMesh left = BoxMesh(box);
    EXPECT_TRUE(Outward(left, box.center));
    EXPECT_GT(SignedVolume(left), 0.0);
    // Colourable by the caller.
    TriangleMesh coloured = BoxMesh(box);
    coloured.vertex_colors.assign(coloured.vertices.size(), Color{255, 0, 0, 255});
    EXPECT_NO_THROW(coloured.Validate());
}

TEST(PrimitiveMeshes, CylinderMeshIsClosedOutwardWithTheRightVolume) {
    CylinderModel c;
    c.center = {-0.1f, 0.3f, 1.2f};
    c.axis = Eigen::Vector3f(0.2f, -1.0f, 0.4f).normalized();
    c.radius = 0.035f;
    c.height = 0.12f;
    const TriangleMesh m = CylinderMesh(c);
    EXPECT_EQ(m.vertices.size(), 66u);
    EXPECT_EQ(m.triangles.size(), 128u);
    EXPECT_NO_THROW(m.Validate());
    EXPECT_TRUE(ClosedAndConsistent(m));
    EXPECT_TRUE(Outward(m, c.center));
    const double analytic = std::numbers::pi * 0.035 * 0.035 * 0.12;
    EXPECT_NEAR(SignedVolume(m), analytic, 0.01 * analytic);
    EXPECT_EQ(CylinderMesh(c, 3).triangles.size(), 12u);
}

TEST(PrimitiveMeshes, FittedModelsMeshToTheirVolume) {
    const Scan& scan = DemoScan();
    const BoxModel box =
        FitUprightBox(scan.cloud, WithLabel(scan.cloud, sim::ObjectLabel(1)), scan.plane, {});
    const double box_volume = box.extents.prod();
    EXPECT_NEAR(SignedVolume(BoxMesh(box)), box_volume, 0.01 * box_volume);
    const CylinderModel cyl =
        FitObjectCylinder(scan.cloud, WithLabel(scan.cloud, sim::ObjectLabel(4)), scan.plane, {});
    const double cyl_volume = std::numbers::pi * cyl.radius * cyl.radius * cyl.height;
    EXPECT_NEAR(SignedVolume(CylinderMesh(cyl, 64)), cyl_volume, 0.01 * cyl_volume);
}

// ---------------------------------------------------------------------------------------------
// Contracts

TEST(PrimitiveContracts, EmptyInputGivesEmptyResults) {
    const Scan& scan = DemoScan();
    const CategoryResult r = CategorizeObject(scan.cloud, {}, {}, scan.plane, {});
    EXPECT_EQ(r.category, Category::kNone);
    EXPECT_EQ(r.probabilities[0], 1.0f);
    EXPECT_EQ(r.points, 0u);
    EXPECT_FALSE(FitUprightBox(scan.cloud, {}, scan.plane, {}).found);
    EXPECT_FALSE(FitOrientedBoundingBox(scan.cloud, {}).found);
    EXPECT_FALSE(FitObjectCylinder(scan.cloud, {}, scan.plane, {}).found);
    // Too few points: none; non-finite points are ignored.
    const Indices table = WithLabel(scan.cloud, sim::kTableLabel);
    const Indices few(table.begin(), table.begin() + 10);
    EXPECT_EQ(CategorizeObject(scan.cloud, few, {}, scan.plane, {}).category, Category::kNone);
    Indices nan_only;
    for (std::size_t i = 0; i < scan.cloud.size() && nan_only.size() < 50; ++i) {
        if (!scan.cloud.IsFinite(i)) nan_only.push_back(static_cast<Index>(i));
    }
    ASSERT_EQ(nan_only.size(), 50u);
    EXPECT_EQ(CategorizeObject(scan.cloud, nan_only, {}, scan.plane, {}).category, Category::kNone);
    EXPECT_FALSE(FitUprightBox(scan.cloud, nan_only, scan.plane, {}).found);
    // Empty objects need no normals.
    PointCloud bare(std::vector<Eigen::Vector3f>{Eigen::Vector3f(0.0f, 0.0f, 1.0f)});
    EXPECT_EQ(CategorizeObject(bare, {}, {}, Eigen::Vector4f::Zero(), {}).category,
              Category::kNone);
}

TEST(PrimitiveContracts, BadParametersAndInputThrow) {
    Scan scan;
    Indices obj;
    scan.cloud = Clutter(obj);
    scan.plane = Eigen::Vector4f(0.0f, -1.0f, 0.0f, 0.0f);
    const Eigen::Vector4f nan_plane(std::nanf(""), 0.0f, 1.0f, 0.0f);
    const Eigen::Vector4f zero_normal(0.0f, 0.0f, 0.0f, 1.0f);
    auto categorize = [&](CategoryParams p) {
        return CategorizeObject(scan.cloud, obj, {}, scan.plane, p);
    };
    EXPECT_THROW(categorize({.min_points = 0}), InvalidArgument);
    EXPECT_THROW(categorize({.min_points = 50, .max_points = 10}), InvalidArgument);
    EXPECT_THROW(categorize({.axis_angle_deg = 0.0f}), InvalidArgument);
    EXPECT_THROW(categorize({.fit_threshold = -0.01f}), InvalidArgument);
    EXPECT_THROW(categorize({.min_radius = 0.2f, .max_radius = 0.1f}), InvalidArgument);
    EXPECT_THROW(categorize({.flat_ratio = 1.5f}), InvalidArgument);
    EXPECT_THROW(categorize({.min_evidence = 1.0f}), InvalidArgument);
    EXPECT_THROW(categorize({.sharpness = 0.0f}), InvalidArgument);
    EXPECT_THROW(categorize({.plate_low_height = 0.05f, .plate_high_height = 0.04f}),
                 InvalidArgument);
    EXPECT_THROW(categorize({.sphere_box_axis_area = 0.7f, .sphere_box_axis_area_max = 0.6f}),
                 InvalidArgument);
    EXPECT_THROW(categorize({.num_threads = -1}), InvalidArgument);
    EXPECT_THROW(CategorizeObject(scan.cloud, obj, {}, nan_plane, {}), InvalidArgument);
    EXPECT_THROW(CategorizeObject(scan.cloud, obj, {}, zero_normal, {}), InvalidArgument);
    EXPECT_THROW(
        CategorizeObject(scan.cloud, {static_cast<Index>(scan.cloud.size())}, {}, scan.plane, {}),
        InvalidArgument);
    EXPECT_THROW(CategorizeObject(scan.cloud, obj, {{static_cast<Index>(scan.cloud.size())}},
                                  scan.plane, {}),
                 InvalidArgument);
    PointCloud no_normals(std::vector<Eigen::Vector3f>(100, Eigen::Vector3f(0, 0, 1)));
    EXPECT_THROW(CategorizeObject(no_normals, {0, 1, 2}, {}, Eigen::Vector4f::Zero(), {}),
                 DataError);

    EXPECT_THROW(FitUprightBox(scan.cloud, obj, Eigen::Vector4f::Zero(), {}), InvalidArgument);
    EXPECT_THROW(FitUprightBox(scan.cloud, obj, nan_plane, {}), InvalidArgument);
    EXPECT_THROW(FitUprightBox(scan.cloud, obj, scan.plane, {.inlier_threshold = 0.0f}),
                 InvalidArgument);
    EXPECT_THROW(FitUprightBox(scan.cloud, obj, scan.plane, {.face_angle_deg = 60.0f}),
                 InvalidArgument);
    EXPECT_THROW(FitOrientedBoundingBox(scan.cloud, {static_cast<Index>(scan.cloud.size())}),
                 InvalidArgument);

    CylinderModelParams cp;
    cp.sac.distance_threshold = 0.0f;
    EXPECT_THROW(FitObjectCylinder(scan.cloud, obj, scan.plane, cp), InvalidArgument);
    EXPECT_THROW(FitObjectCylinder(scan.cloud, obj, scan.plane, {.free_axis_gain = 0.5f}),
                 InvalidArgument);
    EXPECT_THROW(FitObjectCylinder(scan.cloud, obj, nan_plane, {}), InvalidArgument);
    EXPECT_THROW(FitObjectCylinder(no_normals, {0, 1, 2}, Eigen::Vector4f::Zero(), {}), DataError);

    BoxModel bad_box;
    bad_box.extents = {0.1f, -0.1f, 0.1f};
    EXPECT_THROW(BoxMesh(bad_box), InvalidArgument);
    CylinderModel bad_cyl;
    bad_cyl.radius = 0.05f;
    bad_cyl.height = 0.1f;
    EXPECT_THROW(CylinderMesh(bad_cyl, 2), InvalidArgument);
    bad_cyl.axis = Eigen::Vector3f::Zero();
    EXPECT_THROW(CylinderMesh(bad_cyl), InvalidArgument);
}

TEST(PrimitiveContracts, DeterministicAndThreadIndependent) {
    const Scan& scan = DemoScan();
    for (std::uint32_t k = 1; k <= 5; ++k) {
        const Indices obj = WithLabel(scan.cloud, sim::ObjectLabel(k));
        const CategoryResult a = CategorizeObject(scan.cloud, obj, {}, scan.plane, {});
        const CategoryResult b =
            CategorizeObject(scan.cloud, obj, {}, scan.plane, {.num_threads = 1});
        EXPECT_EQ(a.category, b.category);
        EXPECT_EQ(a.probabilities, b.probabilities);
        EXPECT_EQ(a.cylinder_radius, b.cylinder_radius);
        EXPECT_EQ(a.sphere_inlier_ratio, b.sphere_inlier_ratio);

        CylinderModelParams serial;
        serial.sac.num_threads = 1;
        const CylinderModel c1 = FitObjectCylinder(scan.cloud, obj, scan.plane, {});
        const CylinderModel c2 = FitObjectCylinder(scan.cloud, obj, scan.plane, serial);
        EXPECT_EQ(c1.found, c2.found);
        EXPECT_EQ(c1.center, c2.center);
        EXPECT_EQ(c1.axis, c2.axis);
        EXPECT_EQ(c1.radius, c2.radius);
        EXPECT_EQ(c1.height, c2.height);

        const BoxModel b1 = FitUprightBox(scan.cloud, obj, scan.plane, {});
        const BoxModel b2 = FitUprightBox(scan.cloud, obj, scan.plane, {});
        EXPECT_EQ(b1.center, b2.center);
        EXPECT_EQ(b1.extents, b2.extents);
    }
}

}  // namespace
}  // namespace multicue

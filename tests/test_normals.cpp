#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <numeric>
#include <random>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include "multicue/core/exceptions.hpp"
#include "multicue/surface/normals.hpp"
#include "test_util.hpp"

namespace multicue {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr double kDeg = 3.14159265358979323846 / 180.0;

// Angle between the lines of two vectors [rad]; atan2 keeps it accurate near 0 (acos of a dot
// product cannot resolve angles below about 3e-4 rad in float).
double LineAngle(const Eigen::Vector3f& a, const Eigen::Vector3f& b) {
    const Eigen::Vector3d x = a.cast<double>(), y = b.cast<double>();
    return std::atan2(x.cross(y).norm(), std::abs(x.dot(y)));
}

// A synthetic cloud with the true normal of every point.
struct Truth {
    PointCloud cloud;
    std::vector<Eigen::Vector3f> normals;  // NaN where there is no point
};

// Unit vectors u, v spanning the plane orthogonal to n.
void PlaneBasis(const Eigen::Vector3f& n, Eigen::Vector3f& u, Eigen::Vector3f& v) {
    u = n.unitOrthogonal();
    v = n.cross(u);
}

// Points on a jittered grid over a square of side `size` [m] of the plane through `centre` with
// normal `n`, spacing `step` [m], Gaussian noise `sigma` [m] along the normal.
Truth NoisyPlane(const Eigen::Vector3f& centre, const Eigen::Vector3f& n, float size, float step,
                 float sigma, std::uint32_t seed) {
    std::mt19937 rng(seed);
    std::normal_distribution<float> gauss(0.0f, 1.0f);
    std::uniform_real_distribution<float> jitter(-0.3f * step, 0.3f * step);
    Eigen::Vector3f u, v;
    PlaneBasis(n, u, v);
    Truth t;
    for (float a = -size / 2; a <= size / 2; a += step) {
        for (float b = -size / 2; b <= size / 2; b += step) {
            t.cloud.points.push_back(centre + (a + jitter(rng)) * u + (b + jitter(rng)) * v +
                                     sigma * gauss(rng) * n);
            t.normals.push_back(n);
        }
    }
    t.cloud.SetUnorganized();
    return t;
}

// `count` points uniformly on a sphere, radial Gaussian noise `sigma`.
Truth NoisySphere(const Eigen::Vector3f& centre, float radius, int count, float sigma,
                  std::uint32_t seed) {
    std::mt19937 rng(seed);
    std::normal_distribution<float> gauss(0.0f, 1.0f);
    Truth t;
    for (int i = 0; i < count; ++i) {
        const Eigen::Vector3f dir =
            Eigen::Vector3f(gauss(rng), gauss(rng), gauss(rng)).normalized();
        t.cloud.points.push_back(centre + (radius + sigma * gauss(rng)) * dir);
        t.normals.push_back(dir);
    }
    t.cloud.SetUnorganized();
    return t;
}

// `count` points uniformly on the side of a cylinder (axis through `base` along `axis`, length
// `length`), radial Gaussian noise `sigma`.
Truth NoisyCylinder(const Eigen::Vector3f& base, const Eigen::Vector3f& axis, float radius,
                    float length, int count, float sigma, std::uint32_t seed) {
    std::mt19937 rng(seed);
    std::normal_distribution<float> gauss(0.0f, 1.0f);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    Eigen::Vector3f u, v;
    PlaneBasis(axis, u, v);
    Truth t;
    for (int i = 0; i < count; ++i) {
        const float phi = 6.2831853f * unit(rng);
        const Eigen::Vector3f radial = std::cos(phi) * u + std::sin(phi) * v;
        t.cloud.points.push_back(base + length * unit(rng) * axis +
                                 (radius + sigma * gauss(rng)) * radial);
        t.normals.push_back(radial);
    }
    t.cloud.SetUnorganized();
    return t;
}

// A pinhole camera at the origin looking along +z (a Kinect's 525 px focal length, so pixels
// are as far apart as on a real frame) sees a scene through `Hit`, which returns the range along
// the ray and the true normal, or false. Range noise is Gaussian with sigma * z^2 (Kinect-like);
// `holes` of the pixels are NaN at random.
template <typename Hit>
Truth OrganizedView(int width, int height, float sigma, float holes, std::uint32_t seed,
                    Hit&& hit) {
    constexpr float kFocal = 525.0f;
    std::mt19937 rng(seed);
    std::normal_distribution<float> gauss(0.0f, 1.0f);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    Truth t;
    t.cloud.points.assign(static_cast<std::size_t>(width) * height,
                          Eigen::Vector3f::Constant(kNaN));
    t.normals.assign(t.cloud.points.size(), Eigen::Vector3f::Constant(kNaN));
    t.cloud.width = static_cast<std::uint32_t>(width);
    t.cloud.height = static_cast<std::uint32_t>(height);
    for (int v = 0; v < height; ++v) {
        for (int u = 0; u < width; ++u) {
            const Eigen::Vector3f ray = Eigen::Vector3f((u - 0.5f * (width - 1)) / kFocal,
                                                        (v - 0.5f * (height - 1)) / kFocal, 1.0f)
                                            .normalized();
            float range = 0.0f;
            Eigen::Vector3f normal;
            if (!hit(ray, range, normal) || unit(rng) < holes) continue;
            const float z = range * ray.z();
            const std::size_t i = static_cast<std::size_t>(v) * width + u;
            t.cloud.points[i] = (range + sigma * z * z * gauss(rng)) * ray;
            t.normals[i] = normal;
        }
    }
    return t;
}

// A plane through `point` with normal `n` seen by the camera of OrganizedView.
auto PlaneHit(const Eigen::Vector3f& point, const Eigen::Vector3f& n) {
    return [point, n](const Eigen::Vector3f& ray, float& range, Eigen::Vector3f& normal) {
        const float denom = n.dot(ray);
        if (std::abs(denom) < 1e-6f) return false;
        range = n.dot(point) / denom;
        normal = n;
        return range > 0.0f;
    };
}

auto SphereHit(const Eigen::Vector3f& centre, float radius) {
    return [centre, radius](const Eigen::Vector3f& ray, float& range, Eigen::Vector3f& normal) {
        const float b = ray.dot(centre);
        const float disc = b * b - (centre.squaredNorm() - radius * radius);
        if (disc < 0.0f) return false;
        range = b - std::sqrt(disc);
        normal = (range * ray - centre).normalized();
        return true;
    };
}

struct ErrorStats {
    double mean = 0.0;
    double p95 = 0.0;
    double max = 0.0;
    std::size_t count = 0;
};

// Unoriented angle errors over the points with both an estimate and a true normal (and, if
// given, selected by `use`).
ErrorStats AngleErrors(const NormalsResult& r, const std::vector<Eigen::Vector3f>& truth,
                       const std::vector<bool>& use = {}) {
    std::vector<double> e;
    for (std::size_t i = 0; i < truth.size(); ++i) {
        if (!use.empty() && !use[i]) continue;
        if (!truth[i].allFinite() || !r.normals[i].allFinite()) continue;
        e.push_back(LineAngle(r.normals[i], truth[i]));
    }
    ErrorStats s;
    if (e.empty()) return s;
    std::sort(e.begin(), e.end());
    s.count = e.size();
    s.mean = std::accumulate(e.begin(), e.end(), 0.0) / static_cast<double>(e.size());
    s.p95 = e[e.size() * 95 / 100];
    s.max = e.back();
    return s;
}

// Every defined normal is a unit vector pointing towards the viewpoint.
void ExpectOrientedUnitNormals(const PointCloud& c, const NormalsResult& r,
                               const Eigen::Vector3f& viewpoint) {
    std::size_t defined = 0;
    for (std::size_t i = 0; i < c.size(); ++i) {
        if (!r.normals[i].allFinite()) continue;
        ++defined;
        ASSERT_NEAR(r.normals[i].norm(), 1.0f, 1e-5f) << "point " << i;
        ASSERT_GE(r.normals[i].dot(viewpoint - c.points[i]), 0.0f) << "point " << i;
    }
    EXPECT_GT(defined, 0u);
}

std::size_t CountNaN(const std::vector<float>& v) {
    return static_cast<std::size_t>(
        std::count_if(v.begin(), v.end(), [](float x) { return std::isnan(x); }));
}

// Bit-exact equality of two results (NaNs included).
void ExpectBitIdentical(const NormalsResult& a, const NormalsResult& b) {
    ASSERT_EQ(a.normals.size(), b.normals.size());
    ASSERT_EQ(a.curvature.size(), b.curvature.size());
    EXPECT_EQ(a.undefined, b.undefined);
    EXPECT_EQ(
        std::memcmp(a.normals.data(), b.normals.data(), a.normals.size() * sizeof(Eigen::Vector3f)),
        0);
    EXPECT_EQ(
        std::memcmp(a.curvature.data(), b.curvature.data(), a.curvature.size() * sizeof(float)), 0);
}

const Eigen::Vector3f kTilted = Eigen::Vector3f(0.3f, -0.4f, 1.0f).normalized();

// --- k-d tree estimator: recovering known surfaces ------------------------------------------

// 1 mm noise, 5 mm spacing. Measured: k-NN mean 2.6 deg, p95 5.0 deg; radius 2 cm mean 1.1 deg,
// p95 2.2 deg. The bounds here and below leave about 40% headroom.
TEST(Normals, NoisyPlaneKnnAndRadius) {
    const Truth t = NoisyPlane({0.1f, -0.2f, 1.0f}, kTilted, 0.4f, 0.005f, 0.001f, 11);
    const KdTree tree(t.cloud);

    const NormalsResult knn = EstimateNormals(t.cloud, tree, {.k = 20});
    const ErrorStats ek = AngleErrors(knn, t.normals);
    EXPECT_EQ(knn.undefined, 0u);
    EXPECT_EQ(ek.count, t.cloud.size());
    EXPECT_LT(ek.mean, 3.5 * kDeg);
    EXPECT_LT(ek.p95, 7.0 * kDeg);

    const NormalsResult rad = EstimateNormals(t.cloud, tree, {.radius = 0.02f});
    const ErrorStats er = AngleErrors(rad, t.normals);
    EXPECT_EQ(rad.undefined, 0u);
    EXPECT_LT(er.mean, 1.6 * kDeg);
    EXPECT_LT(er.p95, 3.0 * kDeg);
    // Larger neighbourhoods average more noise.
    EXPECT_LT(er.mean, ek.mean);
}

// 8000 points on a 10 cm sphere (4 mm spacing), 1 mm noise. Measured: k-NN mean 3.8 deg, p95
// 7.8 deg; radius mean 0.9 deg, p95 1.9 deg.
TEST(Normals, NoisySphereKnnAndRadius) {
    const Truth t = NoisySphere({0.0f, 0.1f, 1.2f}, 0.1f, 8000, 0.001f, 12);
    const KdTree tree(t.cloud);
    const ErrorStats ek = AngleErrors(EstimateNormals(t.cloud, tree, {.k = 20}), t.normals);
    EXPECT_LT(ek.mean, 5.0 * kDeg);
    EXPECT_LT(ek.p95, 10.5 * kDeg);
    const ErrorStats er = AngleErrors(EstimateNormals(t.cloud, tree, {.radius = 0.02f}), t.normals);
    EXPECT_LT(er.mean, 1.4 * kDeg);
    EXPECT_LT(er.p95, 2.7 * kDeg);
}

// 10000 points on a tilted cylinder of radius 8 cm, 1 mm noise. Measured: k-NN mean 3.9 deg,
// p95 8.0 deg; radius mean 1.1 deg, p95 2.4 deg.
TEST(Normals, NoisyCylinderKnnAndRadius) {
    const Truth t =
        NoisyCylinder({0.0f, 0.0f, 1.0f}, Eigen::Vector3f(1.0f, 0.2f, 0.3f).normalized(), 0.08f,
                      0.3f, 10000, 0.001f, 13);
    const KdTree tree(t.cloud);
    const ErrorStats ek = AngleErrors(EstimateNormals(t.cloud, tree, {.k = 20}), t.normals);
    EXPECT_LT(ek.mean, 5.0 * kDeg);
    EXPECT_LT(ek.p95, 10.5 * kDeg);
    const ErrorStats er = AngleErrors(EstimateNormals(t.cloud, tree, {.radius = 0.02f}), t.normals);
    EXPECT_LT(er.mean, 1.6 * kDeg);
    EXPECT_LT(er.p95, 3.3 * kDeg);
}

TEST(Normals, OrientedTowardsViewpoint) {
    Truth t = NoisySphere({0.0f, 0.0f, 0.0f}, 0.1f, 3000, 0.001f, 14);
    const KdTree tree(t.cloud);
    // Default: the cloud's sensor origin; outside the sphere, half the normals point outwards.
    t.cloud.sensor_origin = {0.0f, 0.0f, -1.0f};
    const NormalsResult from_origin = EstimateNormals(t.cloud, tree, {.k = 15});
    ExpectOrientedUnitNormals(t.cloud, from_origin, t.cloud.sensor_origin);
    // An explicit viewpoint wins: from the centre every normal points inwards.
    const NormalsResult inwards =
        EstimateNormals(t.cloud, tree, {.k = 15, .viewpoint = Eigen::Vector3f::Zero()});
    ExpectOrientedUnitNormals(t.cloud, inwards, Eigen::Vector3f::Zero());
    for (std::size_t i = 0; i < t.cloud.size(); ++i) {
        EXPECT_LT(inwards.normals[i].dot(t.normals[i]), 0.0f);
    }
}

TEST(Normals, CurvatureZeroOnPlanePositiveOnSphere) {
    // Noise-free plane: surface variation vanishes up to rounding.
    const Truth plane = NoisyPlane({0.0f, 0.0f, 1.0f}, kTilted, 0.2f, 0.005f, 0.0f, 15);
    const KdTree plane_tree(plane.cloud);
    const NormalsResult p = EstimateNormals(plane.cloud, plane_tree, {.radius = 0.02f});
    EXPECT_LT(*std::max_element(p.curvature.begin(), p.curvature.end()), 1e-5f);
    EXPECT_LT(AngleErrors(p, plane.normals).max, 1e-3);

    // Sphere of radius R, neighbourhood radius r << R: the cap's height rho^2 / (2R) has
    // variance r^4 / (48 R^2) against r^2 / 4 per tangent axis, so the surface variation is
    // about r^2 / (24 R^2), 0.00167 here (measured 0.00170). It never exceeds 1/3.
    const Truth sphere = NoisySphere({0.0f, 0.0f, 1.0f}, 0.1f, 8000, 0.0f, 16);
    const KdTree sphere_tree(sphere.cloud);
    const NormalsResult s = EstimateNormals(sphere.cloud, sphere_tree, {.radius = 0.02f});
    const double mean = std::accumulate(s.curvature.begin(), s.curvature.end(), 0.0) /
                        static_cast<double>(s.curvature.size());
    EXPECT_NEAR(mean, 0.02 * 0.02 / (24 * 0.1 * 0.1), 0.0003);
    EXPECT_LE(*std::max_element(s.curvature.begin(), s.curvature.end()), 1.0f / 3.0f);
}

// --- oracle: brute-force neighbourhoods and Eigen's iterative eigensolver ----------------------

// Normal and curvature by the textbook route: neighbours by sorting all distances, covariance
// about the mean in double, Eigen's QR-based SelfAdjointEigenSolver.
bool BruteForceNormal(const PointCloud& c, const Eigen::Vector3f& q, int k, float radius,
                      Eigen::Vector3f& normal, float& curvature) {
    std::vector<std::pair<float, std::size_t>> d;
    for (std::size_t i = 0; i < c.size(); ++i) {
        if (!c.points[i].allFinite()) continue;
        const float d2 = (c.points[i] - q).squaredNorm();
        if (radius > 0.0f && d2 > radius * radius) continue;
        d.emplace_back(d2, i);
    }
    std::sort(d.begin(), d.end());
    if (k > 0 && d.size() > static_cast<std::size_t>(k)) d.resize(static_cast<std::size_t>(k));
    if (d.size() < 3) return false;
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (const auto& [d2, i] : d) mean += c.points[i].cast<double>();
    mean /= static_cast<double>(d.size());
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (const auto& [d2, i] : d) {
        const Eigen::Vector3d x = c.points[i].cast<double>() - mean;
        cov += x * x.transpose();
    }
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(cov /
                                                                static_cast<double>(d.size()));
    normal = solver.eigenvectors().col(0).cast<float>();
    curvature = static_cast<float>(solver.eigenvalues()(0) / solver.eigenvalues().sum());
    return true;
}

TEST(Normals, MatchesBruteForceOracle) {
    // A wavy noisy surface with some clutter; NaN points are skipped by everyone.
    std::mt19937 rng(17);
    std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
    PointCloud c;
    for (int i = 0; i < 1200; ++i) {
        const float x = 0.3f * unit(rng), y = 0.3f * unit(rng);
        c.points.emplace_back(
            x, y, 1.0f + 0.03f * std::sin(20.0f * x) * std::cos(15.0f * y) + 0.002f * unit(rng));
    }
    for (int i = 0; i < 100; ++i)
        c.points.emplace_back(0.3f * unit(rng), 0.3f * unit(rng), 0.9f + 0.2f * unit(rng));
    c.points[7] = Eigen::Vector3f::Constant(kNaN);
    c.SetUnorganized();
    const KdTree tree(c);

    struct Mode {
        int k;
        float radius;
    };
    for (const Mode mode : {Mode{10, 0.0f}, Mode{25, 0.0f}, Mode{0, 0.03f}, Mode{12, 0.03f}}) {
        SCOPED_TRACE(testing::Message() << "k " << mode.k << " radius " << mode.radius);
        const NormalsResult r =
            EstimateNormals(c, tree, {.k = mode.k, .radius = mode.radius, .num_threads = 1});
        std::size_t undefined = 0;
        for (std::size_t i = 0; i < c.size(); ++i) {
            Eigen::Vector3f n;
            float curvature = 0.0f;
            if (!c.points[i].allFinite() ||
                !BruteForceNormal(c, c.points[i], mode.k, mode.radius, n, curvature)) {
                EXPECT_FALSE(r.normals[i].allFinite()) << i;
                ++undefined;
                continue;
            }
            ASSERT_TRUE(r.normals[i].allFinite()) << i;
            EXPECT_LT(LineAngle(r.normals[i], n), 1e-4) << i;
            EXPECT_NEAR(r.curvature[i], curvature, 1e-4f) << i;
        }
        EXPECT_EQ(r.undefined, undefined);
    }
}

// --- determinism, subsets, contract -----------------------------------------------------------

TEST(Normals, ThreadCountDoesNotChangeResults) {
    const Truth t =
        NoisyCylinder({0.0f, 0.0f, 1.0f}, Eigen::Vector3f::UnitX(), 0.1f, 0.5f, 30000, 0.002f, 18);
    const KdTree tree(t.cloud);
    for (const NormalParams& base : {NormalParams{.k = 20}, NormalParams{.radius = 0.03f},
                                     NormalParams{.k = 15, .radius = 0.02f}}) {
        NormalParams p = base;
        p.num_threads = 1;
        const NormalsResult one = EstimateNormals(t.cloud, tree, p);
        p.num_threads = 0;
        const NormalsResult all = EstimateNormals(t.cloud, tree, p);
        p.num_threads = 2;
        const NormalsResult two = EstimateNormals(t.cloud, tree, p);
        ExpectBitIdentical(one, all);
        ExpectBitIdentical(one, two);
        ExpectBitIdentical(one, EstimateNormals(t.cloud, tree, p));  // and repeatable
    }
}

// Leaf size changes the tree, its order and the batches of the k-nearest search, not the
// neighbourhoods (random points: no distance ties), so normals agree to rounding.
TEST(Normals, TreeShapeDoesNotChangeNeighbourhoods) {
    const Truth t = NoisySphere({0.0f, 0.0f, 1.0f}, 0.1f, 4000, 0.002f, 30);
    const KdTree reference_tree(t.cloud);
    for (const NormalParams& p : {NormalParams{.k = 12}, NormalParams{.radius = 0.02f},
                                  NormalParams{.k = 12, .radius = 0.01f}}) {
        const NormalsResult reference = EstimateNormals(t.cloud, reference_tree, p);
        for (const int leaf_size : {1, 5, 64, 300}) {
            SCOPED_TRACE(testing::Message() << "leaf_size " << leaf_size);
            const KdTree tree(t.cloud, KdTreeParams{.leaf_size = leaf_size});
            const NormalsResult r = EstimateNormals(t.cloud, tree, p);
            ASSERT_EQ(r.undefined, reference.undefined);
            for (std::size_t i = 0; i < t.cloud.size(); ++i) {
                if (!reference.normals[i].allFinite()) continue;
                EXPECT_LT(LineAngle(r.normals[i], reference.normals[i]), 1e-5) << i;
                EXPECT_NEAR(r.curvature[i], reference.curvature[i], 1e-6f) << i;
            }
        }
    }
}

TEST(Normals, TreeOverSubsetStillGivesEveryPointANormal) {
    const Truth t = NoisyPlane({0.0f, 0.0f, 1.0f}, kTilted, 0.3f, 0.005f, 0.0005f, 19);
    Indices even;
    for (std::size_t i = 0; i < t.cloud.size(); i += 2) even.push_back(static_cast<Index>(i));
    const KdTree tree(t.cloud, even);
    for (const NormalParams& p : {NormalParams{.k = 10}, NormalParams{.radius = 0.02f}}) {
        const NormalsResult r = EstimateNormals(t.cloud, tree, p);
        EXPECT_EQ(r.undefined, 0u);
        EXPECT_LT(AngleErrors(r, t.normals).p95, 5.0 * kDeg);
    }
}

TEST(Normals, TooFewNeighboursAndNaNPointsAreUndefined) {
    // Two isolated pairs, one triple and a NaN; radius 1 cm.
    PointCloud c({{0, 0, 0},
                  {0.005f, 0, 0},
                  {1, 0, 0},
                  {1.005f, 0, 0},
                  {2, 0, 0},
                  {2.005f, 0, 0},
                  {2, 0.005f, 0},
                  {kNaN, kNaN, kNaN}});
    const KdTree tree(c);
    const NormalsResult r = EstimateNormals(c, tree, {.radius = 0.01f});
    EXPECT_EQ(r.undefined, 5u);
    EXPECT_EQ(CountNaN(r.curvature), 5u);
    for (std::size_t i : {4u, 5u, 6u}) {
        EXPECT_LT(LineAngle(r.normals[i], Eigen::Vector3f::UnitZ()), 1e-5) << i;
    }
    // k-NN always finds 3 finite points here; only the NaN point stays undefined.
    EXPECT_EQ(EstimateNormals(c, tree, {.k = 3}).undefined, 1u);
    // Coincident points have no plane.
    const PointCloud same({{1, 1, 1}, {1, 1, 1}, {1, 1, 1}, {1, 1, 1}});
    EXPECT_EQ(EstimateNormals(same, KdTree(same), {.k = 4}).undefined, 4u);
}

TEST(Normals, EmptyAndNaNOnlyClouds) {
    const PointCloud empty;
    const NormalsResult e = EstimateNormals(empty, KdTree(empty), {});
    EXPECT_TRUE(e.normals.empty());
    EXPECT_TRUE(e.curvature.empty());
    EXPECT_EQ(e.undefined, 0u);

    PointCloud nan_only(std::vector<Eigen::Vector3f>(50, Eigen::Vector3f::Constant(kNaN)));
    const KdTree tree(nan_only);
    for (const NormalParams& p : {NormalParams{}, NormalParams{.radius = 0.1f}}) {
        const NormalsResult r = EstimateNormals(nan_only, tree, p);
        EXPECT_EQ(r.undefined, 50u);
        EXPECT_EQ(CountNaN(r.curvature), 50u);
    }
}

TEST(Normals, BadParametersThrow) {
    const PointCloud c = test::RandomCloud(100, 20);
    const KdTree tree(c);
    EXPECT_THROW(EstimateNormals(c, tree, {.k = -1}), InvalidArgument);
    EXPECT_THROW(EstimateNormals(c, tree, {.k = 2}), InvalidArgument);
    EXPECT_THROW(EstimateNormals(c, tree, {.radius = -0.1f}), InvalidArgument);
    EXPECT_THROW(EstimateNormals(c, tree, {.radius = kNaN}), InvalidArgument);
    EXPECT_THROW(EstimateNormals(c, tree, {.radius = std::numeric_limits<float>::infinity()}),
                 InvalidArgument);
    EXPECT_THROW(EstimateNormals(c, tree, {.num_threads = -1}), InvalidArgument);
    // A tree built from another cloud.
    const PointCloud other = test::RandomCloud(100, 21);
    EXPECT_THROW(EstimateNormals(other, tree, {}), InvalidArgument);
    EXPECT_THROW(EstimateNormals(PointCloud(std::vector<Eigen::Vector3f>(c.points.begin(),
                                                                         c.points.begin() + 50)),
                                 tree, {}),
                 InvalidArgument);
    // The message names the value.
    try {
        EstimateNormals(c, tree, {.radius = -0.1f});
        ADD_FAILURE() << "no exception";
    } catch (const InvalidArgument& e) {
        EXPECT_NE(std::string(e.what()).find("-0.1"), std::string::npos) << e.what();
    }
}

TEST(Normals, SetNormalsMovesIntoTheCloud) {
    const Truth t = NoisyPlane({0.0f, 0.0f, 1.0f}, kTilted, 0.1f, 0.01f, 0.0f, 22);
    PointCloud c = t.cloud;
    const KdTree tree(c);
    NormalsResult r = EstimateNormals(c, tree, {.k = 8});
    const NormalsResult copy = r;
    SetNormals(c, std::move(r));
    EXPECT_EQ(c.normals, copy.normals);
    EXPECT_EQ(c.curvature, copy.curvature);
    c.Validate();
    EXPECT_THROW(SetNormals(c, NormalsResult{}), InvalidArgument);
}

// --- organized estimator ----------------------------------------------------------------------

// A tilted plane 1 m away, 1.5 mm range noise at 1 m (growing with z^2), 5% holes.
// Measured: mean 1.5 deg, p95 3.4 deg.
TEST(OrganizedNormals, NoisyTiltedPlane) {
    const Eigen::Vector3f n = Eigen::Vector3f(0.4f, -0.3f, -1.0f).normalized();
    const Truth t = OrganizedView(96, 72, 0.0015f, 0.05f, 23, PlaneHit({0.0f, 0.0f, 1.0f}, n));
    const NormalsResult r = EstimateNormalsOrganized(t.cloud, {});
    const ErrorStats e = AngleErrors(r, t.normals);
    EXPECT_GT(e.count, t.cloud.size() * 9 / 10);
    EXPECT_LT(e.mean, 2.2 * kDeg);
    EXPECT_LT(e.p95, 5.0 * kDeg);
    ExpectOrientedUnitNormals(t.cloud, r, Eigen::Vector3f::Zero());
    EXPECT_EQ(r.undefined, CountNaN(r.curvature));
}

// A sphere of radius 0.15 m at 0.8 m filling the frame. Measured: mean 1.2 deg, p95 3.1 deg.
TEST(OrganizedNormals, NoisySphere) {
    const Truth t = OrganizedView(96, 72, 0.0015f, 0.05f, 24, SphereHit({0.0f, 0.0f, 0.8f}, 0.15f));
    const NormalsResult r = EstimateNormalsOrganized(t.cloud, {});
    const ErrorStats e = AngleErrors(r, t.normals);
    EXPECT_GT(e.count, 1000u);
    EXPECT_LT(e.mean, 1.8 * kDeg);
    EXPECT_LT(e.p95, 4.5 * kDeg);
    ExpectOrientedUnitNormals(t.cloud, r, Eigen::Vector3f::Zero());
    // Curvature is positive on the sphere, about 0 on a noise-free plane.
    EXPECT_GT(std::accumulate(r.curvature.begin(), r.curvature.end(), 0.0,
                              [](double s, float c) { return std::isnan(c) ? s : s + c; }) /
                  static_cast<double>(e.count),
              1e-4);
    const Truth flat = OrganizedView(64, 48, 0.0f, 0.0f, 25,
                                     PlaneHit({0.0f, 0.0f, 1.0f}, -Eigen::Vector3f::UnitZ()));
    const NormalsResult f = EstimateNormalsOrganized(flat.cloud, {});
    EXPECT_EQ(f.undefined, 0u);
    EXPECT_LT(*std::max_element(f.curvature.begin(), f.curvature.end()), 1e-5f);
}

// A box-shaped foreground plane 20 cm in front of a background plane: the depth test keeps the
// two apart, so normals right at the outline are as good as elsewhere.
TEST(OrganizedNormals, DepthEdgesDoNotMixSurfaces) {
    const Eigen::Vector3f back_n = -Eigen::Vector3f::UnitZ();
    const Eigen::Vector3f front_n = Eigen::Vector3f(0.5f, 0.0f, -1.0f).normalized();
    auto back = PlaneHit({0.0f, 0.0f, 1.2f}, back_n);
    auto front = PlaneHit({0.0f, 0.0f, 1.0f}, front_n);
    auto scene = [&](const Eigen::Vector3f& ray, float& range, Eigen::Vector3f& normal) {
        if (std::abs(ray.x() / ray.z()) < 0.03f && std::abs(ray.y() / ray.z()) < 0.03f) {
            return front(ray, range, normal);
        }
        return back(ray, range, normal);
    };
    const Truth t = OrganizedView(80, 60, 0.0f, 0.0f, 26, scene);
    const NormalsResult r = EstimateNormalsOrganized(t.cloud, {});
    EXPECT_EQ(r.undefined, 0u);
    EXPECT_LT(AngleErrors(r, t.normals).max, 0.5 * kDeg);
    // Without the depth test (a huge threshold), the outline mixes both planes.
    const NormalsResult mixed = EstimateNormalsOrganized(t.cloud, {.max_depth_change = 1e3f});
    EXPECT_GT(AngleErrors(mixed, t.normals).max, 5.0 * kDeg);
}

TEST(OrganizedNormals, DepthDependentWindowAveragesMoreFarAway) {
    // A plane at 2 m, where the noise is 4 times that at 1 m: the window grows to
    // 2 * half_window and averages it out better (measured mean 2.1 deg against 3.6 deg).
    const Eigen::Vector3f n = Eigen::Vector3f(0.2f, 0.1f, -1.0f).normalized();
    const Truth t = OrganizedView(96, 72, 0.0015f, 0.0f, 27, PlaneHit({0.0f, 0.0f, 2.0f}, n));
    const ErrorStats fixed = AngleErrors(EstimateNormalsOrganized(t.cloud, {}), t.normals);
    const ErrorStats grown =
        AngleErrors(EstimateNormalsOrganized(t.cloud, {.depth_dependent_window = true}), t.normals);
    EXPECT_LT(grown.mean, 0.75 * fixed.mean);
}

TEST(OrganizedNormals, ThreadCountDoesNotChangeResults) {
    const Truth t =
        OrganizedView(160, 120, 0.0015f, 0.05f, 28, SphereHit({0.0f, 0.0f, 0.8f}, 0.2f));
    for (const bool grow : {false, true}) {
        OrganizedNormalParams p{.depth_dependent_window = grow, .num_threads = 1};
        const NormalsResult one = EstimateNormalsOrganized(t.cloud, p);
        p.num_threads = 0;
        ExpectBitIdentical(one, EstimateNormalsOrganized(t.cloud, p));
        p.num_threads = 2;
        ExpectBitIdentical(one, EstimateNormalsOrganized(t.cloud, p));
    }
}

TEST(OrganizedNormals, MaskComputesTheSameNormalsForItsPixelsOnly) {
    const Truth t =
        OrganizedView(160, 120, 0.0015f, 0.05f, 28, SphereHit({0.0f, 0.0f, 0.8f}, 0.2f));
    for (const bool grow : {false, true}) {
        OrganizedNormalParams p{.depth_dependent_window = grow};
        const NormalsResult all = EstimateNormalsOrganized(t.cloud, p);
        p.mask.assign(t.cloud.size(), 0);
        for (std::size_t i = 0; i < t.cloud.size(); i += 3) p.mask[i] = 1;
        const NormalsResult some = EstimateNormalsOrganized(t.cloud, p);
        for (std::size_t i = 0; i < t.cloud.size(); ++i) {
            if (p.mask[i] != 0 && std::isfinite(all.curvature[i])) {
                EXPECT_EQ(some.normals[i], all.normals[i]);
                EXPECT_EQ(some.curvature[i], all.curvature[i]);
            } else {
                EXPECT_TRUE(std::isnan(some.curvature[i]));
            }
        }
        p.mask.resize(5);
        EXPECT_THROW(EstimateNormalsOrganized(t.cloud, p), InvalidArgument);
    }
}

TEST(OrganizedNormals, ContractEmptyAndNaNOnly) {
    EXPECT_TRUE(EstimateNormalsOrganized(PointCloud{}, {}).normals.empty());
    PointCloud nan_only(std::vector<Eigen::Vector3f>(12, Eigen::Vector3f::Constant(kNaN)));
    nan_only.width = 4;
    nan_only.height = 3;
    const NormalsResult r = EstimateNormalsOrganized(nan_only, {});
    EXPECT_EQ(r.undefined, 12u);
    EXPECT_EQ(CountNaN(r.curvature), 12u);

    const PointCloud unorganized = test::RandomCloud(12, 29);
    EXPECT_THROW(EstimateNormalsOrganized(unorganized, {}), InvalidArgument);
    EXPECT_THROW(EstimateNormalsOrganized(nan_only, {.half_window = 0}), InvalidArgument);
    EXPECT_THROW(EstimateNormalsOrganized(nan_only, {.max_depth_change = 0.0f}), InvalidArgument);
    EXPECT_THROW(EstimateNormalsOrganized(nan_only, {.max_depth_change = kNaN}), InvalidArgument);
    EXPECT_THROW(EstimateNormalsOrganized(nan_only, {.num_threads = -2}), InvalidArgument);
}

}  // namespace
}  // namespace multicue

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Eigenvalues>

#include "multicue/core/exceptions.hpp"
#include "multicue/segmentation/cylinder_least_squares.hpp"
#include "multicue/segmentation/sac_circle.hpp"
#include "multicue/segmentation/sac_cylinder.hpp"
#include "multicue/segmentation/sac_internal.hpp"
#include "multicue/segmentation/sac_line.hpp"
#include "multicue/segmentation/sac_plane.hpp"
#include "multicue/segmentation/sac_sphere.hpp"
#include "multicue/segmentation/sample_consensus.hpp"

namespace multicue {
namespace {

constexpr float kSigma = 0.002f;  // sensor noise [m]
constexpr float kDeg = std::numbers::pi_v<float> / 180.0f;
const float kNaN = std::numeric_limits<float>::quiet_NaN();

float AngleDeg(const Eigen::Vector3f& a, const Eigen::Vector3f& b) {
    return std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.0f, 1.0f)) / kDeg;
}
// Angle between two lines (sign-free) [deg].
float LineAngleDeg(const Eigen::Vector3f& a, const Eigen::Vector3f& b) {
    return std::min(AngleDeg(a, b), AngleDeg(a, -b));
}
float DistanceToLine(const Eigen::Vector3f& p, const Eigen::Vector3f& point,
                     const Eigen::Vector3f& unit_dir) {
    return (p - point).cross(unit_dir).norm();
}

// Unit vectors orthogonal to n (and to each other).
std::pair<Eigen::Vector3f, Eigen::Vector3f> Basis(const Eigen::Vector3f& n) {
    const Eigen::Vector3f u = n.unitOrthogonal();
    return {u, n.cross(u)};
}

// Synthetic data: the first `num_true` points are on the model, the rest are outliers.
struct Scene {
    PointCloud cloud;
    std::size_t num_true = 0;
};

class Generator {
  public:
    explicit Generator(std::uint32_t seed) : rng_(seed) {}
    float Uniform(float lo, float hi) {
        return std::uniform_real_distribution<float>(lo, hi)(rng_);
    }
    float Gauss(float sigma) { return std::normal_distribution<float>(0.0f, sigma)(rng_); }
    Eigen::Vector3f Noise(float sigma) { return {Gauss(sigma), Gauss(sigma), Gauss(sigma)}; }
    Eigen::Vector3f UnitVector() {
        Eigen::Vector3f v;
        do {
            v = Noise(1.0f);
        } while (v.norm() < 1e-3f);
        return v.normalized();
    }
    // Outliers uniform in the box centre +- half, with random normals when the cloud has normals.
    void AddOutliers(PointCloud& c, std::size_t n, const Eigen::Vector3f& centre, float half) {
        const bool with_normals = c.HasNormals();
        for (std::size_t i = 0; i < n; ++i) {
            c.points.emplace_back(centre + Eigen::Vector3f(Uniform(-half, half),
                                                           Uniform(-half, half),
                                                           Uniform(-half, half)));
            if (with_normals) c.normals.push_back(UnitVector());
        }
        c.SetUnorganized();
    }

  private:
    std::mt19937 rng_;
};

std::size_t CountBelow(const Indices& inliers, std::size_t n) {
    return static_cast<std::size_t>(
        std::count_if(inliers.begin(), inliers.end(), [n](Index i) { return i < n; }));
}

// Most true points are inliers and few outliers are.
void ExpectInliersCloseToTruth(const Indices& inliers, std::size_t num_true,
                               std::size_t max_false) {
    const std::size_t hits = CountBelow(inliers, num_true);
    EXPECT_GE(hits, num_true * 97 / 100);
    EXPECT_LE(inliers.size() - hits, max_false);
}

// ---- Scenes ----

const Eigen::Vector3f kPlaneNormal = Eigen::Vector3f(0.3f, -0.2f, 0.93f).normalized();
const Eigen::Vector3f kPlanePoint(0.1f, 0.2f, -0.8f);

Scene PlaneScene(std::size_t n_in, std::size_t n_out, std::uint32_t seed = 1) {
    Generator g(seed);
    Scene s;
    const auto [u, v] = Basis(kPlaneNormal);
    for (std::size_t i = 0; i < n_in; ++i) {
        s.cloud.points.emplace_back(kPlanePoint + g.Uniform(-0.5f, 0.5f) * u +
                                    g.Uniform(-0.5f, 0.5f) * v + g.Noise(kSigma));
    }
    s.num_true = n_in;
    g.AddOutliers(s.cloud, n_out, kPlanePoint, 0.5f);
    return s;
}

// A wall x = 1 (2 m x 2 m) and a smaller table top z = 0.7, both with normals facing the origin.
Scene WallAndTable(std::size_t n_wall, std::size_t n_table, std::uint32_t seed = 2) {
    Generator g(seed);
    Scene s;
    for (std::size_t i = 0; i < n_table; ++i) {
        s.cloud.points.emplace_back(
            Eigen::Vector3f(g.Uniform(0.2f, 0.9f), g.Uniform(-0.4f, 0.4f), 0.7f) + g.Noise(kSigma));
        s.cloud.normals.emplace_back(0.0f, 0.0f, 1.0f);
    }
    s.num_true = n_table;
    for (std::size_t i = 0; i < n_wall; ++i) {
        s.cloud.points.emplace_back(
            Eigen::Vector3f(1.0f, g.Uniform(-1.0f, 1.0f), g.Uniform(0.0f, 2.0f)) + g.Noise(kSigma));
        s.cloud.normals.emplace_back(-1.0f, 0.0f, 0.0f);
    }
    s.cloud.SetUnorganized();
    return s;
}

const Eigen::Vector3f kCylPoint(0.3f, 0.1f, 0.6f);
const Eigen::Vector3f kCylAxis = Eigen::Vector3f(0.1f, 0.2f, 1.0f).normalized();
constexpr float kCylRadius = 0.05f;

void AddCylinder(Generator& g, PointCloud& c, std::size_t n, const Eigen::Vector3f& point,
                 const Eigen::Vector3f& axis, float radius, float length) {
    const auto [u, v] = Basis(axis);
    for (std::size_t i = 0; i < n; ++i) {
        // Two thirds of the circumference, as a single view sees it.
        const float phi = g.Uniform(0.0f, 4.2f);
        const Eigen::Vector3f radial = std::cos(phi) * u + std::sin(phi) * v;
        c.points.emplace_back(point + g.Uniform(-0.5f, 0.5f) * length * axis + radius * radial +
                              g.Noise(kSigma));
        c.normals.emplace_back((radial + g.Noise(0.03f)).normalized());
    }
}

Scene CylinderScene(std::size_t n_in, std::size_t n_out, std::uint32_t seed = 3) {
    Generator g(seed);
    Scene s;
    AddCylinder(g, s.cloud, n_in, kCylPoint, kCylAxis, kCylRadius, 0.25f);
    s.num_true = n_in;
    g.AddOutliers(s.cloud, n_out, kCylPoint, 0.2f);
    return s;
}

// ---- Eq. (4.6) ----

// The normal angles of the scoring: the polynomial acos against the library's, over [0, 1].
TEST(SampleConsensus, PolynomialAcosIsAcosToAFloatsRounding) {
    double worst = 0.0;
    for (int k = 0; k <= 1000000; ++k) {
        const float x = static_cast<float>(k) / 1000000.0f;
        worst = std::max(
            worst, std::abs(double{sac_internal::AcosUnit(x)} - std::acos(static_cast<double>(x))));
    }
    EXPECT_LT(worst, 2e-7);
    EXPECT_EQ(sac_internal::AcosUnit(1.0f), 0.0f);
    EXPECT_NEAR(sac_internal::AcosUnit(0.0f), std::numbers::pi / 2.0, 1e-7);
}

TEST(SampleConsensus, AdaptiveIterationCountFollowsEq46) {
    // log(0.01) / log(1 - 0.5^3) = 34.49 -> 35.
    EXPECT_EQ(AdaptiveIterationCount(0.99, 0.5, 3), 35);
    // log(0.05) / log(1 - 0.8^2) = 2.93 -> 3.
    EXPECT_EQ(AdaptiveIterationCount(0.95, 0.8, 2), 3);
    EXPECT_EQ(AdaptiveIterationCount(0.99, 1.0, 4), 1);
    EXPECT_EQ(AdaptiveIterationCount(0.99, 0.0, 3), std::numeric_limits<int>::max());
    EXPECT_EQ(AdaptiveIterationCount(0.99, 1e-9, 4), std::numeric_limits<int>::max());
    EXPECT_GT(AdaptiveIterationCount(0.999, 0.5, 3), AdaptiveIterationCount(0.99, 0.5, 3));
    EXPECT_THROW(AdaptiveIterationCount(1.0, 0.5, 3), InvalidArgument);
    EXPECT_THROW(AdaptiveIterationCount(0.99, 0.5, 0), InvalidArgument);
}

TEST(SampleConsensus, AdaptiveIterationsFarBelowCapWithManyInliers) {
    const Scene s = PlaneScene(900, 100);
    const PlaneFit fit = FitPlane(s.cloud, {}, {.sac = {.max_iterations = 10000}});
    ASSERT_TRUE(fit.found);
    EXPECT_TRUE(fit.converged);
    EXPECT_LT(fit.iterations, 50);  // T = 4 for w = 0.9, n = 3
    EXPECT_GE(fit.iterations, 1);
}

TEST(SampleConsensus, StopsAtMaxIterationsWhenUnconverged) {
    const Scene s = PlaneScene(100, 900);
    const PlaneFit fit = FitPlane(s.cloud, {}, {.sac = {.max_iterations = 5}});
    EXPECT_EQ(fit.iterations, 5);
    EXPECT_FALSE(fit.converged);
}

// ---- Recovery of known models: 2 mm noise, 30% outliers ----

class PlaneRecovery : public ::testing::TestWithParam<SacMethod> {};

TEST_P(PlaneRecovery, RecoversPlane) {
    const Scene s = PlaneScene(700, 300);
    const PlaneFit fit =
        FitPlane(s.cloud, {}, {.sac = {.method = GetParam(), .distance_threshold = 0.01f}});
    ASSERT_TRUE(fit.found);
    // Oriented towards the sensor origin (0, 0, 0), which is above the plane.
    Eigen::Vector3f n = kPlaneNormal;
    float d = -n.dot(kPlanePoint);
    if (d < 0.0f) {
        n = -n;
        d = -d;
    }
    EXPECT_LT(AngleDeg(fit.plane.head<3>(), n), 1.0f);
    EXPECT_NEAR(fit.plane.head<3>().norm(), 1.0f, 1e-5f);
    EXPECT_NEAR(fit.plane[3], d, 0.003f);
    ExpectInliersCloseToTruth(fit.inliers, s.num_true, 20);
    EXPECT_GT(fit.rmse, 0.5f * kSigma);
    EXPECT_LT(fit.rmse, 2.0f * kSigma);
}

INSTANTIATE_TEST_SUITE_P(Methods, PlaneRecovery,
                         ::testing::Values(SacMethod::kRansac, SacMethod::kMsac),
                         [](const ::testing::TestParamInfo<SacMethod>& param_info) {
                             return param_info.param == SacMethod::kRansac ? "Ransac" : "Msac";
                         });

TEST(SampleConsensus, RecoversLine) {
    Generator g(4);
    PointCloud c;
    const Eigen::Vector3f dir = Eigen::Vector3f(1.0f, 2.0f, 0.5f).normalized();
    const Eigen::Vector3f p0(0.1f, 0.0f, 0.3f);
    for (int i = 0; i < 700; ++i)
        c.points.emplace_back(p0 + g.Uniform(-0.5f, 0.5f) * dir + g.Noise(kSigma));
    g.AddOutliers(c, 300, p0, 0.6f);
    const LineFit fit = FitLine(c, {}, {.sac = {.distance_threshold = 0.01f}});
    ASSERT_TRUE(fit.found);
    EXPECT_LT(AngleDeg(fit.direction, dir), 1.0f);  // canonical sign: largest component > 0
    EXPECT_NEAR(fit.direction.norm(), 1.0f, 1e-5f);
    EXPECT_LT(DistanceToLine(p0, fit.point, fit.direction), 0.003f);
    EXPECT_LT(fit.point.norm() - p0.norm(), 0.05f);  // the inliers' middle, not somewhere far
    ExpectInliersCloseToTruth(fit.inliers, 700, 10);
}

TEST(SampleConsensus, RecoversCircle2d) {
    Generator g(5);
    PointCloud c;
    const Eigen::Vector2f centre(0.2f, -0.1f);
    const float radius = 0.3f;
    for (int i = 0; i < 700; ++i) {
        const float phi = g.Uniform(0.0f, 2.0f * std::numbers::pi_v<float>);
        c.points.emplace_back(centre.x() + radius * std::cos(phi) + g.Gauss(kSigma),
                              centre.y() + radius * std::sin(phi) + g.Gauss(kSigma),
                              g.Uniform(0.0f, 0.2f));  // z plays no part
    }
    g.AddOutliers(c, 300, Eigen::Vector3f(0.2f, -0.1f, 0.1f), 0.5f);
    const Circle2dFit fit = FitCircle2d(c, {}, {.sac = {.distance_threshold = 0.01f}});
    ASSERT_TRUE(fit.found);
    EXPECT_LT((fit.center - centre).norm(), 0.003f);
    EXPECT_NEAR(fit.radius, radius, 0.003f);
    ExpectInliersCloseToTruth(fit.inliers, 700, 30);
}

TEST(SampleConsensus, RecoversCircle3d) {
    Generator g(6);
    PointCloud c;
    const Eigen::Vector3f centre(0.1f, 0.2f, 0.5f);
    const Eigen::Vector3f normal = Eigen::Vector3f(0.2f, 0.3f, 0.9f).normalized();
    const float radius = 0.15f;
    const auto [u, v] = Basis(normal);
    for (int i = 0; i < 700; ++i) {
        const float phi = g.Uniform(0.0f, 2.0f * std::numbers::pi_v<float>);
        c.points.emplace_back(centre + radius * (std::cos(phi) * u + std::sin(phi) * v) +
                              g.Noise(kSigma));
    }
    g.AddOutliers(c, 300, centre, 0.3f);
    const Circle3dFit fit = FitCircle3d(c, {}, {.sac = {.distance_threshold = 0.01f}});
    ASSERT_TRUE(fit.found);
    EXPECT_LT((fit.center - centre).norm(), 0.003f);
    EXPECT_NEAR(fit.radius, radius, 0.003f);
    EXPECT_LT(LineAngleDeg(fit.normal, normal), 2.0f);
    EXPECT_GT(fit.normal.dot(c.sensor_origin - fit.center), 0.0f);  // faces the viewpoint
    ExpectInliersCloseToTruth(fit.inliers, 700, 10);
}

TEST(SampleConsensus, RecoversSphereFromOneSidedView) {
    Generator g(7);
    PointCloud c;
    const Eigen::Vector3f centre(0.2f, -0.1f, 0.8f);
    const float radius = 0.12f;
    while (c.points.size() < 700) {
        const Eigen::Vector3f dir = g.UnitVector();
        if (dir.dot(-centre) <= 0.0f) continue;  // only the half facing the sensor
        c.points.emplace_back(centre + radius * dir + g.Noise(kSigma));
    }
    g.AddOutliers(c, 300, centre, 0.25f);
    const SphereFit fit = FitSphere(c, {}, {.sac = {.distance_threshold = 0.01f}});
    ASSERT_TRUE(fit.found);
    EXPECT_LT((fit.center - centre).norm(), 0.003f);
    EXPECT_NEAR(fit.radius, radius, 0.003f);
    ExpectInliersCloseToTruth(fit.inliers, 700, 25);
}

// Half a sphere facing the sensor with noisy outward normals, and `outliers` points with random
// normals around it.
PointCloud OrientedSphereScene(Generator& g, const Eigen::Vector3f& centre, float radius,
                               int points, int outliers) {
    PointCloud c;
    while (static_cast<int>(c.points.size()) < points) {
        const Eigen::Vector3f dir = g.UnitVector();
        if (dir.dot(-centre) <= 0.0f) continue;
        c.points.emplace_back(centre + radius * dir + g.Noise(kSigma));
        c.normals.emplace_back((dir + g.Noise(0.03f)).normalized());
    }
    g.AddOutliers(c, outliers, centre, 0.25f);
    return c;
}

TEST(SampleConsensus, OrientedSamplesRecoverTheSphereWithFewerSamples) {
    Generator g(21);
    const Eigen::Vector3f centre(-0.15f, 0.05f, 0.9f);
    const float radius = 0.08f;
    // 40 % inliers: a sample of 4 points is clean once in 39 draws, a pair once in 6.
    const PointCloud c = OrientedSphereScene(g, centre, radius, 400, 600);
    SphereFitParams p{.sac = {.distance_threshold = 0.008f, .max_iterations = 2000}};
    const SphereFit four = FitSphere(c, {}, p);
    p.oriented_samples = true;
    const SphereFit two = FitSphere(c, {}, p);
    ASSERT_TRUE(four.found);
    ASSERT_TRUE(two.found);
    EXPECT_LT((two.center - centre).norm(), 0.003f);
    EXPECT_NEAR(two.radius, radius, 0.003f);
    ExpectInliersCloseToTruth(two.inliers, 400, 25);
    EXPECT_TRUE(two.converged);
    EXPECT_LT(two.iterations * 3, four.iterations);
    // The same seed gives the same sphere.
    const SphereFit again = FitSphere(c, {}, p);
    EXPECT_EQ(again.center, two.center);
    EXPECT_EQ(again.inliers, two.inliers);
}

TEST(SampleConsensus, OrientedSphereSamplesNeedNormalsAndNonParallelOnes) {
    Generator g(22);
    PointCloud c = OrientedSphereScene(g, Eigen::Vector3f(0.0f, 0.0f, 1.0f), 0.1f, 100, 0);
    PointCloud bare = c;
    bare.normals.clear();
    EXPECT_THROW(FitSphere(bare, {}, {.oriented_samples = true}), DataError);
    EXPECT_TRUE(FitSphere(bare, {}, {}).found);  // four points need no normals
    // Parallel normals (a plane) give no centre: every pair is degenerate.
    PointCloud flat;
    for (int i = 0; i < 50; ++i) {
        flat.points.emplace_back(0.01f * static_cast<float>(i % 10),
                                 0.01f * static_cast<float>(i / 10), 1.0f);
        flat.normals.emplace_back(0.0f, 0.0f, -1.0f);
    }
    flat.SetUnorganized();
    const SphereFit none =
        FitSphere(flat, {}, {.sac = {.max_iterations = 50}, .oriented_samples = true});
    EXPECT_FALSE(none.found);
    EXPECT_EQ(none.iterations, 50);
    // Two usable points are enough to try.
    EXPECT_FALSE(FitSphere(c, {0}, {.oriented_samples = true}).found);
    EXPECT_TRUE(FitSphere(c, {0, 1, 2, 3, 4, 5, 6, 7, 8, 9}, {.oriented_samples = true}).found);
}

TEST(SampleConsensus, RecoversCylinderFromPointsWithNormals) {
    const Scene s = CylinderScene(700, 300);
    const CylinderFit fit = FitCylinder(s.cloud, {}, {.sac = {.distance_threshold = 0.01f}});
    ASSERT_TRUE(fit.found);
    EXPECT_LT(AngleDeg(fit.axis, kCylAxis), 2.0f);  // canonical sign: largest component > 0
    EXPECT_NEAR(fit.radius, kCylRadius, 0.003f);
    EXPECT_LT(DistanceToLine(kCylPoint, fit.point, fit.axis), 0.003f);
    EXPECT_LT((fit.point - kCylPoint).norm(), 0.02f);  // middle of the inliers
    ExpectInliersCloseToTruth(fit.inliers, s.num_true, 30);
}

// A lying cylinder (axis along x, on a table with normal z) refined from a start with the axis
// turned 5 degrees within the table: each freedom moves only what it allows.
TEST(SampleConsensus, CylinderRefinementRespectsTheAxisFreedom) {
    Generator g(7);
    PointCloud c;
    const Eigen::Vector3f point(0.2f, -0.1f, 0.5f);
    AddCylinder(g, c, 600, point, Eigen::Vector3f::UnitX(), 0.04f, 0.3f);
    c.SetUnorganized();
    Indices all(c.size());
    for (std::size_t i = 0; i < all.size(); ++i) all[i] = static_cast<Index>(i);
    const double turn = 5.0 * std::numbers::pi / 180.0;
    const Eigen::Vector3d start_axis(std::cos(turn), std::sin(turn), 0.0);
    const CylinderEstimate start{point.cast<double>() + Eigen::Vector3d(0.0, 0.005, -0.004),
                                 start_axis, 0.035};

    CylinderEstimate free = start;
    ASSERT_TRUE(RefineCylinder(c, all, {.freedom = CylinderAxisFreedom::kFree}, free));
    EXPECT_LT(LineAngleDeg(free.axis.cast<float>(), Eigen::Vector3f::UnitX()), 0.5f);
    EXPECT_NEAR(free.radius, 0.04, 0.002);
    EXPECT_LT(DistanceToLine(point, free.point.cast<float>(), free.axis.cast<float>()), 0.002f);

    CylinderEstimate about_up = start;
    ASSERT_TRUE(RefineCylinder(
        c, all, {.freedom = CylinderAxisFreedom::kAboutUp, .up = Eigen::Vector3d::UnitZ()},
        about_up));
    EXPECT_NEAR(about_up.axis.z(), 0.0, 1e-12);  // still level
    EXPECT_LT(LineAngleDeg(about_up.axis.cast<float>(), Eigen::Vector3f::UnitX()), 0.5f);
    EXPECT_NEAR(about_up.radius, 0.04, 0.002);

    CylinderEstimate fixed = start;
    ASSERT_TRUE(RefineCylinder(c, all, {.freedom = CylinderAxisFreedom::kFixed}, fixed));
    EXPECT_EQ(fixed.axis, start_axis);
    // The best cylinder with a wrong axis still lowers the cost below the start's.
    auto cost = [&](const CylinderEstimate& x) {
        double sum = 0.0;
        for (Index i : all) {
            const Eigen::Vector3d w = c.points[i].cast<double>() - x.point;
            const double e = (w - w.dot(x.axis) * x.axis).norm() - x.radius;
            sum += e * e;
        }
        return sum;
    };
    EXPECT_LT(cost(fixed), cost(start));
    EXPECT_LT(cost(free), cost(fixed));
}

TEST(SampleConsensus, CylinderRefinementContract) {
    const Scene s = CylinderScene(50, 0);
    const CylinderEstimate start{kCylPoint.cast<double>(), kCylAxis.cast<double>(), kCylRadius};
    CylinderEstimate x = start;
    const Indices some{0, 1, 2, 3, 4, 5};
    EXPECT_THROW(RefineCylinder(s.cloud, some, {.max_iterations = -1}, x), InvalidArgument);
    EXPECT_THROW(RefineCylinder(
                     s.cloud, some,
                     {.freedom = CylinderAxisFreedom::kAboutUp, .up = Eigen::Vector3d::Zero()}, x),
                 InvalidArgument);
    EXPECT_THROW(RefineCylinder(s.cloud, Indices{0, 50}, {}, x), InvalidArgument);
    // No points: nothing to improve. A non-finite start is refused and left as it is.
    EXPECT_TRUE(RefineCylinder(s.cloud, Indices{}, {}, x));
    EXPECT_EQ(x.point, start.point);
    EXPECT_EQ(x.radius, start.radius);
    x.radius = std::numeric_limits<double>::quiet_NaN();
    EXPECT_FALSE(RefineCylinder(s.cloud, some, {}, x));
    EXPECT_TRUE(std::isnan(x.radius));
}

TEST(SampleConsensus, CylinderAxisConstraintAndRadiusLimits) {
    // A large lying cylinder and a smaller upright one: the constraint picks the upright one.
    Generator g(8);
    PointCloud c;
    const Eigen::Vector3f up = Eigen::Vector3f::UnitZ();
    AddCylinder(g, c, 300, Eigen::Vector3f(0.0f, 0.3f, 0.1f), up, 0.04f, 0.2f);
    AddCylinder(g, c, 900, Eigen::Vector3f(0.0f, -0.3f, 0.1f), Eigen::Vector3f::UnitX(), 0.08f,
                0.5f);
    c.SetUnorganized();
    const CylinderFit any = FitCylinder(c, {}, {.sac = {.distance_threshold = 0.01f}});
    ASSERT_TRUE(any.found);
    EXPECT_NEAR(any.radius, 0.08f, 0.003f);
    const CylinderFit upright = FitCylinder(
        c, {}, {.sac = {.distance_threshold = 0.01f}, .axis = up, .max_angle = 10.0f * kDeg});
    ASSERT_TRUE(upright.found);
    EXPECT_NEAR(upright.radius, 0.04f, 0.003f);
    EXPECT_LT(AngleDeg(upright.axis, up), 2.0f);  // oriented along the constraint
    ExpectInliersCloseToTruth(upright.inliers, 300, 5);
    // Radius limits exclude the large one as well. A thinner cylinder inside the large one,
    // touching it along a line, is then geometrically as good as the small one; the normals tell
    // them apart.
    const CylinderFit small =
        FitCylinder(c, {},
                    {.sac = {.distance_threshold = 0.01f, .normal_distance_weight = 0.05f},
                     .min_radius = 0.02f,
                     .max_radius = 0.06f});
    ASSERT_TRUE(small.found);
    EXPECT_NEAR(small.radius, 0.04f, 0.003f);
}

// ---- Constraints, subsets and normals ----

TEST(SampleConsensus, HorizontalConstraintFindsTheTableNotTheWall) {
    const Scene s = WallAndTable(2000, 500);
    const PlaneFitParams plain{.sac = {.distance_threshold = 0.01f}};
    const PlaneFit wall = FitPlane(s.cloud, {}, plain);
    ASSERT_TRUE(wall.found);
    // The dominant plane is the wall; its normal faces the sensor at the origin.
    EXPECT_LT(AngleDeg(wall.plane.head<3>(), -Eigen::Vector3f::UnitX()), 1.0f);
    EXPECT_NEAR(wall.plane[3], 1.0f, 0.003f);

    PlaneFitParams horizontal = plain;
    horizontal.axis = Eigen::Vector3f(0.0f, 0.0f, 2.0f);  // any length
    horizontal.max_angle = 10.0f * kDeg;
    const PlaneFit table = FitPlane(s.cloud, {}, horizontal);
    ASSERT_TRUE(table.found);
    EXPECT_LT(AngleDeg(table.plane.head<3>(), Eigen::Vector3f::UnitZ()), 1.0f);
    EXPECT_NEAR(table.plane[3], -0.7f, 0.003f);
    // The wall's points at table height lie on the table's plane too (about 1% of the wall).
    ExpectInliersCloseToTruth(table.inliers, s.num_true, 50);

    PlaneFitParams vertical = horizontal;
    vertical.axis_mode = PlaneAxisMode::kPerpendicular;
    const PlaneFit wall2 = FitPlane(s.cloud, {}, vertical);
    ASSERT_TRUE(wall2.found);
    EXPECT_LT(AngleDeg(wall2.plane.head<3>(), -Eigen::Vector3f::UnitX()), 1.0f);
}

TEST(SampleConsensus, NormalDistanceWeightRejectsPointsOfOtherSurfaces) {
    const Scene s = WallAndTable(2000, 500);
    PlaneFitParams p{.sac = {.distance_threshold = 0.01f},
                     .axis = Eigen::Vector3f::UnitZ(),
                     .max_angle = 10.0f * kDeg};
    const PlaneFit geometric = FitPlane(s.cloud, {}, p);
    ASSERT_TRUE(geometric.found);
    EXPECT_GT(geometric.inliers.size() - CountBelow(geometric.inliers, s.num_true), 5u);
    p.sac.normal_distance_weight = 0.1f;
    const PlaneFit with_normals = FitPlane(s.cloud, {}, p);
    ASSERT_TRUE(with_normals.found);
    EXPECT_NEAR(with_normals.plane[3], -0.7f, 0.003f);
    // Wall points at table height have normals 90 degrees off: 0.1 * pi/2 > threshold.
    EXPECT_EQ(CountBelow(with_normals.inliers, s.num_true), with_normals.inliers.size());
    EXPECT_GE(with_normals.inliers.size(), s.num_true * 97 / 100);
}

TEST(SampleConsensus, WorksOnTheGivenSubsetOnly) {
    const Scene s = WallAndTable(2000, 500);
    Indices table(s.num_true);
    for (std::size_t i = 0; i < table.size(); ++i) table[i] = static_cast<Index>(i);
    const PlaneFit fit = FitPlane(s.cloud, table, {.sac = {.distance_threshold = 0.01f}});
    ASSERT_TRUE(fit.found);
    // Unconstrained, the normal faces the sensor at the origin, below the table.
    EXPECT_LT(AngleDeg(fit.plane.head<3>(), -Eigen::Vector3f::UnitZ()), 1.0f);
    EXPECT_NEAR(fit.plane[3], 0.7f, 0.003f);
    EXPECT_EQ(CountBelow(fit.inliers, s.num_true), fit.inliers.size());
    EXPECT_GE(fit.inliers.size(), s.num_true * 97 / 100);
    EXPECT_TRUE(std::is_sorted(fit.inliers.begin(), fit.inliers.end()));
}

TEST(SampleConsensus, NanPointsAreIgnored) {
    Scene s = PlaneScene(700, 300);
    // Interleave invalid points: NaN and infinite coordinates.
    const float inf = std::numeric_limits<float>::infinity();
    for (std::size_t i = 0; i < 100; ++i) {
        s.cloud.points.emplace_back(i % 2 == 0 ? Eigen::Vector3f(kNaN, 0.0f, 0.0f)
                                               : Eigen::Vector3f(0.0f, inf, 0.0f));
    }
    s.cloud.points[10] = Eigen::Vector3f::Constant(kNaN);
    s.cloud.SetUnorganized();
    const PlaneFit fit = FitPlane(s.cloud, {}, {.sac = {.distance_threshold = 0.01f}});
    ASSERT_TRUE(fit.found);
    for (Index i : fit.inliers) EXPECT_TRUE(s.cloud.points[i].allFinite()) << i;
    EXPECT_LT(LineAngleDeg(fit.plane.head<3>(), kPlaneNormal), 1.0f);
    EXPECT_TRUE(fit.plane.allFinite());

    PointCloud all_nan(std::vector<Eigen::Vector3f>(50, Eigen::Vector3f::Constant(kNaN)));
    const PlaneFit none = FitPlane(all_nan, {}, {});
    EXPECT_FALSE(none.found);
    EXPECT_TRUE(none.inliers.empty());
    EXPECT_EQ(none.iterations, 0);
}

// ---- Oracles ----

TEST(SampleConsensus, RefinedPlaneIsThePcaPlaneOfItsInliers) {
    const Scene s = PlaneScene(700, 300);
    const PlaneFit fit = FitPlane(s.cloud, {}, {.sac = {.distance_threshold = 0.01f}});
    ASSERT_TRUE(fit.found);
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (Index i : fit.inliers) mean += s.cloud.points[i].cast<double>();
    mean /= static_cast<double>(fit.inliers.size());
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (Index i : fit.inliers) {
        const Eigen::Vector3d d = s.cloud.points[i].cast<double>() - mean;
        cov += d * d.transpose();
    }
    const Eigen::Vector3d n =
        Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(cov).eigenvectors().col(0);
    EXPECT_LT(LineAngleDeg(fit.plane.head<3>(), n.cast<float>()), 0.01f);
    // The plane passes through the centroid of its inliers.
    EXPECT_NEAR(fit.plane.head<3>().cast<double>().dot(mean) + fit.plane[3], 0.0, 1e-5);
}

TEST(SampleConsensus, RefinedSphereIsStationaryForGeometricLeastSquares) {
    Generator g(9);
    PointCloud c;
    const Eigen::Vector3f centre(-0.1f, 0.3f, 1.0f);
    for (int i = 0; i < 500; ++i)
        c.points.emplace_back(centre + 0.1f * g.UnitVector() + g.Noise(kSigma));
    g.AddOutliers(c, 200, centre, 0.2f);
    const SphereFit fit = FitSphere(c, {}, {.sac = {.distance_threshold = 0.008f}});
    ASSERT_TRUE(fit.found);
    // At the minimum of sum (|p - c| - r)^2: the residuals sum to zero (d/dr) and so do the
    // residual-weighted radial directions (d/dc).
    const Eigen::Vector3d cd = fit.center.cast<double>();
    double sum_e = 0.0;
    Eigen::Vector3d grad = Eigen::Vector3d::Zero();
    for (Index i : fit.inliers) {
        const Eigen::Vector3d w = c.points[i].cast<double>() - cd;
        const double e = w.norm() - fit.radius;
        sum_e += e;
        grad += e * w.normalized();
    }
    const double n = static_cast<double>(fit.inliers.size());
    EXPECT_LT(std::abs(sum_e / n), 1e-5);
    EXPECT_LT(grad.norm() / n, 1e-5);
}

TEST(SampleConsensus, ExactModelsAreRecoveredExactly) {
    PointCloud c;
    for (int i = 0; i < 12; ++i) {
        const float phi = 0.5f * static_cast<float>(i);
        c.points.emplace_back(1.0f + 0.25f * std::cos(phi), -2.0f + 0.25f * std::sin(phi), 0.0f);
    }
    c.SetUnorganized();
    const Circle2dFit circle = FitCircle2d(c, {}, {.sac = {.distance_threshold = 1e-4f}});
    ASSERT_TRUE(circle.found);
    EXPECT_EQ(circle.inliers.size(), 12u);
    EXPECT_LT((circle.center - Eigen::Vector2f(1.0f, -2.0f)).norm(), 1e-5f);
    EXPECT_NEAR(circle.radius, 0.25f, 1e-5f);
    EXPECT_LT(circle.rmse, 1e-5f);
    // The same points as a 3D circle, a plane, and (with only three) a plane with 3 inliers.
    const Circle3dFit circle3 = FitCircle3d(c, {}, {.sac = {.distance_threshold = 1e-4f}});
    ASSERT_TRUE(circle3.found);
    EXPECT_LT(LineAngleDeg(circle3.normal, Eigen::Vector3f::UnitZ()), 0.01f);
    EXPECT_NEAR(circle3.radius, 0.25f, 1e-5f);
    const PlaneFit plane = FitPlane(c, {0, 3, 7}, {.sac = {.distance_threshold = 1e-4f}});
    ASSERT_TRUE(plane.found);
    EXPECT_EQ(plane.inliers.size(), 3u);
    EXPECT_LT(LineAngleDeg(plane.plane.head<3>(), Eigen::Vector3f::UnitZ()), 0.01f);
}

// ---- Determinism ----

TEST(SampleConsensus, SameSeedGivesIdenticalResults) {
    const Scene s = CylinderScene(700, 300);
    const CylinderFitParams p{.sac = {.distance_threshold = 0.01f, .seed = 42}};
    const CylinderFit a = FitCylinder(s.cloud, {}, p);
    const CylinderFit b = FitCylinder(s.cloud, {}, p);
    ASSERT_TRUE(a.found);
    EXPECT_EQ(a.point, b.point);
    EXPECT_EQ(a.axis, b.axis);
    EXPECT_EQ(a.radius, b.radius);
    EXPECT_EQ(a.inliers, b.inliers);
    EXPECT_EQ(a.iterations, b.iterations);
    EXPECT_EQ(a.rmse, b.rmse);
}

TEST(SampleConsensus, ThreadCountNeverChangesTheResult) {
    // Enough points for the parallel path, and few inliers so that many batches are scored.
    const Scene s = PlaneScene(3000, 5000, 11);
    PlaneFitParams p{.sac = {.distance_threshold = 0.01f, .seed = 7, .num_threads = 1}};
    const PlaneFit serial = FitPlane(s.cloud, {}, p);
    ASSERT_TRUE(serial.found);
    EXPECT_GT(serial.iterations, 20);
    for (int threads : {2, 3, 4, 0}) {
        p.sac.num_threads = threads;
        const PlaneFit par = FitPlane(s.cloud, {}, p);
        EXPECT_EQ(par.plane, serial.plane) << threads;
        EXPECT_EQ(par.inliers, serial.inliers) << threads;
        EXPECT_EQ(par.iterations, serial.iterations) << threads;
        EXPECT_EQ(par.converged, serial.converged) << threads;
        EXPECT_EQ(par.rmse, serial.rmse) << threads;
    }
    // Mostly inliers: Eq. (4.6) stops after a few samples, inside the first parallel batch.
    const Scene easy = PlaneScene(5400, 600, 13);
    p.sac.num_threads = 1;
    const PlaneFit easy_serial = FitPlane(easy.cloud, {}, p);
    p.sac.num_threads = 3;
    const PlaneFit easy_par = FitPlane(easy.cloud, {}, p);
    ASSERT_TRUE(easy_serial.found);
    EXPECT_LT(easy_serial.iterations, 6);
    EXPECT_EQ(easy_par.iterations, easy_serial.iterations);
    EXPECT_EQ(easy_par.plane, easy_serial.plane);
    EXPECT_EQ(easy_par.inliers, easy_serial.inliers);

    const Scene cyl = CylinderScene(4000, 2000, 12);
    CylinderFitParams cp{.sac = {.distance_threshold = 0.01f, .num_threads = 1}};
    const CylinderFit c1 = FitCylinder(cyl.cloud, {}, cp);
    cp.sac.num_threads = 3;
    const CylinderFit c3 = FitCylinder(cyl.cloud, {}, cp);
    ASSERT_TRUE(c1.found);
    EXPECT_EQ(c1.axis, c3.axis);
    EXPECT_EQ(c1.radius, c3.radius);
    EXPECT_EQ(c1.inliers, c3.inliers);
    EXPECT_EQ(c1.iterations, c3.iterations);
}

// ---- Contracts ----

TEST(SampleConsensus, RejectsBadParameters) {
    const Scene s = PlaneScene(50, 10);
    auto plane = [&](SacParams sac) { return FitPlane(s.cloud, {}, {.sac = sac}); };
    EXPECT_THROW(plane({.distance_threshold = -0.01f}), InvalidArgument);
    EXPECT_THROW(plane({.distance_threshold = 0.0f}), InvalidArgument);
    EXPECT_THROW(plane({.distance_threshold = kNaN}), InvalidArgument);
    EXPECT_THROW(plane({.p_success = 0.0}), InvalidArgument);
    EXPECT_THROW(plane({.p_success = 1.0}), InvalidArgument);
    EXPECT_THROW(plane({.p_success = 1.5}), InvalidArgument);
    EXPECT_THROW(plane({.max_iterations = 0}), InvalidArgument);
    EXPECT_THROW(plane({.max_refine_rounds = -1}), InvalidArgument);
    EXPECT_THROW(plane({.normal_distance_weight = 1.5f}), InvalidArgument);
    EXPECT_THROW(plane({.normal_distance_weight = -0.1f}), InvalidArgument);
    EXPECT_THROW(plane({.num_threads = -1}), InvalidArgument);
    try {
        plane({.distance_threshold = -0.25f});
        FAIL() << "no exception";
    } catch (const InvalidArgument& e) {
        EXPECT_NE(std::string(e.what()).find("-0.25"), std::string::npos) << e.what();
    }
    EXPECT_THROW(FitPlane(s.cloud, {}, {.axis = Eigen::Vector3f::Zero()}), InvalidArgument);
    EXPECT_THROW(FitPlane(s.cloud, {}, {.axis = Eigen::Vector3f::UnitZ(), .max_angle = 2.0f}),
                 InvalidArgument);
    EXPECT_THROW(FitLine(s.cloud, {}, {.axis = Eigen::Vector3f(kNaN, 0.0f, 1.0f)}),
                 InvalidArgument);
    EXPECT_THROW(FitSphere(s.cloud, {}, {.min_radius = -1.0f}), InvalidArgument);
    EXPECT_THROW(FitCircle2d(s.cloud, {}, {.min_radius = 0.2f, .max_radius = 0.1f}),
                 InvalidArgument);
    EXPECT_THROW(FitCircle3d(s.cloud, {}, {.max_radius = kNaN}), InvalidArgument);
    EXPECT_THROW(FitPlane(s.cloud, {0, 1, 100000}, {}), InvalidArgument);
    EXPECT_THROW(RunSampleConsensus(s.cloud, {}, SacModel{}, {}), InvalidArgument);
}

TEST(SampleConsensus, MissingNormalsAreADataError) {
    const Scene s = PlaneScene(50, 10);
    EXPECT_THROW(FitCylinder(s.cloud, {}, {}), DataError);
    EXPECT_THROW(FitPlane(s.cloud, {}, {.sac = {.normal_distance_weight = 0.1f}}), DataError);
    // Models without a surface normal ignore the weight.
    EXPECT_NO_THROW(FitLine(s.cloud, {}, {.sac = {.normal_distance_weight = 0.1f}}));
}

TEST(SampleConsensus, TooFewPointsGiveNotFound) {
    const Scene s = CylinderScene(20, 0);
    EXPECT_FALSE(FitPlane(s.cloud, {0, 1}, {}).found);
    EXPECT_FALSE(FitLine(s.cloud, {4}, {}).found);
    EXPECT_FALSE(FitCircle2d(s.cloud, {0, 1}, {}).found);
    EXPECT_FALSE(FitCircle3d(s.cloud, {0, 1}, {}).found);
    EXPECT_FALSE(FitSphere(s.cloud, {0, 1, 2}, {}).found);
    EXPECT_FALSE(FitCylinder(s.cloud, {3}, {}).found);
    // Points without a finite normal do not count for the cylinder.
    PointCloud c = s.cloud;
    for (std::size_t i = 1; i < c.size(); ++i) c.normals[i] = Eigen::Vector3f::Constant(kNaN);
    const CylinderFit fit = FitCylinder(c, {}, {});
    EXPECT_FALSE(fit.found);
    EXPECT_EQ(fit.iterations, 0);
}

TEST(SampleConsensus, DegenerateDataGivesNotFound) {
    // Collinear points define no plane: every sample is degenerate.
    PointCloud c;
    for (int i = 0; i < 30; ++i) c.points.emplace_back(0.1f * static_cast<float>(i), 0.0f, 1.0f);
    c.SetUnorganized();
    const PlaneFit fit = FitPlane(c, {}, {.sac = {.max_iterations = 200}});
    EXPECT_FALSE(fit.found);
    EXPECT_EQ(fit.iterations, 200);
    EXPECT_FALSE(fit.converged);
    EXPECT_TRUE(fit.inliers.empty());
}

TEST(SampleConsensus, EmptyInputGivesEmptyResult) {
    const PointCloud empty;
    const PlaneFit plane = FitPlane(empty, {}, {});
    EXPECT_FALSE(plane.found);
    EXPECT_TRUE(plane.inliers.empty());
    EXPECT_EQ(plane.iterations, 0);
    EXPECT_FALSE(plane.converged);
    EXPECT_EQ(plane.rmse, 0.0f);
    EXPECT_FALSE(FitLine(empty, {}, {}).found);
    EXPECT_FALSE(FitCircle2d(empty, {}, {}).found);
    EXPECT_FALSE(FitCircle3d(empty, {}, {}).found);
    EXPECT_FALSE(FitSphere(empty, {}, {}).found);
    EXPECT_FALSE(FitCylinder(empty, {}, {}).found);  // no normals needed when there is nothing
}

}  // namespace
}  // namespace multicue

// Robust moving least squares: outlier patches, edge preservation, denoising, organized fast
// path, contracts and determinism.

#include <cmath>
#include <limits>
#include <random>

#include <gtest/gtest.h>

#include "mesh_test_data.hpp"
#include "multicue/core/exceptions.hpp"
#include "multicue/search/kdtree.hpp"
#include "multicue/surface/mls.hpp"

namespace multicue {
namespace {

MlsResult RunMls(const PointCloud& c, const MlsParams& p) {
    const KdTree tree(c);
    return MovingLeastSquares(c, tree, p);
}

/// A 20 x 20 cm plane z = 0 (5 mm grid, jittered) and, over a 4 x 4 cm square, a second sheet of
/// the same density 6 mm above it: about 10 % of the points, outliers as dense as the surface
/// (Figure 2.4).
PointCloud PlaneWithOutlierPatch(std::size_t& surface_points) {
    PointCloud c = test::SampledPlane(40, 40, 0.005f, 0.2f, 11);
    c.normals.clear();
    surface_points = c.size();
    std::mt19937 rng(12);
    std::uniform_real_distribution<float> u(-0.001f, 0.001f);
    for (int y = 0; y < 13; ++y)
        for (int x = 0; x < 13; ++x)
            c.points.emplace_back(0.07f + 0.005f * x + u(rng), 0.07f + 0.005f * y + u(rng),
                                  0.006f + u(rng));
    c.SetUnorganized();
    c.sensor_origin = {0.1f, 0.1f, 1.0f};
    return c;
}

TEST(Mls, RobustIgnoresOutlierPatchThatWeightedLeastSquaresFollows) {
    std::size_t n_surface = 0;
    const PointCloud c = PlaneWithOutlierPatch(n_surface);
    MlsParams p{.radius = 0.02f};
    auto worst_under_patch = [&](const MlsResult& r) {
        float worst = 0.0f;
        for (std::size_t i = 0; i < r.cloud.size(); ++i) {
            if (r.source[i] >= n_surface) continue;  // outlier starts
            const Eigen::Vector3f& q = r.cloud.points[i];
            if (q.x() > 0.065f && q.x() < 0.135f && q.y() > 0.065f && q.y() < 0.135f)
                worst = std::max(worst, std::abs(q.z()));
        }
        return worst;
    };
    const MlsResult robust = RunMls(c, p);
    p.plane_fit = MlsPlaneFit::kWeightedLeastSquares;
    const MlsResult plain = RunMls(c, p);
    ASSERT_EQ(robust.cloud.size(), c.size());
    EXPECT_LT(worst_under_patch(robust), 0.0005f);
    EXPECT_GT(worst_under_patch(plain), 0.0015f);
    EXPECT_LT(robust.mean_inlier_fraction, plain.mean_inlier_fraction);
}

/// Points on the surface of a cube of edge 10 cm, 4 mm grid per face.
PointCloud Cube() {
    PointCloud c;
    const int n = 25;
    const float s = 0.1f / n;
    for (int axis = 0; axis < 3; ++axis) {
        for (int side = 0; side < 2; ++side) {
            for (int i = 0; i <= n; ++i) {
                for (int j = 0; j <= n; ++j) {
                    Eigen::Vector3f p;
                    p[axis] = side * 0.1f;
                    p[(axis + 1) % 3] = i * s;
                    p[(axis + 2) % 3] = j * s;
                    c.points.push_back(p);
                }
            }
        }
    }
    c.SetUnorganized();
    c.sensor_origin = {0.05f, 0.05f, 0.05f};
    return c;
}

TEST(Mls, RobustKeepsCubeEdgesSharperThanPlainMls) {
    const PointCloud cube = Cube();
    MlsParams p{.radius = 0.015f, .polynomial_order = 2};
    const MlsResult robust = RunMls(cube, p);
    p.plane_fit = MlsPlaneFit::kWeightedLeastSquares;
    const MlsResult plain = RunMls(cube, p);
    // Near an edge but off the corners: curvature (Figure 2.5) and normal error.
    auto near_edge = [](const Eigen::Vector3f& q) {
        int at_face = 0, near = 0;
        for (int a = 0; a < 3; ++a) {
            const float d = std::min(std::abs(q[a]), std::abs(q[a] - 0.1f));
            at_face += d < 1e-6f;
            near += d < 0.008f;
        }
        return at_face == 1 && near == 2;  // off the edge line itself (points there are doubled)
    };
    auto stats = [&](const MlsResult& r, double& curvature, double& normal_err, double& shift) {
        curvature = normal_err = shift = 0.0;
        int count = 0;
        for (std::size_t i = 0; i < r.cloud.size(); ++i) {
            const Eigen::Vector3f& q0 = cube.points[r.source[i]];
            if (!near_edge(q0)) continue;
            // The face the starting point lies on.
            int axis = 0;
            for (int a = 0; a < 3; ++a) {
                if (std::min(std::abs(q0[a]), std::abs(q0[a] - 0.1f)) < 1e-6f) axis = a;
            }
            curvature += r.cloud.curvature[i];
            normal_err += 1.0 - std::abs(r.cloud.normals[i][axis]);
            shift += (r.cloud.points[i] - q0).norm();
            ++count;
        }
        ASSERT_GT(count, 100);
        curvature /= count;
        normal_err /= count;
        shift /= count;
    };
    double rc, rn, rs, pc, pn, ps;
    stats(robust, rc, rn, rs);
    stats(plain, pc, pn, ps);
    EXPECT_LT(rc, 0.2 * pc);
    EXPECT_LT(rn, 0.2 * pn);
    EXPECT_LT(rs, 0.2 * ps);
}

TEST(Mls, ReducesNoiseOnSphere) {
    const float radius = 0.1f, noise = 0.002f;
    PointCloud sphere = test::SampledSphere(6000, radius, noise);
    sphere.normals.clear();
    auto rms = [&](const PointCloud& c) {
        double s = 0.0;
        for (const auto& q : c.points) s += std::pow(q.norm() - radius, 2);
        return std::sqrt(s / c.size());
    };
    const MlsResult r = RunMls(sphere, {.radius = 0.03f, .polynomial_order = 2});
    ASSERT_EQ(r.cloud.size(), sphere.size());
    EXPECT_LT(rms(r.cloud), 0.4 * rms(sphere));
    // Normals point radially (PCA orientation: towards the sensor at the centre).
    double err = 0.0;
    for (std::size_t i = 0; i < r.cloud.size(); ++i)
        err += 1.0 + r.cloud.normals[i].dot(r.cloud.points[i].normalized());
    EXPECT_LT(err / r.cloud.size(), 0.01);
    // Plain MLS smooths too, and order 3 works.
    EXPECT_LT(rms(RunMls(sphere, {.radius = 0.03f,
                                  .polynomial_order = 3,
                                  .plane_fit = MlsPlaneFit::kWeightedLeastSquares})
                      .cloud),
              0.4 * rms(sphere));
}

TEST(Mls, ResamplesOnTheGridOfEq21) {
    PointCloud plane = test::SampledPlane(40, 40, 0.0025f, 0.2f);
    plane.normals.clear();
    const MlsResult r = RunMls(plane, {.radius = 0.01f, .resample_step = 0.005f});
    // About one point per 5 mm voxel of the 10 x 10 cm plane, on the plane.
    EXPECT_GT(r.cloud.size(), 350u);
    EXPECT_LT(r.cloud.size(), 500u);
    for (const auto& q : r.cloud.points) EXPECT_NEAR(q.z(), 0.0f, 1e-4f);
}

TEST(Mls, DensityFollowsCurvature) {
    const PointCloud cube = Cube();
    // Output points per unit area near the edges (within 6 mm) and on the faces' interiors.
    auto densities = [&](const MlsResult& r, double& edge, double& face) {
        std::size_t ne = 0, nf = 0;
        for (const auto& q : r.cloud.points) {
            int near = 0;
            for (int a = 0; a < 3; ++a)
                near += std::min(std::abs(q[a]), std::abs(q[a] - 0.1f)) < 0.006f;
            ne += near >= 2;
            nf += near == 1;
        }
        // 12 edges x 2 bands of 6 mm x 10 cm; 6 faces minus their bands.
        edge = ne / (12 * 2 * 0.006 * 0.1);
        face = nf / (6 * 0.088 * 0.088);
    };
    // Steps 12, 6 and 3 mm on the 4 mm input grid.
    MlsParams p{.radius = 0.01f, .resample_step = 0.012f};
    double e0, f0, e1, f1;
    densities(RunMls(cube, p), e0, f0);
    p.curvature_slope = 4.0f;
    densities(RunMls(cube, p), e1, f1);
    EXPECT_LT(e0, 2.0 * f0);  // uniform without adaptation
    EXPECT_GT(e1, 3.0 * f1);  // much denser along the edges with it
    EXPECT_NEAR(f1, f0, 0.3 * f0);
    EXPECT_THROW(RunMls(cube, {.radius = 0.01f, .curvature_slope = -1.0f}), InvalidArgument);
}

TEST(Mls, KeepsColoursAndLabels) {
    PointCloud plane = test::SampledPlane(20, 20, 0.005f);
    plane.colors.assign(plane.size(), Color{200, 100, 50, 255});
    plane.labels.assign(plane.size(), 7u);
    const MlsResult r = RunMls(plane, {.radius = 0.015f});
    ASSERT_EQ(r.cloud.colors.size(), r.cloud.size());
    EXPECT_EQ(r.cloud.colors[10], (Color{200, 100, 50, 255}));
    EXPECT_EQ(r.cloud.labels[10], 7u);
    // Input normals decide the orientation.
    for (const auto& n : r.cloud.normals) EXPECT_GT(n.z(), 0.99f);
}

TEST(Mls, OrganizedFastPathSmoothsADepthFrame) {
    const int w = 64, h = 48;
    PointCloud c;
    c.width = w;
    c.height = h;
    std::mt19937 rng(4);
    std::normal_distribution<float> g(0.0f, 0.001f);
    for (int v = 0; v < h; ++v)
        for (int u = 0; u < w; ++u)
            c.points.emplace_back((u - 32) * 0.002f, (v - 24) * 0.002f, 1.0f + g(rng));
    c.points[100] = Eigen::Vector3f::Constant(std::numeric_limits<float>::quiet_NaN());
    const MlsResult r = MovingLeastSquaresOrganized(c, {.radius = 0.015f, .half_window = 8});
    ASSERT_EQ(r.cloud.size(), c.size());
    EXPECT_EQ(r.cloud.width, static_cast<std::uint32_t>(w));
    EXPECT_FALSE(r.cloud.IsFinite(100));
    double before = 0.0, after = 0.0, normal_err = 0.0;
    std::size_t valid = 0;
    for (std::size_t i = 0; i < c.size(); ++i) {
        if (!r.cloud.IsFinite(i)) continue;
        before += std::pow(c.points[i].z() - 1.0f, 2);
        after += std::pow(r.cloud.points[i].z() - 1.0f, 2);
        EXPECT_LT(r.cloud.normals[i].z(), 0.0f);  // towards the sensor at the origin
        normal_err += 1.0 + r.cloud.normals[i].z();
        ++valid;
    }
    EXPECT_EQ(valid, c.size() - 1);
    EXPECT_LT(after, 0.3 * before);
    EXPECT_LT(normal_err / valid, 0.02);
    EXPECT_THROW(MovingLeastSquaresOrganized(PointCloud({{0, 0, 1}}), {}), InvalidArgument);
    EXPECT_THROW(MovingLeastSquaresOrganized(c, {.half_window = 0}), InvalidArgument);
    EXPECT_TRUE(MovingLeastSquaresOrganized(PointCloud{}, {}).cloud.empty());
}

TEST(Mls, BadParametersAndEmptyInput) {
    const PointCloud plane = test::SampledPlane(5, 5, 0.01f);
    EXPECT_THROW(RunMls(plane, {}), InvalidArgument);
    EXPECT_THROW(RunMls(plane, {.radius = 0.02f, .polynomial_order = 4}), InvalidArgument);
    EXPECT_THROW(RunMls(plane, {.radius = 0.02f, .gaussian = -1.0f}), InvalidArgument);
    EXPECT_THROW(RunMls(plane, {.radius = 0.02f, .confidence = 1.0f}), InvalidArgument);
    EXPECT_THROW(RunMls(plane, {.radius = 0.02f, .min_neighbors = 2}), InvalidArgument);
    EXPECT_THROW(RunMls(plane, {.radius = 0.02f, .resample_step = -0.1f}), InvalidArgument);
    EXPECT_THROW(RunMls(plane, {.radius = 0.02f, .num_threads = -1}), InvalidArgument);
    const PointCloud other = test::SampledPlane(4, 4, 0.01f);
    const KdTree tree(other);
    EXPECT_THROW(MovingLeastSquares(plane, tree, {.radius = 0.02f}), InvalidArgument);
    const MlsResult empty = RunMls(PointCloud{}, {.radius = 0.02f});
    EXPECT_TRUE(empty.cloud.empty());
    // Isolated points are dropped, not projected.
    const MlsResult sparse = RunMls(PointCloud({{0, 0, 0}, {1, 1, 1}}), {.radius = 0.02f});
    EXPECT_EQ(sparse.dropped, 2u);
}

TEST(Mls, DeterministicForAnyThreadCount) {
    std::size_t n = 0;
    const PointCloud c = PlaneWithOutlierPatch(n);
    const MlsResult a = RunMls(c, {.radius = 0.02f, .seed = 9, .num_threads = 1});
    const MlsResult b = RunMls(c, {.radius = 0.02f, .seed = 9, .num_threads = 2});
    ASSERT_EQ(a.cloud.size(), b.cloud.size());
    for (std::size_t i = 0; i < a.cloud.size(); ++i) {
        EXPECT_EQ(a.cloud.points[i], b.cloud.points[i]);
        EXPECT_EQ(a.cloud.normals[i], b.cloud.normals[i]);
    }
}

}  // namespace
}  // namespace multicue

// perceive on degenerate clouds: one point repeated, coordinates of 1e30, a single plane, a lone
// far outlier. Each either works (a well-defined, possibly empty result) or is refused with a
// DataError naming the problem; none may crash or run without end.

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "multicue/core/exceptions.hpp"
#include "multicue/search/kdtree.hpp"
#include "multicue/sim/tabletop_scene.hpp"
#include "multicue/surface/normals.hpp"
#include "multicue/system/perceive.hpp"

namespace multicue {
namespace {

PerceiveParams Params() {
    PerceiveParams p;
    p.num_threads = 2;
    p.category.categoriser = Categoriser::kRules;  // no trained model needed
    return p;
}

const PointCloud& DemoCloud() {
    static const PointCloud cloud = [] {
        const sim::TableTopScene scene = sim::MakeDemoScene();
        sim::ScanParams p;
        p.T_world_camera = sim::DefaultCameraPose(scene);
        return sim::ScanTableTopScene(scene, p);
    }();
    return cloud;
}

/// Unorganized points of a horizontal 1 x 1 m square 1 m below the camera (y down), jittered.
PointCloud Plane(std::size_t n) {
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(-0.5f, 0.5f);
    std::normal_distribution<float> noise(0.0f, 0.001f);
    PointCloud c;
    for (std::size_t i = 0; i < n; ++i)
        c.points.emplace_back(u(rng), 1.0f + noise(rng), 1.5f + u(rng));
    c.width = static_cast<std::uint32_t>(n);
    c.height = 1;
    return c;
}

TEST(PerceiveLimits, OneRepeatedPointIsAtMostOneObject) {
    // Copies of one point are all each other's nearest neighbours: a search that visits every
    // copy from every copy would take hours here (and did, in the normals stage).
    PointCloud c;
    c.points.assign(100000, Eigen::Vector3f(0.1f, 0.2f, 1.0f));
    c.width = static_cast<std::uint32_t>(c.points.size());
    const PerceiveResult r = Perceive(c, Params());
    EXPECT_FALSE(r.support.found);
    EXPECT_LE(r.objects.size(), 1u);
    EXPECT_EQ(r.point_objects.size(), c.size());
}

TEST(PerceiveLimits, CoordinatesOf1e30AreRefused) {
    for (const bool organized : {true, false}) {
        PointCloud c = DemoCloud();
        for (auto& p : c.points) p *= 1e30f;
        if (!organized) c.SetUnorganized();
        PerceiveParams p = Params();
        p.image_grid = false;
        try {
            Perceive(c, p);
            ADD_FAILURE() << "no error";
        } catch (const DataError& e) {
            EXPECT_NE(std::string(e.what()).find("farther than 1e+05 m"), std::string::npos)
                << e.what();
        }
    }
}

TEST(PerceiveLimits, ALoneFarOutlierIsLeftOut) {
    const PerceiveResult clean = Perceive(DemoCloud(), Params());
    for (const bool organized : {true, false}) {
        PointCloud c = DemoCloud();
        // Into an invalid pixel, so that the organized layout stays the same.
        std::size_t i = 0;
        while (c.points[i].allFinite()) ++i;
        c.points[i] = Eigen::Vector3f(1e30f, -1e30f, 1e30f);
        if (!organized) c.SetUnorganized();
        const PerceiveResult r = Perceive(c, Params());
        EXPECT_EQ(r.objects.size(), clean.objects.size());
        EXPECT_EQ(r.point_objects[i], 0u);
    }
}

TEST(PerceiveLimits, AKdTreeRefusesCoordinatesWhoseSquaresOverflow) {
    PointCloud c = DemoCloud();
    c.points[0] = Eigen::Vector3f(0.0f, 3e18f, 0.0f);
    EXPECT_THROW(KdTree{c}, DataError);
    c.points[0] = Eigen::Vector3f(0.0f, 1e17f, 0.0f);
    EXPECT_NO_THROW(KdTree{c});
}

TEST(PerceiveLimits, ASinglePlaneIsATableOrOneFlatObject) {
    // Nothing stands on it: perceive reports no support and the plane itself as one flat object,
    // as it would a board seen alone.
    const PointCloud c = Plane(50000);
    const PerceiveResult r = Perceive(c, Params());
    if (r.support.found) {
        EXPECT_TRUE(r.objects.empty());
    } else {
        ASSERT_EQ(r.objects.size(), 1u);
        EXPECT_EQ(r.objects[0].category.category, Category::kFlat);
        EXPECT_EQ(r.objects[0].indices.size(), c.size());
    }
}

TEST(PerceiveLimits, FewPointsGiveAnEmptyResult) {
    for (std::size_t n : {1u, 2u, 3u, 10u}) {
        const PointCloud c = Plane(n);
        const PerceiveResult r = Perceive(c, Params());
        EXPECT_TRUE(r.objects.empty()) << n;
    }
}

TEST(PerceiveLimits, NormalsOfManyCopiesOfAPointAreUndefinedAndOthersUnchanged) {
    // A wavy surface, then 50000 copies of the origin (a sensor's invalid pixels written as
    // 0 0 0) far from it.
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
    PointCloud surface;
    for (int i = 0; i < 2000; ++i) {
        const float x = 0.3f * unit(rng), y = 0.3f * unit(rng);
        surface.points.emplace_back(x, y, 1.0f + 0.03f * std::sin(20.0f * x));
    }
    surface.SetUnorganized();
    PointCloud both = surface;
    both.points.resize(surface.size() + 50000, Eigen::Vector3f::Zero());
    both.SetUnorganized();
    const NormalsResult alone = EstimateNormals(surface, KdTree(surface), {.k = 10});
    for (const int threads : {1, 2}) {
        const NormalsResult r =
            EstimateNormals(both, KdTree(both), {.k = 10, .num_threads = threads});
        for (std::size_t i = 0; i < surface.size(); ++i) {
            ASSERT_TRUE(r.normals[i].allFinite()) << i;
            EXPECT_LT((r.normals[i] - alone.normals[i]).norm(), 1e-6f) << i;
            EXPECT_NEAR(r.curvature[i], alone.curvature[i], 1e-6f) << i;
        }
        for (std::size_t i = surface.size(); i < both.size(); ++i) {
            ASSERT_FALSE(r.normals[i].allFinite()) << i;  // coincident neighbours
        }
        EXPECT_EQ(r.undefined, alone.undefined + 50000);
    }
}

}  // namespace
}  // namespace multicue

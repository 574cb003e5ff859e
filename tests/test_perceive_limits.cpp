// perceive on degenerate clouds: one point repeated, coordinates of 1e30, a single plane, a lone
// far outlier. Each either works (a well-defined, possibly empty result) or is refused with a
// DataError naming the problem; none may crash or run without end.

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "multicue/core/exceptions.hpp"
#include "multicue/sim/tabletop_scene.hpp"
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

TEST(PerceiveLimits, OneRepeatedPointGivesAnEmptyResult) {
    PointCloud c;
    c.points.assign(20000, Eigen::Vector3f(0.1f, 0.2f, 1.0f));
    c.width = static_cast<std::uint32_t>(c.points.size());
    const PerceiveResult r = Perceive(c, Params());
    EXPECT_FALSE(r.support.found);
    EXPECT_TRUE(r.objects.empty());
    EXPECT_EQ(r.point_objects.size(), c.size());
}

TEST(PerceiveLimits, CoordinatesOf1e30AreRefused) {
    PointCloud c = DemoCloud();
    for (auto& p : c.points) p *= 1e30f;
    try {
        const PerceiveResult r = Perceive(c, Params());
        EXPECT_EQ(r.point_objects.size(), c.size());
    } catch (const DataError& e) {
        EXPECT_NE(std::string(e.what()).find("coordinate"), std::string::npos) << e.what();
    }
}

TEST(PerceiveLimits, ALoneFarOutlierDoesNotChangeTheResult) {
    const PerceiveResult clean = Perceive(DemoCloud(), Params());
    PointCloud c = DemoCloud();
    // Into an invalid pixel of the organized frame, so that the layout stays the same.
    std::size_t i = 0;
    while (c.points[i].allFinite()) ++i;
    c.points[i] = Eigen::Vector3f(1e30f, -1e30f, 1e30f);
    try {
        const PerceiveResult r = Perceive(c, Params());
        EXPECT_EQ(r.objects.size(), clean.objects.size());
        EXPECT_EQ(r.point_objects[i], 0u);
    } catch (const DataError& e) {
        EXPECT_NE(std::string(e.what()).find("coordinate"), std::string::npos) << e.what();
    }
}

TEST(PerceiveLimits, ASinglePlaneIsATableWithoutObjects) {
    const PointCloud c = Plane(50000);
    const PerceiveResult r = Perceive(c, Params());
    EXPECT_TRUE(r.support.found);
    EXPECT_TRUE(r.objects.empty());
}

TEST(PerceiveLimits, FewPointsGiveAnEmptyResult) {
    for (std::size_t n : {1u, 2u, 3u, 10u}) {
        const PointCloud c = Plane(n);
        const PerceiveResult r = Perceive(c, Params());
        EXPECT_TRUE(r.objects.empty()) << n;
    }
}

}  // namespace
}  // namespace multicue

#include <algorithm>
#include <random>

#include <gtest/gtest.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/segmentation/polygonal_prism.hpp"
#include "test_util.hpp"

namespace multicue {
namespace {

const Eigen::Vector4f kTable(0, 0, 1, -0.75f);  // z = 0.75, normal up

PointCloud Square(float half, int n_per_side) {
    PointCloud c;
    for (int i = 0; i <= n_per_side; ++i) {
        for (int j = 0; j <= n_per_side; ++j) {
            c.points.emplace_back(-half + 2 * half * i / n_per_side,
                                  -half + 2 * half * j / n_per_side, 0.75f);
        }
    }
    c.SetUnorganized();
    return c;
}

TEST(PlaneConvexHull, SquareGivesFourCounterClockwiseCorners) {
    const PointCloud c = Square(0.5f, 10);
    const auto hull = PlaneConvexHull(c, {}, kTable);
    ASSERT_EQ(hull.size(), 4u);
    double area = 0;
    for (std::size_t k = 0; k < hull.size(); ++k) {
        const auto& a = hull[k];
        const auto& b = hull[(k + 1) % hull.size()];
        EXPECT_NEAR(std::abs(a.x()), 0.5f, 1e-5f);
        EXPECT_NEAR(std::abs(a.y()), 0.5f, 1e-5f);
        EXPECT_NEAR(a.z(), 0.75f, 1e-5f);
        area += 0.5 * (a.x() * b.y() - a.y() * b.x());
    }
    EXPECT_NEAR(area, 1.0, 1e-4);  // positive: counter-clockwise seen from +z
}

TEST(PlaneConvexHull, OracleEveryPointInsideAndHullVerticesAreInputPoints) {
    PointCloud c = test::RandomCloud(500, 4, 0.3f);
    for (auto& p : c.points) p.z() = 0.75f;
    const auto hull = PlaneConvexHull(c, {}, kTable);
    ASSERT_GE(hull.size(), 3u);
    for (const auto& h : hull) {
        const bool found = std::any_of(c.points.begin(), c.points.end(),
                                       [&](const auto& p) { return (p - h).norm() < 1e-5f; });
        EXPECT_TRUE(found);
    }
    PointCloud above = c;
    for (auto& p : above.points) p.z() = 0.80f;
    // Every point (lifted 5 cm) lies inside the prism of its own hull.
    const Indices in =
        PolygonalPrism(above, kTable, hull, {.min_height = 0.0f, .max_height = 0.1f});
    EXPECT_GE(in.size(), above.size() - hull.size());
}

TEST(PolygonalPrism, HeightAndFootprintLimits) {
    const auto hull = PlaneConvexHull(Square(0.5f, 2), {}, kTable);
    PointCloud c({{0, 0, 0.80f},     // inside, 5 cm up
                  {0, 0, 0.755f},    // too low
                  {0, 0, 1.40f},     // too high
                  {0.7f, 0, 0.80f},  // outside the footprint
                  {0.4f, -0.4f, 0.9f},
                  {std::numeric_limits<float>::quiet_NaN(), 0, 0}});
    const Indices in = PolygonalPrism(c, kTable, hull, {.min_height = 0.01f, .max_height = 0.5f});
    EXPECT_EQ(in, (Indices{0, 4}));
}

// Many points, some on the hull's corners: the same ascending selection with any thread count.
TEST(PolygonalPrism, ThreadsGiveTheDirectSelection) {
    const auto hull = PlaneConvexHull(Square(0.5f, 6), {}, kTable);
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> xy(-0.7f, 0.7f), z(0.7f, 1.4f);
    PointCloud c;
    for (int k = 0; k < 50000; ++k) c.points.emplace_back(xy(rng), xy(rng), z(rng));
    for (const auto& h : hull) c.points.push_back(h + Eigen::Vector3f(0, 0, 0.05f));
    c.SetUnorganized();
    const PrismParams params{.min_height = 0.01f, .max_height = 0.5f};
    const Indices serial = PolygonalPrism(c, kTable, hull, params, 1);
    EXPECT_GT(serial.size(), 1000u);
    EXPECT_LT(serial.size(), c.size() / 2);
    EXPECT_TRUE(std::is_sorted(serial.begin(), serial.end()));
    EXPECT_EQ(PolygonalPrism(c, kTable, hull, params, 2), serial);
    EXPECT_EQ(PolygonalPrism(c, kTable, hull, params, 0), serial);
}

TEST(PolygonalPrism, ContractAndEmpty) {
    const auto hull = PlaneConvexHull(Square(0.5f, 2), {}, kTable);
    EXPECT_THROW(
        PolygonalPrism(PointCloud{}, kTable, hull, {.min_height = 0.2f, .max_height = 0.1f}),
        InvalidArgument);
    EXPECT_THROW(PolygonalPrism(PointCloud{}, kTable, {}, {}), InvalidArgument);
    EXPECT_THROW(PlaneConvexHull(PointCloud{}, {}, Eigen::Vector4f(0, 0, 2, 0)), InvalidArgument);
    EXPECT_TRUE(PolygonalPrism(PointCloud{}, kTable, hull, {}).empty());
    EXPECT_TRUE(PlaneConvexHull(PointCloud{}, {}, kTable).empty());
    EXPECT_THROW(PlaneConvexHull(Square(0.5f, 2), {99}, kTable), InvalidArgument);
}

}  // namespace
}  // namespace multicue

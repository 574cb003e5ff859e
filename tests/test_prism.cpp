#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include <gtest/gtest.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/segmentation/enclosed_floors.hpp"
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

// A synthetic dish on the table z = 0.75: a ring of rim points 1-2 cm up (radius 9-12 cm around
// (cx, 0)), its floor 3 mm up inside radius 8 cm, the table all around out to 25 cm. Indices:
// rim first, then floor, then table.
struct Dish {
    PointCloud cloud;
    Indices rim, floor, table;
};
Dish MakeDish(float cx = 0.0f, float open_from_deg = 360.0f) {
    Dish d;
    auto add = [&](Indices& to, float x, float y, float z) {
        to.push_back(static_cast<Index>(d.cloud.points.size()));
        d.cloud.points.emplace_back(x, y, z);
    };
    for (float r = 0.09f; r <= 0.12f; r += 0.005f) {
        for (float a = 0.0f; a < 360.0f; a += 2.0f) {
            if (a >= open_from_deg) continue;  // an open outline (a C) when below 360
            const float t = a * 3.14159265f / 180.0f;
            add(d.rim, cx + r * std::cos(t), r * std::sin(t), 0.75f + 0.01f + (r - 0.09f) / 3);
        }
    }
    for (float x = -0.25f; x <= 0.25f; x += 0.005f) {
        for (float y = -0.25f; y <= 0.25f; y += 0.005f) {
            const float r = std::hypot(x, y);
            if (r < 0.08f)
                add(d.floor, cx + x, y, 0.753f);
            else if (r > 0.125f)
                add(d.table, cx + x, y, 0.75f + (x > 0 ? 0.002f : -0.002f));
        }
    }
    d.cloud.SetUnorganized();
    return d;
}

TEST(EnclosedFloors, ADishGetsItsFloorAndNoTable) {
    const Dish d = MakeDish();
    const auto floors = EnclosedFloors(d.cloud, kTable, {d.rim}, 0.008f);
    ASSERT_EQ(floors.size(), 1u);
    // Every floor point, no table point.
    EXPECT_EQ(floors[0], d.floor);
    // The same with the plane's normal scaled: only its direction counts.
    EXPECT_EQ(EnclosedFloors(d.cloud, 3.0f * kTable, {d.rim}, 0.008f)[0], d.floor);
}

TEST(EnclosedFloors, OpenOutlinesHighObjectsAndTakenPointsGetNothing) {
    // A C-shaped outline (a banana's hollow side, a clamp) does not enclose the table it frames.
    const Dish c = MakeDish(0.0f, 270.0f);
    const auto open = EnclosedFloors(c.cloud, kTable, {c.rim}, 0.008f)[0];
    EXPECT_LT(open.size(), c.floor.size() / 2);
    for (Index i : open) EXPECT_TRUE(std::binary_search(c.floor.begin(), c.floor.end(), i));
    // A rim 10 cm up is no dish: objects higher than max_object_height keep what they have.
    Dish high = MakeDish();
    for (Index i : high.rim) high.cloud.points[i].z() += 0.1f;
    EXPECT_TRUE(EnclosedFloors(high.cloud, kTable, {high.rim}, 0.008f)[0].empty());
    // Points of another object stay its own; the first enclosing object takes the rest.
    const Dish d = MakeDish();
    Indices half(d.floor.begin(), d.floor.begin() + d.floor.size() / 2);
    const auto two = EnclosedFloors(d.cloud, kTable, {d.rim, half, d.rim}, 0.008f);
    ASSERT_EQ(two.size(), 3u);
    EXPECT_EQ(two[0], Indices(d.floor.begin() + d.floor.size() / 2, d.floor.end()));
    EXPECT_TRUE(two[1].empty());  // half lies at the floor's height, but encloses little
    EXPECT_TRUE(two[2].empty());
    // No plane, no objects, an empty object: nothing.
    EXPECT_TRUE(EnclosedFloors(d.cloud, Eigen::Vector4f::Zero(), {d.rim}, 0.008f)[0].empty());
    EXPECT_TRUE(EnclosedFloors(d.cloud, kTable, {}, 0.008f).empty());
    EXPECT_TRUE(EnclosedFloors(d.cloud, kTable, {Indices{}}, 0.008f)[0].empty());
    // A floor at the prism's lowest height is the object's already (the band ends below it).
    EXPECT_TRUE(EnclosedFloors(d.cloud, kTable, {d.rim}, 0.002f)[0].empty());
}

TEST(EnclosedFloors, BadInputIsRefused) {
    const Dish d = MakeDish();
    EXPECT_THROW(EnclosedFloors(d.cloud, kTable, {{static_cast<Index>(d.cloud.size())}}, 0.008f),
                 InvalidArgument);
    const float nan = std::numeric_limits<float>::quiet_NaN();
    EXPECT_THROW(EnclosedFloors(d.cloud, Eigen::Vector4f(0, 0, nan, 1), {d.rim}, 0.008f),
                 InvalidArgument);
    EXPECT_THROW(EnclosedFloors(d.cloud, kTable, {d.rim}, nan), InvalidArgument);
    for (const EnclosedFloorParams& p :
         {EnclosedFloorParams{.max_object_height = 0.0f}, EnclosedFloorParams{.below = -1.0f},
          EnclosedFloorParams{.cell = 0.0f}, EnclosedFloorParams{.max_object_width = nan}}) {
        EXPECT_THROW(EnclosedFloors(d.cloud, kTable, {d.rim}, 0.008f, p), InvalidArgument);
    }
    // NaN points are never floor points, and do not stop the others.
    Dish holes = MakeDish();
    holes.cloud.points[holes.floor[0]] = Eigen::Vector3f::Constant(nan);
    const auto f = EnclosedFloors(holes.cloud, kTable, {holes.rim}, 0.008f)[0];
    EXPECT_EQ(f, Indices(holes.floor.begin() + 1, holes.floor.end()));
}

}  // namespace
}  // namespace multicue

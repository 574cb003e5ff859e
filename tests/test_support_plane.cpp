// Support plane selection on constructed scenes: the largest near-horizontal plane nearest the
// viewpoint, its connected patch and hull, and the three ways of finding "up".

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/segmentation/support_plane.hpp"
#include "test_util.hpp"

namespace multicue {
namespace {

// Noisy samples of the rectangle [x0,x1] x [y0,y1] at height z (world frame, z up).
void AddHorizontal(PointCloud& c, float x0, float x1, float y0, float y1, float z, float step,
                   std::mt19937& rng) {
    std::normal_distribution<float> noise(0.0f, 0.002f);
    for (float x = x0; x <= x1; x += step) {
        for (float y = y0; y <= y1; y += step) c.points.emplace_back(x, y, z + noise(rng));
    }
}

void AddWall(PointCloud& c, float y, float x0, float x1, float z0, float z1, float step,
             std::mt19937& rng) {
    std::normal_distribution<float> noise(0.0f, 0.002f);
    for (float x = x0; x <= x1; x += step) {
        for (float z = z0; z <= z1; z += step) c.points.emplace_back(x, y + noise(rng), z);
    }
}

// Floor (larger, far), table (a little smaller, nearer the sensor above it) and a wall; the pose is
// set, so the cloud is in a world frame with z up. Planes of similar size compete on nearness.
PointCloud RoomWithTable() {
    std::mt19937 rng(3);
    PointCloud c;
    AddHorizontal(c, -2.0f, 2.0f, -2.0f, 2.0f, 0.0f, 0.06f, rng);    // floor: 4.5k points
    AddHorizontal(c, -0.5f, 0.5f, -0.3f, 0.3f, 0.75f, 0.012f, rng);  // table: 4k points
    AddWall(c, 2.0f, -2.0f, 2.0f, 0.0f, 2.0f, 0.03f, rng);           // wall
    c.SetUnorganized();
    c.sensor_origin = {0.0f, -1.0f, 1.5f};
    c.sensor_orientation = Eigen::Quaternionf(Eigen::AngleAxisf(0.3f, Eigen::Vector3f::UnitX()));
    return c;
}

TEST(SupportPlane, PicksTheTableNearestTheViewpointNotTheLargerFloor) {
    const PointCloud c = RoomWithTable();
    const SupportPlane s = FindSupportPlane(c, {});
    ASSERT_TRUE(s.found);
    EXPECT_EQ(s.up_source, UpSource::kViewpoint);
    EXPECT_GT(s.plane.z(), 0.999f);
    EXPECT_NEAR(-s.plane.w(), 0.75f, 0.005f);
    for (Index i : s.inliers) EXPECT_NEAR(c.points[i].z(), 0.75f, 0.015f);
    EXPECT_GT(s.inliers.size(), 3500u);
    // The hull spans the table top.
    Eigen::Vector3f lo = Eigen::Vector3f::Constant(1e9f), hi = -lo;
    for (const auto& h : s.hull) {
        lo = lo.cwiseMin(h);
        hi = hi.cwiseMax(h);
    }
    EXPECT_NEAR(lo.x(), -0.5f, 0.02f);
    EXPECT_NEAR(hi.x(), 0.5f, 0.02f);
    EXPECT_NEAR(lo.y(), -0.3f, 0.02f);
    EXPECT_NEAR(hi.y(), 0.3f, 0.02f);
}

TEST(SupportPlane, GivenUpAndTheLargestPatchOnly) {
    std::mt19937 rng(5);
    PointCloud c;
    AddHorizontal(c, -0.5f, 0.5f, -0.3f, 0.3f, 0.75f, 0.012f, rng);  // the table
    AddHorizontal(c, 1.5f, 1.8f, -0.1f, 0.1f, 0.75f, 0.012f, rng);   // a shelf at the same height
    c.SetUnorganized();
    c.sensor_origin = {0.0f, -1.0f, 1.5f};
    SupportPlaneParams p;
    p.up = Eigen::Vector3f(0, 0, 2);
    const SupportPlane s = FindSupportPlane(c, p);
    ASSERT_TRUE(s.found);
    EXPECT_EQ(s.up_source, UpSource::kGiven);
    for (Index i : s.inliers) EXPECT_LT(c.points[i].x(), 1.0f);  // the shelf is left out
}

TEST(SupportPlane, CameraFrameConventionFindsTheTableSeenFromAbove) {
    // Table 1 m below a camera looking down 45 degrees: optical frame, y down, identity pose.
    std::mt19937 rng(7);
    PointCloud world;
    AddHorizontal(world, -0.4f, 0.4f, 0.6f, 1.4f, 0.0f, 0.01f, rng);
    const Eigen::Matrix3f R_cam_world =
        (Eigen::AngleAxisf(static_cast<float>(M_PI) / 4, Eigen::Vector3f::UnitX()) *
         Eigen::AngleAxisf(-static_cast<float>(M_PI) / 2, Eigen::Vector3f::UnitX()))
            .toRotationMatrix();
    PointCloud c;
    for (const auto& p : world.points)
        c.points.push_back(R_cam_world * (p - Eigen::Vector3f(0, 0, 1)));
    c.SetUnorganized();
    const SupportPlane s = FindSupportPlane(c, {});
    ASSERT_TRUE(s.found);
    EXPECT_EQ(s.up_source, UpSource::kCamera);
    const Eigen::Vector3f up_cam = R_cam_world * Eigen::Vector3f::UnitZ();
    EXPECT_GT(s.plane.head<3>().dot(up_cam), 0.999f);
}

// The visible faces of an axis-aligned box standing at height z0: its top and the two sides
// that face a sensor at negative y and negative x.
void AddBox(PointCloud& c, const Eigen::Vector3f& lo, const Eigen::Vector3f& hi, float step,
            std::mt19937& rng) {
    AddHorizontal(c, lo.x(), hi.x(), lo.y(), hi.y(), hi.z(), step, rng);
    AddWall(c, lo.y(), lo.x(), hi.x(), lo.z() + step, hi.z() - step, step, rng);
    std::normal_distribution<float> noise(0.0f, 0.002f);
    for (float y = lo.y(); y <= hi.y(); y += step) {
        for (float z = lo.z() + step; z <= hi.z() - step; z += step)
            c.points.emplace_back(lo.x() + noise(rng), y, z);
    }
}

// A floor (4 m x 3 m) and a 1 m x 0.6 m table top 72 cm above it, centred on the origin.
void AddFloorAndTable(PointCloud& c, std::mt19937& rng) {
    AddHorizontal(c, -2.0f, 2.0f, -1.0f, 2.0f, 0.0f, 0.02f, rng);
    AddHorizontal(c, -0.5f, 0.5f, -0.3f, 0.3f, 0.72f, 0.015f, rng);
}

// Removes what a table top (|x| < half_x, |y| < half_y at height z) hides from the sensor: the
// points below it whose ray from the sensor crosses it.
void HideBelowTableTop(PointCloud& c, float half_x, float half_y, float z) {
    const Eigen::Vector3f o = c.sensor_origin;
    std::erase_if(c.points, [&](const Eigen::Vector3f& p) {
        if (p.z() >= z - 0.01f) return false;
        const Eigen::Vector3f x = o + (o.z() - z) / (o.z() - p.z()) * (p - o);
        return std::abs(x.x()) < half_x && std::abs(x.y()) < half_y;
    });
}

// A table mostly covered by a large box near the sensor, whose top holds more sampled points
// than the visible table and is nearer the viewpoint, plus small boxes (a complex real scene's
// failure: the box top was taken for the table and no object was found).
PointCloud TableUnderALargeBox(bool stacked) {
    std::mt19937 rng(21);
    PointCloud c;
    const float table = 0.75f;
    AddHorizontal(c, -0.45f, 0.45f, -0.3f, 0.3f, table, 0.012f, rng);
    // The table under the large box is hidden from the sensor.
    const Eigen::Vector3f lo(-0.3f, -0.25f, table), hi(0.25f, 0.2f, table + 0.25f);
    std::erase_if(c.points, [&](const Eigen::Vector3f& p) {
        return p.x() > lo.x() && p.x() < hi.x() && p.y() > lo.y() && p.y() < hi.y();
    });
    AddBox(c, lo, hi, 0.006f, rng);
    if (stacked)
        AddBox(c, hi - Eigen::Vector3f(0.2f, 0.2f, 0.0f), hi + Eigen::Vector3f(0, 0, 0.1f), 0.006f,
               rng);
    AddBox(c, {0.3f, -0.25f, table}, {0.4f, -0.15f, table + 0.12f}, 0.006f, rng);
    AddBox(c, {0.3f, 0.05f, table}, {0.42f, 0.2f, table + 0.08f}, 0.006f, rng);
    c.SetUnorganized();
    c.sensor_origin = {0.0f, -0.8f, 1.45f};
    c.sensor_orientation = Eigen::Quaternionf(Eigen::AngleAxisf(0.4f, Eigen::Vector3f::UnitX()));
    return c;
}

TEST(SupportPlane, TheTableIsWhatSupportsTheObjectsNeverABoxTop) {
    for (bool stacked : {false, true}) {
        const PointCloud c = TableUnderALargeBox(stacked);
        std::size_t top = 0, table = 0;
        for (const auto& p : c.points) {
            top += std::abs(p.z() - 1.0f) < 0.003f ? 1 : 0;
            table += std::abs(p.z() - 0.75f) < 0.003f ? 1 : 0;
        }
        ASSERT_GT(top, table) << "the scene must make the box top the larger plane";
        const SupportPlane s = FindSupportPlane(c, {});
        ASSERT_TRUE(s.found);
        EXPECT_NEAR(-s.plane.w() / s.plane.z(), 0.75f, 0.01f) << "stacked " << stacked;
        EXPECT_GT(s.supported, 0u);
        // The choice by view alone (nothing counts as supported) takes the box top.
        SupportPlaneParams by_view;
        by_view.min_supported_fraction = 1.0f;
        const SupportPlane v = FindSupportPlane(c, by_view);
        ASSERT_TRUE(v.found);
        EXPECT_NEAR(-v.plane.w() / v.plane.z(), 1.0f, 0.01f);
    }
}

TEST(SupportPlane, ATableWithObjectsOnTheFloorIsTheTable) {
    // A robot's view: a large floor around a table with objects; the floor supports only the
    // table's legs.
    std::mt19937 rng(23);
    PointCloud c;
    AddFloorAndTable(c, rng);
    for (float x : {-0.45f, 0.45f}) {
        for (float y : {-0.25f, 0.25f})
            AddBox(c, {x, y, 0.0f}, {x + 0.03f, y + 0.03f, 0.72f}, 0.01f, rng);
    }
    AddBox(c, {-0.2f, -0.1f, 0.72f}, {0.0f, 0.1f, 0.9f}, 0.006f, rng);
    AddBox(c, {0.15f, -0.1f, 0.72f}, {0.3f, 0.05f, 0.8f}, 0.006f, rng);
    c.sensor_origin = {0.0f, -1.2f, 1.4f};
    HideBelowTableTop(c, 0.5f, 0.3f, 0.72f);
    c.SetUnorganized();
    c.sensor_orientation = Eigen::Quaternionf(Eigen::AngleAxisf(0.5f, Eigen::Vector3f::UnitX()));
    const SupportPlane s = FindSupportPlane(c, {});
    ASSERT_TRUE(s.found);
    EXPECT_NEAR(-s.plane.w() / s.plane.z(), 0.72f, 0.01f);
}

TEST(SupportPlane, APlaneThroughObjectTopsWithTheTableSeenBetweenIsNoSupport) {
    // Two boxes of equal height on a table the cloud holds only between them: the plane through
    // their tops has the table below it inside its hull.
    std::mt19937 rng(29);
    PointCloud c;
    AddBox(c, {-0.3f, -0.1f, 0.75f}, {-0.1f, 0.1f, 0.95f}, 0.006f, rng);
    AddBox(c, {0.1f, -0.1f, 0.75f}, {0.3f, 0.1f, 0.95f}, 0.006f, rng);
    AddHorizontal(c, -0.08f, 0.08f, -0.1f, 0.1f, 0.75f, 0.01f, rng);
    c.SetUnorganized();
    c.sensor_origin = {0.0f, -0.8f, 1.5f};
    const SupportPlane s = FindSupportPlane(c, {});
    if (s.found) {
        EXPECT_NEAR(-s.plane.w() / s.plane.z(), 0.75f, 0.01f);
    }
}

TEST(SupportPlane, ATableIsTheTableEvenWhenTheFloorHoldsMore) {
    // Thick legs and a box on the floor hold more points than the one cup on the table.
    std::mt19937 rng(37);
    PointCloud c;
    AddFloorAndTable(c, rng);
    for (float x : {-0.45f, 0.35f})
        AddBox(c, {x, -0.3f, 0.0f}, {x + 0.1f, -0.2f, 0.71f}, 0.008f, rng);
    AddBox(c, {0.8f, -0.6f, 0.0f}, {1.3f, -0.1f, 0.45f}, 0.008f, rng);       // on the floor
    AddBox(c, {-0.05f, -0.05f, 0.72f}, {0.03f, 0.03f, 0.82f}, 0.006f, rng);  // the cup
    c.sensor_origin = {0.0f, -1.2f, 1.4f};
    HideBelowTableTop(c, 0.5f, 0.3f, 0.72f);
    c.SetUnorganized();
    c.sensor_orientation = Eigen::Quaternionf(Eigen::AngleAxisf(0.5f, Eigen::Vector3f::UnitX()));
    const SupportPlane s = FindSupportPlane(c, {});
    ASSERT_TRUE(s.found);
    EXPECT_NEAR(-s.plane.w() / s.plane.z(), 0.72f, 0.01f);
    SupportPlaneParams no_raise;
    no_raise.raised_gap = 0.0f;  // the most support alone: the floor
    const SupportPlane f = FindSupportPlane(c, no_raise);
    ASSERT_TRUE(f.found);
    EXPECT_NEAR(-f.plane.w() / f.plane.z(), 0.0f, 0.01f);
}

TEST(SupportPlane, TheRegionAboveTheTableHoldsTheObjects) {
    const PointCloud c = TableUnderALargeBox(false);
    const TableRegion r = FindTableRegion(c, {}, {});
    ASSERT_TRUE(r.support.found);
    std::size_t above = 0;
    for (const auto& p : c.points) above += p.z() > 0.77f ? 1 : 0;
    EXPECT_GT(r.points.size(), above * 9 / 10);
}

// The table visible only in front of the objects: a box at its back stands beyond the hull of
// the table's points, and a wall rising behind the table must stay out.
TEST(SupportPlane, ObjectsBeyondTheVisibleTableAreInTheRegionWallsAreNot) {
    std::mt19937 rng(31);
    PointCloud c;
    AddHorizontal(c, -0.5f, 0.5f, -0.3f, 0.1f, 0.75f, 0.01f, rng);        // seen table
    AddBox(c, {-0.2f, -0.2f, 0.75f}, {0.0f, -0.05f, 0.9f}, 0.006f, rng);  // on it
    // Its lowest centimetres are hidden by the objects in front.
    AddBox(c, {-0.4f, 0.115f, 0.762f}, {-0.2f, 0.25f, 0.85f}, 0.006f, rng);  // at the back
    AddWall(c, 0.13f, 0.0f, 0.5f, 0.78f, 1.6f, 0.02f, rng);  // a cabinet side, its foot hidden
    c.SetUnorganized();
    c.sensor_origin = {0.0f, -1.0f, 1.5f};
    auto count = [&](const Indices& region, auto pred) {
        std::size_t n = 0;
        for (Index i : region) n += pred(c.points[i]) ? 1 : 0;
        return n;
    };
    auto back_box = [](const Eigen::Vector3f& p) { return p.y() > 0.112f && p.x() < -0.1f; };
    auto wall = [](const Eigen::Vector3f& p) { return p.y() > 0.12f && p.x() > -0.05f; };
    const TableRegion r = FindTableRegion(c, {}, {});
    ASSERT_TRUE(r.support.found);
    EXPECT_NEAR(-r.support.plane.w() / r.support.plane.z(), 0.75f, 0.01f);
    EXPECT_TRUE(std::is_sorted(r.points.begin(), r.points.end()));
    EXPECT_GT(count(r.points, back_box), 200u);
    EXPECT_EQ(count(r.points, wall), 0u);
    const TableRegion off = FindTableRegion(c, {}, {.edge_reach = 0.0f});
    EXPECT_EQ(count(off.points, back_box), 0u);
    EXPECT_THROW(FindTableRegion(c, {}, {.edge_reach = -1.0f}), InvalidArgument);
}

// An organized frame in world coordinates (z up): a table cut in two in the image by a strip of
// box fronts standing on it, a box top and a hole inside it, and after a run of invalid pixels a
// shelf at the table's height 1.5 m away.
PointCloud OrganizedTableFrame() {
    std::mt19937 rng(41);
    std::normal_distribution<float> noise(0.0f, 0.002f);
    const std::uint32_t w = 200, h = 120;
    PointCloud c;
    c.points.resize(std::size_t{w} * h);
    for (std::uint32_t v = 0; v < h; ++v) {
        for (std::uint32_t u = 0; u < w; ++u) {
            const float y = -0.3f + 0.005f * static_cast<float>(v);
            float x = -0.5f + 0.007f * static_cast<float>(u), z = 0.75f + noise(rng);
            if (u >= 140 && u < 150) {
                x = z = test::kNaN;  // nothing measured
            } else if (u >= 150) {
                x += 1.0f;  // the shelf
            } else if (u >= 60 && u < 70) {
                z = 0.75f + 0.02f * static_cast<float>(u - 59);  // box fronts, rows 0 to h
            } else if (u >= 90 && u < 110 && v >= 40 && v < 70) {
                z = 0.85f;  // a box top
            } else if (u >= 20 && u < 30 && v >= 80 && v < 90) {
                x = z = test::kNaN;  // a hole
            }
            c.points[std::size_t{v} * w + u] = {x, y, z};
        }
    }
    c.width = w;
    c.height = h;
    c.sensor_origin = {0.0f, -1.0f, 1.5f};
    return c;
}

// The organized path (pixel runs joined through neighbouring rows and border pixels) keeps the
// same patch as clustering every plane point in 3D, whatever the thread count.
TEST(SupportPlane, OrganizedPatchEqualsTheUnorganizedOneOnAnyThreadCount) {
    const PointCloud organized = OrganizedTableFrame();
    ASSERT_TRUE(organized.IsOrganized());
    PointCloud flat = organized;
    flat.SetUnorganized();
    const SupportPlane a = FindSupportPlane(organized, {.num_threads = 1});
    const SupportPlane b = FindSupportPlane(organized, {.num_threads = 2});
    const SupportPlane f = FindSupportPlane(flat, {.num_threads = 1});
    ASSERT_TRUE(a.found);
    ASSERT_TRUE(f.found);
    EXPECT_EQ(a.plane, f.plane);
    EXPECT_EQ(a.inliers, f.inliers);
    EXPECT_EQ(a.inliers, b.inliers);
    EXPECT_EQ(a.hull.size(), b.hull.size());
    // Both halves of the table, nothing of the shelf.
    std::size_t left = 0, right = 0;
    for (Index i : a.inliers) {
        const Eigen::Vector3f& p = organized.points[i];
        EXPECT_LT(p.x(), 0.5f);
        left += p.x() < -0.1f ? 1 : 0;
        right += p.x() > 0.0f ? 1 : 0;
    }
    EXPECT_GT(left, 5000u);
    EXPECT_GT(right, 3000u);
    const TableRegion ra = FindTableRegion(organized, {.num_threads = 1}, {});
    const TableRegion rb = FindTableRegion(organized, {.num_threads = 2}, {});
    EXPECT_EQ(ra.points, rb.points);
}

TEST(SupportPlane, NoPlaneAndContract) {
    EXPECT_FALSE(FindSupportPlane(PointCloud{}, {}).found);
    EXPECT_FALSE(FindSupportPlane(test::RandomCloud(2000, 9), {}).found);
    SupportPlaneParams p;
    p.distance_threshold = -0.01f;
    EXPECT_THROW(FindSupportPlane(RoomWithTable(), p), InvalidArgument);
    p = {};
    p.up = Eigen::Vector3f::Zero();
    EXPECT_THROW(FindSupportPlane(RoomWithTable(), p), InvalidArgument);
    p = {};
    p.max_candidates = 0;
    EXPECT_THROW(FindSupportPlane(RoomWithTable(), p), InvalidArgument);
    p = {};
    p.min_supported_fraction = 1.5f;
    EXPECT_THROW(FindSupportPlane(RoomWithTable(), p), InvalidArgument);
    EXPECT_THROW(FindSupportPlane(RoomWithTable(), {}, {.min_height = 0.3f, .max_height = 0.1f}),
                 InvalidArgument);
}

TEST(SupportPlane, DeterministicForASeed) {
    const PointCloud c = RoomWithTable();
    const SupportPlane a = FindSupportPlane(c, {.num_threads = 1});
    const SupportPlane b = FindSupportPlane(c, {.num_threads = 2});
    EXPECT_EQ(a.plane, b.plane);
    EXPECT_EQ(a.inliers, b.inliers);
}

}  // namespace
}  // namespace multicue

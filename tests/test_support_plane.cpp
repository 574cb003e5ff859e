// Support plane selection on constructed scenes: the largest near-horizontal plane nearest the
// viewpoint, its connected patch and hull, and the three ways of finding "up".

#include <random>

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

// Kitchen mapping stages on small synthetic kitchens: room axes of a rotated room, structure,
// handle vs knob, hinge side from the handle, articulation from a synthetic opened door and a
// pulled-out drawer, export round trip, bad input.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <random>

#include <tinyxml.h>

#include "kitchen_test_data.hpp"
#include "multicue/core/exceptions.hpp"
#include "multicue/io/urdf.hpp"
#include "multicue/mapping/fronts.hpp"
#include "multicue/mapping/kitchen_map.hpp"
#include "multicue/mapping/map_export.hpp"
#include "multicue/ml/classifier.hpp"
#include "multicue/ml/dataset.hpp"
#include "test_util.hpp"

namespace multicue {
namespace {

using namespace mapping;

constexpr float kDeg = std::numbers::pi_v<float> / 180.0f;

/// Smallest angle between v and any of the frame's axes (either sign) [deg].
float AngleToFrame(const Eigen::Vector3f& v, const Eigen::Matrix3f& axes) {
    return std::acos(std::min(1.0f, (axes.transpose() * v).cwiseAbs().maxCoeff())) / kDeg;
}

TEST(RoomAxes, RecoversTheAxesOfARotatedRoom) {
    for (const float yaw : {0.0f, 23.0f, 67.0f, 141.0f}) {
        test::SyntheticKitchen k = test::MakeSyntheticKitchen(3);
        const Eigen::Matrix3f R = (Eigen::AngleAxisf(yaw * kDeg, Eigen::Vector3f::UnitZ()) *
                                   Eigen::AngleAxisf(2.0f * kDeg, Eigen::Vector3f::UnitX()))
                                      .toRotationMatrix();
        test::RotateCloud(k.cloud, R);
        // Noisy normals: 3 degrees of jitter.
        std::mt19937 rng(5);
        std::normal_distribution<float> g(0.0f, 0.05f);
        for (auto& n : k.cloud.normals)
            n = (n + Eigen::Vector3f(g(rng), g(rng), g(rng))).normalized();
        const RoomAxesResult r = EstimateRoomAxes(k.cloud, {.up = Eigen::Vector3f::UnitZ()});
        ASSERT_TRUE(r.found) << yaw;
        for (int a = 0; a < 3; ++a) {
            EXPECT_LT(AngleToFrame(R.col(a), r.frame.axes), 1.0f) << "yaw " << yaw << " axis " << a;
        }
        EXPECT_GT(r.frame.Up().dot(R.col(2)), 0.99f);
        EXPECT_NEAR(r.frame.axes.determinant(), 1.0f, 1e-4f);
        EXPECT_GT(r.inliers, r.used / 2);
    }
}

TEST(RoomAxes, DeterministicAndContracts) {
    const test::SyntheticKitchen k = test::MakeSyntheticKitchen(4);
    const auto a = EstimateRoomAxes(k.cloud, {.seed = 9});
    const auto b = EstimateRoomAxes(k.cloud, {.seed = 9});
    EXPECT_TRUE(a.frame.axes.isApprox(b.frame.axes, 0.0f));
    EXPECT_THROW(EstimateRoomAxes(k.cloud, {.angle_threshold_deg = 0.0f}), InvalidArgument);
    EXPECT_THROW(EstimateRoomAxes(k.cloud, {.max_iterations = 0}), InvalidArgument);
    EXPECT_THROW(EstimateRoomAxes(k.cloud, {.up = Eigen::Vector3f::Zero()}), InvalidArgument);
    PointCloud no_normals = k.cloud;
    no_normals.normals.clear();
    EXPECT_THROW(EstimateRoomAxes(no_normals), DataError);
    EXPECT_FALSE(EstimateRoomAxes(PointCloud()).found);
}

TEST(RoomStructure, FloorCeilingWallsWorktopAndFace) {
    const test::SyntheticKitchen k = test::MakeSyntheticKitchen(1);
    const RoomStructure s = SegmentRoomStructure(k.cloud, RoomFrame{}, {});
    EXPECT_NEAR(s.floor_height, 0.0f, 0.01f);
    EXPECT_NEAR(s.ceiling_height, 2.5f, 0.01f);
    int walls = 0, faces = 0, worktops = 0;
    for (const auto& c : s.components) {
        walls += c.label == MapClass::kWall;
        worktops += c.label == MapClass::kWorktop;
        if (c.label == MapClass::kFace && c.axis == 1 && c.area > 0.5f) {
            ++faces;
            EXPECT_NEAR(-c.plane.w() * c.plane.y(), k.face_y, 0.01f);  // the plane y = 2.4
            EXPECT_LT(c.plane.y(), 0.0f);                              // facing the sensor
        }
    }
    EXPECT_EQ(walls, 2);
    EXPECT_EQ(worktops, 1);
    EXPECT_EQ(faces, 1);
    EXPECT_THROW(SegmentRoomStructure(k.cloud, RoomFrame{}, {.distance_threshold = -1.0f}),
                 InvalidArgument);
    EXPECT_THROW(SegmentRoomStructure(k.cloud, RoomFrame{}, {}, std::vector<float>(3, 1.0f)),
                 InvalidArgument);
}

// A close view: a strip of floor in front of the counters, the underside of a shelf seen from
// below, a counter on a cupboard front away from every wall and a table with a short apron.
TEST(RoomStructure, AStripOfFloorAndACounterAwayFromTheWalls) {
    std::mt19937 rng(3);
    PointCloud c;
    c.sensor_origin = Eigen::Vector3f(0.0f, -0.5f, 1.4f);
    const Color grey{128, 128, 128, 255};
    const Eigen::Vector3f ux(1, 0, 0), uy(0, 1, 0), uz(0, 0, 1);
    // Floor strip: 2.0 x 0.08 m (0.16 m^2; 0.2-0.27 m^2 of 3 cm cells).
    test::AddPatch(c, {-1.0f, 0.85f, 0.0f}, 2.0f * ux, 0.08f * uy, 0.01f, uz, grey, 0.0f, rng);
    // Underside of a shelf, 0.5 x 0.4 m, 2 m up, facing down.
    test::AddPatch(c, {-0.25f, 1.2f, 2.0f}, 0.5f * ux, 0.4f * uy, 0.01f, -uz, grey, 0.0f, rng);
    // Counter 0.9 m high on a cupboard front 0.78 m tall, 12 cm behind its edge.
    test::AddPatch(c, {-1.0f, 1.0f, 0.9f}, 1.0f * ux, 0.6f * uy, 0.01f, uz, grey, 0.0f, rng);
    test::AddPatch(c, {-1.0f, 1.12f, 0.1f}, 1.0f * ux, 0.78f * uz, 0.01f, -uy, grey, 0.0f, rng);
    // Table 0.75 m high with an 11 cm apron and two legs 5 cm wide in view.
    test::AddPatch(c, {0.2f, 1.0f, 0.75f}, 0.8f * ux, 0.8f * uy, 0.01f, uz, grey, 0.0f, rng);
    test::AddPatch(c, {0.2f, 1.02f, 0.62f}, 0.8f * ux, 0.11f * uz, 0.01f, -uy, grey, 0.0f, rng);
    for (const float x : {0.22f, 0.93f}) {
        test::AddPatch(c, {x, 1.03f, 0.02f}, 0.05f * ux, 0.58f * uz, 0.01f, -uy, grey, 0.0f, rng);
    }
    auto label_at = [](const RoomStructure& s, float height) {
        for (const auto& comp : s.components) {
            if (comp.axis == 2 && std::abs(std::abs(comp.plane.w()) - height) < 0.02f)
                return comp.label;
        }
        return MapClass::kNone;
    };
    const RoomStructure s = SegmentRoomStructure(c, RoomFrame{}, {});
    EXPECT_NEAR(s.floor_height, 0.0f, 0.01f);
    EXPECT_TRUE(std::isnan(s.ceiling_height));  // a shelf's underside is no ceiling
    EXPECT_EQ(label_at(s, 0.9f), MapClass::kWorktop);
    EXPECT_EQ(label_at(s, 0.75f), MapClass::kTable);
    // Without the face rule the counter is a table; with the floor needing 0.3 m^2, no floor.
    const RoomStructure t =
        SegmentRoomStructure(c, RoomFrame{}, {.min_floor_area = 0.3f, .worktop_face_height = 0.0f});
    EXPECT_TRUE(std::isnan(t.floor_height));
    EXPECT_EQ(label_at(t, 0.9f), MapClass::kTable);
    EXPECT_THROW(SegmentRoomStructure(c, RoomFrame{}, {.worktop_face_height = -1.0f}),
                 InvalidArgument);
    EXPECT_THROW(SegmentRoomStructure(c, RoomFrame{}, {.min_ceiling_area = 0.0f}), InvalidArgument);
    // Seen from 1.6 m, the table top lies 0.85 m below the sensor. With the floor strip too
    // small, the table is no floor: the counter's front, the legs and the strip lie below it.
    c.sensor_origin.z() = 1.6f;
    const RoomStructure high = SegmentRoomStructure(c, RoomFrame{}, {.min_floor_area = 0.3f});
    EXPECT_TRUE(std::isnan(high.floor_height));
    EXPECT_EQ(label_at(high, 0.75f), MapClass::kTable);
    EXPECT_NEAR(SegmentRoomStructure(c, RoomFrame{}, {}).floor_height, 0.0f, 0.01f);
    const RoomStructure off = SegmentRoomStructure(
        c, RoomFrame{}, {.min_floor_area = 0.3f, .max_below_floor_share = 1.0f});
    EXPECT_NEAR(off.floor_height, 0.75f, 0.01f);
    EXPECT_THROW(SegmentRoomStructure(c, RoomFrame{}, {.max_below_floor_share = -0.1f}),
                 InvalidArgument);
}

TEST(Fixtures, HandleVersusKnob) {
    std::mt19937 rng(2);
    PlanarComponent face;
    face.axis = 1;
    face.plane = Eigen::Vector4f(0, -1, 0, 2.4f);  // y = 2.4, facing -y
    face.min = {-3.0f, 0.0f};
    face.max = {3.0f, 1.0f};
    PointCloud c;
    test::AddHandle(c, {1.0f, 2.4f, 0.5f}, 0.2f, rng);
    const auto handle_points = static_cast<Index>(c.size());
    test::AddKnob(c, {1.5f, 2.4f, 0.5f}, rng);
    Indices bar(handle_points), knob;
    for (Index i = 0; i < handle_points; ++i) bar[i] = i;
    for (Index i = handle_points; i < c.size(); ++i) knob.push_back(i);
    Fixture f;
    ASSERT_TRUE(ClassifyFixture(c, bar, face, RoomFrame{}, {}, f));
    EXPECT_EQ(f.type, FixtureType::kHandle);
    EXPECT_NEAR(f.length, 0.2f, 0.01f);
    EXPECT_GT(std::abs(f.direction.x()), 0.99f);
    EXPECT_NEAR(f.protrusion, 0.035f, 0.005f);
    EXPECT_GT(f.line_inlier_ratio, 0.3f);
    ASSERT_TRUE(ClassifyFixture(c, knob, face, RoomFrame{}, {}, f));
    EXPECT_EQ(f.type, FixtureType::kKnob);
    EXPECT_NEAR(f.center.x(), 1.5f, 0.01f);
    // A long plank in front of the face is neither (too wide to be a handle's bar, too big for a
    // knob).
    PointCloud plank;
    test::AddPatch(plank, {0, 2.35f, 0.2f}, {0.3f, 0, 0}, {0, 0, 0.25f}, 0.005f, {0, -1, 0},
                   Color{}, 0.0f, rng);
    Indices all(plank.size());
    for (Index i = 0; i < plank.size(); ++i) all[i] = i;
    EXPECT_FALSE(ClassifyFixture(plank, all, face, RoomFrame{}, {}, f));
}

TEST(Fixtures, FoundInFrontOfTheFaceOnly) {
    const test::SyntheticKitchen k = test::MakeSyntheticKitchen(1);
    const RoomStructure s = SegmentRoomStructure(k.cloud, RoomFrame{}, {});
    const FixtureResult r = DetectFixtures(k.cloud, RoomFrame{}, s, {});
    ASSERT_EQ(r.fixtures.size(), 2u);
    for (const Fixture& f : r.fixtures) {
        EXPECT_EQ(f.type, FixtureType::kHandle);
        const bool door = std::abs(f.center.x() - 1.03f) < 0.02f;
        const bool drawer = std::abs(f.center.x() - 1.65f) < 0.02f;
        EXPECT_TRUE(door || drawer) << f.center.transpose();
        EXPECT_GT(std::abs((door ? f.direction.z() : f.direction.x())), 0.98f);
    }
    EXPECT_THROW(DetectFixtures(k.cloud, RoomFrame{}, s, {.min_height = 0.2f}), InvalidArgument);
}

/// A front on the plane y = 2.4 facing -y, x 0.6 .. 1.1, z 0.15 .. 0.8 (face u = -x, v = z).
Front DoorFront() {
    PlanarComponent face;
    face.axis = 1;
    face.plane = Eigen::Vector4f(0, -1, 0, 2.4f);
    Front f;
    f.u_axis = PlaneU(face, RoomFrame{});
    f.v_axis = PlaneV(face, RoomFrame{});
    f.normal = -Eigen::Vector3f::UnitY();
    const Eigen::Vector2f a(Eigen::Vector3f(0.6f, 2.4f, 0.15f).dot(f.u_axis), 0.15f);
    const Eigen::Vector2f b(Eigen::Vector3f(1.1f, 2.4f, 0.8f).dot(f.u_axis), 0.8f);
    f.min = a.cwiseMin(b);
    f.max = a.cwiseMax(b);
    f.center = Eigen::Vector3f(0.85f, 2.4f, 0.475f);
    f.fixtures = {0};
    return f;
}

Fixture HandleAt(const Eigen::Vector3f& c, bool vertical) {
    Fixture h;
    h.type = FixtureType::kHandle;
    h.center = c;
    h.direction = vertical ? Eigen::Vector3f::UnitZ() : Eigen::Vector3f::UnitX();
    h.length = 0.15f;
    return h;
}

/// Where a point of the front goes when the joint opens by a small amount.
Eigen::Vector3f Opened(const Articulation& a, const Eigen::Vector3f& p, float amount) {
    if (a.type == JointType::kPrismatic) return p + a.axis * amount;
    return a.origin + Eigen::AngleAxisf(amount, a.axis) * (p - a.origin);
}

TEST(Articulation, HingeSideFromTheHandle) {
    const Front f = DoorFront();
    // Vertical handle near the right edge (x = 1.05): hinged at the left edge x = 0.6.
    Articulation a =
        ArticulationFromFixtures(f, {HandleAt({1.05f, 2.365f, 0.5f}, true)}, RoomFrame{}, 0.0f);
    ASSERT_EQ(a.type, JointType::kRevolute);
    EXPECT_GT(std::abs(a.axis.z()), 0.999f);
    EXPECT_NEAR(a.origin.x(), 0.6f, 0.01f);
    // The hinge line lies the hinge depth behind the front's surface (y = 2.4).
    EXPECT_NEAR(a.origin.y(), 2.4f + ArticulationParams{}.hinge_depth, 1e-4f);
    ArticulationParams flush;
    flush.hinge_depth = 0.0f;
    EXPECT_NEAR(ArticulationFromFixtures(f, {HandleAt({1.05f, 2.365f, 0.5f}, true)}, RoomFrame{},
                                         0.0f, flush)
                    .origin.y(),
                2.4f, 1e-4f);
    flush.hinge_depth = -0.01f;
    EXPECT_THROW(ArticulationFromFixtures(f, {HandleAt({1.05f, 2.365f, 0.5f}, true)}, RoomFrame{},
                                          0.0f, flush),
                 InvalidArgument);
    // Opening swings the free edge out of the furniture (towards -y).
    EXPECT_LT(Opened(a, {1.1f, 2.4f, 0.5f}, 0.1f).y(), 2.39f);
    // Near the left edge: hinged at the right edge.
    a = ArticulationFromFixtures(f, {HandleAt({0.65f, 2.365f, 0.5f}, true)}, RoomFrame{}, 0.0f);
    ASSERT_EQ(a.type, JointType::kRevolute);
    EXPECT_NEAR(a.origin.x(), 1.1f, 0.01f);
    EXPECT_LT(Opened(a, {0.6f, 2.4f, 0.5f}, 0.1f).y(), 2.39f);
    // Horizontal handle near the top of a tall front: hinged at the bottom (oven, dishwasher).
    a = ArticulationFromFixtures(f, {HandleAt({0.85f, 2.365f, 0.75f}, false)}, RoomFrame{}, 0.0f);
    ASSERT_EQ(a.type, JointType::kRevolute);
    EXPECT_GT(std::abs(a.axis.x()), 0.999f);
    EXPECT_NEAR(a.origin.z(), 0.15f, 0.01f);
    EXPECT_LT(Opened(a, {0.85f, 2.4f, 0.8f}, 0.1f).y(), 2.39f);
    // Horizontal handle on a low front: a drawer pulled out along the normal.
    Front drawer = f;
    drawer.min.y() = 0.6f;
    drawer.center.z() = 0.7f;
    a = ArticulationFromFixtures(drawer, {HandleAt({0.85f, 2.365f, 0.7f}, false)}, RoomFrame{},
                                 0.0f);
    ASSERT_EQ(a.type, JointType::kPrismatic);
    EXPECT_TRUE(a.axis.isApprox(-Eigen::Vector3f::UnitY()));
    // No fixture, no joint.
    Front bare = f;
    bare.fixtures.clear();
    EXPECT_EQ(ArticulationFromFixtures(bare, {}, RoomFrame{}, 0.0f).type, JointType::kUnknown);
    EXPECT_THROW(ArticulationFromFixtures(f, {}, RoomFrame{}, 0.0f, {.top_share = 2.0f}),
                 InvalidArgument);
}

TEST(Articulation, AWallCupboardsFrontIsNoDrawer) {
    // A short front (z 0.15 .. 0.5) with a horizontal handle in its middle near the top: low
    // down a drawer; 1.45 m above the floor (a wall cupboard) a flap hinged at its bottom edge.
    Front f = DoorFront();
    f.max.y() = 0.5f;
    f.center.z() = 0.325f;
    const Fixture h = HandleAt({0.85f, 2.365f, 0.45f}, false);
    EXPECT_EQ(ArticulationFromFixtures(f, {h}, RoomFrame{}, 0.0f).type, JointType::kPrismatic);
    const Articulation a = ArticulationFromFixtures(f, {h}, RoomFrame{}, -1.3f);
    ASSERT_EQ(a.type, JointType::kRevolute);
    EXPECT_GT(std::abs(a.axis.x()), 0.999f);
    EXPECT_NEAR(a.origin.z(), 0.15f, 0.01f);
    EXPECT_LT(Opened(a, {0.85f, 2.4f, 0.5f}, 0.1f).y(), 2.39f);
    // The handle near the bottom: hinged at the top edge.
    const Articulation b =
        ArticulationFromFixtures(f, {HandleAt({0.85f, 2.365f, 0.2f}, false)}, RoomFrame{}, -1.3f);
    ASSERT_EQ(b.type, JointType::kRevolute);
    EXPECT_NEAR(b.origin.z(), 0.5f, 0.01f);
    ArticulationParams drawers;
    drawers.wall_drawers = true;
    EXPECT_EQ(ArticulationFromFixtures(f, {h}, RoomFrame{}, -1.3f, drawers).type,
              JointType::kPrismatic);
}

TEST(Articulation, TwoMountsSideBySideAreOneHorizontalHandle) {
    // A low front (z 0.45 .. 0.7) with only the two mounts of its bar found, 5 cm from either
    // end, each 2 cm long and pointing anywhere: one horizontal handle centred across it, a
    // drawer. Either mount alone, near a side edge, makes a door hinged at the other edge.
    Front f = DoorFront();
    f.min.y() = 0.45f;
    f.max.y() = 0.7f;
    f.center.z() = 0.575f;
    f.fixtures = {0, 1};
    Fixture left = HandleAt({0.65f, 2.365f, 0.62f}, true), right = left;
    left.length = right.length = 0.02f;
    right.center.x() = 1.05f;
    right.center.z() = 0.625f;
    right.direction = Eigen::Vector3f(0.6f, 0.0f, 0.8f);
    const Articulation a = ArticulationFromFixtures(f, {left, right}, RoomFrame{}, 0.0f);
    EXPECT_EQ(a.type, JointType::kPrismatic);
    EXPECT_TRUE(a.axis.isApprox(-Eigen::Vector3f::UnitY()));
    Front one = f;
    one.fixtures = {0};
    EXPECT_EQ(ArticulationFromFixtures(one, {left}, RoomFrame{}, 0.0f).type, JointType::kRevolute);
    // One above the other they are no horizontal handle: the main one (vertical) makes a door.
    right.center = Eigen::Vector3f(0.65f, 2.365f, 0.5f);
    EXPECT_EQ(ArticulationFromFixtures(f, {left, right}, RoomFrame{}, 0.0f).type,
              JointType::kRevolute);
    // Off, the first mount decides: a door.
    right = left;
    right.center.x() = 1.05f;
    EXPECT_EQ(ArticulationFromFixtures(f, {left, right}, RoomFrame{}, 0.0f,
                                       {.pair_fixture_max_length = 0.0f})
                  .type,
              JointType::kRevolute);
    EXPECT_THROW(ArticulationFromFixtures(f, {left, right}, RoomFrame{}, 0.0f,
                                          {.pair_fixture_max_length = -1.0f}),
                 InvalidArgument);
    // A door's vertical handle near its right edge with a small stray fixture near its left edge
    // is no pair: the handle stays the main fixture.
    Fixture handle = HandleAt({1.05f, 2.365f, 0.6f}, true);
    handle.length = 0.2f;
    const Articulation door = ArticulationFromFixtures(f, {handle, left}, RoomFrame{}, 0.0f);
    ASSERT_EQ(door.type, JointType::kRevolute);
    EXPECT_NEAR(door.origin.x(), 0.6f, 0.01f);
}

TEST(Articulation, AFrontTallerThanAnyDrawerIsADoor) {
    // DoorFront is 0.65 m tall; a horizontal handle in its middle, off to the right.
    const Front f = DoorFront();
    const Fixture h = HandleAt({0.95f, 2.365f, 0.5f}, false);
    const Articulation a = ArticulationFromFixtures(f, {h}, RoomFrame{}, 0.0f);
    ASSERT_EQ(a.type, JointType::kRevolute);
    EXPECT_GT(std::abs(a.axis.z()), 0.999f);
    EXPECT_NEAR(a.origin.x(), 0.6f, 0.01f);
    EXPECT_LT(Opened(a, {1.1f, 2.4f, 0.5f}, 0.1f).y(), 2.39f);
    ArticulationParams tall;
    tall.drawer_max_height = 0.7f;
    EXPECT_EQ(ArticulationFromFixtures(f, {h}, RoomFrame{}, 0.0f, tall).type,
              JointType::kPrismatic);
    tall.drawer_max_height = 0.0f;
    EXPECT_THROW(ArticulationFromFixtures(f, {h}, RoomFrame{}, 0.0f, tall), InvalidArgument);
}

TEST(Articulation, ANarrowFrontWithAHandleAtItsTopIsHingedAtItsSide) {
    // DoorFront cut to 0.3 m wide (x 0.6 .. 0.9), 0.65 m tall; a horizontal handle near its
    // top, right of its middle: narrower than any oven or dishwasher, hinged at the left edge.
    Front f = DoorFront();
    f.max.x() = f.min.x() + 0.3f;
    f.center.x() = 0.75f;
    const Fixture h = HandleAt({0.8f, 2.365f, 0.75f}, false);
    const Articulation a = ArticulationFromFixtures(f, {h}, RoomFrame{}, 0.0f);
    ASSERT_EQ(a.type, JointType::kRevolute);
    EXPECT_GT(std::abs(a.axis.z()), 0.999f);
    EXPECT_NEAR(a.origin.x(), 0.6f, 0.01f);
    ArticulationParams any;
    any.flap_min_width = 0.0f;
    const Articulation b = ArticulationFromFixtures(f, {h}, RoomFrame{}, 0.0f, any);
    ASSERT_EQ(b.type, JointType::kRevolute);
    EXPECT_GT(std::abs(b.axis.x()), 0.999f);
    EXPECT_NEAR(b.origin.z(), 0.15f, 0.01f);
    any.flap_min_width = -0.1f;
    EXPECT_THROW(ArticulationFromFixtures(f, {h}, RoomFrame{}, 0.0f, any), InvalidArgument);
}

/// DoorFront resized to x 0 .. width, z 0.15 .. 0.15 + height.
Front FrontOfSize(float width, float height) {
    Front f = DoorFront();
    const Eigen::Vector2f a(Eigen::Vector3f(0.0f, 2.4f, 0.15f).dot(f.u_axis), 0.15f);
    const Eigen::Vector2f b(Eigen::Vector3f(width, 2.4f, 0.15f + height).dot(f.u_axis),
                            0.15f + height);
    f.min = a.cwiseMin(b);
    f.max = a.cwiseMax(b);
    f.center = Eigen::Vector3f(width / 2, 2.4f, 0.15f + height / 2);
    return f;
}

TEST(Articulation, AHorizontalHandleAtASideEdgeMarksASideDoor) {
    // A wide wall cupboard front (1.2 x 0.45 m, 1.3 m above the floor) with a short horizontal
    // handle in its lower right corner: a door hinged at its left edge, not a flap hinged at its
    // top (CabinetUpper/46744 of the model library).
    const Front wide = FrontOfSize(1.2f, 0.45f);
    Fixture h = HandleAt({1.12f, 2.365f, 0.2f}, false);
    h.length = 0.05f;
    Articulation door = ArticulationFromFixtures(wide, {h}, RoomFrame{}, -1.3f);
    ASSERT_EQ(door.type, JointType::kRevolute);
    EXPECT_GT(std::abs(door.axis.z()), 0.999f);
    EXPECT_NEAR(door.origin.x(), 0.0f, 0.01f);
    EXPECT_LT(Opened(door, {1.2f, 2.4f, 0.3f}, 0.1f).y(), 2.39f);
    // The same handle centred: a flap hinged at the top edge.
    h.center.x() = 0.6f;
    const Articulation flap = ArticulationFromFixtures(wide, {h}, RoomFrame{}, -1.3f);
    ASSERT_EQ(flap.type, JointType::kRevolute);
    EXPECT_GT(std::abs(flap.axis.x()), 0.999f);
    EXPECT_NEAR(flap.origin.z(), 0.6f, 0.01f);
    // With the rule off, the corner handle makes a flap too.
    h.center.x() = 0.08f;
    ArticulationParams off;
    off.side_share = 0.0f;
    const Articulation offed = ArticulationFromFixtures(wide, {h}, RoomFrame{}, -1.3f, off);
    ASSERT_EQ(offed.type, JointType::kRevolute);
    EXPECT_GT(std::abs(offed.axis.x()), 0.999f);
    // At the left edge: hinged at the right edge.
    door = ArticulationFromFixtures(wide, {h}, RoomFrame{}, -1.3f);
    ASSERT_EQ(door.type, JointType::kRevolute);
    EXPECT_GT(std::abs(door.axis.z()), 0.999f);
    EXPECT_NEAR(door.origin.x(), 1.2f, 0.01f);
    // Low down, a drawer's height (0.3 m) with the handle at its edge: still a drawer.
    h.center.z() = 0.3f;
    EXPECT_EQ(ArticulationFromFixtures(FrontOfSize(1.2f, 0.3f), {h}, RoomFrame{}, 0.0f).type,
              JointType::kPrismatic);
    // A cupboard door 0.45 x 0.75 m with a short handle in its upper right corner: hinged at its
    // left edge, not at its bottom as an oven's door; 0.86 m wide (a dishwasher's), at its
    // bottom.
    h.center = Eigen::Vector3f(0.4f, 2.365f, 0.85f);
    door = ArticulationFromFixtures(FrontOfSize(0.45f, 0.75f), {h}, RoomFrame{}, 0.0f);
    ASSERT_EQ(door.type, JointType::kRevolute);
    EXPECT_GT(std::abs(door.axis.z()), 0.999f);
    EXPECT_NEAR(door.origin.x(), 0.0f, 0.01f);
    h.center.x() = 0.78f;
    const Articulation bottom =
        ArticulationFromFixtures(FrontOfSize(0.86f, 0.75f), {h}, RoomFrame{}, 0.0f);
    ASSERT_EQ(bottom.type, JointType::kRevolute);
    EXPECT_GT(std::abs(bottom.axis.x()), 0.999f);
    EXPECT_NEAR(bottom.origin.z(), 0.15f, 0.01f);
    off.side_share = 0.5f;
    EXPECT_THROW(ArticulationFromFixtures(wide, {h}, RoomFrame{}, 0.0f, off), InvalidArgument);
    off.side_share = 0.2f;
    off.edge_flap_min_width = -1.0f;
    EXPECT_THROW(ArticulationFromFixtures(wide, {h}, RoomFrame{}, 0.0f, off), InvalidArgument);
}

/// `f` moved up by `dz`.
Front Raised(Front f, float dz) {
    f.min.y() += dz;
    f.max.y() += dz;
    f.center.z() += dz;
    return f;
}

TEST(Articulation, ADeepFrontInAStackOfDrawersIsADrawer) {
    // A pan drawer 0.92 x 0.5 m with a handle centred near its top (MiniFridgeBase/45746 of the
    // model library): alone, an oven's door hinged at its bottom edge; with a drawer as wide
    // directly above it (3 mm gap), a drawer.
    std::vector<Front> fronts = {FrontOfSize(0.92f, 0.5f),
                                 Raised(FrontOfSize(0.92f, 0.3f), 0.503f)};
    fronts[1].fixtures = {1};
    const std::vector<Fixture> fx = {HandleAt({0.46f, 2.365f, 0.6f}, false),
                                     HandleAt({0.46f, 2.365f, 0.9f}, false)};
    const Articulation alone = ArticulationFromFixtures(fronts[0], fx, RoomFrame{}, 0.0f);
    ASSERT_EQ(alone.type, JointType::kRevolute);
    EXPECT_GT(std::abs(alone.axis.x()), 0.999f);
    const Articulation stacked = ArticulationFromFixtures(fronts, 0, fx, RoomFrame{}, 0.0f);
    ASSERT_EQ(stacked.type, JointType::kPrismatic);
    EXPECT_LT((stacked.axis - fronts[0].normal).norm(), 1e-5f);
    EXPECT_EQ(ArticulationFromFixtures(fronts, 1, fx, RoomFrame{}, 0.0f).type,
              JointType::kPrismatic);
    // The drawer above found 5 cm short at one side: its handle, centred on the deep front,
    // still makes a stack.
    Front short_above = Raised(FrontOfSize(0.87f, 0.3f), 0.503f);
    short_above.fixtures = {1};
    EXPECT_EQ(ArticulationFromFixtures(std::vector<Front>{fronts[0], short_above}, 0, fx,
                                       RoomFrame{}, 0.0f)
                  .type,
              JointType::kPrismatic);
    // Off: the flap.
    ArticulationParams off;
    off.stack_tolerance = 0.0f;
    EXPECT_EQ(ArticulationFromFixtures(fronts, 0, fx, RoomFrame{}, 0.0f, off).type,
              JointType::kRevolute);
    // No stack: the front above narrower, or 10 cm higher up, or on another face, or with a
    // vertical handle, or an oven's door taller than any drawer.
    auto joint_with = [&](const Front& below, const Fixture& handle, const Front& above,
                          const Fixture& its_handle) {
        const std::vector<Front> two = {below, above};
        return ArticulationFromFixtures(two, 0, {handle, its_handle}, RoomFrame{}, 0.0f).type;
    };
    Front narrow = Raised(FrontOfSize(0.6f, 0.3f), 0.503f);
    narrow.fixtures = {1};
    EXPECT_EQ(joint_with(fronts[0], fx[0], narrow, fx[1]), JointType::kRevolute);
    EXPECT_EQ(joint_with(fronts[0], fx[0], Raised(fronts[1], 0.1f), fx[1]), JointType::kRevolute);
    Front elsewhere = fronts[1];
    elsewhere.face = 3;  // on another face (another piece of furniture)
    EXPECT_EQ(joint_with(fronts[0], fx[0], elsewhere, fx[1]), JointType::kRevolute);
    EXPECT_EQ(joint_with(fronts[0], fx[0], fronts[1], HandleAt({0.85f, 2.365f, 0.8f}, true)),
              JointType::kRevolute);
    // A door under a drawer with a handle running across its top near its free edge (centre 12
    // cm off the middle), or a drawer above with its handle off the middle: no stack.
    EXPECT_EQ(joint_with(fronts[0], HandleAt({0.58f, 2.365f, 0.6f}, false), fronts[1], fx[1]),
              JointType::kRevolute);
    EXPECT_EQ(joint_with(fronts[0], fx[0], fronts[1], HandleAt({0.3f, 2.365f, 0.9f}, false)),
              JointType::kRevolute);
    Front over_tall = Raised(FrontOfSize(0.92f, 0.2f), 0.703f);
    over_tall.fixtures = {1};
    EXPECT_EQ(joint_with(FrontOfSize(0.92f, 0.7f), HandleAt({0.46f, 2.365f, 0.8f}, false),
                         over_tall, fx[1]),
              JointType::kRevolute);
    // Bad parameters.
    off.stack_tolerance = -0.01f;
    EXPECT_THROW(ArticulationFromFixtures(fronts, 0, fx, RoomFrame{}, 0.0f, off), InvalidArgument);
    off.stack_tolerance = 0.04f;
    off.stack_centre_share = 0.5f;
    EXPECT_THROW(ArticulationFromFixtures(fronts, 0, fx, RoomFrame{}, 0.0f, off), InvalidArgument);
}

/// Adds to `c` the panels at y = 2.4 left and right of a door (x 0.3 .. 0.6 and 1.1 .. 1.4, z
/// 0.1 .. 0.9) and returns the door closed (x 0.6 .. 1.1, z 0.15 .. 0.8).
PointCloud AddPanelsBesideDoor(PointCloud& c, std::mt19937& rng) {
    test::AddPatch(c, {0.3f, 2.4f, 0.1f}, {0.3f, 0, 0}, {0, 0, 0.8f}, 0.01f, {0, -1, 0}, Color{},
                   0.001f, rng);
    test::AddPatch(c, {1.1f, 2.4f, 0.1f}, {0.3f, 0, 0}, {0, 0, 0.8f}, 0.01f, {0, -1, 0}, Color{},
                   0.001f, rng);
    PointCloud door;
    test::AddPatch(door, {0.6f, 2.4f, 0.15f}, {0.5f, 0, 0}, {0, 0, 0.65f}, 0.01f, {0, -1, 0},
                   Color{}, 0.001f, rng);
    return door;
}

/// The door as points (x 0.6 .. 1.1, z 0.15 .. 0.8), opened by `angle` about its left edge or
/// pulled out by `pull`, with a fixed frame around it.
PointCloud DoorScan(float angle, float pull) {
    std::mt19937 rng(7);
    PointCloud c;
    const PointCloud door = AddPanelsBesideDoor(c, rng);
    // Opening: about the vertical line x = 0.6, y = 2.4, the free edge swinging towards -y.
    const Eigen::Vector3f hinge(0.6f, 2.4f, 0.0f);
    const Eigen::Matrix3f R =
        Eigen::AngleAxisf(angle, -Eigen::Vector3f::UnitZ()).toRotationMatrix();
    for (const auto& p : door.points) {
        c.points.push_back(hinge + R * (p - hinge) - Eigen::Vector3f(0, pull, 0));
    }
    return c;
}

/// DoorScan's closed scan with the door taken away (its closed place empty), the frame kept.
PointCloud FrameWithoutTheDoor(const PointCloud& closed) {
    PointCloud frame;
    for (const auto& x : closed.points) {
        if (x.x() < 0.595f || x.x() > 1.105f) frame.points.push_back(x);
    }
    return frame;
}

/// DoorScan's frame with its door (x 0.6 .. 1.1, z 0.15 .. 0.8, y = 2.4, drawn with `seed`)
/// turned by `R` about `hinge`.
PointCloud DoorTurned(const PointCloud& closed, const Eigen::Vector3f& hinge,
                      const Eigen::Matrix3f& R, unsigned seed) {
    PointCloud opened = FrameWithoutTheDoor(closed);
    PointCloud door;
    std::mt19937 rng(seed);
    test::AddPatch(door, {0.6f, 2.4f, 0.15f}, {0.5f, 0, 0}, {0, 0, 0.65f}, 0.01f, {0, -1, 0},
                   Color{}, 0.001f, rng);
    for (const auto& x : door.points) opened.points.push_back(hinge + R * (x - hinge));
    return opened;
}

TEST(Articulation, LearnedJointsFromWhatTheFrontLooksLike) {
    // Two fronts of one face, a 0.92 x 0.5 m one with a horizontal handle centred near its top
    // and a 0.4 x 0.65 m door beside it with a vertical handle near its right edge.
    KitchenMap map;
    map.floor_height = 0.0f;
    Front deep = FrontOfSize(0.92f, 0.5f);
    deep.face = 0;
    deep.fixtures = {0};
    Front door = FrontOfSize(0.4f, 0.65f);
    door.face = 0;
    door.fixtures = {1};
    door.min.x() += 1.0f;  // 1 m along the face
    door.max.x() += 1.0f;
    door.center += door.u_axis;
    map.fronts = {deep, door};
    map.fixtures = {
        HandleAt(deep.center + Eigen::Vector3f(0, -0.035f, 0.2f), false),
        HandleAt(door.center + door.u_axis * 0.15f - Eigen::Vector3f(0, 0.035f, 0), true)};
    // The rules: the deep front alone is an oven's door hinged at its bottom, the door hinged at
    // its left edge.
    for (std::size_t i = 0; i < map.fronts.size(); ++i) {
        map.fronts[i].articulation =
            ArticulationFromFixtures(map.fronts, i, map.fixtures, map.frame, map.floor_height);
    }
    const auto class_of = [&](std::size_t i) {
        const Articulation& a = map.fronts[i].articulation;
        return JointClassOf(a.type, a.axis, a.origin, map.fronts[i], map.frame);
    };
    EXPECT_EQ(class_of(0), "revolute_bottom");
    EXPECT_EQ(class_of(1), "revolute_side");
    EXPECT_EQ(JointClassOf(JointType::kUnknown, {}, {}, deep, map.frame), "");
    const std::vector<float> x = JointFeatures(map, 0);
    ASSERT_EQ(x.size(), JointFeatureNames().size());
    const auto at = [&](const std::vector<float>& v, const char* name) {
        const auto& n = JointFeatureNames();
        return v[static_cast<std::size_t>(std::find(n.begin(), n.end(), name) - n.begin())];
    };
    EXPECT_NEAR(at(x, "width"), 0.92f, 1e-4f);
    EXPECT_NEAR(at(x, "height"), 0.5f, 1e-4f);
    EXPECT_NEAR(at(x, "bottom"), 0.15f, 1e-4f);
    EXPECT_NEAR(at(x, "top"), 0.65f, 1e-4f);
    EXPECT_EQ(at(x, "horizontal"), 1.0f);
    EXPECT_NEAR(at(x, "u"), 0.5f, 1e-4f);
    EXPECT_NEAR(at(x, "v"), 0.9f, 1e-4f);
    EXPECT_EQ(at(x, "piece_fronts"), 0.0f);  // no pieces grouped
    EXPECT_EQ(at(x, "rule_bottom"), 1.0f);   // the rules' answer
    EXPECT_EQ(at(x, "rule_prismatic") + at(x, "rule_side") + at(x, "rule_top"), 0.0f);
    const std::vector<float> y = JointFeatures(map, 1);
    EXPECT_EQ(at(y, "horizontal"), 0.0f);
    EXPECT_NEAR(at(y, "u"), 0.5f + 0.15f / 0.4f, 1e-4f);
    EXPECT_EQ(at(y, "rule_side"), 1.0f);
    EXPECT_THROW(JointFeatures(map, 2), std::out_of_range);
    // A classifier taught that wide fronts with a horizontal handle are drawers (noisy synthetic
    // rows) makes the deep front a drawer and leaves the door.
    ml::Dataset rows = ml::Dataset::WithBlocks({{"joint", JointFeatureNames()}});
    std::mt19937 rng(5);
    std::normal_distribution<float> noise(0.0f, 0.01f);
    for (int k = 0; k < 40; ++k) {
        std::vector<float> a = x, b = y;
        for (auto& v : a) v += noise(rng);
        for (auto& v : b) v += noise(rng);
        rows.AppendRow(a, "prismatic");
        rows.AppendRow(b, "revolute_side");
    }
    auto classifier = ml::CreateClassifier("rtrees:trees=20");
    classifier->Fit(rows);
    KitchenMap learned = map;
    const std::vector<std::size_t> changed = ClassifyJoints(learned, *classifier);
    ASSERT_EQ(changed, std::vector<std::size_t>{0});
    EXPECT_EQ(learned.fronts[0].articulation.type, JointType::kPrismatic);
    EXPECT_EQ(learned.fronts[0].articulation.source, "classifier");
    EXPECT_LT((learned.fronts[0].articulation.axis - deep.normal).norm(), 1e-5f);
    EXPECT_EQ(learned.fronts[1].articulation.origin, map.fronts[1].articulation.origin);
    // Deterministic; and a front whose joint came from motion is left alone.
    KitchenMap again = map;
    EXPECT_EQ(ClassifyJoints(again, *classifier), changed);
    KitchenMap moved = map;
    moved.fronts[0].articulation.source = "motion";
    EXPECT_TRUE(ClassifyJoints(moved, *classifier).empty());
    KitchenMap empty;
    EXPECT_TRUE(ClassifyJoints(empty, *classifier).empty());
    // Classifiers of another kind are refused.
    ml::Dataset other = ml::Dataset::WithBlocks({{"other", {"a", "b"}}});
    other.AppendRow(std::vector<float>{0, 1}, "prismatic");
    other.AppendRow(std::vector<float>{1, 0}, "revolute_side");
    auto foreign = ml::CreateClassifier("rtrees:trees=5");
    foreign->Fit(other);
    EXPECT_THROW(ClassifyJoints(again, *foreign), InvalidArgument);
    EXPECT_THROW(CheckJointClassifier(*ml::CreateClassifier("rtrees:trees=5")), InvalidArgument);
}

TEST(Articulation, FromASyntheticOpenedDoorAndDrawer) {
    const Front f = DoorFront();
    const PointCloud closed = DoorScan(0.0f, 0.0f);
    for (const float deg : {30.0f, 60.0f, 100.0f}) {
        const MotionResult m = ArticulationFromMotion(closed, DoorScan(deg * kDeg, 0.0f), f);
        ASSERT_TRUE(m.found) << deg;
        ASSERT_EQ(m.articulation.type, JointType::kRevolute) << deg;
        const Eigen::Vector3f axis = m.articulation.axis;
        EXPECT_LT(std::acos(std::min(1.0f, std::abs(axis.z()))) / kDeg, 2.0f) << deg;
        // The hinge line passes x = 0.6, y = 2.4.
        const Eigen::Vector3f o = m.articulation.origin;
        const Eigen::Vector3f at_z = o + axis * ((0.5f - o.z()) / axis.z());
        EXPECT_LT((at_z.head<2>() - Eigen::Vector2f(0.6f, 2.4f)).norm(), 0.02f) << deg;
        EXPECT_NEAR(m.opening / kDeg, deg, 3.0f);
        // A positive angle opens it.
        EXPECT_LT(Opened(m.articulation, {1.1f, 2.4f, 0.5f}, 0.1f).y(), 2.39f) << deg;
    }
    const MotionResult d = ArticulationFromMotion(closed, DoorScan(0.0f, 0.3f), f);
    ASSERT_TRUE(d.found);
    EXPECT_EQ(d.articulation.type, JointType::kPrismatic);
    EXPECT_NEAR(d.opening, 0.3f, 0.01f);
    EXPECT_LT(d.articulation.axis.y(), -0.99f);
    // Nothing moved: no motion.
    EXPECT_FALSE(ArticulationFromMotion(closed, closed, f).found);
    EXPECT_FALSE(ArticulationFromMotion(PointCloud(), closed, f).found);
    EXPECT_THROW(ArticulationFromMotion(closed, closed, f, {.parallel_deg = 0.0f}),
                 InvalidArgument);
}

/// The face at y = 2.4 left and right of drawers at x 0.7 .. 0.9 (x 0.3 .. 0.7 and 0.9 .. 1.3,
/// z 0.3 .. 0.9).
void AddFaceBesideDrawers(PointCloud& c, std::mt19937& rng) {
    test::AddPatch(c, {0.3f, 2.4f, 0.3f}, {0.4f, 0, 0}, {0, 0, 0.6f}, 0.01f, {0, -1, 0}, Color{},
                   0.001f, rng);
    test::AddPatch(c, {0.9f, 2.4f, 0.3f}, {0.4f, 0, 0}, {0, 0, 0.6f}, 0.01f, {0, -1, 0}, Color{},
                   0.001f, rng);
}

/// A drawer front (x 0.7 .. 0.9, z `bottom` .. `bottom + height`) in the face at y = 2.4,
/// pulled out by `pull` with its box's sides and bottom (from `box_offset` above the front's
/// bottom, `box_height` tall) in view.
void AddDrawer(PointCloud& c, float bottom, float height, float box_offset, float box_height,
               float pull, std::mt19937& rng) {
    const float y = 2.4f - pull;
    test::AddPatch(c, {0.7f, y, bottom}, {0.2f, 0, 0}, {0, 0, height}, 0.005f, {0, -1, 0}, Color{},
                   0.001f, rng);
    if (pull <= 0.0f) return;
    const float z = bottom + box_offset;
    for (const float x : {0.705f, 0.895f}) {
        test::AddPatch(c, {x, y, z}, {0, pull, 0}, {0, 0, box_height}, 0.005f,
                       {x < 0.8f ? 1.0f : -1.0f, 0, 0}, Color{}, 0.001f, rng);
    }
    test::AddPatch(c, {0.705f, y, z}, {0.19f, 0, 0}, {0, pull, 0}, 0.005f, {0, 0, 1}, Color{},
                   0.001f, rng);
}

/// A drawer front (x 0.7 .. 0.9, z 0.5 .. 0.65) in a face at y = 2.4, pulled out by `pull` with
/// its sides and bottom in view: it runs out farther than its front is wide or tall.
PointCloud DrawerScan(float pull) {
    std::mt19937 rng(11);
    PointCloud c;
    AddFaceBesideDrawers(c, rng);
    AddDrawer(c, 0.5f, 0.15f, 0.02f, 0.12f, pull, rng);
    return c;
}

Front DrawerFront() {
    Front f = DoorFront();
    const Eigen::Vector2f a(Eigen::Vector3f(0.7f, 2.4f, 0.5f).dot(f.u_axis), 0.5f);
    const Eigen::Vector2f b(Eigen::Vector3f(0.9f, 2.4f, 0.65f).dot(f.u_axis), 0.65f);
    f.min = a.cwiseMin(b);
    f.max = a.cwiseMax(b);
    f.center = Eigen::Vector3f(0.8f, 2.4f, 0.575f);
    return f;
}

/// DrawerFront's width from `bottom` to `top` (a stack of drawers, or a taller drawer).
Front DrawerFrontBetween(float bottom, float top) {
    Front f = DrawerFront();
    f.min.y() = bottom;
    f.max.y() = top;
    f.center.z() = (bottom + top) / 2.0f;
    return f;
}

/// Whether `m` is a slide out of the face at y = 2.4 (towards -y) by `travel`.
::testing::AssertionResult SlidOutBy(const MotionResult& m, float travel) {
    if (!m.found) return ::testing::AssertionFailure() << "no motion found";
    if (m.articulation.type != JointType::kPrismatic)
        return ::testing::AssertionFailure() << "not prismatic";
    if (std::abs(m.opening - travel) > 0.02f)
        return ::testing::AssertionFailure() << "travel " << m.opening << ", not " << travel;
    if (!(m.articulation.axis.y() < -0.99f))
        return ::testing::AssertionFailure() << "axis " << m.articulation.axis.transpose();
    return ::testing::AssertionSuccess();
}

TEST(Articulation, ADrawerRunningOutFartherThanItsFrontIsWideSlides) {
    const Front f = DrawerFront();
    const PointCloud closed = DrawerScan(0.0f);
    EXPECT_TRUE(SlidOutBy(ArticulationFromMotion(closed, DrawerScan(0.45f), f), 0.45f));
    // Out of reach, the front is not seen, and its box's bottom passes for a flap; but the box
    // runs out farther than a flap of the front's height could: with the box test on
    // (ADrawerWhoseBoxAloneIsSeenSlides) it slides.
    MotionParams near;
    near.reach = 0.3f;
    near.max_beyond_turn_share = 0.0f;
    const MotionResult n = ArticulationFromMotion(closed, DrawerScan(0.45f), f, near);
    EXPECT_NE(n.articulation.type, JointType::kPrismatic);
    near.max_beyond_turn_share = MotionParams{}.max_beyond_turn_share;
    EXPECT_EQ(ArticulationFromMotion(closed, DrawerScan(0.45f), f, near).articulation.type,
              JointType::kPrismatic);
    near.min_slide_coverage = 1.5f;
    EXPECT_THROW(ArticulationFromMotion(closed, closed, f, near), InvalidArgument);
}

/// Four drawers 11 cm tall (x 0.7 .. 0.9, z 0.35 .. 0.79) in a face at y = 2.4, the third from
/// the bottom pulled out by `pull` with its sides and bottom in view.
PointCloud DrawerStackScan(float pull) {
    std::mt19937 rng(13);
    PointCloud c;
    AddFaceBesideDrawers(c, rng);
    for (int k = 0; k < 4; ++k) {
        AddDrawer(c, 0.352f + 0.11f * static_cast<float>(k), 0.106f, 0.01f, 0.08f,
                  k == 2 ? pull : 0.0f, rng);
    }
    return c;
}

TEST(Articulation, ADrawerOfAStackFoundAsOneFrontSlides) {
    // The stack's handles were missed and its four drawers make one front: the pulled drawer
    // covers a quarter of that rectangle, too little for a slide, but it is the part of the
    // rectangle that the motion vacated.
    const Front f = DrawerFrontBetween(0.35f, 0.79f);
    const PointCloud closed = DrawerStackScan(0.0f);
    const PointCloud opened = DrawerStackScan(0.3f);
    const MotionResult m = ArticulationFromMotion(closed, opened, f);
    EXPECT_TRUE(SlidOutBy(m, 0.3f));
    EXPECT_NEAR(m.front_min.y(), 0.57f, 0.02f);
    EXPECT_NEAR(m.front_max.y(), 0.67f, 0.02f);
    EXPECT_NEAR(m.front_max.x() - m.front_min.x(), 0.2f, 0.03f);
    // The whole rectangle: a quarter of it slid, taken for a turn; with the box test on, the
    // moved points lie farther out than that turn reaches (ADrawerWhoseBoxAloneIsSeenSlides).
    MotionParams whole;
    whole.vacated_max_share = 0.0f;
    whole.max_beyond_turn_share = 0.0f;
    const MotionResult n = ArticulationFromMotion(closed, opened, f, whole);
    ASSERT_TRUE(n.found);
    EXPECT_EQ(n.articulation.type, JointType::kRevolute);
    EXPECT_EQ(n.front_max.y(), f.max.y());
    whole.max_beyond_turn_share = MotionParams{}.max_beyond_turn_share;
    EXPECT_EQ(ArticulationFromMotion(closed, opened, f, whole).articulation.type,
              JointType::kPrismatic);
    whole.vacated_max_share = 1.5f;
    EXPECT_THROW(ArticulationFromMotion(closed, opened, f, whole), InvalidArgument);
}

/// DoorScan's door (x 0.6 .. 1.1, z 0.15 .. 0.8, y = 2.4) hinged at its bottom edge instead,
/// opened by `angle` (an oven's or a dishwasher's door), between the same panels; with `rim`, a
/// densely seen strip 8 cm tall parallel to the face stands on the opened door's top edge (as a
/// handle bar or a rack's front would).
PointCloud FlapScan(float angle, bool rim = false) {
    std::mt19937 rng(17);
    PointCloud c;
    const PointCloud door = AddPanelsBesideDoor(c, rng);
    // About the horizontal line z = 0.15, y = 2.4, the top edge coming out towards -y.
    const Eigen::Vector3f hinge(0.0f, 2.4f, 0.15f);
    const Eigen::Matrix3f R = Eigen::AngleAxisf(angle, Eigen::Vector3f::UnitX()).toRotationMatrix();
    for (const auto& p : door.points) c.points.push_back(hinge + R * (p - hinge));
    if (rim) {
        const Eigen::Vector3f top = hinge + R * Eigen::Vector3f(0.0f, 0.0f, 0.65f);
        test::AddPatch(c, {0.6f, top.y(), top.z()}, {0.5f, 0, 0}, {0, 0, 0.08f}, 0.004f, {0, -1, 0},
                       Color{}, 0.001f, rng);
    }
    return c;
}

TEST(Articulation, ADoorHingedAtItsBottomIsNoDrawer) {
    // Opened, the door and a strip standing on its top edge parallel to the face (as a slid
    // drawer's front would) are in view: the door turned about its bottom edge.
    const Front f = DoorFront();
    const PointCloud closed = FlapScan(0.0f);
    for (const float deg : {40.0f, 60.0f, 80.0f}) {
        for (const bool rim : {false, true}) {
            const MotionResult m = ArticulationFromMotion(closed, FlapScan(deg * kDeg, rim), f);
            ASSERT_TRUE(m.found) << deg << rim;
            EXPECT_EQ(m.articulation.type, JointType::kRevolute) << deg << rim;
            EXPECT_GT(std::abs(m.articulation.axis.x()), 0.99f) << deg << rim;
            EXPECT_NEAR(m.articulation.origin.z(), 0.15f, 0.03f) << deg << rim;
            EXPECT_NEAR(m.opening, deg * kDeg, 3.0f * kDeg) << deg << rim;
            EXPECT_EQ(m.front_min.y(), f.min.y()) << deg << rim;
            EXPECT_EQ(m.front_max.y(), f.max.y()) << deg << rim;
        }
    }
}

TEST(Articulation, AFrontIsCutAlongItsHeightOnly) {
    // One rectangle over the door of DoorScan and the panel left of it (x 0.3 .. 1.1): the door
    // opened by 60 deg vacates the right part of it, over the whole height. Drawers stack, so
    // the rectangle is not cut across its width.
    Front f = DoorFront();
    f.min.x() = Eigen::Vector3f(0.3f, 2.4f, 0.0f).dot(f.u_axis);
    f.center.x() = 0.7f;
    const PointCloud closed = DoorScan(0.0f, 0.0f);
    const MotionResult m = ArticulationFromMotion(closed, DoorScan(60.0f * kDeg, 0.0f), f);
    ASSERT_TRUE(m.found);
    EXPECT_GT(m.vacated_points, 1000u);
    EXPECT_EQ(m.front_min, f.min);
    EXPECT_EQ(m.front_max, f.max);
}

TEST(Articulation, AnOpenedScanSplitsAFrontSpanningSeveralDrawers) {
    // The map took the stack of DrawerStackScan for one front, with one handle found on its top
    // drawer; the robot pulls out the third drawer from the bottom.
    const PointCloud closed = DrawerStackScan(0.0f);
    KitchenMap map;
    Fixture handle;
    handle.center = Eigen::Vector3f(0.8f, 2.37f, 0.74f);
    handle.direction = Eigen::Vector3f::UnitX();
    handle.length = 0.12f;
    map.fixtures = {handle};
    Front f = DrawerFrontBetween(0.35f, 0.79f);
    f.fixtures = {0};
    for (std::size_t i = 0; i < closed.size(); ++i) {
        const Eigen::Vector3f& x = closed.points[i];
        if (std::abs(x.y() - 2.4f) < 0.01f && x.x() >= 0.7f && x.x() <= 0.9f && x.z() >= 0.35f &&
            x.z() <= 0.79f) {
            f.indices.push_back(static_cast<Index>(i));
        }
    }
    map.fronts = {f};
    // A map of another cloud: refused, the map unchanged.
    PointCloud smaller;
    smaller.points.assign(closed.points.begin(), closed.points.begin() + 100);
    EXPECT_THROW(UpdateArticulationFromOpenedScan(map, smaller, DrawerStackScan(0.3f)),
                 InvalidArgument);
    ASSERT_EQ(map.fronts.size(), 1u);
    ASSERT_EQ(UpdateArticulationFromOpenedScan(map, closed, DrawerStackScan(0.3f)), 0);
    ASSERT_EQ(map.fronts.size(), 3u);
    const Front& moved = map.fronts[0];
    EXPECT_EQ(moved.articulation.type, JointType::kPrismatic);
    EXPECT_EQ(moved.articulation.source, "motion");
    EXPECT_NEAR(moved.min.y(), 0.57f, 0.02f);
    EXPECT_NEAR(moved.max.y(), 0.67f, 0.02f);
    EXPECT_NEAR(moved.center.z(), (moved.min.y() + moved.max.y()) / 2, 1e-5f);
    EXPECT_TRUE(moved.fixtures.empty());
    // The rest: the two drawers below it, and the top drawer with the handle (a drawer by its
    // fixture).
    const Front& below = map.fronts[1];
    const Front& above = map.fronts[2];
    EXPECT_FLOAT_EQ(below.min.y(), 0.35f);
    EXPECT_FLOAT_EQ(below.max.y(), moved.min.y());
    EXPECT_FLOAT_EQ(above.min.y(), moved.max.y());
    EXPECT_FLOAT_EQ(above.max.y(), 0.79f);
    EXPECT_EQ(below.articulation.type, JointType::kUnknown);
    EXPECT_EQ(above.fixtures, std::vector<int>{0});
    EXPECT_EQ(above.articulation.type, JointType::kPrismatic);
    EXPECT_EQ(above.articulation.source, "fixture");
    for (const Front* g : {&moved, &below, &above}) {
        EXPECT_GT(g->indices.size(), 100u);
        for (const Index i : g->indices) {
            const float z = closed.points[i].z();
            EXPECT_TRUE(z >= g->min.y() && z <= g->max.y()) << z;
        }
    }
    EXPECT_LE(moved.indices.size() + below.indices.size() + above.indices.size(), f.indices.size());
    // Opened again, the part alone moves: nothing more is split. The drawers below it sweep
    // more of the moved points (the pulled drawer's box), but kept their own.
    MotionParams by_moved;
    by_moved.select_by_vacated = false;
    KitchenMap copy = map;
    EXPECT_EQ(UpdateArticulationFromOpenedScan(copy, closed, DrawerStackScan(0.3f), by_moved), 1);
    ASSERT_EQ(UpdateArticulationFromOpenedScan(map, closed, DrawerStackScan(0.3f)), 0);
    EXPECT_EQ(map.fronts.size(), 3u);
}

/// DoorScan's door opened by 60 deg about its left edge (x = 0.6) and seen edge-on: the frame,
/// and of the door a strip along its free edge, parallel to the face 0.3 m out.
PointCloud DoorSeenEdgeOn(const PointCloud& closed, std::mt19937& rng) {
    PointCloud opened = FrameWithoutTheDoor(closed);
    test::AddPatch(opened, {0.82f, 2.1f, 0.15f}, {0.05f, 0, 0}, {0, 0, 0.65f}, 0.005f, {0, -1, 0},
                   Color{}, 0.001f, rng);
    return opened;
}

TEST(Articulation, AParallelStripCoveringLittleOfTheFrontIsADoorNotADrawer) {
    // A door opened by 60 deg about its left edge (x = 0.6) and seen edge-on: what the sensor
    // shows of it is a strip along its free edge, parallel to the face 0.3 m out.
    const Front f = DoorFront();
    const PointCloud closed = DoorScan(0.0f, 0.0f);
    std::mt19937 rng(3);
    const PointCloud frame = DoorSeenEdgeOn(closed, rng);
    const MotionResult m = ArticulationFromMotion(closed, frame, f);
    ASSERT_TRUE(m.found);
    EXPECT_EQ(m.articulation.type, JointType::kRevolute);
    // Without the coverage test the strip passes for a drawer front.
    MotionParams planes_only;
    planes_only.min_slide_coverage = 0.0f;
    EXPECT_EQ(ArticulationFromMotion(closed, frame, f, planes_only).articulation.type,
              JointType::kPrismatic);
}

/// The face of AddFaceBesideDrawers with a drawer front 25 cm tall (x 0.7 .. 0.9, z 0.45 ..
/// 0.7) pulled out by `pull`, seen by a sensor at (0.8, 1.0, 1.5) whose field of view ends at
/// the plane through it 40.4 deg below the horizontal (the bottom of a camera image): pulled out
/// 0.4 m, the drawer shows its top 5 cm only.
PointCloud DrawerLeavingTheView(float pull) {
    std::mt19937 rng(19);
    PointCloud c;
    AddFaceBesideDrawers(c, rng);
    test::AddPatch(c, {0.7f, 2.4f - pull, 0.45f}, {0.2f, 0, 0}, {0, 0, 0.25f}, 0.005f, {0, -1, 0},
                   Color{}, 0.001f, rng);
    const Eigen::Vector3f sensor(0.8f, 1.0f, 1.5f);
    PointCloud seen;
    for (const auto& x : c.points) {
        if (sensor.z() - x.z() < 0.85f * (x.y() - sensor.y())) seen.points.push_back(x);
    }
    seen.sensor_origin = sensor;
    return seen;
}

TEST(Articulation, ADrawerLeavingTheFieldOfViewSlides) {
    const Front f = DrawerFrontBetween(0.45f, 0.7f);
    const PointCloud closed = DrawerLeavingTheView(0.0f);
    const PointCloud opened = DrawerLeavingTheView(0.4f);
    const MotionResult m = ArticulationFromMotion(closed, opened, f);
    EXPECT_TRUE(SlidOutBy(m, 0.4f));
    // The moved points cover the fifth of the slid front the sensor could see, and all of it.
    EXPECT_LT(m.slide_coverage, 0.3f);
    EXPECT_GT(m.slide_seen_coverage, 0.9f);
    // A slide must cover more of what the sensor saw than of the whole front.
    MotionParams strict;
    strict.min_seen_slide_coverage = 0.8f;
    EXPECT_EQ(ArticulationFromMotion(closed, opened, f, strict).articulation.type,
              JointType::kPrismatic);
    // Without a sensor position nothing is known of what it saw.
    PointCloud no_sensor = opened;
    no_sensor.sensor_origin.setZero();
    EXPECT_EQ(ArticulationFromMotion(closed, no_sensor, f).slide_seen_coverage, -1.0f);
    strict.min_seen_slide_coverage = -0.1f;
    EXPECT_THROW(ArticulationFromMotion(closed, opened, f, strict), InvalidArgument);
    // Deterministic.
    const MotionResult again = ArticulationFromMotion(closed, opened, f);
    EXPECT_EQ(again.slide_seen_coverage, m.slide_seen_coverage);
    EXPECT_EQ(again.opening, m.opening);
}

/// The face y = 2.4 from x = `x0` to 1.4 (z 0.1 .. 0.85) as a grid of 1 cm, row by row from the
/// top: organized (its left column the image's border) or not, seen from (0.85, 1.0, 1.5).
PointCloud FaceGrid(float x0, bool organized) {
    PointCloud c;
    const int columns = static_cast<int>(std::lround((1.4f - x0) / 0.01f)) + 1;
    const int rows = 76;
    for (int v = 0; v < rows; ++v) {
        for (int u = 0; u < columns; ++u) {
            c.points.emplace_back(x0 + 0.01f * static_cast<float>(u), 2.4f,
                                  0.85f - 0.01f * static_cast<float>(v));
        }
    }
    if (organized) {
        c.width = static_cast<std::uint32_t>(columns);
        c.height = static_cast<std::uint32_t>(rows);
    } else {
        c.SetUnorganized();
    }
    c.sensor_origin = Eigen::Vector3f(0.85f, 1.0f, 1.5f);
    return c;
}

/// DoorFront() hinged at its left edge (x = 0.6) by a vertical handle near its right edge, its
/// points those of `scan` within its rectangle.
Front HingedDoorIn(const PointCloud& scan) {
    Front f = DoorFront();
    f.articulation =
        ArticulationFromFixtures(f, {HandleAt({1.05f, 2.365f, 0.5f}, true)}, RoomFrame{}, 0.0f);
    for (std::size_t i = 0; i < scan.size(); ++i) {
        const Eigen::Vector3f& x = scan.points[i];
        if (x.x() >= 0.6f - 1e-4f && x.x() <= 1.1f + 1e-4f && x.z() >= 0.15f - 1e-4f &&
            x.z() <= 0.8f + 1e-4f) {
            f.indices.push_back(static_cast<Index>(i));
        }
    }
    return f;
}

TEST(Articulation, AHingeEdgeAtTheBorderOfTheViewIsNotSeen) {
    for (const bool organized : {true, false}) {
        SCOPED_TRACE(organized ? "organized" : "unorganized");
        // The face beyond the hinge edge in view: seen.
        const PointCloud wide = FaceGrid(0.3f, organized);
        const Front in_view = HingedDoorIn(wide);
        ASSERT_EQ(in_view.articulation.type, JointType::kRevolute);
        ASSERT_NEAR(in_view.articulation.origin.x(), 0.6f, 0.01f);
        EXPECT_TRUE(HingeEdgeSeen(in_view, {wide}, {0}));
        // The view ends at the hinge edge: not seen.
        const PointCloud cut = FaceGrid(0.6f, organized);
        const Front cut_front = HingedDoorIn(cut);
        EXPECT_FALSE(HingeEdgeSeen(cut_front, {cut}, {0}));
        EXPECT_EQ(HingeEdgeSeen(cut_front, {cut}, {0}), HingeEdgeSeen(cut_front, {cut}, {0}));
        // One scan of two that saw it is enough (the second scan's points follow the first's).
        Front both = cut_front;
        for (std::size_t i = 0; i < wide.size(); ++i) {
            const Eigen::Vector3f& x = wide.points[i];
            if (x.x() >= 0.6f - 1e-4f && x.x() <= 1.1f + 1e-4f && x.z() >= 0.15f - 1e-4f &&
                x.z() <= 0.8f + 1e-4f) {
                both.indices.push_back(static_cast<Index>(cut.size() + i));
            }
        }
        EXPECT_TRUE(HingeEdgeSeen(both, {cut, wide}, {0, cut.size()}));
        EXPECT_FALSE(HingeEdgeSeen(cut_front, {cut, wide}, {0, cut.size()}));
        // The free edge is in view either way; the hinge at it would be seen.
        Front other_side = cut_front;
        other_side.articulation = ArticulationFromFixtures(
            other_side, {HandleAt({0.65f, 2.365f, 0.5f}, true)}, RoomFrame{}, 0.0f);
        ASSERT_NEAR(other_side.articulation.origin.x(), 1.1f, 0.01f);
        EXPECT_TRUE(HingeEdgeSeen(other_side, {cut}, {0}));
    }
    // An unorganized scan without a sensor position cannot tell; nor can an empty front.
    PointCloud blind = FaceGrid(0.6f, false);
    blind.sensor_origin.setZero();
    EXPECT_TRUE(HingeEdgeSeen(HingedDoorIn(blind), {blind}, {0}));
    Front empty = HingedDoorIn(blind);
    empty.indices.clear();
    EXPECT_TRUE(HingeEdgeSeen(empty, {blind}, {0}));
    // Drawers have no hinge.
    const PointCloud cut = FaceGrid(0.6f, true);
    Front drawer = HingedDoorIn(cut);
    drawer.articulation.type = JointType::kPrismatic;
    EXPECT_TRUE(HingeEdgeSeen(drawer, {cut}, {0}));
    // Contracts.
    EXPECT_THROW(HingeEdgeSeen(HingedDoorIn(cut), {cut}, {}), InvalidArgument);
    EXPECT_THROW(HingeEdgeSeen(HingedDoorIn(cut), {cut}, {0}, {.edge_band = 0.0f}),
                 InvalidArgument);
    EXPECT_THROW(HingeEdgeSeen(HingedDoorIn(cut), {cut}, {0}, {.edge_border = -1}),
                 InvalidArgument);
}

TEST(Articulation, ADoorSeenEdgeOnIsADoorWhereTheSensorSeesPastIt) {
    // The strip of AParallelStripCoveringLittleOfTheFrontIsADoorNotADrawer, seen from a sensor in
    // front of the door, with the cupboard's back wall (y = 2.9) behind the door's closed place
    // and the floor: the rays through the slid front reach them, so the slid front was seen,
    // and the strip covers little of it.
    const Front f = DoorFront();
    const PointCloud closed = DoorScan(0.0f, 0.0f);
    std::mt19937 rng(3);
    PointCloud opened = DoorSeenEdgeOn(closed, rng);
    test::AddPatch(opened, {0.3f, 2.9f, 0.0f}, {1.1f, 0, 0}, {0, 0, 0.8f}, 0.01f, {0, -1, 0},
                   Color{}, 0.001f, rng);
    test::AddPatch(opened, {0.3f, 1.5f, 0.0f}, {1.1f, 0, 0}, {0, 1.4f, 0}, 0.01f, {0, 0, 1},
                   Color{}, 0.001f, rng);
    opened.sensor_origin = Eigen::Vector3f(0.85f, 1.0f, 1.2f);
    const MotionResult m = ArticulationFromMotion(closed, opened, f);
    ASSERT_TRUE(m.found);
    EXPECT_EQ(m.articulation.type, JointType::kRevolute);
    EXPECT_GE(m.slide_seen_coverage, 0.0f);
    EXPECT_LT(m.slide_seen_coverage, 0.3f);
}

/// Whether a motion was found and taken for a flap's turn (about a horizontal axis).
bool IsFlapTurn(const MotionResult& m) {
    return m.found && m.articulation.type == JointType::kRevolute && m.turn_flap;
}

/// The face of AddFaceBesideDrawers with a drawer 15 cm tall (x 0.7 .. 0.9, z 0.5 .. 0.65)
/// pulled out by `pull`, its front out of view: what is seen of it is its box's bottom and sides
/// (out to `pull` from the face), as where a drawer pulled towards a camera leaves the image.
PointCloud DrawerBoxAlone(float pull) {
    std::mt19937 rng(23);
    PointCloud c;
    AddFaceBesideDrawers(c, rng);
    PointCloud drawer;
    AddDrawer(drawer, 0.5f, 0.15f, 0.02f, 0.12f, pull, rng);
    for (const auto& x : drawer.points) {
        if (pull <= 0.0f || x.y() > 2.4f - pull + 0.01f) c.points.push_back(x);
    }
    return c;
}

TEST(Articulation, ADrawerWhoseBoxAloneIsSeenSlides) {
    const Front f = DrawerFront();
    const PointCloud closed = DrawerScan(0.0f);
    const PointCloud opened = DrawerBoxAlone(0.45f);
    // Taken for a flap opened downwards, the box's bottom turned back covers the front; but a
    // flap 15 cm tall reaches no more than 20 cm out, the bottom runs out 45 cm, and the box's
    // sides stand across the flap's plane.
    MotionParams off;
    off.max_beyond_turn_share = 0.0f;
    const MotionResult flap = ArticulationFromMotion(closed, opened, f, off);
    ASSERT_TRUE(IsFlapTurn(flap));
    EXPECT_NEAR(flap.turn_reach, 0.15f, 0.03f);
    EXPECT_GT(flap.beyond_turn_points, flap.outline_points / 2);
    EXPECT_GT(flap.beyond_off_plane, flap.beyond_turn_points / 4);
    const MotionResult m = ArticulationFromMotion(closed, opened, f);
    ASSERT_TRUE(m.found);
    EXPECT_EQ(m.articulation.type, JointType::kPrismatic);
    EXPECT_LT(m.articulation.axis.y(), -0.99f);
    EXPECT_NEAR(m.opening, 0.45f, 0.03f);
    EXPECT_EQ(m.moved.size(), m.outline_points);
    // The bottom lies on the flap's plane: with every point beyond required off it, a flap.
    MotionParams all_off;
    all_off.min_beyond_off_plane = 1.0f;
    EXPECT_EQ(ArticulationFromMotion(closed, opened, f, all_off).articulation.type,
              JointType::kRevolute);
    // Deterministic; bad shares are refused.
    EXPECT_EQ(ArticulationFromMotion(closed, opened, f).opening, m.opening);
    off.max_beyond_turn_share = 1.5f;
    EXPECT_THROW(ArticulationFromMotion(closed, opened, f, off), InvalidArgument);
    all_off.min_beyond_off_plane = -0.5f;
    EXPECT_THROW(ArticulationFromMotion(closed, opened, f, all_off), InvalidArgument);
}

/// AddFaceBesideDrawers' face with a drawer 40 cm tall (x 0.7 .. 0.9, z 0.45 .. 0.85) in it,
/// closed (`pull` 0) or pulled out by `pull` with its front out of view: what is seen of it is
/// its box's bottom and sides, 10 cm tall, and, where the box is `depth` deep and runs on behind
/// the face, its back.
PointCloud DeepDrawerScan(float pull, float depth) {
    std::mt19937 rng(31);
    PointCloud c;
    AddFaceBesideDrawers(c, rng);
    if (pull <= 0.0f) {
        test::AddPatch(c, {0.7f, 2.4f, 0.45f}, {0.2f, 0, 0}, {0, 0, 0.4f}, 0.005f, {0, -1, 0},
                       Color{}, 0.001f, rng);
        return c;
    }
    const float y0 = 2.4f - pull + 0.01f, y1 = 2.4f - pull + depth;
    for (const float x : {0.705f, 0.895f}) {
        test::AddPatch(c, {x, y0, 0.47f}, {0, y1 - y0, 0}, {0, 0, 0.1f}, 0.005f,
                       {x < 0.8f ? 1.0f : -1.0f, 0, 0}, Color{}, 0.001f, rng);
    }
    test::AddPatch(c, {0.705f, y0, 0.47f}, {0.19f, 0, 0}, {0, y1 - y0, 0}, 0.005f, {0, 0, 1},
                   Color{}, 0.001f, rng);
    if (y1 > 2.4f) {
        test::AddPatch(c, {0.705f, y1, 0.47f}, {0.19f, 0, 0}, {0, 0, 0.1f}, 0.005f, {0, -1, 0},
                       Color{}, 0.001f, rng);
    }
    return c;
}

TEST(Articulation, ADeepDrawersBoxRunningOnBehindTheFaceSlides) {
    const Front f = DrawerFrontBetween(0.45f, 0.85f);
    const PointCloud closed = DeepDrawerScan(0.0f, 0.0f);
    // Pulled out 30 cm, a box 80 cm deep: its bottom, out of the face no farther than the 40 cm
    // flap could reach, passes for a flap opened downwards, but runs on 50 cm behind the face.
    const PointCloud opened = DeepDrawerScan(0.3f, 0.8f);
    MotionParams off;
    off.min_through_share = 0.0f;
    const MotionResult flap = ArticulationFromMotion(closed, opened, f, off);
    ASSERT_TRUE(IsFlapTurn(flap));
    EXPECT_EQ(flap.beyond_turn_points, 0u);
    EXPECT_GT(flap.through_points, flap.turned_points);
    const MotionResult m = ArticulationFromMotion(closed, opened, f);
    ASSERT_TRUE(m.found);
    EXPECT_EQ(m.articulation.type, JointType::kPrismatic);
    EXPECT_LT(m.articulation.axis.y(), -0.99f);
    EXPECT_NEAR(m.opening, 0.3f, 0.03f);
    EXPECT_EQ(m.through_points, flap.through_points);
    // A box no deeper than its pull shows nothing behind the face: a flap, as before.
    const MotionResult shallow = ArticulationFromMotion(closed, DeepDrawerScan(0.3f, 0.3f), f);
    ASSERT_TRUE(shallow.found);
    EXPECT_EQ(shallow.articulation.type, JointType::kRevolute);
    EXPECT_EQ(shallow.through_points, 0u);
    // Deterministic; a bad share is refused.
    EXPECT_EQ(ArticulationFromMotion(closed, opened, f).through_points, m.through_points);
    off.min_through_share = -0.1f;
    EXPECT_THROW(ArticulationFromMotion(closed, opened, f, off), InvalidArgument);
}

// A deep drawer pulled out towards the sensor may leave the view with its front; what is seen of
// its box then passes for a door turned a little. A front the map holds for a drawer from its
// fixture stays a drawer unless the turn covers enough of it.
TEST(Articulation, AWeaklySeenTurnOfAFrontHeldForADrawerIsASlide) {
    const Front f = DrawerFrontBetween(0.45f, 0.85f);
    const PointCloud closed = DeepDrawerScan(0.0f, 0.0f);
    const PointCloud opened = DeepDrawerScan(0.3f, 0.3f);  // a box as deep as its pull
    const MotionResult turn = ArticulationFromMotion(closed, opened, f);  // no joint before
    ASSERT_TRUE(IsFlapTurn(turn));
    const float cover =
        turn.turn_seen_coverage >= 0.0f ? turn.turn_seen_coverage : turn.turn_coverage;
    ASSERT_GT(cover, 0.05f);
    ASSERT_LT(cover, 0.95f);
    MotionParams p;
    p.min_turn_coverage_for_drawer = cover + 0.05f;
    // A front with no joint before: the turn, whatever its coverage.
    EXPECT_EQ(ArticulationFromMotion(closed, opened, f, p).articulation.type, JointType::kRevolute);
    Front drawer = f;
    drawer.articulation.type = JointType::kPrismatic;
    drawer.articulation.axis = f.normal;
    drawer.articulation.source = "fixture";
    const MotionResult m = ArticulationFromMotion(closed, opened, drawer, p);
    ASSERT_TRUE(m.found);
    EXPECT_EQ(m.articulation.type, JointType::kPrismatic);
    EXPECT_EQ(m.articulation.source, "motion");
    EXPECT_LT(m.articulation.axis.y(), -0.99f);
    EXPECT_NEAR(m.opening, 0.3f, 0.03f);
    // A turn that covers enough stays a turn; off (0), the turn too.
    p.min_turn_coverage_for_drawer = cover - 0.05f;
    EXPECT_EQ(ArticulationFromMotion(closed, opened, drawer, p).articulation.type,
              JointType::kRevolute);
    p.min_turn_coverage_for_drawer = 0.0f;
    EXPECT_EQ(ArticulationFromMotion(closed, opened, drawer, p).articulation.type,
              JointType::kRevolute);
    // A door held for a drawer but clearly turned stays a door (the default share).
    Front door = DoorFront();
    door.articulation = drawer.articulation;
    const MotionResult d =
        ArticulationFromMotion(DoorScan(0.0f, 0.0f), DoorScan(60.0f * kDeg, 0.0f), door);
    ASSERT_TRUE(d.found);
    EXPECT_EQ(d.articulation.type, JointType::kRevolute);
    EXPECT_GE(d.turn_seen_coverage >= 0.0f ? d.turn_seen_coverage : d.turn_coverage,
              MotionParams{}.min_turn_coverage_for_drawer);
    // Deterministic; a bad share is refused.
    p.min_turn_coverage_for_drawer = cover + 0.05f;
    EXPECT_EQ(ArticulationFromMotion(closed, opened, drawer, p).opening, m.opening);
    p.min_turn_coverage_for_drawer = 1.5f;
    EXPECT_THROW(ArticulationFromMotion(closed, opened, drawer, p), InvalidArgument);
}

TEST(Articulation, AFlapOpenedDownwardsStaysAFlap) {
    // The door of DoorScan hinged at its bottom edge (z = 0.15) and opened downwards by 80 deg:
    // nothing of it lies beyond its height out of the face. Found shorter than it is (its lower
    // 30 cm), it reaches beyond its rectangle, but on its own plane: still a flap.
    const Front f = DoorFront();
    const PointCloud closed = DoorScan(0.0f, 0.0f);
    const PointCloud opened = DoorTurned(
        closed, {0.85f, 2.4f, 0.15f},
        Eigen::AngleAxisf(80.0f * kDeg, Eigen::Vector3f::UnitX()).toRotationMatrix(), 29);
    const MotionResult m = ArticulationFromMotion(closed, opened, f);
    ASSERT_TRUE(IsFlapTurn(m));
    EXPECT_GT(std::abs(m.articulation.axis.x()), 0.99f);
    EXPECT_EQ(m.beyond_turn_points, 0u);
    // The cupboard's inside seen behind the face (its bottom 2 cm over the hinge, its back 50
    // cm in): the flap's plane ends at the hinge, so it stays a flap.
    PointCloud inside = opened;
    std::mt19937 rng(41);
    test::AddPatch(inside, {0.62f, 2.41f, 0.17f}, {0.46f, 0, 0}, {0, 0.49f, 0}, 0.01f, {0, 0, 1},
                   Color{}, 0.001f, rng);
    test::AddPatch(inside, {0.62f, 2.9f, 0.17f}, {0.46f, 0, 0}, {0, 0, 0.6f}, 0.01f, {0, -1, 0},
                   Color{}, 0.001f, rng);
    const MotionResult in = ArticulationFromMotion(closed, inside, f);
    ASSERT_TRUE(IsFlapTurn(in));
    EXPECT_LT(in.through_points, in.turned_points / 10);
    EXPECT_NEAR(m.opening / kDeg, 80.0f, 3.0f);
    Front lower = f;
    lower.max.y() = 0.45f;
    lower.center.z() = 0.3f;
    const MotionResult s = ArticulationFromMotion(closed, opened, lower);
    ASSERT_TRUE(s.found);
    EXPECT_EQ(s.articulation.type, JointType::kRevolute);
    EXPECT_GT(s.beyond_turn_points, s.outline_points / 4);
    EXPECT_LT(s.beyond_off_plane, s.beyond_turn_points / 10);
    // Without the plane test the flap passes for a drawer's box.
    MotionParams any_plane;
    any_plane.min_beyond_off_plane = 0.0f;
    EXPECT_EQ(ArticulationFromMotion(closed, opened, lower, any_plane).articulation.type,
              JointType::kPrismatic);
}

TEST(Articulation, AHingeAxisNearTheFrontsVerticalIsVertical) {
    // The door of DoorScan opened by 50 deg about an axis leaning 4 deg from the vertical (in
    // the face plane): the furniture is axis-aligned, so the lean is taken for the plane fit's.
    const Front f = DoorFront();
    const PointCloud closed = DoorScan(0.0f, 0.0f);
    const Eigen::Vector3f lean =
        Eigen::AngleAxisf(4.0f * kDeg, Eigen::Vector3f::UnitY()) * Eigen::Vector3f::UnitZ();
    const PointCloud opened = DoorTurned(
        closed, {0.6f, 2.4f, 0.475f}, Eigen::AngleAxisf(50.0f * kDeg, -lean).toRotationMatrix(), 5);
    const MotionResult m = ArticulationFromMotion(closed, opened, f);
    ASSERT_TRUE(m.found);
    ASSERT_EQ(m.articulation.type, JointType::kRevolute);
    EXPECT_GT(std::abs(m.articulation.axis.z()), 0.99999f);
    EXPECT_NEAR(m.opening / kDeg, 50.0f, 3.0f);
    MotionParams as_fitted;
    as_fitted.axis_snap_deg = 0.0f;
    const MotionResult n = ArticulationFromMotion(closed, opened, f, as_fitted);
    ASSERT_EQ(n.articulation.type, JointType::kRevolute);
    EXPECT_NEAR(std::acos(std::abs(n.articulation.axis.z())) / kDeg, 4.0f, 1.0f);
    as_fitted.axis_snap_deg = 45.0f;
    EXPECT_THROW(ArticulationFromMotion(closed, opened, f, as_fitted), InvalidArgument);
}

TEST(Articulation, AHingeFarFromTheMovedPlaneIsTakenAtTheFrontsEdge) {
    // In front of the door a panel 0.25 m out, tilted by 30 deg: its plane meets the face 0.5 m
    // from it, left of the door, where nothing hangs. The hinge is taken at a vertical edge of
    // the door instead.
    const Front f = DoorFront();
    const PointCloud closed = DoorScan(0.0f, 0.0f);
    PointCloud opened = closed;
    const Eigen::Vector3f along(std::cos(30.0f * kDeg), -std::sin(30.0f * kDeg), 0.0f);
    for (float s = 0.0f; s <= 0.4f; s += 0.01f) {
        for (float z = 0.15f; z <= 0.8f; z += 0.01f) {
            opened.points.push_back(Eigen::Vector3f(0.65f, 2.15f, z) + along * s);
        }
    }
    const MotionResult m = ArticulationFromMotion(closed, opened, f);
    ASSERT_TRUE(m.found);
    ASSERT_EQ(m.articulation.type, JointType::kRevolute);
    EXPECT_GT(std::abs(m.articulation.axis.z()), 0.999f);
    const float x = m.articulation.origin.x();
    EXPECT_LT(std::min(std::abs(x - 0.6f), std::abs(x - 1.1f)), 0.02f) << x;
    EXPECT_NEAR(m.articulation.origin.y(), 2.4f, 0.02f);
    // Believing every plane: the hinge lies where the planes meet, 0.4 m left of the door.
    MotionParams believe;
    believe.max_hinge_gap = 0.0f;
    const MotionResult n = ArticulationFromMotion(closed, opened, f, believe);
    ASSERT_EQ(n.articulation.type, JointType::kRevolute);
    EXPECT_NEAR(n.articulation.origin.x(), 0.65f - 0.25f / std::tan(30.0f * kDeg), 0.03f);
    believe.max_hinge_gap = -1.0f;
    EXPECT_THROW(ArticulationFromMotion(closed, opened, f, believe), InvalidArgument);
}

/// A tilting laser at the origin in a box room (walls at x = 3 and y = +-2, floor 1.4 m below,
/// ceiling 1.1 m above): rows are tilts from -40 to 60 deg about the y axis every 0.5 deg,
/// columns beams from 0 to 180 deg every 0.25 deg in the scan plane, 1 cm range noise (the
/// simulator's laser). Beams along y meet at every tilt.
PointCloud TiltingLaserRoom() {
    std::mt19937 rng(31);
    std::normal_distribution<float> noise(0.0f, 0.01f);
    PointCloud c;
    const int rows = 201, columns = 721;
    for (int r = 0; r < rows; ++r) {
        const float tilt = static_cast<float>(r - 80) * 0.5f * std::numbers::pi_v<float> / 180.0f;
        for (int k = 0; k < columns; ++k) {
            const float beam = static_cast<float>(k) * 0.25f * std::numbers::pi_v<float> / 180.0f;
            const Eigen::Vector3f in_plane(std::sin(beam), std::cos(beam), 0.0f);
            const Eigen::Vector3f d = Eigen::AngleAxisf(tilt, Eigen::Vector3f::UnitY()) * in_plane;
            float t = std::numeric_limits<float>::infinity();
            if (d.x() > 1e-6f) t = std::min(t, 3.0f / d.x());
            if (std::abs(d.y()) > 1e-6f) t = std::min(t, 2.0f / std::abs(d.y()));
            if (d.z() < -1e-6f) t = std::min(t, -1.4f / d.z());
            if (d.z() > 1e-6f) t = std::min(t, 1.1f / d.z());
            c.points.push_back(d * (t + noise(rng)));
        }
    }
    c.width = columns;
    c.height = rows;
    return c;
}

TEST(MapKitchen, NormalsWhereATiltingLasersScanLinesMeet) {
    const PointCloud scan = TiltingLaserRoom();
    // The side walls' points within 20 cm of the sensor's height, where the rows converge.
    auto wrong_share = [&](const MapKitchenParams& p) {
        std::vector<std::size_t> offsets;
        std::vector<float> ranges;
        const PointCloud merged = MergeScansWithNormals({scan}, p, offsets, ranges);
        std::size_t n = 0, wrong = 0;
        for (std::size_t i = 0; i < merged.size(); ++i) {
            const Eigen::Vector3f& x = merged.points[i];
            if (std::abs(std::abs(x.y()) - 2.0f) > 0.02f || std::abs(x.z()) > 0.2f || x.x() > 2.9f)
                continue;
            ++n;
            const Eigen::Vector3f& nm = merged.normals[i];
            wrong += !nm.allFinite() || std::abs(nm.y()) < std::cos(20.0f * 0.0174533f);
        }
        EXPECT_GT(n, 1000u);
        return static_cast<double>(wrong) / static_cast<double>(std::max<std::size_t>(1, n));
    };
    MapKitchenParams windows = KitchenParamsFor(KitchenSensor::kLaser);
    windows.organized_normals = true;
    const double before = wrong_share(windows);
    const double after = wrong_share(KitchenParamsFor(KitchenSensor::kLaser));
    EXPECT_GT(before, 0.2);
    EXPECT_LT(after, 0.05);
    // The far wall's normals are right either way (within 20 deg).
    std::vector<std::size_t> offsets;
    std::vector<float> ranges;
    const PointCloud a = MergeScansWithNormals({scan}, windows, offsets, ranges);
    const PointCloud b =
        MergeScansWithNormals({scan}, KitchenParamsFor(KitchenSensor::kLaser), offsets, ranges);
    std::size_t far = 0, right = 0;
    for (std::size_t i = 0; i < a.size(); ++i) {
        if (a.points[i].x() < 2.98f || std::abs(a.points[i].y()) > 1.5f ||
            std::abs(a.points[i].z()) > 0.9f)
            continue;
        ++far;
        right += std::abs(a.normals[i].x()) > 0.94f && std::abs(b.normals[i].x()) > 0.94f;
    }
    EXPECT_GT(far, 1000u);
    EXPECT_GT(static_cast<double>(right), 0.98 * static_cast<double>(far));
}

MapKitchenResult MapSynthetic(int threads = 0) {
    test::SyntheticKitchen k = test::MakeSyntheticKitchen(1);
    MapKitchenParams p = KitchenParamsFor(KitchenSensor::kKinect);
    p.structure.range_noise = 0.0f;  // noise-free synthetic data
    p.num_threads = threads;
    p.axes.up = Eigen::Vector3f::UnitZ();
    PointCloud scan = k.cloud;
    scan.normals.clear();  // MapKitchen estimates its own
    return MapKitchen({scan}, p);
}

TEST(MapKitchen, SyntheticKitchenEndToEnd) {
    const MapKitchenResult r = MapSynthetic();
    const KitchenMap& m = r.map;
    EXPECT_NEAR(m.floor_height, 0.0f, 0.02f);
    EXPECT_NEAR(m.ceiling_height, 2.5f, 0.02f);
    // The door and the drawer have fixtures; the plain body panels between the fronts' colour
    // edges pass for fronts without one (AddFrontsFromGaps), with no joint and no shared point.
    int revolute = 0, prismatic = 0, with_fixture = 0;
    std::vector<int> owner(r.cloud.size(), 0);
    for (const Front& f : m.fronts) {
        revolute += f.articulation.type == JointType::kRevolute;
        prismatic += f.articulation.type == JointType::kPrismatic;
        with_fixture += !f.fixtures.empty();
        if (f.fixtures.empty()) {
            EXPECT_EQ(f.articulation.type, JointType::kUnknown);
        }
        for (const Index i : f.indices) {
            EXPECT_EQ(owner[i]++, 0);
        }
    }
    EXPECT_EQ(with_fixture, 2);
    EXPECT_EQ(revolute, 1);
    EXPECT_EQ(prismatic, 1);
    for (const Front& f : m.fronts) {
        if (f.articulation.type != JointType::kRevolute) continue;
        // The door: its rectangle, hinged at x = 0.6.
        EXPECT_NEAR(f.max.y() - f.min.y(), 0.65f, 0.05f);
        EXPECT_NEAR(f.max.x() - f.min.x(), 0.5f, 0.05f);
        EXPECT_NEAR(f.articulation.origin.x(), 0.6f, 0.03f);
    }
    EXPECT_EQ(m.point_class.size(), r.cloud.size());
    EXPECT_FALSE(m.furniture.empty());
}

TEST(MapKitchen, AScanWithoutColourOrIntensityIsMappedByItsGeometry) {
    // A depth camera without colour, or a laser without intensity: the fronts grow by their
    // offset from the face (here, where the door and the drawer differ from the body only in
    // colour, over the whole face, split between the two handles) and the handles still give
    // their joints.
    test::SyntheticKitchen k = test::MakeSyntheticKitchen(1);
    PointCloud scan = k.cloud;
    scan.normals.clear();
    scan.colors.clear();
    const std::vector<float> look = AppearanceValues(scan, AppearanceCue::kAuto, 255.0f);
    ASSERT_EQ(look.size(), scan.size());
    EXPECT_TRUE(std::all_of(look.begin(), look.end(), [](float v) { return v == 0.0f; }));
    MapKitchenParams p = KitchenParamsFor(KitchenSensor::kKinect);
    p.structure.range_noise = 0.0f;
    p.axes.up = Eigen::Vector3f::UnitZ();
    const MapKitchenResult r = MapKitchen({scan}, p);
    EXPECT_EQ(r.map.fixtures.size(), 2u);
    int with_fixture = 0;
    for (const Front& f : r.map.fronts) {
        EXPECT_FALSE(f.indices.empty());
        if (f.fixtures.empty()) continue;
        ++with_fixture;
        EXPECT_NE(f.articulation.type, JointType::kUnknown);
    }
    EXPECT_EQ(with_fixture, 2);
    EXPECT_NEAR(r.map.floor_height, 0.0f, 0.02f);
    EXPECT_NEAR(r.map.ceiling_height, 2.5f, 0.02f);
    // A cue the scan cannot give is refused with a clear error.
    p.fronts.cue = AppearanceCue::kColor;
    try {
        MapKitchen({scan}, p);
        FAIL() << "no exception";
    } catch (const DataError& e) {
        EXPECT_NE(std::string(e.what()).find("colour"), std::string::npos) << e.what();
    }
}

TEST(MapKitchen, TheSensorIsGuessedFromWhatTheScansHold) {
    PointCloud image;  // a 2 x 2 depth image without colour
    image.points.assign(4, Eigen::Vector3f(0, 0, 1));
    image.width = 2;
    image.height = 2;
    EXPECT_EQ(GuessKitchenSensor({image}), KitchenSensor::kKinect);
    PointCloud sweep = image;  // the same with intensity: a laser sweep
    sweep.intensity.assign(4, 0.5f);
    EXPECT_EQ(GuessKitchenSensor({sweep}), KitchenSensor::kLaser);
    EXPECT_EQ(GuessKitchenSensor({image, sweep}), KitchenSensor::kLaser);
    PointCloud loose = image;  // unorganized points without colour: a laser
    loose.width = 4;
    loose.height = 1;
    EXPECT_EQ(GuessKitchenSensor({loose}), KitchenSensor::kLaser);
    PointCloud coloured = loose;  // colours: a camera
    coloured.colors.assign(4, Color{});
    EXPECT_EQ(GuessKitchenSensor({sweep, coloured}), KitchenSensor::kKinect);
}

TEST(MapKitchen, SerialEqualsParallel) {
    const MapKitchenResult a = MapSynthetic(1), b = MapSynthetic(2);
    EXPECT_EQ(a.map.point_class, b.map.point_class);
    EXPECT_EQ(a.map.point_front, b.map.point_front);
}

TEST(MapKitchen, BadInputGivesClearErrors) {
    const MapKitchenParams p = KitchenParamsFor(KitchenSensor::kKinect);
    EXPECT_THROW(MapKitchen({}, p), DataError);
    PointCloud nan_only;
    nan_only.points.assign(10, Eigen::Vector3f::Constant(std::numeric_limits<float>::quiet_NaN()));
    EXPECT_THROW(MapKitchen({nan_only}, p), DataError);
    // A floor alone: no vertical planes to look for furniture on.
    std::mt19937 rng(1);
    PointCloud floor;
    test::AddPatch(floor, {0, 0, 0}, {2, 0, 0}, {0, 2, 0}, 0.02f, {0, 0, 1}, Color{}, 0.001f, rng);
    floor.normals.clear();
    floor.colors.clear();
    floor.sensor_origin = {1, 1, 1.4f};
    floor.width = static_cast<std::uint32_t>(floor.size());
    try {
        MapKitchen({floor}, p);
        FAIL() << "no exception";
    } catch (const DataError& e) {
        EXPECT_NE(std::string(e.what()).find("vertical"), std::string::npos) << e.what();
    }
    MapKitchenParams bad = p;
    bad.fronts.alpha_mads = 0.0f;
    EXPECT_THROW(MapKitchen({floor}, bad), InvalidArgument);
}

TEST(MapExport, UrdfRoundTripAndWellFormedOwl) {
    const MapKitchenResult r = MapSynthetic();
    const io::UrdfModel urdf = KitchenMapUrdf(r.map, "test_kitchen");
    const io::UrdfModel back = io::ParseUrdf(io::UrdfToXml(urdf), "map.urdf");
    ASSERT_EQ(back.joints.size(), urdf.joints.size());
    std::size_t movable = 0;
    for (std::size_t j = 0; j < urdf.joints.size(); ++j) {
        EXPECT_EQ(back.joints[j].type, urdf.joints[j].type);
        EXPECT_TRUE(back.joints[j].origin.isApprox(urdf.joints[j].origin, 1e-4));
        if (urdf.joints[j].type == io::UrdfJointType::kFixed) continue;
        ++movable;
        EXPECT_TRUE(back.joints[j].axis.isApprox(urdf.joints[j].axis, 1e-6));
        EXPECT_NEAR(back.joints[j].upper, urdf.joints[j].upper, 1e-6);
    }
    // Fronts without a joint (found without a fixture) are fixed.
    std::size_t known = 0;
    for (const Front& f : r.map.fronts) known += f.articulation.type != JointType::kUnknown;
    EXPECT_EQ(known, 2u);
    EXPECT_EQ(movable, known);
    // The joints' axes in the world are those of the map's fronts.
    std::map<std::string, Eigen::Isometry3d> pose{{back.root, Eigen::Isometry3d::Identity()}};
    for (int pass = 0; pass < 4; ++pass) {
        for (const auto& j : back.joints) {
            if (pose.count(j.parent)) pose[j.child] = pose[j.parent] * j.origin;
        }
    }
    for (std::size_t f = 0; f < r.map.fronts.size(); ++f) {
        const io::UrdfJoint* j = back.FindJoint("front_" + std::to_string(f) + "_joint");
        ASSERT_NE(j, nullptr);
        if (r.map.fronts[f].articulation.type == JointType::kUnknown) {
            EXPECT_EQ(j->type, io::UrdfJointType::kFixed);
            continue;
        }
        const Eigen::Vector3d world = pose[j->child].linear() * j->axis;
        EXPECT_TRUE(world.cast<float>().isApprox(r.map.fronts[f].articulation.axis, 1e-4f));
    }
    // The map's JSON says of every joint whether the scan saw its hinge's edge.
    const auto json = KitchenMapJson(r.map);
    ASSERT_EQ(json["fronts"].size(), r.map.fronts.size());
    for (std::size_t f = 0; f < r.map.fronts.size(); ++f) {
        EXPECT_EQ(json["fronts"][f]["joint"]["hinge_seen"].get<bool>(),
                  r.map.fronts[f].articulation.hinge_seen);
    }
    const std::string owl = KitchenMapOwl(r.map, "test_kitchen");
    TiXmlDocument doc;
    doc.Parse(owl.c_str());
    ASSERT_FALSE(doc.Error()) << doc.ErrorDesc();
    const TiXmlElement* rdf = doc.FirstChildElement("rdf:RDF");
    ASSERT_NE(rdf, nullptr);
    int individuals = 0, joints = 0;
    for (const TiXmlElement* e = rdf->FirstChildElement("owl:NamedIndividual"); e;
         e = e->NextSiblingElement("owl:NamedIndividual")) {
        ++individuals;
        const std::string type = e->FirstChildElement("rdf:type")->Attribute("rdf:resource");
        joints += type.find("HingedJoint") != std::string::npos ||
                  type.find("PrismaticJoint") != std::string::npos;
    }
    EXPECT_GT(individuals, 5);
    EXPECT_EQ(joints, 2);
    test::TempDir dir;
    WriteKitchenMap(dir / "out", r.map, "test_kitchen");
    for (const char* f : {"map.json", "map.urdf", "map.owl"}) {
        EXPECT_TRUE(std::filesystem::is_regular_file(dir / "out" / f)) << f;
    }
    EXPECT_NO_THROW(io::ReadUrdf(dir / "out" / "map.urdf"));
}

}  // namespace
}  // namespace multicue

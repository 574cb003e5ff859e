// Occupancy map (OctoMap wrapper) and the incremental map: free / occupied / unknown space, .bt
// round trip, frames aligned from noisy odometry, failed frames left out, determinism.

#include <cmath>
#include <limits>
#include <sstream>

#include <gtest/gtest.h>
#include <octomap/OcTree.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/registration/incremental_map.hpp"
#include "multicue/search/occupancy_map.hpp"
#include "multicue/sim/rng.hpp"
#include "multicue/sim/scene_gen.hpp"
#include "multicue/sim/sensors.hpp"
#include "reduced_kinect.hpp"
#include "registration_scenes.hpp"

namespace multicue {
namespace {

using test::MakeTransform;
using test::RotationErrorDeg;
using test::TranslationError;

// A wall x = 2 m, 2 x 2 m, seen from the origin.
PointCloud Wall() {
    PointCloud c;
    for (int i = -20; i <= 20; ++i)
        for (int j = -20; j <= 20; ++j) c.points.emplace_back(2.0f, 0.05f * i, 0.05f * j);
    c.points.emplace_back(Eigen::Vector3f::Constant(std::numeric_limits<float>::quiet_NaN()));
    c.SetUnorganized();
    return c;
}

TEST(OccupancyMap, FreeOccupiedAndUnknown) {
    OccupancyMap map({.resolution = 0.05});
    EXPECT_TRUE(map.empty());
    map.InsertScan(Wall(), Eigen::Vector3f::Zero());
    EXPECT_FALSE(map.empty());
    EXPECT_EQ(map.Query({1.0f, 0.0f, 0.0f}), Occupancy::kFree);
    EXPECT_EQ(map.Query({2.01f, 0.0f, 0.0f}), Occupancy::kOccupied);
    EXPECT_EQ(map.Query({3.0f, 0.0f, 0.0f}), Occupancy::kUnknown);   // behind the wall
    EXPECT_EQ(map.Query({-1.0f, 0.0f, 0.0f}), Occupancy::kUnknown);  // behind the sensor
    EXPECT_GT(map.Probability({2.01f, 0.0f, 0.0f}), 0.5);
    EXPECT_LT(map.Probability({1.0f, 0.0f, 0.0f}), 0.5);
    const OccupancyCounts c = map.Counts();
    EXPECT_GT(c.occupied_leaves, 100u);
    EXPECT_GT(c.free_volume, 0.5);  // the pyramid between the sensor and the wall
    EXPECT_EQ(map.OccupiedCenters().size(), c.occupied_leaves);
    Eigen::Vector3f lo, hi;
    ASSERT_TRUE(map.Bounds(lo, hi));
    EXPECT_NEAR(hi.x(), 2.05f, 0.06f);
    EXPECT_EQ(std::string(OccupancyName(Occupancy::kFree)), "free");
}

TEST(OccupancyMap, BinaryTreeRoundTrip) {
    OccupancyMap map({.resolution = 0.05});
    map.InsertScan(Wall(), Eigen::Vector3f::Zero());
    std::stringstream bt;
    map.WriteBinary(bt);
    const OccupancyMap back = OccupancyMap::ReadBinary(bt, "wall.bt");
    EXPECT_DOUBLE_EQ(back.resolution(), 0.05);
    for (const Eigen::Vector3f& p : {Eigen::Vector3f(1, 0, 0), Eigen::Vector3f(2.01f, 0.3f, -0.2f),
                                     Eigen::Vector3f(3, 0, 0)}) {
        EXPECT_EQ(back.Query(p), map.Query(p));
    }
    EXPECT_EQ(back.Counts().occupied_leaves, map.Counts().occupied_leaves);
    std::stringstream garbage("not an octree\n1 2 3");
    EXPECT_THROW(OccupancyMap::ReadBinary(garbage, "garbage.bt"), FormatError);
    std::stringstream empty;
    EXPECT_THROW(OccupancyMap::ReadBinary(empty, "empty.bt"), FormatError);
    std::string text = bt.str();
    std::stringstream truncated(text.substr(0, text.size() / 2));
    EXPECT_THROW(OccupancyMap::ReadBinary(truncated, "truncated.bt"), FormatError);
}

// Oracle: OctoMap's own reader and writer agree with ours (octovis and octomap_server read the
// files `multicue map` writes).
TEST(OccupancyMap, OctomapReadsAndWritesTheSameTrees) {
    OccupancyMap map({.resolution = 0.05});
    map.InsertScan(Wall(), Eigen::Vector3f::Zero());
    std::stringstream bt;
    map.WriteBinary(bt);
    octomap::OcTree tree(0.1);
    std::stringstream copy(bt.str());
    ASSERT_TRUE(tree.readBinary(copy));
    EXPECT_DOUBLE_EQ(tree.getResolution(), 0.05);
    std::size_t occupied = 0;
    for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it) {
        occupied += tree.isNodeOccupied(*it);
    }
    EXPECT_EQ(occupied, map.Counts().occupied_leaves);
    std::stringstream theirs;
    ASSERT_TRUE(tree.writeBinary(theirs));
    EXPECT_EQ(OccupancyMap::ReadBinary(theirs, "theirs.bt").Counts().occupied_leaves, occupied);
}

TEST(OccupancyMap, BadParametersAndInput) {
    EXPECT_THROW(OccupancyMap({.resolution = 0.0}), InvalidArgument);
    EXPECT_THROW(OccupancyMap({.prob_hit = 0.4}), InvalidArgument);
    EXPECT_THROW(OccupancyMap({.prob_miss = 0.6}), InvalidArgument);
    EXPECT_THROW(OccupancyMap({.clamp_min = 0.5}), InvalidArgument);
    EXPECT_THROW(OccupancyMap({.max_range = -1.0}), InvalidArgument);
    OccupancyMap map;
    EXPECT_THROW(map.InsertScan(Wall(), Eigen::Vector3f::Constant(std::nanf(""))), InvalidArgument);
    map.InsertScan(PointCloud{}, Eigen::Vector3f::Zero());  // nothing to insert
    EXPECT_TRUE(map.empty());
}

// A boxes scene seen by a small simulated Kinect from views 20 degrees apart, odometry steps
// perturbed by 3 degrees and 3 cm.
struct Sequence {
    std::vector<PointCloud> frames;
    std::vector<Eigen::Isometry3d> truth, odometry;
};

Sequence MakeSequence(int n) {
    sim::TableSceneParams table = sim::TableSceneParamsFor(sim::TableSceneMode::kBoxes);
    table.min_objects = table.max_objects = 4;
    const sim::Scene scene = sim::MakeTableScene(table, 21);
    const auto views = sim::TableViewpoints(scene, 18, {}, 21);
    const sim::RayCaster caster(scene);
    sim::KinectParams kinect = test::ReducedKinect(2);
    kinect.num_threads = 1;
    Sequence s;
    for (int k = 0; k < n; ++k) {
        s.truth.push_back(views[static_cast<std::size_t>(k)].cast<double>());
        s.frames.push_back(sim::ScanKinect(caster, views[static_cast<std::size_t>(k)], kinect,
                                           static_cast<std::uint64_t>(100 + k)));
        s.odometry.push_back(k == 0 ? s.truth[0]
                                    : s.odometry.back() * (s.truth[k - 1].inverse() * s.truth[k]) *
                                          MakeTransform(3.0, {0.02, -0.02, 0.01}));
    }
    return s;
}

MapParams SmallMapParams() {
    MapParams p;
    p.registration = RegistrationParams::ForResolution(0.01f);
    p.registration.icp.depth_noise = 1.4e-3f;
    p.map_voxel = 0.01f;
    p.occupancy.resolution = 0.03;
    p.mesh.vertex_spacing = 0.01f;
    p.num_threads = 1;
    return p;
}

TEST(IncrementalMap, AlignsFramesFromNoisyOdometry) {
    const Sequence s = MakeSequence(4);
    IncrementalMap map(SmallMapParams());
    for (std::size_t k = 0; k < s.frames.size(); ++k) {
        const auto r = map.AddFrame(s.frames[k], s.odometry[k]);
        SCOPED_TRACE(k);
        EXPECT_TRUE(r.in_map) << r.registration.reason;
        EXPECT_LT(RotationErrorDeg(s.truth[k], r.T_world_sensor), 0.5);
        EXPECT_LT(TranslationError(s.truth[k], r.T_world_sensor), 0.008);
        if (k > 0) {
            EXPECT_GT(RotationErrorDeg(s.truth[k], s.odometry[k]), 2.5);
        }
    }
    ASSERT_EQ(map.frames().size(), 4u);
    EXPECT_GT(map.cloud().size(), 1000u);
    EXPECT_TRUE(map.cloud().HasNormals());
    // The occupancy map knows the table top as occupied and the air above it as free.
    ASSERT_NE(map.occupancy(), nullptr);
    EXPECT_GT(map.occupancy()->Counts().occupied_leaves, 100u);
    EXPECT_GT(map.occupancy()->Counts().free_leaves, 100u);
    // A mesh grown frame by frame; later frames re-sample their overlap.
    EXPECT_GT(map.mesh().triangles.size(), 1000u);
    EXPECT_GT(map.frames()[1].resampled_overlap, 0u);
    EXPECT_GT(map.frames()[1].mesh.new_triangles, 0u);
    EXPECT_GT(map.frames()[2].mesh.dropped_overlap + map.frames()[2].resampled_overlap, 0u);
}

TEST(IncrementalMap, FailedFramesAreLeftOut) {
    Sequence s = MakeSequence(3);
    MapParams p = SmallMapParams();
    p.mesh.enabled = false;
    IncrementalMap map(p);
    map.AddFrame(s.frames[0], s.odometry[0]);
    // NaN-only frame: reported and skipped.
    PointCloud nan_frame = s.frames[1];
    for (auto& q : nan_frame.points) q.setConstant(std::numeric_limits<float>::quiet_NaN());
    const auto r1 = map.AddFrame(nan_frame, s.odometry[1]);
    EXPECT_FALSE(r1.in_map);
    EXPECT_EQ(r1.registration.status, RegistrationStatus::kEmptyInput);
    // A frame of a single plane elsewhere: nothing constrains its alignment, so it is left out.
    const std::size_t before = map.cloud().size();
    const auto r2 = map.AddFrame(test::SinglePlane(0.002f, 3), s.odometry[2]);
    EXPECT_FALSE(r2.in_map) << r2.registration.reason;
    EXPECT_EQ(map.cloud().size(), before);
    EXPECT_THROW(IncrementalMap({.map_voxel = 0.0f}), InvalidArgument);
    Eigen::Isometry3d bad = Eigen::Isometry3d::Identity();
    bad(0, 0) = std::numeric_limits<double>::quiet_NaN();
    EXPECT_THROW(map.AddFrame(s.frames[0], bad), InvalidArgument);
}

TEST(IncrementalMap, SameMapForAnyThreadCount) {
    const Sequence s = MakeSequence(2);
    std::vector<std::vector<Eigen::Isometry3d>> poses;
    std::vector<std::size_t> triangles;
    for (int threads : {1, 2}) {
        MapParams p = SmallMapParams();
        p.num_threads = threads;
        IncrementalMap map(p);
        poses.emplace_back();
        for (std::size_t k = 0; k < s.frames.size(); ++k) {
            poses.back().push_back(map.AddFrame(s.frames[k], s.odometry[k]).T_world_sensor);
        }
        triangles.push_back(map.mesh().triangles.size());
    }
    for (std::size_t k = 0; k < poses[0].size(); ++k) {
        EXPECT_EQ(poses[0][k].matrix(), poses[1][k].matrix());
    }
    EXPECT_EQ(triangles[0], triangles[1]);
    // AlignFrameSequence gives the same poses without occupancy and mesh.
    const std::vector<const PointCloud*> ptrs = {&s.frames[0], &s.frames[1]};
    const auto aligned = AlignFrameSequence(ptrs, {s.odometry[0], s.odometry[1]}, SmallMapParams());
    EXPECT_EQ(aligned[1].T_world_sensor.matrix(), poses[0][1].matrix());
    EXPECT_THROW(AlignFrameSequence(ptrs, {s.odometry[0]}, SmallMapParams()), InvalidArgument);
}

}  // namespace
}  // namespace multicue

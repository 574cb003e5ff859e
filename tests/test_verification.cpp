#include <gtest/gtest.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/reconstruction/primitive_models.hpp"
#include "multicue/reconstruction/verification.hpp"
#include "multicue/sim/tabletop_scene.hpp"

namespace multicue {
namespace {

struct ScannedBox {
    PointCloud scan;  // camera frame, sensor at the origin
    BoxModel truth;   // the scanned box, camera frame
    Eigen::Vector3f toward_camera;
};

ScannedBox ScanOneBox() {
    sim::TableTopScene scene;
    sim::SceneBox box;
    box.center_xy = {0.05f, 0.0f};
    box.yaw = 0.4f;
    box.extents = {0.16f, 0.10f, 0.12f};
    scene.boxes.push_back(box);
    sim::ScanParams params;
    params.T_world_camera = sim::DefaultCameraPose(scene);
    ScannedBox s;
    s.scan = sim::ScanTableTopScene(scene, params);
    const Eigen::Isometry3f T_camera_world = params.T_world_camera.inverse();
    const Eigen::Vector3f center_world(box.center_xy.x(), box.center_xy.y(),
                                       scene.table_height + box.extents.z() / 2);
    s.truth.found = true;
    s.truth.center = T_camera_world * center_world;
    s.truth.axes = T_camera_world.linear() *
                   Eigen::AngleAxisf(box.yaw, Eigen::Vector3f::UnitZ()).toRotationMatrix();
    s.truth.extents = box.extents;
    s.toward_camera = -s.truth.center.normalized();
    return s;
}

TEST(Verification, TheTrueModelIsVerifiedInFrontAndOccludedBehind) {
    const ScannedBox s = ScanOneBox();
    const auto r = VerifyModel(BoxMesh(s.truth), s.scan, Eigen::Vector3f::Zero());
    EXPECT_TRUE(r.accepted);
    EXPECT_LT(r.invalid_ratio, 0.05f);
    EXPECT_GT(r.verified_ratio, 0.25f);  // the seen faces
    EXPECT_GT(r.occluded_ratio, 0.25f);  // the back and the bottom
    EXPECT_NEAR(r.verified_ratio + r.occluded_ratio + r.invalid_ratio, 1.0f, 1e-5f);
    EXPECT_EQ(r.states.size(), r.samples.size());
}

TEST(Verification, AModelInObservedFreeSpaceIsRejected) {
    const ScannedBox s = ScanOneBox();
    BoxModel floating = s.truth;
    floating.center += 0.12f * s.toward_camera;  // in the air between camera and box
    const auto r = VerifyModel(BoxMesh(floating), s.scan, Eigen::Vector3f::Zero());
    EXPECT_FALSE(r.accepted);
    EXPECT_GT(r.invalid_ratio, 0.3f);
}

TEST(Verification, AModelHiddenBehindTheObjectIsOccludedNotInvalid) {
    const ScannedBox s = ScanOneBox();
    BoxModel hidden = s.truth;
    hidden.extents *= 0.5f;  // inside the real box: never seen, never contradicted
    const auto r = VerifyModel(BoxMesh(hidden), s.scan, Eigen::Vector3f::Zero());
    EXPECT_TRUE(r.accepted);
    EXPECT_GT(r.occluded_ratio, 0.9f);
}

TEST(Verification, TheSameStatesOnAnyThreadCount) {
    const ScannedBox s = ScanOneBox();
    BoxModel shifted = s.truth;  // partly in free space, partly verified, partly hidden
    shifted.center += 0.04f * s.toward_camera;
    for (const BoxModel& model : {s.truth, shifted}) {
        const auto one = VerifyModel(BoxMesh(model), s.scan, Eigen::Vector3f::Zero());
        for (int threads : {2, 3, 0}) {
            VerificationParams p;
            p.num_threads = threads;
            const auto many = VerifyModel(BoxMesh(model), s.scan, Eigen::Vector3f::Zero(), p);
            EXPECT_EQ(many.states, one.states) << threads << " threads";
            EXPECT_EQ(many.invalid_ratio, one.invalid_ratio);
        }
    }
}

TEST(Verification, EmptyModelsAndBadParameters) {
    const ScannedBox s = ScanOneBox();
    const auto empty = VerifyModel(TriangleMesh{}, s.scan, Eigen::Vector3f::Zero());
    EXPECT_TRUE(empty.accepted);
    EXPECT_TRUE(empty.samples.empty());
    VerificationParams bad;
    bad.voxel_size = 0.0f;
    EXPECT_THROW(VerifyModel(BoxMesh(s.truth), s.scan, Eigen::Vector3f::Zero(), bad),
                 InvalidArgument);
    VerificationParams negative_threads;
    negative_threads.num_threads = -1;
    EXPECT_THROW(VerifyModel(BoxMesh(s.truth), s.scan, Eigen::Vector3f::Zero(), negative_threads),
                 InvalidArgument);
    VerificationParams huge;
    huge.voxel_size = 0.0001f;
    EXPECT_THROW(VerifyModel(BoxMesh(s.truth), s.scan, Eigen::Vector3f::Zero(), huge),
                 InvalidArgument);
    EXPECT_THROW(VerifyModel(BoxMesh(s.truth), s.scan,
                             Eigen::Vector3f(std::numeric_limits<float>::quiet_NaN(), 0, 0)),
                 InvalidArgument);
    EXPECT_THROW(SampleMeshSurface(BoxMesh(s.truth), -1.0f), InvalidArgument);
}

}  // namespace
}  // namespace multicue

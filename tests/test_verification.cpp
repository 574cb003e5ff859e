#include <gtest/gtest.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/reconstruction/primitive_models.hpp"
#include "multicue/reconstruction/verification.hpp"
#include "multicue/search/voxel_traversal.hpp"
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

// The states by the definition: every ray walked through the whole grid (the model's bounds grown
// by the margin), a cell occupied when a ray ends in it, else free when one crosses it; a sample is
// verified with an occupied cell within tolerance_voxels, invalid in a free cell, else occluded.
std::vector<SurfaceState> StatesByFullWalks(const VerificationResult& v, const PointCloud& scan,
                                            const VerificationParams& p) {
    Eigen::Vector3f lo = v.samples.front(), hi = lo;
    for (const auto& q : v.samples) {
        lo = lo.cwiseMin(q);
        hi = hi.cwiseMax(q);
    }
    lo.array() -= p.margin;
    hi.array() += p.margin;
    const Eigen::Vector3i dims =
        ((hi - lo) / p.voxel_size).array().ceil().cast<int>().cwiseMax(1).matrix();
    std::vector<int> cells(static_cast<std::size_t>(dims.prod()), 0);  // 0 unknown, 1 free, 2 occ.
    const auto inside = [&](const Eigen::Vector3i& c) {
        return (c.array() >= 0).all() && (c.array() < dims.array()).all();
    };
    const auto at = [&](const Eigen::Vector3i& c) -> int& {
        return cells[static_cast<std::size_t>((c.z() * dims.y() + c.y()) * dims.x() + c.x())];
    };
    for (const auto& point : scan.points) {
        if (!point.allFinite()) continue;
        Eigen::Vector3d s = ((Eigen::Vector3f::Zero() - lo) / p.voxel_size).cast<double>();
        const Eigen::Vector3d e = ((point - lo) / p.voxel_size).cast<double>();
        if (!ClipSegmentToBox(s, e, dims.cast<double>())) continue;
        const Eigen::Vector3i end = e.array().floor().cast<int>();
        const auto mark = [&](const Eigen::Vector3i& c) {
            if (c == end || !inside(c)) return false;
            at(c) = std::max(at(c), 1);
            return true;
        };
        if (mark(s.array().floor().cast<int>())) WalkCells(s, e, mark);
        if (inside(end)) at(end) = 2;
    }
    std::vector<SurfaceState> states;
    const int r = p.tolerance_voxels;
    for (const auto& q : v.samples) {
        const Eigen::Vector3i c = ((q - lo) / p.voxel_size).array().floor().cast<int>();
        bool near = false;
        for (int dz = -r; dz <= r; ++dz) {
            for (int dy = -r; dy <= r; ++dy) {
                for (int dx = -r; dx <= r; ++dx) {
                    const Eigen::Vector3i n = c + Eigen::Vector3i(dx, dy, dz);
                    near = near || (inside(n) && at(n) == 2);
                }
            }
        }
        states.push_back(near                      ? SurfaceState::kVerified
                         : inside(c) && at(c) == 1 ? SurfaceState::kInvalid
                                                   : SurfaceState::kOccluded);
    }
    return states;
}

TEST(Verification, StatesAreThoseOfWalkingEveryRayThroughTheWholeGrid) {
    const ScannedBox s = ScanOneBox();
    for (float shift : {0.0f, 0.04f, -0.05f, 0.1f}) {
        for (float margin : {0.0f, 0.05f, 0.12f}) {
            BoxModel model = s.truth;
            model.center += shift * s.toward_camera;
            model.extents *= 1.0f + shift;
            VerificationParams p;
            p.margin = margin;
            const VerificationResult v =
                VerifyModel(BoxMesh(model), s.scan, Eigen::Vector3f::Zero(), p);
            ASSERT_FALSE(v.samples.empty());
            EXPECT_EQ(v.states, StatesByFullWalks(v, s.scan, p)) << shift << " " << margin;
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

#include <cmath>
#include <map>

#include <gtest/gtest.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/sim/tabletop_scene.hpp"

namespace multicue::sim {
namespace {

ScanParams SmallScan(const TableTopScene& scene) {
    ScanParams p;
    p.camera = {160, 120, 131.25f, 131.25f, 79.5f, 59.5f};
    p.T_world_camera = DefaultCameraPose(scene);
    return p;
}

TEST(TableTopScene, OrganizedWithLabelsAndColors) {
    const TableTopScene scene = MakeDemoScene();
    const PointCloud c = ScanTableTopScene(scene, SmallScan(scene));
    EXPECT_EQ(c.width, 160u);
    EXPECT_EQ(c.height, 120u);
    EXPECT_TRUE(c.IsOrganized());
    EXPECT_NO_THROW(c.Validate());
    std::map<std::uint32_t, int> counts;
    for (std::size_t i = 0; i < c.size(); ++i) {
        counts[c.labels[i]]++;
        EXPECT_EQ(c.labels[i] == 0, !c.IsFinite(i));
    }
    EXPECT_GT(counts[kTableLabel], 1000);
    for (std::uint32_t k = 1; k <= 5; ++k) EXPECT_GT(counts[ObjectLabel(k)], 10) << "object " << k;
}

TEST(TableTopScene, TablePointsLieOnTheTableWithinNoise) {
    const TableTopScene scene = MakeDemoScene();
    ScanParams p = SmallScan(scene);
    p.axial_noise = 0.0f;
    const PointCloud c = ScanTableTopScene(scene, p);
    for (std::size_t i = 0; i < c.size(); ++i) {
        if (c.labels[i] != kTableLabel) continue;
        const Eigen::Vector3f w = p.T_world_camera * c.points[i];
        EXPECT_NEAR(w.z(), scene.table_height, 1e-4f);
    }
}

TEST(TableTopScene, DeterministicForASeed) {
    const TableTopScene scene = MakeDemoScene();
    const PointCloud a = ScanTableTopScene(scene, SmallScan(scene));
    const PointCloud b = ScanTableTopScene(scene, SmallScan(scene));
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t i = 0; i < a.size(); ++i) {
        if (a.IsFinite(i)) {
            EXPECT_EQ(a.points[i], b.points[i]);
        }
    }
}

TEST(TableTopScene, BadParameters) {
    const TableTopScene scene = MakeDemoScene();
    ScanParams p = SmallScan(scene);
    p.camera.fx = 0.0f;
    EXPECT_THROW(ScanTableTopScene(scene, p), InvalidArgument);
    p = SmallScan(scene);
    p.max_range = 0.1f;
    EXPECT_THROW(ScanTableTopScene(scene, p), InvalidArgument);
    p = SmallScan(scene);
    p.camera.width = 0;
    EXPECT_THROW(ScanTableTopScene(scene, p), InvalidArgument);
}

TEST(TableTopScene, EmptySceneSeesTableAndFloorOnly) {
    TableTopScene scene;
    const PointCloud c = ScanTableTopScene(scene, SmallScan(scene));
    for (auto l : c.labels) EXPECT_LE(l, kFloorLabel);
}

}  // namespace
}  // namespace multicue::sim

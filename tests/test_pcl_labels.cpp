// labels.pcd of perceive read by PCL: pcl::PointXYZL gets the object id of every point from the
// `label` field, in the input's layout.

#include <cstdint>
#include <cstring>
#include <map>

#include <gtest/gtest.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include "multicue/sim/tabletop_scene.hpp"
#include "multicue/system/perceive.hpp"
#include "multicue/system/perceive_output.hpp"
#include "test_util.hpp"

namespace multicue {
namespace {

TEST(PclLabels, PointXYZLReadsTheObjectIdsOfLabelsPcd) {
    sim::ScanParams scan;
    const auto scene = sim::MakeDemoScene();
    scan.T_world_camera = sim::DefaultCameraPose(scene);
    const PointCloud cloud = sim::ScanTableTopScene(scene, scan);
    const PerceiveResult r = Perceive(cloud, PerceiveParams{});
    ASSERT_GE(r.objects.size(), 3u);
    test::TempDir dir;
    WritePerceiveOutputs(dir.path(), PerceiveResultJson("scene.pcd", r),
                         PerceiveLabelsCloud(cloud, r), PerceiveModelsMesh(r));

    pcl::PointCloud<pcl::PointXYZL> labels;
    ASSERT_EQ(pcl::io::loadPCDFile((dir / "labels.pcd").string(), labels), 0);
    ASSERT_EQ(labels.size(), cloud.size());
    EXPECT_EQ(labels.width, cloud.width);
    EXPECT_EQ(labels.height, cloud.height);
    std::map<std::uint32_t, std::size_t> counts;
    for (std::size_t i = 0; i < labels.size(); ++i) {
        ASSERT_EQ(labels[i].label, r.point_objects[i]) << "point " << i;
        if (cloud.IsFinite(i)) {
            EXPECT_EQ(labels[i].x, cloud.points[i].x());
        }
        if (labels[i].label != 0) ++counts[labels[i].label];
    }
    ASSERT_EQ(counts.size(), r.objects.size());
    for (const auto& o : r.objects) {
        EXPECT_EQ(counts[static_cast<std::uint32_t>(o.id)], o.indices.size()) << "object " << o.id;
    }
}

}  // namespace
}  // namespace multicue

// multicue/adapters/pcl.hpp: conversions to and from pcl::PointCloud keep every field the point
// type has, the layout and the sensor pose; PCL's own PCD writer is the oracle for the result.

#include <cmath>
#include <cstdint>
#include <limits>
#include <random>

#include <gtest/gtest.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include "multicue/adapters/pcl.hpp"
#include "multicue/core/exceptions.hpp"
#include "multicue/io/pcd.hpp"
#include "test_util.hpp"

namespace multicue {
namespace {

/// A 4 x 3 organized cloud with every field, one NaN point and a sensor pose.
PointCloud FullCloud() {
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    std::uniform_int_distribution<int> byte(0, 255);
    PointCloud c;
    const std::size_t n = 12;
    for (std::size_t i = 0; i < n; ++i) {
        c.points.emplace_back(u(rng), u(rng), u(rng));
        c.normals.push_back(Eigen::Vector3f(u(rng), u(rng), u(rng)).normalized());
        c.colors.push_back(
            Color{static_cast<std::uint8_t>(byte(rng)), static_cast<std::uint8_t>(byte(rng)),
                  static_cast<std::uint8_t>(byte(rng)), static_cast<std::uint8_t>(byte(rng))});
        c.labels.push_back(static_cast<std::uint32_t>(1000 + i));
        c.curvature.push_back(0.01f * static_cast<float>(i));
    }
    c.points[5] = Eigen::Vector3f::Constant(std::numeric_limits<float>::quiet_NaN());
    c.width = 4;
    c.height = 3;
    c.sensor_origin = {0.5f, -0.25f, 1.0f};
    c.sensor_orientation = Eigen::Quaternionf(Eigen::AngleAxisf(0.3f, Eigen::Vector3f::UnitY()));
    return c;
}

void ExpectSamePoints(const PointCloud& a, const PointCloud& b) {
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t i = 0; i < a.size(); ++i) {
        if (!a.IsFinite(i)) {
            EXPECT_FALSE(b.IsFinite(i)) << i;
            continue;
        }
        EXPECT_EQ(a.points[i], b.points[i]) << i;
    }
}

TEST(AdaptersPcl, XyzrgbaKeepsColoursLayoutAndPose) {
    const PointCloud c = FullCloud();
    const auto pcl_cloud = adapters::ToPcl<pcl::PointXYZRGBA>(c);
    EXPECT_EQ(pcl_cloud.width, 4u);
    EXPECT_EQ(pcl_cloud.height, 3u);
    EXPECT_FALSE(pcl_cloud.is_dense);
    EXPECT_EQ(pcl_cloud[2].r, c.colors[2].r);
    EXPECT_EQ(pcl_cloud[2].a, c.colors[2].a);
    EXPECT_EQ(pcl_cloud.sensor_origin_.head<3>(), c.sensor_origin);
    const PointCloud back = adapters::FromPcl(pcl_cloud);
    ExpectSamePoints(c, back);
    EXPECT_EQ(back.colors, c.colors);
    EXPECT_TRUE(back.IsOrganized());
    EXPECT_EQ(back.width, 4u);
    EXPECT_FALSE(back.HasLabels());  // PointXYZRGBA has no label
    EXPECT_FALSE(back.HasNormals());
    EXPECT_TRUE(back.sensor_orientation.isApprox(c.sensor_orientation));
}

TEST(AdaptersPcl, XyzlAndXyzrgbAndPointNormal) {
    const PointCloud c = FullCloud();
    const PointCloud l = adapters::FromPcl(adapters::ToPcl<pcl::PointXYZL>(c));
    EXPECT_EQ(l.labels, c.labels);
    EXPECT_FALSE(l.HasColors());
    const PointCloud rgb = adapters::FromPcl(adapters::ToPcl<pcl::PointXYZRGB>(c));
    ASSERT_EQ(rgb.colors.size(), c.size());
    EXPECT_EQ(rgb.colors[3].g, c.colors[3].g);
    const PointCloud pn = adapters::FromPcl(adapters::ToPcl<pcl::PointNormal>(c));
    EXPECT_EQ(pn.normals, c.normals);
    EXPECT_EQ(pn.curvature, c.curvature);
    const PointCloud xyz = adapters::FromPcl(adapters::ToPcl<pcl::PointXYZ>(c));
    ExpectSamePoints(c, xyz);
    EXPECT_FALSE(xyz.HasColors() || xyz.HasLabels() || xyz.HasNormals());
}

TEST(AdaptersPcl, MissingFieldsGetThePointTypeDefaults) {
    PointCloud c({{1, 2, 3}, {4, 5, 6}});
    const auto p = adapters::ToPcl<pcl::PointXYZRGBL>(c);
    EXPECT_TRUE(p.is_dense);
    EXPECT_EQ(p.height, 1u);
    EXPECT_EQ(p.width, 2u);
    EXPECT_EQ(p[1].label, 0u);
    EXPECT_EQ(p[1].a, 255);
    EXPECT_EQ(p[1].r, 0);
}

TEST(AdaptersPcl, NormalsThroughPclNormal) {
    PointCloud c = FullCloud();
    const auto normals = adapters::ToPclNormals(c);
    ASSERT_EQ(normals.size(), c.size());
    EXPECT_EQ(normals[4].getNormalVector3fMap(), c.normals[4]);
    EXPECT_EQ(normals.width, 4u);
    PointCloud d = c;
    d.normals.clear();
    d.curvature.clear();
    EXPECT_THROW(adapters::ToPclNormals(d), DataError);
    adapters::SetNormalsFromPcl(d, normals);
    EXPECT_EQ(d.normals, c.normals);
    EXPECT_EQ(d.curvature, c.curvature);
    pcl::PointCloud<pcl::Normal> short_normals;
    short_normals.resize(3);
    EXPECT_THROW(adapters::SetNormalsFromPcl(d, short_normals), InvalidArgument);
}

TEST(AdaptersPcl, BadAndEmptyInput) {
    PointCloud bad = FullCloud();
    bad.labels.pop_back();
    EXPECT_THROW(adapters::ToPcl<pcl::PointXYZL>(bad), DataError);
    const auto empty = adapters::ToPcl<pcl::PointXYZ>(PointCloud{});
    EXPECT_TRUE(empty.empty());
    EXPECT_TRUE(adapters::FromPcl(empty).empty());
}

// Oracle: the converted cloud written by PCL's own writer reads back in multicue as the original.
TEST(AdaptersPcl, PclWriterAgreesWithTheConversion) {
    pcl::console::setVerbosityLevel(pcl::console::L_ERROR);
    const PointCloud c = FullCloud();
    test::TempDir dir;
    const auto path = (dir / "pcl.pcd").string();
    ASSERT_EQ(pcl::io::savePCDFileBinary(path, adapters::ToPcl<pcl::PointXYZRGBL>(c)), 0);
    const PointCloud r = io::ReadPcd(path);
    ExpectSamePoints(c, r);
    EXPECT_EQ(r.labels, c.labels);
    ASSERT_EQ(r.colors.size(), c.size());
    for (std::size_t i = 0; i < c.size(); ++i) {
        EXPECT_EQ(r.colors[i].r, c.colors[i].r);
        EXPECT_EQ(r.colors[i].b, c.colors[i].b);
    }
    EXPECT_EQ(r.width, 4u);
    EXPECT_EQ(r.height, 3u);
}

}  // namespace
}  // namespace multicue

// multicue/adapters/open3d.hpp: conversions to and from open3d::geometry::PointCloud; Open3D's
// own bounds and normal orientation are the oracles.

#include <cmath>
#include <cstdint>
#include <limits>
#include <random>

#include <gtest/gtest.h>
#include <open3d/geometry/PointCloud.h>

#include "multicue/adapters/open3d.hpp"
#include "multicue/core/exceptions.hpp"

namespace multicue {
namespace {

PointCloud RandomCloud(std::size_t n) {
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(-2.0f, 2.0f);
    PointCloud c;
    for (std::size_t i = 0; i < n; ++i) {
        c.points.emplace_back(u(rng), u(rng), u(rng));
        c.normals.push_back(Eigen::Vector3f(u(rng), u(rng), u(rng)).normalized());
        c.colors.push_back(Color{static_cast<std::uint8_t>(i % 256),
                                 static_cast<std::uint8_t>((7 * i) % 256),
                                 static_cast<std::uint8_t>(255 - i % 256), 255});
    }
    c.SetUnorganized();
    return c;
}

TEST(AdaptersOpen3d, RoundTripKeepsPointsNormalsAndEveryColourValue) {
    const PointCloud c = RandomCloud(512);  // all 256 values of each channel
    const open3d::geometry::PointCloud o = adapters::ToOpen3d(c);
    ASSERT_EQ(o.points_.size(), c.size());
    EXPECT_TRUE(o.HasNormals());
    EXPECT_TRUE(o.HasColors());
    EXPECT_DOUBLE_EQ(o.colors_[255].x(), 1.0);
    const PointCloud back = adapters::FromOpen3d(o);
    EXPECT_EQ(back.points, c.points);  // float -> double -> float is exact
    EXPECT_EQ(back.normals, c.normals);
    EXPECT_EQ(back.colors, c.colors);
    EXPECT_EQ(back.height, 1u);
    EXPECT_EQ(back.width, c.size());
}

TEST(AdaptersOpen3d, Open3dSeesTheSameGeometry) {
    const PointCloud c = RandomCloud(1000);
    const auto o = adapters::ToOpen3d(c);
    Eigen::Vector3f lo = c.points[0], hi = c.points[0];
    for (const auto& p : c.points) {
        lo = lo.cwiseMin(p);
        hi = hi.cwiseMax(p);
    }
    EXPECT_TRUE(o.GetMinBound().isApprox(lo.cast<double>()));
    EXPECT_TRUE(o.GetMaxBound().isApprox(hi.cast<double>()));
    // Open3D orients the converted normals towards a point; multicue sees the flipped ones.
    auto oriented = o;
    oriented.OrientNormalsTowardsCameraLocation(Eigen::Vector3d::Zero());
    const PointCloud back = adapters::FromOpen3d(oriented);
    for (std::size_t i = 0; i < c.size(); ++i) {
        EXPECT_LE(back.normals[i].dot(c.points[i]), 1e-6f) << i;
        EXPECT_NEAR(std::abs(back.normals[i].dot(c.normals[i])), 1.0f, 1e-6f) << i;
    }
}

TEST(AdaptersOpen3d, OutOfRangeColoursAreClampedAndFieldsMayBeAbsent) {
    open3d::geometry::PointCloud o;
    o.points_ = {{0, 0, 0}, {1, 1, 1}};
    o.colors_ = {{-0.5, 0.5, 2.0}, {1.0, 0.0, 0.2}};
    const PointCloud c = adapters::FromOpen3d(o);
    EXPECT_EQ(c.colors[0], (Color{0, 128, 255, 255}));
    EXPECT_EQ(c.colors[1], (Color{255, 0, 51, 255}));
    EXPECT_FALSE(c.HasNormals());
    PointCloud plain({{1, 2, 3}});
    const auto p = adapters::ToOpen3d(plain);
    EXPECT_FALSE(p.HasNormals());
    EXPECT_FALSE(p.HasColors());
}

TEST(AdaptersOpen3d, NanPointsKeepTheirPlaceAndBadInputThrows) {
    PointCloud c = RandomCloud(4);
    c.points[1].x() = std::numeric_limits<float>::quiet_NaN();
    const auto o = adapters::ToOpen3d(c);
    ASSERT_EQ(o.points_.size(), 4u);
    EXPECT_TRUE(std::isnan(o.points_[1].x()));
    c.colors.pop_back();
    EXPECT_THROW(adapters::ToOpen3d(c), DataError);
    EXPECT_TRUE(adapters::FromOpen3d(open3d::geometry::PointCloud{}).empty());
}

}  // namespace
}  // namespace multicue

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <string>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/search/voxel_hash_map.hpp"
#include "test_util.hpp"

namespace multicue {
namespace {

using test::kNaN;
using Coord = std::tuple<int, int, int>;

// Reference: an ordered map from voxel coordinates to point indices, keyed (y, x, z) to iterate
// in the documented voxel order.
std::map<Coord, Indices> ReferenceVoxels(const PointCloud& c, float leaf) {
    std::map<Coord, Indices> voxels;
    for (std::size_t i = 0; i < c.size(); ++i) {
        if (!c.points[i].allFinite()) continue;
        const Eigen::Vector3i v = VoxelCoordinates(c.points[i], leaf);
        voxels[{v.y(), v.x(), v.z()}].push_back(static_cast<Index>(i));
    }
    return voxels;
}

Coord ToCoord(const Eigen::Vector3i& v) { return {v.y(), v.x(), v.z()}; }

void ExpectMatchesReference(const VoxelHashMap& map, const PointCloud& c, float leaf) {
    const auto expected = ReferenceVoxels(c, leaf);
    ASSERT_EQ(map.num_voxels(), expected.size());
    std::size_t points = 0;
    VoxelHashMap::VoxelId v = 0;
    for (const auto& [coord, indices] : expected) {
        EXPECT_EQ(ToCoord(map.Coordinates(v)), coord);
        const auto got = map.Points(v);
        EXPECT_EQ(Indices(got.begin(), got.end()), indices);
        const auto [y, x, z] = coord;
        EXPECT_EQ(map.Find({x, y, z}), v);
        points += indices.size();
        ++v;
    }
    EXPECT_EQ(map.num_points(), points);
}

TEST(VoxelHashMap, MatchesOrderedMapReference) {
    PointCloud c = test::RandomCloud(5000, 3, 1.0f);
    for (std::size_t i = 0; i < c.size(); i += 97) c.points[i].y() = kNaN;
    c.points[7].x() = std::numeric_limits<float>::infinity();
    const VoxelHashMap map(c, {.leaf_size = 0.1f});
    ExpectMatchesReference(map, c, 0.1f);
    // Every finite point is found in its voxel.
    for (std::size_t i = 0; i < c.size(); ++i) {
        const VoxelHashMap::VoxelId v = map.FindVoxelOf(c.points[i]);
        if (!c.points[i].allFinite()) {
            EXPECT_EQ(v, VoxelHashMap::kNoVoxel);
            continue;
        }
        ASSERT_NE(v, VoxelHashMap::kNoVoxel);
        const auto pts = map.Points(v);
        EXPECT_TRUE(std::binary_search(pts.begin(), pts.end(), static_cast<Index>(i)));
    }
}

TEST(VoxelHashMap, WideGridUsesTheSameOrder) {
    // Over 2^32 voxel keys in the bounding grid: the sort runs on 64-bit keys.
    PointCloud c = test::RandomCloud(3000, 4, 500.0f);
    c.points.push_back({-600.0f, 0.0f, 0.0f});
    c.SetUnorganized();
    const VoxelHashMap map(c, {.leaf_size = 0.05f});
    const auto& dims = map.partition().dims;
    EXPECT_GT(
        static_cast<double>(dims[0]) * static_cast<double>(dims[1]) * static_cast<double>(dims[2]),
        4294967296.0);
    ExpectMatchesReference(map, c, 0.05f);
}

TEST(VoxelHashMap, NeighborsMatchBruteForce) {
    const PointCloud c = test::RandomCloud(3000, 5, 1.0f);
    const float leaf = 0.2f;
    const VoxelHashMap map(c, {.leaf_size = leaf});
    const auto reference = ReferenceVoxels(c, leaf);
    std::vector<VoxelHashMap::VoxelId> got;
    for (int x = -7; x <= 6; ++x) {
        for (int y = -7; y <= 6; y += 3) {
            for (int z = -7; z <= 6; z += 2) {
                for (const bool centre : {true, false}) {
                    std::vector<VoxelHashMap::VoxelId> expected;
                    VoxelHashMap::VoxelId v = 0;
                    for (const auto& [coord, indices] : reference) {
                        const auto [cy, cx, cz] = coord;
                        const int cheb =
                            std::max({std::abs(cx - x), std::abs(cy - y), std::abs(cz - z)});
                        if (cheb <= 1 && (centre || cheb > 0)) expected.push_back(v);
                        ++v;
                    }
                    EXPECT_EQ(map.Neighbors({x, y, z}, centre, got), expected.size());
                    EXPECT_EQ(got, expected);
                }
            }
        }
    }
}

TEST(VoxelHashMap, RegularGridKnownVoxels) {
    // Two points in each voxel of a 4x3x2 block of 0.1 m voxels starting at the origin, and
    // negative coordinates rounding down.
    PointCloud c;
    for (int x = 0; x < 4; ++x) {
        for (int y = 0; y < 3; ++y) {
            for (int z = 0; z < 2; ++z) {
                const Eigen::Vector3f centre = 0.1f * Eigen::Vector3f(x + 0.5f, y + 0.5f, z + 0.5f);
                c.points.push_back(centre + Eigen::Vector3f::Constant(0.02f));
                c.points.push_back(centre - Eigen::Vector3f::Constant(0.02f));
            }
        }
    }
    c.points.push_back({-0.05f, -0.15f, 0.01f});
    c.SetUnorganized();
    const VoxelHashMap map(c, {.leaf_size = 0.1f});
    EXPECT_EQ(map.num_voxels(), 25u);
    EXPECT_EQ(map.Coordinates(0), Eigen::Vector3i(-1, -2, 0));
    EXPECT_EQ(map.Points(0).size(), 1u);
    for (VoxelHashMap::VoxelId v = 1; v < 25; ++v) EXPECT_EQ(map.Points(v).size(), 2u);
    EXPECT_EQ(map.Coordinates(24), Eigen::Vector3i(3, 2, 1));
    EXPECT_EQ(map.Find({0, 0, 0}), 1u);
    EXPECT_EQ(map.Find({4, 0, 0}), VoxelHashMap::kNoVoxel);   // outside the grid
    EXPECT_EQ(map.Find({-1, 0, 0}), VoxelHashMap::kNoVoxel);  // inside the grid, empty
    EXPECT_EQ(map.Find({std::numeric_limits<int>::max(), 0, 0}), VoxelHashMap::kNoVoxel);
    std::vector<VoxelHashMap::VoxelId> n;
    EXPECT_EQ(map.Neighbors({1, 1, 0}, true, n), 18u);  // 3x3x2 occupied around an inner voxel
    EXPECT_EQ(map.Neighbors({1, 1, 0}, false, n), 17u);
    EXPECT_EQ(VoxelCoordinates({-0.05f, 0.0f, 0.25f}, 0.1f), Eigen::Vector3i(-1, 0, 2));
}

TEST(VoxelHashMap, OneVoxel) {
    // All points in one voxel: a grid of a single key, nothing to sort.
    const PointCloud c({{0.31f, 0.32f, 0.33f}, {0.35f, 0.36f, 0.37f}, {0.39f, 0.31f, 0.30f}});
    const VoxelHashMap map(c, {.leaf_size = 0.1f});
    ASSERT_EQ(map.num_voxels(), 1u);
    EXPECT_EQ(map.Coordinates(0), Eigen::Vector3i(3, 3, 3));
    const auto pts = map.Points(0);
    EXPECT_EQ(Indices(pts.begin(), pts.end()), (Indices{0, 1, 2}));
    std::vector<VoxelHashMap::VoxelId> n;
    EXPECT_EQ(map.Neighbors({2, 2, 2}, false, n), 1u);
    EXPECT_EQ(map.Neighbors({3, 3, 3}, false, n), 0u);
}

TEST(VoxelHashMap, EmptyAndNaNOnlyClouds) {
    PointCloud nan_only = test::RandomCloud(10);
    for (auto& p : nan_only.points) p.x() = kNaN;
    const VoxelHashMap map(nan_only, {.leaf_size = 0.1f});
    EXPECT_TRUE(map.empty());
    EXPECT_EQ(map.num_points(), 0u);
    EXPECT_EQ(map.Find({0, 0, 0}), VoxelHashMap::kNoVoxel);
    EXPECT_EQ(map.FindVoxelOf({0, 0, 0}), VoxelHashMap::kNoVoxel);
    std::vector<VoxelHashMap::VoxelId> n{1, 2};
    EXPECT_EQ(map.Neighbors({0, 0, 0}, true, n), 0u);
    EXPECT_TRUE(n.empty());
    const VoxelHashMap empty(PointCloud{}, {.leaf_size = 0.1f});
    EXPECT_TRUE(empty.empty());
    EXPECT_EQ(empty.partition().offsets, std::vector<std::uint32_t>{0});
}

TEST(VoxelHashMap, BadParametersThrow) {
    const PointCloud c = test::RandomCloud(100);
    for (const float leaf : {0.0f, -0.1f, kNaN, std::numeric_limits<float>::infinity(), 1e-45f}) {
        EXPECT_THROW(VoxelHashMap(c, {.leaf_size = leaf}), InvalidArgument) << leaf;
    }
    EXPECT_THROW(VoxelHashMap(c, {.leaf_size = 0.1f, .num_threads = -1}), InvalidArgument);
    EXPECT_THROW(VoxelCoordinates({kNaN, 0, 0}, 0.1f), InvalidArgument);
    EXPECT_THROW(VoxelCoordinates({1e9f, 0, 0}, 0.1f), InvalidArgument);
    EXPECT_THROW(VoxelCoordinates({1, 0, 0}, 0.0f), InvalidArgument);
    try {
        (void)VoxelHashMap(c, {.leaf_size = -0.1f});
        FAIL() << "no exception";
    } catch (const InvalidArgument& e) {
        EXPECT_NE(std::string(e.what()).find("-0.1"), std::string::npos) << e.what();
    }
    // Too fine a grid for the extent: more than 2^64 voxels, or coordinates beyond 32 bits.
    PointCloud wide({{-1000.0f, -1000.0f, -1000.0f}, {1000.0f, 1000.0f, 1000.0f}});
    try {
        (void)VoxelHashMap(wide, {.leaf_size = 1e-6f});
        FAIL() << "no exception";
    } catch (const InvalidArgument& e) {
        EXPECT_NE(std::string(e.what()).find("2^64"), std::string::npos) << e.what();
    }
    EXPECT_THROW(VoxelHashMap(PointCloud({{1e30f, 0, 0}}), {.leaf_size = 0.01f}), InvalidArgument);
    // The suggested leaf size works.
    EXPECT_NO_THROW(VoxelHashMap(wide, {.leaf_size = 1e-3f}));
}

TEST(VoxelHashMap, SameResultForAnyThreadCount) {
    PointCloud c = test::RandomCloud(60000, 9, 2.0f);  // several blocks of the parallel build
    for (std::size_t i = 0; i < c.size(); i += 13) c.points[i].z() = kNaN;
    const VoxelPartition serial = PartitionByVoxel(c, {.leaf_size = 0.05f, .num_threads = 1});
    for (const int threads : {0, 2}) {
        const VoxelPartition parallel =
            PartitionByVoxel(c, {.leaf_size = 0.05f, .num_threads = threads});
        EXPECT_EQ(parallel.keys, serial.keys);
        EXPECT_EQ(parallel.offsets, serial.offsets);
        EXPECT_EQ(parallel.indices, serial.indices);
    }
    EXPECT_GT(serial.num_voxels(), 10000u);
}

}  // namespace
}  // namespace multicue

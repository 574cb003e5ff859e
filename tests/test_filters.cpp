#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <numeric>
#include <random>
#include <string>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/core/logging.hpp"
#include "multicue/filters/filters.hpp"
#include "multicue/search/kdtree.hpp"
#include "multicue/search/voxel_hash_map.hpp"
#include "test_util.hpp"

namespace multicue {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();

// Random cloud with every optional field filled and some invalid points.
PointCloud RichCloud(std::size_t n, std::uint32_t seed, float extent = 1.0f) {
    PointCloud c = test::RandomCloud(n, seed, extent);
    std::mt19937 rng(seed + 100);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    std::uniform_int_distribution<int> byte(0, 255), label(0, 3);
    for (std::size_t i = 0; i < n; ++i) {
        c.normals.push_back(Eigen::Vector3f(u(rng), u(rng), u(rng)).normalized());
        c.colors.push_back(
            {static_cast<std::uint8_t>(byte(rng)), static_cast<std::uint8_t>(byte(rng)),
             static_cast<std::uint8_t>(byte(rng)), static_cast<std::uint8_t>(byte(rng))});
        c.curvature.push_back(0.5f + 0.5f * u(rng));
        c.labels.push_back(static_cast<std::uint32_t>(label(rng)));
        c.intensity.push_back(100.0f * u(rng));
        c.confidence.push_back(0.5f + 0.5f * u(rng));
    }
    for (std::size_t i = 0; i < n; i += 17) c.points[i].x() = kNaN;
    for (std::size_t i = 5; i < n; i += 23) c.normals[i] = Eigen::Vector3f::Constant(kNaN);
    for (std::size_t i = 3; i < n; i += 29) c.curvature[i] = kNaN;
    return c;
}

PointCloud NaNCloud(std::size_t n) {
    PointCloud c = test::RandomCloud(n);
    for (auto& p : c.points) p = Eigen::Vector3f::Constant(kNaN);
    return c;
}

// Cube of uniform inliers in [-0.5, 0.5]^3 followed by 5% outliers 2-5 m away.
PointCloud CubeWithOutliers(std::size_t inliers, std::size_t outliers, std::uint32_t seed) {
    PointCloud c = test::RandomCloud(inliers, seed, 0.5f);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> dir(-1.0f, 1.0f), dist(2.0f, 5.0f);
    for (std::size_t i = 0; i < outliers; ++i) {
        const Eigen::Vector3f d = Eigen::Vector3f(dir(rng), dir(rng), dir(rng)).normalized();
        c.points.push_back(dist(rng) * d);
    }
    c.SetUnorganized();
    return c;
}

bool BitEqual(const std::vector<Eigen::Vector3f>& a, const std::vector<Eigen::Vector3f>& b) {
    return a.size() == b.size() &&
           (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(a[0])) == 0);
}
bool BitEqual(const std::vector<float>& a, const std::vector<float>& b) {
    return a.size() == b.size() &&
           (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(a[0])) == 0);
}

// ------------------------------------------------------------------ non-finite removal

TEST(RemoveNonFinite, KeepsFinitePointsWithTheirFields) {
    PointCloud c = RichCloud(200, 1);
    c.points[2].z() = kInf;
    c.width = 20;
    c.height = 10;
    c.sensor_origin = {1, 2, 3};
    Indices expected;
    for (Index i = 0; i < c.size(); ++i) {
        if (std::isfinite(c.points[i].x()) && std::isfinite(c.points[i].z())) expected.push_back(i);
    }
    EXPECT_EQ(FiniteIndices(c), expected);
    EXPECT_EQ(FiniteIndices(c, 2), expected);
    EXPECT_EQ(FiniteIndices(c, 0), expected);
    const PointCloud out = RemoveNonFinite(c);
    ASSERT_EQ(out.size(), expected.size());
    EXPECT_EQ(out.height, 1u);
    EXPECT_EQ(out.width, out.size());
    EXPECT_EQ(out.sensor_origin, c.sensor_origin);
    for (std::size_t j = 0; j < expected.size(); ++j) {
        EXPECT_EQ(out.points[j], c.points[expected[j]]);
        EXPECT_EQ(out.colors[j], c.colors[expected[j]]);
        EXPECT_EQ(out.labels[j], c.labels[expected[j]]);
    }
}

TEST(RemoveNonFinite, EmptyAndNaNOnly) {
    EXPECT_TRUE(FiniteIndices(PointCloud{}).empty());
    EXPECT_TRUE(RemoveNonFinite(PointCloud{}).empty());
    EXPECT_TRUE(FiniteIndices(NaNCloud(5)).empty());
    EXPECT_TRUE(RemoveNonFinite(NaNCloud(5)).empty());
    PointCloud broken = test::RandomCloud(5);
    broken.labels.resize(2);
    EXPECT_THROW(RemoveNonFinite(broken), DataError);
}

// ------------------------------------------------------------------ crop box

TEST(CropBox, MatchesBruteForceWithTransform) {
    const PointCloud c = RichCloud(3000, 2, 2.0f);
    CropBoxParams p{.min = {-0.5f, -1.0f, -0.2f}, .max = {1.0f, 0.3f, 0.7f}};
    p.T_box_cloud = Eigen::Translation3f(0.1f, -0.2f, 0.3f) *
                    Eigen::AngleAxisf(0.6f, Eigen::Vector3f(1, -1, 2).normalized());
    Indices inside, outside;
    for (Index i = 0; i < c.size(); ++i) {
        if (!c.points[i].allFinite()) continue;
        const Eigen::Vector3f q = p.T_box_cloud * c.points[i];
        const bool in = (q.array() >= p.min.array()).all() && (q.array() <= p.max.array()).all();
        (in ? inside : outside).push_back(i);
    }
    EXPECT_EQ(CropBox(c, p), inside);
    p.negative = true;
    EXPECT_EQ(CropBox(c, p), outside);
    EXPECT_GT(inside.size(), 50u);
    EXPECT_GT(outside.size(), 50u);
}

TEST(CropBox, KnownBoxBoundsIncludedAndOpenAxes) {
    // Points on a 0.1 m lattice from 0 to 1 m on each axis.
    PointCloud c;
    for (int x = 0; x <= 10; ++x) {
        for (int y = 0; y <= 10; ++y) {
            for (int z = 0; z <= 10; ++z) c.points.push_back(0.1f * Eigen::Vector3f(x, y, z));
        }
    }
    c.points.push_back(Eigen::Vector3f::Constant(kNaN));
    c.SetUnorganized();
    // [0.2, 0.4] x [0, 1] x [0.5, 0.5]: 3 x 11 x 1 lattice points (bounds included).
    const Indices in = CropBox(c, {.min = {0.2f, 0.0f, 0.5f}, .max = {0.4f, 1.0f, 0.5f}});
    EXPECT_EQ(in.size(), 33u);
    for (Index i : in) EXPECT_NEAR(c.points[i].z(), 0.5f, 1e-6f);
    // Open below in z: everything with z <= 0.25.
    const Indices low = CropBox(c, {.min = {-kInf, -kInf, -kInf}, .max = {kInf, kInf, 0.25f}});
    EXPECT_EQ(low.size(), 3u * 121u);
    // The NaN point is in neither result.
    const Indices out =
        CropBox(c, {.min = {0.2f, 0.0f, 0.5f}, .max = {0.4f, 1.0f, 0.5f}, .negative = true});
    EXPECT_EQ(in.size() + out.size(), c.size() - 1);
}

TEST(CropBox, BadParametersAndEmptyInput) {
    const PointCloud c = test::RandomCloud(10);
    EXPECT_THROW(CropBox(c, {.min = {0, 1, 0}, .max = {1, 0, 1}}), InvalidArgument);
    EXPECT_THROW(CropBox(c, {.min = {kNaN, 0, 0}, .max = {1, 1, 1}}), InvalidArgument);
    CropBoxParams bad;
    bad.T_box_cloud.translation().x() = kNaN;
    EXPECT_THROW(CropBox(c, bad), InvalidArgument);
    try {
        CropBox(c, {.min = {0, 2, 0}, .max = {1, 1, 1}});
        FAIL() << "no exception";
    } catch (const InvalidArgument& e) {
        EXPECT_NE(std::string(e.what()).find("min.y"), std::string::npos) << e.what();
    }
    EXPECT_TRUE(CropBox(PointCloud{}, {}).empty());
    EXPECT_TRUE(CropBox(NaNCloud(4), {.negative = true}).empty());
}

// ------------------------------------------------------------------ voxel grid

// Reference voxel grid: std::map over voxel coordinates, field means computed directly.
PointCloud ReferenceVoxelGrid(const PointCloud& c, float leaf, std::size_t min_points) {
    std::map<std::tuple<int, int, int>, Indices> voxels;
    for (Index i = 0; i < c.size(); ++i) {
        if (!c.points[i].allFinite()) continue;
        const Eigen::Vector3i v = VoxelCoordinates(c.points[i], leaf);
        voxels[{v.y(), v.x(), v.z()}].push_back(i);  // the documented (y, x, z) order
    }
    PointCloud out;
    for (const auto& [key, idx] : voxels) {
        if (idx.size() < min_points) continue;
        Eigen::Vector3d p = Eigen::Vector3d::Zero(), nsum = Eigen::Vector3d::Zero();
        double r = 0, g = 0, b = 0, a = 0, curv = 0, inten = 0, conf = 0;
        int ncount = 0, ccount = 0;
        std::map<std::uint32_t, int> votes;
        for (Index i : idx) {
            p += c.points[i].cast<double>();
            if (c.normals[i].allFinite()) {
                nsum += c.normals[i].cast<double>();
                ++ncount;
            }
            r += c.colors[i].r;
            g += c.colors[i].g;
            b += c.colors[i].b;
            a += c.colors[i].a;
            if (std::isfinite(c.curvature[i])) {
                curv += c.curvature[i];
                ++ccount;
            }
            inten += c.intensity[i];
            conf += c.confidence[i];
            ++votes[c.labels[i]];
        }
        const double n = static_cast<double>(idx.size());
        out.points.push_back((p / n).cast<float>());
        out.normals.push_back(ncount > 0 && nsum.norm() > 0
                                  ? Eigen::Vector3f((nsum / nsum.norm()).cast<float>())
                                  : Eigen::Vector3f::Constant(kNaN));
        auto round = [&](double s) { return static_cast<std::uint8_t>(std::floor(s / n + 0.5)); };
        out.colors.push_back({round(r), round(g), round(b), round(a)});
        out.curvature.push_back(ccount > 0 ? static_cast<float>(curv / ccount) : kNaN);
        out.intensity.push_back(static_cast<float>(inten / n));
        out.confidence.push_back(static_cast<float>(conf / n));
        // std::map iterates labels ascending, so max_element's first maximum is the smallest.
        out.labels.push_back(std::max_element(votes.begin(), votes.end(), [](auto& x, auto& y) {
                                 return x.second < y.second;
                             })->first);
    }
    out.SetUnorganized();
    return out;
}

TEST(VoxelGrid, MatchesMapReference) {
    const PointCloud c = RichCloud(20000, 3);
    for (const auto& [leaf, min_points] :
         {std::pair{0.1f, 1}, std::pair{0.05f, 1}, std::pair{0.2f, 25}}) {
        const PointCloud got =
            VoxelGrid(c, {.leaf_size = leaf, .min_points_per_voxel = min_points});
        const PointCloud expected =
            ReferenceVoxelGrid(c, leaf, static_cast<std::size_t>(min_points));
        ASSERT_EQ(got.size(), expected.size()) << leaf;
        ASSERT_GT(got.size(), 0u);
        for (std::size_t j = 0; j < got.size(); ++j) {
            EXPECT_TRUE(got.points[j].isApprox(expected.points[j], 1e-6f)) << j;
            EXPECT_EQ(got.colors[j], expected.colors[j]) << j;
            EXPECT_EQ(got.labels[j], expected.labels[j]) << j;
            if (expected.normals[j].allFinite()) {
                EXPECT_TRUE(got.normals[j].isApprox(expected.normals[j], 1e-5f)) << j;
            } else {
                EXPECT_FALSE(got.normals[j].allFinite());
            }
            if (std::isnan(expected.curvature[j])) {
                EXPECT_TRUE(std::isnan(got.curvature[j])) << j;
            } else {
                EXPECT_NEAR(got.curvature[j], expected.curvature[j], 1e-6f) << j;
            }
            EXPECT_NEAR(got.intensity[j], expected.intensity[j], 1e-4f);
            EXPECT_NEAR(got.confidence[j], expected.confidence[j], 1e-6f);
        }
    }
}

TEST(VoxelGrid, RegularGridGivesExactCentroidsAndColours) {
    // Each 1 m voxel (x, y, z in 0..2) holds two points symmetric about its centre, coloured
    // 10 and 13 (mean 11.5 rounds to 12) and (200, 0) in red/green.
    PointCloud c;
    for (int x = 0; x < 3; ++x) {
        for (int y = 0; y < 3; ++y) {
            for (int z = 0; z < 3; ++z) {
                const Eigen::Vector3f centre(x + 0.5f, y + 0.5f, z + 0.5f);
                c.points.push_back(centre + Eigen::Vector3f(0.25f, -0.125f, 0.0625f));
                c.points.push_back(centre - Eigen::Vector3f(0.25f, -0.125f, 0.0625f));
                c.colors.push_back({10, 200, 7, 255});
                c.colors.push_back({13, 0, 7, 255});
            }
        }
    }
    c.SetUnorganized();
    const PointCloud out = VoxelGrid(c, {.leaf_size = 1.0f});
    ASSERT_EQ(out.size(), 27u);
    std::size_t j = 0;
    for (int y = 0; y < 3; ++y) {  // output order: y, then x, then z
        for (int x = 0; x < 3; ++x) {
            for (int z = 0; z < 3; ++z, ++j) {
                EXPECT_EQ(out.points[j], Eigen::Vector3f(x + 0.5f, y + 0.5f, z + 0.5f));
                EXPECT_EQ(out.colors[j], (Color{12, 100, 7, 255}));
            }
        }
    }
    EXPECT_FALSE(out.HasNormals());
    EXPECT_FALSE(out.HasLabels());
}

TEST(VoxelGrid, LabelsNormalsAndExtraFields) {
    PointCloud c({{0.1f, 0.1f, 0.1f},
                  {0.2f, 0.1f, 0.1f},
                  {0.3f, 0.1f, 0.1f},
                  {0.4f, 0.1f, 0.1f},
                  {1.1f, 0.1f, 0.1f},
                  {1.2f, 0.1f, 0.1f},
                  {1.3f, 0.1f, 0.1f}});
    c.labels = {7, 3, 7, 3, 9, 9, 2};                                   // tie 3/7 -> 3; majority 9
    c.normals = {{0, 0, 1}, {0, 0, -1}, {0, 0, 1},         {0, 0, -1},  // cancel -> NaN
                 {1, 0, 0}, {0, 1, 0},  {kNaN, kNaN, kNaN}};            // NaN normal ignored
    c.extra_fields.push_back({"x_extra", 'F', 4, 1, std::vector<std::uint8_t>(7 * 4, 0)});
    c.sensor_origin = {0, 0, 2};
    c.sensor_orientation = Eigen::Quaternionf(Eigen::AngleAxisf(0.3f, Eigen::Vector3f::UnitZ()));
    std::vector<std::string> logged;
    SetLogSink([&](LogLevel, std::string_view m) { logged.emplace_back(m); });
    const LogLevel level = GetLogLevel();
    SetLogLevel(LogLevel::kDebug);
    const PointCloud out = VoxelGrid(c, {.leaf_size = 1.0f});
    SetLogLevel(level);
    SetLogSink({});
    ASSERT_EQ(out.size(), 2u);
    EXPECT_EQ(out.labels, (std::vector<std::uint32_t>{3, 9}));
    EXPECT_FALSE(out.normals[0].allFinite());
    EXPECT_TRUE(out.normals[1].isApprox(Eigen::Vector3f(1, 1, 0).normalized()));
    EXPECT_TRUE(out.extra_fields.empty());
    ASSERT_EQ(logged.size(), 1u);
    EXPECT_NE(logged[0].find("x_extra"), std::string::npos);
    EXPECT_EQ(out.sensor_origin, c.sensor_origin);
    EXPECT_TRUE(out.sensor_orientation.isApprox(c.sensor_orientation));
    EXPECT_NO_THROW(out.Validate());
}

TEST(VoxelGrid, OrganizedInputGivesUnorganizedOutput) {
    PointCloud c = RichCloud(600, 4);
    c.width = 30;
    c.height = 20;
    const PointCloud out = VoxelGrid(c, {.leaf_size = 0.5f});
    EXPECT_EQ(out.height, 1u);
    EXPECT_EQ(out.width, out.size());
    EXPECT_EQ(out.size(), 64u);  // 4 voxels per axis over [-1, 1)
}

TEST(VoxelGrid, BadParametersThrow) {
    const PointCloud c = test::RandomCloud(100);
    for (const float leaf : {0.0f, -0.1f, kNaN, kInf}) {
        EXPECT_THROW(VoxelGrid(c, {.leaf_size = leaf}), InvalidArgument) << leaf;
    }
    try {
        VoxelGrid(c, {.leaf_size = -0.1f});
        FAIL() << "no exception";
    } catch (const InvalidArgument& e) {
        EXPECT_NE(std::string(e.what()).find("leaf_size must be > 0, got -0.1"), std::string::npos)
            << e.what();
    }
    EXPECT_THROW(VoxelGrid(c, {.min_points_per_voxel = -1}), InvalidArgument);
    EXPECT_THROW(VoxelGrid(c, {.num_threads = -2}), InvalidArgument);
    // A grid too fine for the extent is an error naming a usable leaf size, not a silent overflow.
    const PointCloud wide({{-5000.0f, -5000.0f, -5000.0f}, {5000.0f, 5000.0f, 5000.0f}});
    try {
        VoxelGrid(wide, {.leaf_size = 1e-5f});
        FAIL() << "no exception";
    } catch (const InvalidArgument& e) {
        EXPECT_NE(std::string(e.what()).find("use leaf_size >="), std::string::npos) << e.what();
    }
    PointCloud broken = test::RandomCloud(10);
    broken.colors.resize(3);
    EXPECT_THROW(VoxelGrid(broken, {.leaf_size = 0.1f}), DataError);
}

TEST(VoxelGrid, EmptyAndNaNOnly) {
    PointCloud empty;
    empty.colors.clear();
    EXPECT_TRUE(VoxelGrid(empty, {}).empty());
    PointCloud nan = NaNCloud(50);
    nan.colors.resize(50);
    nan.sensor_origin = {1, 1, 1};
    const PointCloud out = VoxelGrid(nan, {});
    EXPECT_TRUE(out.empty());
    EXPECT_EQ(out.sensor_origin, nan.sensor_origin);
    EXPECT_NO_THROW(out.Validate());
}

TEST(VoxelGrid, SameResultForAnyThreadCount) {
    const PointCloud c = RichCloud(80000, 5, 1.0f);
    const PointCloud serial = VoxelGrid(c, {.leaf_size = 0.03f, .num_threads = 1});
    EXPECT_GT(serial.size(), 20000u);
    for (const int threads : {0, 2}) {
        const PointCloud parallel = VoxelGrid(c, {.leaf_size = 0.03f, .num_threads = threads});
        EXPECT_TRUE(BitEqual(parallel.points, serial.points));
        EXPECT_TRUE(BitEqual(parallel.normals, serial.normals));
        EXPECT_TRUE(BitEqual(parallel.curvature, serial.curvature));
        EXPECT_TRUE(BitEqual(parallel.intensity, serial.intensity));
        EXPECT_EQ(parallel.colors, serial.colors);
        EXPECT_EQ(parallel.labels, serial.labels);
    }
}

// ------------------------------------------------------------------ statistical outliers

// Brute-force mean distance to the k nearest other finite points.
std::vector<double> BruteMeanDistances(const PointCloud& c, std::size_t k) {
    std::vector<double> out(c.size(), std::numeric_limits<double>::infinity());
    std::vector<double> d;
    for (std::size_t i = 0; i < c.size(); ++i) {
        if (!c.points[i].allFinite()) continue;
        d.clear();
        for (std::size_t j = 0; j < c.size(); ++j) {
            if (j != i && c.points[j].allFinite()) {
                d.push_back((c.points[j].cast<double>() - c.points[i].cast<double>()).norm());
            }
        }
        std::sort(d.begin(), d.end());
        d.resize(std::min(d.size(), k));
        if (!d.empty())
            out[i] = std::accumulate(d.begin(), d.end(), 0.0) / static_cast<double>(d.size());
    }
    return out;
}

TEST(StatisticalOutlierRemoval, MatchesBruteForce) {
    PointCloud c = test::RandomCloud(1500, 6);
    for (std::size_t i = 0; i < c.size(); i += 31) c.points[i].y() = kNaN;
    c.points[10] = c.points[11];  // a duplicate point
    const KdTree tree(c);
    for (const auto& [k, ratio] : {std::pair{8, 1.0f}, std::pair{1, 0.5f}, std::pair{30, 2.0f}}) {
        const auto mean = BruteMeanDistances(c, static_cast<std::size_t>(k));
        double sum = 0, sq = 0;
        std::size_t n = 0;
        for (double m : mean) {
            if (!std::isfinite(m)) continue;
            sum += m;
            ++n;
        }
        const double mu = sum / static_cast<double>(n);
        for (double m : mean) {
            if (std::isfinite(m)) sq += (m - mu) * (m - mu);
        }
        const double threshold = mu + ratio * std::sqrt(sq / static_cast<double>(n - 1));
        const Indices kept = StatisticalOutlierRemoval(c, tree, {.k = k, .std_ratio = ratio});
        EXPECT_TRUE(std::is_sorted(kept.begin(), kept.end()));
        std::size_t compared = 0;
        for (Index i = 0; i < c.size(); ++i) {
            const bool is_kept = std::binary_search(kept.begin(), kept.end(), i);
            if (!std::isfinite(mean[i])) {
                EXPECT_FALSE(is_kept);
                continue;
            }
            if (std::abs(mean[i] - threshold) < 1e-5 * threshold) continue;  // float rounding
            EXPECT_EQ(is_kept, mean[i] <= threshold) << i;
            ++compared;
        }
        EXPECT_GT(compared, c.size() * 9 / 10);
    }
}

TEST(StatisticalOutlierRemoval, RemovesFarOutliersOfACube) {
    const std::size_t inliers = 4000, outliers = 200;  // 5% outliers
    const PointCloud c = CubeWithOutliers(inliers, outliers, 7);
    const KdTree tree(c);
    const Indices kept = StatisticalOutlierRemoval(c, tree, {.k = 20, .std_ratio = 2.0f});
    const auto inliers_kept = static_cast<std::size_t>(
        std::count_if(kept.begin(), kept.end(), [&](Index i) { return i < inliers; }));
    EXPECT_EQ(kept.size(), inliers_kept) << "an outlier was kept";
    EXPECT_GT(inliers_kept, inliers * 95 / 100);
}

TEST(StatisticalOutlierRemoval, BadParametersEmptyAndNaNOnly) {
    const PointCloud c = test::RandomCloud(100);
    const KdTree tree(c);
    EXPECT_THROW(StatisticalOutlierRemoval(c, tree, {.k = 0}), InvalidArgument);
    EXPECT_THROW(StatisticalOutlierRemoval(c, tree, {.std_ratio = -1.0f}), InvalidArgument);
    EXPECT_THROW(StatisticalOutlierRemoval(c, tree, {.std_ratio = kNaN}), InvalidArgument);
    EXPECT_THROW(StatisticalOutlierRemoval(c, tree, {.num_threads = -1}), InvalidArgument);
    const PointCloud empty;
    EXPECT_TRUE(StatisticalOutlierRemoval(empty, KdTree(empty), {}).empty());
    const PointCloud nan = NaNCloud(20);
    EXPECT_TRUE(StatisticalOutlierRemoval(nan, KdTree(nan), {}).empty());
    // A single point has no neighbours and is dropped; two points keep each other.
    const PointCloud one({{0, 0, 0}});
    EXPECT_TRUE(StatisticalOutlierRemoval(one, KdTree(one), {}).empty());
    const PointCloud two({{0, 0, 0}, {1, 0, 0}});
    EXPECT_EQ(StatisticalOutlierRemoval(two, KdTree(two), {}), (Indices{0, 1}));
}

TEST(StatisticalOutlierRemoval, SameResultForAnyThreadCount) {
    const PointCloud c = CubeWithOutliers(6000, 300, 8);
    const KdTree tree(c);
    const Indices serial = StatisticalOutlierRemoval(c, tree, {.k = 10, .num_threads = 1});
    EXPECT_EQ(StatisticalOutlierRemoval(c, tree, {.k = 10, .num_threads = 0}), serial);
    EXPECT_EQ(StatisticalOutlierRemoval(c, tree, {.k = 10, .num_threads = 2}), serial);
}

// ------------------------------------------------------------------ radius outliers

TEST(RadiusOutlierRemoval, MatchesBruteForce) {
    PointCloud c = test::RandomCloud(2000, 9);
    for (std::size_t i = 0; i < c.size(); i += 37) c.points[i].z() = kNaN;
    c.points[20] = c.points[21];
    const KdTree tree(c);
    for (const auto& [radius, min_neighbors] :
         {std::pair{0.1f, 2}, std::pair{0.15f, 6}, std::pair{0.05f, 0}}) {
        Indices expected;
        for (Index i = 0; i < c.size(); ++i) {
            if (!c.points[i].allFinite()) continue;
            int others = 0;
            for (Index j = 0; j < c.size(); ++j) {
                others += j != i && (c.points[j] - c.points[i]).squaredNorm() <= radius * radius;
            }
            if (others >= min_neighbors) expected.push_back(i);
        }
        EXPECT_EQ(RadiusOutlierRemoval(c, tree, {.radius = radius, .min_neighbors = min_neighbors}),
                  expected);
        EXPECT_GT(expected.size(), 0u);
        if (min_neighbors > 0) {
            EXPECT_LT(expected.size(), c.CountFinite());  // the test removes something
        } else {
            EXPECT_EQ(expected.size(), c.CountFinite());
        }
    }
}

TEST(RadiusOutlierRemoval, RemovesFarOutliersOfACube) {
    const std::size_t inliers = 4000, outliers = 200;
    const PointCloud c = CubeWithOutliers(inliers, outliers, 10);
    const KdTree tree(c);
    const Indices kept = RadiusOutlierRemoval(c, tree, {.radius = 0.1f, .min_neighbors = 3});
    const auto inliers_kept = static_cast<std::size_t>(
        std::count_if(kept.begin(), kept.end(), [&](Index i) { return i < inliers; }));
    EXPECT_EQ(kept.size(), inliers_kept) << "an outlier was kept";
    EXPECT_GT(inliers_kept, inliers * 95 / 100);
}

TEST(RadiusOutlierRemoval, BadParametersEmptyAndNaNOnly) {
    const PointCloud c = test::RandomCloud(100);
    const KdTree tree(c);
    EXPECT_THROW(RadiusOutlierRemoval(c, tree, {.radius = -0.1f}), InvalidArgument);
    EXPECT_THROW(RadiusOutlierRemoval(c, tree, {.radius = 0.0f}), InvalidArgument);
    EXPECT_THROW(RadiusOutlierRemoval(c, tree, {.radius = kInf}), InvalidArgument);
    EXPECT_THROW(RadiusOutlierRemoval(c, tree, {.min_neighbors = -1}), InvalidArgument);
    EXPECT_THROW(RadiusOutlierRemoval(c, tree, {.num_threads = -1}), InvalidArgument);
    const PointCloud empty;
    EXPECT_TRUE(RadiusOutlierRemoval(empty, KdTree(empty), {}).empty());
    const PointCloud nan = NaNCloud(20);
    EXPECT_TRUE(RadiusOutlierRemoval(nan, KdTree(nan), {.min_neighbors = 0}).empty());
}

TEST(RadiusOutlierRemoval, SameResultForAnyThreadCount) {
    const PointCloud c = CubeWithOutliers(6000, 300, 11);
    const KdTree tree(c);
    const RadiusOutlierParams p{.radius = 0.06f, .min_neighbors = 2, .num_threads = 1};
    const Indices serial = RadiusOutlierRemoval(c, tree, p);
    for (const int threads : {0, 2}) {
        RadiusOutlierParams q = p;
        q.num_threads = threads;
        EXPECT_EQ(RadiusOutlierRemoval(c, tree, q), serial);
    }
}

}  // namespace
}  // namespace multicue

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/search/organized.hpp"
#include "test_util.hpp"

namespace multicue {
namespace {

using test::kNaN;

// Organized cloud of a pinhole camera (focal length f, principal point at the image centre)
// looking at a wavy surface 0.8-1.6 m away; about 10% of the pixels are invalid (NaN).
PointCloud PinholeCloud(std::uint32_t width, std::uint32_t height, float f, std::uint32_t seed = 3,
                        float depth_sign = 1.0f) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    std::normal_distribution<float> noise(0.0f, 0.002f);
    const float cx = 0.5f * static_cast<float>(width - 1),
                cy = 0.5f * static_cast<float>(height - 1);
    PointCloud c;
    c.points.resize(std::size_t{width} * height);
    c.width = width;
    c.height = height;
    for (std::uint32_t v = 0; v < height; ++v) {
        for (std::uint32_t u = 0; u < width; ++u) {
            const float xn = (static_cast<float>(u) - cx) / f,
                        yn = (static_cast<float>(v) - cy) / f;
            float z = 1.2f + 0.25f * xn + 0.15f * std::sin(8.0f * yn) + noise(rng);
            if (unit(rng) < 0.1f) z = kNaN;
            z *= depth_sign;
            // x = (u - cx) z / f keeps x/z exact whatever the depth noise, as a depth camera does.
            c.points[std::size_t{v} * width + u] = {xn * z, yn * z, z};
        }
    }
    return c;
}

// Brute force: finite window pixels within the radius, with their squared distances.
std::vector<std::pair<float, Index>> BruteWindow(const PointCloud& c, Index center, int half,
                                                 float radius) {
    std::vector<std::pair<float, Index>> out;
    const Eigen::Vector3f q = c.points[center];
    if (!q.allFinite()) return out;
    const int u0 = static_cast<int>(center % c.width), v0 = static_cast<int>(center / c.width);
    for (int v = v0 - half; v <= v0 + half; ++v) {
        for (int u = u0 - half; u <= u0 + half; ++u) {
            if (u < 0 || v < 0 || u >= static_cast<int>(c.width) || v >= static_cast<int>(c.height))
                continue;
            const auto i = static_cast<Index>(v * static_cast<int>(c.width) + u);
            if (!c.points[i].allFinite()) continue;
            const float d2 = (c.points[i] - q).squaredNorm();
            if (d2 <= radius * radius) out.emplace_back(d2, i);
        }
    }
    return out;
}

TEST(OrganizedSearch, RadiusMatchesBruteForceOverWindow) {
    const PointCloud c = PinholeCloud(40, 30, 33.0f);
    Indices idx;
    std::vector<float> d2;
    for (const auto& [half, radius] :
         {std::pair{1, 0.05f}, std::pair{3, 0.08f}, std::pair{5, 1.0f}}) {
        const OrganizedSearchParams p{.half_window = half, .radius = radius};
        for (Index i = 0; i < c.size(); ++i) {
            const auto expected = BruteWindow(c, i, half, radius);
            ASSERT_EQ(OrganizedRadiusSearch(c, i, p, idx, d2), expected.size());
            ASSERT_EQ(d2.size(), expected.size());
            for (std::size_t j = 0; j < expected.size(); ++j) {
                EXPECT_EQ(idx[j], expected[j].second);  // ascending index order
                EXPECT_EQ(d2[j], expected[j].first);
            }
        }
    }
}

TEST(OrganizedSearch, KnnMatchesBruteForceOverWindow) {
    const PointCloud c = PinholeCloud(40, 30, 33.0f, 5);
    Indices idx;
    std::vector<float> d2;
    for (const auto& [half, radius, k] : {std::tuple{2, 1.0f, 5}, std::tuple{4, 0.06f, 12},
                                          std::tuple{1, 10.0f, 30}, std::tuple{3, 0.05f, 16}}) {
        const OrganizedSearchParams p{.half_window = half, .radius = radius};
        for (Index i = 0; i < c.size(); ++i) {
            auto expected = BruteWindow(c, i, half, radius);
            std::sort(expected.begin(), expected.end());
            expected.resize(std::min<std::size_t>(expected.size(), static_cast<std::size_t>(k)));
            ASSERT_EQ(OrganizedKnnSearch(c, i, k, p, idx, d2), expected.size());
            for (std::size_t j = 0; j < expected.size(); ++j) {
                EXPECT_EQ(idx[j], expected[j].second);
                EXPECT_EQ(d2[j], expected[j].first);
            }
            if (c.points[i].allFinite()) {
                EXPECT_EQ(idx.front(), i);  // the centre itself, at distance 0
            }
        }
    }
}

// A mask leaves pixels out of every neighbourhood, as if they were invalid.
TEST(OrganizedSearch, MaskedPixelsAreNoNeighbours) {
    const PointCloud c = PinholeCloud(40, 30, 33.0f, 7);
    std::mt19937 rng(8);
    std::vector<std::uint8_t> mask(c.size());
    for (auto& m : mask) m = rng() % 3 == 0 ? 0 : 1;
    PointCloud masked = c;  // the same frame with the masked-out pixels made invalid
    for (std::size_t i = 0; i < c.size(); ++i) {
        if (mask[i] == 0) masked.points[i] = Eigen::Vector3f::Constant(kNaN);
    }
    Indices idx, expected_idx;
    std::vector<float> d2, expected_d2;
    for (Index i = 0; i < c.size(); ++i) {
        if (mask[i] == 0) continue;  // masked pixels as centres: see below
        const OrganizedSearchParams p{.half_window = 3, .radius = 0.1f, .mask = mask};
        const OrganizedSearchParams plain{.half_window = 3, .radius = 0.1f};
        OrganizedRadiusSearch(c, i, p, idx, d2);
        OrganizedRadiusSearch(masked, i, plain, expected_idx, expected_d2);
        EXPECT_EQ(idx, expected_idx);
        EXPECT_EQ(d2, expected_d2);
        OrganizedKnnSearch(c, i, 7, p, idx, d2);
        OrganizedKnnSearch(masked, i, 7, plain, expected_idx, expected_d2);
        EXPECT_EQ(idx, expected_idx);
        EXPECT_EQ(d2, expected_d2);
    }
    // A centre outside the mask still finds the mask's pixels around it, itself not among them.
    Index outside = 0;
    while (mask[outside] != 0 || !c.points[outside].allFinite()) ++outside;
    OrganizedRadiusSearch(c, outside, {.half_window = 2, .mask = mask}, idx, d2);
    for (Index j : idx) EXPECT_EQ(mask[j], 1);
    std::vector<std::uint8_t> short_mask(c.size() - 1, 1);
    EXPECT_THROW(OrganizedRadiusSearch(c, 0, {.mask = short_mask}, idx, d2), InvalidArgument);
    EXPECT_THROW(OrganizedKnnSearch(c, 0, 3, {.mask = short_mask}, idx, d2), InvalidArgument);
}

TEST(OrganizedSearch, EqualDistancesAreOrderedByIndex) {
    PointCloud c;
    c.width = 3;
    c.height = 3;
    c.points.assign(9, Eigen::Vector3f(1, 1, 1));  // all at the same place
    Indices idx;
    std::vector<float> d2;
    EXPECT_EQ(OrganizedKnnSearch(c, 4, 4, OrganizedSearchParams{.half_window = 1}, idx, d2), 4u);
    EXPECT_EQ(idx, (Indices{0, 1, 2, 3}));
}

TEST(OrganizedSearch, WindowIsClampedAndNaNCentreHasNoNeighbours) {
    PointCloud c = PinholeCloud(8, 6, 10.0f);
    for (auto& p : c.points) {
        if (!p.allFinite()) p = Eigen::Vector3f(0.0f, 0.0f, 1.0f);  // all valid
    }
    Indices idx;
    std::vector<float> d2;
    // Corner pixel with a 2-pixel window: 3x3 pixels inside the image.
    EXPECT_EQ(OrganizedRadiusSearch(c, 0, OrganizedSearchParams{.half_window = 2}, idx, d2), 9u);
    EXPECT_EQ(idx, (Indices{0, 1, 2, 8, 9, 10, 16, 17, 18}));
    // A window larger than the image holds every valid pixel.
    EXPECT_EQ(OrganizedRadiusSearch(c, 20, OrganizedSearchParams{.half_window = 100}, idx, d2),
              c.size());
    c.points[20] = Eigen::Vector3f::Constant(kNaN);
    EXPECT_EQ(OrganizedRadiusSearch(c, 20, OrganizedSearchParams{}, idx, d2), 0u);
    EXPECT_EQ(OrganizedKnnSearch(c, 20, 3, OrganizedSearchParams{}, idx, d2), 0u);
    EXPECT_TRUE(idx.empty());
    EXPECT_TRUE(d2.empty());
    // Invalid neighbours are never returned.
    EXPECT_EQ(OrganizedRadiusSearch(c, 21, OrganizedSearchParams{.half_window = 1}, idx, d2), 8u);
    EXPECT_EQ(std::count(idx.begin(), idx.end(), Index{20}), 0);
}

TEST(OrganizedSearch, AllNaNCloudHasNoNeighbours) {
    PointCloud c;
    c.width = 4;
    c.height = 4;
    c.points.assign(16, Eigen::Vector3f::Constant(kNaN));
    Indices idx;
    std::vector<float> d2;
    for (Index i = 0; i < 16; ++i) {
        EXPECT_EQ(OrganizedRadiusSearch(c, i, OrganizedSearchParams{}, idx, d2), 0u);
        EXPECT_EQ(OrganizedKnnSearch(c, i, 5, OrganizedSearchParams{}, idx, d2), 0u);
    }
    EXPECT_THROW(EstimateFocalLength(c), DataError);
}

TEST(OrganizedSearch, BadArgumentsThrow) {
    const PointCloud organized = PinholeCloud(8, 6, 10.0f);
    const PointCloud unorganized = test::RandomCloud(48);
    Indices idx;
    std::vector<float> d2;
    const OrganizedSearchParams ok;
    EXPECT_THROW(OrganizedRadiusSearch(unorganized, 0, ok, idx, d2), InvalidArgument);
    EXPECT_THROW(OrganizedKnnSearch(unorganized, 0, 3, ok, idx, d2), InvalidArgument);
    EXPECT_THROW(OrganizedRadiusSearch(PointCloud{}, 0, ok, idx, d2), InvalidArgument);
    EXPECT_THROW(OrganizedRadiusSearch(organized, 48, ok, idx, d2), InvalidArgument);
    EXPECT_THROW(OrganizedRadiusSearch(organized, 0, {.half_window = 0}, idx, d2), InvalidArgument);
    EXPECT_THROW(OrganizedRadiusSearch(organized, 0, {.radius = 0.0f}, idx, d2), InvalidArgument);
    EXPECT_THROW(OrganizedRadiusSearch(organized, 0, {.radius = -0.1f}, idx, d2), InvalidArgument);
    EXPECT_THROW(OrganizedRadiusSearch(organized, 0, {.radius = kNaN}, idx, d2), InvalidArgument);
    EXPECT_THROW(OrganizedKnnSearch(organized, 0, 0, ok, idx, d2), InvalidArgument);
    EXPECT_THROW(EstimateFocalLength(unorganized), InvalidArgument);
    try {
        OrganizedRadiusSearch(organized, 0, {.radius = -0.1f}, idx, d2);
        FAIL() << "no exception";
    } catch (const InvalidArgument& e) {
        EXPECT_NE(std::string(e.what()).find("-0.1"), std::string::npos) << e.what();
    }
}

TEST(OrganizedSearch, EstimatesTheFocalLength) {
    // 640x480 frame of a 525-pixel camera, looking along +z and along -z.
    for (const float sign : {1.0f, -1.0f}) {
        const PointCloud c = PinholeCloud(640, 480, 525.0f, 11, sign);
        EXPECT_NEAR(EstimateFocalLength(c), 525.0f, 0.5f);
    }
    // The same frame moved to a world pose with the sensor pose recorded.
    PointCloud moved = PinholeCloud(320, 240, 262.5f, 12);
    const Eigen::Quaternionf q(Eigen::AngleAxisf(0.7f, Eigen::Vector3f(1, 2, 3).normalized()));
    const Eigen::Vector3f t(0.5f, -2.0f, 1.0f);
    for (auto& p : moved.points) p = q * p + t;
    moved.sensor_orientation = q;
    moved.sensor_origin = t;
    EXPECT_NEAR(EstimateFocalLength(moved), 262.5f, 0.5f);
}

TEST(OrganizedSearch, WindowHalfSizeForRadius) {
    EXPECT_EQ(WindowHalfSizeForRadius(0.02f, 1.0f, 525.0f), 11);  // 10.5 pixels
    EXPECT_EQ(WindowHalfSizeForRadius(0.02f, -1.0f, 525.0f), 11);
    EXPECT_EQ(WindowHalfSizeForRadius(0.02f, 2.0f, 525.0f), 6);
    EXPECT_EQ(WindowHalfSizeForRadius(1e-6f, 3.0f, 525.0f), 1);
    EXPECT_EQ(WindowHalfSizeForRadius(1e6f, 1e-3f, 525.0f), 1'000'000);
    EXPECT_THROW(WindowHalfSizeForRadius(0.0f, 1.0f, 525.0f), InvalidArgument);
    EXPECT_THROW(WindowHalfSizeForRadius(0.02f, 0.0f, 525.0f), InvalidArgument);
    EXPECT_THROW(WindowHalfSizeForRadius(0.02f, kNaN, 525.0f), InvalidArgument);
    EXPECT_THROW(WindowHalfSizeForRadius(0.02f, 1.0f, -1.0f), InvalidArgument);
}

TEST(OrganizedSearch, ScaledWindowFindsEveryRadiusNeighbour) {
    // Known model: with the window of WindowHalfSizeForRadius scaled by 1.2 (the documented
    // off-axis margin) the organized radius search equals a radius search over the whole image,
    // for every pixel of a frame with the field of view of a 640x480, f = 525 camera.
    const PointCloud c = PinholeCloud(160, 120, 131.25f, 21);
    const float f = EstimateFocalLength(c);
    const float radius = 0.03f;
    Indices idx;
    std::vector<float> d2;
    std::size_t total = 0;
    for (Index i = 0; i < c.size(); i += 7) {
        if (!c.points[i].allFinite()) continue;
        const int half = static_cast<int>(std::ceil(
            1.2f * static_cast<float>(WindowHalfSizeForRadius(radius, c.points[i].z(), f))));
        OrganizedRadiusSearch(c, i, {.half_window = half, .radius = radius}, idx, d2);
        Indices expected;
        for (Index j = 0; j < c.size(); ++j) {
            if ((c.points[j] - c.points[i]).squaredNorm() <= radius * radius) expected.push_back(j);
        }
        ASSERT_EQ(idx, expected) << "pixel " << i;
        total += idx.size();
    }
    EXPECT_GT(total, 1000u);  // the test exercised real neighbourhoods
}

}  // namespace
}  // namespace multicue

namespace multicue {
namespace {

// The finite points of an organized frame in a shuffled order, without the grid.
PointCloud DropGrid(const PointCloud& organized, std::uint32_t seed, Indices& pixel_of_point) {
    Indices order;
    for (std::size_t i = 0; i < organized.size(); ++i) {
        if (organized.points[i].allFinite()) order.push_back(static_cast<Index>(i));
    }
    std::mt19937 rng(seed);
    std::shuffle(order.begin(), order.end(), rng);
    PointCloud flat;
    for (Index i : order) flat.points.push_back(organized.points[i]);
    flat.SetUnorganized();
    pixel_of_point = order;
    return flat;
}

TEST(RecoverImageGrid, PutsADepthFrameBackOnItsPixels) {
    const PointCloud frame = PinholeCloud(160, 120, 140.0f, 5);
    Indices pixel_of_point;
    PointCloud flat = DropGrid(frame, 2, pixel_of_point);
    // A rotation alone (PCL's 0 1 0 0 convention) keeps it a sensor frame.
    flat.sensor_orientation = Eigen::Quaternionf(0.0f, 1.0f, 0.0f, 0.0f);
    const auto grid = RecoverImageGrid(flat);
    ASSERT_TRUE(grid.has_value());
    // The image may lose empty border columns or rows, never a point; pixels keep their layout.
    ASSERT_TRUE(grid->organized.IsOrganized());
    EXPECT_LE(grid->organized.width, 160u);
    EXPECT_LE(grid->organized.height, 120u);
    EXPECT_GE(grid->organized.width, 158u);
    const std::uint32_t w = grid->organized.width;
    for (std::size_t k = 0; k < flat.size(); ++k) {
        const Index p = grid->pixel_of[k];
        ASSERT_NE(p, ImageGrid::kNoPoint);
        EXPECT_EQ(grid->input_of[p], k);
        EXPECT_EQ(grid->organized.points[p], flat.points[k]);
        if (k > 0) {
            // Neighbouring pixels of the frame are neighbouring pixels of the grid.
            const Index a = pixel_of_point[k], b = pixel_of_point[k - 1];
            const int du = static_cast<int>(a % 160) - static_cast<int>(b % 160);
            const int dv = static_cast<int>(a / 160) - static_cast<int>(b / 160);
            const int gu = static_cast<int>(p % w) - static_cast<int>(grid->pixel_of[k - 1] % w);
            const int gv = static_cast<int>(p / w) - static_cast<int>(grid->pixel_of[k - 1] / w);
            EXPECT_EQ(du, gu);
            EXPECT_EQ(dv, gv);
        }
    }
}

TEST(RecoverImageGrid, TheSameGridOnAnyThreadCount) {
    const PointCloud frame = PinholeCloud(160, 120, 140.0f, 5);
    Indices pixel_of_point;
    const PointCloud flat = DropGrid(frame, 3, pixel_of_point);
    const auto one = RecoverImageGrid(flat, 1);
    const auto two = RecoverImageGrid(flat, 2);
    ASSERT_TRUE(one.has_value());
    ASSERT_TRUE(two.has_value());
    EXPECT_EQ(one->organized.width, two->organized.width);
    EXPECT_EQ(one->organized.height, two->organized.height);
    EXPECT_EQ(one->input_of, two->input_of);
    EXPECT_EQ(one->pixel_of, two->pixel_of);
    ASSERT_EQ(one->organized.size(), two->organized.size());
    for (std::size_t p = 0; p < one->organized.size(); ++p) {
        const Eigen::Vector3f& x = one->organized.points[p];
        const Eigen::Vector3f& y = two->organized.points[p];
        EXPECT_TRUE(x == y || (!x.allFinite() && !y.allFinite()));
    }
}

TEST(RecoverImageGrid, NothingForCloudsThatAreNotOneDepthImage) {
    const PointCloud frame = PinholeCloud(80, 60, 70.0f, 7);
    Indices order;
    PointCloud flat = DropGrid(frame, 3, order);
    ASSERT_TRUE(RecoverImageGrid(flat).has_value());
    EXPECT_FALSE(RecoverImageGrid(frame).has_value());         // organized already
    EXPECT_FALSE(RecoverImageGrid(PointCloud{}).has_value());  // empty
    PointCloud world = flat;                                   // in a world frame
    world.sensor_origin = {0.0f, 0.0f, 1.5f};
    EXPECT_FALSE(RecoverImageGrid(world).has_value());
    PointCloud jittered = flat;  // filtered or merged: off the lattice
    std::mt19937 rng(4);
    std::normal_distribution<float> noise(0.0f, 0.003f);
    for (auto& p : jittered.points) p += Eigen::Vector3f(noise(rng), noise(rng), 0.0f);
    EXPECT_FALSE(RecoverImageGrid(jittered).has_value());
    PointCloud doubled = flat;  // two points on one pixel
    doubled.points.push_back(flat.points.front() * 1.1f);
    doubled.SetUnorganized();
    EXPECT_FALSE(RecoverImageGrid(doubled).has_value());
    EXPECT_FALSE(RecoverImageGrid(test::RandomCloud(2000, 1)).has_value());
}

}  // namespace
}  // namespace multicue

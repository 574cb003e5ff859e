#include <limits>

#include <gtest/gtest.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/core/logging.hpp"
#include "multicue/core/parallel.hpp"
#include "multicue/core/point_cloud.hpp"
#include "multicue/core/progress.hpp"
#include "multicue/core/task_order.hpp"
#include "multicue/core/triangle_mesh.hpp"
#include "test_util.hpp"

namespace multicue {
namespace {

TEST(Color, PackMatchesPclLayout) {
    const Color c{10, 20, 30, 255};
    EXPECT_EQ(PackRgba(c), 0xff0a141eu);
    EXPECT_EQ(UnpackRgba(0xff0a141eu), c);
}

TEST(PointCloud, HasChecksAndOrganization) {
    PointCloud c;
    EXPECT_TRUE(c.empty());
    EXPECT_FALSE(c.HasNormals());
    c.points.assign(6, Eigen::Vector3f::Zero());
    c.width = 3;
    c.height = 2;
    EXPECT_TRUE(c.IsOrganized());
    c.colors.resize(6);
    EXPECT_TRUE(c.HasColors());
    EXPECT_NO_THROW(c.Validate());
    c.normals.resize(5);
    EXPECT_THROW(c.Validate(), DataError);
    c.normals.resize(6);
    c.width = 4;
    EXPECT_THROW(c.Validate(), DataError);
}

TEST(PointCloud, CountFiniteAndBounds) {
    PointCloud c({{0, 0, 0}, {1, 2, 3}, {std::numeric_limits<float>::quiet_NaN(), 0, 0}});
    EXPECT_EQ(c.CountFinite(), 2u);
    EXPECT_TRUE(c.HasFinite());
    EXPECT_FALSE(PointCloud{}.HasFinite());
    const float nan = std::numeric_limits<float>::quiet_NaN();
    EXPECT_FALSE(
        PointCloud({{nan, 0, 0}, {0, std::numeric_limits<float>::infinity(), 0}}).HasFinite());
    Eigen::Vector3f lo, hi;
    ASSERT_TRUE(ComputeBounds(c, lo, hi));
    EXPECT_EQ(lo, Eigen::Vector3f(0, 0, 0));
    EXPECT_EQ(hi, Eigen::Vector3f(1, 2, 3));
    EXPECT_FALSE(ComputeBounds(PointCloud{}, lo, hi));
}

TEST(PointCloud, SelectByIndexCarriesAllFields) {
    PointCloud c({{0, 0, 0}, {1, 0, 0}, {2, 0, 0}});
    c.labels = {7, 8, 9};
    c.intensity = {0.1f, 0.2f, 0.3f};
    ExtraField f{"ring", 'U', 2, 1, {}};
    f.data = {1, 0, 2, 0, 3, 0};
    c.extra_fields.push_back(f);
    c.sensor_origin = {1, 2, 3};
    const PointCloud s = SelectByIndex(c, {2, 0});
    ASSERT_EQ(s.size(), 2u);
    EXPECT_EQ(s.points[0].x(), 2.0f);
    EXPECT_EQ(s.labels, (std::vector<std::uint32_t>{9, 7}));
    EXPECT_FLOAT_EQ(s.intensity[1], 0.1f);
    ASSERT_EQ(s.extra_fields.size(), 1u);
    EXPECT_EQ(s.extra_fields[0].data, (std::vector<std::uint8_t>{3, 0, 1, 0}));
    EXPECT_EQ(s.sensor_origin, c.sensor_origin);
    EXPECT_NO_THROW(s.Validate());
    EXPECT_THROW(SelectByIndex(c, {3}), InvalidArgument);
    EXPECT_TRUE(SelectByIndex(c, {}).empty());
}

TEST(TriangleMesh, ValidateNormalsAppend) {
    TriangleMesh m;
    m.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    m.triangles = {Triangle(0, 1, 2)};
    EXPECT_NO_THROW(m.Validate());
    const auto n = m.ComputeTriangleNormals();
    EXPECT_NEAR(n[0].z(), 1.0f, 1e-6f);
    TriangleMesh m2 = m;
    m2.Append(m);
    EXPECT_EQ(m2.vertices.size(), 6u);
    EXPECT_EQ(m2.triangles[1], Triangle(3, 4, 5));
    m.triangles.push_back(Triangle(0, 1, 3));
    EXPECT_THROW(m.Validate(), DataError);
}

TEST(Parallel, SerialAndParallelAgree) {
    std::vector<double> a(100000), b(100000);
    ParallelFor(a.size(), 1, [&](std::size_t i) { a[i] = std::sqrt(static_cast<double>(i)); });
    ParallelFor(b.size(), 0, [&](std::size_t i) { b[i] = std::sqrt(static_cast<double>(i)); });
    EXPECT_EQ(a, b);
    EXPECT_THROW(ResolveThreadCount(-1), InvalidArgument);
    EXPECT_GE(ResolveThreadCount(0), 1);
    EXPECT_EQ(ResolveThreadCount(3), 3);
}

TEST(Parallel, MoreThreadsThanCoresIsQuietAndGivesTheSameResult) {
    EXPECT_EQ(ArenaThreadCount(1), 1);
    EXPECT_LE(ArenaThreadCount(1000), ResolveThreadCount(0));
    std::vector<double> a(100000), b(100000);
    ParallelFor(a.size(), 1, [&](std::size_t i) { a[i] = std::sqrt(static_cast<double>(i)); });
    ::testing::internal::CaptureStderr();
    ParallelFor(b.size(), 64, [&](std::size_t i) { b[i] = std::sqrt(static_cast<double>(i)); });
    EXPECT_EQ(::testing::internal::GetCapturedStderr(), "");
    EXPECT_EQ(a, b);
}

// ParallelSelect keeps the indices in ascending order whatever the thread count and block size.
TEST(Parallel, SelectKeepsTheSerialOrder) {
    const auto keep = [](std::size_t i) { return (i * 2654435761u) % 7 < 3; };
    Indices serial;
    for (std::size_t i = 0; i < 100003; ++i) {
        if (keep(i)) serial.push_back(static_cast<Index>(i));
    }
    for (const int threads : {1, 2, 0}) {
        for (const std::size_t grain : {std::size_t{1}, std::size_t{1000}, std::size_t{1 << 20}}) {
            EXPECT_EQ(ParallelSelect(100003, threads, keep, grain), serial);
        }
    }
    EXPECT_TRUE(ParallelSelect(0, 2, keep).empty());
    EXPECT_TRUE(ParallelSelect(1000, 2, [](std::size_t) { return false; }).empty());
}

TEST(Parallel, InvokeRunsBothAndOneAfterTheOtherOnOneThread) {
    for (const int threads : {1, 2}) {
        std::vector<int> order;
        std::vector<double> a(50000), b(50000);
        ParallelInvoke(
            threads,
            [&] {
                if (threads == 1) order.push_back(1);
                ParallelFor(a.size(), threads, [&](std::size_t i) { a[i] = 2.0 * i; });
            },
            [&] {
                if (threads == 1) order.push_back(2);
                ParallelFor(b.size(), threads, [&](std::size_t i) { b[i] = 3.0 * i; });
            });
        EXPECT_EQ(a[49999], 2.0 * 49999);
        EXPECT_EQ(b[49999], 3.0 * 49999);
        if (threads == 1) {
            EXPECT_EQ(order, (std::vector<int>{1, 2}));
        }
    }
    EXPECT_THROW(ParallelInvoke(
                     2, [] {}, [] { throw DataError("second"); }),
                 DataError);
}

TEST(Parallel, LargestFirstOrdersBySizeThenPosition) {
    const std::vector<std::size_t> sizes = {3, 9, 3, 0, 9, 5};
    const auto size = [&](std::size_t k) { return sizes[k]; };
    EXPECT_EQ(LargestFirst(sizes.size(), size), (std::vector<std::size_t>{1, 4, 5, 0, 2, 3}));
    EXPECT_TRUE(LargestFirst(0, size).empty());
}

// Loops nested in a parallel loop (objects in parallel, each with loops of its own) run in the
// outer loop's threads, isolated: a thread-local buffer used around an inner loop is never taken
// over by another outer task meanwhile, and the results are the serial ones.
TEST(Parallel, NestedLoopsAgreeWithSerialOnesAndKeepTheirThreadLocals) {
    constexpr std::size_t kOuter = 16, kInner = 20000;
    std::vector<double> serial(kOuter * kInner), nested(kOuter * kInner);
    auto run = [&](int threads, std::vector<double>& out, bool& intact) {
        ParallelFor(
            kOuter, threads,
            [&](std::size_t o) {
                thread_local std::size_t owner = 0;
                owner = o;
                ParallelFor(
                    kInner, threads,
                    [&](std::size_t i) { out[o * kInner + i] = std::sqrt(double(o * kInner + i)); },
                    256);
                if (owner != o) intact = false;
            },
            1);
    };
    bool intact = true;
    run(1, serial, intact);
    run(2, nested, intact);
    EXPECT_EQ(serial, nested);
    EXPECT_TRUE(intact);
}

TEST(Logging, LevelsAndSink) {
    std::vector<std::string> seen;
    SetLogSink([&](LogLevel, std::string_view m) { seen.emplace_back(m); });
    SetLogLevel(LogLevel::kInfo);
    LogDebug("hidden {}", 1);
    LogInfo("shown {}", 2);
    LogWarning("warn");
    SetLogSink({});
    SetLogLevel(LogLevel::kWarning);
    EXPECT_EQ(seen, (std::vector<std::string>{"shown 2", "warn"}));
    EXPECT_EQ(ParseLogLevel("debug"), LogLevel::kDebug);
    EXPECT_THROW(ParseLogLevel("loud"), InvalidArgument);
}

}  // namespace
}  // namespace multicue

TEST(Progress, CountsFromSeveralThreadsAndStaysSilentByDefault) {
    multicue::Progress progress;
    multicue::ParallelFor(
        1000, 0, [&](std::size_t) { progress.Advance(); }, 16);
    EXPECT_EQ(progress.done(), 1000u);
}

TEST(Progress, InterruptFlagCanBeSetAndCleared) {
    multicue::RequestInterrupt(true);
    EXPECT_TRUE(multicue::InterruptRequested());
    multicue::RequestInterrupt(false);
    EXPECT_FALSE(multicue::InterruptRequested());
}

// Feature-based initial alignment: descriptor matching against brute force, length pruning,
// RANSAC on matches with outliers, FPFH alignment from a large rotation, RGB keypoints of
// textured organized frames, bad parameters, determinism.

#include <cmath>
#include <limits>
#include <random>

#include <gtest/gtest.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/registration/feature_alignment.hpp"
#include "multicue/registration/icp.hpp"
#include "multicue/registration/preprocess.hpp"
#include "multicue/registration/rgb_keypoints.hpp"
#include "registration_scenes.hpp"
#include "test_util.hpp"

namespace multicue {
namespace {

using test::MakeTransform;
using test::RotationErrorDeg;
using test::TranslationError;

TEST(FeatureMatching, EqualsBruteForce) {
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    FeatureMatrix a(300, 33), b(250, 33);
    for (Eigen::Index i = 0; i < a.size(); ++i) a.data()[i] = u(rng);
    for (Eigen::Index i = 0; i < b.size(); ++i) b.data()[i] = u(rng);
    a.row(7).setConstant(std::numeric_limits<float>::quiet_NaN());
    auto nearest = [](const FeatureMatrix& x, const FeatureMatrix& y, Eigen::Index i) {
        Eigen::Index best = -1;
        float bd = std::numeric_limits<float>::infinity();
        for (Eigen::Index j = 0; j < y.rows(); ++j) {
            if (!y.row(j).allFinite()) continue;
            const float d = (x.row(i) - y.row(j)).squaredNorm();
            if (d < bd) {
                bd = d;
                best = j;
            }
        }
        return best;
    };
    const auto m = MatchFeatureRows(a, b, {.mutual = true, .ratio = 1.0f});
    std::size_t expected = 0;
    for (Eigen::Index i = 0; i < a.rows(); ++i) {
        if (!a.row(i).allFinite()) continue;
        const auto j = nearest(a, b, i);
        if (nearest(b, a, j) == i) ++expected;
    }
    EXPECT_EQ(m.size(), expected);
    for (std::size_t k = 0; k < m.size(); ++k) {
        EXPECT_EQ(static_cast<Eigen::Index>(m.target[k]), nearest(a, b, m.source[k]));
        EXPECT_NE(m.source[k], 7u);
    }
    EXPECT_THROW(MatchFeatureRows(a, FeatureMatrix(3, 5), {}), InvalidArgument);
    EXPECT_THROW(MatchFeatureRows(a, b, {.ratio = 0.0f}), InvalidArgument);
}

// 400 matches of which 60 % are wrong.
struct Matches {
    PointCloud source, target;
    PointMatches matches;
    Eigen::Isometry3d T;
};
Matches SyntheticMatches() {
    Matches s;
    s.T = MakeTransform(40.0, {0.3, -0.2, 0.5});
    s.source = test::RandomCloud(400, 5, 0.5f);
    s.target = test::Transformed(s.source, s.T);
    std::mt19937 rng(6);
    std::normal_distribution<float> noise(0.0f, 0.003f);
    for (auto& p : s.target.points) p += Eigen::Vector3f(noise(rng), noise(rng), noise(rng));
    std::uniform_int_distribution<Index> any(0, 399);
    for (Index i = 0; i < 400; ++i) {
        s.matches.source.push_back(i);
        s.matches.target.push_back(i % 5 < 2 ? i : any(rng));
    }
    return s;
}

TEST(Ransac, RecoversTheTransformDespiteOutliers) {
    const Matches s = SyntheticMatches();
    const auto r = AlignMatchesRansac(s.source, s.target, s.matches, {.num_threads = 1});
    EXPECT_TRUE(r.converged) << r.reason;
    EXPECT_LT(RotationErrorDeg(r.T_target_source, s.T), 0.5);
    EXPECT_LT(TranslationError(r.T_target_source, s.T), 0.005);
    EXPECT_GE(r.correspondences, 155u);  // the 160 correct matches, a few lost to noise at most
    EXPECT_LT(r.correspondences, 200u);
    // Early exit: far fewer samples than the cap.
    EXPECT_LT(r.iterations, 2000);
    // Same samples, same result with any thread count.
    const auto many = AlignMatchesRansac(s.source, s.target, s.matches, {.num_threads = 0});
    EXPECT_EQ(r.T_target_source.matrix(), many.T_target_source.matrix());
    EXPECT_EQ(r.iterations, many.iterations);
}

TEST(Ransac, NoAgreementIsFlagged) {
    Matches s = SyntheticMatches();
    std::mt19937 rng(2);
    std::uniform_int_distribution<Index> any(0, 399);
    for (auto& t : s.matches.target) t = any(rng);
    const auto r = AlignMatchesRansac(s.source, s.target, s.matches,
                                      {.max_iterations = 500, .min_inliers = 20});
    EXPECT_FALSE(r.converged);
    EXPECT_EQ(r.status, RegistrationStatus::kNoHypothesis) << r.reason;
    EXPECT_EQ(AlignMatchesRansac(s.source, s.target, PointMatches{}, {}).status,
              RegistrationStatus::kEmptyInput);
    EXPECT_THROW(AlignMatchesRansac(s.source, s.target, s.matches, {.max_iterations = 0}),
                 InvalidArgument);
    EXPECT_THROW(AlignMatchesRansac(s.source, s.target, s.matches, {.inlier_distance = -1.0f}),
                 InvalidArgument);
    PointMatches bad;
    bad.source = {0, 1, 5000};
    bad.target = {0, 1, 2};
    EXPECT_THROW(AlignMatchesRansac(s.source, s.target, bad, {}), InvalidArgument);
}

TEST(LengthPruning, KeepsTheConsistentMatches) {
    const Matches s = SyntheticMatches();
    const auto kept = PruneByLengthConsistency(s.source, s.target, s.matches,
                                               {.keep_fraction = 0.4f, .min_keep = 10});
    ASSERT_EQ(kept.size(), 160u);
    std::size_t correct = 0;
    for (std::size_t k : kept) correct += s.matches.source[k] == s.matches.target[k];
    EXPECT_GT(correct, 150u);
    EXPECT_THROW(PruneByLengthConsistency(s.source, s.target, s.matches, {.keep_fraction = 0.0f}),
                 InvalidArgument);
}

TEST(FpfhAlignment, RecoversALargeRotationThenIcpRefines) {
    const auto T = MakeTransform(60.0, {0.3, 0.2, -0.1});
    const PreprocessParams pre{.voxel_size = 0.01f, .num_threads = 1};
    const PointCloud a = PreprocessForRegistration(test::TableWithBoxes(0.001f, 1), pre);
    const PointCloud b =
        PreprocessForRegistration(test::Transformed(test::TableWithBoxes(0.001f, 2), T), pre);
    const KdTree ta(a), tb(b);
    FpfhAlignParams params;
    params.num_threads = 1;
    const auto coarse = AlignFpfh(a, ta, b, tb, params);
    ASSERT_TRUE(coarse.converged) << coarse.reason;
    EXPECT_LT(RotationErrorDeg(coarse.T_target_source, T), 5.0);
    EXPECT_LT(TranslationError(coarse.T_target_source, T), 0.05);
    IcpParams icp;
    icp.initial_max_distance = 0.1f;
    const auto fine = RegisterIcp(a, b, &tb, icp, coarse.T_target_source);
    EXPECT_TRUE(fine.converged) << fine.reason;
    EXPECT_LT(RotationErrorDeg(fine.T_target_source, T), 0.3);
    EXPECT_LT(TranslationError(fine.T_target_source, T), 0.003);
    params.num_threads = 2;
    const auto again = AlignFpfh(a, ta, b, tb, params);
    EXPECT_EQ(coarse.T_target_source.matrix(), again.T_target_source.matrix());
}

// An organized frame of a textured wall (plane z = 2 in the world, smooth random blobs of grey)
// seen by a pinhole camera at T_world_camera (sensor at the origin of the frame).
PointCloud TexturedWall(const Eigen::Isometry3d& T_world_camera) {
    const int w = 320, h = 240;
    const double f = 300.0;
    PointCloud c;
    c.width = w;
    c.height = h;
    c.points.resize(static_cast<std::size_t>(w) * h);
    c.colors.resize(c.points.size());
    // Random grey levels on square cells of three sizes: unique corners everywhere.
    auto texture = [](double x, double y) {
        double v = 0.0;
        for (const double cell : {0.11, 0.05, 0.023}) {
            const auto i = static_cast<std::int64_t>(std::floor(x / cell));
            const auto j = static_cast<std::int64_t>(std::floor(y / cell));
            std::uint64_t hsh =
                static_cast<std::uint64_t>(i * 73856093 ^ j * 19349663) * 0x9E3779B97F4A7C15ull;
            hsh ^= hsh >> 29;
            v += static_cast<double>(hsh % 1000) / 1000.0 - 0.5;
        }
        return v;
    };
    for (int v = 0; v < h; ++v) {
        for (int u = 0; u < w; ++u) {
            const Eigen::Vector3d ray((u - w / 2.0) / f, (v - h / 2.0) / f, 1.0);
            const Eigen::Vector3d o = T_world_camera.translation();
            const Eigen::Vector3d d = T_world_camera.linear() * ray;
            const double t = (2.0 - o.z()) / d.z();
            const Eigen::Vector3d hit = o + t * d;
            const std::size_t i = static_cast<std::size_t>(v) * w + static_cast<std::size_t>(u);
            c.points[i] = (t * ray).cast<float>();
            const auto g = static_cast<std::uint8_t>(
                std::clamp(128.0 + 60.0 * texture(hit.x(), hit.y()), 0.0, 255.0));
            c.colors[i] = Color{g, g, g, 255};
        }
    }
    return c;
}

TEST(RgbKeypoints, OrbAndSiftMatchesAlignTexturedFrames) {
    Eigen::Isometry3d A = Eigen::Isometry3d::Identity();
    Eigen::Isometry3d B = MakeTransform(6.0, {0.15, -0.05, 0.1});
    const PointCloud a = TexturedWall(A);
    const PointCloud b = TexturedWall(B);
    const Eigen::Isometry3d T_true = B.inverse() * A;  // a's frame -> b's frame
    for (const auto detector : {KeypointDetector::kOrb, KeypointDetector::kSift}) {
        SCOPED_TRACE(KeypointDetectorName(detector));
        const auto m = MatchRgbKeypoints(a, b, {.detector = detector});
        EXPECT_GT(m.size(), 30u);
        const auto r = AlignMatchesRansac(a, b, m, {.inlier_distance = 0.01f, .num_threads = 1});
        EXPECT_TRUE(r.converged) << r.reason;
        EXPECT_LT(RotationErrorDeg(r.T_target_source, T_true), 1.0);
        EXPECT_LT(TranslationError(r.T_target_source, T_true), 0.02);
    }
    PointCloud plain = a;
    plain.colors.clear();
    EXPECT_THROW(MatchRgbKeypoints(plain, b, {}), InvalidArgument);
    EXPECT_THROW(MatchRgbKeypoints(test::RandomCloud(10), b, {}), InvalidArgument);
    EXPECT_THROW(MatchRgbKeypoints(a, b, {.max_keypoints = 1}), InvalidArgument);
    EXPECT_THROW(ParseKeypointDetector("surf"), InvalidArgument);
    // No texture, no matches.
    PointCloud flat = a;
    for (auto& col : flat.colors) col = Color{128, 128, 128, 255};
    EXPECT_TRUE(MatchRgbKeypoints(flat, flat, {}).empty());
}

}  // namespace
}  // namespace multicue

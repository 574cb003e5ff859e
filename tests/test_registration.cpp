// ICP variants: recovery of known transforms from noisy synthetic scenes, the closed-form rigid
// fit against exact pairs, degenerate and empty input flagged, bad parameters, determinism.

#include <cmath>
#include <limits>
#include <numeric>
#include <random>

#include <gtest/gtest.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/core/params.hpp"
#include "multicue/registration/correspondences.hpp"
#include "multicue/registration/icp.hpp"
#include "multicue/registration/preprocess.hpp"
#include "multicue/registration/register.hpp"
#include "multicue/registration/registration_result.hpp"
#include "multicue/sim/rng.hpp"
#include "multicue/sim/scene_gen.hpp"
#include "multicue/sim/sensors.hpp"
#include "registration_scenes.hpp"

namespace multicue {
namespace {

using test::MakeTransform;
using test::RotationErrorDeg;
using test::TranslationError;

PointCloud Prepared(const PointCloud& c, float voxel = 0.01f) {
    return PreprocessForRegistration(c, {.voxel_size = voxel, .num_threads = 1});
}

struct Pair {
    PointCloud source;
    PointCloud target;
    Eigen::Isometry3d T_true;
};

// Two independent noisy samples of the same table scene; the target moved by T_true.
Pair TablePair(double angle_deg, const Eigen::Vector3d& t, float sigma = 0.002f) {
    Pair p;
    p.T_true = MakeTransform(angle_deg, t);
    p.source = Prepared(test::TableWithBoxes(sigma, 1));
    p.target = Prepared(test::Transformed(test::TableWithBoxes(sigma, 2), p.T_true));
    return p;
}

TEST(RigidFit, RecoversExactTransformFromPairs) {
    const auto T = MakeTransform(33.0, {0.4, -1.2, 2.0});
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    std::vector<Eigen::Vector3d> a, b;
    for (int i = 0; i < 50; ++i) {
        a.emplace_back(u(rng), u(rng), u(rng));
        b.push_back(T * a.back());
    }
    Eigen::Isometry3d fit;
    ASSERT_TRUE(FitRigidTransform(a, b, {}, fit));
    EXPECT_LT((fit.matrix() - T.matrix()).cwiseAbs().maxCoeff(), 1e-9);
    // Collinear points leave a rotation free: refused.
    std::vector<Eigen::Vector3d> line, moved;
    for (int i = 0; i < 10; ++i) {
        line.emplace_back(i, 2.0 * i, 0.0);
        moved.push_back(T * line.back());
    }
    EXPECT_FALSE(FitRigidTransform(line, moved, {}, fit));
}

TEST(Icp, EveryMethodRecoversAKnownTransform) {
    const Pair p = TablePair(5.0, {0.04, -0.03, 0.02});
    for (const auto method :
         {IcpMethod::kPointToPoint, IcpMethod::kPointToPlane, IcpMethod::kSymmetric}) {
        IcpParams params;
        params.method = method;
        params.correspondences.max_distance = 0.03f;
        params.initial_max_distance = 0.15f;
        // Point-to-point slides along the table plane slowly: it needs many more iterations.
        params.max_iterations = method == IcpMethod::kPointToPoint ? 400 : 50;
        const auto r = RegisterIcp(p.source, p.target, params);
        SCOPED_TRACE(IcpMethodName(method));
        EXPECT_TRUE(r.converged) << r.reason;
        EXPECT_EQ(r.status, RegistrationStatus::kConverged);
        EXPECT_LT(RotationErrorDeg(r.T_target_source, p.T_true), 0.3);
        EXPECT_LT(TranslationError(r.T_target_source, p.T_true), 0.003);
        EXPECT_GT(r.fitness, 0.9);
        EXPECT_LT(r.inlier_rmse, 0.012);  // nearest-point distances on a 1 cm grid
        EXPECT_GT(r.constraints.condition, params.min_condition);
    }
}

TEST(Icp, RobustKernelsResistOutliers) {
    Pair p = TablePair(3.0, {0.02, 0.01, -0.02});
    // 30 % of the source replaced by clutter that exists only in the source.
    std::mt19937 rng(9);
    std::uniform_real_distribution<float> u(-0.6f, 0.6f);
    for (std::size_t i = 0; i < p.source.size(); i += 3) {
        p.source.points[i] = {u(rng), u(rng), 0.05f + 0.1f * std::abs(u(rng))};
    }
    for (const auto kernel :
         {RobustKernelType::kHuber, RobustKernelType::kTukey, RobustKernelType::kCauchy}) {
        IcpParams params;
        params.kernel = kernel;
        params.correspondences.max_distance = 0.03f;
        params.initial_max_distance = 0.1f;
        params.kernel_scale = 0.01f;
        params.max_iterations = 100;
        const auto r = RegisterIcp(p.source, p.target, params);
        SCOPED_TRACE(RobustKernelName(kernel));
        EXPECT_LT(RotationErrorDeg(r.T_target_source, p.T_true), 0.5);
        EXPECT_LT(TranslationError(r.T_target_source, p.T_true), 0.005);
    }
    EXPECT_EQ(RobustWeight(RobustKernelType::kTukey, 2.0, 1.0), 0.0);
    EXPECT_DOUBLE_EQ(RobustWeight(RobustKernelType::kHuber, 4.0, 1.0), 0.25);
    EXPECT_DOUBLE_EQ(RobustWeight(RobustKernelType::kCauchy, 1.0, 1.0), 0.5);
    EXPECT_DOUBLE_EQ(RobustWeight(RobustKernelType::kNone, 100.0, 1.0), 1.0);
}

TEST(Icp, OnePlaneIsDegenerate) {
    const auto T = MakeTransform(2.0, {0.03, 0.02, 0.01});
    const auto source = Prepared(test::SinglePlane(0.002f, 1), 0.02f);
    const auto target = Prepared(test::Transformed(test::SinglePlane(0.002f, 2), T), 0.02f);
    const auto r = RegisterIcp(source, target, IcpParams{});
    EXPECT_FALSE(r.converged);
    EXPECT_EQ(r.status, RegistrationStatus::kDegenerate) << r.reason;
    EXPECT_LT(r.constraints.condition, 1e-3);
}

TEST(Icp, CorridorIsDegenerateAlongItsAxis) {
    const auto T = MakeTransform(1.0, {0.02, 0.01, 0.0});
    const auto source = Prepared(test::Corridor(0.002f, 1), 0.03f);
    const auto target = Prepared(test::Transformed(test::Corridor(0.002f, 2), T), 0.03f);
    IcpParams params;
    params.correspondences.max_distance = 0.1f;
    const auto r = RegisterIcp(source, target, params);
    EXPECT_FALSE(r.converged);
    EXPECT_EQ(r.status, RegistrationStatus::kDegenerate) << r.reason;
    // The free motion is the translation along x.
    const Vector6d& d = r.constraints.weakest_direction;
    EXPECT_GT(std::abs(d(3)), 0.9) << d.transpose();
}

TEST(Icp, NoOverlapIsFlagged) {
    const Pair p = TablePair(0.0, {2.0, 0.0, 0.0});
    const auto r = RegisterIcp(p.source, p.target, IcpParams{});
    EXPECT_FALSE(r.converged);
    EXPECT_EQ(r.status, RegistrationStatus::kTooFewCorrespondences) << r.reason;
    // Half of the source outside the target: low overlap.
    Pair half = TablePair(0.0, {0.0, 0.0, 0.0});
    PointCloud cut;
    for (std::size_t i = 0; i < half.target.size(); ++i) {
        if (half.target.points[i].x() < -0.35f) {
            cut.points.push_back(half.target.points[i]);
            cut.normals.push_back(half.target.normals[i]);
        }
    }
    cut.SetUnorganized();
    IcpParams params;
    params.min_fitness = 0.5;
    const auto low = RegisterIcp(half.source, cut, params);
    EXPECT_FALSE(low.converged);
    EXPECT_EQ(low.status, RegistrationStatus::kLowOverlap) << low.reason;
}

TEST(Icp, EmptyAndNanOnlyInput) {
    const auto target = Prepared(test::TableWithBoxes(0.002f, 1));
    PointCloud empty;
    const auto r = RegisterIcp(empty, target, IcpParams{});
    EXPECT_FALSE(r.converged);
    EXPECT_EQ(r.status, RegistrationStatus::kEmptyInput);
    PointCloud nan_only(std::vector<Eigen::Vector3f>(
        100, Eigen::Vector3f::Constant(std::numeric_limits<float>::quiet_NaN())));
    EXPECT_EQ(RegisterIcp(nan_only, target, IcpParams{}).status, RegistrationStatus::kEmptyInput);
    EXPECT_EQ(RegisterIcp(target, nan_only, IcpParams{.method = IcpMethod::kPointToPoint}).status,
              RegistrationStatus::kEmptyInput);
    EXPECT_TRUE(PreprocessForRegistration(nan_only, {}).empty());
}

TEST(Icp, BadParametersAndInputThrow) {
    const auto cloud = Prepared(test::TableWithBoxes(0.002f, 1));
    auto bad = [&](auto set) {
        IcpParams p;
        set(p);
        return [&cloud, p] { RegisterIcp(cloud, cloud, p); };
    };
    EXPECT_THROW(bad([](IcpParams& p) { p.correspondences.max_distance = 0; })(), InvalidArgument);
    EXPECT_THROW(bad([](IcpParams& p) { p.correspondences.max_normal_angle_deg = 0; })(),
                 InvalidArgument);
    EXPECT_THROW(bad([](IcpParams& p) { p.max_iterations = 0; })(), InvalidArgument);
    EXPECT_THROW(bad([](IcpParams& p) { p.gate_decay = 1.5f; })(), InvalidArgument);
    EXPECT_THROW(bad([](IcpParams& p) { p.min_fitness = 2.0; })(), InvalidArgument);
    EXPECT_THROW(bad([](IcpParams& p) { p.min_condition = -1.0; })(), InvalidArgument);
    EXPECT_THROW(bad([](IcpParams& p) { p.num_threads = -2; })(), InvalidArgument);
    EXPECT_THROW(bad([](IcpParams& p) { p.kernel_scale = -1.0f; })(), InvalidArgument);
    EXPECT_THROW(
        bad([](IcpParams& p) { p.correspondences.search = CorrespondenceSearch::kProjective; })(),
        InvalidArgument);
    PointCloud no_normals = cloud;
    no_normals.normals.clear();
    EXPECT_THROW(RegisterIcp(cloud, no_normals, IcpParams{}), DataError);
    EXPECT_THROW(RegisterIcp(no_normals, cloud, IcpParams{.method = IcpMethod::kSymmetric}),
                 DataError);
    Eigen::Isometry3d nan_init = Eigen::Isometry3d::Identity();
    nan_init(0, 3) = std::numeric_limits<double>::quiet_NaN();
    EXPECT_THROW(RegisterIcp(cloud, cloud, IcpParams{}, nan_init), InvalidArgument);
    EXPECT_THROW(ParseIcpMethod("plane-to-moon"), InvalidArgument);
    EXPECT_THROW(ParseRobustKernel("gauss"), InvalidArgument);
    EXPECT_THROW(PreprocessForRegistration(cloud, {.voxel_size = -1.0f}), InvalidArgument);
}

TEST(Icp, SameResultForAnyThreadCount) {
    const Pair p = TablePair(4.0, {0.03, 0.02, -0.01});
    for (const auto method : {IcpMethod::kPointToPoint, IcpMethod::kPointToPlane}) {
        IcpParams params;
        params.method = method;
        params.initial_max_distance = 0.1f;
        params.num_threads = 1;
        const auto one = RegisterIcp(p.source, p.target, params);
        for (int threads : {2, 0}) {
            params.num_threads = threads;
            const auto many = RegisterIcp(p.source, p.target, params);
            EXPECT_EQ(one.T_target_source.matrix(), many.T_target_source.matrix());
            EXPECT_EQ(one.iterations, many.iterations);
            EXPECT_EQ(one.inlier_rmse, many.inlier_rmse);
        }
    }
}

// The correspondence cache of an ICP loop skips searches but never changes a pair: over a
// converging sequence of estimates (large steps, then ever smaller ones, gates shrinking), Find
// with one cache gives exactly the pairs of Find without it. Duplicated target points make ties.
TEST(Icp, CachedCorrespondencesEqualFreshSearches) {
    const Pair p = TablePair(4.0, {0.03, 0.02, -0.01});
    PointCloud target = p.target;
    for (std::size_t i = 0; i < target.size(); i += 7) {
        target.points.push_back(target.points[i]);
        target.normals.push_back(target.normals[i]);
    }
    target.width = static_cast<std::uint32_t>(target.points.size());
    const KdTree tree(target);
    const CorrespondenceSearcher searcher(target, &tree, {.max_distance = 0.02f});
    Indices subset(p.source.size());
    std::iota(subset.begin(), subset.end(), Index{0});
    NearestCache cache;
    std::vector<Correspondence> cached, fresh;
    std::size_t pairs = 0;
    for (int step = 0; step < 30; ++step) {
        // Estimates approach the truth geometrically, with a jump back at step 12.
        const double scale = step == 12 ? 1.0 : std::pow(0.6, step % 12);
        const Eigen::Isometry3d T =
            p.T_true * MakeTransform(5.0 * scale, Eigen::Vector3d(0.04, -0.03, 0.02) * scale);
        const float gate = step < 5 ? 0.08f - 0.012f * static_cast<float>(step) : 0.02f;
        searcher.Find(p.source, subset, T, gate, cached, 1, &cache);
        searcher.Find(p.source, subset, T, gate, fresh, 1);
        ASSERT_EQ(cached.size(), fresh.size()) << "step " << step;
        for (std::size_t k = 0; k < fresh.size(); ++k) {
            ASSERT_EQ(cached[k].source, fresh[k].source);
            ASSERT_EQ(cached[k].target, fresh[k].target) << "step " << step;
            ASSERT_EQ(cached[k].squared_distance, fresh[k].squared_distance);
        }
        pairs += fresh.size();
    }
    EXPECT_GT(pairs, 30 * p.source.size() / 2);
    // A cache sized for another subset is reset, not misread.
    Indices half(subset.begin(), subset.begin() + static_cast<std::ptrdiff_t>(subset.size() / 2));
    searcher.Find(p.source, half, p.T_true, 0.02f, cached, 1, &cache);
    searcher.Find(p.source, half, p.T_true, 0.02f, fresh, 1);
    EXPECT_EQ(cache.entries.size(), half.size());
    ASSERT_EQ(cached.size(), fresh.size());
    for (std::size_t k = 0; k < fresh.size(); ++k) EXPECT_EQ(cached[k].target, fresh[k].target);
    // The target registered to itself: a query on a duplicated point has both old partners at
    // distance 0, and a second search from the same pose must not bound itself to radius 0.
    Indices all(target.size());
    std::iota(all.begin(), all.end(), Index{0});
    NearestCache self;
    for (int repeat = 0; repeat < 2; ++repeat) {
        ASSERT_NO_THROW(
            searcher.Find(target, all, Eigen::Isometry3d::Identity(), 0.02f, cached, 1, &self));
        searcher.Find(target, all, Eigen::Isometry3d::Identity(), 0.02f, fresh, 1);
        ASSERT_EQ(cached.size(), fresh.size());
        for (std::size_t k = 0; k < fresh.size(); ++k) {
            EXPECT_EQ(cached[k].target, fresh[k].target);
            EXPECT_EQ(cached[k].squared_distance, 0.0f);
        }
    }
}

// Two simulated Kinect frames of one table scene: the projective fast path on the organized
// target and the k-d tree path both recover the true relative pose.
TEST(Icp, ProjectiveAndTreeCorrespondencesOnKinectFrames) {
    sim::TableSceneParams table;
    table.mode = sim::TableSceneMode::kBoxes;
    table.min_objects = table.max_objects = 4;
    const sim::Scene scene = sim::MakeTableScene(table, 11);
    const auto views = sim::TableViewpoints(scene, 24, {}, 11);
    const sim::RayCaster caster(scene);
    sim::KinectParams kinect;
    kinect.num_threads = 1;
    const PointCloud a = sim::ScanKinect(caster, views[0], kinect, 1);
    const PointCloud b = sim::ScanKinect(caster, views[1], kinect, 2);
    const Eigen::Isometry3d T_true = (views[1].inverse() * views[0]).cast<double>();  // a -> b
    const PointCloud source = Prepared(a, 0.01f);
    const PointCloud target_frame =
        PreprocessForRegistration(b, {.keep_organized = true, .num_threads = 1});
    const PointCloud target_down = Prepared(b, 0.01f);
    const Eigen::Isometry3d init = MakeTransform(3.0, {0.03, -0.02, 0.02}) * T_true;
    for (const auto search : {CorrespondenceSearch::kProjective, CorrespondenceSearch::kKdTree}) {
        IcpParams params;
        params.correspondences.search = search;
        params.initial_max_distance = 0.15f;
        params.depth_noise = 1.4e-3f;
        const auto& target =
            search == CorrespondenceSearch::kProjective ? target_frame : target_down;
        const auto r = RegisterIcp(source, target, params, init);
        SCOPED_TRACE(CorrespondenceSearchName(search));
        EXPECT_TRUE(r.converged) << r.reason;
        EXPECT_LT(RotationErrorDeg(r.T_target_source, T_true), 0.3);
        EXPECT_LT(TranslationError(r.T_target_source, T_true), 0.005);
    }
    EXPECT_TRUE(EstimatePinhole(b).has_value());
    EXPECT_FALSE(EstimatePinhole(source).has_value());
}

TEST(AlignmentQuality, CountsInliersAndRmse) {
    const auto target = test::TableWithBoxes(0.0f, 1);
    const KdTree tree(target);
    const auto q = EvaluateAlignment(target, tree, Eigen::Isometry3d::Identity(), 0.01);
    EXPECT_EQ(q.inliers, q.usable);
    EXPECT_DOUBLE_EQ(q.fitness, 1.0);
    EXPECT_DOUBLE_EQ(q.inlier_rmse, 0.0);
    const auto far = EvaluateAlignment(target, tree, MakeTransform(0, {5, 0, 0}), 0.01);
    EXPECT_EQ(far.inliers, 0u);
    EXPECT_THROW(EvaluateAlignment(target, tree, Eigen::Isometry3d::Identity(), 0.0),
                 InvalidArgument);
}

}  // namespace
}  // namespace multicue

namespace multicue {
namespace {

TEST(RegisterPipeline, AutoWithAndWithoutAGuessAndAnyThreadCount) {
    const auto T = test::MakeTransform(35.0, {0.2, -0.1, 0.05});
    const PointCloud a = test::TableWithBoxes(0.001f, 1, 2500.0f);
    const PointCloud b = test::Transformed(test::TableWithBoxes(0.001f, 2, 2500.0f), T);
    RegistrationParams p = RegistrationParams::ForResolution(0.01f);
    p.num_threads = 1;
    const auto global = Register(a, b, p);  // auto without a guess: global
    EXPECT_TRUE(global.converged) << global.reason;
    EXPECT_LT(test::RotationErrorDeg(global.T_target_source, T), 0.3);
    EXPECT_LT(test::TranslationError(global.T_target_source, T), 0.003);
    p.num_threads = 2;
    EXPECT_EQ(Register(a, b, p).T_target_source.matrix(), global.T_target_source.matrix());
    const auto local = Register(a, b, p, test::MakeTransform(3.0, {0.02, 0, 0}) * T);
    EXPECT_TRUE(local.converged) << local.reason;
    EXPECT_LT(test::RotationErrorDeg(local.T_target_source, T), 0.3);
    // A guess far outside the reach of local alignment: `plane` alone fails, `auto` then aligns
    // without the guess.
    const Eigen::Isometry3d far = test::MakeTransform(-60.0, {0.5, 0.4, 0.0}) * T;
    RegistrationParams plane = p;
    plane.method = RegistrationMethod::kPlane;
    const auto lost = Register(a, b, plane, far);
    EXPECT_FALSE(lost.converged && test::RotationErrorDeg(lost.T_target_source, T) < 1.0);
    const auto recovered = Register(a, b, p, far);
    EXPECT_TRUE(recovered.converged) << recovered.reason;
    EXPECT_LT(test::RotationErrorDeg(recovered.T_target_source, T), 0.3);
    EXPECT_LT(test::TranslationError(recovered.T_target_source, T), 0.003);
    if (!lost.converged) {
        EXPECT_NE(recovered.reason.find("without it"), std::string::npos) << recovered.reason;
    }
    // Empty and NaN-only input: flagged, not thrown.
    EXPECT_EQ(Register(PointCloud{}, b, p).status, RegistrationStatus::kEmptyInput);
}

TEST(RegisterPipeline, BadParametersNameTheirNode) {
    EXPECT_THROW(RegistrationParams::ForResolution(0.0f), InvalidArgument);
    EXPECT_THROW(ParseRegistrationMethod("teleport"), InvalidArgument);
    RegistrationParams p = RegistrationParams::ForResolution(0.01f);
    p.icp.max_iterations = 0;
    try {
        p.Validate();
        FAIL() << "no exception";
    } catch (const ParameterError& e) {
        EXPECT_EQ(e.path(), "icp");
    }
    p = RegistrationParams::ForResolution(0.01f);
    p.fpfh.ransac.p_success = 1.5;
    EXPECT_THROW(p.Validate(), InvalidArgument);
    p = RegistrationParams::ForResolution(0.01f);
    p.free_space.max_violation = 0.0;
    EXPECT_THROW(p.Validate(), InvalidArgument);
    EXPECT_THROW(SuggestResolution(PointCloud{}), DataError);
    // A table top at 1 cm spacing: about 1 cm (its diagonal / 300 is smaller).
    PointCloud grid;
    for (int i = 0; i < 100; ++i)
        for (int j = 0; j < 60; ++j) grid.points.emplace_back(0.01f * i, 0.01f * j, 0.0f);
    grid.SetUnorganized();
    EXPECT_NEAR(SuggestResolution(grid), 0.01f, 1e-6f);
}

}  // namespace
}  // namespace multicue

// Planar patches and plane correspondences: extraction, the closed-form plane triple, the
// moment-based plane terms against explicit sums, points and planes together, and global
// registration of a synthetic room without an initial guess.

#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/registration/plane_registration.hpp"
#include "multicue/registration/planes.hpp"
#include "multicue/registration/preprocess.hpp"
#include "registration_scenes.hpp"

namespace multicue {
namespace {

using test::MakeTransform;
using test::RotationErrorDeg;
using test::TranslationError;

PointCloud Room(std::uint32_t seed, const Eigen::Isometry3d& T = Eigen::Isometry3d::Identity()) {
    return PreprocessForRegistration(test::Transformed(test::RoomCorner(0.005f, seed), T),
                                     {.voxel_size = 0.05f, .num_threads = 1});
}

PlaneExtractionParams RoomPlanes() {
    return {.radius = 0.15f, .min_points = 40, .max_rmse = 0.02f, .merge_distance = 0.05f};
}

TEST(Planes, ExtractsTheFlatRegionsOfARoom) {
    const PointCloud room = Room(1);
    const KdTree tree(room);
    const auto patches = ExtractPlanarPatches(room, tree, RoomPlanes());
    // Floor, two walls, and the box's top and two visible sides at least.
    ASSERT_GE(patches.size(), 5u);
    EXPECT_GT(std::abs(patches[0].normal.z()), 0.99);  // the floor is the largest
    EXPECT_NEAR(patches[0].d, 0.0, 0.01);
    for (std::size_t i = 1; i < patches.size(); ++i) {
        EXPECT_LE(patches[i].size(), patches[i - 1].size());
    }
    for (const auto& p : patches) {
        EXPECT_LT(p.rmse, 0.02);
        EXPECT_NEAR(p.normal.norm(), 1.0, 1e-9);
        // Oriented towards the sensor.
        EXPECT_GT(p.normal.dot(room.sensor_origin.cast<double>() - p.centroid), 0.0);
    }
    EXPECT_TRUE(ExtractPlanarPatches(PointCloud{}, tree, RoomPlanes()).empty());
}

TEST(Planes, TripleGivesTheExactTransform) {
    const auto T = MakeTransform(70.0, {1.0, -2.0, 0.5});
    PlanarPatch s[3];
    s[0].normal = Eigen::Vector3d(0, 0, 1);
    s[0].d = -0.2;
    s[1].normal = Eigen::Vector3d(1, 1, 0).normalized();
    s[1].d = 1.0;
    s[2].normal = Eigen::Vector3d(0, -1, 0.2).normalized();
    s[2].d = -3.0;
    PlanarPatch t[3];
    for (int k = 0; k < 3; ++k) {
        s[k].centroid = -s[k].d * s[k].normal;
        t[k] = TransformPatch(s[k], T);
    }
    const PlanarPatch* const sp[3] = {&s[0], &s[1], &s[2]};
    const PlanarPatch* const tp[3] = {&t[0], &t[1], &t[2]};
    Eigen::Isometry3d fit;
    ASSERT_TRUE(TransformFromPlaneTriple(sp, tp, fit));
    EXPECT_LT((fit.matrix() - T.matrix()).cwiseAbs().maxCoeff(), 1e-9);
    // Parallel planes cannot fix the translation.
    s[1].normal = s[0].normal;
    t[1] = TransformPatch(s[1], T);
    EXPECT_FALSE(TransformFromPlaneTriple(sp, tp, fit));
}

TEST(Planes, MomentTermsEqualExplicitSums) {
    const PointCloud room = Room(2);
    const KdTree tree(room);
    const auto patches = ExtractPlanarPatches(room, tree, RoomPlanes());
    ASSERT_GE(patches.size(), 3u);
    const auto T = MakeTransform(3.0, {0.05, -0.02, 0.03});
    const std::vector<PlanePair> pairs = {{0, 0}, {1, 1}, {2, 2}};
    const Eigen::Vector3d center(0.7, 0.3, -0.2);
    Matrix6d H = Matrix6d::Zero();
    Vector6d g = Vector6d::Zero();
    const double cost = AddPlaneTerms(patches, patches, pairs, {0.5, 0.5, 0.5}, T, center, H, g);
    Matrix6d He = Matrix6d::Zero();
    Vector6d ge = Vector6d::Zero();
    double ce = 0.0;
    for (const auto& pair : pairs) {
        const auto& n = patches[pair.target].normal;
        for (Index i : patches[pair.source].indices) {
            const Eigen::Vector3d p = T * room.points[i].cast<double>();
            const double r = n.dot(p) + patches[pair.target].d;
            Vector6d J;
            J.head<3>() = (p - center).cross(n);
            J.tail<3>() = n;
            He += 0.5 * J * J.transpose();
            ge += 0.5 * r * J;
            ce += 0.5 * r * r;
        }
    }
    EXPECT_LT((H - He).cwiseAbs().maxCoeff(), 1e-6 * He.cwiseAbs().maxCoeff());
    EXPECT_LT((g - ge).cwiseAbs().maxCoeff(), 1e-6 * ge.cwiseAbs().maxCoeff());
    EXPECT_NEAR(cost, ce, 1e-6 * ce);
}

TEST(Planes, MatchesPlanesUnderTheTrueTransform) {
    const auto T = MakeTransform(10.0, {0.2, 0.1, 0.0});
    const PointCloud a = Room(1);
    const PointCloud b = Room(2, T);
    const KdTree ta(a), tb(b);
    const auto pa = ExtractPlanarPatches(a, ta, RoomPlanes());
    const auto pb = ExtractPlanarPatches(b, tb, RoomPlanes());
    const auto pairs = MatchPlanes(pa, pb, T, {});
    EXPECT_GE(pairs.size(), 4u);
    for (const auto& pair : pairs) {
        EXPECT_GT((T.linear() * pa[pair.source].normal).dot(pb[pair.target].normal), 0.99);
    }
    EXPECT_LT(MatchPlanes(pa, pb, Eigen::Isometry3d::Identity(), {}).size(), pairs.size());
}

TEST(PlaneRegistration, PointsAndPlanesRecoverAKnownTransform) {
    const auto T = MakeTransform(6.0, {0.15, -0.1, 0.05});
    const PointCloud a = Room(1);
    const PointCloud b = Room(2, T);
    const KdTree ta(a), tb(b);
    const auto pa = ExtractPlanarPatches(a, ta, RoomPlanes());
    const auto pb = ExtractPlanarPatches(b, tb, RoomPlanes());
    PointPlaneParams params;
    params.icp.correspondences.max_distance = 0.1f;
    params.icp.initial_max_distance = 0.4f;
    params.matching.max_offset = 0.3f;
    params.matching.max_angle_deg = 15.0f;
    const auto r = RegisterPointsAndPlanes(a, b, &tb, pa, pb, params);
    EXPECT_TRUE(r.converged) << r.reason;
    EXPECT_LT(RotationErrorDeg(r.T_target_source, T), 0.3);
    EXPECT_LT(TranslationError(r.T_target_source, T), 0.01);
    EXPECT_NE(r.reason.find("source planes matched"), std::string::npos);
}

TEST(PlaneRegistration, GlobalAlignmentOfARoomWithoutAGuess) {
    // Large motions in every direction; no initial guess is given.
    for (const auto& T : {MakeTransform(120.0, {1.0, -0.5, 0.3}), MakeTransform(-75.0, {-2, 1, 0}),
                          MakeTransform(170.0, {0.3, 0.3, -0.2})}) {
        const PointCloud a = Room(1);
        const PointCloud b = Room(2, T);
        const KdTree ta(a), tb(b);
        const auto pa = ExtractPlanarPatches(a, ta, RoomPlanes());
        const auto pb = ExtractPlanarPatches(b, tb, RoomPlanes());
        PlaneGlobalParams params;
        params.score_distance = 0.1f;
        params.refine.icp.correspondences.max_distance = 0.1f;
        params.num_threads = 1;
        const auto r = RegisterPlanesGlobal(a, b, tb, pa, pb, params);
        EXPECT_TRUE(r.converged) << r.reason;
        EXPECT_GT(r.iterations, 0);
        EXPECT_LT(RotationErrorDeg(r.T_target_source, T), 0.5);
        EXPECT_LT(TranslationError(r.T_target_source, T), 0.02);
    }
}

TEST(PlaneRegistration, GlobalNeedsThreeNonParallelPlanes) {
    const PointCloud a =
        PreprocessForRegistration(test::SinglePlane(0.002f, 1), {.voxel_size = 0.05f});
    const PointCloud b =
        PreprocessForRegistration(test::SinglePlane(0.002f, 2), {.voxel_size = 0.05f});
    const KdTree ta(a), tb(b);
    const auto pa = ExtractPlanarPatches(a, ta, RoomPlanes());
    const auto pb = ExtractPlanarPatches(b, tb, RoomPlanes());
    const auto r = RegisterPlanesGlobal(a, b, tb, pa, pb, {});
    EXPECT_FALSE(r.converged);
    EXPECT_EQ(r.status, RegistrationStatus::kNoHypothesis);
    EXPECT_NE(r.reason.find("non-parallel"), std::string::npos) << r.reason;
    const auto empty = RegisterPlanesGlobal(PointCloud{}, b, tb, {}, pb, {});
    EXPECT_EQ(empty.status, RegistrationStatus::kEmptyInput);
}

TEST(PlaneRegistration, BadParametersThrow) {
    const PointCloud a = Room(1);
    const KdTree ta(a);
    EXPECT_THROW(ExtractPlanarPatches(a, ta, {.radius = 0.0f}), InvalidArgument);
    EXPECT_THROW(ExtractPlanarPatches(a, ta, {.min_points = 2}), InvalidArgument);
    EXPECT_THROW(ExtractPlanarPatches(a, ta, {.max_planes = 0}), InvalidArgument);
    PointCloud bare = a;
    bare.normals.clear();
    EXPECT_THROW(ExtractPlanarPatches(bare, ta, {}), DataError);
    EXPECT_THROW(MatchPlanes({}, {}, Eigen::Isometry3d::Identity(), {.max_offset = -1.0f}),
                 InvalidArgument);
    PlaneGlobalParams g;
    g.angle_tolerance_deg = 0.0f;
    EXPECT_THROW(RegisterPlanesGlobal(a, a, ta, {}, {}, g), InvalidArgument);
    PointPlaneParams pp;
    pp.icp.method = IcpMethod::kPointToPoint;
    EXPECT_THROW(RegisterPointsAndPlanes(a, a, &ta, {}, {}, pp), InvalidArgument);
    pp.icp.method = IcpMethod::kPointToPlane;
    pp.plane_weight = -1.0;
    try {
        RegisterPointsAndPlanes(a, a, &ta, {}, {}, pp);
        FAIL() << "no exception";
    } catch (const InvalidArgument& e) {
        EXPECT_NE(std::string(e.what()).find("plane_weight"), std::string::npos);
    }
}

TEST(PlaneRegistration, SameResultForAnyThreadCount) {
    const auto T = MakeTransform(100.0, {0.5, 0.5, 0.0});
    const PointCloud a = Room(1);
    const PointCloud b = Room(2, T);
    const KdTree ta(a), tb(b);
    const auto pa = ExtractPlanarPatches(a, ta, RoomPlanes());
    const auto pb = ExtractPlanarPatches(b, tb, RoomPlanes());
    PlaneGlobalParams params;
    params.score_distance = 0.1f;
    params.refine.icp.correspondences.max_distance = 0.1f;
    params.num_threads = 1;
    const auto one = RegisterPlanesGlobal(a, b, tb, pa, pb, params);
    params.num_threads = 2;
    const auto two = RegisterPlanesGlobal(a, b, tb, pa, pb, params);
    EXPECT_EQ(one.T_target_source.matrix(), two.T_target_source.matrix());
    EXPECT_EQ(one.iterations, two.iterations);
}

}  // namespace
}  // namespace multicue

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <random>

#include <gtest/gtest.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/reconstruction/rotational_model.hpp"
#include "multicue/search/kdtree.hpp"
#include "multicue/sim/procedural.hpp"
#include "multicue/sim/scene_gen.hpp"
#include "multicue/sim/sensors.hpp"
#include "multicue/surface/normals.hpp"

namespace multicue {
namespace {

constexpr float kPi = 3.14159265f;

struct Profile {
    std::function<float(float)> radius;  // radius at height h in [0, height]
    float height = 0.0f;
};

Profile Bottle() {
    return {[](float h) {
                if (h < 0.16f) return 0.035f;
                if (h < 0.22f) return 0.035f - (h - 0.16f) / 0.06f * 0.021f;
                return 0.014f;
            },
            0.26f};
}

Profile Bowl() {
    // A spherical bowl: radius 0.02 at the foot to 0.08 at the rim, 0.07 high.
    return {[](float h) { return 0.02f + 0.06f * std::sqrt(std::min(1.0f, h / 0.07f)); }, 0.07f};
}

Profile Vase() {
    return {[](float h) { return 0.045f + 0.02f * std::sin(h / 0.2f * 2.0f * kPi); }, 0.2f};
}

/// Points of the surface seen from the origin (camera) with Kinect-like axial noise, normals
/// estimated from the noisy points (the way a real scan gets them).
PointCloud ScanProfile(const Profile& profile, const Eigen::Vector3f& base,
                       const Eigen::Vector3f& axis, std::uint32_t seed,
                       float noise_scale = 1.4e-3f) {
    std::mt19937 rng(seed);
    std::normal_distribution<float> gauss(0.0f, 1.0f);
    const Eigen::Vector3f a = axis.normalized();
    const Eigen::Vector3f e1 = a.unitOrthogonal();
    const Eigen::Vector3f e2 = a.cross(e1);
    PointCloud cloud;
    const float dh = 0.0025f;
    for (float h = 0.0f; h <= profile.height; h += dh) {
        const float r = profile.radius(h);
        const float slope = (profile.radius(std::min(profile.height, h + 1e-3f)) -
                             profile.radius(std::max(0.0f, h - 1e-3f))) /
                            2e-3f;
        const int around = std::max(12, static_cast<int>(2.0f * kPi * r / dh));
        for (int j = 0; j < around; ++j) {
            const float theta = 2.0f * kPi * static_cast<float>(j) / static_cast<float>(around);
            const Eigen::Vector3f radial = std::cos(theta) * e1 + std::sin(theta) * e2;
            const Eigen::Vector3f p = base + h * a + r * radial;
            const Eigen::Vector3f n = (radial - slope * a).normalized();
            if (n.dot(-p) <= 0.1f * p.norm()) continue;  // facing away or grazing
            const float z = p.norm();
            cloud.points.push_back(p + (noise_scale * z * z * gauss(rng)) * p.normalized());
        }
    }
    cloud.SetUnorganized();
    const KdTree tree(cloud);
    SetNormals(cloud,
               EstimateNormals(cloud, tree, {.k = 20, .viewpoint = Eigen::Vector3f::Zero()}));
    return cloud;
}

Indices All(const PointCloud& c) {
    Indices idx(c.size());
    for (std::size_t i = 0; i < idx.size(); ++i) idx[i] = static_cast<std::uint32_t>(i);
    return idx;
}

float AngleDeg(const Eigen::Vector3f& a, const Eigen::Vector3f& b) {
    return std::acos(std::min(1.0f, std::abs(a.normalized().dot(b.normalized())))) * 180.0f / kPi;
}

struct Case {
    const char* name;
    Profile profile;
    Eigen::Vector3f axis;
};

TEST(RotationalModel, RecoversTheAxisAndContourOfTiltedBottlesBowlsAndVases) {
    const Eigen::Vector3f base(0.05f, 0.1f, 0.9f);
    const Case cases[] = {
        {"upright bottle", Bottle(), Eigen::Vector3f(0.0f, -1.0f, 0.3f)},
        {"tilted bottle", Bottle(), Eigen::Vector3f(0.5f, -1.0f, 0.1f)},
        {"bowl", Bowl(), Eigen::Vector3f(0.0f, -1.0f, -0.6f)},
        {"vase", Vase(), Eigen::Vector3f(-0.3f, -1.0f, 0.4f)},
    };
    std::uint32_t seed = 1;
    for (const auto& c : cases) {
        const PointCloud cloud = ScanProfile(c.profile, base, c.axis, seed++);
        const auto model =
            FitRotationalModel(cloud, All(cloud), Eigen::Vector3f::Zero(), Eigen::Vector4f::Zero());
        ASSERT_TRUE(model.found) << c.name;
        EXPECT_LT(AngleDeg(model.axis, c.axis), 5.0f) << c.name;
        // The contour: radius at mid-height within 5 mm of the truth.
        const Eigen::Vector3f a = c.axis.normalized();
        const float h_mid = 0.5f * c.profile.height;
        const float h_model = (base + h_mid * a - model.origin).dot(model.axis);
        EXPECT_NEAR(model.RadiusAt(h_model), c.profile.radius(h_mid), 0.005f) << c.name;
        EXPECT_GT(model.inlier_ratio, 0.85f) << c.name;
    }
}

/// A small shallow bowl (rim radius 7.5 cm, 3.6 cm high, 4 mm wall) on a table, scanned by the
/// simulated Kinect from a low camera at 1.3-1.5 m: the outside of the near wall and the inside
/// of the far wall are seen, the bottom is not. The normals of such a wall barely constrain the
/// axis (they nearly meet in one point, as on a sphere: the normal lines alone give 19 and 23
/// degrees here); the contour and the level rim do.
TEST(RotationalModel, RecoversTheAxisOfAShallowBowlSeenFromTheSide) {
    const float R = 0.075f, h = 0.036f, Rb = 0.03f, t = 0.004f;
    std::vector<sim::ProfilePoint> profile{{0.0f, 0.0f, 0}};
    for (int i = 0; i <= 10; ++i) {
        const float s = static_cast<float>(i) / 10.0f * kPi / 2.0f;
        profile.push_back({Rb + (R - Rb) * std::sin(s), h * (1.0f - std::cos(s)), 0});
    }
    for (int i = 10; i >= 0; --i) {
        const float s = static_cast<float>(i) / 10.0f * kPi / 2.0f;
        profile.push_back({Rb - t + (R - Rb) * std::sin(s), t + (h - t) * (1.0f - std::cos(s)), 0});
    }
    profile.push_back({0.0f, t, 0});
    sim::ObjectModel object;
    object.mesh = std::make_shared<sim::PartMesh>(sim::MakeRevolutionMesh(profile, {"bowl"}));
    object.category = object.source = "bowl";
    const struct {
        float distance, elevation_deg;
        std::uint64_t seed;
    } views[] = {{1.3f, 28.0f, 14}, {1.5f, 20.0f, 12}};
    for (const auto& v : views) {
        sim::TurntableParams table;
        const float elevation = v.elevation_deg * kPi / 180.0f;
        table.distance = v.distance * std::cos(elevation);
        table.camera_height = table.table_height + v.distance * std::sin(elevation);
        const sim::Scene scene = sim::MakeTurntableScene(object, table, 3);
        const Eigen::Isometry3f pose = sim::TurntableViews(scene, 12, table)[0];
        PointCloud cloud = sim::ScanKinect(scene, pose, sim::KinectParams{}, v.seed);
        SetNormals(cloud, EstimateNormalsOrganized(cloud, {}));
        Indices bowl;
        for (std::uint32_t i = 0; i < cloud.size(); ++i) {
            if (cloud.labels[i] == sim::ObjectLabel(1)) bowl.push_back(i);
        }
        ASSERT_GT(bowl.size(), 500u);
        const Eigen::Vector3f up = pose.linear().transpose() * Eigen::Vector3f::UnitZ();
        const auto model =
            FitRotationalModel(cloud, bowl, Eigen::Vector3f::Zero(), Eigen::Vector4f::Zero());
        ASSERT_TRUE(model.found);
        EXPECT_LT(AngleDeg(model.axis, up), 4.0f) << v.distance << " m";
        EXPECT_GT(model.profile_spread, 0.0f);
        EXPECT_LT(model.profile_spread, 0.005f);
        // The contour: the rim (its widest part) within 1 cm.
        EXPECT_NEAR(*std::max_element(model.radii.begin(), model.radii.end()), R, 0.01f)
            << v.distance << " m";
    }
}

TEST(RotationalModel, UprightPriorAndSupportPlaneReachDownToTheTable) {
    // Upright bottle on a table 5 cm below its lowest scanned point; camera frame y down.
    const Eigen::Vector3f up(0.0f, -1.0f, 0.0f);
    const Eigen::Vector3f base(0.0f, 0.2f, 1.0f);
    const PointCloud cloud = ScanProfile(Bottle(), base, up, 5);
    Indices upper;
    for (std::uint32_t i = 0; i < cloud.size(); ++i) {
        if ((cloud.points[i] - base).dot(up) > 0.05f) upper.push_back(i);
    }
    const Eigen::Vector4f plane(up.x(), up.y(), up.z(), -up.dot(base));
    RotationalFitParams params;
    params.max_tilt_deg = 15.0f;
    const auto model = FitRotationalModel(cloud, upper, up, plane, params);
    ASSERT_TRUE(model.found);
    EXPECT_LT(AngleDeg(model.axis, up), 3.0f);
    EXPECT_GT(model.axis.dot(up), 0.0f);
    const float bottom = (model.origin + model.heights.front() * model.axis - base).dot(up);
    EXPECT_NEAR(bottom, 0.0f, 0.01f);
}

TEST(RotationalModel, MeshIsClosedAndOutwardOriented) {
    RotationalModel m;
    m.found = true;
    m.heights = {0.0f, 0.1f, 0.2f};
    m.radii = {0.03f, 0.04f, 0.02f};
    const TriangleMesh mesh = RotationalMesh(m, 16);
    mesh.Validate();
    EXPECT_EQ(mesh.triangles.size(), 2u * 16u * 2u + 2u * 16u);
    // Signed volume positive (outward), close to the frustum volumes.
    double volume = 0.0;
    for (const auto& t : mesh.triangles) {
        volume += mesh.vertices[t[0]].cast<double>().dot(mesh.vertices[t[1]].cast<double>().cross(
                      mesh.vertices[t[2]].cast<double>())) /
                  6.0;
    }
    auto frustum = [](double r1, double r2, double h) {
        return 3.14159265 * h / 3.0 * (r1 * r1 + r1 * r2 + r2 * r2);
    };
    const double expected = frustum(0.03, 0.04, 0.1) + frustum(0.04, 0.02, 0.1);
    EXPECT_NEAR(volume, expected, 0.05 * expected);
    EXPECT_TRUE(RotationalMesh(RotationalModel{}, 16).empty());
    EXPECT_THROW(RotationalMesh(m, 2), InvalidArgument);
}

TEST(RotationalModel, BadInputEmptyInputAndDeterminism) {
    const PointCloud cloud = ScanProfile(Bottle(), {0.0f, 0.0f, 1.0f}, {0.0f, -1.0f, 0.2f}, 3);
    const Eigen::Vector3f none = Eigen::Vector3f::Zero();
    const Eigen::Vector4f no_plane = Eigen::Vector4f::Zero();
    EXPECT_FALSE(FitRotationalModel(cloud, {}, none, no_plane).found);
    EXPECT_THROW(
        FitRotationalModel(cloud, {static_cast<std::uint32_t>(cloud.size())}, none, no_plane),
        InvalidArgument);
    RotationalFitParams bad;
    bad.line_threshold = 0.0f;
    EXPECT_THROW(FitRotationalModel(cloud, All(cloud), none, no_plane, bad), InvalidArgument);
    RotationalFitParams bad_tolerance;
    bad_tolerance.profile_tolerance = 0.0f;
    EXPECT_THROW(FitRotationalModel(cloud, All(cloud), none, no_plane, bad_tolerance),
                 InvalidArgument);
    RotationalFitParams bad_points;
    bad_points.profile_points = 5;
    EXPECT_THROW(FitRotationalModel(cloud, All(cloud), none, no_plane, bad_points),
                 InvalidArgument);
    RotationalFitParams bad_weight;
    bad_weight.rim_weight = -1.0f;
    EXPECT_THROW(FitRotationalModel(cloud, All(cloud), none, no_plane, bad_weight),
                 InvalidArgument);
    PointCloud bare = cloud;
    bare.normals.clear();
    EXPECT_THROW(FitRotationalModel(bare, All(bare), none, no_plane), DataError);
    RotationalFitParams bad_threads;
    bad_threads.num_threads = -1;
    EXPECT_THROW(FitRotationalModel(cloud, All(cloud), none, no_plane, bad_threads),
                 InvalidArgument);
    const auto a = FitRotationalModel(cloud, All(cloud), none, no_plane);
    const auto b = FitRotationalModel(cloud, All(cloud), none, no_plane);
    EXPECT_EQ(a.axis, b.axis);
    EXPECT_EQ(a.radii, b.radii);
    // The axis search and the refinement's starts in parallel: the same model.
    RotationalFitParams two;
    two.num_threads = 2;
    const auto c = FitRotationalModel(cloud, All(cloud), none, no_plane, two);
    EXPECT_EQ(a.axis, c.axis);
    EXPECT_EQ(a.origin, c.origin);
    EXPECT_EQ(a.radii, c.radii);
    EXPECT_EQ(a.heights, c.heights);
}

}  // namespace
}  // namespace multicue

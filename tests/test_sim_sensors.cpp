// Sensor models of the simulator: noise statistics, missing data, ground truth, determinism.

#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <numbers>

#include <gtest/gtest.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/sim/procedural.hpp"
#include "multicue/sim/scene_gen.hpp"
#include "multicue/sim/sensors.hpp"
#include "reduced_kinect.hpp"

namespace multicue::sim {
namespace {

constexpr float kPi = std::numbers::pi_v<float>;

/// A large plane through `center` with unit normal `n` (a thin box), label 20.
Scene PlaneScene(const Eigen::Vector3f& center, const Eigen::Vector3f& n) {
    PartMesh m = MakeBoxMesh({6.0f, 6.0f, 0.01f}, "plane");
    for (auto& v : m.mesh.vertices) v.z() -= 0.01f;  // top face at z = 0
    SceneObject o;
    o.mesh = std::make_shared<const PartMesh>(std::move(m));
    o.T_world_object.linear() =
        Eigen::Quaternionf::FromTwoVectors(Eigen::Vector3f::UnitZ(), n).toRotationMatrix();
    o.T_world_object.translation() = center;
    o.label = ObjectLabel(1);
    o.category = 2;
    Scene s;
    s.objects.push_back(o);
    return s;
}

/// Camera at the origin looking along world +z (identity optical frame).
const Eigen::Isometry3f kCamera = Eigen::Isometry3f::Identity();

double RelativeNoise(const Scene& scene, float tilt, const KinectParams& p, float z0) {
    const Eigen::Vector3f n(0.0f, -std::sin(tilt), -std::cos(tilt));
    const PointCloud c = ScanKinect(scene, kCamera, p, 42);
    // True depth along each pixel ray from the analytic plane n.(x - (0,0,z0)) = 0.
    double sum = 0, sum2 = 0;
    std::size_t count = 0;
    for (std::uint32_t v = 0; v < p.height; ++v) {
        for (std::uint32_t u = 0; u < p.width; ++u) {
            const auto& q = c.points[std::size_t{v} * p.width + u];
            if (!q.allFinite()) continue;
            const Eigen::Vector3f ray((u - p.cx) / p.fx, (v - p.cy) / p.fy, 1.0f);
            const float z_true = n.z() * z0 / n.dot(ray);
            const double e = (q.z() - z_true) / (double{z_true} * z_true);
            sum += e;
            sum2 += e * e;
            ++count;
        }
    }
    EXPECT_GT(count, 1000u);
    const double mean = sum / count;
    return std::sqrt(sum2 / count - mean * mean);
}

TEST(SimKinect, AxialNoiseFollowsKhoshelham) {
    // A plane tilted by 30 degrees so that disparities cover many quantisation steps.
    const float tilt = 30.0f * kPi / 180.0f;
    for (float z0 : {0.5f, 1.0f, 2.0f}) {
        KinectParams p = test::ReducedKinect(4);
        p.width = 320;
        p.height = 240;
        p.fx = p.fy = 525.0f;  // the model's focal length: noise is per Kinect pixel
        p.cx = 159.5f;
        p.cy = 119.5f;
        const Eigen::Vector3f n(0.0f, -std::sin(tilt), -std::cos(tilt));
        const Scene s = PlaneScene({0.0f, 0.0f, z0}, n);
        const double sigma = RelativeNoise(s, tilt, p, z0);
        EXPECT_NEAR(sigma, 1.4e-3, 0.15 * 1.4e-3) << "plane at " << z0 << " m";
    }
}

TEST(SimKinect, NoNoiseWithoutNoiseAndQuantisation) {
    KinectParams p = test::ReducedKinect(4);
    p.axial_noise = 0.0f;
    p.disparity_step = 0.0f;
    const Scene s = PlaneScene({0, 0, 1.0f}, {0, 0, -1});
    const PointCloud c = ScanKinect(s, kCamera, p, 1);
    for (const auto& q : c.points) {
        if (q.allFinite()) {
            EXPECT_NEAR(q.z(), 1.0f, 1e-5f);
        }
    }
}

TEST(SimKinect, MissingDataRisesAtGrazingAngles) {
    KinectParams p = test::ReducedKinect(4);
    p.max_range = 10.0f;
    std::vector<double> valid;
    for (float deg : {0.0f, 40.0f, 65.0f, 80.0f}) {
        const float a = deg * kPi / 180.0f;
        const Scene s = PlaneScene({0, 0, 1.5f}, {0, -std::sin(a), -std::cos(a)});
        const PointCloud c = ScanKinect(s, kCamera, p, 3);
        valid.push_back(static_cast<double>(c.CountFinite()) / c.size());
    }
    EXPECT_GT(valid[0], 0.99);
    EXPECT_GE(valid[0], valid[1]);
    EXPECT_GT(valid[1], valid[2]);
    EXPECT_GT(valid[2], valid[3]);
    EXPECT_LT(valid[3], 0.6 * valid[0]);  // beyond 78 degrees in much of the image
}

/// A table scene with a box of known size, seen from 45 degrees above.
Scene BoxScene(const Eigen::Vector3f& extents, float yaw) {
    Scene s;
    PartMesh floor = MakeBoxMesh({4, 4, 0.02f}, "floor");
    for (auto& v : floor.mesh.vertices) v.z() -= 0.02f;
    SceneObject f;
    f.mesh = std::make_shared<const PartMesh>(std::move(floor));
    f.label = kFloorLabel;
    s.objects.push_back(f);
    SceneObject b;
    b.mesh = std::make_shared<const PartMesh>(MakeBoxMesh(extents));
    b.T_world_object.linear() = Eigen::AngleAxisf(yaw, Eigen::Vector3f::UnitZ()).toRotationMatrix();
    b.label = ObjectLabel(1);
    b.category = 2;
    b.color = {200, 20, 20, 255};
    s.objects.push_back(b);
    return s;
}

TEST(SimKinect, EveryPointLiesOnTheSurfaceItIsLabelledWith) {
    const Eigen::Vector3f e(0.2f, 0.12f, 0.15f);
    const Scene s = BoxScene(e, 0.4f);
    KinectParams p = test::ReducedKinect(4);
    p.axial_noise = 0.0f;
    p.disparity_step = 0.0f;
    p.lateral_noise_px = 0.0f;
    const auto T = LookAt({0.6f, -0.5f, 0.7f}, {0, 0, 0.05f});
    const PointCloud c = ScanKinect(s, T, p, 5);
    const auto* cat = c.FindExtraField("category");
    const auto* part = c.FindExtraField("part");
    ASSERT_NE(cat, nullptr);
    ASSERT_NE(part, nullptr);
    std::size_t on_box = 0;
    const Eigen::Isometry3f box_inv = s.objects[1].T_world_object.inverse();
    for (std::size_t i = 0; i < c.size(); ++i) {
        if (!c.IsFinite(i)) {
            EXPECT_EQ(c.labels[i], 0u);
            continue;
        }
        const Eigen::Vector3f w = T * c.points[i];
        if (c.labels[i] == kFloorLabel) {
            EXPECT_NEAR(w.z(), 0.0f, 1e-4f);
            EXPECT_EQ(cat->data[i], 0);
        } else {
            ASSERT_EQ(c.labels[i], ObjectLabel(1));
            EXPECT_EQ(cat->data[i], 2);
            const Eigen::Vector3f q = box_inv * w;
            const Eigen::Vector3f d(std::abs(q.x()) - e.x() / 2, std::abs(q.y()) - e.y() / 2,
                                    std::max(q.z() - e.z(), -q.z()));
            EXPECT_LT(d.maxCoeff(), 1e-4f);   // inside or on the box
            EXPECT_GT(d.maxCoeff(), -1e-4f);  // on a face
            EXPECT_EQ(c.colors[i].r > 150, true);
            ++on_box;
        }
    }
    EXPECT_GT(on_box, 200u);
}

TEST(SimKinect, ScannedBoxExtentsAgreeWithinNoise) {
    const Eigen::Vector3f e(0.2f, 0.12f, 0.15f);
    const Scene s = BoxScene(e, 0.4f);
    KinectParams p;  // full resolution and default noise
    p.num_threads = 2;
    const auto T = LookAt({0.6f, -0.5f, 0.7f}, {0, 0, 0.05f});
    const PointCloud c = ScanKinect(s, T, p, 9);
    const Eigen::Isometry3f box_inv = s.objects[1].T_world_object.inverse();
    Eigen::AlignedBox3f box;
    for (std::size_t i = 0; i < c.size(); ++i) {
        if (c.labels[i] == ObjectLabel(1)) box.extend(box_inv * (T * c.points[i]));
    }
    // Seen from one side, the top face spans x and y and the side faces span z.
    const Eigen::Vector3f measured = box.sizes();
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(measured[k], e[k], 0.012f) << "axis " << k;
}

TEST(SimKinect, ProjectorShadowRemovesPointsBesideObjects) {
    const Scene s = BoxScene({0.1f, 0.1f, 0.3f}, 0.0f);
    KinectParams p = test::ReducedKinect(4);
    const auto T = LookAt({0.0f, -0.8f, 0.6f}, {0, 0, 0.1f});
    p.projector_shadow = false;
    const std::size_t without = ScanKinect(s, T, p, 1).CountFinite();
    p.projector_shadow = true;
    const std::size_t with = ScanKinect(s, T, p, 1).CountFinite();
    EXPECT_LT(with + 20, without);
}

TEST(SimKinect, DeterministicForSeedAndThreadCount) {
    const Scene s = MakeTableScene({}, 7);
    const auto poses = TableViewpoints(s, 1, {}, 7);
    KinectParams p;
    p.num_threads = 1;
    const PointCloud a = ScanKinect(s, poses[0], p, 11);
    p.num_threads = 2;
    const PointCloud b = ScanKinect(s, poses[0], p, 11);
    const PointCloud d = ScanKinect(s, poses[0], p, 12);
    ASSERT_EQ(a.size(), b.size());
    EXPECT_EQ(std::memcmp(a.points.data(), b.points.data(), a.size() * sizeof(a.points[0])), 0);
    EXPECT_EQ(a.labels, b.labels);
    EXPECT_EQ(a.extra_fields[1].data, b.extra_fields[1].data);
    EXPECT_NE(std::memcmp(a.points.data(), d.points.data(), a.size() * sizeof(a.points[0])), 0);
}

TEST(SimKinect, BadParameters) {
    const Scene s = PlaneScene({0, 0, 1}, {0, 0, -1});
    const RayCaster caster(s);
    KinectParams p = test::ReducedKinect(4);
    p.fx = 0;
    EXPECT_THROW(ScanKinect(caster, kCamera, p, 1), InvalidArgument);
    p = test::ReducedKinect(4);
    p.max_range = 0.1f;
    EXPECT_THROW(ScanKinect(caster, kCamera, p, 1), InvalidArgument);
    p = test::ReducedKinect(4);
    p.baseline = 0.0f;
    EXPECT_THROW(ScanKinect(caster, kCamera, p, 1), InvalidArgument);
    p = test::ReducedKinect(4);
    p.max_incidence_deg = 120.0f;
    EXPECT_THROW(ScanKinect(caster, kCamera, p, 1), InvalidArgument);
}

TEST(SimKinect, EmptySceneGivesNoReturns) {
    Scene s;
    const RayCaster caster(s);
    const PointCloud c = ScanKinect(caster, kCamera, test::ReducedKinect(4), 1);
    EXPECT_EQ(c.CountFinite(), 0u);
    EXPECT_TRUE(c.IsOrganized());
}

TEST(RayCaster, OccludedBatchReadsActiveRaysOnly) {
    // A plane at z = 1. Rays from z = 0 up to z = 2 cross it, rays up to z = 0.5 do not; the
    // inactive lanes hold NaNs, huge values and a reach (a caller fills active rays only), which
    // must change nothing and reach no kernel (Embree's checks reject such rays).
    const Scene s = PlaneScene({0.0f, 0.0f, 1.0f}, Eigen::Vector3f::UnitZ());
    const RayCaster caster(s);
    constexpr std::size_t n = 19;  // two full packets and a part
    const float nan = std::numeric_limits<float>::quiet_NaN(), huge = 1e30f;
    std::vector<Eigen::Vector3f> origins(n), dirs(n);
    std::vector<float> t_far(n);
    bool active[n], occluded[n];
    for (std::size_t i = 0; i < n; ++i) {
        active[i] = i % 3 != 1;
        origins[i] = active[i] ? Eigen::Vector3f(0.1f * static_cast<float>(i), 0.0f, 0.0f)
                               : Eigen::Vector3f(Eigen::Vector3f::Constant(i % 2 ? nan : huge));
        dirs[i] = active[i] ? Eigen::Vector3f(Eigen::Vector3f::UnitZ())
                            : Eigen::Vector3f(Eigen::Vector3f::Constant(i % 2 ? huge : nan));
        t_far[i] = active[i] ? (i % 2 == 0 ? 2.0f : 0.5f) : 5.0f;
    }
    caster.OccludedBatch(origins.data(), dirs.data(), t_far.data(), active, n, 0.0f, occluded);
    for (std::size_t i = 0; i < n; ++i) {
        EXPECT_EQ(occluded[i], active[i] && i % 2 == 0) << i;
        if (active[i]) {
            EXPECT_EQ(occluded[i], caster.Occluded(origins[i], dirs[i], 0.0f, t_far[i])) << i;
        }
    }
}

TEST(SimLaser, OrganizedByTiltStepWithRangeNoise) {
    // A wall 2 m in front of the head (x forward).
    const Scene s = PlaneScene({2.0f, 0.0f, 0.0f}, {-1.0f, 0.0f, 0.0f});
    LaserParams p;
    p.fov_deg = 40.0f;
    p.tilt_min_deg = -10.0f;
    p.tilt_max_deg = 10.0f;
    p.tilt_step_deg = 1.0f;
    const RayCaster caster(s);
    const PointCloud c = ScanLaser(caster, Eigen::Isometry3f::Identity(), p, 3);
    EXPECT_EQ(c.height, 21u);
    EXPECT_EQ(c.width, 161u);
    double sum = 0, sum2 = 0;
    std::size_t n = 0;
    for (const auto& q : c.points) {
        if (!q.allFinite()) continue;
        const double e = q.x() - 2.0;  // the wall is at x = 2
        // Range error projected on x: scaled by the cosine, close to 1 in this field.
        sum += e;
        sum2 += e * e;
        ++n;
    }
    ASSERT_GT(n, 3000u);
    const double sd = std::sqrt(sum2 / n - (sum / n) * (sum / n));
    EXPECT_NEAR(sd, 0.01 * 0.97, 0.0015);
    p.num_threads = 1;
    const PointCloud a = ScanLaser(caster, Eigen::Isometry3f::Identity(), p, 3);
    EXPECT_EQ(std::memcmp(a.points.data(), c.points.data(), a.size() * sizeof(a.points[0])), 0);
}

TEST(SimTof, NoiseGrowsAsAmplitudeFalls) {
    TofParams p;
    auto noise = [&](Color color, double& amplitude, double& confidence) {
        Scene s = PlaneScene({0, 0, 1.5f}, {0, 0, -1});
        s.objects[0].color = color;
        const RayCaster caster(s);
        const PointCloud c = ScanTof(caster, kCamera, p, 4);
        double sum = 0, sum2 = 0;
        amplitude = confidence = 0;
        std::size_t n = 0;
        for (std::size_t i = 0; i < c.size(); ++i) {
            if (!c.IsFinite(i)) continue;
            const double r = c.points[i].norm();
            const double r_true = 1.5 * r / c.points[i].z();
            sum += r - r_true;
            sum2 += (r - r_true) * (r - r_true);
            amplitude += c.intensity[i];
            confidence += c.confidence[i];
            ++n;
        }
        EXPECT_GT(n, 10000u);
        amplitude /= n;
        confidence /= n;
        return std::sqrt(sum2 / n - (sum / n) * (sum / n));
    };
    double a_white, c_white, a_dark, c_dark;
    const double white = noise({250, 250, 250, 255}, a_white, c_white);
    const double dark = noise({20, 20, 20, 255}, a_dark, c_dark);
    EXPECT_GT(a_white, 2 * a_dark);
    EXPECT_GT(dark, 1.5 * white);
    EXPECT_GT(c_white, c_dark);
}

}  // namespace
}  // namespace multicue::sim

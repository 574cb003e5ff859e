// Weighted sampling and scoring of the sample consensus engine, and the RSD / shape-prior guided
// box and cylinder fits (thesis sections 5.4.1 and 5.4.2.1).

#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Geometry>

#include "multicue/core/exceptions.hpp"
#include "multicue/reconstruction/fit_guidance.hpp"
#include "multicue/reconstruction/primitive_models.hpp"
#include "multicue/segmentation/sac_cylinder.hpp"
#include "multicue/segmentation/sac_plane.hpp"
#include "multicue/segmentation/sample_consensus.hpp"

namespace multicue {
namespace {

constexpr float kPi = std::numbers::pi_v<float>;

void Add(PointCloud& c, const Eigen::Vector3f& p, const Eigen::Vector3f& n) {
    c.points.push_back(p);
    c.normals.push_back(n.normalized());
}

void Finish(PointCloud& c) {
    c.width = static_cast<std::uint32_t>(c.points.size());
    c.height = 1;
}

Indices All(const PointCloud& c) {
    Indices idx(c.size());
    for (std::size_t i = 0; i < idx.size(); ++i) idx[i] = static_cast<Index>(i);
    return idx;
}

// Position noise sigma and normal noise (radians, roughly) on every point.
void Perturb(PointCloud& c, float sigma, float normal_sigma, std::uint32_t seed) {
    std::mt19937 rng(seed);
    std::normal_distribution<float> g(0.0f, 1.0f);
    for (std::size_t i = 0; i < c.size(); ++i) {
        c.points[i] += sigma * Eigen::Vector3f(g(rng), g(rng), g(rng));
        c.normals[i] =
            (c.normals[i] + normal_sigma * Eigen::Vector3f(g(rng), g(rng), g(rng))).normalized();
    }
}

// A box standing on z = 0, rotated by yaw about z, centred at (cx, cy): the faces seen from
// `view` (direction towards the viewer) sampled on a grid of `step`.
PointCloud BoxView(const Eigen::Vector3f& ext, float yaw, const Eigen::Vector2f& centre,
                   const Eigen::Vector3f& view, float step) {
    PointCloud c;
    const Eigen::Matrix3f r = Eigen::AngleAxisf(yaw, Eigen::Vector3f::UnitZ()).toRotationMatrix();
    const Eigen::Vector3f o(centre.x(), centre.y(), 0.5f * ext.z());
    for (int axis = 0; axis < 3; ++axis) {
        for (int sign = -1; sign <= 1; sign += 2) {
            Eigen::Vector3f n = Eigen::Vector3f::Zero();
            n[axis] = static_cast<float>(sign);
            if ((r * n).dot(view) <= 0.05f) continue;  // faces away
            const int a = (axis + 1) % 3, b = (axis + 2) % 3;
            for (float s = -0.5f * ext[a]; s <= 0.5f * ext[a]; s += step) {
                for (float t = -0.5f * ext[b]; t <= 0.5f * ext[b]; t += step) {
                    Eigen::Vector3f p = Eigen::Vector3f::Zero();
                    p[axis] = 0.5f * ext[axis] * static_cast<float>(sign);
                    p[a] = s;
                    p[b] = t;
                    Add(c, o + r * p, r * n);
                }
            }
        }
    }
    Finish(c);
    return c;
}

// A closed cylinder (radius r, height h) with unit axis `axis` through `base` (its bottom
// centre): the side and top cap points seen from `view`.
PointCloud CylinderView(const Eigen::Vector3f& base, const Eigen::Vector3f& axis, float r, float h,
                        const Eigen::Vector3f& view, float step) {
    PointCloud c;
    const Eigen::Vector3f a = axis.normalized();
    const Eigen::Vector3f e1 = a.unitOrthogonal(), e2 = a.cross(e1);
    const int around = static_cast<int>(2.0f * kPi * r / step);
    for (int k = 0; k < around; ++k) {
        const float phi = 2.0f * kPi * static_cast<float>(k) / static_cast<float>(around);
        const Eigen::Vector3f radial = std::cos(phi) * e1 + std::sin(phi) * e2;
        if (radial.dot(view) <= 0.05f) continue;
        for (float t = 0.0f; t <= h; t += step) Add(c, base + t * a + r * radial, radial);
    }
    if (a.dot(view) > 0.05f) {
        for (float x = -r; x <= r; x += step) {
            for (float y = -r; y <= r; y += step) {
                if (x * x + y * y > r * r) continue;
                Add(c, base + h * a + x * e1 + y * e2, a);
            }
        }
    }
    Finish(c);
    return c;
}

// A model of sample size `k` that records the drawn points and never accepts a sample, so the
// engine draws exactly max_iterations samples.
SacModel RecordingModel(int k, std::vector<std::vector<Index>>& drawn) {
    SacModel m;
    m.sample_size = k;
    m.fit_sample = [&drawn](const PointCloud&, std::span<const Index> s, SacCoefficients&) {
        drawn.emplace_back(s.begin(), s.end());
        return false;
    };
    m.distances = [](const PointCloud&, const SacCoefficients&, std::span<const Index>,
                     std::span<float> d) { std::fill(d.begin(), d.end(), 0.0f); };
    return m;
}

TEST(WeightedSampling, DrawsProportionallyToTheWeights) {
    PointCloud c;
    for (int i = 0; i < 6; ++i) Add(c, Eigen::Vector3f(float(i), 0, 0), Eigen::Vector3f::UnitZ());
    Finish(c);
    SacParams p;
    p.max_iterations = 40000;
    p.seed = 11;
    p.sample_weights = {1.0f, 2.0f, 3.0f, 4.0f, 0.0f, 10.0f};
    std::vector<std::vector<Index>> drawn;
    // Point 5 is not among the indices: only 0-4 can be drawn, 4 has weight 0.
    const SacResult r = RunSampleConsensus(c, {0, 1, 2, 3, 4}, RecordingModel(1, drawn), p);
    EXPECT_FALSE(r.found);
    ASSERT_EQ(drawn.size(), 40000u);
    std::vector<int> count(6, 0);
    for (const auto& s : drawn) ++count[s[0]];
    EXPECT_EQ(count[4], 0);
    EXPECT_EQ(count[5], 0);
    for (int i = 0; i < 4; ++i) {
        const double expected = (i + 1) / 10.0;
        const double sd = std::sqrt(expected * (1.0 - expected) / 40000.0);
        EXPECT_NEAR(count[i] / 40000.0, expected, 5.0 * sd) << "point " << i;
    }
}

TEST(WeightedSampling, SamplesWithoutRepetitionFollowTheWeights) {
    PointCloud c;
    for (int i = 0; i < 4; ++i) Add(c, Eigen::Vector3f(float(i), 0, 0), Eigen::Vector3f::UnitZ());
    Finish(c);
    SacParams p;
    p.max_iterations = 30000;
    p.seed = 3;
    p.sample_weights = {1.0f, 1.0f, 2.0f, 6.0f};
    std::vector<std::vector<Index>> drawn;
    RunSampleConsensus(c, {}, RecordingModel(2, drawn), p);
    ASSERT_EQ(drawn.size(), 30000u);
    // Successive sampling without replacement: P(first = 3) = 0.6; P(second = 3) =
    // sum over first j != 3 of P(j) * 6 / (10 - w_j) = 0.1 * 6/9 * 2 + 0.2 * 6/8 = 0.2833.
    int first3 = 0, second3 = 0;
    for (const auto& s : drawn) {
        ASSERT_NE(s[0], s[1]);
        first3 += s[0] == 3 ? 1 : 0;
        second3 += s[1] == 3 ? 1 : 0;
    }
    EXPECT_NEAR(first3 / 30000.0, 0.6, 0.015);
    EXPECT_NEAR(second3 / 30000.0, 0.1 * 6.0 / 9.0 * 2.0 + 0.2 * 6.0 / 8.0, 0.015);
}

TEST(WeightedSampling, TooFewDrawablePointsGiveNoModel) {
    PointCloud c = CylinderView({0, 0, 0}, {0, 0, 1}, 0.04f, 0.1f, {1, 0, 0}, 0.005f);
    CylinderFitParams p;
    p.sac.sample_weights.assign(c.size(), 0.0f);
    p.sac.sample_weights[3] = 1.0f;  // one drawable point, the sample needs two
    const CylinderFit f = FitCylinder(c, {}, p);
    EXPECT_FALSE(f.found);
}

TEST(WeightedSampling, BadWeightsAreRejected) {
    PointCloud c = CylinderView({0, 0, 0}, {0, 0, 1}, 0.04f, 0.1f, {1, 0, 0}, 0.005f);
    const float nan = std::numeric_limits<float>::quiet_NaN();
    for (int which = 0; which < 2; ++which) {
        auto set = [&](std::vector<float> w) {
            CylinderFitParams p;
            (which == 0 ? p.sac.sample_weights : p.sac.score_weights) = std::move(w);
            return p;
        };
        EXPECT_THROW(FitCylinder(c, {}, set(std::vector<float>(c.size() - 1, 1.0f))),
                     InvalidArgument);
        std::vector<float> w(c.size(), 1.0f);
        w[7] = -0.5f;
        EXPECT_THROW(FitCylinder(c, {}, set(w)), InvalidArgument);
        w[7] = nan;
        EXPECT_THROW(FitCylinder(c, {}, set(w)), InvalidArgument);
        w[7] = std::numeric_limits<float>::infinity();
        EXPECT_THROW(FitCylinder(c, {}, set(w)), InvalidArgument);
    }
    try {
        CylinderFitParams p;
        p.sac.score_weights.assign(2, 1.0f);
        FitCylinder(c, {}, p);
        FAIL() << "no exception";
    } catch (const InvalidArgument& e) {
        EXPECT_NE(std::string(e.what()).find("score_weights"), std::string::npos) << e.what();
    }
}

TEST(WeightedSampling, BadGuidanceIsRejected) {
    PointCloud c = CylinderView({0, 0, 0}, {0, 0, 1}, 0.04f, 0.1f, {1, 0, 0}, 0.005f);
    const Indices idx = All(c);
    const Eigen::Vector4f plane(0, 0, 1, 0);
    std::vector<float> shortv(c.size() - 1, 0.5f), r(c.size(), 0.05f), prior(c.size(), 0.5f);
    EXPECT_THROW(FitObjectCylinder(c, idx, plane, {}, {.rsd_min_radius = shortv}), InvalidArgument);
    EXPECT_THROW(FitUprightBox(c, idx, plane, {}, {.shape_prior = shortv}), InvalidArgument);
    r[5] = -0.01f;
    EXPECT_THROW(FitObjectCylinder(c, idx, plane, {}, {.rsd_min_radius = r}), InvalidArgument);
    r[5] = std::numeric_limits<float>::quiet_NaN();  // unknown: allowed
    EXPECT_NO_THROW(FitObjectCylinder(c, idx, plane, {}, {.rsd_min_radius = r}));
    prior[9] = 1.5f;
    EXPECT_THROW(FitObjectCylinder(c, idx, plane, {}, {.shape_prior = prior}), InvalidArgument);
    prior[9] = std::numeric_limits<float>::quiet_NaN();
    EXPECT_THROW(FitFootprintRectangle(c, idx, plane, {}, {.shape_prior = prior}), InvalidArgument);
    FitGuidance g;
    g.rsd.floor_weight = 0.0f;
    EXPECT_THROW(FitObjectCylinder(c, idx, plane, {}, g), InvalidArgument);
}

TEST(WeightedSampling, ScoreWeightsChooseTheModel) {
    // Two parallel planes: 600 points at z = 0, 400 at z = 0.5. Unweighted, the larger wins;
    // with the larger one's points weighted 0.1, the smaller one does.
    PointCloud c;
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> u(-0.5f, 0.5f);
    for (int i = 0; i < 1000; ++i) {
        Add(c, Eigen::Vector3f(u(rng), u(rng), i < 600 ? 0.0f : 0.5f), Eigen::Vector3f::UnitZ());
    }
    Finish(c);
    PlaneFitParams p;
    p.sac.method = SacMethod::kRansac;
    const PlaneFit plain = FitPlane(c, {}, p);
    ASSERT_TRUE(plain.found);
    EXPECT_EQ(plain.inliers.size(), 600u);
    p.sac.score_weights.assign(1000, 1.0f);
    for (int i = 0; i < 600; ++i) p.sac.score_weights[i] = 0.1f;
    const PlaneFit weighted = FitPlane(c, {}, p);
    ASSERT_TRUE(weighted.found);
    EXPECT_EQ(weighted.inliers.size(), 400u);
}

TEST(WeightedSampling, DeterministicAndIndependentOfThreads) {
    PointCloud c = CylinderView({0, 0, 0}, {0.3f, 0.1f, 1.0f}, 0.05f, 0.3f, {1, 0, 0.4f}, 0.0025f);
    Perturb(c, 0.002f, 0.05f, 9);
    ASSERT_GE(c.size(), 4096u);  // threads are used from this size on
    std::mt19937 rng(2);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    CylinderFitParams p;
    p.sac.max_iterations = 300;
    p.sac.p_success = 0.999999;
    for (std::size_t i = 0; i < c.size(); ++i) {
        p.sac.sample_weights.push_back(u(rng));
        p.sac.score_weights.push_back(u(rng));
    }
    p.sac.num_threads = 1;
    const CylinderFit a = FitCylinder(c, {}, p);
    const CylinderFit b = FitCylinder(c, {}, p);
    p.sac.num_threads = 4;
    const CylinderFit t = FitCylinder(c, {}, p);
    ASSERT_TRUE(a.found);
    for (const CylinderFit* x : {&b, &t}) {
        EXPECT_EQ(x->inliers, a.inliers);
        EXPECT_EQ(x->iterations, a.iterations);
        EXPECT_EQ(x->axis, a.axis);
        EXPECT_EQ(x->radius, a.radius);
    }
    p.sac.seed = 2;
    p.sac.num_threads = 1;
    const CylinderFit other = FitCylinder(c, {}, p);
    EXPECT_NE(other.iterations * 1000.0f + other.radius, a.iterations * 1000.0f + a.radius);
}

TEST(WeightedSampling, RsdWeightsPreferTheRightSurface) {
    const RsdSamplingParams p;
    EXPECT_FLOAT_EQ(RsdSamplingWeight(0.2f, SampledSurface::kPlanar, p), 1.0f);
    EXPECT_FLOAT_EQ(RsdSamplingWeight(0.03f, SampledSurface::kPlanar, p), p.floor_weight);
    EXPECT_FLOAT_EQ(RsdSamplingWeight(0.03f, SampledSurface::kCurved, p), 1.0f);
    EXPECT_FLOAT_EQ(RsdSamplingWeight(0.2f, SampledSurface::kCurved, p), p.floor_weight);
    EXPECT_NEAR(RsdSamplingWeight(0.1f, SampledSurface::kCurved, p), 0.5f * (1 + p.floor_weight),
                1e-6f);
    EXPECT_FLOAT_EQ(
        RsdSamplingWeight(std::numeric_limits<float>::quiet_NaN(), SampledSurface::kCurved, p),
        p.floor_weight);
    // RSD of a cylinder side is about its radius; of a plane the cap (0.2 m).
    PointCloud c = CylinderView({0, 0, 0}, {0, 0, 1}, 0.04f, 0.12f, {1, 0, 0.5f}, 0.003f);
    const std::vector<float> r = RsdMinRadii(c, All(c));
    ASSERT_EQ(r.size(), c.size());
    int side = 0, cap = 0;
    double side_sum = 0.0, cap_sum = 0.0;
    for (std::size_t i = 0; i < c.size(); ++i) {
        const bool is_cap = std::abs(c.normals[i].z()) > 0.9f && c.points[i].z() > 0.119f &&
                            c.points[i].head<2>().norm() < 0.02f;
        const bool is_side =
            std::abs(c.normals[i].z()) < 0.1f && c.points[i].z() > 0.03f && c.points[i].z() < 0.09f;
        if (is_cap) {
            ++cap;
            cap_sum += r[i];
        } else if (is_side) {
            ++side;
            side_sum += r[i];
        }
    }
    ASSERT_GT(side, 0);
    ASSERT_GT(cap, 0);
    EXPECT_NEAR(side_sum / side, 0.04, 0.01);
    EXPECT_GT(cap_sum / cap, 0.15);
}

TEST(WeightedSampling, RecoversABoxFromTwoFacesAndFromOneFace) {
    const Eigen::Vector3f ext(0.2f, 0.12f, 0.15f);
    const float yaw = 0.4f;
    const Eigen::Vector4f plane(0, 0, 1, 0);
    // Seen from a corner (two sides and the top) and head-on (one side and the top).
    const Eigen::Vector3f views[2] = {Eigen::Vector3f(1.0f, 0.8f, 0.8f).normalized(),
                                      Eigen::Vector3f(std::cos(yaw), std::sin(yaw), 0.7f)};
    for (int v = 0; v < 2; ++v) {
        PointCloud c = BoxView(ext, yaw, {0.3f, -0.1f}, views[v], 0.004f);
        Perturb(c, 0.0015f, 0.08f, 21 + v);
        const Indices idx = All(c);
        const std::vector<float> r = RsdMinRadii(c, idx);
        const FitGuidance g{.rsd_min_radius = r};
        FootprintRectangleParams rp;
        rp.sac.max_iterations = 50;
        const FootprintRectangle rect = FitFootprintRectangle(c, idx, plane, rp, g);
        ASSERT_TRUE(rect.found) << "view " << v;
        EXPECT_GT(rect.side_points, 100u);
        // Orientation modulo 90 degrees.
        float d =
            std::fmod(std::atan2(rect.axis.y(), rect.axis.x()) - yaw + 4.0f * kPi, 0.5f * kPi);
        d = std::min(d, 0.5f * kPi - d);
        EXPECT_LT(d, 2.0f * kPi / 180.0f) << "view " << v;
        const BoxModel box = FitUprightBox(c, idx, plane, {}, g);
        ASSERT_TRUE(box.found);
        EXPECT_NEAR(box.extents.x(), 0.2f, 0.006f) << "view " << v;
        EXPECT_NEAR(box.extents.y(), 0.12f, 0.006f) << "view " << v;
        EXPECT_NEAR(box.extents.z(), 0.15f, 0.006f) << "view " << v;
        EXPECT_NEAR(box.center.x(), 0.3f, 0.006f) << "view " << v;
        EXPECT_NEAR(box.center.y(), -0.1f, 0.006f) << "view " << v;
    }
}

TEST(WeightedSampling, RecoversATiltedCylinderWithRsdWeights) {
    const Eigen::Vector3f axis = Eigen::Vector3f(0.5f, 0.2f, 0.8f).normalized();
    const Eigen::Vector3f base(0.1f, 0.2f, 0.05f);
    // One-sided partial view: the half facing the viewer, its top cap included.
    PointCloud c =
        CylinderView(base, axis, 0.045f, 0.16f, Eigen::Vector3f(-0.6f, 1.0f, 0.9f), 0.004f);
    Perturb(c, 0.0015f, 0.08f, 4);
    const Indices idx = All(c);
    const std::vector<float> r = RsdMinRadii(c, idx);
    CylinderModelParams p;
    p.sac.num_threads = 1;
    p.sac.max_iterations = 100;
    const CylinderModel m =
        FitObjectCylinder(c, idx, Eigen::Vector4f::Zero(), p, {.rsd_min_radius = r});
    ASSERT_TRUE(m.found);
    EXPECT_LT(std::acos(std::min(1.0f, std::abs(m.axis.dot(axis)))), 2.0f * kPi / 180.0f);
    EXPECT_NEAR(m.radius, 0.045f, 0.002f);
    // The axis passes through the true one.
    const Eigen::Vector3f w = m.center - base;
    EXPECT_LT((w - w.dot(axis) * axis).norm(), 0.003f);
}

TEST(WeightedSampling, RsdWeightsNeedFewerSamples) {
    // A short can seen from above: as many lid points as side points. Uniform sampling draws
    // many lid points (their normals give no axis); curved-preferring sampling mostly side points.
    PointCloud c = CylinderView({0, 0, 0}, {0, 0, 1}, 0.05f, 0.05f, {1, 0, 2.5f}, 0.003f);
    Finish(c);
    Perturb(c, 0.001f, 0.015f, 8);
    const Indices idx = All(c);
    const std::vector<float> r = RsdMinRadii(c, idx);
    std::vector<float> w(c.size());
    for (std::size_t i = 0; i < c.size(); ++i) {
        w[i] = RsdSamplingWeight(r[i], SampledSurface::kCurved, {});
    }
    long uniform = 0, weighted = 0;
    for (std::uint64_t seed = 1; seed <= 10; ++seed) {
        CylinderFitParams p;
        p.sac.seed = seed;
        p.sac.num_threads = 1;
        p.sac.distance_threshold = 0.004f;
        p.max_radius = 0.3f;
        const CylinderFit a = FitCylinder(c, idx, p);
        p.sac.sample_weights = w;
        const CylinderFit b = FitCylinder(c, idx, p);
        ASSERT_TRUE(a.found && b.found);
        EXPECT_NEAR(b.radius, 0.05f, 0.002f) << "seed " << seed;
        uniform += a.iterations;
        weighted += b.iterations;
    }
    EXPECT_LT(weighted * 2, uniform) << weighted << " vs " << uniform;
}

}  // namespace
}  // namespace multicue

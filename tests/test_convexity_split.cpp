#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include <gtest/gtest.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/segmentation/convexity_split.hpp"

namespace multicue {
namespace {

const Eigen::Vector4f kTable(0.0f, 0.0f, 1.0f, 0.0f);  // z = 0, normal up

struct Scene {
    PointCloud cloud;
    Indices object;              // every point
    std::vector<Indices> parts;  // surface parts, as region growing would give them
    std::vector<int> label;      // per point: which real object it belongs to
};

void AddPoint(Scene& s, const Eigen::Vector3f& p, const Eigen::Vector3f& n, std::size_t part,
              int label) {
    const auto i = static_cast<Index>(s.cloud.points.size());
    s.cloud.points.push_back(p);
    s.cloud.normals.push_back(n.normalized());
    s.object.push_back(i);
    if (s.parts.size() <= part) s.parts.resize(part + 1);
    s.parts[part].push_back(i);
    s.label.push_back(label);
}

// A hemispherical bowl (radius 6 cm, wall 4 mm) standing on the table, seen from 45 degrees above
// its front: the outer front wall and the inside behind it, down to where the front rim hides it.
// Normals point to the viewer: outwards on the outer wall, inwards on the inside. The inside is
// cut into three vertical strips, as the arcs of normal-angle region growing would cut it.
Scene HollowBowl() {
    constexpr float kOuter = 0.06f;
    constexpr float kInner = 0.056f;
    constexpr float kStep = 0.003f;
    const Eigen::Vector3f centre(0.0f, 0.0f, kOuter);  // of the sphere; the rim lies at its height
    const Eigen::Vector3f viewer = centre + Eigen::Vector3f(0.0f, -0.5f, 0.5f);
    Scene s;
    for (const float radius : {kOuter, kInner}) {
        const bool inside = radius == kInner;
        const int rings =
            static_cast<int>(std::ceil(radius * std::numbers::pi_v<float> / 2 / kStep));
        for (int r = 0; r <= rings; ++r) {
            const float elevation = std::numbers::pi_v<float> / 2 * static_cast<float>(r) / rings;
            const int around = std::max(1, static_cast<int>(2 * std::numbers::pi_v<float> * radius *
                                                            std::sin(elevation) / kStep));
            for (int a = 0; a < around; ++a) {
                const float azimuth =
                    2 * std::numbers::pi_v<float> * static_cast<float>(a) / around;
                const Eigen::Vector3f dir(std::sin(elevation) * std::cos(azimuth),
                                          std::sin(elevation) * std::sin(azimuth),
                                          -std::cos(elevation));
                const Eigen::Vector3f p = centre + radius * dir;
                const Eigen::Vector3f n = inside ? Eigen::Vector3f(-dir) : dir;
                if (n.dot(viewer - p) <= 0.0f) continue;  // facing away
                if (inside) {
                    // The line of sight must leave the bowl through its opening, not the front rim.
                    const float t = (centre.z() - p.z()) / (viewer.z() - p.z());
                    const Eigen::Vector3f q = p + t * (viewer - p);
                    if ((q - centre).head<2>().norm() >= kInner) continue;
                }
                std::size_t part = 0;
                if (inside) part = p.x() < -kOuter / 3 ? 1 : (p.x() > kOuter / 3 ? 3 : 2);
                AddPoint(s, p, n, part, 0);
            }
        }
    }
    s.cloud.SetUnorganized();
    return s;
}

// A 20 x 15 x 6 cm box with a 12 x 10 x 5 cm box on top, seen from above, front and right; one part
// per visible face. The faces of the two boxes meet in concave creases.
Scene StackedBoxes() {
    constexpr float kStep = 0.004f;
    Scene s;
    std::size_t part = 0;
    auto face = [&](const Eigen::Vector3f& origin, const Eigen::Vector3f& u,
                    const Eigen::Vector3f& v, const Eigen::Vector3f& normal, int label,
                    const Eigen::Vector2f& hole_lo = Eigen::Vector2f::Constant(1.0f),
                    const Eigen::Vector2f& hole_hi = Eigen::Vector2f::Constant(-1.0f)) {
        const int nu = static_cast<int>(u.norm() / kStep);
        const int nv = static_cast<int>(v.norm() / kStep);
        for (int i = 0; i <= nu; ++i) {
            for (int j = 0; j <= nv; ++j) {
                const Eigen::Vector3f p =
                    origin + u * (static_cast<float>(i) / nu) + v * (static_cast<float>(j) / nv);
                const bool under = p.x() > hole_lo.x() && p.x() < hole_hi.x() &&
                                   p.y() > hole_lo.y() && p.y() < hole_hi.y();
                if (!under) AddPoint(s, p, normal, part, label);
            }
        }
        ++part;
    };
    const Eigen::Vector3f x = Eigen::Vector3f::UnitX();
    const Eigen::Vector3f y = Eigen::Vector3f::UnitY();
    const Eigen::Vector3f z = Eigen::Vector3f::UnitZ();
    // Lower box: top (without the upper box's footprint), front, right side.
    face({-0.1f, -0.075f, 0.06f}, 0.2f * x, 0.15f * y, z, 0, {-0.06f, -0.05f}, {0.06f, 0.05f});
    face({-0.1f, -0.075f, 0.0f}, 0.2f * x, 0.06f * z, -y, 0);
    face({0.1f, -0.075f, 0.0f}, 0.15f * y, 0.06f * z, x, 0);
    // Upper box: top, front, right side.
    face({-0.06f, -0.05f, 0.11f}, 0.12f * x, 0.1f * y, z, 1);
    face({-0.06f, -0.05f, 0.06f}, 0.12f * x, 0.05f * z, -y, 1);
    face({0.06f, -0.05f, 0.06f}, 0.1f * y, 0.05f * z, x, 1);
    s.cloud.SetUnorganized();
    return s;
}

// True when every group holds the points of one real object only.
bool GroupsArePure(const Scene& s, const std::vector<Indices>& groups) {
    return std::all_of(groups.begin(), groups.end(), [&](const Indices& g) {
        return std::all_of(g.begin(), g.end(),
                           [&](Index i) { return s.label[i] == s.label[g.front()]; });
    });
}

TEST(ConvexitySplit, HollowBowlStaysWhole) {
    const Scene bowl = HollowBowl();
    ASSERT_EQ(bowl.parts.size(), 4u);
    for (const auto& part : bowl.parts) ASSERT_GT(part.size(), 150u);

    // The rules (not the learned classifier): the inside meets itself in concave bends, and
    // without the bend rule the bowl falls apart.
    ConvexitySplitParams rules;
    rules.learned = false;
    ConvexitySplitParams no_bends = rules;
    no_bends.bend_angle_deg = 0.0f;
    const auto split = SplitByConvexity(bowl.cloud, bowl.object, bowl.parts, no_bends, kTable);
    EXPECT_GE(split.objects.size(), 2u);
    EXPECT_EQ(split.bend_joins, 0u);
    // Without a support plane there are no heights, so no bends are joined either.
    EXPECT_GE(SplitByConvexity(bowl.cloud, bowl.object, bowl.parts, rules).objects.size(), 2u);

    const auto whole = SplitByConvexity(bowl.cloud, bowl.object, bowl.parts, rules, kTable);
    ASSERT_EQ(whole.objects.size(), 1u);
    EXPECT_EQ(whole.objects[0], bowl.object);
    EXPECT_GE(whole.bend_joins, 1u);
    EXPECT_GE(whole.concave_borders, 1u);
}

TEST(ConvexitySplit, StackedBoxesSplitEvenWhenEveryCreaseCountsAsABend) {
    const Scene boxes = StackedBoxes();
    for (const float bend : {0.0f, 35.0f, 180.0f}) {
        SCOPED_TRACE(bend);
        ConvexitySplitParams params;
        params.learned = false;
        params.bend_angle_deg = bend;
        const auto split = SplitByConvexity(boxes.cloud, boxes.object, boxes.parts, params, kTable);
        ASSERT_EQ(split.objects.size(), 2u);
        EXPECT_TRUE(GroupsArePure(boxes, split.objects));
        // The upper box rises 5 cm above the lower one: never joined across the crease.
        EXPECT_EQ(split.bend_joins, 0u);
        EXPECT_GE(split.concave_borders, 1u);
    }
}

// The learned classifier (the default with a support plane): same objects as the rules here.
TEST(ConvexitySplit, LearnedClassifierKeepsTheBowlWholeAndSplitsTheStackedBoxes) {
    Scene bowl = HollowBowl();
    bowl.cloud.sensor_origin = Eigen::Vector3f(0.0f, -0.5f, 0.56f);
    const auto whole = SplitByConvexity(bowl.cloud, bowl.object, bowl.parts, {}, kTable);
    ASSERT_EQ(whole.objects.size(), 1u);
    EXPECT_EQ(whole.objects[0], bowl.object);
    EXPECT_EQ(whole.bend_joins, 0u);  // no rule at work

    Scene boxes = StackedBoxes();
    boxes.cloud.sensor_origin = Eigen::Vector3f(0.4f, -0.6f, 0.6f);
    const auto split = SplitByConvexity(boxes.cloud, boxes.object, boxes.parts, {}, kTable);
    ASSERT_EQ(split.objects.size(), 2u);
    EXPECT_TRUE(GroupsArePure(boxes, split.objects));
    // Each object's parts are the given parts that lie in it, three faces each.
    ASSERT_EQ(split.parts.size(), 2u);
    for (std::size_t o = 0; o < 2; ++o) {
        EXPECT_EQ(split.parts[o].size(), 3u);
        std::size_t points = 0;
        for (const auto& part : split.parts[o]) points += part.size();
        EXPECT_EQ(points, split.objects[o].size());
    }
    // A threshold of almost 1 joins nothing: six faces, and each group is one face or folded
    // into a neighbour when too small.
    ConvexitySplitParams strict;
    strict.classifier.threshold = 0.999999f;
    strict.min_object_points = 1;
    EXPECT_EQ(
        SplitByConvexity(boxes.cloud, boxes.object, boxes.parts, strict, kTable).objects.size(),
        6u);
}

TEST(ConvexitySplit, RejectsBadParametersAndMissingNormals) {
    const Scene bowl = HollowBowl();
    ConvexitySplitParams p;
    p.bend_angle_deg = -1.0f;
    EXPECT_THROW(SplitByConvexity(bowl.cloud, bowl.object, bowl.parts, p), InvalidArgument);
    p = {};
    p.bend_angle_deg = 181.0f;
    EXPECT_THROW(SplitByConvexity(bowl.cloud, bowl.object, bowl.parts, p), InvalidArgument);
    p = {};
    p.max_top_difference = -0.01f;
    EXPECT_THROW(SplitByConvexity(bowl.cloud, bowl.object, bowl.parts, p), InvalidArgument);
    p = {};
    p.classifier.threshold = 1.0f;
    EXPECT_THROW(SplitByConvexity(bowl.cloud, bowl.object, bowl.parts, p), InvalidArgument);
    p = {};
    p.fold.min_fold_deg = 0.0f;
    EXPECT_THROW(SplitByConvexity(bowl.cloud, bowl.object, bowl.parts, p), InvalidArgument);
    p = {};
    p.patch_size = 0.0f;
    EXPECT_THROW(SplitByConvexity(bowl.cloud, bowl.object, bowl.parts, p), InvalidArgument);
    PointCloud bare = bowl.cloud;
    bare.normals.clear();
    EXPECT_THROW(SplitByConvexity(bare, bowl.object, bowl.parts, {}), DataError);
}

TEST(ConvexitySplit, EmptyObjectGivesNoGroupsAndOnePartGivesTheObject) {
    const Scene bowl = HollowBowl();
    EXPECT_TRUE(SplitByConvexity(bowl.cloud, {}, bowl.parts, {}, kTable).objects.empty());
    const auto one = SplitByConvexity(bowl.cloud, bowl.object, {bowl.object}, {}, kTable);
    ASSERT_EQ(one.objects.size(), 1u);
    EXPECT_EQ(one.objects[0], bowl.object);
}

}  // namespace
}  // namespace multicue

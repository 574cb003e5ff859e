// Grouping by models (thesis section 5.4.1) on simulated frames with exact ground truth: objects
// that segmentation kept together are split by their models, one object seen as two surfaces is
// merged, and single objects stay whole.

#include <gtest/gtest.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/reconstruction/model_grouping.hpp"
#include "test_scene_helpers.hpp"

namespace multicue {
namespace {

using test::Shape;

ModelParams Models() {
    ModelParams p;
    p.num_threads = 1;
    return p;
}

// The two objects a split made: each (nearly) one shape, and different shapes.
void ExpectSplitIntoShapes(const test::SimulatedFrame& f, const std::vector<PerceivedObject>& out,
                           const GroupingResult& g) {
    ASSERT_EQ(out.size(), 2u);
    EXPECT_EQ(g.changed, (std::vector<std::size_t>{0, 1}));
    EXPECT_EQ(g.split, 1u);
    const auto [purity_a, shape_a] = test::Purity(f, out[0].indices);
    const auto [purity_b, shape_b] = test::Purity(f, out[1].indices);
    EXPECT_GT(purity_a, 0.9);
    EXPECT_GT(purity_b, 0.9);
    EXPECT_NE(shape_a, shape_b);
    for (const auto& o : out) {
        EXPECT_TRUE(std::is_sorted(o.indices.begin(), o.indices.end()));
        EXPECT_FALSE(o.parts.empty());
    }
}

TEST(ModelGrouping, StackedBoxesAreCutAtTheLowerTopFace) {
    // A box standing on a larger one: two horizontal faces 10 cm and 18 cm above the table.
    const auto f = test::ScanShapes({{Shape::kBox, {0.22f, 0.16f, 0.10f}, {0, 0, 0}},
                                     {Shape::kBox, {0.12f, 0.10f, 0.08f}, {0, 0.01f, 0.10f}}});
    std::vector<PerceivedObject> objects{test::MergedObject(f, {0, 1}, Category::kBox)};
    const GroupingResult g = SplitStackedBoxes(f.cloud, objects, f.plane, Models(), 150);
    ExpectSplitIntoShapes(f, objects, g);
    EXPECT_EQ(g.allowed, (std::vector<Category>{Category::kBox, Category::kFlat}));
    // The new objects wait to be categorised and modelled again.
    EXPECT_EQ(objects[0].category.category, Category::kNone);
}

TEST(ModelGrouping, ASingleBoxIsNotStackedAndBadParametersAreRefused) {
    const auto f = test::ScanShapes({{Shape::kBox, {0.2f, 0.15f, 0.12f}, {0, 0, 0}}});
    std::vector<PerceivedObject> objects{test::MergedObject(f, {0}, Category::kBox)};
    const Indices before = objects[0].indices;
    EXPECT_TRUE(SplitStackedBoxes(f.cloud, objects, f.plane, Models(), 150).changed.empty());
    ASSERT_EQ(objects.size(), 1u);
    EXPECT_EQ(objects[0].indices, before);
    EXPECT_EQ(objects[0].category.category, Category::kBox);  // kept as it was
    ModelParams bad = Models();
    bad.stacked.min_step = 0.0f;
    EXPECT_THROW(SplitStackedBoxes(f.cloud, objects, f.plane, bad, 150), InvalidArgument);
    std::vector<PerceivedObject> none;
    EXPECT_THROW(SplitStackedBoxes(f.cloud, none, f.plane, bad, 150), InvalidArgument);
}

TEST(ModelGrouping, StackedSplitNeedsAPlaneAndBoxes) {
    const auto f = test::ScanShapes({{Shape::kBox, {0.22f, 0.16f, 0.10f}, {0, 0, 0}},
                                     {Shape::kBox, {0.12f, 0.10f, 0.08f}, {0, 0.01f, 0.10f}}});
    std::vector<PerceivedObject> objects{test::MergedObject(f, {0, 1}, Category::kBox)};
    EXPECT_TRUE(SplitStackedBoxes(f.cloud, objects, Eigen::Vector4f::Zero(), Models(), 150)
                    .changed.empty());
    objects[0].category.category = Category::kCylinder;
    EXPECT_TRUE(SplitStackedBoxes(f.cloud, objects, f.plane, Models(), 150).changed.empty());
    objects[0].category.category = Category::kBox;
    ModelParams off = Models();
    off.stacked.enabled = false;
    EXPECT_TRUE(SplitStackedBoxes(f.cloud, objects, f.plane, off, 150).changed.empty());
    // Pieces smaller than the smallest object cancel the split.
    EXPECT_TRUE(SplitStackedBoxes(f.cloud, objects, f.plane, Models(), 1000000).changed.empty());
    EXPECT_EQ(objects.size(), 1u);
}

TEST(ModelGrouping, TouchingBoxesThatOneBoxExplainsPoorlyAreSplit) {
    // A tall and a low box side by side, touching: one upright box leaves the low box's top far
    // from its surface.
    const auto f = test::ScanShapes({{Shape::kBox, {0.10f, 0.10f, 0.18f}, {-0.05f, 0.05f, 0}},
                                     {Shape::kBox, {0.10f, 0.20f, 0.07f}, {0.05f, 0, 0}}});
    ModelParams p = Models();
    p.several_min_ratio = 0.0f;  // whatever the part count says
    std::vector<PerceivedObject> objects{test::MergedObject(f, {0, 1}, Category::kBox)};
    const GroupingResult g = SplitTouchingBoxes(f.cloud, objects, f.plane, p, 150);
    ExpectSplitIntoShapes(f, objects, g);
    EXPECT_EQ(g.allowed, (std::vector<Category>{Category::kBox, Category::kFlat}));
    // Deterministic: the same split again.
    std::vector<PerceivedObject> again{test::MergedObject(f, {0, 1}, Category::kBox)};
    SplitTouchingBoxes(f.cloud, again, f.plane, p, 150);
    ASSERT_EQ(again.size(), 2u);
    EXPECT_EQ(again[0].indices, objects[0].indices);
    EXPECT_EQ(again[1].parts, objects[1].parts);
    // The splits are tried on any number of threads with the same result.
    for (const int threads : {1, 2, 3}) {
        ModelParams q = p;
        q.num_threads = threads;
        std::vector<PerceivedObject> threaded{test::MergedObject(f, {0, 1}, Category::kBox)};
        SplitTouchingBoxes(f.cloud, threaded, f.plane, q, 150);
        ASSERT_EQ(threaded.size(), 2u) << threads;
        EXPECT_EQ(threaded[0].indices, objects[0].indices) << threads;
        EXPECT_EQ(threaded[1].indices, objects[1].indices) << threads;
    }

    // One box explains a single box: nothing to split.
    const auto one = test::ScanShapes({{Shape::kBox, {0.2f, 0.12f, 0.10f}, {0, 0, 0}}});
    std::vector<PerceivedObject> single{test::MergedObject(one, {0}, Category::kBox)};
    EXPECT_TRUE(SplitTouchingBoxes(one.cloud, single, one.plane, p, 150).changed.empty());
    EXPECT_EQ(single.size(), 1u);
}

TEST(ModelGrouping, TouchingBoxSplitFollowsThePartCountModelAndItsParameters) {
    const auto f = test::ScanShapes({{Shape::kBox, {0.10f, 0.10f, 0.18f}, {-0.05f, 0, 0}},
                                     {Shape::kBox, {0.10f, 0.12f, 0.07f}, {0.05f, 0, 0}}});
    std::vector<PerceivedObject> objects{test::MergedObject(f, {0, 1}, Category::kBox)};
    ModelParams p = Models();
    // A Poisson model that expects many parts per object finds one object likelier.
    p.part_counts.flat_mean = 40.0;
    p.part_counts.round_mean = 40.0;
    p.part_counts.other_mean = 40.0;
    EXPECT_TRUE(SplitTouchingBoxes(f.cloud, objects, f.plane, p, 150).changed.empty());
    p = Models();
    p.several_min_ratio = 0.0f;
    p.touching.enabled = false;
    EXPECT_TRUE(SplitTouchingBoxes(f.cloud, objects, f.plane, p, 150).changed.empty());
    p.touching.enabled = true;
    p.touching.max_parts = 1;
    EXPECT_THROW(SplitTouchingBoxes(f.cloud, objects, f.plane, p, 150), InvalidArgument);
    p = Models();
    p.several_min_ratio = -1.0f;
    EXPECT_THROW(SplitTouchingBoxes(f.cloud, objects, f.plane, p, 150), InvalidArgument);
}

TEST(ModelGrouping, TouchingRoundObjectsGetACylinderEach) {
    // A narrow tall can beside a wide low tin: one cylinder explains only one of them.
    const auto f = test::ScanShapes({{Shape::kCylinder, {0.065f, 0.065f, 0.06f}, {0, 0, 0}},
                                     {Shape::kCylinder, {0.03f, 0.03f, 0.15f}, {0.115f, 0, 0}}});
    ModelParams p = Models();
    p.several_min_ratio = 0.0f;
    std::vector<PerceivedObject> objects{test::MergedObject(f, {0, 1}, Category::kCylinder)};
    const GroupingResult g = SplitTouchingRound(f.cloud, objects, f.plane, p, 150);
    ExpectSplitIntoShapes(f, objects, g);
    EXPECT_TRUE(g.allowed.empty());

    // A single can is explained by one cylinder; boxes are not round.
    const auto can = test::ScanShapes({{Shape::kCylinder, {0.04f, 0.04f, 0.12f}, {0, 0, 0}}});
    std::vector<PerceivedObject> single{test::MergedObject(can, {0}, Category::kCylinder)};
    EXPECT_TRUE(SplitTouchingRound(can.cloud, single, can.plane, p, 150).changed.empty());
    std::vector<PerceivedObject> boxy{test::MergedObject(f, {0, 1}, Category::kBox)};
    EXPECT_TRUE(SplitTouchingRound(f.cloud, boxy, f.plane, p, 150).changed.empty());
    p.touching.round_enabled = false;
    std::vector<PerceivedObject> again{test::MergedObject(f, {0, 1}, Category::kCylinder)};
    EXPECT_TRUE(SplitTouchingRound(f.cloud, again, f.plane, p, 150).changed.empty());
}

TEST(ModelGrouping, TouchingRoundSplitsDoNotDependOnTheThreadCount) {
    // Several objects judged in parallel: the split pair takes its place among the others.
    const auto f = test::ScanShapes({{Shape::kCylinder, {0.065f, 0.065f, 0.06f}, {0, 0, 0}},
                                     {Shape::kCylinder, {0.03f, 0.03f, 0.15f}, {0.115f, 0, 0}},
                                     {Shape::kCylinder, {0.04f, 0.04f, 0.12f}, {-0.2f, 0.1f, 0}},
                                     {Shape::kBox, {0.08f, 0.1f, 0.06f}, {0.2f, 0.2f, 0}}});
    auto objects_for = [&] {
        return std::vector<PerceivedObject>{test::MergedObject(f, {2}, Category::kCylinder),
                                            test::MergedObject(f, {0, 1}, Category::kCylinder),
                                            test::MergedObject(f, {3}, Category::kBox)};
    };
    std::vector<std::vector<PerceivedObject>> results;
    std::vector<GroupingResult> groupings;
    for (int threads : {1, 2, 0}) {
        ModelParams p = Models();
        p.several_min_ratio = 0.0f;
        p.num_threads = threads;
        std::vector<PerceivedObject> objects = objects_for();
        groupings.push_back(SplitTouchingRound(f.cloud, objects, f.plane, p, 150));
        results.push_back(std::move(objects));
    }
    ASSERT_EQ(results[0].size(), 4u);
    EXPECT_EQ(results[0][0].indices, objects_for()[0].indices);
    EXPECT_EQ(results[0].back().indices, objects_for()[2].indices);
    for (std::size_t r = 1; r < results.size(); ++r) {
        EXPECT_EQ(groupings[r].changed, groupings[0].changed);
        ASSERT_EQ(results[r].size(), results[0].size());
        for (std::size_t k = 0; k < results[0].size(); ++k) {
            EXPECT_EQ(results[r][k].indices, results[0][k].indices);
            EXPECT_EQ(results[r][k].parts, results[0][k].parts);
        }
    }
}

// An object whose model is the cylinder (center, radius, height) along z.
PerceivedObject WithCylinder(Indices indices, const Eigen::Vector3f& center, float radius,
                             float height, bool accepted = true) {
    PerceivedObject o;
    o.indices = std::move(indices);
    o.parts = {o.indices};
    CylinderModel c;
    c.found = true;
    c.center = center;
    c.radius = radius;
    c.height = height;
    o.model.cylinder = c;
    o.model.accepted = accepted;
    o.category.category = Category::kCylinder;
    return o;
}

TEST(ModelGrouping, CoaxialCylindersOfOneRadiusThatOverlapAreOneObject) {
    std::vector<PerceivedObject> objects{
        WithCylinder({0, 2, 4}, {0, 0, 0.05f}, 0.05f, 0.10f),
        WithCylinder({1, 3}, {0.003f, 0, 0.04f}, 0.046f, 0.08f),  // the inside of the same pot
        WithCylinder({5}, {0, 0, 0.30f}, 0.05f, 0.10f),           // a second pot stacked above
        WithCylinder({6}, {0.001f, 0, 0.05f}, 0.02f, 0.10f),      // a thin can on the axis
    };
    const GroupingResult g = MergeConcentricObjects(objects, ConcentricMergeParams{});
    ASSERT_EQ(objects.size(), 3u);
    EXPECT_EQ(g.changed, (std::vector<std::size_t>{0}));
    EXPECT_EQ(g.merged, 1u);
    EXPECT_TRUE(g.allowed.empty());
    EXPECT_EQ(objects[0].indices, (Indices{0, 1, 2, 3, 4}));
    EXPECT_EQ(objects[0].parts.size(), 2u);
    EXPECT_EQ(objects[1].indices, (Indices{5}));
    EXPECT_EQ(objects[2].indices, (Indices{6}));
    EXPECT_TRUE(CoaxialSameRadius(*objects[1].model.cylinder, *objects[1].model.cylinder, {}));
}

TEST(ModelGrouping, ConcentricMergeIsTransitiveAndChecksItsParameters) {
    std::vector<PerceivedObject> objects{
        WithCylinder({0}, {0, 0, 0.05f}, 0.05f, 0.10f),
        WithCylinder({1}, {0, 0, 0.12f}, 0.05f, 0.06f),
        WithCylinder({2}, {0, 0, 0.17f}, 0.05f, 0.06f),
    };
    auto copy = objects;
    EXPECT_EQ(MergeConcentricObjects(copy, {}).merged, 2u);
    EXPECT_EQ(copy.size(), 1u);
    copy = objects;
    EXPECT_TRUE(MergeConcentricObjects(copy, {.enabled = false}).changed.empty());
    EXPECT_EQ(copy.size(), 3u);
    EXPECT_THROW(MergeConcentricObjects(copy, {.distance = -0.01f}), InvalidArgument);
    std::vector<PerceivedObject> none;
    EXPECT_THROW(MergeConcentricObjects(none, {.angle_deg = -1.0f}), InvalidArgument);
    EXPECT_TRUE(MergeConcentricObjects(none, {}).changed.empty());
}

TEST(ModelGrouping, ObjectsInsideAContainerJoinIt) {
    // A bowl's accepted cylinder (radius 6 cm, 8 cm high); its loose bottom inside it, a box
    // beside it.
    PointCloud cloud;
    auto add = [&](const Eigen::Vector3f& p) {
        cloud.points.push_back(p);
        return static_cast<Index>(cloud.points.size() - 1);
    };
    Indices wall, bottom, beside;
    for (int a = 0; a < 36; ++a) {
        const float t = static_cast<float>(a) * 0.1745f;
        wall.push_back(add({0.06f * std::cos(t), 0.06f * std::sin(t), 0.04f}));
    }
    for (int k = 0; k < 20; ++k) bottom.push_back(add({0.002f * k - 0.02f, 0.01f, 0.005f}));
    for (int k = 0; k < 20; ++k) beside.push_back(add({0.3f + 0.002f * k, 0.0f, 0.05f}));
    cloud.SetUnorganized();
    std::vector<PerceivedObject> objects{
        WithCylinder(bottom, {0, 0, 0.04f}, 0.01f, 0.01f),
        WithCylinder(wall, {0, 0, 0.04f}, 0.06f, 0.08f),
        WithCylinder(beside, {0.32f, 0, 0.05f}, 0.02f, 0.1f),
    };
    auto copy = objects;
    const GroupingResult g = MergeContainedObjects(cloud, copy, ContainedMergeParams{});
    ASSERT_EQ(copy.size(), 2u);
    EXPECT_EQ(g.changed, (std::vector<std::size_t>{0}));
    EXPECT_EQ(copy[0].indices.size(), wall.size() + bottom.size());  // the container's place
    EXPECT_EQ(copy[1].indices, beside);
    // A rejected container model holds nothing.
    copy = objects;
    copy[1].model.accepted = false;
    EXPECT_TRUE(MergeContainedObjects(cloud, copy, {}).changed.empty());
    EXPECT_EQ(copy.size(), 3u);
    EXPECT_THROW(MergeContainedObjects(cloud, copy, {.min_share = 0.0f}), InvalidArgument);
    EXPECT_TRUE(MergeContainedObjects(cloud, copy, {.enabled = false}).changed.empty());
}

}  // namespace
}  // namespace multicue

// The table-top pipeline on synthetic scenes with exact ground truth, and its output contract.

#include <fstream>
#include <limits>
#include <map>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "multicue/core/exceptions.hpp"
#include "multicue/io/config.hpp"
#include "multicue/io/file_utils.hpp"
#include "multicue/io/pcd.hpp"
#include "multicue/io/ply.hpp"
#include "multicue/sim/tabletop_scene.hpp"
#include "multicue/system/perceive.hpp"
#include "multicue/system/perceive_output.hpp"
#include "multicue/system/perceive_views.hpp"
#include "test_util.hpp"

namespace multicue {
namespace {

struct Scene {
    sim::TableTopScene scene;
    PointCloud cloud;
};

const Scene& DemoScene() {
    static const Scene s = [] {
        Scene r;
        r.scene = sim::MakeDemoScene();
        sim::ScanParams p;
        p.T_world_camera = sim::DefaultCameraPose(r.scene);
        r.cloud = sim::ScanTableTopScene(r.scene, p);
        return r;
    }();
    return s;
}

// Best F-measure of each ground-truth object against the predicted objects.
// The perceived object holding most points of ground-truth label `label` (0 if none).
std::uint32_t MajorityObject(const PointCloud& cloud, const PerceiveResult& r,
                             std::uint32_t label) {
    std::map<std::uint32_t, std::size_t> votes;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        if (cloud.labels[i] == label && r.point_objects[i] != 0) ++votes[r.point_objects[i]];
    }
    std::uint32_t best = 0;
    std::size_t count = 0;
    for (const auto& [id, n] : votes) {
        if (n > count) {
            best = id;
            count = n;
        }
    }
    return best;
}

std::map<std::uint32_t, double> BestOverlap(const PointCloud& truth, const PerceiveResult& r) {
    std::map<std::uint32_t, std::map<std::uint32_t, double>> inter;
    std::map<std::uint32_t, double> gsize, psize;
    for (std::size_t i = 0; i < truth.size(); ++i) {
        const std::uint32_t g = truth.labels[i] >= 20 ? truth.labels[i] / 10 : 0;
        const std::uint32_t p = r.point_objects[i];
        if (g > 0) gsize[g] += 1;
        if (p > 0) psize[p] += 1;
        if (g > 0 && p > 0) inter[g][p] += 1;
    }
    std::map<std::uint32_t, double> best;
    for (const auto& [g, n] : gsize) {
        best[g] = 0.0;
        for (const auto& [p, c] : inter[g]) {
            const double prec = c / psize[p], rec = c / n;
            best[g] = std::max(best[g], 2 * prec * rec / (prec + rec));
        }
    }
    return best;
}

TEST(Perceive, DemoSceneObjectsCategoriesAndModels) {
    const auto& s = DemoScene();
    const PerceiveResult r = Perceive(s.cloud, PerceiveParams{});
    ASSERT_TRUE(r.support.found);
    ASSERT_EQ(r.objects.size(), 5u);
    // The support plane is the table: its normal is world up seen in the camera frame.
    const Eigen::Vector3f up_cam =
        sim::DefaultCameraPose(s.scene).linear().transpose() * Eigen::Vector3f::UnitZ();
    EXPECT_GT(r.support.plane.head<3>().dot(up_cam), std::cos(2.0f * M_PI / 180.0f));
    for (const auto& [g, f] : BestOverlap(s.cloud, r)) EXPECT_GT(f, 0.9) << "object " << g;
    // Every predicted object: boxes (objects 1-3) box or flat, cylinders (4-5) cylinder.
    for (const auto& o : r.objects) {
        std::map<std::uint32_t, int> votes;
        for (Index i : o.indices) votes[s.cloud.labels[i] / 10]++;
        const auto truth = std::max_element(votes.begin(), votes.end(),
                                            [](auto& a, auto& b) { return a.second < b.second; })
                               ->first -
                           1;
        const Category c = o.category.category;
        if (truth <= s.scene.boxes.size()) {
            EXPECT_TRUE(c == Category::kBox || c == Category::kFlat) << CategoryName(c);
            EXPECT_TRUE(o.model.box.has_value());
        } else {
            EXPECT_EQ(c, Category::kCylinder);
            ASSERT_TRUE(o.model.cylinder.has_value());
            const auto& cyl = s.scene.cylinders[truth - s.scene.boxes.size() - 1];
            EXPECT_NEAR(o.model.cylinder->radius, cyl.radius, 0.006f);
        }
        EXPECT_FALSE(o.model.mesh.triangles.empty());
    }
}

// A frame saved without its invalid pixels, in another order, is perceived as the frame was.
TEST(Perceive, AnUnorganizedDepthFrameIsPerceivedOnItsPixelGrid) {
    const auto& s = DemoScene();
    Indices order;
    for (std::size_t i = 0; i < s.cloud.size(); ++i) {
        if (s.cloud.points[i].allFinite()) order.push_back(static_cast<Index>(i));
    }
    std::reverse(order.begin(), order.end());
    PointCloud flat;
    for (Index i : order) flat.points.push_back(s.cloud.points[i]);
    flat.SetUnorganized();
    flat.sensor_origin = s.cloud.sensor_origin;
    flat.sensor_orientation = s.cloud.sensor_orientation;
    const PerceiveResult framed = Perceive(s.cloud, PerceiveParams{});
    const PerceiveResult r = Perceive(flat, PerceiveParams{});
    ASSERT_EQ(r.objects.size(), framed.objects.size());
    ASSERT_EQ(r.point_objects.size(), flat.size());
    ASSERT_FALSE(r.timings_ms.empty());
    EXPECT_EQ(r.timings_ms.front().first, "image_grid");
    for (std::size_t k = 0; k < order.size(); ++k) {
        ASSERT_EQ(r.point_objects[k], framed.point_objects[order[k]]) << "point " << k;
        ASSERT_EQ(r.point_categories[k], framed.point_categories[order[k]]);
    }
    for (const auto& o : r.objects) EXPECT_TRUE(std::is_sorted(o.indices.begin(), o.indices.end()));
    // Without the grid the same cloud goes the unorganized way.
    PerceiveParams off;
    off.image_grid = false;
    const PerceiveResult plain = Perceive(flat, off);
    EXPECT_TRUE(plain.timings_ms.empty() || plain.timings_ms.front().first != "image_grid");
}

TEST(Perceive, OccludedBoxIsOneObject) {
    // A wide box behind a tall thin one that splits it in two in the image: clustering sees two
    // fragments, the occlusion merge joins them.
    sim::TableTopScene scene;
    scene.boxes = {
        {{0.00f, 0.15f}, 0.0f, {0.30f, 0.08f, 0.12f}, {200, 60, 40, 255}},
        {{0.00f, -0.05f}, 0.0f, {0.05f, 0.05f, 0.26f}, {60, 170, 80, 255}},
    };
    sim::ScanParams sp;
    sp.T_world_camera = sim::DefaultCameraPose(scene);
    const PointCloud cloud = sim::ScanTableTopScene(scene, sp);
    PerceiveParams off;
    off.occlusion.enabled = false;
    EXPECT_EQ(Perceive(cloud, off).objects.size(), 3u);
    const PerceiveResult r = Perceive(cloud, PerceiveParams{});
    ASSERT_EQ(r.objects.size(), 2u);
    for (const auto& [g, f] : BestOverlap(cloud, r)) EXPECT_GT(f, 0.9) << "object " << g;
}

TEST(Perceive, NoTableGivesNullSupportAndObjectsFromTheWholeCloud) {
    const auto& s = DemoScene();
    Indices objects_only;
    for (std::size_t i = 0; i < s.cloud.size(); ++i) {
        if (s.cloud.labels[i] >= 20) objects_only.push_back(static_cast<Index>(i));
    }
    const PointCloud c = SelectByIndex(s.cloud, objects_only);
    const PerceiveResult r = Perceive(c, PerceiveParams{});
    EXPECT_FALSE(r.support.found);
    EXPECT_GE(r.objects.size(), 3u);
    const auto j = PerceiveResultJson("x.pcd", r);
    EXPECT_TRUE(j["support"].is_null());
}

TEST(Perceive, GuidedFitsKeepTheDemoSceneModels) {
    // RSD-guided sampling changes which samples are drawn, not what the models converge to.
    const auto& s = DemoScene();
    PerceiveParams guided;
    guided.models.guided_fits = true;
    const PerceiveResult a = Perceive(s.cloud, PerceiveParams{});
    const PerceiveResult b = Perceive(s.cloud, guided);
    ASSERT_EQ(a.objects.size(), b.objects.size());
    for (std::size_t k = 0; k < a.objects.size(); ++k) {
        const auto& ma = a.objects[k].model;
        const auto& mb = b.objects[k].model;
        EXPECT_EQ(a.objects[k].category.category, b.objects[k].category.category);
        ASSERT_EQ(ma.box.has_value(), mb.box.has_value());
        ASSERT_EQ(ma.cylinder.has_value(), mb.cylinder.has_value());
        if (ma.box) {
            EXPECT_LT((ma.box->extents - mb.box->extents).norm(), 0.005f);
        }
        if (ma.cylinder) {
            EXPECT_NEAR(ma.cylinder->radius, mb.cylinder->radius, 0.002f);
        }
        EXPECT_TRUE(a.objects[k].part_probabilities.empty());  // rule-based categories
    }
    guided.models.guided_rsd.radius = -1.0f;
    EXPECT_THROW(Perceive(s.cloud, guided), InvalidArgument);
}

TEST(PerceiveViews, OneFrameOrTwoEqualFramesKeepTheCategories) {
    const auto& s = DemoScene();
    const PerceiveParams params;
    std::vector<PerceiveResult> one{Perceive(s.cloud, params)};
    const PerceiveResult before = one.front();
    const Eigen::Isometry3f pose = sim::DefaultCameraPose(s.scene);
    FuseViewCategories({&s.cloud}, {pose}, one, params);
    std::vector<PerceiveResult> two{before, before};
    FuseViewCategories({&s.cloud, &s.cloud}, {pose, pose}, two, params);
    for (const auto* fused : {&one[0], &two[0], &two[1]}) {
        ASSERT_EQ(fused->objects.size(), before.objects.size());
        for (std::size_t k = 0; k < before.objects.size(); ++k) {
            const auto& a = before.objects[k].category;
            const auto& b = fused->objects[k].category;
            EXPECT_EQ(a.category, b.category);
            for (std::size_t c = 0; c < kNumCategories; ++c) {
                EXPECT_NEAR(a.probabilities[c], b.probabilities[c], 1e-4f);
            }
        }
        EXPECT_EQ(fused->point_objects, before.point_objects);
    }
}

TEST(PerceiveViews, TheSurerViewWinsInEveryFrame) {
    // Two registered frames of one scene; in the second, the first object is confidently another
    // category. The voxel votes give both frames the better supported category.
    const auto& s = DemoScene();
    const PerceiveParams params;
    std::vector<PerceiveResult> r{Perceive(s.cloud, params), Perceive(s.cloud, params)};
    ASSERT_FALSE(r[0].objects.empty());
    const Category first = r[0].objects[0].category.category;
    const Category other = first == Category::kOther ? Category::kSphere : Category::kOther;
    auto& changed = r[1].objects[0].category;
    changed.probabilities.fill(0.0f);
    changed.probabilities[static_cast<std::size_t>(other)] = 1.0f;
    changed.category = other;
    r[0].objects[0].category.probabilities.fill(0.0f);
    r[0].objects[0].category.probabilities[static_cast<std::size_t>(first)] = 0.6f;
    r[0].objects[0].category.probabilities[static_cast<std::size_t>(other)] = 0.4f;
    // Frame 2 seen from elsewhere: its points in its own sensor frame, its pose maps them back.
    const Eigen::Isometry3f pose = sim::DefaultCameraPose(s.scene);
    Eigen::Isometry3f move = Eigen::Isometry3f::Identity();
    move.translate(Eigen::Vector3f(0.3f, -0.1f, 0.2f));
    move.rotate(Eigen::AngleAxisf(0.4f, Eigen::Vector3f::UnitY()));
    PointCloud moved = s.cloud;
    for (auto& p : moved.points) p = move * p;
    moved.normals.clear();
    FuseViewCategories({&s.cloud, &moved}, {pose, pose * move.inverse()}, r, params);
    for (const auto& fused : r) {
        EXPECT_EQ(fused.objects[0].category.category, other);
        EXPECT_NEAR(fused.objects[0].category.probabilities[static_cast<std::size_t>(other)], 0.7f,
                    0.02f);
        const Index i = fused.objects[0].indices.front();
        EXPECT_EQ(fused.point_categories[i], static_cast<std::uint8_t>(other));
    }
    // The second frame's object was refitted for its new category only if it changed there.
    EXPECT_FALSE(r[0].objects[0].model.mesh.triangles.empty());
}

TEST(PerceiveViews, BadInput) {
    const auto& s = DemoScene();
    const PerceiveParams params;
    std::vector<PerceiveResult> r{Perceive(s.cloud, params)};
    const Eigen::Isometry3f pose = Eigen::Isometry3f::Identity();
    EXPECT_THROW(FuseViewCategories({&s.cloud, &s.cloud}, {pose}, r, params), InvalidArgument);
    EXPECT_THROW(FuseViewCategories({&s.cloud}, {pose}, r, params, {.voxel_size = 0.0f}),
                 InvalidArgument);
    Eigen::Isometry3f nan_pose = pose;
    nan_pose.translation().x() = std::numeric_limits<float>::quiet_NaN();
    EXPECT_THROW(FuseViewCategories({&s.cloud}, {nan_pose}, r, params), InvalidArgument);
    PointCloud other;
    other.points.resize(3, Eigen::Vector3f::Zero());
    EXPECT_THROW(FuseViewCategories({&other}, {pose}, r, params), InvalidArgument);
    std::vector<PerceiveResult> none;
    EXPECT_NO_THROW(FuseViewCategories({}, {}, none, params));
}

TEST(Perceive, DeterministicAndThreadIndependent) {
    const auto& s = DemoScene();
    PerceiveParams one;
    one.num_threads = 1;
    PerceiveParams two;
    two.num_threads = 2;
    const PerceiveResult a = Perceive(s.cloud, one);
    const PerceiveResult b = Perceive(s.cloud, two);
    const PerceiveResult c = Perceive(s.cloud, one);
    EXPECT_EQ(a.point_objects, b.point_objects);
    EXPECT_EQ(a.point_categories, b.point_categories);
    EXPECT_EQ(a.point_objects, c.point_objects);
    ASSERT_EQ(a.objects.size(), b.objects.size());
    for (std::size_t k = 0; k < a.objects.size(); ++k) {
        EXPECT_EQ(a.objects[k].category.probabilities, b.objects[k].category.probabilities);
    }
}

TEST(Perceive, InsideAndOutsideOfAPotAreOneObject) {
    // mOSD learn38: two pots and two cans whose inner and outer walls segment apart; their
    // cylinders share the axis, so model-based grouping joins them (section 5.4.1).
    if (!test::HasSharedData()) GTEST_SKIP() << "no shared data";
    const PointCloud cloud = io::ReadPcd(test::SharedData("scans/mosd-learn/learn38.pcd"));
    PerceiveParams params;
    // The rules' concave split, which leaves the walls apart (the learned grouping joins some).
    params.parts.convexity.learned = false;
    params.models.contained.enabled = false;  // would join them as well
    params.models.concentric.enabled = false;
    const std::size_t apart = Perceive(cloud, params).objects.size();
    params.models.concentric.enabled = true;
    const PerceiveResult merged = Perceive(cloud, params);
    EXPECT_EQ(merged.objects.size(), 4u);  // the ground truth's four objects
    EXPECT_LT(merged.objects.size(), apart);
    for (const auto& o : merged.objects) {
        EXPECT_EQ(o.id, static_cast<int>(&o - merged.objects.data()) + 1);
    }
    params.models.concentric.distance = -1.0f;
    EXPECT_THROW(Perceive(cloud, params), InvalidArgument);
}

TEST(Perceive, StackedBoxesAreSplitAtTheLowerTopFace) {
    // mOSD learn22: a box standing on a larger one, which segmentation keeps together; their two
    // horizontal faces at different heights and the better fit of two boxes split them.
    if (!test::HasSharedData()) GTEST_SKIP() << "no shared data";
    const PointCloud cloud = io::ReadPcd(test::SharedData("scans/mosd-learn/learn22.pcd"));
    auto majority = [&](const PerceiveResult& r, std::uint32_t label) {
        return MajorityObject(cloud, r, label);
    };
    PerceiveParams params;
    params.models.stacked.enabled = false;
    // The learned grouping of parts splits them by itself.
    const PerceiveResult learned = Perceive(cloud, params);
    EXPECT_NE(majority(learned, 30), majority(learned, 40));
    EXPECT_NE(majority(learned, 30), 0u);
    params.parts.convexity.learned = false;  // the rules keep them together
    const PerceiveResult together = Perceive(cloud, params);
    EXPECT_EQ(majority(together, 30), majority(together, 40));
    params.models.stacked.enabled = true;
    const PerceiveResult split = Perceive(cloud, params);
    EXPECT_NE(majority(split, 30), majority(split, 40));
    EXPECT_NE(majority(split, 30), 0u);
    params.models.stacked.min_step = 0.0f;
    EXPECT_THROW(Perceive(cloud, params), InvalidArgument);
}

TEST(Perceive, TouchingBoxesThatOneBoxExplainsPoorlyAreSplit) {
    // mOSD learn24: two boxes side by side under a third one; segmentation keeps the two
    // together, one upright box explains under half of their points, two explain nearly all.
    if (!test::HasSharedData()) GTEST_SKIP() << "no shared data";
    const PointCloud cloud = io::ReadPcd(test::SharedData("scans/mosd-learn/learn24.pcd"));
    auto majority = [&](const PerceiveResult& r, std::uint32_t label) {
        return MajorityObject(cloud, r, label);
    };
    PerceiveParams params;
    params.models.touching.enabled = false;
    const PerceiveResult together = Perceive(cloud, params);
    EXPECT_EQ(majority(together, 20), majority(together, 40));
    params.models.touching.enabled = true;
    const PerceiveResult split = Perceive(cloud, params);
    EXPECT_NE(majority(split, 20), majority(split, 40));
    EXPECT_NE(majority(split, 40), 0u);
    EXPECT_NE(majority(split, 40), majority(split, 30));  // the box on top stays apart
    for (const auto& o : split.objects) {
        if (o.id == static_cast<int>(majority(split, 40))) {
            const Category c = o.category.category;
            EXPECT_TRUE(c == Category::kBox || c == Category::kFlat) << CategoryName(c);
        }
    }
    params.models.touching.max_parts = 1;
    EXPECT_THROW(Perceive(cloud, params), InvalidArgument);
}

TEST(Perceive, CanStandingInABowlIsSplitByTwoCylinders) {
    // mOSD learn41: a can standing in a bowl, one object after segmentation (12 parts, which the
    // Poisson model finds likelier for two objects); one cylinder explains the can's parts, a
    // second one the bowl's.
    if (!test::HasSharedData()) GTEST_SKIP() << "no shared data";
    const PointCloud cloud = io::ReadPcd(test::SharedData("scans/mosd-learn/learn41.pcd"));
    auto objects_of = [&](const PerceiveResult& r, std::uint32_t label) {
        std::map<std::uint32_t, std::size_t> votes;
        for (std::size_t i = 0; i < cloud.size(); ++i) {
            if (cloud.labels[i] == label && r.point_objects[i] != 0) ++votes[r.point_objects[i]];
        }
        return votes;
    };
    PerceiveParams params;
    params.models.touching.round_enabled = false;
    // The learned grouping of parts splits them by itself; the rules keep them together.
    EXPECT_EQ(Perceive(cloud, params).objects.size(), 2u);
    params.parts.convexity.learned = false;
    const PerceiveResult together = Perceive(cloud, params);
    EXPECT_EQ(together.objects.size(), 1u);
    params.models.touching.round_enabled = true;
    const PerceiveResult split = Perceive(cloud, params);
    ASSERT_EQ(split.objects.size(), 2u);
    for (const std::uint32_t label : {20u, 30u}) {
        const auto votes = objects_of(split, label);
        std::size_t all = 0, best = 0;
        for (const auto& [id, n] : votes) {
            all += n;
            best = std::max(best, n);
        }
        EXPECT_GT(best, 9 * all / 10) << "label " << label;
    }
    // A Poisson model that expects many parts per object does not try the split.
    params.models.part_counts.other_mean = 30.0;
    params.models.part_counts.round_mean = 30.0;
    EXPECT_EQ(Perceive(cloud, params).objects.size(), 1u);
    params.models.several_min_ratio = -1.0f;
    EXPECT_THROW(Perceive(cloud, params), InvalidArgument);
}

TEST(Perceive, PiecesInsideABowlJoinIt) {
    // mOSD learn34: a bowl (ground-truth object 4: labels 40-42) whose inner wall, inner bottom
    // and outer wall segment apart; the bottom and the outer wall lie inside the inner wall's
    // surface of revolution.
    if (!test::HasSharedData()) GTEST_SKIP() << "no shared data";
    const PointCloud cloud = io::ReadPcd(test::SharedData("scans/mosd-learn/learn34.pcd"));
    auto best_share = [&](const PerceiveResult& r, std::uint32_t object) {
        std::map<std::uint32_t, std::size_t> votes;
        std::size_t all = 0, best = 0;
        for (std::size_t i = 0; i < cloud.size(); ++i) {
            if (cloud.labels[i] / 10 == object && cloud.labels[i] >= 20) {
                ++all;
                if (r.point_objects[i] != 0) best = std::max(best, ++votes[r.point_objects[i]]);
            }
        }
        return all ? static_cast<double>(best) / static_cast<double>(all) : 0.0;
    };
    PerceiveParams params;
    params.models.contained.enabled = false;
    const PerceiveResult apart = Perceive(cloud, params);
    EXPECT_LT(best_share(apart, 4), 0.8);
    params.models.contained.enabled = true;
    const PerceiveResult joined = Perceive(cloud, params);
    EXPECT_LT(joined.objects.size(), apart.objects.size());
    EXPECT_GT(best_share(joined, 4), 0.83);  // a rim strip stays apart
    for (const std::uint32_t other : {2u, 3u}) {
        EXPECT_GT(best_share(joined, other), 0.85) << "object " << other;
    }
    params.models.contained.min_share = 0.0f;
    EXPECT_THROW(Perceive(cloud, params), InvalidArgument);
}

TEST(Perceive, BadInput) {
    EXPECT_THROW(Perceive(PointCloud{}, {}), DataError);
    PointCloud nan_only;
    nan_only.points.assign(10, Eigen::Vector3f::Constant(std::numeric_limits<float>::quiet_NaN()));
    nan_only.SetUnorganized();
    EXPECT_THROW(Perceive(nan_only, {}), DataError);
    PerceiveParams bad;
    bad.clustering.tolerance = -1.0f;
    EXPECT_THROW(Perceive(DemoScene().cloud, bad), InvalidArgument);
    bad = {};
    bad.num_threads = -3;
    EXPECT_THROW(Perceive(DemoScene().cloud, bad), InvalidArgument);
}

// part-graph+rules: weight 0 reproduces the rules, weight 1 the part-graph votes.
TEST(Perceive, PartGraphPlusRulesBlendsTheTwo) {
    const auto& s = DemoScene();
    const PerceiveResult rules = Perceive(s.cloud, {});
    ASSERT_FALSE(rules.objects.empty());
    // A model of the scene's own objects, labelled sphere whatever they are.
    PointCloud cloud = s.cloud;
    auto model = std::make_shared<PartGraphModel>();
    for (const auto& o : rules.objects) {
        if (o.parts.empty()) continue;
        PointCloud c = cloud;
        if (!c.HasNormals()) c.normals.assign(c.size(), Eigen::Vector3f::UnitZ());
        model->AddObject(ComputePartDescriptors(c, o.parts), BuildPartGraph(c, o.parts),
                         Category::kSphere, {.max_parts = 4});
    }
    model->Build();
    PerceiveParams p;
    const PerceiveModels models{model};
    p.category.categoriser = Categoriser::kPartGraphRules;
    p.category.cylinder_profile_ratio = 0.0f;  // the experts' categories, not the models'
    const PerceiveResult rules_only = [&] {
        PerceiveParams r;
        r.category.cylinder_profile_ratio = 0.0f;
        return Perceive(s.cloud, r);
    }();
    p.category.part_graph_weight = 0.0f;
    const PerceiveResult w0 = Perceive(s.cloud, p, models);
    ASSERT_EQ(w0.objects.size(), rules_only.objects.size());
    for (std::size_t k = 0; k < w0.objects.size(); ++k) {
        EXPECT_EQ(w0.objects[k].category.category, rules_only.objects[k].category.category);
    }
    p.category.part_graph_weight = 1.0f;
    const PerceiveResult w1 = Perceive(s.cloud, p, models);
    for (const auto& o : w1.objects) {
        EXPECT_EQ(o.part_probabilities.size(), o.parts.size());  // one distribution per part
        if (o.category.category == Category::kNone) continue;
        EXPECT_EQ(o.category.category, Category::kSphere);
        float sum = 0.0f;
        for (float v : o.category.probabilities) sum += v;
        EXPECT_NEAR(sum, 1.0f, 1e-5f);
    }
    // Groups only inside objects and each whole object's own vote: still the model's category.
    p.category.part_graph.group_weight = 2.0f;
    for (const auto& o : Perceive(s.cloud, p, models).objects) {
        if (o.category.category != Category::kNone) {
            EXPECT_EQ(o.category.category, Category::kSphere);
        }
    }
    p.category.part_graph.group_weight = -1.0f;
    EXPECT_THROW(Perceive(s.cloud, p, models), InvalidArgument);
    p.category.part_graph.group_weight = 0.0f;
    p.category.part_graph_weight = 1.5f;
    EXPECT_THROW(Perceive(s.cloud, p, models), InvalidArgument);
    p.category.part_graph_weight = 0.5f;
    EXPECT_THROW(ParseCategoriser("votes"), InvalidArgument);
    // The learned categorisers need their model, whatever the scene.
    EXPECT_THROW(Perceive(s.cloud, p), InvalidArgument);
}

// The three experts' weighted product: one expert's weight alone gives its ranking, the
// weights set who wins a disagreement, a missing cluster expert is left out, bad weights throw.
TEST(Perceive, BlendThreeExpertsWeighsTheExperts) {
    auto dist = [](Category c, float p) {
        CategoryDistribution d{};
        for (std::size_t k = 1; k < kNumCategories; ++k) d[k] = (1.0f - p) / 5.0f;
        d[static_cast<std::size_t>(c)] = p;
        return d;
    };
    const auto rules = dist(Category::kBox, 0.6f);
    const auto part_graph = dist(Category::kFlat, 0.7f);
    const auto cluster = dist(Category::kCylinder, 0.8f);
    auto winner = [&](const Eigen::Vector3f& w, const CategoryDistribution& c) {
        const auto p = BlendThreeExperts(rules, part_graph, c, w);
        float sum = 0.0f;
        for (float v : p) sum += v;
        EXPECT_NEAR(sum, 1.0f, 1e-5f);
        EXPECT_EQ(p[0], 0.0f);
        return ArgMaxCategory(p);
    };
    EXPECT_EQ(winner({1, 0, 0}, cluster), Category::kBox);
    EXPECT_EQ(winner({0, 1, 0}, cluster), Category::kFlat);
    EXPECT_EQ(winner({0, 0, 1}, cluster), Category::kCylinder);
    EXPECT_EQ(winner({0.25f, 0.6f, 0.15f}, cluster), Category::kFlat);
    EXPECT_EQ(winner({3, 1, 1}, cluster), Category::kBox);
    // Scaling the weights changes nothing.
    EXPECT_EQ(BlendThreeExperts(rules, part_graph, cluster, {1, 2, 3}),
              BlendThreeExperts(rules, part_graph, cluster, {2, 4, 6}));
    // Without cluster rows the cluster expert is all zero and drops out.
    const CategoryDistribution none{};
    EXPECT_EQ(winner({0.25f, 0.6f, 0.15f}, none), Category::kFlat);
    EXPECT_EQ(winner({0, 0, 1}, none), Category::kBox);  // nothing else weighted: the rules
    // Equal weights agree with the two-step blend of rules and part-graph when there is no cluster.
    const auto two = BlendCategoryProbabilities(rules, part_graph, 0.5f);
    const auto three = BlendThreeExperts(rules, part_graph, none, Eigen::Vector3f::Ones());
    for (std::size_t k = 0; k < kNumCategories; ++k) EXPECT_NEAR(three[k], two[k], 1e-6f);
    EXPECT_THROW(BlendThreeExperts(rules, part_graph, cluster, {-1, 1, 1}), InvalidArgument);
    EXPECT_THROW(BlendThreeExperts(rules, part_graph, cluster, {0, 0, 0}), InvalidArgument);
    EXPECT_THROW(BlendThreeExperts(rules, part_graph, cluster,
                                   {std::numeric_limits<float>::quiet_NaN(), 1, 1}),
                 InvalidArgument);
    PerceiveParams bad;
    bad.category.expert_weights = {1, -1, 1};
    EXPECT_THROW(Perceive(DemoScene().cloud, bad), InvalidArgument);
}

TEST(PerceiveOutput, FilesFollowTheContract) {
    test::TempDir dir;
    const auto& s = DemoScene();
    const PerceiveResult r = Perceive(s.cloud, PerceiveParams{});
    WritePerceiveOutputs(dir.path(), PerceiveResultJson("scene.pcd", r),
                         PerceiveLabelsCloud(s.cloud, r), PerceiveModelsMesh(r));
    const auto j = nlohmann::json::parse(io::ReadFileBytes(dir / "result.json"));
    EXPECT_EQ(j["format"], "multicue.result/2");
    EXPECT_EQ(j["points"], s.cloud.size());
    const std::vector<std::string> names = j["categories"];
    EXPECT_EQ(names, (std::vector<std::string>{"none", "sphere", "box", "flat", "cylinder", "plate",
                                               "other"}));
    EXPECT_EQ(j["support"]["plane"].size(), 4u);
    EXPECT_GE(j["support"]["hull"].size(), 3u);
    EXPECT_TRUE(j["timings_ms"].contains("normals"));

    // labels.pcd: the input's layout, NaN points kept, ids and categories as in result.json; the
    // PCL field `label` holds the same ids as `object`.
    const PointCloud labels = io::ReadPcd(dir / "labels.pcd");
    ASSERT_EQ(labels.width, s.cloud.width);
    ASSERT_EQ(labels.height, s.cloud.height);
    ASSERT_EQ(labels.labels.size(), labels.size());
    const ExtraField* object = labels.FindExtraField("object");
    const ExtraField* category = labels.FindExtraField("category");
    ASSERT_NE(object, nullptr);
    ASSERT_NE(category, nullptr);
    EXPECT_EQ(object->type, 'U');
    EXPECT_EQ(object->size, 4);
    EXPECT_EQ(category->size, 1);
    std::map<std::uint32_t, std::size_t> counts;
    std::map<std::uint32_t, std::uint8_t> cats;
    for (std::size_t i = 0; i < labels.size(); ++i) {
        EXPECT_EQ(labels.IsFinite(i), s.cloud.IsFinite(i));
        std::uint32_t id = 0;
        std::memcpy(&id, object->data.data() + 4 * i, 4);
        EXPECT_EQ(labels.labels[i], id);
        if (id == 0) {
            EXPECT_EQ(category->data[i], 0);
            continue;
        }
        counts[id]++;
        cats[id] = category->data[i];
    }
    ASSERT_EQ(counts.size(), j["objects"].size());
    for (const auto& o : j["objects"]) {
        const std::uint32_t id = o["id"];
        EXPECT_EQ(counts[id], o["points"].get<std::size_t>());
        EXPECT_EQ(names[cats[id]], o["category"]);
        double sum = 0;
        for (const auto& [name, p] : o["probabilities"].items()) sum += p.get<double>();
        EXPECT_NEAR(sum, 1.0, 1e-3);
    }
    const TriangleMesh models = io::ReadPlyMesh(dir / "models.ply");
    EXPECT_FALSE(models.triangles.empty());
    EXPECT_TRUE(models.HasVertexColors());
}

TEST(PerceiveOutput, LabelsCloudTakingThePointsEqualsTheCopy) {
    const auto& s = DemoScene();
    const PerceiveResult r = Perceive(s.cloud, PerceiveParams{});
    const PointCloud copied = PerceiveLabelsCloud(s.cloud, r);
    PointCloud input = s.cloud;
    const PointCloud taken = PerceiveLabelsCloud(std::move(input), r);
    EXPECT_EQ(input.size(), 0u);  // NOLINT(bugprone-use-after-move): released on purpose
    EXPECT_TRUE(input.normals.empty());
    ASSERT_EQ(taken.size(), copied.size());
    EXPECT_EQ(taken.width, copied.width);
    EXPECT_EQ(taken.height, copied.height);
    EXPECT_EQ(taken.labels, copied.labels);
    ASSERT_EQ(taken.extra_fields.size(), copied.extra_fields.size());
    for (std::size_t f = 0; f < taken.extra_fields.size(); ++f) {
        EXPECT_EQ(taken.extra_fields[f].data, copied.extra_fields[f].data);
    }
    for (std::size_t i = 0; i < taken.size(); ++i) {
        ASSERT_EQ(taken.IsFinite(i), copied.IsFinite(i));
        if (taken.IsFinite(i)) {
            ASSERT_EQ(taken.points[i], copied.points[i]);
        }
    }
}

TEST(PerceiveOutput, FailedWriteKeepsExistingFiles) {
    test::TempDir dir;
    { std::ofstream(dir / "result.json") << "old"; }
    const PerceiveResult r = Perceive(DemoScene().cloud, PerceiveParams{});
    PointCloud broken = PerceiveLabelsCloud(DemoScene().cloud, r);
    broken.extra_fields[0].data.resize(3);  // inconsistent: the labels write fails
    EXPECT_THROW(
        WritePerceiveOutputs(dir.path(), PerceiveResultJson("x", r), broken, PerceiveModelsMesh(r)),
        Error);
    EXPECT_EQ(io::ReadFileBytes(dir / "result.json"), "old");
    EXPECT_FALSE(std::filesystem::exists(dir / "labels.pcd"));
    std::size_t entries = 0;
    for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator(dir.path())) {
        ++entries;
    }
    EXPECT_EQ(entries, 1u);  // no staging folder left behind
}

TEST(PerceiveConfig, DumpParsesBackAndUnknownKeysFail) {
    auto dump = io::ConfigSection::Dump();
    PerceiveParams defaults;
    ReadPerceiveParams(dump, defaults);
    auto again = io::ConfigSection::Parse(dump.DumpText(), "dump");
    PerceiveParams p;
    ReadPerceiveParams(again, p);
    EXPECT_NO_THROW(again.CheckAllUsed());
    EXPECT_EQ(p.clustering.min_points, defaults.clustering.min_points);
    EXPECT_FALSE(p.support.up.has_value());

    auto typo = io::ConfigSection::Parse(R"({"clustering": {"min_pionts": 5}})", "t.json");
    ReadPerceiveParams(typo, p);
    EXPECT_THROW(typo.CheckAllUsed(), InvalidArgument);
    auto set = io::ConfigSection::Parse(
        R"({"support": {"up": [0, -1, 0]}, "clustering": {"min_points": 42}})", "t.json");
    ReadPerceiveParams(set, p);
    set.CheckAllUsed();
    EXPECT_EQ(p.clustering.min_points, 42u);
    ASSERT_TRUE(p.support.up.has_value());
    EXPECT_EQ(*p.support.up, Eigen::Vector3f(0, -1, 0));
}

TEST(PerceiveConfig, KeysOfEarlierReleasesAreReadUnderTheirNewNames) {
    auto old = io::ConfigSection::Parse(R"({
        "normals": {"k": 12, "organized": {"half_window": 5}},
        "objects": {"cluster_tolerance": 0.02, "min_points": 42},
        "parts": {"k": 8},
        "convexity": {"enabled": false, "patch_size": 0.02},
        "category": {"categoriser": "part-graph", "part_graph_k": 7, "min_points": 40,
                     "part_graph_within_objects": false, "part_graph_priors": {"other": 0.5}},
        "box": {"inlier_threshold": 0.02},
        "cylinder": {"max_iterations": 100, "min_radius": 0.01},
        "models": {"mesh_search_radius": 0.03, "guided_rsd_radius": 0.03,
                   "touching": {"round_enabled": false}}})",
                                        "old.json");
    PerceiveParams p;
    ReadPerceiveParams(old, p);
    EXPECT_NO_THROW(old.CheckAllUsed());
    EXPECT_EQ(p.normals.unorganized.k, 12);
    EXPECT_EQ(p.normals.organized.half_window, 5);
    EXPECT_FLOAT_EQ(p.clustering.tolerance, 0.02f);
    EXPECT_EQ(p.clustering.min_points, 42u);
    EXPECT_EQ(p.parts.region_growing.k, 8);
    EXPECT_FALSE(p.parts.convexity.enabled);
    EXPECT_FLOAT_EQ(p.parts.convexity.patch_size, 0.02f);
    EXPECT_EQ(p.category.categoriser, Categoriser::kPartGraph);
    EXPECT_EQ(p.category.part_graph.k, 7u);
    EXPECT_FALSE(p.category.part_graph.within_groups);
    EXPECT_FLOAT_EQ(
        p.category.part_graph.category_priors[static_cast<std::size_t>(Category::kOther)], 0.5f);
    EXPECT_EQ(p.category.rules.min_points, 40u);
    EXPECT_FLOAT_EQ(p.models.box.inlier_threshold, 0.02f);
    EXPECT_EQ(p.models.cylinder.sac.max_iterations, 100);
    EXPECT_FLOAT_EQ(p.models.cylinder.min_radius, 0.01f);
    EXPECT_FLOAT_EQ(p.models.mesh.search_radius, 0.03f);
    EXPECT_FLOAT_EQ(p.models.guided_rsd.radius, 0.03f);
    EXPECT_FALSE(p.models.touching.round_enabled);
    EXPECT_NO_THROW(p.Validate());

    // A value given under both names is refused; a new key next to an old one is merged.
    auto both = io::ConfigSection::Parse(
        R"({"objects": {"min_points": 5}, "clustering": {"min_points": 6}})", "both.json");
    EXPECT_THROW(ReadPerceiveParams(both, p), InvalidArgument);
    auto merged = io::ConfigSection::Parse(
        R"({"objects": {"min_points": 5}, "clustering": {"tolerance": 0.01}})", "m.json");
    PerceiveParams q;
    ReadPerceiveParams(merged, q);
    EXPECT_NO_THROW(merged.CheckAllUsed());
    EXPECT_EQ(q.clustering.min_points, 5u);
    EXPECT_FLOAT_EQ(q.clustering.tolerance, 0.01f);
    for (const auto& [from, to] : PerceiveRenamedKeys()) EXPECT_NE(from, to);
}

TEST(PerceiveConfig, EveryKeyIsDocumentedAndNamedAsItsField) {
    auto dump = io::ConfigSection::Dump();
    PerceiveParams p;
    ReadPerceiveParams(dump, p);
    const auto keys = dump.RecordedKeys();
    EXPECT_GT(keys.size(), 150u);
    const std::string markdown = dump.DumpMarkdown();
    for (const auto& key : keys) {
        EXPECT_NE(markdown.find("| `" + key + "` |"), std::string::npos) << key;
    }
    // Every row has a meaning.
    EXPECT_EQ(markdown.find("` |  |"), std::string::npos);
    EXPECT_NE(markdown.find("## models"), std::string::npos);
}

TEST(PerceiveConfig, TheCategoriserIsOneOfItsNames) {
    auto bad = io::ConfigSection::Parse(R"({"category": {"categoriser": "votes"}})", "c.json");
    PerceiveParams p;
    try {
        ReadPerceiveParams(bad, p);
        ADD_FAILURE() << "accepted";
    } catch (const InvalidArgument& e) {
        const std::string what = e.what();
        EXPECT_NE(what.find("c.json: 'category.categoriser'"), std::string::npos) << what;
        EXPECT_NE(what.find("part-graph+rules+cluster"), std::string::npos) << what;
    }
    auto three = io::ConfigSection::Parse(
        R"({"category": {"categoriser": "part-graph+rules+cluster"}})", "c.json");
    ReadPerceiveParams(three, p);
    EXPECT_EQ(p.category.categoriser, Categoriser::kThreeExperts);
}

}  // namespace
}  // namespace multicue

// Each stage of perceive on its own, on simulated frames with exact ground truth: the table
// region, frame normals, object hypotheses, parts and the concave split, occlusion merging,
// categories, models, point labels; and the parameter tree, checked whole before any work.

#include <algorithm>
#include <iterator>

#include <gtest/gtest.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/core/params.hpp"
#include "multicue/system/perceive.hpp"
#include "test_scene_helpers.hpp"

namespace multicue {
namespace {

using test::Shape;

const test::SimulatedFrame& BoxAndCan() {
    static const auto f =
        test::ScanShapes({{Shape::kBox, {0.16f, 0.10f, 0.12f}, {-0.12f, 0, 0}},
                          {Shape::kCylinder, {0.04f, 0.04f, 0.12f}, {0.12f, 0, 0}}});
    return f;
}

const test::SimulatedFrame& StackedBoxes() {
    static const auto f =
        test::ScanShapes({{Shape::kBox, {0.22f, 0.16f, 0.10f}, {0, 0, 0}},
                          {Shape::kBox, {0.12f, 0.10f, 0.08f}, {0, 0.01f, 0.10f}}});
    return f;
}

// Equal vectors, NaN entries equal to NaN.
bool SameNormals(const std::vector<Eigen::Vector3f>& a, const std::vector<Eigen::Vector3f>& b) {
    if (a.size() != b.size()) return false;
    for (std::size_t i = 0; i < a.size(); ++i) {
        if (a[i].allFinite() != b[i].allFinite()) return false;
        if (a[i].allFinite() && a[i] != b[i]) return false;
    }
    return true;
}

Indices Finite(const PointCloud& cloud) {
    Indices out;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        if (cloud.IsFinite(i)) out.push_back(static_cast<Index>(i));
    }
    return out;
}

PointCloud Unorganized(PointCloud cloud) {
    cloud.width = static_cast<std::uint32_t>(cloud.size());
    cloud.height = 1;
    return cloud;
}

TEST(PerceiveStages, TableRegionHoldsTheObjectsAndNotTheTable) {
    const auto& f = BoxAndCan();
    const TableRegion region = FindTableRegion(f.cloud, {}, PerceiveParams{}.prism);
    ASSERT_TRUE(region.support.found);
    EXPECT_GT(region.support.plane.head<3>().dot(f.plane.head<3>()), std::cos(1.0f * M_PI / 180));
    EXPECT_NEAR(region.support.plane.w(), f.plane.w(), 0.01f);
    std::size_t object_points = 0;
    for (const auto& t : f.truth) object_points += t.size();
    std::size_t inside = 0;
    for (Index i : region.points) inside += f.cloud.labels[i] >= 20;
    EXPECT_GT(inside, 95 * object_points / 100);
    EXPECT_LT(region.points.size() - inside, object_points / 50);  // hardly any table point

    // Without a table every finite point may be an object.
    PointCloud objects_only = f.cloud;
    for (std::size_t i = 0; i < objects_only.size(); ++i) {
        if (objects_only.labels[i] < 20) {
            objects_only.points[i].setConstant(std::numeric_limits<float>::quiet_NaN());
        }
    }
    const TableRegion none = FindTableRegion(objects_only, {}, {});
    EXPECT_FALSE(none.support.found);
    EXPECT_EQ(none.points, Finite(objects_only));
    EXPECT_THROW(FindTableRegion(f.cloud, {}, {.min_height = 0.2f, .max_height = 0.1f}),
                 InvalidArgument);
}

// Area of a convex polygon on a plane with unit normal n.
float HullArea(const std::vector<Eigen::Vector3f>& hull, const Eigen::Vector3f& n) {
    Eigen::Vector3f sum = Eigen::Vector3f::Zero();
    for (std::size_t k = 0; k < hull.size(); ++k) sum += hull[k].cross(hull[(k + 1) % hull.size()]);
    return 0.5f * std::abs(sum.dot(n));
}

// The organized frame's table (pixel pieces joined at their borders) is the table of the same
// points without their pixel grid (3D clustering of every point): a table cut in two by a narrow
// gap is one patch, one cut by a gap wider than the tolerance keeps its larger side.
TEST(PerceiveStages, TableOfAnOrganizedFrameIsTheTableOfItsPoints) {
    const auto& f = BoxAndCan();
    for (const int gap : {4, 200}) {  // pixels: about 1 cm and 40 cm at the table
        PointCloud cut = f.cloud;
        for (std::size_t i = 0; i < cut.size(); ++i) {
            const int u = static_cast<int>(i % cut.width);
            if (cut.labels[i] < 20 && u >= 400 && u < 400 + gap)
                cut.points[i].setConstant(std::numeric_limits<float>::quiet_NaN());
        }
        const SupportPlane organized = FindSupportPlane(cut, {}, PerceiveParams{}.prism);
        const SupportPlane flat = FindSupportPlane(Unorganized(cut), {}, PerceiveParams{}.prism);
        ASSERT_TRUE(organized.found);
        ASSERT_TRUE(flat.found);
        EXPECT_EQ(organized.plane, flat.plane);
        EXPECT_EQ(organized.inliers, flat.inliers) << "gap " << gap;
        const Eigen::Vector3f n = organized.plane.head<3>();
        EXPECT_NEAR(HullArea(organized.hull, n), HullArea(flat.hull, n),
                    1e-3f * HullArea(flat.hull, n));
        std::size_t right = 0;
        for (Index i : organized.inliers) right += i % cut.width >= 400 ? 1 : 0;
        if (gap == 4) {
            EXPECT_GT(right, 0u);  // both sides
            EXPECT_LT(right, organized.inliers.size());
        } else {
            EXPECT_TRUE(right == 0 || right == organized.inliers.size());  // one side only
        }
    }
}

TEST(PerceiveStages, FrameNormalsCoverTheRegionOnly) {
    const auto& f = BoxAndCan();
    PointCloud frame = f.cloud;
    frame.normals.clear();
    frame.curvature.clear();
    const Indices region = f.truth[0];
    const NormalsResult n = EstimateFrameNormals(frame, region, {});
    ASSERT_EQ(n.normals.size(), frame.size());
    std::size_t defined = 0;
    for (std::size_t i = 0; i < frame.size(); ++i) defined += n.normals[i].allFinite();
    EXPECT_LE(defined, region.size());
    EXPECT_GT(defined, 9 * region.size() / 10);
    // Normals face the sensor.
    for (Index i : region) {
        if (n.normals[i].allFinite()) {
            EXPECT_LT(n.normals[i].dot(frame.points[i]), 0.0f);
        }
    }
    // An unorganized cloud takes the k-d tree path, as EstimateNormals with the same settings.
    const PointCloud flat = Unorganized(frame);
    const NormalsResult u = EstimateFrameNormals(flat, region, {});
    const KdTree tree(flat);
    const NormalsResult oracle = EstimateNormals(flat, tree, FrameNormalParams{}.unorganized);
    EXPECT_TRUE(SameNormals(u.normals, oracle.normals));
    EXPECT_THROW(EstimateFrameNormals(frame, {static_cast<Index>(frame.size())}, {}),
                 InvalidArgument);
    FrameNormalParams bad;
    bad.organized.half_window = 0;
    EXPECT_THROW(EstimateFrameNormals(frame, region, bad), InvalidArgument);
    // Ensure leaves existing normals alone.
    PointCloud with = f.cloud;
    EnsureFrameNormals(with, region, {});
    EXPECT_TRUE(SameNormals(with.normals, f.cloud.normals));
}

TEST(PerceiveStages, ClustersAreTheObjectsInBothPaths) {
    const auto& f = BoxAndCan();
    Indices objects;
    for (const auto& t : f.truth) objects.insert(objects.end(), t.begin(), t.end());
    std::sort(objects.begin(), objects.end());
    const ClusteringResult organized = ClusterObjects(f.cloud, objects, {});
    ASSERT_EQ(organized.clusters.size(), 2u);
    for (const auto& c : organized.clusters) EXPECT_GT(test::Purity(f, c).first, 0.99);
    const ClusteringResult flat = ClusterObjects(Unorganized(f.cloud), objects, {});
    ASSERT_EQ(flat.clusters.size(), 2u);
    EXPECT_EQ(flat.clusters, organized.clusters);
    EXPECT_TRUE(ClusterObjects(f.cloud, {}, {}).clusters.empty());
    // Clusters under min_points are no objects.
    EXPECT_TRUE(ClusterObjects(f.cloud, objects, {.min_points = 100000, .max_points = 200000})
                    .clusters.empty());
    EXPECT_THROW(ClusterObjects(f.cloud, objects, {.tolerance = 0.0f}), InvalidArgument);
    EXPECT_THROW(ClusterObjects(f.cloud, objects, {.organized_half_window = 0}), InvalidArgument);
    EXPECT_THROW(ClusterObjects(f.cloud, objects, {.min_points = 10, .max_points = 5}),
                 InvalidArgument);
}

TEST(PerceiveStages, PartsAndTheConcaveSplitSeparateStackedBoxes) {
    const auto& f = StackedBoxes();
    Indices both = f.truth[0];
    both.insert(both.end(), f.truth[1].begin(), f.truth[1].end());
    std::sort(both.begin(), both.end());
    const Eigen::Vector4f plane = f.plane;
    PartSegmentationParams p;
    p.num_threads = 1;
    const PartSegmentationResult r = SegmentParts(f.cloud, {both}, plane, p, 150);
    ASSERT_GE(r.objects.size(), 2u);
    EXPECT_EQ(r.split_hypotheses, 1u);
    // The two largest pieces are the two boxes (a small strip of the lower one may stay apart).
    std::vector<std::pair<std::size_t, std::size_t>> sizes;  // points, shape
    std::size_t parts = 0;
    for (const auto& o : r.objects) {
        sizes.emplace_back(o.indices.size(), test::Purity(f, o.indices).second);
        EXPECT_GT(test::Purity(f, o.indices).first, 0.95);
        EXPECT_TRUE(std::is_sorted(o.indices.begin(), o.indices.end()));
        for (const auto& part : o.parts) {
            for (Index i : part) {
                EXPECT_TRUE(std::binary_search(o.indices.begin(), o.indices.end(), i));
            }
        }
        parts += o.parts.size();
    }
    std::sort(sizes.rbegin(), sizes.rend());
    EXPECT_NE(sizes[0].second, sizes[1].second);
    EXPECT_GT(sizes[1].first, f.truth[1].size() / 2);
    EXPECT_GE(parts, 4u);  // at least two faces each
    // Without the split the hypothesis stays whole, parts and all.
    p.convexity.enabled = false;
    const PartSegmentationResult whole = SegmentParts(f.cloud, {both}, plane, p, 150);
    ASSERT_EQ(whole.objects.size(), 1u);
    EXPECT_EQ(whole.objects[0].indices, both);
    EXPECT_GE(whole.objects[0].parts.size(), parts);
    // Pieces under min_object_points are dropped.
    p.convexity.enabled = true;
    const PartSegmentationResult none = SegmentParts(f.cloud, {both}, plane, p, 1000000);
    EXPECT_TRUE(none.objects.empty());
    EXPECT_GE(none.dropped_pieces, 1u);
}

TEST(PerceiveStages, PartSegmentationIsDeterministicAndChecksItsInput) {
    const auto& f = BoxAndCan();
    PartSegmentationParams one, two;
    one.num_threads = 1;
    two.num_threads = 2;
    const auto a = SegmentParts(f.cloud, f.truth, f.plane, one, 150);
    const auto b = SegmentParts(f.cloud, f.truth, f.plane, two, 150);
    ASSERT_EQ(a.objects.size(), b.objects.size());
    for (std::size_t k = 0; k < a.objects.size(); ++k) {
        EXPECT_EQ(a.objects[k].indices, b.objects[k].indices);
        EXPECT_EQ(a.objects[k].parts, b.objects[k].parts);
    }
    EXPECT_TRUE(SegmentParts(f.cloud, {}, f.plane, one, 150).objects.empty());
    PointCloud bare = f.cloud;
    bare.normals.clear();
    EXPECT_THROW(SegmentParts(bare, f.truth, f.plane, one, 150), DataError);
    PartSegmentationParams bad;
    bad.region_growing.radius = 0.0f;
    EXPECT_THROW(SegmentParts(f.cloud, {}, f.plane, bad, 150), InvalidArgument);
    bad = {};
    bad.convexity.patch_size = -1.0f;
    EXPECT_THROW(SegmentParts(f.cloud, {}, f.plane, bad, 150), InvalidArgument);
}

TEST(PerceiveStages, OcclusionMergeCanBeOffAndLeavesSingleObjects) {
    const auto& f = BoxAndCan();
    const auto segments = SegmentParts(f.cloud, f.truth, f.plane, {}, 150).objects;
    Switchable<OcclusionMergeParams> p;
    p.enabled = false;
    const auto off = MergeOccludedObjects(f.cloud, segments, f.plane, p);
    ASSERT_EQ(off.size(), segments.size());
    // Two objects side by side in full view are not fragments of one.
    p.enabled = true;
    EXPECT_EQ(MergeOccludedObjects(f.cloud, segments, f.plane, p).size(), segments.size());
    EXPECT_EQ(MergeOccludedObjects(f.cloud, {segments[0]}, f.plane, p).size(), 1u);
    p.min_rows = 0;
    EXPECT_THROW(MergeOccludedObjects(f.cloud, segments, f.plane, p), InvalidArgument);
}

std::vector<PerceivedObject> Objects(const test::SimulatedFrame& f) {
    std::vector<PerceivedObject> objects;
    for (std::size_t k = 0; k < f.truth.size(); ++k) {
        objects.push_back(test::MergedObject(f, {k}, Category::kNone));
        objects.back().category = {};
    }
    return objects;
}

TEST(PerceiveStages, RulesCategoriseBoxesAndCylinders) {
    const auto& f = BoxAndCan();
    std::vector<PerceivedObject> objects = Objects(f);
    CategorizationParams p;
    p.num_threads = 1;
    CategorizeObjects(f.cloud, objects, f.plane, p, nullptr);
    const Category box = objects[0].category.category;
    EXPECT_TRUE(box == Category::kBox || box == Category::kFlat) << CategoryName(box);
    EXPECT_EQ(objects[1].category.category, Category::kCylinder);
    for (const auto& o : objects) EXPECT_TRUE(o.part_probabilities.empty());
    // Thread counts change nothing.
    std::vector<PerceivedObject> again = Objects(f);
    p.num_threads = 2;
    CategorizeObjects(f.cloud, again, f.plane, p, nullptr);
    for (std::size_t k = 0; k < objects.size(); ++k) {
        EXPECT_EQ(again[k].category.probabilities, objects[k].category.probabilities);
    }
}

TEST(PerceiveStages, CategoriesOfSomeObjectsWithinAllowedOnes) {
    const auto& f = BoxAndCan();
    std::vector<PerceivedObject> objects = Objects(f);
    const std::vector<std::size_t> which{1};
    const std::vector<Category> boxes{Category::kBox, Category::kFlat};
    CategorizeObjects(f.cloud, objects, f.plane, {}, nullptr, which, boxes);
    EXPECT_EQ(objects[0].category.category, Category::kNone);  // not asked for
    const CategoryResult& c = objects[1].category;
    EXPECT_TRUE(c.category == Category::kBox || c.category == Category::kFlat);
    float sum = 0.0f;
    for (std::size_t k = 0; k < kNumCategories; ++k) {
        const auto cat = static_cast<Category>(k);
        if (cat != Category::kBox && cat != Category::kFlat) {
            EXPECT_EQ(c.probabilities[k], 0.0f);
        }
        sum += c.probabilities[k];
    }
    EXPECT_NEAR(sum, 1.0f, 1e-5f);
    const std::vector<std::size_t> outside{5};
    EXPECT_THROW(CategorizeObjects(f.cloud, objects, f.plane, {}, nullptr, outside),
                 InvalidArgument);
    // Learned categorisers need their model.
    CategorizationParams learned;
    learned.categoriser = Categoriser::kThreeExperts;
    EXPECT_THROW(CategorizeObjects(f.cloud, objects, f.plane, learned, nullptr), InvalidArgument);
    CategorizationParams bad;
    bad.cluster_k = 0;
    EXPECT_THROW(CategorizeObjects(f.cloud, objects, f.plane, bad, nullptr), InvalidArgument);
}

TEST(PerceiveStages, CategoriserNamesRoundTrip) {
    for (Categoriser c :
         {Categoriser::kRules, Categoriser::kPartGraph, Categoriser::kPartGraphRules,
          Categoriser::kThreeExperts, Categoriser::kStacked}) {
        EXPECT_EQ(ParseCategoriser(CategoriserName(c)), c);
    }
    EXPECT_EQ(CategoriserName(Categoriser::kThreeExperts), "part-graph+rules+cluster");
    EXPECT_THROW(ParseCategoriser("Rules"), InvalidArgument);
    EXPECT_FALSE(CategorizationParams{}.NeedsPartGraph());
}

TEST(PerceiveStages, ARoundProfileMakesACylinder) {
    // Surfaces of revolution: a mug-like profile (radius 4 cm, 10 cm high) and a bowl.
    auto object = [](Category c, std::vector<float> radii, float height) {
        PerceivedObject o;
        o.category.category = c;
        o.category.probabilities[static_cast<std::size_t>(Category::kCylinder)] = 0.3f;
        o.model.accepted = true;
        RotationalModel rot;
        rot.radii = std::move(radii);
        for (std::size_t k = 0; k < rot.radii.size(); ++k)
            rot.heights.push_back(height * static_cast<float>(k) / (rot.radii.size() - 1));
        o.model.rotational = std::move(rot);
        return o;
    };
    std::vector<PerceivedObject> objects;
    objects.push_back(object(Category::kOther, {0.038f, 0.039f, 0.040f}, 0.10f));  // mug
    objects.push_back(object(Category::kOther, {0.03f, 0.06f, 0.09f}, 0.08f));     // bowl
    objects.push_back(object(Category::kSphere, {0.04f, 0.04f}, 0.02f));           // too low
    objects.push_back(object(Category::kBox, {0.04f, 0.04f}, 0.10f));              // not other
    objects.push_back(object(Category::kOther, {0.04f, 0.041f}, 0.10f));
    objects.back().model.accepted = false;  // a rejected model says nothing
    CategorizationParams p;
    CategorizeByModels(objects, p);
    EXPECT_EQ(objects[0].category.category, Category::kCylinder);
    EXPECT_TRUE(objects[0].category_from_model);
    EXPECT_FLOAT_EQ(objects[0].category.confidence, 0.3f);
    EXPECT_EQ(objects[1].category.category, Category::kOther);
    EXPECT_EQ(objects[2].category.category, Category::kSphere);
    EXPECT_EQ(objects[3].category.category, Category::kBox);
    EXPECT_EQ(objects[4].category.category, Category::kOther);
    EXPECT_FALSE(objects[4].category_from_model);
    // Off, and bad values.
    std::vector<PerceivedObject> again{object(Category::kOther, {0.04f, 0.04f}, 0.1f)};
    p.cylinder_profile_ratio = 0.0f;
    CategorizeByModels(again, p);
    EXPECT_EQ(again[0].category.category, Category::kOther);
    p.cylinder_profile_ratio = 0.5f;
    EXPECT_THROW(p.Validate(), InvalidArgument);
}

TEST(PerceiveStages, ModelsOfSomeObjects) {
    const auto& f = BoxAndCan();
    std::vector<PerceivedObject> objects = Objects(f);
    CategorizeObjects(f.cloud, objects, f.plane, {}, nullptr);
    ModelParams p;
    p.num_threads = 1;
    const std::vector<std::size_t> second{1};
    ModelObjects(f.cloud, objects, f.plane, p, second);
    EXPECT_TRUE(objects[0].model.mesh.vertices.empty());
    ASSERT_TRUE(objects[1].model.cylinder.has_value());
    EXPECT_NEAR(objects[1].model.cylinder->radius, 0.04f, 0.005f);
    ModelObjects(f.cloud, objects, f.plane, p);
    EXPECT_TRUE(objects[0].model.box.has_value());
    const std::vector<std::size_t> outside{2};
    EXPECT_THROW(ModelObjects(f.cloud, objects, f.plane, p, outside), InvalidArgument);
}

TEST(PerceiveStages, LabelPointsNumbersObjectsAndLabelsTheirPoints) {
    PointCloud cloud;
    cloud.points = {{0, 0, 1}, {1, 0, 1}, {2, 0, 1}, {3, 0, 1}};
    cloud.SetUnorganized();
    PerceiveResult r;
    r.objects.resize(2);
    r.objects[0].id = 7;
    r.objects[0].indices = {1, 3};
    r.objects[0].category.category = Category::kBox;
    r.objects[1].indices = {2};
    r.objects[1].category.category = Category::kPlate;
    LabelPoints(cloud, r);
    EXPECT_EQ(r.point_objects, (std::vector<std::uint32_t>{0, 1, 2, 1}));
    EXPECT_EQ(r.point_categories,
              (std::vector<std::uint8_t>{0, static_cast<std::uint8_t>(Category::kBox),
                                         static_cast<std::uint8_t>(Category::kPlate),
                                         static_cast<std::uint8_t>(Category::kBox)}));
    EXPECT_EQ(r.objects[0].id, 1);
    EXPECT_EQ(r.objects[1].id, 2);
    EXPECT_EQ(r.objects[0].centroid, Eigen::Vector3f(2, 0, 1));
    r.objects[1].indices = {9};
    EXPECT_THROW(LabelPoints(cloud, r), InvalidArgument);
    PerceiveResult empty;
    LabelPoints(cloud, empty);
    EXPECT_EQ(empty.point_objects, std::vector<std::uint32_t>(4, 0));
}

TEST(PerceiveStages, ADishGetsItsFloorBackFromTheTable) {
    // A plate 2 cm high whose floor lies 4 mm above the table, below the prism's 8 mm, beside a
    // box 2.5 cm high whose sides' lowest 8 mm are cut the same way.
    const test::SimulatedFrame f =
        test::ScanShapes({{Shape::kDish, {0.12f, 0.12f, 0.02f}, {-0.12f, 0.05f, 0.0f}},
                          {Shape::kBox, {0.15f, 0.1f, 0.025f}, {0.15f, 0.05f, 0.0f}}});
    ASSERT_GT(f.truth[0].size(), 2000u);
    PerceiveParams off;
    off.floors.enabled = false;
    const PerceiveResult with = Perceive(f.cloud, PerceiveParams{});
    const PerceiveResult without = Perceive(f.cloud, off);
    // The object holding most of the dish's points, and its share of them / of its own points.
    auto dish = [&](const PerceiveResult& r) {
        std::pair<double, double> best{0.0, 0.0};
        for (const PerceivedObject& o : r.objects) {
            Indices common;
            std::set_intersection(o.indices.begin(), o.indices.end(), f.truth[0].begin(),
                                  f.truth[0].end(), std::back_inserter(common));
            const double recall = double(common.size()) / double(f.truth[0].size());
            if (recall > best.first)
                best = {recall, double(common.size()) / double(o.indices.size())};
        }
        return best;
    };
    const auto [recall_with, precision_with] = dish(with);
    const auto [recall_without, precision_without] = dish(without);
    std::printf("[ floors ] dish recall %.3f precision %.3f; without floors %.3f %.3f\n",
                recall_with, precision_with, recall_without, precision_without);
    EXPECT_LT(recall_without, 0.7);  // its rim
    EXPECT_GT(recall_with, 0.9);
    EXPECT_GT(precision_with, 0.97);  // no table around it
    // The table's inliers gave the floor up; every object keeps its category and model.
    EXPECT_LT(with.support.inliers.size(), without.support.inliers.size());
    ASSERT_EQ(with.objects.size(), without.objects.size());
    for (std::size_t k = 0; k < with.objects.size(); ++k) {
        EXPECT_EQ(with.objects[k].category.category, without.objects[k].category.category);
        EXPECT_EQ(with.objects[k].model.box.has_value(), without.objects[k].model.box.has_value());
        EXPECT_EQ(with.objects[k].model.cylinder.has_value(),
                  without.objects[k].model.cylinder.has_value());
        EXPECT_EQ(with.objects[k].model.mesh.vertices.size(),
                  without.objects[k].model.mesh.vertices.size());
        EXPECT_GE(with.objects[k].indices.size(), without.objects[k].indices.size());
        // The parts still hold every point of their object, the floor as one part more.
        Indices in_parts;
        for (const Indices& part : with.objects[k].parts)
            in_parts.insert(in_parts.end(), part.begin(), part.end());
        std::sort(in_parts.begin(), in_parts.end());
        EXPECT_EQ(in_parts, with.objects[k].indices);
        EXPECT_LE(with.objects[k].parts.size(), without.objects[k].parts.size() + 1);
    }
    PerceiveParams bad;
    bad.floors.cell = 0.0f;
    EXPECT_THROW(Perceive(f.cloud, bad), ParameterError);
}

TEST(PerceiveStages, ThreadCountReachesEveryParallelStage) {
    PerceiveParams p;
    p.num_threads = 3;
    const PerceiveParams t = ApplyThreadCount(p);
    EXPECT_EQ(t.normals.organized.num_threads, 3);
    EXPECT_EQ(t.normals.unorganized.num_threads, 3);
    EXPECT_EQ(t.support.num_threads, 3);
    EXPECT_EQ(t.parts.num_threads, 3);
    EXPECT_EQ(t.category.num_threads, 3);
    EXPECT_EQ(t.models.num_threads, 3);
}

// A frame without objects: a few scattered points, no table, no cluster large enough.
const PointCloud& EmptyTable() {
    static const PointCloud cloud = [] {
        PointCloud c;
        for (int i = 0; i < 60; ++i) {
            c.points.emplace_back(0.05f * static_cast<float>(i % 7),
                                  0.04f * static_cast<float>(i % 5),
                                  1.0f + 0.03f * static_cast<float>(i % 3));
        }
        c.SetUnorganized();
        return c;
    }();
    return cloud;
}

TEST(PerceiveStages, EveryBadParameterIsRefusedBeforeAnyWorkWhateverTheScene) {
    ASSERT_TRUE(Perceive(EmptyTable(), {}).objects.empty());
    struct Case {
        const char* path;
        void (*set)(PerceiveParams&);
    };
    const std::vector<Case> cases = {
        {"threads", [](PerceiveParams& p) { p.num_threads = -1; }},
        {"normals.organized", [](PerceiveParams& p) { p.normals.organized.half_window = 0; }},
        {"normals.unorganized", [](PerceiveParams& p) { p.normals.unorganized.k = 2; }},
        {"support", [](PerceiveParams& p) { p.support.distance_threshold = 0.0f; }},
        {"prism", [](PerceiveParams& p) { p.prism.min_height = 1.0f; }},
        {"clustering", [](PerceiveParams& p) { p.clustering.tolerance = -1.0f; }},
        {"parts.region_growing", [](PerceiveParams& p) { p.parts.region_growing.radius = 0.0f; }},
        {"parts.convexity", [](PerceiveParams& p) { p.parts.convexity.min_convex_share = 2.0f; }},
        {"occlusion", [](PerceiveParams& p) { p.occlusion.min_rows = 0; }},
        {"category", [](PerceiveParams& p) { p.category.cluster_k = 0; }},
        {"category", [](PerceiveParams& p) { p.category.part_graph_weight = 2.0f; }},
        {"category",
         [](PerceiveParams& p) {
             p.category.expert_weights = {0, 0, 0};
         }},
        {"category.rules", [](PerceiveParams& p) { p.category.rules.min_points = 0; }},
        {"category.part_graph", [](PerceiveParams& p) { p.category.part_graph.k = 0; }},
        {"models", [](PerceiveParams& p) { p.models.min_inlier_ratio = 1.5f; }},
        {"models", [](PerceiveParams& p) { p.models.mesh_max_points = 2; }},
        {"models", [](PerceiveParams& p) { p.models.several_min_ratio = -1.0f; }},
        {"models.mesh", [](PerceiveParams& p) { p.models.mesh.search_radius = 0.0f; }},
        {"models.guided_rsd", [](PerceiveParams& p) { p.models.guided_rsd.radius = -1.0f; }},
        {"models.box", [](PerceiveParams& p) { p.models.box.inlier_threshold = 0.0f; }},
        {"models.cylinder", [](PerceiveParams& p) { p.models.cylinder.min_radius = -1.0f; }},
        {"models.rotational", [](PerceiveParams& p) { p.models.rotational.max_points = 1; }},
        {"models.verification", [](PerceiveParams& p) { p.models.verification.voxel_size = 0.0f; }},
        {"models.concentric", [](PerceiveParams& p) { p.models.concentric.distance = -1.0f; }},
        {"models.contained", [](PerceiveParams& p) { p.models.contained.min_share = 0.0f; }},
        {"models.stacked", [](PerceiveParams& p) { p.models.stacked.min_step = 0.0f; }},
        {"models.touching", [](PerceiveParams& p) { p.models.touching.max_parts = 13; }},
        {"models.part_counts", [](PerceiveParams& p) { p.models.part_counts.flat_mean = 0.0; }},
    };
    for (const auto& c : cases) {
        PerceiveParams p;
        c.set(p);
        try {
            Perceive(EmptyTable(), p);
            ADD_FAILURE() << c.path << ": accepted";
        } catch (const ParameterError& e) {
            EXPECT_EQ(e.path(), c.path) << e.what();
        }
        EXPECT_THROW(p.Validate(), InvalidArgument) << c.path;
    }
    EXPECT_NO_THROW(PerceiveParams{}.Validate());
}

TEST(PerceiveStages, DisabledStepsAreStillChecked) {
    PerceiveParams p;
    p.models.rotational.enabled = false;
    p.models.rotational.inlier_threshold = 0.0f;
    EXPECT_THROW(Perceive(EmptyTable(), p), InvalidArgument);
    p = {};
    p.parts.convexity.enabled = false;
    p.parts.convexity.patch_size = 0.0f;
    EXPECT_THROW(Perceive(EmptyTable(), p), InvalidArgument);
}

}  // namespace
}  // namespace multicue

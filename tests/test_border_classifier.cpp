// The learned grouping of parts into objects: part borders and their features on two touching
// boxes of known geometry, the logistic regression against a hand computation and recovering a
// known linear rule, parts that fold over two faces, bad parameters and determinism.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/segmentation/border_classifier.hpp"
#include "multicue/segmentation/border_features.hpp"
#include "multicue/segmentation/convexity_split.hpp"
#include "multicue/segmentation/folded_parts.hpp"
#include "multicue/segmentation/part_borders.hpp"

namespace multicue {
namespace {

const Eigen::Vector4f kTable(0.0f, 0.0f, 1.0f, 0.0f);  // z = 0, normal up

std::size_t Feature(std::string_view name) {
    for (std::size_t k = 0; k < kBorderFeatureCount; ++k) {
        if (kBorderFeatureNames[k] == name) return k;
    }
    ADD_FAILURE() << "no feature " << name;
    return 0;
}

struct Boxes {
    PointCloud cloud;
    Indices object;
    std::vector<Indices> parts;  // one per visible face
    std::vector<int> label;      // per point: box 0 or 1
};

// Box A (12 x 10 x 8 cm) and, touching its right side, the taller box B (10 x 8 x 14 cm, set back
// 2 cm), seen from the front left above. Visible faces, one part each: 0 A top, 1 A front,
// 2 A left, 3 B top, 4 B front, 5 B's left side above A's top. A's top meets B's side in a
// concave crease; A's faces meet each other convexly.
Boxes TouchingBoxes() {
    constexpr float kStep = 0.004f;
    Boxes s;
    auto face = [&](const Eigen::Vector3f& origin, const Eigen::Vector3f& u,
                    const Eigen::Vector3f& v, const Eigen::Vector3f& normal, int label) {
        const int nu = static_cast<int>(std::lround(u.norm() / kStep));
        const int nv = static_cast<int>(std::lround(v.norm() / kStep));
        Indices part;
        for (int i = 0; i <= nu; ++i) {
            for (int j = 0; j <= nv; ++j) {
                const auto idx = static_cast<Index>(s.cloud.points.size());
                s.cloud.points.push_back(origin + u * (static_cast<float>(i) / nu) +
                                         v * (static_cast<float>(j) / nv));
                s.cloud.normals.push_back(normal);
                s.object.push_back(idx);
                s.label.push_back(label);
                part.push_back(idx);
            }
        }
        s.parts.push_back(std::move(part));
    };
    const Eigen::Vector3f x = Eigen::Vector3f::UnitX();
    const Eigen::Vector3f y = Eigen::Vector3f::UnitY();
    const Eigen::Vector3f z = Eigen::Vector3f::UnitZ();
    face({-0.12f, -0.05f, 0.08f}, 0.12f * x, 0.1f * y, z, 0);
    face({-0.12f, -0.05f, 0.0f}, 0.12f * x, 0.08f * z, -y, 0);
    face({-0.12f, -0.05f, 0.0f}, 0.1f * y, 0.08f * z, -x, 0);
    face({0.0f, -0.03f, 0.14f}, 0.1f * x, 0.08f * y, z, 1);
    face({0.0f, -0.03f, 0.0f}, 0.1f * x, 0.14f * z, -y, 1);
    face({0.0f, -0.03f, 0.08f}, 0.08f * y, 0.06f * z, -x, 1);
    s.cloud.SetUnorganized();
    s.cloud.sensor_origin = Eigen::Vector3f(-0.4f, -0.6f, 0.6f);
    return s;
}

const PartBorder* FindBorder(const PartBorders& borders, std::size_t a, std::size_t b) {
    for (const PartBorder& e : borders.borders) {
        if (e.a == a && e.b == b) return &e;
    }
    return nullptr;
}

TEST(PartBorders, TouchingBoxesMeetConcavelyAndTheirOwnFacesConvexly) {
    const Boxes boxes = TouchingBoxes();
    const PartBorders borders =
        ComputePartBorders(boxes.cloud, boxes.object, boxes.parts, {}, kTable);
    ASSERT_EQ(borders.point_part.size(), boxes.object.size());
    ASSERT_EQ(borders.part_patches.size(), 6u);
    for (std::size_t p = 0; p < 6; ++p) EXPECT_GT(borders.part_patches[p], 0u) << p;

    const PartBorder* own = FindBorder(borders, 0, 1);     // A top, A front
    const PartBorder* crease = FindBorder(borders, 0, 5);  // A top, B's side
    ASSERT_NE(own, nullptr);
    ASSERT_NE(crease, nullptr);
    EXPECT_GE(own->ConvexShare(), 0.9f);
    EXPECT_GT(own->mean_bend, 0.0f);
    EXPECT_NEAR(own->median_angle_deg, 90.0f, 20.0f);
    EXPECT_LE(crease->ConvexShare(), 0.1f);
    EXPECT_LT(crease->mean_bend, 0.0f);
    // The crease lies at A's top, 8 cm above the table (patch midpoints within a patch).
    EXPECT_NEAR(crease->mean_height, 0.08f, 0.015f);
    // Flat faces neither bulge nor cave in much (the patches on their edges mix two faces).
    for (float bend : borders.part_bend) EXPECT_NEAR(bend, 0.0f, 0.15f);
}

TEST(BorderFeatures, MeasureHeightsAndConvexityOfTheTouchingBoxes) {
    const Boxes boxes = TouchingBoxes();
    const PartBorders borders =
        ComputePartBorders(boxes.cloud, boxes.object, boxes.parts, {}, kTable);
    const std::vector<PartSummary> parts = SummarizeParts(boxes.parts, borders, kTable);
    ASSERT_EQ(parts.size(), 6u);
    // Patch centroids lie at most half a patch (7.5 mm) inside the faces; patches on an edge mix
    // the normals of two faces.
    EXPECT_NEAR(parts[0].top, 0.08f, 0.008f);
    EXPECT_NEAR(parts[3].top, 0.14f, 0.008f);
    EXPECT_NEAR(parts[5].bottom, 0.08f, 0.008f);
    EXPECT_NEAR(parts[0].normal.z(), 1.0f, 0.02f);
    EXPECT_NEAR(parts[1].normal.y(), -1.0f, 0.02f);
    for (const PartSummary& p : parts) EXPECT_LT(p.spread, 0.3f);

    const Eigen::Vector3f up = kTable.head<3>();
    const BorderFeatures own =
        ComputeBorderFeatures(*FindBorder(borders, 0, 1), borders, parts, up);
    const BorderFeatures crease =
        ComputeBorderFeatures(*FindBorder(borders, 0, 5), borders, parts, up);
    EXPECT_GE(own[Feature("convex_share")], 0.9f);
    EXPECT_LE(crease[Feature("convex_share")], 0.1f);
    EXPECT_NEAR(own[Feature("part_normal_angle")], 0.5f * M_PI, 0.2);
    EXPECT_NEAR(crease[Feature("part_normal_angle")], 0.5f * M_PI, 0.2);
    // A's top and A's front end at 8 cm; B's side rises 6 cm higher (less up to a patch at
    // each end).
    EXPECT_LT(own[Feature("top_difference")], 0.02f);
    EXPECT_NEAR(crease[Feature("top_difference")], 0.06f, 0.016f);
    // B's side starts where A's top is: it stands on it.
    EXPECT_NEAR(crease[Feature("lifted")], 0.08f, 0.008f);
    EXPECT_NEAR(crease[Feature("stack_contact")], 0.0f, 0.01f);
    EXPECT_LT(crease[Feature("min_upright")], 0.15f);
    EXPECT_GT(crease[Feature("max_upright")], 0.95f);
    EXPECT_GT(own[Feature("bend")], 0.0f);
    EXPECT_LT(crease[Feature("bend")], 0.0f);
    for (float v : own) EXPECT_TRUE(std::isfinite(v));
    for (float v : crease) EXPECT_TRUE(std::isfinite(v));
}

TEST(BorderClassifier, LearnedGroupingSplitsTheTouchingBoxesIntoTheTwoBoxes) {
    const Boxes boxes = TouchingBoxes();
    const ConvexitySplitResult split =
        SplitByConvexity(boxes.cloud, boxes.object, boxes.parts, {}, kTable);
    ASSERT_EQ(split.objects.size(), 2u);
    for (const Indices& o : split.objects) {
        for (Index i : o) ASSERT_EQ(boxes.label[i], boxes.label[o.front()]);
    }
    // Deterministic: the same input gives the same groups.
    const ConvexitySplitResult again =
        SplitByConvexity(boxes.cloud, boxes.object, boxes.parts, {}, kTable);
    EXPECT_EQ(again.objects, split.objects);
    EXPECT_EQ(again.parts, split.parts);
}

TEST(BorderClassifier, JoinProbabilityIsTheLogisticOfTheLinearScore) {
    BorderClassifierParams p;
    p.weights.fill(0.0f);
    p.weights[0] = 2.0f;
    p.weights[3] = -1.0f;
    p.bias = 0.5f;
    BorderFeatures f{};
    f[0] = 1.0f;
    f[3] = 0.25f;
    f[7] = 100.0f;  // weight 0
    const double z = 0.5 + 2.0 - 0.25;
    EXPECT_NEAR(JoinProbability(f, p), 1.0 / (1.0 + std::exp(-z)), 1e-6);
    f.fill(0.0f);
    p.bias = 0.0f;
    EXPECT_FLOAT_EQ(JoinProbability(f, p), 0.5f);
}

// Rows whose truth is drawn from a known logistic rule on three of the features (the others
// noise): the fit gives back the rule's weights and bias.
std::vector<BorderExample> RuleRows(std::size_t n, unsigned seed) {
    std::mt19937 rng(seed);
    std::normal_distribution<float> normal(0.0f, 1.0f);
    std::uniform_real_distribution<double> uniform(0.0, 1.0);
    std::vector<BorderExample> rows(n);
    for (BorderExample& r : rows) {
        for (float& v : r.features) v = normal(rng);
        r.features[1] = 0.5f + 0.2f * r.features[1];  // other scales and offsets
        r.features[6] = 0.05f * r.features[6];
        const double z = 0.7 + 3.0 * (r.features[1] - 0.5) / 0.2 * 0.5 - 40.0 * r.features[6] +
                         1.2 * r.features[20];
        r.same = uniform(rng) < 1.0 / (1.0 + std::exp(-z));
    }
    return rows;
}

TEST(BorderClassifier, FitRecoversAKnownLinearRule) {
    const std::vector<BorderExample> rows = RuleRows(40000, 7);
    BorderClassifierParams start;
    start.threshold = 0.6f;
    start.large_part_points = 99;
    const BorderClassifierParams fit = FitBorderClassifier(rows, 0.0, start);
    // z = 0.7 + 7.5 (f1 - 0.5) - 40 f6 + 1.2 f20 = -3.05 + 7.5 f1 - 40 f6 + 1.2 f20.
    EXPECT_NEAR(fit.bias, -3.05f, 0.3f);
    EXPECT_NEAR(fit.weights[1], 7.5f, 0.5f);
    EXPECT_NEAR(fit.weights[6], -40.0f, 3.0f);
    EXPECT_NEAR(fit.weights[20], 1.2f, 0.1f);
    for (std::size_t k = 0; k < kBorderFeatureCount; ++k) {
        if (k != 1 && k != 6 && k != 20) {
            EXPECT_NEAR(fit.weights[k], 0.0f, 0.1f) << k;
        }
    }
    EXPECT_FLOAT_EQ(fit.threshold, 0.6f);
    EXPECT_EQ(fit.large_part_points, 99u);
    EXPECT_NO_THROW(fit.Validate());

    // A strong penalty shrinks the weights towards zero; the rows' weights count.
    const BorderClassifierParams shrunk = FitBorderClassifier(rows, 10.0, start);
    EXPECT_LT(std::abs(shrunk.weights[1]), 0.5f * std::abs(fit.weights[1]));
    std::vector<BorderExample> doubled = rows;
    for (BorderExample& r : doubled) r.weight = 2.0;
    const BorderClassifierParams same = FitBorderClassifier(doubled, 0.0, start);
    EXPECT_NEAR(same.weights[1], fit.weights[1], 1e-3f);

    // Deterministic.
    const BorderClassifierParams again = FitBorderClassifier(rows, 0.0, start);
    EXPECT_EQ(again.weights, fit.weights);
    EXPECT_EQ(again.bias, fit.bias);
}

TEST(BorderClassifier, RejectsBadParametersAndRows) {
    BorderClassifierParams p;
    EXPECT_NO_THROW(p.Validate());
    for (float t : {0.0f, 1.0f, -0.5f, NAN}) {
        p = {};
        p.threshold = t;
        EXPECT_THROW(p.Validate(), InvalidArgument) << t;
    }
    p = {};
    p.bias = INFINITY;
    EXPECT_THROW(p.Validate(), InvalidArgument);
    p = {};
    p.weights[4] = NAN;
    EXPECT_THROW(p.Validate(), InvalidArgument);
    ConvexitySplitParams cp;
    cp.classifier.weights[2] = NAN;
    const Boxes boxes = TouchingBoxes();
    EXPECT_THROW(SplitByConvexity(boxes.cloud, boxes.object, boxes.parts, cp, kTable),
                 InvalidArgument);

    std::vector<BorderExample> rows = RuleRows(200, 3);
    EXPECT_THROW(FitBorderClassifier({}, 0.01), InvalidArgument);
    EXPECT_THROW(FitBorderClassifier(rows, -1.0), InvalidArgument);
    EXPECT_THROW(FitBorderClassifier(rows, NAN), InvalidArgument);
    std::vector<BorderExample> one_kind = rows;
    for (BorderExample& r : one_kind) r.same = true;
    EXPECT_THROW(FitBorderClassifier(one_kind, 0.01), InvalidArgument);
    std::vector<BorderExample> bad = rows;
    bad[5].features[3] = NAN;
    EXPECT_THROW(FitBorderClassifier(bad, 0.01), InvalidArgument);
    bad = rows;
    bad[5].weight = -1.0;
    EXPECT_THROW(FitBorderClassifier(bad, 0.01), InvalidArgument);
}

// A part that holds two faces of a box (region growing ran across a rounded edge) is cut into
// the two faces; a flat part stays whole.
TEST(FoldedParts, APartOverTwoFacesIsCutIntoTheFaces) {
    Boxes boxes = TouchingBoxes();
    std::vector<Indices> parts = boxes.parts;
    Indices merged = parts[0];
    merged.insert(merged.end(), parts[1].begin(), parts[1].end());
    std::vector<Indices> folded = {merged, parts[2], parts[3], parts[4], parts[5]};
    const PartBorders borders = ComputePartBorders(boxes.cloud, boxes.object, folded, {}, kTable);
    const std::vector<Indices> cut =
        SplitFoldedParts(boxes.cloud, boxes.object, folded, borders, FoldSplitParams{});
    ASSERT_EQ(cut.size(), 6u);
    std::size_t points = 0;
    for (const Indices& p : cut) points += p.size();
    EXPECT_EQ(points, boxes.object.size());
    // Each of A's top and front ends up (nearly) whole in one piece.
    for (const std::size_t face : {0u, 1u}) {
        std::size_t best = 0;
        for (const Indices& p : cut) {
            std::size_t shared = 0;
            for (Index i : p) {
                shared += std::find(boxes.parts[face].begin(), boxes.parts[face].end(), i) !=
                                  boxes.parts[face].end()
                              ? 1
                              : 0;
            }
            best = std::max(best, shared);
        }
        EXPECT_GE(static_cast<double>(best), 0.85 * boxes.parts[face].size()) << face;
    }
    // Flat parts only: nothing to cut.
    const PartBorders flat = ComputePartBorders(boxes.cloud, boxes.object, boxes.parts, {}, kTable);
    EXPECT_EQ(SplitFoldedParts(boxes.cloud, boxes.object, boxes.parts, flat, FoldSplitParams{}),
              boxes.parts);
    FoldSplitParams bad;
    bad.min_fold_deg = 0.0f;
    EXPECT_THROW(SplitFoldedParts(boxes.cloud, boxes.object, boxes.parts, flat, bad),
                 InvalidArgument);
}

}  // namespace
}  // namespace multicue

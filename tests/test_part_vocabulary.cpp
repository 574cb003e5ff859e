// Vocabulary of parts and whole-cluster descriptors (recognition module, baselines of
// docs/part-graph.md).

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "multicue/core/exceptions.hpp"
#include "multicue/recognition/part_vocabulary.hpp"

namespace multicue {
namespace {

// Three well separated Gaussian blobs in 4 dimensions, one category each.
struct Mixture {
    FeatureMatrix x;
    std::vector<Category> categories;
    std::vector<Eigen::Vector4f> centres;
};

Mixture MakeMixture(std::uint32_t seed, std::size_t per_blob = 60) {
    Mixture m;
    m.centres = {Eigen::Vector4f(0, 0, 0, 0), Eigen::Vector4f(5, 0, 1, 0),
                 Eigen::Vector4f(0, 5, 0, -3)};
    const Category cats[3] = {Category::kBox, Category::kCylinder, Category::kFlat};
    std::mt19937 rng(seed);
    std::normal_distribution<float> noise(0.0f, 0.3f);
    m.x.resize(static_cast<Eigen::Index>(3 * per_blob), 4);
    Eigen::Index r = 0;
    for (std::size_t i = 0; i < per_blob; ++i) {
        for (int b = 0; b < 3; ++b) {
            for (int j = 0; j < 4; ++j) m.x(r, j) = m.centres[b][j] + noise(rng);
            m.categories.push_back(cats[b]);
            ++r;
        }
    }
    return m;
}

TEST(PartVocabulary, RecoversTheClustersOfAMixture) {
    const Mixture m = MakeMixture(3);
    PartVocabularyParams p;
    p.words = 3;
    p.activations = 1;
    const PartVocabulary v = PartVocabulary::Train(m.x, m.categories, p);
    ASSERT_EQ(v.num_words(), 3u);
    ASSERT_EQ(v.dims(), 4u);
    const Category cats[3] = {Category::kBox, Category::kCylinder, Category::kFlat};
    for (int b = 0; b < 3; ++b) {
        // Some word lies at the blob's centre and holds only its category.
        double best = std::numeric_limits<double>::infinity();
        int word = -1;
        for (std::size_t w = 0; w < v.num_words(); ++w) {
            const double d =
                (v.words().row(static_cast<Eigen::Index>(w)).transpose() - m.centres[b]).norm();
            if (d < best) {
                best = d;
                word = static_cast<int>(w);
            }
        }
        EXPECT_LT(best, 0.15);
        const auto& counts = v.word_counts()[static_cast<std::size_t>(word)];
        EXPECT_EQ(counts[static_cast<std::size_t>(cats[b])], 60.0f);
        const auto p_centre = v.PartProbabilities(std::span<const float>(m.centres[b].data(), 4));
        EXPECT_NEAR(p_centre[static_cast<std::size_t>(cats[b])], 1.0f, 1e-6f);
    }
}

TEST(PartVocabulary, ActivationsAndBagOfWords) {
    const Mixture m = MakeMixture(3);
    PartVocabularyParams p;
    p.words = 3;
    p.activations = 2;
    const PartVocabulary v = PartVocabulary::Train(m.x, m.categories, p);
    const Eigen::Vector4f q(0.2f, 0.0f, 0.0f, 0.0f);
    const auto a = v.Activate(std::span<const float>(q.data(), 4));
    ASSERT_EQ(a.size(), 2u);
    EXPECT_NEAR(a[0].second + a[1].second, 1.0f, 1e-6f);
    EXPECT_GT(a[0].second, a[1].second);  // nearest word weighs most (1 / distance)
    const FeatureVector bow = v.BagOfWords(m.x.topRows(9));
    ASSERT_EQ(bow.size(), 3);
    EXPECT_NEAR(bow.sum(), 1.0f, 1e-5f);
    EXPECT_TRUE((bow.array() > 0.2f).all()) << bow.transpose();  // three parts of each blob
    EXPECT_EQ(v.BagOfWords(FeatureMatrix(0, 4)).sum(), 0.0f);
}

TEST(PartVocabulary, DeterministicAndNormalised) {
    const Mixture m = MakeMixture(7);
    PartVocabularyParams p;
    p.words = 5;
    p.normalize = true;
    p.num_threads = 1;
    const PartVocabulary a = PartVocabulary::Train(m.x, m.categories, p);
    p.num_threads = 2;
    const PartVocabulary b = PartVocabulary::Train(m.x, m.categories, p);
    EXPECT_TRUE(a.words().isApprox(b.words()));
    EXPECT_EQ(a.words(), b.words());
    // Normalised words lie in [0, 1]; far-away queries are clamped, not rejected.
    EXPECT_GE(a.words().minCoeff(), 0.0f);
    EXPECT_LE(a.words().maxCoeff(), 1.0f);
    const Eigen::Vector4f far(100, -100, 100, 100);
    EXPECT_NO_THROW(a.Activate(std::span<const float>(far.data(), 4)));
    // More words than parts: one word per part.
    p.words = 1000;
    EXPECT_EQ(
        PartVocabulary::Train(m.x.topRows(4), {m.categories.begin(), m.categories.begin() + 4}, p)
            .num_words(),
        4u);
}

TEST(PartVocabulary, BadInput) {
    const Mixture m = MakeMixture(9, 4);
    PartVocabularyParams p;
    p.words = 2;
    EXPECT_THROW(PartVocabulary::Train(FeatureMatrix(0, 4), {}, p), InvalidArgument);
    EXPECT_THROW(PartVocabulary::Train(m.x, {Category::kBox}, p), InvalidArgument);
    auto none = m.categories;
    none[1] = Category::kNone;
    EXPECT_THROW(PartVocabulary::Train(m.x, none, p), InvalidArgument);
    PartVocabularyParams zero = p;
    zero.words = 0;
    EXPECT_THROW(PartVocabulary::Train(m.x, m.categories, zero), InvalidArgument);
    zero = p;
    zero.activations = 0;
    EXPECT_THROW(PartVocabulary::Train(m.x, m.categories, zero), InvalidArgument);
    FeatureMatrix nan = m.x;
    nan(2, 1) = std::numeric_limits<float>::quiet_NaN();
    EXPECT_THROW(PartVocabulary::Train(nan, m.categories, p), DataError);
    const PartVocabulary v = PartVocabulary::Train(m.x, m.categories, p);
    const float three[3] = {0, 0, 0};
    EXPECT_THROW(v.Activate(three), InvalidArgument);
    EXPECT_THROW(v.BagOfWords(FeatureMatrix::Zero(2, 3)), InvalidArgument);
    const float bad[4] = {0, std::numeric_limits<float>::infinity(), 0, 0};
    EXPECT_THROW(v.Activate(bad), DataError);
    const float ok[4] = {0, 0, 0, 0};
    EXPECT_THROW(PartVocabulary().Activate(ok), InvalidArgument);
}

// Points on the surface of an axis-aligned box with outward normals.
PointCloud BoxSurface(float sx, float sy, float sz, float step) {
    PointCloud c;
    const Eigen::Vector3f half(sx / 2, sy / 2, sz / 2);
    for (int axis = 0; axis < 3; ++axis) {
        const int u = (axis + 1) % 3, w = (axis + 2) % 3;
        for (float s : {-1.0f, 1.0f}) {
            for (float a = -half[u]; a <= half[u] + 1e-6f; a += step) {
                for (float b = -half[w]; b <= half[w] + 1e-6f; b += step) {
                    Eigen::Vector3f p, n = Eigen::Vector3f::Zero();
                    p[axis] = s * half[axis];
                    p[u] = a;
                    p[w] = b;
                    n[axis] = s;
                    c.points.push_back(p + Eigen::Vector3f(0, 0, 1));
                    c.normals.push_back(n);
                }
            }
        }
    }
    c.width = static_cast<std::uint32_t>(c.points.size());
    c.height = 1;
    return c;
}

Indices All(const PointCloud& c) {
    Indices idx(c.size());
    for (std::size_t i = 0; i < c.size(); ++i) idx[i] = static_cast<Index>(i);
    return idx;
}

TEST(ClusterDescriptor, BlocksAndExtents) {
    const PointCloud box = BoxSurface(0.3f, 0.2f, 0.1f, 0.005f);
    ClusterDescriptorParams p;
    p.size_weight = 10.0f;
    const FeatureVector d = ComputeClusterDescriptor(box, All(box), p);
    ASSERT_EQ(d.size(), kClusterDescriptorSize);
    EXPECT_TRUE(d.allFinite());
    EXPECT_NEAR(d.head(21).squaredNorm(), 1.0f, 1e-4f);  // sqrt of a unit-sum histogram
    // Four VFH blocks are filled (f4 stays empty by default), each of squared norm 1/4.
    EXPECT_NEAR(d.segment(21, 308).squaredNorm(), 1.0f, 1e-3f);
    // The extents of a box surface: sides of its largest faces, order descending.
    const float e0 = d[21 + 308] / 10.0f, e1 = d[21 + 309] / 10.0f, e2 = d[21 + 310] / 10.0f;
    EXPECT_GT(e0, e1);
    EXPECT_GT(e1, e2);
    EXPECT_GT(e0, 0.25f);
    EXPECT_LT(e0, 0.36f);
    // Deterministic; without a size weight the extents stay zero.
    EXPECT_EQ(ComputeClusterDescriptor(box, All(box), p), d);
    EXPECT_EQ(ComputeClusterDescriptor(box, All(box)).tail(3).sum(), 0.0f);
    // A flat patch (one face) differs in shape from the box.
    Indices face;
    for (std::size_t i = 0; i < box.size(); ++i) {
        if (box.normals[i].z() > 0.5f) face.push_back(static_cast<Index>(i));
    }
    const FeatureVector f = ComputeClusterDescriptor(box, face);
    EXPECT_GT((f.head(21) - d.head(21)).norm(), 0.2f);
}

TEST(ClusterDescriptor, BadAndEmptyInput) {
    PointCloud box = BoxSurface(0.1f, 0.1f, 0.1f, 0.01f);
    EXPECT_EQ(ComputeClusterDescriptor(box, {}).cwiseAbs().sum(), 0.0f);
    EXPECT_EQ(ComputeClusterDescriptor(box, {0, 1}).cwiseAbs().sum(), 0.0f);  // too few
    EXPECT_THROW(ComputeClusterDescriptor(box, {static_cast<Index>(box.size())}), InvalidArgument);
    ClusterDescriptorParams p;
    p.size_weight = -1.0f;
    EXPECT_THROW(ComputeClusterDescriptor(box, All(box), p), InvalidArgument);
    box.points[0] = Eigen::Vector3f::Constant(std::numeric_limits<float>::quiet_NaN());
    EXPECT_TRUE(ComputeClusterDescriptor(box, All(box)).allFinite());  // NaN point skipped
    box.normals.clear();
    EXPECT_THROW(ComputeClusterDescriptor(box, All(box)), DataError);
}

}  // namespace
}  // namespace multicue

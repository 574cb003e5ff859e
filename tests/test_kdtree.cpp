#include <algorithm>
#include <limits>
#include <numeric>

#include <gtest/gtest.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/search/kdtree.hpp"
#include "test_util.hpp"

namespace multicue {
namespace {

// Brute-force oracle: indices of the k nearest finite points (ties broken by index).
Indices BruteKnn(const PointCloud& c, const Eigen::Vector3f& q, std::size_t k) {
    Indices idx;
    for (std::size_t i = 0; i < c.size(); ++i) {
        if (c.points[i].allFinite()) idx.push_back(static_cast<Index>(i));
    }
    std::sort(idx.begin(), idx.end(), [&](Index a, Index b) {
        const float da = (c.points[a] - q).squaredNorm(), db = (c.points[b] - q).squaredNorm();
        return da < db || (da == db && a < b);
    });
    idx.resize(std::min(k, idx.size()));
    return idx;
}

TEST(KdTree, KnnMatchesBruteForce) {
    PointCloud c = test::RandomCloud(3000, 7);
    c.points[5] = Eigen::Vector3f::Constant(std::numeric_limits<float>::quiet_NaN());
    const KdTree tree(c);
    EXPECT_EQ(tree.size(), 2999u);
    const PointCloud queries = test::RandomCloud(50, 8);
    Indices idx;
    std::vector<float> d2;
    for (const auto& q : queries.points) {
        ASSERT_EQ(tree.SearchKnn(q, 10, idx, d2), 10u);
        EXPECT_EQ(idx, BruteKnn(c, q, 10));
        EXPECT_TRUE(std::is_sorted(d2.begin(), d2.end()));
    }
}

TEST(KdTree, RadiusMatchesBruteForce) {
    const PointCloud c = test::RandomCloud(3000, 9);
    const KdTree tree(c);
    Indices idx;
    std::vector<float> d2;
    for (int t = 0; t < 20; ++t) {
        const Eigen::Vector3f q = c.points[static_cast<std::size_t>(t) * 37];
        tree.SearchRadius(q, 0.2f, idx, d2);
        Indices expected;
        for (std::size_t i = 0; i < c.size(); ++i) {
            if ((c.points[i] - q).squaredNorm() <= 0.04f) expected.push_back(static_cast<Index>(i));
        }
        Indices got = idx;
        std::sort(got.begin(), got.end());
        EXPECT_EQ(got, expected);
        EXPECT_TRUE(std::is_sorted(d2.begin(), d2.end()));
        tree.SearchRadius(q, 0.2f, idx, d2, 3);
        EXPECT_EQ(idx.size(), std::min<std::size_t>(3, expected.size()));
    }
}

TEST(KdTree, SubsetAndNearest) {
    const PointCloud c({{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {3, 0, 0}});
    const KdTree tree(c, Indices{1, 3});
    Index i = 0;
    float d = 0;
    ASSERT_TRUE(tree.SearchNearest({0.1f, 0, 0}, i, d));
    EXPECT_EQ(i, 1u);
    EXPECT_NEAR(d, 0.81f, 1e-6f);
    EXPECT_THROW(KdTree(c, Indices{9}), InvalidArgument);
}

TEST(KdTree, NearestWithinMatchesBruteForce) {
    const PointCloud c = test::RandomCloud(2000, 11);
    const KdTree tree(c);
    const PointCloud queries = test::RandomCloud(200, 12, 1.5f);
    for (const float r : {0.02f, 0.05f, 0.2f}) {
        for (const auto& q : queries.points) {
            Index nearest = 0;
            float d2 = std::numeric_limits<float>::infinity();
            for (std::size_t k = 0; k < c.size(); ++k) {
                const float dk = (c.points[k] - q).squaredNorm();
                if (dk < d2) {
                    d2 = dk;
                    nearest = static_cast<Index>(k);
                }
            }
            Index i = 0;
            float found = 0.0f;
            const bool ok = tree.SearchNearestWithin(q, r, i, found);
            EXPECT_EQ(ok, d2 <= r * r);
            if (ok) {
                EXPECT_EQ(i, nearest);
                EXPECT_EQ(found, d2);
            }
        }
    }
    // A point exactly at the radius is found.
    Index i = 0;
    float d2 = 0.0f;
    EXPECT_TRUE(
        tree.SearchNearestWithin(c.points[0] + Eigen::Vector3f(0.0f, 0.0f, 0.0f), 1e-6f, i, d2));
    EXPECT_THROW(tree.SearchNearestWithin(c.points[0], 0.0f, i, d2), InvalidArgument);
    EXPECT_FALSE(KdTree(PointCloud{}).SearchNearestWithin(c.points[0], 1.0f, i, d2));
}

// The k nearest within a radius: the brute-force k nearest cut at the radius; its nearest is
// SearchNearestWithin's, also among duplicated points (ties).
TEST(KdTree, KnnWithinMatchesBruteForceAndNearestWithin) {
    PointCloud c = test::RandomCloud(1500, 21);
    for (std::size_t i = 0; i < 300; ++i) c.points.push_back(c.points[i * 3]);  // exact ties
    const KdTree tree(c);
    const PointCloud queries = test::RandomCloud(150, 22, 1.5f);
    for (const float r : {0.03f, 0.1f, 0.5f}) {
        for (const auto& q : queries.points) {
            for (const int k : {1, 2, 5}) {
                Index idx[5];
                float d2[5];
                const std::size_t n = tree.SearchKnnWithin(q, k, r, idx, d2);
                Indices expected = BruteKnn(c, q, static_cast<std::size_t>(k));
                std::erase_if(expected, [&](Index i) {
                    return KdTree::SquaredDistance(c.points[i], q) > r * r;
                });
                ASSERT_EQ(n, expected.size());
                for (std::size_t j = 0; j < n; ++j) {
                    EXPECT_EQ(d2[j], KdTree::SquaredDistance(c.points[expected[j]], q));
                }
                Index nearest = 0;
                float nearest_d2 = 0.0f;
                ASSERT_EQ(tree.SearchNearestWithin(q, r, nearest, nearest_d2), n > 0);
                if (n > 0) {
                    EXPECT_EQ(idx[0], nearest);
                    EXPECT_EQ(d2[0], nearest_d2);
                }
            }
        }
    }
    Index idx[2];
    float d2[2];
    EXPECT_THROW(tree.SearchKnnWithin(c.points[0], 0, 1.0f, idx, d2), InvalidArgument);
    EXPECT_THROW(tree.SearchKnnWithin(c.points[0], 2, -1.0f, idx, d2), InvalidArgument);
    EXPECT_EQ(KdTree(PointCloud{}).SearchKnnWithin(c.points[0], 2, 1.0f, idx, d2), 0u);
}

TEST(KdTree, EmptyAndBadParameters) {
    const KdTree tree{PointCloud{}};
    Indices idx;
    std::vector<float> d2;
    EXPECT_EQ(tree.SearchKnn({0, 0, 0}, 3, idx, d2), 0u);
    EXPECT_EQ(tree.SearchRadius({0, 0, 0}, 1.0f, idx, d2), 0u);
    Index i;
    float d;
    EXPECT_FALSE(tree.SearchNearest({0, 0, 0}, i, d));
    EXPECT_THROW(tree.SearchKnn({0, 0, 0}, 0, idx, d2), InvalidArgument);
    EXPECT_THROW(tree.SearchRadius({0, 0, 0}, -0.1f, idx, d2), InvalidArgument);
    EXPECT_THROW(KdTree(test::RandomCloud(3), KdTreeParams{.leaf_size = 0}), InvalidArgument);
}

}  // namespace
}  // namespace multicue

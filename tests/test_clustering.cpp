#include <algorithm>
#include <cmath>
#include <cstdint>
#include <deque>
#include <limits>
#include <numbers>
#include <numeric>
#include <random>
#include <set>
#include <vector>

#include <gtest/gtest.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/search/kdtree.hpp"
#include "multicue/search/organized.hpp"
#include "multicue/segmentation/euclidean_clustering.hpp"
#include "multicue/segmentation/region_growing.hpp"
#include "test_util.hpp"

namespace multicue {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

using ClusterSet = std::set<Indices>;

ClusterSet AsSet(std::vector<Indices> clusters) {
    ClusterSet s;
    for (auto& c : clusters) {
        std::sort(c.begin(), c.end());
        s.insert(c);
    }
    return s;
}

// ---------------------------------------------------------------------------------------------
// Synthetic data

// Gaussian blobs of random sizes plus scattered points and a few NaN points.
PointCloud RandomBlobs(std::uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> uniform(-1.0f, 1.0f);
    std::uniform_int_distribution<int> blob_size(20, 200);
    std::normal_distribution<float> gauss(0.0f, 0.04f);
    PointCloud c;
    for (int b = 0; b < 6; ++b) {
        const Eigen::Vector3f center(uniform(rng), uniform(rng), uniform(rng));
        const int m = blob_size(rng);
        for (int i = 0; i < m; ++i) {
            c.points.push_back(center + Eigen::Vector3f(gauss(rng), gauss(rng), gauss(rng)));
        }
    }
    for (int i = 0; i < 150; ++i) c.points.emplace_back(uniform(rng), uniform(rng), uniform(rng));
    for (int i = 0; i < 5; ++i)
        c.points.insert(c.points.begin() + 17 * i, Eigen::Vector3f(kNaN, 0, 0));
    c.SetUnorganized();
    return c;
}

// Brute-force Euclidean clustering: flood fill scanning every point for every point.
std::vector<Indices> BruteForceClusters(const PointCloud& c, const std::vector<bool>& use,
                                        float tolerance) {
    const std::size_t n = c.size();
    std::vector<bool> done(n, false);
    std::vector<Indices> clusters;
    for (std::size_t s = 0; s < n; ++s) {
        if (!use[s] || done[s] || !c.IsFinite(s)) continue;
        Indices cluster{static_cast<Index>(s)};
        done[s] = true;
        for (std::size_t h = 0; h < cluster.size(); ++h) {
            for (std::size_t j = 0; j < n; ++j) {
                if (!use[j] || done[j] || !c.IsFinite(j)) continue;
                if ((c.points[j] - c.points[cluster[h]]).squaredNorm() < tolerance * tolerance) {
                    done[j] = true;
                    cluster.push_back(static_cast<Index>(j));
                }
            }
        }
        clusters.push_back(cluster);
    }
    return clusters;
}

// Appends the surface of a box sampled on a jittered grid (about `spacing` apart, no point on an
// edge), with outward normals. Returns the face (0..5) of every appended point.
std::vector<int> AppendBox(PointCloud& c, const Eigen::Vector3f& center,
                           const Eigen::Matrix3f& rotation, const Eigen::Vector3f& extents,
                           float spacing, float noise, std::mt19937& rng) {
    std::normal_distribution<float> gauss(0.0f, noise);
    std::vector<int> faces;
    for (int axis = 0; axis < 3; ++axis) {
        const int a = (axis + 1) % 3;
        const int b = (axis + 2) % 3;
        const int na = std::max(1, static_cast<int>(std::round(extents[a] / spacing)));
        const int nb = std::max(1, static_cast<int>(std::round(extents[b] / spacing)));
        for (int sign = -1; sign <= 1; sign += 2) {
            Eigen::Vector3f normal = Eigen::Vector3f::Zero();
            normal[axis] = static_cast<float>(sign);
            for (int i = 0; i < na; ++i) {
                for (int j = 0; j < nb; ++j) {
                    Eigen::Vector3f p;
                    p[axis] = 0.5f * extents[axis] * static_cast<float>(sign);
                    p[a] = extents[a] * ((static_cast<float>(i) + 0.5f) / na - 0.5f);
                    p[b] = extents[b] * ((static_cast<float>(j) + 0.5f) / nb - 0.5f);
                    p += Eigen::Vector3f(gauss(rng), gauss(rng), gauss(rng));
                    c.points.push_back(center + rotation * p);
                    c.normals.push_back(rotation * normal);
                    faces.push_back(2 * axis + (sign > 0 ? 1 : 0));
                }
            }
        }
    }
    c.SetUnorganized();
    return faces;
}

// A normal tilted from `n` by a random angle of a few degrees.
Eigen::Vector3f Perturb(const Eigen::Vector3f& n, float sigma, std::mt19937& rng) {
    std::normal_distribution<float> gauss(0.0f, sigma);
    return (n + Eigen::Vector3f(gauss(rng), gauss(rng), gauss(rng))).normalized();
}

void RandomCurvature(PointCloud& c, std::mt19937& rng, float lo = 0.0f, float hi = 0.01f) {
    std::uniform_real_distribution<float> u(lo, hi);
    c.curvature.resize(c.size());
    for (auto& k : c.curvature) k = u(rng);
}

// An organized frame of a pinhole camera (z forward, y down) looking at two spheres and two
// rotated boxes on a NaN background. Grazing hits (incidence over 60 degrees) are dropped, as a
// depth sensor would, so that neighbouring pixels on one object are never far apart in 3D.
struct OrganizedScene {
    PointCloud cloud;
    std::vector<int> object;              // per pixel: -1 background, else 0..3
    std::vector<Eigen::Vector3f> normal;  // per pixel: the surface normal, NaN on the background
};

OrganizedScene MakeOrganizedScene(std::uint32_t seed) {
    constexpr int kWidth = 320;
    constexpr int kHeight = 240;
    constexpr float kF = 260.0f;
    struct Sphere {
        Eigen::Vector3f c;
        float r;
    };
    struct Box {
        Eigen::Vector3f c;
        Eigen::Matrix3f R;
        Eigen::Vector3f half;
    };
    const std::vector<Sphere> spheres{{{-0.30f, -0.05f, 1.3f}, 0.12f},
                                      {{0.30f, 0.15f, 1.6f}, 0.10f}};
    const std::vector<Box> boxes{{{0.10f, -0.15f, 1.1f},
                                  (Eigen::AngleAxisf(0.5f, Eigen::Vector3f::UnitY()) *
                                   Eigen::AngleAxisf(0.4f, Eigen::Vector3f::UnitX()))
                                      .toRotationMatrix(),
                                  {0.08f, 0.06f, 0.07f}},
                                 {{-0.05f, 0.22f, 1.2f},
                                  (Eigen::AngleAxisf(-0.6f, Eigen::Vector3f::UnitY()) *
                                   Eigen::AngleAxisf(0.3f, Eigen::Vector3f::UnitX()))
                                      .toRotationMatrix(),
                                  {0.10f, 0.04f, 0.06f}}};
    std::mt19937 rng(seed);
    std::normal_distribution<float> depth_noise(0.0f, 0.001f);
    const float min_cos = std::cos(60.0f * std::numbers::pi_v<float> / 180.0f);

    OrganizedScene scene;
    scene.cloud.points.assign(kWidth * kHeight, Eigen::Vector3f::Constant(kNaN));
    scene.object.assign(kWidth * kHeight, -1);
    scene.normal.assign(kWidth * kHeight, Eigen::Vector3f::Constant(kNaN));
    for (int v = 0; v < kHeight; ++v) {
        for (int u = 0; u < kWidth; ++u) {
            const Eigen::Vector3f d =
                Eigen::Vector3f((u - 159.5f) / kF, (v - 119.5f) / kF, 1.0f).normalized();
            float best_t = std::numeric_limits<float>::infinity();
            Eigen::Vector3f best_n = Eigen::Vector3f::Zero();
            int best_object = -1;
            for (std::size_t s = 0; s < spheres.size(); ++s) {
                const float b = d.dot(spheres[s].c);
                const float disc =
                    b * b - (spheres[s].c.squaredNorm() - spheres[s].r * spheres[s].r);
                if (disc < 0.0f) continue;
                const float t = b - std::sqrt(disc);
                if (t > 0.0f && t < best_t) {
                    best_t = t;
                    best_n = (t * d - spheres[s].c) / spheres[s].r;
                    best_object = static_cast<int>(s);
                }
            }
            for (std::size_t k = 0; k < boxes.size(); ++k) {
                const Box& box = boxes[k];
                const Eigen::Vector3f o = box.R.transpose() * (-box.c);
                const Eigen::Vector3f dl = box.R.transpose() * d;
                float t_near = -std::numeric_limits<float>::infinity();
                float t_far = std::numeric_limits<float>::infinity();
                int axis_near = -1;
                for (int a = 0; a < 3; ++a) {
                    const float t1 = (-box.half[a] - o[a]) / dl[a];
                    const float t2 = (box.half[a] - o[a]) / dl[a];
                    if (std::min(t1, t2) > t_near) {
                        t_near = std::min(t1, t2);
                        axis_near = a;
                    }
                    t_far = std::min(t_far, std::max(t1, t2));
                }
                if (t_near > t_far || t_near <= 0.0f || t_near >= best_t) continue;
                Eigen::Vector3f nl = Eigen::Vector3f::Zero();
                nl[axis_near] = dl[axis_near] > 0.0f ? -1.0f : 1.0f;
                best_t = t_near;
                best_n = box.R * nl;
                best_object = static_cast<int>(spheres.size() + k);
            }
            if (best_object < 0 || -d.dot(best_n) < min_cos) continue;
            const std::size_t i =
                static_cast<std::size_t>(v) * kWidth + static_cast<std::size_t>(u);
            scene.cloud.points[i] = (best_t + depth_noise(rng)) * d;
            scene.object[i] = best_object;
            scene.normal[i] = best_n;
        }
    }
    scene.cloud.width = kWidth;
    scene.cloud.height = kHeight;
    return scene;
}

// ---------------------------------------------------------------------------------------------
// Euclidean clustering with a k-d tree

TEST(EuclideanClustering, MatchesBruteForceFloodFill) {
    for (std::uint32_t seed : {1u, 2u, 3u}) {
        const PointCloud c = RandomBlobs(seed);
        const KdTree tree(c);
        for (float tolerance : {0.03f, 0.08f, 0.2f}) {
            const auto result = EuclideanClustering(c, tree, {.tolerance = tolerance});
            const auto expected =
                BruteForceClusters(c, std::vector<bool>(c.size(), true), tolerance);
            EXPECT_EQ(AsSet(result.clusters), AsSet(expected))
                << "seed " << seed << " tol " << tolerance;
            EXPECT_EQ(result.num_points, c.CountFinite());
        }
    }
}

TEST(EuclideanClustering, SubsetMatchesBruteForceWithEitherTree) {
    const PointCloud c = RandomBlobs(4);
    Indices subset;
    std::vector<bool> use(c.size(), false);
    for (std::size_t i = 0; i < c.size(); i += 2) {
        subset.push_back(static_cast<Index>(i));
        use[i] = true;
    }
    subset.push_back(subset.front());  // duplicates are ignored
    const auto expected = AsSet(BruteForceClusters(c, use, 0.08f));
    const KdTree whole(c);
    const KdTree part(c, subset);
    const EuclideanClusteringParams params{.tolerance = 0.08f, .subset = subset};
    EXPECT_EQ(AsSet(EuclideanClustering(c, whole, params).clusters), expected);
    EXPECT_EQ(AsSet(EuclideanClustering(c, part, params).clusters), expected);
}

// The grid version is exact: the same clusters, in the same order, as the k-d tree version, on
// random blobs, on subsets, and on a dense surface whose cells hold many points.
TEST(EuclideanClusteringGrid, IdenticalToTheKdTreeVersion) {
    for (std::uint32_t seed : {1u, 2u, 3u, 7u}) {
        const PointCloud c = RandomBlobs(seed);
        const KdTree tree(c);
        for (float tolerance : {0.01f, 0.03f, 0.08f, 0.2f, 1.5f}) {
            const EuclideanClusteringParams params{
                .tolerance = tolerance, .min_cluster_size = 2, .compute_labels = true};
            const auto grid = EuclideanClusteringGrid(c, params);
            const auto with_tree = EuclideanClustering(c, tree, params);
            EXPECT_EQ(grid.clusters, with_tree.clusters) << "seed " << seed << " tol " << tolerance;
            EXPECT_EQ(grid.labels, with_tree.labels);
            EXPECT_EQ(grid.num_points, with_tree.num_points);
            EXPECT_EQ(grid.num_too_small, with_tree.num_too_small);
        }
    }
    const PointCloud c = RandomBlobs(4);
    Indices subset;
    std::vector<bool> use(c.size(), false);
    for (std::size_t i = 0; i < c.size(); i += 3) {
        subset.push_back(static_cast<Index>(i));
        use[i] = true;
    }
    EXPECT_EQ(AsSet(EuclideanClusteringGrid(c, {.tolerance = 0.08f, .subset = subset}).clusters),
              AsSet(BruteForceClusters(c, use, 0.08f)));
    // A subset given out of order, with repeats and a NaN point: the same as the plain one.
    PointCloud holes = c;
    holes.points[subset[5]] = Eigen::Vector3f::Constant(kNaN);
    Indices shuffled = subset;
    shuffled.insert(shuffled.end(), subset.begin(), subset.begin() + 40);
    std::shuffle(shuffled.begin(), shuffled.end(), std::mt19937(5));
    const auto plain = EuclideanClusteringGrid(holes, {.tolerance = 0.08f, .subset = subset});
    const auto mixed = EuclideanClusteringGrid(holes, {.tolerance = 0.08f, .subset = shuffled});
    EXPECT_EQ(mixed.clusters, plain.clusters);
    EXPECT_EQ(mixed.num_points, plain.num_points);
    EXPECT_LT(plain.num_points, subset.size());
}

TEST(EuclideanClusteringGrid, DenseSheetsOneGapApart) {
    // Two dense sheets 1.3 cm apart: one cluster at a 1.5 cm tolerance, two at 1 cm.
    std::mt19937 rng(11);
    std::normal_distribution<float> noise(0.0f, 0.0003f);
    PointCloud c;
    for (float x = 0.0f; x < 0.3f; x += 0.002f) {
        for (float y = 0.0f; y < 0.2f; y += 0.002f) {
            c.points.emplace_back(x, y, noise(rng));
            c.points.emplace_back(x, y, 0.013f + noise(rng));
        }
    }
    c.SetUnorganized();
    const KdTree tree(c);
    for (float tolerance : {0.01f, 0.015f}) {
        const auto grid = EuclideanClusteringGrid(c, {.tolerance = tolerance});
        EXPECT_EQ(grid.clusters, EuclideanClustering(c, tree, {.tolerance = tolerance}).clusters);
        EXPECT_EQ(grid.clusters.size(), tolerance < 0.013f ? 2u : 1u);
    }
}

TEST(EuclideanClusteringGrid, ContractAndEmptyInput) {
    PointCloud empty;
    EXPECT_TRUE(EuclideanClusteringGrid(empty, {}).clusters.empty());
    PointCloud c = RandomBlobs(1);
    EXPECT_THROW(EuclideanClusteringGrid(c, {.tolerance = 0.0f}), InvalidArgument);
    EXPECT_THROW(EuclideanClusteringGrid(c, {.tolerance = kNaN}), InvalidArgument);
    EXPECT_THROW(EuclideanClusteringGrid(c, {.subset = {static_cast<Index>(c.size())}}),
                 InvalidArgument);
    // Far beyond the grid's reach: the k-d tree's answer (a lone point far away).
    c.points.emplace_back(1e5f, 0.0f, 0.0f);
    c.SetUnorganized();
    const KdTree tree(c);
    EXPECT_EQ(EuclideanClusteringGrid(c, {.tolerance = 0.01f}).clusters,
              EuclideanClustering(c, tree, {.tolerance = 0.01f}).clusters);
}

TEST(EuclideanClustering, ThreeNoisyBoxesGiveThreeClustersOfTheRightSize) {
    std::mt19937 rng(5);
    PointCloud c;
    const Eigen::Matrix3f I = Eigen::Matrix3f::Identity();
    const auto yaw = Eigen::AngleAxisf(0.7f, Eigen::Vector3f::UnitZ()).toRotationMatrix();
    const std::size_t a =
        AppendBox(c, {0.0f, 0.0f, 0.1f}, I, {0.2f, 0.15f, 0.2f}, 0.01f, 0.001f, rng).size();
    const std::size_t b =
        AppendBox(c, {0.4f, 0.1f, 0.05f}, yaw, {0.1f, 0.1f, 0.1f}, 0.01f, 0.001f, rng).size();
    const std::size_t d =
        AppendBox(c, {0.0f, 0.4f, 0.03f}, I, {0.06f, 0.05f, 0.06f}, 0.01f, 0.001f, rng).size();
    ASSERT_GT(a, b);
    ASSERT_GT(b, d);
    const KdTree tree(c);
    const auto result = EuclideanClustering(c, tree, {.tolerance = 0.02f, .compute_labels = true});
    ASSERT_EQ(result.clusters.size(), 3u);
    EXPECT_EQ(result.clusters[0].size(), a);
    EXPECT_EQ(result.clusters[1].size(), b);
    EXPECT_EQ(result.clusters[2].size(), d);
    // Points were appended box by box, so each cluster is one contiguous index range.
    EXPECT_EQ(result.clusters[0].front(), 0u);
    EXPECT_EQ(result.clusters[1].front(), a);
    EXPECT_EQ(result.clusters[2].front(), a + b);
    for (const auto& cluster : result.clusters) {
        EXPECT_TRUE(std::is_sorted(cluster.begin(), cluster.end()));
        EXPECT_EQ(cluster.back() - cluster.front() + 1, cluster.size());
    }
    ASSERT_EQ(result.labels.size(), c.size());
    for (std::size_t k = 0; k < result.clusters.size(); ++k) {
        for (Index i : result.clusters[k]) EXPECT_EQ(result.labels[i], static_cast<int>(k));
    }
}

TEST(EuclideanClustering, SizeFiltersDropClustersAndCountThem) {
    std::mt19937 rng(6);
    PointCloud c;
    const Eigen::Matrix3f I = Eigen::Matrix3f::Identity();
    const std::size_t a =
        AppendBox(c, {0.0f, 0.0f, 0.0f}, I, {0.2f, 0.2f, 0.2f}, 0.01f, 0.0f, rng).size();
    const std::size_t b =
        AppendBox(c, {0.5f, 0.0f, 0.0f}, I, {0.1f, 0.1f, 0.1f}, 0.01f, 0.0f, rng).size();
    const std::size_t d =
        AppendBox(c, {0.0f, 0.5f, 0.0f}, I, {0.05f, 0.05f, 0.05f}, 0.01f, 0.0f, rng).size();
    const KdTree tree(c);

    auto r = EuclideanClustering(c, tree, {.tolerance = 0.02f, .min_cluster_size = b});
    ASSERT_EQ(r.clusters.size(), 2u);
    EXPECT_EQ(r.clusters[0].size(), a);
    EXPECT_EQ(r.clusters[1].size(), b);
    EXPECT_EQ(r.num_too_small, 1u);
    EXPECT_EQ(r.num_too_large, 0u);

    r = EuclideanClustering(c, tree,
                            {.tolerance = 0.02f, .max_cluster_size = b, .compute_labels = true});
    ASSERT_EQ(r.clusters.size(), 2u);
    EXPECT_EQ(r.clusters[0].size(), b);
    EXPECT_EQ(r.clusters[1].size(), d);
    EXPECT_EQ(r.num_too_large, 1u);
    for (std::size_t i = 0; i < a; ++i) EXPECT_EQ(r.labels[i], kNoCluster);

    r = EuclideanClustering(c, tree,
                            {.tolerance = 0.02f, .min_cluster_size = b, .max_cluster_size = b});
    ASSERT_EQ(r.clusters.size(), 1u);
    EXPECT_EQ(r.clusters[0].size(), b);

    r = EuclideanClustering(c, tree, {.tolerance = 0.02f, .min_cluster_size = a + 1});
    EXPECT_TRUE(r.clusters.empty());
    EXPECT_EQ(r.num_too_small, 3u);
}

TEST(EuclideanClustering, EqualSizesAreOrderedBySmallestIndex) {
    PointCloud c({{5, 0, 0}, {0, 0, 0}, {5.01f, 0, 0}, {0.01f, 0, 0}, {9, 9, 9}});
    const KdTree tree(c);
    const auto r = EuclideanClustering(c, tree, {.tolerance = 0.05f});
    ASSERT_EQ(r.clusters.size(), 3u);
    EXPECT_EQ(r.clusters[0], (Indices{0, 2}));
    EXPECT_EQ(r.clusters[1], (Indices{1, 3}));
    EXPECT_EQ(r.clusters[2], (Indices{4}));
}

TEST(EuclideanClustering, RejectsBadParametersAndMismatchedTree) {
    const PointCloud c = test::RandomCloud(50, 3);
    const KdTree tree(c);
    EXPECT_THROW(EuclideanClustering(c, tree, {.tolerance = 0.0f}), InvalidArgument);
    EXPECT_THROW(EuclideanClustering(c, tree, {.tolerance = -0.1f}), InvalidArgument);
    EXPECT_THROW(EuclideanClustering(c, tree, {.tolerance = kNaN}), InvalidArgument);
    EXPECT_THROW(
        EuclideanClustering(c, tree, {.tolerance = std::numeric_limits<float>::infinity()}),
        InvalidArgument);
    EXPECT_THROW(EuclideanClustering(c, tree, {.min_cluster_size = 10, .max_cluster_size = 5}),
                 InvalidArgument);
    EXPECT_THROW(EuclideanClustering(c, tree, {.max_cluster_size = 0}), InvalidArgument);
    EXPECT_THROW(EuclideanClustering(c, tree, {.subset = {1, 50}}), InvalidArgument);
    // A tree that lacks some of the points to cluster.
    const KdTree partial(c, Indices{0, 1, 2});
    EXPECT_THROW(EuclideanClustering(c, partial, {.tolerance = 0.5f}), InvalidArgument);
    // A tree over a larger, different cloud.
    const PointCloud big = test::RandomCloud(500, 4);
    const KdTree other(big);
    EXPECT_THROW(EuclideanClustering(c, other, {.tolerance = 0.5f}), InvalidArgument);
    // Bad parameters are reported even for an empty cloud.
    const PointCloud empty;
    const KdTree empty_tree(empty);
    EXPECT_THROW(EuclideanClustering(empty, empty_tree, {.tolerance = 0.0f}), InvalidArgument);
}

TEST(EuclideanClustering, EmptyInputGivesEmptyResult) {
    const PointCloud empty;
    const KdTree empty_tree(empty);
    auto r = EuclideanClustering(empty, empty_tree, {.compute_labels = true});
    EXPECT_TRUE(r.clusters.empty());
    EXPECT_TRUE(r.labels.empty());
    EXPECT_EQ(r.num_points, 0u);

    PointCloud nan_only(std::vector<Eigen::Vector3f>(4, Eigen::Vector3f::Constant(kNaN)));
    const KdTree nan_tree(nan_only);
    r = EuclideanClustering(nan_only, nan_tree, {.compute_labels = true});
    EXPECT_TRUE(r.clusters.empty());
    EXPECT_EQ(r.labels, std::vector<std::int32_t>(4, kNoCluster));
}

TEST(EuclideanClustering, RepeatedRunsAreIdentical) {
    const PointCloud c = RandomBlobs(8);
    const KdTree tree(c);
    const EuclideanClusteringParams params{.tolerance = 0.06f, .compute_labels = true};
    const auto first = EuclideanClustering(c, tree, params);
    for (int i = 0; i < 3; ++i) {
        const auto again = EuclideanClustering(c, tree, params);
        EXPECT_EQ(again.clusters, first.clusters);
        EXPECT_EQ(again.labels, first.labels);
    }
    for (std::size_t k = 1; k < first.clusters.size(); ++k) {
        const auto& p = first.clusters[k - 1];
        const auto& q = first.clusters[k];
        EXPECT_TRUE(p.size() > q.size() || (p.size() == q.size() && p.front() < q.front()));
    }
}

// ---------------------------------------------------------------------------------------------
// Organized Euclidean clustering

TEST(EuclideanClusteringOrganized, MatchesKdTreeOnSceneWithoutBridging) {
    const OrganizedScene scene = MakeOrganizedScene(11);
    const PointCloud& c = scene.cloud;
    ASSERT_TRUE(c.IsOrganized());
    const KdTree tree(c);
    const auto reference = EuclideanClustering(c, tree, {.tolerance = 0.025f});
    ASSERT_EQ(reference.clusters.size(), 4u);
    // Each cluster is exactly one object.
    std::vector<std::size_t> object_size(4, 0);
    for (int o : scene.object) {
        if (o >= 0) ++object_size[static_cast<std::size_t>(o)];
    }
    for (const auto& cluster : reference.clusters) {
        const int o = scene.object[cluster.front()];
        EXPECT_EQ(cluster.size(), object_size[static_cast<std::size_t>(o)]);
        for (Index i : cluster) EXPECT_EQ(scene.object[i], o);
    }
    for (int connectivity : {4, 8}) {
        for (int half_window : {1, 2}) {
            const auto organized = EuclideanClusteringOrganized(c, {.tolerance = 0.025f,
                                                                    .connectivity = connectivity,
                                                                    .half_window = half_window,
                                                                    .compute_labels = true});
            EXPECT_EQ(organized.clusters, reference.clusters)
                << "connectivity " << connectivity << " half_window " << half_window;
            EXPECT_EQ(organized.num_points, c.CountFinite());
            ASSERT_EQ(organized.labels.size(), c.size());
            for (std::size_t i = 0; i < c.size(); ++i) {
                EXPECT_EQ(organized.labels[i] == kNoCluster, scene.object[i] < 0);
            }
        }
    }
}

TEST(EuclideanClusteringOrganized, MaskAndSubsetMatchKdTreeSubset) {
    const OrganizedScene scene = MakeOrganizedScene(12);
    const PointCloud& c = scene.cloud;
    Indices subset;
    std::vector<std::uint8_t> mask(c.size(), 0);
    for (std::size_t i = 0; i < c.size(); ++i) {
        if (scene.object[i] == 0 || scene.object[i] == 3) {
            subset.push_back(static_cast<Index>(i));
            mask[i] = 1;
        }
    }
    const KdTree tree(c);
    const auto reference = EuclideanClustering(c, tree, {.tolerance = 0.025f, .subset = subset});
    ASSERT_EQ(reference.clusters.size(), 2u);
    EXPECT_EQ(EuclideanClusteringOrganized(c, {.tolerance = 0.025f, .subset = subset}).clusters,
              reference.clusters);
    EXPECT_EQ(EuclideanClusteringOrganized(c, {.tolerance = 0.025f, .mask = mask}).clusters,
              reference.clusters);
}

// A flat patch cut by one column of invalid pixels: 3D neighbours across the gap are 5 mm apart.
PointCloud PatchWithGap() {
    PointCloud c;
    c.width = 40;
    c.height = 30;
    for (std::uint32_t v = 0; v < c.height; ++v) {
        for (std::uint32_t u = 0; u < c.width; ++u) {
            c.points.emplace_back(0.005f * static_cast<float>(u), 0.005f * static_cast<float>(v),
                                  1.0f);
            if (u == 20) c.points.back() = Eigen::Vector3f::Constant(kNaN);
        }
    }
    return c;
}

TEST(EuclideanClusteringOrganized, ImageGapSplitsUnlessTheWindowBridgesIt) {
    const PointCloud c = PatchWithGap();
    const KdTree tree(c);
    const auto reference = EuclideanClustering(c, tree, {.tolerance = 0.012f});
    ASSERT_EQ(reference.clusters.size(), 1u);
    const auto split = EuclideanClusteringOrganized(c, {.tolerance = 0.012f});
    ASSERT_EQ(split.clusters.size(), 2u);
    EXPECT_EQ(split.clusters[0].size(), 20u * 30u);
    EXPECT_EQ(split.clusters[1].size(), 19u * 30u);
    // Every organized cluster lies inside one k-d tree cluster.
    for (const auto& cluster : split.clusters) {
        EXPECT_TRUE(std::includes(reference.clusters[0].begin(), reference.clusters[0].end(),
                                  cluster.begin(), cluster.end()));
    }
    const auto bridged = EuclideanClusteringOrganized(c, {.tolerance = 0.012f, .half_window = 2});
    EXPECT_EQ(bridged.clusters, reference.clusters);
    // The diamond of 4-connectivity with reach 2 also spans the one-pixel gap.
    EXPECT_EQ(
        EuclideanClusteringOrganized(c, {.tolerance = 0.012f, .connectivity = 4, .half_window = 2})
            .clusters,
        reference.clusters);
}

TEST(EuclideanClusteringOrganized, DiagonalPixelsJoinOnlyWithEightConnectivity) {
    // A diagonal and, at another depth, an anti-diagonal line of pixels in a 12x6 frame.
    PointCloud c;
    c.width = 12;
    c.height = 6;
    c.points.assign(72, Eigen::Vector3f::Constant(kNaN));
    for (std::uint32_t k = 0; k < 6; ++k) {
        const float step = 0.01f * static_cast<float>(k);
        c.points[k * 12 + k] = Eigen::Vector3f(step, step, 1.0f);
        c.points[k * 12 + 11 - k] = Eigen::Vector3f(-step, step, 2.0f);
    }
    const auto eight = EuclideanClusteringOrganized(c, {.tolerance = 0.02f, .connectivity = 8});
    ASSERT_EQ(eight.clusters.size(), 2u);
    EXPECT_EQ(eight.clusters[0], (Indices{0, 13, 26, 39, 52, 65}));
    EXPECT_EQ(eight.clusters[1], (Indices{11, 22, 33, 44, 55, 66}));
    const auto four = EuclideanClusteringOrganized(c, {.tolerance = 0.02f, .connectivity = 4});
    EXPECT_EQ(four.clusters.size(), 12u);
}

TEST(EuclideanClusteringOrganized, TheSameClustersOnAnyThreadCount) {
    const OrganizedScene scene = MakeOrganizedScene(13);
    const PointCloud& c = scene.cloud;
    const KdTree tree(c);
    const auto reference = EuclideanClustering(c, tree, {.tolerance = 0.025f});
    for (int threads : {1, 2, 3, 0}) {
        const auto organized = EuclideanClusteringOrganized(c, {.tolerance = 0.025f,
                                                                .half_window = 2,
                                                                .compute_labels = true,
                                                                .num_threads = threads});
        EXPECT_EQ(organized.clusters, reference.clusters) << threads << " threads";
    }
}

TEST(EuclideanClusteringOrganized, ArmsJoinedFarBelowAreOneCluster) {
    // A U of pixels 60 rows tall: its two arms (columns 2 and 9) meet only in the bottom row, many
    // rows below where they start, and a separate bar lies beside it.
    PointCloud c;
    c.width = 16;
    c.height = 64;
    c.points.assign(c.width * c.height, Eigen::Vector3f::Constant(kNaN));
    auto set = [&](std::uint32_t u, std::uint32_t v) {
        c.points[v * c.width + u] =
            Eigen::Vector3f(0.01f * static_cast<float>(u), 0.01f * static_cast<float>(v), 1.0f);
    };
    for (std::uint32_t v = 1; v <= 60; ++v) {
        set(2, v);
        set(9, v);
        set(13, v);
    }
    for (std::uint32_t u = 2; u <= 9; ++u) set(u, 60);
    for (int threads : {1, 2, 0}) {
        const auto r =
            EuclideanClusteringOrganized(c, {.tolerance = 0.015f, .num_threads = threads});
        ASSERT_EQ(r.clusters.size(), 2u) << threads << " threads";
        EXPECT_EQ(r.clusters[0].size(), 60u + 60u + 6u);
        EXPECT_EQ(r.clusters[0].front(), 1u * 16u + 2u);
        EXPECT_EQ(r.clusters[1].size(), 60u);
    }
}

TEST(EuclideanClusteringOrganized, RejectsBadParametersAndInput) {
    const PointCloud c = PatchWithGap();
    EXPECT_THROW(EuclideanClusteringOrganized(c, {.tolerance = 0.0f}), InvalidArgument);
    EXPECT_THROW(EuclideanClusteringOrganized(c, {.min_cluster_size = 3, .max_cluster_size = 2}),
                 InvalidArgument);
    EXPECT_THROW(EuclideanClusteringOrganized(c, {.connectivity = 6}), InvalidArgument);
    EXPECT_THROW(EuclideanClusteringOrganized(c, {.half_window = 0}), InvalidArgument);
    EXPECT_THROW(EuclideanClusteringOrganized(c, {.num_threads = -1}), InvalidArgument);
    EXPECT_THROW(EuclideanClusteringOrganized(c, {.mask = std::vector<std::uint8_t>(5, 1)}),
                 InvalidArgument);
    EXPECT_THROW(EuclideanClusteringOrganized(
                     c, {.subset = {0}, .mask = std::vector<std::uint8_t>(c.size(), 1)}),
                 InvalidArgument);
    EXPECT_THROW(EuclideanClusteringOrganized(c, {.subset = {static_cast<Index>(c.size())}}),
                 InvalidArgument);
    const PointCloud unorganized = test::RandomCloud(20, 1);
    EXPECT_THROW(EuclideanClusteringOrganized(unorganized, {}), InvalidArgument);
}

TEST(EuclideanClusteringOrganized, EmptyInputGivesEmptyResult) {
    EXPECT_TRUE(EuclideanClusteringOrganized(PointCloud{}, {}).clusters.empty());
    PointCloud nan_frame;
    nan_frame.width = 8;
    nan_frame.height = 4;
    nan_frame.points.assign(32, Eigen::Vector3f::Constant(kNaN));
    const auto r = EuclideanClusteringOrganized(nan_frame, {.compute_labels = true});
    EXPECT_TRUE(r.clusters.empty());
    EXPECT_EQ(r.labels, std::vector<std::int32_t>(32, kNoCluster));
}

// ---------------------------------------------------------------------------------------------
// Region growing

// Brute-force reference of the growth phase: seeds by (curvature, index), every neighbour found by
// scanning all points (radius, or the k nearest within the radius).
std::vector<Indices> BruteForceRegions(const PointCloud& c, float radius, int k, float max_deg) {
    const std::size_t n = c.size();
    Indices order(n);
    std::iota(order.begin(), order.end(), 0u);
    std::sort(order.begin(), order.end(), [&](Index a, Index b) {
        return c.curvature[a] != c.curvature[b] ? c.curvature[a] < c.curvature[b] : a < b;
    });
    auto neighbours = [&](Index q) {
        std::vector<std::pair<float, Index>> by_distance;
        for (std::size_t j = 0; j < n; ++j) {
            by_distance.emplace_back((c.points[j] - c.points[q]).squaredNorm(),
                                     static_cast<Index>(j));
        }
        std::size_t keep = n;
        if (k > 0 && n > static_cast<std::size_t>(k)) {
            keep = static_cast<std::size_t>(k);
            std::nth_element(by_distance.begin(), by_distance.begin() + static_cast<long>(keep) - 1,
                             by_distance.end());
        }
        Indices within;
        for (std::size_t m = 0; m < keep; ++m) {
            if (by_distance[m].first < radius * radius) within.push_back(by_distance[m].second);
        }
        return within;
    };
    const float cos_max = std::cos(max_deg * std::numbers::pi_v<float> / 180.0f);
    std::vector<bool> taken(n, false);
    std::vector<Indices> parts;
    for (Index s : order) {
        if (taken[s]) continue;
        Indices part{s};
        taken[s] = true;
        for (std::size_t h = 0; h < part.size(); ++h) {
            for (Index j : neighbours(part[h])) {
                if (!taken[j] && c.normals[j].dot(c.normals[s]) > cos_max) {
                    taken[j] = true;
                    part.push_back(j);
                }
            }
        }
        std::sort(part.begin(), part.end());
        parts.push_back(part);
    }
    return parts;
}

// A wavy sheet z = 0.05 sin(8x) cos(8y) with analytic normals and random curvature.
PointCloud WavySheet(std::size_t n, std::uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(0.0f, 0.5f);
    PointCloud c;
    for (std::size_t i = 0; i < n; ++i) {
        const float x = u(rng);
        const float y = u(rng);
        c.points.emplace_back(x, y, 0.05f * std::sin(8 * x) * std::cos(8 * y));
        const float dx = 0.4f * std::cos(8 * x) * std::cos(8 * y);
        const float dy = -0.4f * std::sin(8 * x) * std::sin(8 * y);
        c.normals.push_back(Eigen::Vector3f(-dx, -dy, 1.0f).normalized());
    }
    c.SetUnorganized();
    RandomCurvature(c, rng);
    return c;
}

TEST(RegionGrowing, GrowthMatchesBruteForce) {
    const PointCloud c = WavySheet(1200, 21);
    const KdTree tree(c);
    for (int k : {0, 12}) {
        for (float angle : {10.0f, 20.0f}) {
            const auto result = RegionGrowing(
                c, tree, {.radius = 0.04f, .k = k, .max_angle_deg = angle, .min_part_size = 1});
            const auto expected = BruteForceRegions(c, 0.04f, k, angle);
            EXPECT_EQ(result.parts, expected) << "k " << k << " angle " << angle;
            EXPECT_EQ(result.num_grown_parts, expected.size());
            EXPECT_EQ(result.num_merged_parts, 0u);
            ASSERT_EQ(result.seeds.size(), result.parts.size());
            for (std::size_t p = 1; p < result.seeds.size(); ++p) {
                EXPECT_LE(c.curvature[result.seeds[p - 1]], c.curvature[result.seeds[p]]);
            }
        }
    }
}

PointCloud NoisyBox(std::vector<int>& faces, std::uint32_t seed) {
    std::mt19937 rng(seed);
    PointCloud c;
    const auto rotation = (Eigen::AngleAxisf(0.4f, Eigen::Vector3f::UnitZ()) *
                           Eigen::AngleAxisf(0.2f, Eigen::Vector3f::UnitX()))
                              .toRotationMatrix();
    faces = AppendBox(c, {0.1f, 0.2f, 0.8f}, rotation, {0.3f, 0.2f, 0.15f}, 0.01f, 0.001f, rng);
    for (auto& n : c.normals) n = Perturb(n, 0.05f, rng);
    RandomCurvature(c, rng);
    return c;
}

TEST(RegionGrowing, NoisyBoxSplitsIntoItsFaces) {
    std::vector<int> faces;
    const PointCloud c = NoisyBox(faces, 31);
    const KdTree tree(c);
    const auto result = RegionGrowing(c, tree, {});  // thesis values: 5 cm, 40 degrees, 10 points
    ASSERT_EQ(result.parts.size(), 6u);
    std::set<int> seen;
    for (const auto& part : result.parts) {
        const int face = faces[part.front()];
        for (Index i : part) EXPECT_EQ(faces[i], face);
        EXPECT_EQ(part.size(),
                  static_cast<std::size_t>(std::count(faces.begin(), faces.end(), face)));
        seen.insert(face);
    }
    EXPECT_EQ(seen.size(), 6u);
    EXPECT_EQ(result.num_discarded_points, 0u);
    ASSERT_EQ(result.part_ids.size(), c.size());
    for (std::size_t p = 0; p < result.parts.size(); ++p) {
        for (Index i : result.parts[p]) EXPECT_EQ(result.part_ids[i], static_cast<int>(p));
    }
}

TEST(RegionGrowing, VisibleFacesOfABoxAsSubset) {
    std::vector<int> faces;
    const PointCloud c = NoisyBox(faces, 32);
    // A camera looking at the box sees the faces whose (mean) normal points towards it.
    const Eigen::Vector3f view =
        Eigen::Vector3f(1.5f, -1.0f, 2.0f) - Eigen::Vector3f(0.1f, 0.2f, 0.8f);
    std::vector<Eigen::Vector3f> face_normal(6, Eigen::Vector3f::Zero());
    for (std::size_t i = 0; i < c.size(); ++i)
        face_normal[static_cast<std::size_t>(faces[i])] += c.normals[i];
    std::set<int> visible_faces;
    for (int f = 0; f < 6; ++f) {
        if (face_normal[static_cast<std::size_t>(f)].normalized().dot(view.normalized()) > 0.1f) {
            visible_faces.insert(f);
        }
    }
    Indices visible;
    for (std::size_t i = 0; i < c.size(); ++i) {
        if (visible_faces.count(faces[i])) visible.push_back(static_cast<Index>(i));
    }
    ASSERT_EQ(visible_faces.size(), 3u);
    const KdTree tree(c);
    const auto result = RegionGrowing(c, tree, {.subset = visible});
    ASSERT_EQ(result.parts.size(), 3u);
    std::size_t total = 0;
    for (const auto& part : result.parts) {
        const int face = faces[part.front()];
        EXPECT_TRUE(visible_faces.count(face));
        for (Index i : part) EXPECT_EQ(faces[i], face);
        total += part.size();
    }
    EXPECT_EQ(total, visible.size());
    std::size_t outside = 0;
    for (auto id : result.part_ids) outside += id == kNoPart ? 1 : 0;
    EXPECT_EQ(outside, c.size() - visible.size());
}

// The visible half of an upright cylinder (side and top cap): flat cap found first, the side split
// into arcs whose normals stay within max_angle of their seed (at most 2 * 40 = 80 degrees each).
TEST(RegionGrowing, CylinderCapIsOnePartAndSideSplitsIntoNarrowArcs) {
    std::mt19937 rng(41);
    std::normal_distribution<float> noise(0.0f, 0.0005f);
    PointCloud c;
    std::vector<bool> on_cap;
    const float r = 0.05f;
    const float height = 0.15f;
    for (int a = 0; a < 32; ++a) {
        const float theta = std::numbers::pi_v<float> * (static_cast<float>(a) + 0.5f) / 32.0f;
        for (int h = 0; h < 30; ++h) {
            const Eigen::Vector3f n(std::cos(theta), std::sin(theta), 0.0f);
            c.points.push_back(r * n +
                               Eigen::Vector3f(noise(rng), noise(rng),
                                               height * (static_cast<float>(h) + 0.5f) / 30.0f));
            c.normals.push_back(Perturb(n, 0.03f, rng));
            c.curvature.push_back(0.02f +
                                  0.005f * std::uniform_real_distribution<float>(0, 1)(rng));
            on_cap.push_back(false);
        }
    }
    for (float x = -r; x <= r; x += 0.005f) {
        for (float y = -r; y <= r; y += 0.005f) {
            if (x * x + y * y > 0.98f * r * r) continue;
            c.points.emplace_back(x, y, height + noise(rng));
            c.normals.push_back(Perturb(Eigen::Vector3f::UnitZ(), 0.03f, rng));
            c.curvature.push_back(0.001f * std::uniform_real_distribution<float>(0, 1)(rng));
            on_cap.push_back(true);
        }
    }
    c.SetUnorganized();
    const KdTree tree(c);
    const auto result = RegionGrowing(c, tree, {});
    ASSERT_GE(result.parts.size(), 1u);
    // Lowest curvature first: the cap is the first part, whole.
    const auto cap_points =
        static_cast<std::size_t>(std::count(on_cap.begin(), on_cap.end(), true));
    EXPECT_EQ(result.parts[0].size(), cap_points);
    for (Index i : result.parts[0]) EXPECT_TRUE(on_cap[i]);
    const std::size_t side_parts = result.parts.size() - 1;
    EXPECT_GE(side_parts, 3u);  // 180 degrees of side need at least three 80-degree arcs
    EXPECT_LE(side_parts, 6u);
    const float cos40 = std::cos(40.0f * std::numbers::pi_v<float> / 180.0f);
    for (std::size_t p = 1; p < result.parts.size(); ++p) {
        const Eigen::Vector3f seed_normal = c.normals[result.seeds[p]];
        for (Index i : result.parts[p]) {
            EXPECT_FALSE(on_cap[i]);
            EXPECT_GT(c.normals[i].dot(seed_normal), cos40);
        }
    }
    EXPECT_EQ(result.num_discarded_points, 0u);
}

// A plane with three kinds of tiny parts: two chained next to it (merged, the far one through the
// near one), a pair of touching tiny parts far away (grouped into one part of 12 points) and an
// isolated one of 4 points (discarded, or kept when asked to).
PointCloud PlaneWithTinyParts(std::size_t& plane_points) {
    std::mt19937 rng(51);
    PointCloud c;
    for (int i = 0; i < 30; ++i) {
        for (int j = 0; j < 30; ++j) {
            c.points.emplace_back(0.01f * static_cast<float>(i), 0.01f * static_cast<float>(j),
                                  0.0f);
            c.normals.push_back(Perturb(Eigen::Vector3f::UnitZ(), 0.02f, rng));
        }
    }
    plane_points = c.size();
    auto add_group = [&](const Eigen::Vector3f& at, int count, const Eigen::Vector3f& normal) {
        for (int m = 0; m < count; ++m) {
            c.points.push_back(at + Eigen::Vector3f(0.003f * static_cast<float>(m), 0.0f, 0.0f));
            c.normals.push_back(normal);
        }
    };
    add_group({0.15f, 0.15f, 0.03f}, 5, Eigen::Vector3f::UnitX());  // 3 cm above the plane
    add_group({0.15f, 0.15f, 0.07f}, 5, Eigen::Vector3f::UnitY());  // 7 cm above, near the first
    add_group({1.0f, 1.0f, 1.0f}, 6, Eigen::Vector3f::UnitZ());     // far away ...
    add_group({1.0f, 1.0f, 1.02f}, 6, Eigen::Vector3f::UnitX());    // ... touching the previous
    add_group({-1.0f, -1.0f, -1.0f}, 4, Eigen::Vector3f::UnitZ());  // isolated
    c.SetUnorganized();
    RandomCurvature(c, rng, 0.0f, 0.001f);
    for (std::size_t i = plane_points; i < c.size(); ++i) c.curvature[i] += 0.01f;
    return c;
}

TEST(RegionGrowing, TinyPartsAreMergedGroupedOrDiscarded) {
    std::size_t plane = 0;
    const PointCloud c = PlaneWithTinyParts(plane);
    const KdTree tree(c);
    auto result = RegionGrowing(c, tree, {});
    EXPECT_EQ(result.num_grown_parts, 6u);
    ASSERT_EQ(result.parts.size(), 2u);
    EXPECT_EQ(result.parts[0].size(), plane + 10);  // both chained tiny parts merged
    EXPECT_EQ(result.parts[1].size(), 12u);         // the touching pair grouped
    EXPECT_EQ(result.parts[1].front(), plane + 10);
    EXPECT_EQ(result.num_merged_parts, 3u);
    EXPECT_EQ(result.num_discarded_points, 4u);
    for (std::size_t i = c.size() - 4; i < c.size(); ++i) EXPECT_EQ(result.part_ids[i], kNoPart);

    result = RegionGrowing(c, tree, {.discard_small_parts = false});
    ASSERT_EQ(result.parts.size(), 3u);
    EXPECT_EQ(result.parts[0].size(), plane + 10);
    const Indices isolated{static_cast<Index>(c.size() - 4), static_cast<Index>(c.size() - 3),
                           static_cast<Index>(c.size() - 2), static_cast<Index>(c.size() - 1)};
    EXPECT_TRUE(result.parts[1] == isolated || result.parts[2] == isolated);
    EXPECT_EQ(result.num_discarded_points, 0u);

    // Without merging every grown part stays.
    result = RegionGrowing(c, tree, {.min_part_size = 1});
    EXPECT_EQ(result.parts.size(), 6u);
}

TEST(RegionGrowing, UnorientedNormalsWithIgnoreSign) {
    std::mt19937 rng(61);
    std::bernoulli_distribution flip(0.5);
    PointCloud c;
    for (int i = 0; i < 25; ++i) {
        for (int j = 0; j < 25; ++j) {
            c.points.emplace_back(0.01f * static_cast<float>(i), 0.01f * static_cast<float>(j),
                                  0.0f);
            c.normals.push_back(Eigen::Vector3f(0.0f, 0.0f, flip(rng) ? 1.0f : -1.0f));
        }
    }
    c.SetUnorganized();
    RandomCurvature(c, rng);
    const KdTree tree(c);
    EXPECT_EQ(RegionGrowing(c, tree, {}).parts.size(), 2u);
    EXPECT_EQ(RegionGrowing(c, tree, {.ignore_normal_sign = true}).parts.size(), 1u);
}

TEST(RegionGrowing, NonFinitePointsNormalsAndCurvatureAreLeftOut) {
    PointCloud c = WavySheet(400, 71);
    c.points[3] = Eigen::Vector3f::Constant(kNaN);
    c.normals[5] = Eigen::Vector3f::Constant(kNaN);
    c.normals[6] = Eigen::Vector3f::Zero();
    c.curvature[7] = kNaN;
    const KdTree tree(c);
    const auto result = RegionGrowing(c, tree, {.min_part_size = 1});
    EXPECT_EQ(result.num_points, 396u);
    for (Index i : {3u, 5u, 6u, 7u}) EXPECT_EQ(result.part_ids[i], kNoPart);
    std::size_t total = 0;
    for (const auto& p : result.parts) total += p.size();
    EXPECT_EQ(total, 396u);
}

TEST(RegionGrowing, RejectsBadParametersAndMissingFields) {
    const PointCloud c = WavySheet(100, 81);
    const KdTree tree(c);
    EXPECT_THROW(RegionGrowing(c, tree, {.radius = 0.0f}), InvalidArgument);
    EXPECT_THROW(RegionGrowing(c, tree, {.radius = -1.0f}), InvalidArgument);
    EXPECT_THROW(RegionGrowing(c, tree, {.radius = kNaN}), InvalidArgument);
    EXPECT_THROW(RegionGrowing(c, tree, {.k = -1}), InvalidArgument);
    EXPECT_THROW(RegionGrowing(c, tree, {.max_angle_deg = 0.0f}), InvalidArgument);
    EXPECT_THROW(RegionGrowing(c, tree, {.max_angle_deg = 190.0f}), InvalidArgument);
    EXPECT_THROW(RegionGrowing(c, tree, {.subset = {0, 100}}), InvalidArgument);
    const KdTree partial(c, Indices{0, 1, 2, 3});
    EXPECT_THROW(RegionGrowing(c, partial, {}), InvalidArgument);
    const KdTree other(WavySheet(300, 82));
    EXPECT_THROW(RegionGrowing(c, other, {}), InvalidArgument);

    PointCloud no_normals = c;
    no_normals.normals.clear();
    EXPECT_THROW(RegionGrowing(no_normals, tree, {}), DataError);
    PointCloud no_curvature = c;
    no_curvature.curvature.clear();
    EXPECT_THROW(RegionGrowing(no_curvature, tree, {}), DataError);
    PointCloud short_normals = c;
    short_normals.normals.pop_back();
    EXPECT_THROW(RegionGrowing(short_normals, tree, {}), DataError);
}

TEST(RegionGrowing, EmptyInputGivesEmptyResult) {
    const PointCloud empty;
    const KdTree empty_tree(empty);
    const auto r = RegionGrowing(empty, empty_tree, {});
    EXPECT_TRUE(r.parts.empty());
    EXPECT_TRUE(r.part_ids.empty());

    PointCloud nan_only(std::vector<Eigen::Vector3f>(3, Eigen::Vector3f::Constant(kNaN)));
    nan_only.normals.assign(3, Eigen::Vector3f::UnitZ());
    nan_only.curvature.assign(3, 0.0f);
    const KdTree nan_tree(nan_only);
    const auto n = RegionGrowing(nan_only, nan_tree, {});
    EXPECT_TRUE(n.parts.empty());
    EXPECT_EQ(n.part_ids, std::vector<std::int32_t>(3, kNoPart));
}

// Region growing on the pixel windows of an organized frame: where the window holds every
// point's k nearest points of the mask, the parts are those grown on a k-d tree over the mask.
TEST(RegionGrowingOrganized, MatchesTheTreeWhereTheWindowHoldsTheNearest) {
    const OrganizedScene scene = MakeOrganizedScene(13);
    PointCloud c = scene.cloud;
    c.normals = scene.normal;
    std::mt19937 rng(14);
    RandomCurvature(c, rng);
    Indices objects;
    std::vector<std::uint8_t> mask(c.size(), 0);
    for (std::size_t i = 0; i < c.size(); ++i) {
        if (scene.object[i] < 0) continue;
        objects.push_back(static_cast<Index>(i));
        mask[i] = 1;
    }
    ASSERT_GT(objects.size(), 3000u);
    const KdTree tree(c, objects);
    for (int k : {6, 16}) {
        for (float angle : {20.0f, 40.0f}) {
            const RegionGrowingParams params{
                .radius = 0.03f, .k = k, .max_angle_deg = angle, .subset = objects};
            const auto expected = RegionGrowing(c, tree, params);
            const auto got = RegionGrowingOrganized(c, params, {.half_window = 6, .mask = mask});
            EXPECT_EQ(got.parts, expected.parts) << "k " << k << " angle " << angle;
            EXPECT_EQ(got.part_ids, expected.part_ids);
            EXPECT_EQ(got.num_merged_parts, expected.num_merged_parts);
            EXPECT_GT(got.parts.size(), 4u);
        }
    }
    // Only a part of the objects: the parts lie within it.
    Indices first(objects.begin(), objects.begin() + objects.size() / 3);
    const auto part = RegionGrowingOrganized(c, {.radius = 0.03f, .k = 8, .subset = first},
                                             {.half_window = 3, .mask = mask});
    for (const auto& p : part.parts)
        for (Index i : p) EXPECT_TRUE(std::binary_search(first.begin(), first.end(), i));
}

// A neighbour table searched once for all objects serves each object's region growing, and is
// the same for any thread count.
TEST(RegionGrowingOrganized, OneNeighbourTableForSeveralGrowings) {
    const OrganizedScene scene = MakeOrganizedScene(17);
    PointCloud c = scene.cloud;
    c.normals = scene.normal;
    std::mt19937 rng(18);
    RandomCurvature(c, rng);
    std::vector<Indices> objects(4);
    std::vector<std::uint8_t> mask(c.size(), 0);
    Indices all;
    for (std::size_t i = 0; i < c.size(); ++i) {
        if (scene.object[i] < 0) continue;
        objects[static_cast<std::size_t>(scene.object[i])].push_back(static_cast<Index>(i));
        all.push_back(static_cast<Index>(i));
        mask[i] = 1;
    }
    const OrganizedSearchParams search{.half_window = 3, .mask = mask};
    const RegionGrowingParams params{.radius = 0.05f, .k = 16};
    const NeighbourTable one = OrganizedNeighbourTable(c, all, params, search, 1);
    const NeighbourTable two = OrganizedNeighbourTable(c, all, params, search, 2);
    EXPECT_EQ(one.count, two.count);
    EXPECT_EQ(one.neighbours, two.neighbours);
    EXPECT_EQ(one.squared_distances, two.squared_distances);
    for (const Indices& object : objects) {
        RegionGrowingParams p = params;
        p.subset = object;
        const auto expected = RegionGrowingOrganized(c, p, search);
        const auto got = RegionGrowing(c, one, p);
        EXPECT_EQ(got.parts, expected.parts);
        EXPECT_EQ(got.part_ids, expected.part_ids);
        EXPECT_FALSE(got.parts.empty());
        // The same subset reversed and with repeats: the same parts and ids.
        p.subset.assign(object.rbegin(), object.rend());
        p.subset.insert(p.subset.end(), object.begin(), object.begin() + 25);
        const auto repeated = RegionGrowing(c, one, p);
        EXPECT_EQ(repeated.parts, expected.parts);
        EXPECT_EQ(repeated.part_ids, expected.part_ids);
        EXPECT_EQ(repeated.num_points, expected.num_points);
    }
    // A point without a row cannot be segmented with the table.
    const NeighbourTable first = OrganizedNeighbourTable(c, objects[0], params, search, 1);
    RegionGrowingParams p = params;
    p.subset = objects[1];
    EXPECT_THROW(RegionGrowing(c, first, p), InvalidArgument);
    EXPECT_THROW(OrganizedNeighbourTable(c, {static_cast<Index>(c.size())}, params, search),
                 InvalidArgument);
}

// Each row of the neighbour table is the point's own window search (OrganizedKnnSearch), cut
// strictly at the radius: on a small frame with holes, a mask that leaves out pixels (a centre
// among them), pixels at every image border, and repeated points whose equal distances are
// ranked by index; for k below, at and above the window's size.
TEST(RegionGrowingOrganized, NeighbourTableRowsAreTheWindowSearches) {
    constexpr std::size_t kWidth = 23, kHeight = 17;
    std::mt19937 rng(21);
    std::uniform_real_distribution<float> jitter(-0.002f, 0.002f);
    std::uniform_int_distribution<int> coin(0, 9);
    PointCloud c;
    c.width = kWidth;
    c.height = kHeight;
    c.points.resize(kWidth * kHeight);
    std::vector<std::uint8_t> mask(c.size(), 1);
    for (std::size_t v = 0; v < kHeight; ++v) {
        for (std::size_t u = 0; u < kWidth; ++u) {
            const std::size_t i = v * kWidth + u;
            c.points[i] = {0.004f * static_cast<float>(u) + jitter(rng),
                           0.004f * static_cast<float>(v) + jitter(rng),
                           1.0f + 0.01f * std::sin(0.7f * static_cast<float>(u))};
            if (coin(rng) == 0) c.points[i] = Eigen::Vector3f::Constant(kNaN);
            if (coin(rng) == 0) mask[i] = 0;
        }
    }
    for (std::size_t i = 40; i < 60; ++i) c.points[i + 1] = c.points[i];  // ties
    Indices all(c.size());
    std::iota(all.begin(), all.end(), Index{0});
    for (int hw : {1, 3, 5}) {
        for (int k : {1, 7, 16, 60}) {
            const RegionGrowingParams params{.radius = 0.015f, .k = k};
            const OrganizedSearchParams search{.half_window = hw, .mask = mask};
            const NeighbourTable table = OrganizedNeighbourTable(c, all, params, search, 2);
            OrganizedSearchParams s = search;
            s.radius = params.radius;
            Indices nb;
            std::vector<float> d2;
            for (std::size_t r = 0; r < all.size(); ++r) {
                OrganizedKnnSearch(c, all[r], k, s, nb, d2);
                Indices expected;
                std::vector<float> expected_d2;
                for (std::size_t m = 0; m < nb.size(); ++m) {
                    if (!(d2[m] < params.radius * params.radius)) continue;
                    expected.push_back(nb[m]);
                    expected_d2.push_back(d2[m]);
                }
                const auto begin = static_cast<std::ptrdiff_t>(r * table.stride);
                const Indices got(table.neighbours.begin() + begin,
                                  table.neighbours.begin() + begin + table.count[r]);
                const std::vector<float> got_d2(
                    table.squared_distances.begin() + begin,
                    table.squared_distances.begin() + begin + table.count[r]);
                ASSERT_EQ(got, expected) << "hw " << hw << " k " << k << " point " << all[r];
                ASSERT_EQ(got_d2, expected_d2);
            }
        }
    }
}

TEST(RegionGrowingOrganized, RejectsBadInputAndHandlesEmptyInput) {
    const OrganizedScene scene = MakeOrganizedScene(15);
    PointCloud c = scene.cloud;
    c.normals = scene.normal;
    std::mt19937 rng(16);
    RandomCurvature(c, rng);
    std::vector<std::uint8_t> mask(c.size(), 0);
    EXPECT_THROW(RegionGrowingOrganized(c, {}, {.half_window = 0}), InvalidArgument);
    EXPECT_THROW(RegionGrowingOrganized(c, {.radius = -1.0f}, {}), InvalidArgument);
    std::vector<std::uint8_t> short_mask(c.size() - 1, 1);
    EXPECT_THROW(RegionGrowingOrganized(c, {}, {.mask = short_mask}), InvalidArgument);
    // Every finite point is to be segmented, but the mask holds none of them.
    EXPECT_THROW(RegionGrowingOrganized(c, {}, {.mask = mask}), InvalidArgument);
    PointCloud unorganized = c;
    unorganized.SetUnorganized();
    EXPECT_THROW(RegionGrowingOrganized(unorganized, {}, {}), InvalidArgument);
    PointCloud no_normals = c;
    no_normals.normals.clear();
    EXPECT_THROW(RegionGrowingOrganized(no_normals, {}, {}), DataError);

    const PointCloud empty;
    EXPECT_TRUE(RegionGrowingOrganized(empty, {}, {}).parts.empty());
}

TEST(RegionGrowing, DeterministicAndIndependentOfPointOrder) {
    std::size_t plane = 0;
    PointCloud c = PlaneWithTinyParts(plane);
    std::vector<int> faces;
    const PointCloud box = NoisyBox(faces, 91);
    for (std::size_t i = 0; i < box.size(); ++i) {
        c.points.push_back(box.points[i] + Eigen::Vector3f(2.0f, 0.0f, 0.0f));
        c.normals.push_back(box.normals[i]);
        c.curvature.push_back(box.curvature[i]);
    }
    c.SetUnorganized();
    const KdTree tree(c);
    const auto first = RegionGrowing(c, tree, {});
    const auto again = RegionGrowing(c, tree, {});
    EXPECT_EQ(again.parts, first.parts);
    EXPECT_EQ(again.seeds, first.seeds);
    EXPECT_EQ(again.part_ids, first.part_ids);

    // The same points in another order give the same parts (curvatures are distinct).
    Indices perm(c.size());
    std::iota(perm.begin(), perm.end(), 0u);
    std::shuffle(perm.begin(), perm.end(), std::mt19937(92));
    const PointCloud shuffled = SelectByIndex(c, perm);
    const KdTree shuffled_tree(shuffled);
    const auto other = RegionGrowing(shuffled, shuffled_tree, {});
    std::vector<Indices> mapped;
    for (const auto& part : other.parts) {
        Indices m;
        for (Index i : part) m.push_back(perm[i]);
        mapped.push_back(m);
    }
    EXPECT_EQ(AsSet(mapped), AsSet(first.parts));
    ASSERT_EQ(other.seeds.size(), first.seeds.size());
    for (std::size_t p = 0; p < other.seeds.size(); ++p)
        EXPECT_EQ(perm[other.seeds[p]], first.seeds[p]);
}

}  // namespace
}  // namespace multicue

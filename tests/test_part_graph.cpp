// Part graphs, subgraph enumeration, keys, descriptors and the hashed model (recognition module).

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <set>

#include <Eigen/Eigenvalues>

#include "multicue/core/exceptions.hpp"
#include "multicue/ml/serialization.hpp"
#include "multicue/recognition/part_graph.hpp"
#include "multicue/recognition/part_graph_model.hpp"
#include "test_util.hpp"

namespace multicue {
namespace {

PartGraph RandomGraph(std::size_t n, double p, std::uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    PartGraph g(n);
    for (std::uint32_t a = 0; a < n; ++a) {
        for (std::uint32_t b = a + 1; b < n; ++b) {
            if (u(rng) < p) g.AddEdge(a, b);
        }
    }
    return g;
}

bool Connected(const PartGraph& g, const std::vector<std::uint32_t>& vs) {
    std::vector<std::uint32_t> stack{vs[0]};
    std::set<std::uint32_t> seen{vs[0]};
    while (!stack.empty()) {
        const auto v = stack.back();
        stack.pop_back();
        for (auto u : vs) {
            if (!seen.count(u) && g.Adjacent(u, v)) {
                seen.insert(u);
                stack.push_back(u);
            }
        }
    }
    return seen.size() == vs.size();
}

std::set<std::vector<std::uint32_t>> BruteForce(const PartGraph& g, std::size_t k) {
    std::set<std::vector<std::uint32_t>> out;
    const std::size_t n = g.size();
    for (std::uint32_t mask = 1; mask < (1u << n); ++mask) {
        std::vector<std::uint32_t> vs;
        for (std::uint32_t i = 0; i < n; ++i) {
            if (mask & (1u << i)) vs.push_back(i);
        }
        if (vs.size() <= k && Connected(g, vs)) out.insert(vs);
    }
    return out;
}

TEST(PartGraph, EnumerationMatchesBruteForceExactlyOnce) {
    for (std::uint32_t seed = 1; seed <= 12; ++seed) {
        const std::size_t n = 4 + seed % 7;
        const PartGraph g = RandomGraph(n, 0.2 + 0.05 * (seed % 5), seed);
        for (std::size_t k : {1u, 2u, 3u, 5u, 8u}) {
            const auto expected = BruteForce(g, k);
            std::set<std::vector<std::uint32_t>> got;
            std::size_t visits = 0;
            std::vector<std::uint32_t> order(n);
            for (std::uint32_t i = 0; i < n; ++i) order[i] = static_cast<std::uint32_t>(n - 1 - i);
            const std::size_t count = EnumerateConnectedSubgraphs(
                g, k,
                [&](std::span<const std::uint32_t> vs) {
                    std::vector<std::uint32_t> v(vs.begin(), vs.end());
                    std::sort(v.begin(), v.end());
                    EXPECT_TRUE(got.insert(v).second) << "visited twice";
                    ++visits;
                    return true;
                },
                seed % 2 ? std::span<const std::uint32_t>(order)
                         : std::span<const std::uint32_t>());
            EXPECT_EQ(count, visits);
            EXPECT_EQ(got, expected) << "seed " << seed << " k " << k;
        }
    }
}

TEST(PartGraph, KnownCountsAndStop) {
    // Path of 4: subgraphs 4 + 3 + 2 + 1 = 10; complete graph of 4: 15.
    PartGraph path(4);
    path.AddEdge(0, 1);
    path.AddEdge(1, 2);
    path.AddEdge(2, 3);
    EXPECT_EQ(EnumerateConnectedSubgraphs(path, 4, [](auto) { return true; }), 10u);
    PartGraph k4(4);
    for (std::uint32_t a = 0; a < 4; ++a)
        for (std::uint32_t b = a + 1; b < 4; ++b) k4.AddEdge(a, b);
    EXPECT_EQ(EnumerateConnectedSubgraphs(k4, 4, [](auto) { return true; }), 15u);
    EXPECT_EQ(EnumerateConnectedSubgraphs(k4, 4, [](auto) { return false; }), 1u);
    EXPECT_THROW(EnumerateConnectedSubgraphs(k4, 0, [](auto) { return true; }), InvalidArgument);
    EXPECT_THROW(EnumerateConnectedSubgraphs(k4, 16, [](auto) { return true; }), InvalidArgument);
    const std::vector<std::uint32_t> bad = {0, 0, 1, 2};
    EXPECT_THROW(EnumerateConnectedSubgraphs(
                     k4, 2, [](auto) { return true; }, bad),
                 InvalidArgument);
    EXPECT_THROW(k4.AddEdge(1, 1), InvalidArgument);
    EXPECT_THROW(k4.AddEdge(1, 4), InvalidArgument);
    EXPECT_EQ(EnumerateConnectedSubgraphs(PartGraph(0), 3, [](auto) { return true; }), 0u);
}

TEST(PartGraph, KeysAreDegreeSequences) {
    // Star 0-{1,2,3} and path 0-1-2-3: both 4 parts, different keys; a relabelled star equal.
    PartGraph g(8);
    g.AddEdge(0, 1);
    g.AddEdge(0, 2);
    g.AddEdge(0, 3);
    g.AddEdge(4, 5);
    g.AddEdge(5, 6);
    g.AddEdge(6, 7);
    const std::vector<std::uint32_t> star = {0, 1, 2, 3}, star2 = {3, 0, 2, 1}, path = {4, 5, 6, 7};
    EXPECT_EQ(SubgraphKey(g, star), SubgraphKey(g, star2));
    EXPECT_NE(SubgraphKey(g, star), SubgraphKey(g, path));
    EXPECT_EQ(KeyParts(SubgraphKey(g, star)), 4u);
    EXPECT_EQ(KeyDegrees(SubgraphKey(g, star)), (std::vector<int>{3, 1, 1, 1}));
    EXPECT_EQ(KeyDegrees(SubgraphKey(g, path)), (std::vector<int>{2, 2, 1, 1}));
    EXPECT_THROW(SubgraphKey(g, std::vector<std::uint32_t>{}), InvalidArgument);
}

// Three flat patches: A and B 5 mm apart, C 10 cm away.
PointCloud ThreePatches(std::vector<Indices>& parts) {
    PointCloud c;
    parts.assign(3, {});
    auto patch = [&](int p, float x0, float z) {
        for (int i = 0; i < 12; ++i)
            for (int j = 0; j < 12; ++j) {
                parts[p].push_back(static_cast<Index>(c.points.size()));
                c.points.emplace_back(x0 + 0.004f * i, 0.004f * j, z);
                c.normals.emplace_back(0.0f, 0.0f, 1.0f);
            }
    };
    patch(0, 0.0f, 0.0f);
    patch(1, 0.049f, 0.0f);
    patch(2, 0.3f, 0.0f);
    c.width = static_cast<std::uint32_t>(c.points.size());
    c.height = 1;
    return c;
}

TEST(PartGraph, AdjacencyFromDistance) {
    std::vector<Indices> parts;
    const PointCloud c = ThreePatches(parts);
    const PartGraph g = BuildPartGraph(c, parts, {.adjacency_distance = 0.01f});
    EXPECT_TRUE(g.Adjacent(0, 1));
    EXPECT_FALSE(g.Adjacent(0, 2));
    EXPECT_FALSE(g.Adjacent(1, 2));
    EXPECT_EQ(g.num_edges(), 1u);
    const PartGraph g2 = BuildPartGraph(c, parts, {.adjacency_distance = 0.004f});
    EXPECT_EQ(g2.num_edges(), 0u);
    EXPECT_THROW(BuildPartGraph(c, parts, {.adjacency_distance = 0.0f}), InvalidArgument);
    parts[0].push_back(100000);
    EXPECT_THROW(BuildPartGraph(c, parts), InvalidArgument);
}

// Oracle: parts are adjacent exactly when two of their points are closer than the distance
// (random blobs of many parts, overlapping and not, checked against every pair of points).
TEST(PartGraph, AdjacencyMatchesBruteForce) {
    std::mt19937 rng(41);
    std::uniform_real_distribution<float> centre(0.0f, 0.3f);
    std::normal_distribution<float> spread(0.0f, 0.01f);
    PointCloud c;
    std::vector<Indices> parts(25);
    for (auto& part : parts) {
        const Eigen::Vector3f m(centre(rng), centre(rng), centre(rng));
        for (int k = 0; k < 60; ++k) {
            part.push_back(static_cast<Index>(c.points.size()));
            c.points.push_back(m + Eigen::Vector3f(spread(rng), spread(rng), spread(rng)));
        }
    }
    c.SetUnorganized();
    for (float d : {0.005f, 0.02f, 0.05f}) {
        const PartGraph g = BuildPartGraph(c, parts, {.adjacency_distance = d});
        for (std::uint32_t a = 0; a < parts.size(); ++a) {
            for (std::uint32_t b = a + 1; b < parts.size(); ++b) {
                bool near = false;
                for (Index i : parts[a])
                    for (Index j : parts[b])
                        near = near || (c.points[i] - c.points[j]).squaredNorm() < d * d;
                EXPECT_EQ(g.Adjacent(a, b), near) << "parts " << a << ", " << b << " at " << d;
            }
        }
    }
}

TEST(PartGraph, DescriptorsAreAdditive) {
    std::vector<Indices> parts;
    const PointCloud c = ThreePatches(parts);
    const FeatureMatrix d = ComputePartDescriptors(c, parts);
    ASSERT_EQ(d.rows(), 3);
    ASSERT_EQ(d.cols(), kPartDescriptorSize);
    for (int p = 0; p < 3; ++p) EXPECT_GT(d.row(p).head<kPartGrsdSize>().sum(), 0.0f);
    const std::vector<std::uint32_t> ab = {0, 1}, abc = {2, 0, 1};
    const auto s = SubgraphDescriptor(d, ab);
    EXPECT_TRUE(s.isApprox(d.row(0) + d.row(1)));
    EXPECT_TRUE(SubgraphDescriptor(d, abc).isApprox(d.row(0) + d.row(1) + d.row(2)));
    // Empty parts, no parts.
    std::vector<Indices> with_empty = parts;
    with_empty.push_back({});
    const FeatureMatrix e = ComputePartDescriptors(c, with_empty);
    EXPECT_EQ(e.row(3).cwiseAbs().sum(), 0.0f);
    EXPECT_EQ(ComputePartDescriptors(c, {}).rows(), 0);
    PointCloud no_normals = c;
    no_normals.normals.clear();
    EXPECT_THROW(ComputePartDescriptors(no_normals, parts), DataError);
}

// A plane patch (normals +z) and the side of a 2 cm cylinder about z (radial normals).
PointCloud PatchAndCylinder(std::vector<Indices>& parts) {
    PointCloud c;
    parts.assign(3, {});
    for (int i = 0; i < 15; ++i)
        for (int j = 0; j < 15; ++j) {
            parts[0].push_back(static_cast<Index>(c.points.size()));
            c.points.emplace_back(0.2f + 0.004f * i, 0.004f * j, 0.0f);
            c.normals.emplace_back(0.0f, 0.0f, 1.0f);
        }
    for (int a = 0; a < 60; ++a)
        for (int h = 0; h < 16; ++h) {
            const float t = 2.0f * 3.14159265f * static_cast<float>(a) / 60.0f;
            // Lower and upper half of the side are parts 1 and 2.
            parts[h < 8 ? 1 : 2].push_back(static_cast<Index>(c.points.size()));
            c.points.emplace_back(0.02f * std::cos(t), 0.02f * std::sin(t), 0.004f * h);
            c.normals.emplace_back(std::cos(t), std::sin(t), 0.0f);
        }
    c.width = static_cast<std::uint32_t>(c.points.size());
    c.height = 1;
    return c;
}

TEST(PartGraph, ElevationAndCurvatureBlocks) {
    std::vector<Indices> parts;
    const PointCloud c = PatchAndCylinder(parts);
    const Eigen::Vector3f z = Eigen::Vector3f::UnitZ();
    const FeatureMatrix d = ComputePartDescriptors(c, parts, {}, z);
    auto elevation = [&](const FeatureMatrix& m, int p) {
        return Eigen::RowVectorXf(m.row(p).segment(kPartElevationOffset, kPartElevationSize));
    };
    auto curvature = [&](const FeatureMatrix& m, int p) {
        return Eigen::RowVectorXf(m.row(p).segment(kPartRsdOffset, kPartRsdSize));
    };
    // Horizontal patch: every normal along up (last bin); cylinder side: all horizontal (first).
    EXPECT_EQ(elevation(d, 0)[kPartElevationSize - 1], 225.0f);
    EXPECT_EQ(elevation(d, 0).sum(), 225.0f);
    EXPECT_EQ(elevation(d, 1)[0], 480.0f);
    EXPECT_EQ(elevation(d, 1).sum(), 480.0f);
    // Sign and length of up do not change the counts (the moments' frame turns); unknown up is
    // the camera's -y.
    const FeatureMatrix down = ComputePartDescriptors(c, parts, {}, Eigen::Vector3f(0, 0, -3));
    EXPECT_TRUE(down.leftCols(kPartGrsdSize).isApprox(d.leftCols(kPartGrsdSize)));
    EXPECT_TRUE(down.rightCols(kPartElevationSize + kPartRsdSize)
                    .isApprox(d.rightCols(kPartElevationSize + kPartRsdSize)));
    const FeatureMatrix cam = ComputePartDescriptors(c, parts, {});
    EXPECT_EQ(elevation(cam, 0)[0], 225.0f);
    EXPECT_TRUE(elevation(cam, 0).isApprox(
        elevation(ComputePartDescriptors(c, parts, {}, -Eigen::Vector3f::UnitY()), 0)));
    // Curvature: the plane is planar (r_min >= 10 cm), the 2 cm cylinder curved (< 3 cm).
    EXPECT_EQ(curvature(d, 0)[2], curvature(d, 0).sum());
    EXPECT_GT(curvature(d, 0).sum(), 0.0f);
    const Eigen::RowVectorXf side = curvature(d, 1) + curvature(d, 2);
    EXPECT_GT(side[0], 0.8f * side.sum());
    // Additive: the union of parts 1 and 2 as one part has the sum of their rows.
    const std::vector<Indices> joined = {parts[0], [&] {
                                             Indices u = parts[1];
                                             u.insert(u.end(), parts[2].begin(), parts[2].end());
                                             return u;
                                         }()};
    const FeatureMatrix j = ComputePartDescriptors(c, joined, {}, z);
    const std::vector<std::uint32_t> both = {1, 2};
    const auto sum = SubgraphDescriptor(d, both);
    for (int k = kPartElevationOffset; k < kPartDescriptorSize; ++k) {
        EXPECT_EQ(j(1, k), sum[k]) << k;
    }
    for (int k = kPartMomentOffset; k < kPartMomentOffset + kPartMomentSize; ++k) {
        EXPECT_NEAR(j(1, k), sum[k], 1e-4f * (1.0f + std::abs(sum[k]))) << k;
    }
    // Mapped: square-rooted unit-sum blocks times their weights.
    PartGraphModel m;
    m.descriptor_params.elevation_weight = 2.0f;
    m.descriptor_params.rsd_weight = 0.5f;
    float mapped[kPartMappedSize];
    m.MapDescriptor(sum.data(), mapped);
    float e2 = 0.0f, r2 = 0.0f;
    for (int k = 0; k < kPartElevationSize; ++k)
        e2 += mapped[kPartGrsdSize + 3 + k] * mapped[kPartGrsdSize + 3 + k];
    for (int k = 0; k < kPartRsdSize; ++k) {
        const float v = mapped[kPartGrsdSize + 3 + kPartElevationSize + k];
        r2 += v * v;
    }
    EXPECT_NEAR(e2, 4.0f, 1e-4f);
    EXPECT_NEAR(r2, 0.25f, 1e-4f);
    EXPECT_NEAR(mapped[kPartGrsdSize + 3], 2.0f, 1e-5f);  // all in the first bin
    // Weight 0: the block is empty.
    m.descriptor_params.elevation_weight = 0.0f;
    m.MapDescriptor(sum.data(), mapped);
    for (int k = 0; k < kPartElevationSize; ++k) EXPECT_EQ(mapped[kPartGrsdSize + 3 + k], 0.0f);
    // Bad input.
    EXPECT_THROW(ComputePartDescriptors(c, parts, {}, Eigen::Vector3f(NAN, 0, 1)), InvalidArgument);
    EXPECT_THROW(ComputePartDescriptors(c, parts, {.elevation_weight = -1.0f}), InvalidArgument);
    EXPECT_THROW(ComputePartDescriptors(c, parts, {.extent_weights = {1.0f, INFINITY, 1.0f}}),
                 InvalidArgument);
}

// Separate extent factors scale the largest, middle and smallest extent.
TEST(PartGraph, ExtentWeights) {
    std::vector<Indices> parts;
    const PointCloud c = PatchAndCylinder(parts);
    const FeatureMatrix d = ComputePartDescriptors(c, parts, {}, Eigen::Vector3f::UnitZ());
    const std::vector<std::uint32_t> all = {0, 1, 2};
    const auto raw = SubgraphDescriptor(d, all);
    PartGraphModel m;
    float a[kPartMappedSize], b[kPartMappedSize];
    m.MapDescriptor(raw.data(), a);
    m.descriptor_params.extent_weights = {0.5f, 1.0f, 3.0f};
    m.MapDescriptor(raw.data(), b);
    EXPECT_NEAR(b[kPartGrsdSize], 0.5f * a[kPartGrsdSize], 1e-4f);
    EXPECT_NEAR(b[kPartGrsdSize + 1], a[kPartGrsdSize + 1], 1e-4f);
    EXPECT_NEAR(b[kPartGrsdSize + 2], 3.0f * a[kPartGrsdSize + 2], 1e-4f);
    EXPECT_GT(a[kPartGrsdSize + 2], 0.0f);
}

// Upright extents: the two extents on the support plane, then the one along up.
TEST(PartGraph, UprightExtents) {
    std::vector<Indices> parts;
    const PointCloud c = ThreePatches(parts);  // horizontal 12 x 12 patches, 4 mm apart
    const std::vector<Indices> one = {parts[2]};
    PartGraphModel m;
    m.descriptor_params.size_weight = 1.0f;
    m.descriptor_params.upright_extents = true;
    const double side = 0.004 * std::sqrt(143.0);
    float out[kPartMappedSize];
    const FeatureMatrix up_z = ComputePartDescriptors(c, one, {}, Eigen::Vector3f::UnitZ());
    m.MapDescriptor(up_z.row(0).data(), out);
    EXPECT_NEAR(out[kPartGrsdSize], side, 1e-4);
    EXPECT_NEAR(out[kPartGrsdSize + 1], side, 1e-4);
    EXPECT_NEAR(out[kPartGrsdSize + 2], 0.0, 1e-4);
    // Seen with x as up, the patch is a wall: one extent on the plane, one along up.
    const FeatureMatrix up_x = ComputePartDescriptors(c, one, {}, Eigen::Vector3f::UnitX());
    m.MapDescriptor(up_x.row(0).data(), out);
    EXPECT_NEAR(out[kPartGrsdSize], side, 1e-4);
    EXPECT_NEAR(out[kPartGrsdSize + 1], 0.0, 1e-4);
    EXPECT_NEAR(out[kPartGrsdSize + 2], side, 1e-4);
    // Principal extents do not depend on up.
    m.descriptor_params.upright_extents = false;
    float a[kPartMappedSize], b[kPartMappedSize];
    m.MapDescriptor(up_z.row(0).data(), a);
    m.MapDescriptor(up_x.row(0).data(), b);
    for (int j = 0; j < 3; ++j) EXPECT_NEAR(a[kPartGrsdSize + j], b[kPartGrsdSize + j], 1e-4f);
}

// The extents of a group come from its summed moments and equal those of the union's points.
TEST(PartGraph, ExtentsFromSummedMoments) {
    std::vector<Indices> parts;
    const PointCloud c = ThreePatches(parts);
    const FeatureMatrix d = ComputePartDescriptors(c, parts);
    EXPECT_FLOAT_EQ(d(0, kPartGrsdSize), 144.0f);  // point count
    PartGraphModel m;
    m.descriptor_params.size_weight = 1.0f;  // extents in metres
    auto direct = [&](const std::vector<int>& ids) {
        Eigen::Vector3d mean = Eigen::Vector3d::Zero();
        std::size_t n = 0;
        for (int p : ids)
            for (Index i : parts[p]) mean += c.points[i].cast<double>(), ++n;
        mean /= double(n);
        Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
        for (int p : ids)
            for (Index i : parts[p]) {
                const Eigen::Vector3d q = c.points[i].cast<double>() - mean;
                cov += q * q.transpose();
            }
        cov /= double(n);
        const Eigen::Vector3d l = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(cov).eigenvalues();
        return Eigen::Vector3d(std::sqrt(12 * l[2]), std::sqrt(12 * std::max(l[1], 0.0)),
                               std::sqrt(12 * std::max(l[0], 0.0)));
    };
    for (const std::vector<int>& ids : {std::vector<int>{0}, {0, 1}, {0, 1, 2}}) {
        std::vector<std::uint32_t> vs(ids.begin(), ids.end());
        const auto raw = SubgraphDescriptor(d, vs);
        float mapped[kPartMappedSize];
        m.MapDescriptor(raw.data(), mapped);
        const Eigen::Vector3d want = direct(ids);
        for (int j = 0; j < 3; ++j) EXPECT_NEAR(mapped[kPartGrsdSize + j], want[j], 1e-4);
        float sum = 0.0f;
        for (int j = 0; j < kPartGrsdSize; ++j) sum += mapped[j] * mapped[j];
        EXPECT_NEAR(sum, 1.0f, 1e-5f);  // square-rooted unit-sum histogram
    }
    // One 12 x 12 patch, 4 mm apart: extents 4 mm * sqrt(143) twice, flat.
    float one[kPartMappedSize];
    m.MapDescriptor(SubgraphDescriptor(d, std::vector<std::uint32_t>{2}).data(), one);
    EXPECT_NEAR(one[kPartGrsdSize], 0.004 * std::sqrt(143.0), 1e-4);
    EXPECT_NEAR(one[kPartGrsdSize + 2], 0.0, 1e-4);
    // Weight 0 drops the extents.
    m.descriptor_params.size_weight = 0.0f;
    m.MapDescriptor(SubgraphDescriptor(d, std::vector<std::uint32_t>{2}).data(), one);
    EXPECT_EQ(one[kPartGrsdSize], 0.0f);
}

// Balanced votes: a category with a third of the rows weighs as much as the other.
TEST(PartGraphModel, BalancedVotesDivideByClassShare) {
    PartGraphModel m;
    PartGraph g(3);
    g.AddEdge(0, 1);
    g.AddEdge(1, 2);
    FeatureMatrix box = FeatureMatrix::Zero(3, kPartDescriptorSize);
    FeatureMatrix ball = FeatureMatrix::Zero(3, kPartDescriptorSize);
    for (int p = 0; p < 3; ++p) {
        box(p, 6) = 10.0f;
        ball(p, 15) = 10.0f;
    }
    for (int i = 0; i < 3; ++i) m.AddObject(box, g, Category::kBox, {.max_parts = 1});
    m.AddObject(ball, g, Category::kSphere, {.max_parts = 1});
    m.Build();
    const std::uint64_t key = SubgraphKey(g, std::vector<std::uint32_t>{0});
    const auto plain = m.Classify(key, box.row(0).data(), 100);
    const auto balanced = m.Classify(key, box.row(0).data(), 100, nullptr, true);
    EXPECT_NEAR(plain[static_cast<int>(Category::kBox)], 0.75f, 1e-6f);
    EXPECT_NEAR(balanced[static_cast<int>(Category::kBox)], 0.5f, 1e-6f);
    EXPECT_NEAR(balanced[static_cast<int>(Category::kSphere)], 0.5f, 1e-6f);
    // Distance-weighted: the three box rows lie at distance 0, the sphere row at sqrt(2)
    // (Jeffries-Matusita of disjoint histograms): 3 / 0.05 against 1 / (sqrt(2) + 0.05).
    const auto near = m.Classify(key, box.row(0).data(), 100, nullptr, false, 0.05f);
    const float wb = 3.0f / 0.05f, ws = 1.0f / (std::sqrt(2.0f) + 0.05f);
    EXPECT_NEAR(near[static_cast<int>(Category::kBox)], wb / (wb + ws), 1e-4f);
    PartGraphRecognitionParams bad;
    bad.distance_offset = 0.0f;
    EXPECT_THROW(RecognizeParts(m, g, box, bad), InvalidArgument);
}

TEST(PartGraphModel, BlendIsAWeightedProductOfExperts) {
    std::array<float, kNumCategories> a{}, b{};
    a[static_cast<int>(Category::kBox)] = 0.7f;
    a[static_cast<int>(Category::kFlat)] = 0.3f;
    b[static_cast<int>(Category::kFlat)] = 0.6f;
    b[static_cast<int>(Category::kCylinder)] = 0.4f;
    EXPECT_EQ(ArgMaxCategory(BlendCategoryProbabilities(a, b, 0.0f)), Category::kBox);
    EXPECT_EQ(ArgMaxCategory(BlendCategoryProbabilities(a, b, 1.0f)), Category::kFlat);
    // Both agree on flat more than on anything else.
    const auto mid = BlendCategoryProbabilities(a, b, 0.5f);
    EXPECT_EQ(ArgMaxCategory(mid), Category::kFlat);
    EXPECT_EQ(mid[0], 0.0f);
    float sum = 0.0f;
    for (float v : mid) sum += v;
    EXPECT_NEAR(sum, 1.0f, 1e-6f);
    EXPECT_THROW(BlendCategoryProbabilities(a, b, -0.1f), InvalidArgument);
    EXPECT_THROW(BlendCategoryProbabilities(a, b, 1.1f), InvalidArgument);
    // The general form: a lone weighted expert keeps its ranking; bad weights are refused.
    const std::array<const CategoryDistribution*, 2> experts{&a, &b};
    const std::array<float, 2> only_a{3.0f, 0.0f}, negative{1.0f, -1.0f}, zero{0.0f, 0.0f};
    const std::array<float, 1> one{1.0f};
    EXPECT_EQ(ArgMaxCategory(WeightedProductOfExperts(experts, only_a)), Category::kBox);
    EXPECT_THROW(WeightedProductOfExperts(experts, negative), InvalidArgument);
    EXPECT_THROW(WeightedProductOfExperts(experts, zero), InvalidArgument);
    EXPECT_THROW(WeightedProductOfExperts(experts, one), InvalidArgument);
}

// A model over synthetic descriptors: two categories with distinct histograms.
PartGraphModel SyntheticModel() {
    PartGraphModel m;
    PartGraph g(3);
    g.AddEdge(0, 1);
    g.AddEdge(1, 2);
    for (int obj = 0; obj < 4; ++obj) {
        FeatureMatrix box = FeatureMatrix::Zero(3, kPartDescriptorSize);
        FeatureMatrix ball = FeatureMatrix::Zero(3, kPartDescriptorSize);
        for (int p = 0; p < 3; ++p) {
            box(p, 6) = 50.0f + static_cast<float>(obj + p);
            box(p, 0) = 5.0f;
            ball(p, 15) = 40.0f + static_cast<float>(obj * p);
            ball(p, 11) = 8.0f;
        }
        m.AddObject(box, g, Category::kBox, {.max_parts = 3, .seed = 1u + obj});
        m.AddObject(ball, g, Category::kSphere, {.max_parts = 3, .seed = 7u + obj});
    }
    m.Build();
    return m;
}

TEST(PartGraphModel, ClassifiesAndRoundTrips) {
    const PartGraphModel m = SyntheticModel();
    EXPECT_EQ(m.num_rows(), 2u * 4u * 6u);  // 6 connected subgraphs of a 3-path
    PartGraph q(2);
    q.AddEdge(0, 1);
    FeatureMatrix d = FeatureMatrix::Zero(2, kPartDescriptorSize);
    d(0, 6) = 30.0f;
    d(0, 0) = 4.0f;
    d(1, 15) = 30.0f;
    d(1, 11) = 5.0f;
    const PartGraphResult r = RecognizeParts(m, q, d, {.max_parts = 2, .k = 3});
    EXPECT_EQ(r.part_categories[0], Category::kBox);
    EXPECT_EQ(r.part_categories[1], Category::kSphere);
    EXPECT_EQ(r.subgraphs, 3u);

    test::TempDir dir;
    const auto path = dir.path() / "m.mcpg";
    m.Save(path);
    const PartGraphModel l = PartGraphModel::Load(path);
    EXPECT_EQ(l.Serialize(), m.Serialize());
    {  // every descriptor weight travels with the model
        PartGraphModel w = SyntheticModel();
        w.descriptor_params.size_weight = 7.0f;
        w.descriptor_params.extent_weights = {0.5f, 1.5f, 2.5f};
        w.descriptor_params.grsd_weight = 0.75f;
        w.descriptor_params.elevation_weight = 3.0f;
        w.descriptor_params.rsd_weight = 0.25f;
        w.descriptor_params.upright_extents = true;
        w.descriptor_params.voxels.rsd.angle_quantile = 0.65f;
        const PartGraphModel lw = PartGraphModel::Deserialize(w.Serialize(), "w");
        EXPECT_EQ(lw.descriptor_params.voxels.rsd.angle_quantile, 0.65f);
        EXPECT_EQ(lw.descriptor_params.size_weight, 7.0f);
        EXPECT_EQ(lw.descriptor_params.extent_weights, w.descriptor_params.extent_weights);
        EXPECT_EQ(lw.descriptor_params.grsd_weight, 0.75f);
        EXPECT_EQ(lw.descriptor_params.elevation_weight, 3.0f);
        EXPECT_EQ(lw.descriptor_params.rsd_weight, 0.25f);
        EXPECT_TRUE(lw.descriptor_params.upright_extents);
        EXPECT_EQ(lw.Serialize(), w.Serialize());
        w.descriptor_params.rsd_weight = -1.0f;
        EXPECT_THROW(PartGraphModel::Deserialize(w.Serialize(), "negative"), FormatError);
    }
    const PartGraphResult r2 = RecognizeParts(l, q, d, {.max_parts = 2, .k = 3});
    EXPECT_EQ(r2.part_probabilities, r.part_probabilities);

    // Unseen degree sequence of a known size falls back to the nearest bucket.
    PartGraph tri(3);
    tri.AddEdge(0, 1);
    tri.AddEdge(1, 2);
    tri.AddEdge(0, 2);
    FeatureMatrix t = FeatureMatrix::Zero(3, kPartDescriptorSize);
    for (int p = 0; p < 3; ++p) t(p, 15) = 20.0f;
    const PartGraphResult r3 = RecognizeParts(l, tri, t, {.max_parts = 3, .k = 3});
    EXPECT_GT(r3.fallbacks, 0u);
    EXPECT_EQ(r3.part_categories[2], Category::kSphere);

    // Empty input.
    EXPECT_TRUE(RecognizeParts(l, PartGraph(0), FeatureMatrix(0, kPartDescriptorSize))
                    .part_categories.empty());
    EXPECT_THROW(RecognizeParts(l, q, d, {.k = 0}), InvalidArgument);
    EXPECT_THROW(RecognizeParts(l, tri, d), InvalidArgument);
}

// Objects as groups of parts: single parts look like flat (GRSD- column 6) and sphere (column
// 15) parts, but together they are the two parts of a box; only the whole object's own vote
// knows it. Subgraphs across objects do not vote when restricted to groups.
TEST(PartGraphModel, GroupsRestrictSubgraphsAndVoteAsWholes) {
    PartGraphModel m;
    PartGraph pair(2);
    pair.AddEdge(0, 1);
    for (int obj = 0; obj < 4; ++obj) {
        FeatureMatrix box = FeatureMatrix::Zero(2, kPartDescriptorSize);
        box(0, 6) = 50.0f;
        box(1, 15) = 50.0f;
        box(0, 0) = box(1, 0) = 3.0f;
        FeatureMatrix flat = FeatureMatrix::Zero(2, kPartDescriptorSize);
        flat(0, 6) = flat(1, 6) = 50.0f;
        FeatureMatrix ball = FeatureMatrix::Zero(2, kPartDescriptorSize);
        ball(0, 15) = ball(1, 15) = 50.0f;
        const std::uint64_t seed = 1u + static_cast<std::uint64_t>(obj);
        m.AddObject(box, pair, Category::kBox, {.max_parts = 2, .seed = seed});
        m.AddObject(flat, pair, Category::kFlat, {.max_parts = 2, .seed = seed});
        m.AddObject(ball, pair, Category::kSphere, {.max_parts = 2, .seed = seed});
    }
    m.Build();
    FeatureMatrix q = FeatureMatrix::Zero(2, kPartDescriptorSize);
    q(0, 6) = 50.0f;
    q(1, 15) = 50.0f;
    PartGraphRecognitionParams rp{.max_parts = 1, .k = 4, .balanced = false};
    const std::vector<std::uint32_t> one{0, 0}, two{0, 1};
    const PartGraphResult parts_only = RecognizeParts(m, pair, q, rp, one);
    EXPECT_EQ(parts_only.part_categories[0], Category::kFlat);
    EXPECT_EQ(parts_only.part_categories[1], Category::kSphere);
    EXPECT_EQ(parts_only.subgraphs, 2u);
    rp.group_weight = 3.0f;
    const PartGraphResult whole = RecognizeParts(m, pair, q, rp, one);
    EXPECT_EQ(whole.part_categories[0], Category::kBox);
    EXPECT_EQ(whole.part_categories[1], Category::kBox);
    EXPECT_EQ(whole.subgraphs, 3u);
    // Two objects: each whole is a single part, nothing spans them.
    const PartGraphResult apart = RecognizeParts(m, pair, q, rp, two);
    EXPECT_EQ(apart.part_categories[0], Category::kFlat);
    EXPECT_EQ(apart.part_categories[1], Category::kSphere);
    rp.group_weight = 0.0f;
    rp.max_parts = 2;
    EXPECT_EQ(RecognizeParts(m, pair, q, rp, two).subgraphs, 2u);
    EXPECT_EQ(RecognizeParts(m, pair, q, rp).subgraphs, 3u);  // no groups: the pair votes
    rp.within_groups = false;
    EXPECT_EQ(RecognizeParts(m, pair, q, rp, two).subgraphs, 3u);
    // Deterministic, and bad groups or weights are refused.
    rp.group_weight = 1.0f;
    EXPECT_EQ(RecognizeParts(m, pair, q, rp, one).part_probabilities,
              RecognizeParts(m, pair, q, rp, one).part_probabilities);
    EXPECT_THROW(RecognizeParts(m, pair, q, rp, std::vector<std::uint32_t>{0}), InvalidArgument);
    rp.group_weight = -1.0f;
    EXPECT_THROW(RecognizeParts(m, pair, q, rp, one), InvalidArgument);
}

TEST(PartGraphModel, CategoryPriorsScaleTheVotes) {
    // Every stored row of one descriptor: 3 of "other", 2 of cylinder.
    PartGraphModel m;
    PartGraph single(1);
    FeatureMatrix d = FeatureMatrix::Zero(1, kPartDescriptorSize);
    d(0, 6) = 50.0f;
    for (int i = 0; i < 3; ++i) m.AddObject(d, single, Category::kOther, {.max_parts = 1});
    for (int i = 0; i < 2; ++i) m.AddObject(d, single, Category::kCylinder, {.max_parts = 1});
    m.Build();
    PartGraphRecognitionParams rp{.k = 5, .balanced = false};
    const PartGraphResult plain = RecognizeParts(m, single, d, rp);
    EXPECT_EQ(plain.part_categories[0], Category::kOther);
    EXPECT_NEAR(plain.part_probabilities[0][static_cast<std::size_t>(Category::kOther)], 0.6f,
                1e-5f);
    // Priors multiply the accumulated votes: 3 x 0.5 < 2 x 1.
    rp.category_priors[static_cast<std::size_t>(Category::kOther)] = 0.5f;
    const PartGraphResult shifted = RecognizeParts(m, single, d, rp);
    EXPECT_EQ(shifted.part_categories[0], Category::kCylinder);
    EXPECT_NEAR(shifted.part_probabilities[0][static_cast<std::size_t>(Category::kCylinder)],
                2.0f / 3.5f, 1e-5f);
    // Uniform priors of any scale change nothing; bad priors are refused.
    rp.category_priors.fill(4.0f);
    EXPECT_EQ(RecognizeParts(m, single, d, rp).part_probabilities, plain.part_probabilities);
    rp.category_priors[static_cast<std::size_t>(Category::kBox)] = -1.0f;
    EXPECT_THROW(RecognizeParts(m, single, d, rp), InvalidArgument);
    rp.category_priors.fill(std::numeric_limits<float>::quiet_NaN());
    EXPECT_THROW(RecognizeParts(m, single, d, rp), InvalidArgument);
    rp.category_priors.fill(0.0f);
    EXPECT_THROW(RecognizeParts(m, single, d, rp), InvalidArgument);
    // The same weighting of any distribution (the whole-object expert's in perceive).
    std::array<float, kNumCategories> p{}, priors = UniformCategoryPriors();
    p[static_cast<std::size_t>(Category::kOther)] = 0.6f;
    p[static_cast<std::size_t>(Category::kCylinder)] = 0.4f;
    priors[static_cast<std::size_t>(Category::kOther)] = 0.5f;
    const auto q = ApplyCategoryPriors(p, priors);
    EXPECT_NEAR(q[static_cast<std::size_t>(Category::kCylinder)], 0.4f / 0.7f, 1e-6f);
    EXPECT_NEAR(q[static_cast<std::size_t>(Category::kOther)], 0.3f / 0.7f, 1e-6f);
    EXPECT_EQ(ApplyCategoryPriors({}, priors), (std::array<float, kNumCategories>{}));
}

TEST(PartGraphModel, CorruptFilesAreRejected) {
    const PartGraphModel m = SyntheticModel();
    test::TempDir dir;
    const auto path = dir.path() / "m.mcpg";
    m.Save(path);
    std::string bytes;
    {
        std::ifstream in(path, std::ios::binary);
        bytes.assign(std::istreambuf_iterator<char>(in), {});
    }
    std::string flipped = bytes;
    flipped[bytes.size() / 2] = static_cast<char>(flipped[bytes.size() / 2] ^ 0x55);
    EXPECT_THROW(PartGraphModel::Deserialize(flipped, "flipped"), FormatError);
    EXPECT_THROW(PartGraphModel::Deserialize(bytes.substr(0, bytes.size() - 9), "cut"),
                 FormatError);
    EXPECT_THROW(PartGraphModel::Deserialize("not a model", "text"), FormatError);
    // Files of previous layouts (version 1: GRSD- only; 2: no elevation and curvature blocks;
    // 3: no whole-object rows; 4: no RSD angle quantile; 5: no stacker) are refused by their
    // version.
    for (std::uint32_t old : {1u, 2u, 3u, 4u, 5u}) {
        try {
            PartGraphModel::Deserialize(ml::WrapContainer("MCPARTGR", old, "old"), "old.mcpg");
            ADD_FAILURE() << "version " << old << " accepted";
        } catch (const FormatError& e) {
            const std::string msg = e.what();
            EXPECT_NE(msg.find("version " + std::to_string(old)), std::string::npos) << msg;
            EXPECT_NE(msg.find("reads version 6"), std::string::npos) << msg;
        }
    }
    EXPECT_THROW(PartGraphModel::Load(dir.path() / "missing.mcpg"), IoError);
    PartGraphModel unbuilt;
    const float z[kPartDescriptorSize] = {};
    EXPECT_THROW(unbuilt.Classify(0, z, 1), InvalidArgument);
    PartGraph g(1);
    EXPECT_THROW(
        unbuilt.AddObject(FeatureMatrix::Zero(1, kPartDescriptorSize), g, Category::kNone, {}),
        InvalidArgument);
    EXPECT_THROW(
        unbuilt.AddObject(FeatureMatrix::Zero(2, kPartDescriptorSize), g, Category::kBox, {}),
        InvalidArgument);
}

TEST(PartGraphModel, WholeObjectExpertFindsNearestRowsAndRoundTrips) {
    PartGraphModel m = SyntheticModel();
    EXPECT_EQ(m.num_clusters(), 0u);
    const auto empty = m.ClassifyCluster(Eigen::VectorXf::Ones(4), 3);
    EXPECT_EQ(*std::max_element(empty.begin(), empty.end()), 0.0f);
    // Two clouds of rows: boxes near (1, 0, 0, 0), cylinders near (0, 1, 0, 0).
    for (int i = 0; i < 6; ++i) {
        Eigen::VectorXf box = Eigen::VectorXf::Zero(4), cyl = Eigen::VectorXf::Zero(4);
        box[0] = 1.0f + 0.01f * float(i);
        box[2] = 0.02f * float(i);
        cyl[1] = 1.0f - 0.01f * float(i);
        cyl[3] = 0.02f * float(i);
        m.AddCluster(box, Category::kBox);
        m.AddCluster(cyl, Category::kCylinder);
    }
    m.AddCluster(Eigen::VectorXf::Zero(4), Category::kBox);  // all zero: skipped
    EXPECT_EQ(m.num_clusters(), 12u);
    Eigen::VectorXf q = Eigen::VectorXf::Zero(4);
    q[0] = 0.9f;
    q[1] = 0.2f;
    const auto p = m.ClassifyCluster(q, 5);
    EXPECT_FLOAT_EQ(p[static_cast<std::size_t>(Category::kBox)], 1.0f);
    const auto all = m.ClassifyCluster(q, 100);  // k above the row count: every row votes
    EXPECT_FLOAT_EQ(all[static_cast<std::size_t>(Category::kCylinder)], 0.5f);
    const auto wrong = m.ClassifyCluster(Eigen::VectorXf::Ones(3), 5);
    EXPECT_EQ(*std::max_element(wrong.begin(), wrong.end()), 0.0f);
    m.cluster_size_weight = 4.0f;
    const PartGraphModel back = PartGraphModel::Deserialize(m.Serialize(), "round trip");
    EXPECT_EQ(back.num_clusters(), 12u);
    EXPECT_EQ(back.cluster_size_weight, 4.0f);
    EXPECT_EQ(back.ClassifyCluster(q, 5), p);
    EXPECT_EQ(back.Serialize(), m.Serialize());
    EXPECT_THROW(m.AddCluster(Eigen::VectorXf::Ones(5), Category::kBox), InvalidArgument);
    EXPECT_THROW(m.AddCluster(Eigen::VectorXf::Ones(4), Category::kNone), InvalidArgument);
    Eigen::VectorXf nan = Eigen::VectorXf::Ones(4);
    nan[1] = std::numeric_limits<float>::quiet_NaN();
    EXPECT_THROW(m.AddCluster(nan, Category::kBox), InvalidArgument);
}

TEST(PartGraphModel, VoxelVotesAccumulateViews) {
    VoxelVoteGrid grid(0.005f);
    std::array<float, kNumCategories> box{}, ball{};
    box[static_cast<int>(Category::kBox)] = 1.0f;
    ball[static_cast<int>(Category::kSphere)] = 1.0f;
    const Eigen::Vector3f p(0.101f, 0.2f, 0.3f), near(0.1024f, 0.2001f, 0.3001f);
    grid.Add({p}, {box});
    grid.Add({near}, {ball});
    grid.Add({near}, {ball});
    EXPECT_EQ(grid.CategoryAt(p), Category::kSphere);
    EXPECT_EQ(grid.CategoryAt(Eigen::Vector3f(1, 1, 1)), Category::kNone);
    EXPECT_THROW(grid.Add({p}, {}), InvalidArgument);
    EXPECT_THROW(VoxelVoteGrid(0.0f), InvalidArgument);
}

// The stacker recovers a known rule from noisy experts: the truth is the category that the
// part-graph and cluster experts both raise, while the rules' distribution is pure noise.
TEST(CategoryStacker, LearnsWhichExpertToTrust) {
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    auto make = [&](int n, std::vector<std::array<float, kStackerInputSize>>& x,
                    std::vector<Category>& y) {
        for (int i = 0; i < n; ++i) {
            const auto truth = static_cast<std::size_t>(1 + i % 6);
            CategoryResult rules;
            for (std::size_t c = 1; c < kNumCategories; ++c) rules.probabilities[c] = u(rng);
            CategoryDistribution pg{}, cl{};
            for (std::size_t c = 1; c < kNumCategories; ++c) {
                pg[c] = 0.3f * u(rng);
                cl[c] = 0.3f * u(rng);
            }
            pg[truth] += 0.5f;
            cl[truth] += 0.4f;
            rules.extents = Eigen::Vector3f(0.1f + 0.01f * u(rng), 0.05f, 0.02f);
            x.push_back(StackerInputs(rules, pg, cl));
            y.push_back(static_cast<Category>(truth));
        }
    };
    std::vector<std::array<float, kStackerInputSize>> xt, xv;
    std::vector<Category> yt, yv;
    make(600, xt, yt);
    make(300, xv, yv);
    CategoryStacker s;
    EXPECT_FALSE(s.trained());
    EXPECT_THROW(s.Predict(xv[0]), InvalidArgument);
    s.Fit(xt, yt);
    ASSERT_TRUE(s.trained());
    EXPECT_EQ(s.train_rows(), 600u);
    int correct = 0;
    for (std::size_t i = 0; i < xv.size(); ++i) {
        const auto p = s.Predict(xv[i]);
        EXPECT_EQ(p[0], 0.0f);
        float sum = 0.0f;
        for (float v : p) sum += v;
        EXPECT_NEAR(sum, 1.0f, 1e-5f);
        correct += ArgMaxCategory(p) == yv[i];
    }
    EXPECT_GE(correct, 285) << correct << " of 300";
    // Deterministic, and the parameters round-trip exactly.
    CategoryStacker again;
    again.Fit(xt, yt);
    EXPECT_EQ(again.Parameters(), s.Parameters());
    const CategoryStacker back = CategoryStacker::FromParameters(s.Parameters(), "stacker");
    EXPECT_EQ(back.Predict(xv[7]), s.Predict(xv[7]));
    EXPECT_FALSE(CategoryStacker::FromParameters({}, "empty").trained());
    // Non-finite inputs count as 0 instead of poisoning the output.
    auto nan_row = xv[0];
    nan_row[30] = std::numeric_limits<float>::quiet_NaN();
    for (float v : s.Predict(nan_row)) EXPECT_TRUE(std::isfinite(v));
}

TEST(CategoryStacker, RefusesBadInput) {
    CategoryStacker s;
    std::vector<std::array<float, kStackerInputSize>> x(3);
    EXPECT_THROW(s.Fit({}, {}), InvalidArgument);
    EXPECT_THROW(s.Fit(x, {Category::kBox}), InvalidArgument);
    EXPECT_THROW(s.Fit(x, {Category::kBox, Category::kNone, Category::kFlat}), InvalidArgument);
    const std::vector<Category> y = {Category::kBox, Category::kFlat, Category::kBox};
    EXPECT_THROW(s.Fit(x, y, {.l2 = -1.0f}), InvalidArgument);
    EXPECT_THROW(s.Fit(x, y, {.iterations = 0}), InvalidArgument);
    EXPECT_THROW(s.Fit(x, y, {.step = 0.0f}), InvalidArgument);
    EXPECT_FALSE(s.trained());
    s.Fit(x, y);  // constant inputs: the prior of the training rows
    EXPECT_EQ(ArgMaxCategory(s.Predict(x[0])), Category::kBox);
    auto params = s.Parameters();
    params.pop_back();
    EXPECT_THROW(CategoryStacker::FromParameters(params, "cut"), FormatError);
    params = s.Parameters();
    params[5] = std::numeric_limits<float>::infinity();
    EXPECT_THROW(CategoryStacker::FromParameters(params, "inf"), FormatError);
}

}  // namespace
}  // namespace multicue

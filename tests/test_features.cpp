// Features of section 2.5 and 4.2.3.1 on synthetic surfaces: RSD radii, surface types, GRSD-
// additivity, histogram normalisation, invariance, bad input and determinism.

#include <algorithm>
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "features_synthetic.hpp"
#include "multicue/core/exceptions.hpp"
#include "multicue/features/features.hpp"
#include "multicue/surface/normals.hpp"

namespace multicue {
namespace {

using test::AddKinectNoise;

std::vector<float> Column(const FeatureMatrix& m, int col) {
    std::vector<float> v;
    for (Eigen::Index i = 0; i < m.rows(); ++i) {
        if (m.row(i).allFinite()) v.push_back(m(i, col));
    }
    return v;
}

float Quantile(std::vector<float> v, double q) {
    std::sort(v.begin(), v.end());
    return v[static_cast<std::size_t>(q * static_cast<double>(v.size() - 1))];
}

// Section 2.5.1: on synthetic spheres of radius 2-20 cm, r_min is within 1 cm of the radius for
// every point (exact normals, 2 cm neighbourhoods, 5 distance bins).
TEST(Rsd, SpheresWithinOneCentimetreForAllPoints) {
    for (float radius : {0.02f, 0.035f, 0.05f, 0.1f, 0.15f, 0.2f}) {
        const PointCloud sphere = test::Sphere(radius, {0.0f, 0.0f, 1.0f}, 0.004f);
        const KdTree tree(sphere);
        const FeatureMatrix rsd = ComputeRsd(sphere, tree, {});
        ASSERT_EQ(rsd.rows(), static_cast<Eigen::Index>(sphere.size()));
        for (Eigen::Index i = 0; i < rsd.rows(); ++i) {
            ASSERT_NEAR(rsd(i, 0), radius, 0.01f) << "sphere radius " << radius << " point " << i;
            ASSERT_LE(rsd(i, 0), rsd(i, 1));
        }
    }
}

// The same with Kinect noise at 0.6 m and estimated normals: noise widens the angle range, so
// the 1 cm bound holds for 90% of the points up to 15 cm; at 20 cm the median is within 1.5 cm.
TEST(Rsd, NoisySpheresKinectModel) {
    for (float radius : {0.02f, 0.035f, 0.05f, 0.1f, 0.15f, 0.2f}) {
        PointCloud sphere = test::Sphere(radius, {0.0f, 0.0f, 0.6f + radius}, 0.003f, true);
        AddKinectNoise(sphere, 7);
        const KdTree tree(sphere);
        SetNormals(sphere, EstimateNormals(sphere, tree, {.radius = std::min(0.03f, radius)}));
        const auto r_min = Column(ComputeRsd(sphere, tree, {}), 0);
        std::vector<float> err;
        for (float r : r_min) err.push_back(std::abs(r - radius));
        EXPECT_LT(Quantile(err, 0.5), radius <= 0.15f ? 0.01f : 0.015f) << radius;
        if (radius <= 0.15f) {
            EXPECT_LT(Quantile(err, 0.9), 0.01f) << radius;
        }
    }
}

// On a cylinder r_min is its radius and r_max large, away from the two open ends. r_max needs a
// neighbour at a near-zero angle in every distance bin, which the sampling grid does not always
// provide, so it is checked for 90% of the points.
TEST(Rsd, Cylinders) {
    for (float radius : {0.03f, 0.05f, 0.1f}) {
        const PointCloud cyl = test::Cylinder(radius, 0.2f, {0.0f, 0.0f, 1.0f}, 0.003f);
        const KdTree tree(cyl);
        const FeatureMatrix rsd = ComputeRsd(cyl, tree, {});
        std::size_t inner = 0, large = 0;
        for (Eigen::Index i = 0; i < rsd.rows(); ++i) {
            if (std::abs(cyl.points[i].y()) > 0.1f - 0.025f) continue;
            ASSERT_NEAR(rsd(i, 0), radius, 0.01f) << radius;
            ++inner;
            large += rsd(i, 1) > 0.175f ? 1 : 0;
        }
        EXPECT_GT(large, inner * 9 / 10) << radius;
    }
}

// Planes give r_min above the plane threshold, with and without noise.
TEST(Rsd, PlanesAreFlat) {
    PointCloud plane = test::Plane(0.2f, 0.8f, 0.003f);
    const KdTree tree(plane);
    for (const auto& row : Column(ComputeRsd(plane, tree, {}), 0)) ASSERT_GT(row, 0.1f);
    AddKinectNoise(plane, 3);
    const KdTree noisy_tree(plane);
    SetNormals(plane, EstimateNormals(plane, noisy_tree, {.radius = 0.03f}));
    const FeatureMatrix rsd = ComputeRsd(plane, noisy_tree, {});
    std::size_t flat = 0, inner = 0;
    for (Eigen::Index i = 0; i < rsd.rows(); ++i) {
        if (plane.points[i].head<2>().cwiseAbs().maxCoeff() > 0.07f) continue;
        ++inner;
        flat += rsd(i, 0) > 0.1f ? 1 : 0;
    }
    EXPECT_GT(flat, inner * 95 / 100);
}

// Heavy-tailed normal noise (every tenth normal tilted by 30 degrees, as at depth steps of a
// real sensor): with the extreme angles (angle_quantile 1, section 2.5.1) the plane looks curved
// everywhere; with the 80th percentile it is a plane almost everywhere (small first bins hold
// few neighbours), and spheres keep their radius.
TEST(Rsd, AngleQuantileIgnoresNormalOutliers) {
    PointCloud plane = test::Plane(0.2f, 0.8f, 0.003f);
    const Eigen::Vector3f tilted =
        Eigen::AngleAxisf(0.5236f, Eigen::Vector3f::UnitX()) * plane.normals[0];
    for (std::size_t i = 0; i < plane.size(); i += 10) plane.normals[i] = tilted;
    const KdTree tree(plane);
    auto flat_share = [&](const RsdParams& p) {
        const FeatureMatrix rsd = ComputeRsd(plane, tree, p);
        std::size_t flat = 0, inner = 0;
        for (Eigen::Index i = 0; i < rsd.rows(); ++i) {
            // The tilted points themselves see all others tilted; count the rest.
            if (i % 10 == 0 || plane.points[i].head<2>().cwiseAbs().maxCoeff() > 0.07f) continue;
            ++inner;
            flat += rsd(i, 0) > 0.1f ? 1 : 0;
        }
        return static_cast<double>(flat) / static_cast<double>(inner);
    };
    EXPECT_LT(flat_share({}), 0.05);
    EXPECT_GT(flat_share({.angle_quantile = 0.8f}), 0.85);
    EXPECT_EQ(ComputeRsd(plane, tree, {.angle_quantile = 1.0f}), ComputeRsd(plane, tree, {}));
    for (float radius : {0.035f, 0.1f}) {
        const PointCloud sphere = test::Sphere(radius, {0.0f, 0.0f, 1.0f}, 0.004f);
        const KdTree st(sphere);
        const auto r_min = Column(ComputeRsd(sphere, st, {.angle_quantile = 0.8f}), 0);
        std::vector<float> err;
        for (float r : r_min) err.push_back(std::abs(r - radius));
        EXPECT_LT(Quantile(err, 0.9), 0.015f) << radius;
    }
    EXPECT_THROW(ComputeRsd(plane, tree, {.angle_quantile = 0.0f}), InvalidArgument);
    EXPECT_THROW(ComputeRsd(plane, tree, {.angle_quantile = 1.5f}), InvalidArgument);
}

TEST(Rsd, PclOrderGivesCapTimesFactorsOnAPlane) {
    const PointCloud plane = test::Plane(0.1f, 0.8f, 0.004f);
    const KdTree tree(plane);
    const FeatureMatrix ours = ComputeRsd(plane, tree, {});
    const FeatureMatrix pcl = ComputeRsd(plane, tree, {.pcl_compatible = true});
    EXPECT_FLOAT_EQ(ours(0, 0), 0.2f);
    EXPECT_FLOAT_EQ(ours(0, 1), 0.2f);
    EXPECT_NEAR(pcl(0, 0), 0.18f, 1e-6f);
    EXPECT_NEAR(pcl(0, 1), 0.22f, 1e-6f);
}

TEST(SurfaceTypes, ThresholdsOfSection252) {
    EXPECT_EQ(ClassifySurface(0.15f, 0.2f), SurfaceType::kPlane);
    EXPECT_EQ(ClassifySurface(0.05f, 0.2f), SurfaceType::kCylinder);
    EXPECT_EQ(ClassifySurface(0.01f, 0.1f), SurfaceType::kEdge);
    EXPECT_EQ(ClassifySurface(0.04f, 0.06f), SurfaceType::kSphere);
    EXPECT_EQ(ClassifySurface(0.02f, 0.12f), SurfaceType::kRim);
    EXPECT_EQ(ClassifySurface(NAN, 0.1f), SurfaceType::kUndefined);
    EXPECT_EQ(SurfaceTypeName(SurfaceType::kCylinder), "cylinder");
    EXPECT_THROW(LabelSurfaceTypes(FeatureMatrix(3, 3)), InvalidArgument);
}

double Share(const std::vector<SurfaceType>& types, SurfaceType want,
             const std::vector<bool>& use) {
    std::size_t hit = 0, all = 0;
    for (std::size_t i = 0; i < types.size(); ++i) {
        if (!use[i]) continue;
        ++all;
        hit += types[i] == want ? 1 : 0;
    }
    return all == 0 ? 0.0 : static_cast<double>(hit) / static_cast<double>(all);
}

// Synthetic planes, cylinders, spheres and box edges get the labels the thresholds say.
TEST(SurfaceTypes, LabelsSyntheticShapes) {
    const auto label = [](const PointCloud& c) {
        const KdTree tree(c);
        return LabelSurfaceTypes(ComputeRsd(c, tree, {}));
    };
    const PointCloud plane = test::Plane(0.2f, 1.0f, 0.004f);
    const std::vector<bool> all_plane(plane.size(), true);
    EXPECT_GT(Share(label(plane), SurfaceType::kPlane, all_plane), 0.99);

    const PointCloud cyl = test::Cylinder(0.04f, 0.2f, {0.0f, 0.0f, 1.0f}, 0.004f);
    std::vector<bool> cyl_inner(cyl.size());
    for (std::size_t i = 0; i < cyl.size(); ++i) cyl_inner[i] = std::abs(cyl.points[i].y()) < 0.07f;
    EXPECT_GT(Share(label(cyl), SurfaceType::kCylinder, cyl_inner), 0.9);

    const PointCloud sphere = test::Sphere(0.04f, {0.0f, 0.0f, 1.0f}, 0.003f);
    EXPECT_GT(Share(label(sphere), SurfaceType::kSphere, std::vector<bool>(sphere.size(), true)),
              0.95);

    // A straight sharp edge has r_min near 0 but r_max large (straight along the edge), so the
    // cylinder rule, checked before the edge rule, claims it; where three faces meet (a box
    // corner) r_max is small too and the label is edge/corner.
    const PointCloud edge = test::Edge(0.1f, 1.0f, 0.003f);
    const KdTree edge_tree(edge);
    const FeatureMatrix edge_rsd = ComputeRsd(edge, edge_tree, {});
    std::vector<bool> far_from_edge(edge.size());
    for (std::size_t i = 0; i < edge.size(); ++i) {
        const Eigen::Vector3f& p = edge.points[i];
        const float to_edge = std::max(-p.x(), p.z() - 1.0f);  // distance to the edge line
        const bool inside_y = std::abs(p.y()) < 0.03f;
        if (inside_y && to_edge < 0.004f) {
            EXPECT_LT(edge_rsd(static_cast<Eigen::Index>(i), 0), 0.015f);
        }
        far_from_edge[i] = inside_y && to_edge > 0.025f && to_edge < 0.07f;
    }
    EXPECT_GT(Share(LabelSurfaceTypes(edge_rsd), SurfaceType::kPlane, far_from_edge), 0.9);

    PointCloud corner = test::Edge(0.06f, 1.0f, 0.003f);
    for (int i = 0; i <= 20; ++i) {  // third face y = -0.03 closing the corner
        for (int j = 1; j <= 20; ++j) {
            corner.points.emplace_back(-0.003f * i, -0.03f, 1.0f + 0.003f * j);
            corner.normals.emplace_back(0.0f, 1.0f, 0.0f);
        }
    }
    corner.SetUnorganized();
    // Estimated normals: blended across the faces, as a sensor's are.
    const KdTree corner_tree(corner);
    SetNormals(corner, EstimateNormals(corner, corner_tree, {.radius = 0.01f}));
    std::vector<bool> at_corner(corner.size());
    for (std::size_t i = 0; i < corner.size(); ++i) {
        at_corner[i] = (corner.points[i] - Eigen::Vector3f(0.0f, -0.03f, 1.0f)).norm() < 0.005f;
    }
    EXPECT_GT(Share(label(corner), SurfaceType::kEdge, at_corner), 0.8);
}

// A mug-like scene: a cylinder standing on a plane, with Kinect noise.
PointCloud CylinderOnPlane() {
    PointCloud cyl = test::Cylinder(0.04f, 0.12f, {0.0f, 0.0f, 0.8f}, 0.004f, true);
    PointCloud plane = test::Plane(0.25f, 0.9f, 0.004f);
    for (auto& p : plane.points)
        p = Eigen::Vector3f(p.x(), 0.06f + 0.5f * (p.z() - 0.9f), p.y() + 0.85f);
    for (auto& n : plane.normals) n = Eigen::Vector3f(0.0f, -1.0f, 0.0f);
    for (std::size_t i = 0; i < plane.size(); ++i) {
        cyl.points.push_back(plane.points[i]);
        cyl.normals.push_back(plane.normals[i]);
    }
    cyl.SetUnorganized();
    AddKinectNoise(cyl, 11);
    return cyl;
}

// GRSD- is additive: H(A u B) = H(A) + H(B) + the exact correction of the shared boundary.
TEST(GrsdMinus, AdditiveUpToTheSharedBoundary) {
    const PointCloud scene = CylinderOnPlane();
    const KdTree tree(scene);
    const VoxelRsdResult voxels = ComputeVoxelRsd(scene, tree, {});
    ASSERT_GT(voxels.size(), 20u);
    std::vector<std::uint32_t> a, b, all;
    for (std::uint32_t v = 0; v < voxels.size(); ++v) {
        (voxels.coordinates[v].x() < 0 ? a : b).push_back(v);
        all.push_back(v);
    }
    const FeatureVector ha = GrsdMinusOfVoxels(voxels, a);
    const FeatureVector hb = GrsdMinusOfVoxels(voxels, b);
    const FeatureVector hab = GrsdMinusOfVoxels(voxels, all);
    const FeatureVector corr = GrsdMinusBoundaryCorrection(voxels, a, b);
    EXPECT_GT(corr.cwiseAbs().sum(), 0.0f);  // the halves touch
    for (int k = 0; k < kGrsdSize; ++k) EXPECT_FLOAT_EQ(hab[k], ha[k] + hb[k] + corr[k]) << k;
    // Far-apart parts add exactly.
    std::vector<std::uint32_t> left, right;
    for (std::uint32_t v : a) {
        if (voxels.coordinates[v].x() < -3) left.push_back(v);
    }
    for (std::uint32_t v : b) {
        if (voxels.coordinates[v].x() > 2) right.push_back(v);
    }
    std::vector<std::uint32_t> both = left;
    both.insert(both.end(), right.begin(), right.end());
    EXPECT_EQ(GrsdMinusBoundaryCorrection(voxels, left, right).cwiseAbs().sum(), 0.0f);
    EXPECT_TRUE(GrsdMinusOfVoxels(voxels, both)
                    .isApprox(GrsdMinusOfVoxels(voxels, left) + GrsdMinusOfVoxels(voxels, right)));
    // Every defined voxel contributes 26 counts, the diagonal twice; the empty-empty bin stays 0.
    std::size_t defined = 0;
    for (auto t : voxels.types) defined += t != SurfaceType::kUndefined ? 1 : 0;
    float diagonal = 0.0f;
    for (int t = 0; t < kNumSurfaceTypes; ++t) diagonal += hab[GrsdBin(t, t)];
    EXPECT_FLOAT_EQ(hab.sum() - 0.5f * diagonal, 26.0f * static_cast<float>(defined));
    EXPECT_EQ(hab[GrsdBin(5, 5)], 0.0f);
    EXPECT_EQ(ComputeGrsdMinus(scene), hab);
    EXPECT_THROW(GrsdMinusOfVoxels(voxels, std::vector<std::uint32_t>{0, 0}), InvalidArgument);
    EXPECT_THROW(GrsdMinusBoundaryCorrection(voxels, a, a), InvalidArgument);
}

TEST(GrsdMinus, BinLayout) {
    EXPECT_EQ(GrsdBin(0, 0), 0);
    EXPECT_EQ(GrsdBin(0, 5), 5);
    EXPECT_EQ(GrsdBin(1, 1), 6);
    EXPECT_EQ(GrsdBin(5, 1), 10);
    EXPECT_EQ(GrsdBin(2, 2), 11);
    EXPECT_EQ(GrsdBin(5, 5), 20);
    EXPECT_THROW(GrsdBin(6, 0), InvalidArgument);
}

TEST(Grsd, RayCastFreeSpace) {
    const PointCloud scene = CylinderOnPlane();
    const FeatureVector h = ComputeGrsd(scene);
    ASSERT_EQ(h.size(), kGrsdSize);
    EXPECT_GE(h.minCoeff(), 0.0f);
    // The space between the sensor and the plane in front of the cylinder is seen free.
    EXPECT_GT(h[GrsdBin(5, 5)], 0.0f);
    EXPECT_GT(h[GrsdBin(1, 5)], 0.0f);
    EXPECT_EQ(ComputeGrsd(scene), h);
    PointCloud cluster = scene;
    EXPECT_THROW(ComputeGrsd(cluster, {.viewpoint = Eigen::Vector3f(NAN, 0, 0)}), InvalidArgument);
    cluster.normals.clear();
    EXPECT_THROW(ComputeGrsd(cluster), InvalidArgument);
    EXPECT_EQ(ComputeGrsd(PointCloud{}).size(), kGrsdSize);
}

PointCloud NoisySphereWithNormals(float radius, std::uint32_t seed) {
    PointCloud c = test::Sphere(radius, {0.02f, -0.01f, 0.7f}, 0.005f, true);
    AddKinectNoise(c, seed);
    const KdTree tree(c);
    SetNormals(c, EstimateNormals(c, tree, {.radius = 0.02f}));
    c.colors.resize(c.size());
    for (std::size_t i = 0; i < c.size(); ++i) {
        c.colors[i] = Color{static_cast<std::uint8_t>(40 + i % 200),
                            static_cast<std::uint8_t>(90 + (i * 7) % 150),
                            static_cast<std::uint8_t>(i % 3 == 0 ? 0 : 120), 255};
    }
    return c;
}

TEST(Histograms, SumToTheDocumentedNormalisation) {
    const PointCloud c = NoisySphereWithNormals(0.05f, 2);
    const KdTree tree(c);
    const PairFeatureParams params{.radius = 0.02f};
    const FeatureMatrix pfh = ComputePfh(c, tree, params);
    const FeatureMatrix fpfh = ComputeFpfh(c, tree, params);
    const FeatureMatrix rgb = ComputePfhRgb(c, tree, params);
    ASSERT_EQ(pfh.cols(), kPfhSize);
    ASSERT_EQ(fpfh.cols(), kFpfhSize);
    ASSERT_EQ(rgb.cols(), kPfhRgbSize);
    for (Eigen::Index i = 0; i < pfh.rows(); ++i) {
        EXPECT_NEAR(pfh.row(i).sum(), 100.0f, 0.05f);
        for (int block = 0; block < 3; ++block)
            EXPECT_NEAR(fpfh.row(i).segment(11 * block, 11).sum(), 100.0f, 0.01f);
        EXPECT_NEAR(rgb.row(i).head(125).sum(), 200.0f, 0.1f);
        EXPECT_NEAR(rgb.row(i).tail(125).sum(), 200.0f, 0.1f);
    }
    const FeatureVector vfh = ComputeVfh(c);
    const float n = static_cast<float>(c.size());
    ASSERT_EQ(vfh.size(), kVfhSize);
    for (int block = 0; block < 3; ++block)
        EXPECT_NEAR(vfh.segment(45 * block, 45).sum(), 100.0f * n / (n - 1.0f), 0.05f);
    EXPECT_EQ(vfh.segment(135, 45).sum(), 0.0f);
    EXPECT_NEAR(vfh.tail(128).sum(), 100.0f, 0.01f);
    const FeatureVector sized =
        ComputeVfh(c, {.normalize_distances = true, .size_component = true});
    EXPECT_NEAR(sized.segment(135, 45).sum(), 100.0f * n / (n - 1.0f), 0.05f);
}

// PFH and FPFH depend only on the relative geometry: a rigid motion leaves them unchanged up to
// values that fall on the other side of a bin border through rounding.
TEST(Histograms, RotationInvariant) {
    PointCloud c = NoisySphereWithNormals(0.04f, 5);
    const Eigen::Matrix3f R =
        Eigen::AngleAxisf(0.7f, Eigen::Vector3f(1.0f, 2.0f, -0.5f).normalized()).toRotationMatrix();
    PointCloud moved = c;
    for (auto& p : moved.points) p = R * p + Eigen::Vector3f(0.3f, -0.2f, 0.1f);
    for (auto& n : moved.normals) n = R * n;
    const PairFeatureParams params{.radius = 0.02f};
    const KdTree t1(c), t2(moved);
    for (auto compute : {ComputePfh, ComputeFpfh}) {
        const FeatureMatrix a = compute(c, t1, params);
        const FeatureMatrix b = compute(moved, t2, params);
        const double mean_l1 = (a - b).cwiseAbs().sum() / static_cast<double>(a.rows());
        EXPECT_LT(mean_l1, 0.5);  // of a row sum of 100 (PFH) or 300 (FPFH)
    }
    EXPECT_LT((ComputeVfh(c, {.viewpoint = Eigen::Vector3f::Zero()}) -
               ComputeVfh(moved, {.viewpoint = Eigen::Vector3f(0.3f, -0.2f, 0.1f)}))
                  .cwiseAbs()
                  .sum(),
              2.0f);
}

TEST(Features, BadInput) {
    PointCloud c = test::Plane(0.05f, 1.0f, 0.005f);
    const KdTree tree(c);
    EXPECT_THROW(ComputeRsd(c, tree, {.radius = 0.0f}), InvalidArgument);
    EXPECT_THROW(ComputeRsd(c, tree, {.radius = -0.1f}), InvalidArgument);
    EXPECT_THROW(ComputeRsd(c, tree, {.num_bins = 0}), InvalidArgument);
    EXPECT_THROW(ComputeFpfh(c, tree, {.radius = NAN}), InvalidArgument);
    EXPECT_THROW(ComputePfh(c, tree, {.radius = 0.02f, .num_threads = -1}), InvalidArgument);
    EXPECT_THROW(ComputePfhRgb(c, tree, {}), InvalidArgument);  // no colours
    EXPECT_THROW(ComputeVoxelRsd(c, tree, {.voxel_size = 0.0f}), InvalidArgument);
    PointCloud bare = c;
    bare.normals.clear();
    try {
        ComputeFpfh(bare, tree, {});
        FAIL() << "no error without normals";
    } catch (const InvalidArgument& e) {
        EXPECT_NE(std::string(e.what()).find("normals"), std::string::npos);
    }
    EXPECT_THROW(ComputeRsd(bare, tree, {}), InvalidArgument);
    EXPECT_THROW(ComputeVfh(bare), InvalidArgument);
    EXPECT_THROW(ComputeGrsdMinus(bare), InvalidArgument);
    EXPECT_THROW(ComputePartStatistics(bare), InvalidArgument);
    EXPECT_THROW(ComputeClusterFeature("shot", c), InvalidArgument);
    // NaN points and normals give NaN rows, not crashes.
    c.points[3] = Eigen::Vector3f::Constant(NAN);
    c.normals[5] = Eigen::Vector3f::Constant(NAN);
    const KdTree tree_nan(c);
    const FeatureMatrix fpfh = ComputeFpfh(c, tree_nan, {.radius = 0.02f});
    EXPECT_FALSE(fpfh.row(3).allFinite());
    EXPECT_FALSE(fpfh.row(5).allFinite());
    EXPECT_TRUE(fpfh.row(4).allFinite());
    EXPECT_EQ(CountDefinedRows(fpfh), c.size() - 2);
}

TEST(Features, EmptyInput) {
    const PointCloud empty;
    const KdTree tree(empty);
    EXPECT_EQ(ComputeRsd(empty, tree, {}).rows(), 0);
    EXPECT_EQ(ComputeRsd(empty, tree, {}).cols(), 2);
    EXPECT_EQ(ComputeFpfh(empty, tree, {}).rows(), 0);
    EXPECT_EQ(ComputePfh(empty, tree, {}).rows(), 0);
    EXPECT_EQ(ComputePfhRgb(empty, tree, {}).rows(), 0);
    EXPECT_EQ(ComputeVoxelRsd(empty, tree, {}).size(), 0u);
    EXPECT_EQ(ComputeVfh(empty), FeatureVector::Zero(kVfhSize));
    EXPECT_EQ(ComputeGrsdMinus(empty), FeatureVector::Zero(kGrsdSize));
    EXPECT_EQ(ComputePartStatistics(empty), FeatureVector::Zero(kPartStatsSize));
    for (const auto& f : ClusterFeatures())
        EXPECT_EQ(ComputeClusterFeature(f.name, empty).size(), f.dimension) << f.name;
}

TEST(Features, IndependentOfThreadCount) {
    const PointCloud c = NoisySphereWithNormals(0.06f, 9);
    const KdTree tree(c);
    for (auto compute : {ComputePfh, ComputeFpfh, ComputePfhRgb}) {
        const FeatureMatrix one = compute(c, tree, {.radius = 0.02f, .num_threads = 1});
        const FeatureMatrix four = compute(c, tree, {.radius = 0.02f, .num_threads = 4});
        EXPECT_EQ(one, four);
    }
    EXPECT_EQ(ComputeRsd(c, tree, {.num_threads = 1}), ComputeRsd(c, tree, {.num_threads = 3}));
    VoxelRsdParams p1, p4;
    p1.rsd.num_threads = 1;
    p4.rsd.num_threads = 4;
    EXPECT_EQ(ComputeVoxelRsd(c, tree, p1).radii, ComputeVoxelRsd(c, tree, p4).radii);
    EXPECT_EQ(ComputePartStatistics(c, {.num_threads = 1}),
              ComputePartStatistics(c, {.num_threads = 4}));
}

// A flat 20 x 10 cm horizontal board: extents, ratios and orientation come out as built.
TEST(PartStatistics, RecoversABoard) {
    PointCloud board;
    for (int i = 0; i <= 50; ++i) {
        for (int j = 0; j <= 25; ++j) {
            board.points.emplace_back(-0.1f + 0.004f * i, -0.05f + 0.004f * j, 0.7f);
            board.normals.emplace_back(0.0f, 0.0f, 1.0f);
        }
    }
    board.SetUnorganized();
    const FeatureVector f = ComputePartStatistics(board, {.voxel_size = 0.01f});
    ASSERT_EQ(f.size(), kPartStatsSize);
    EXPECT_NEAR(f[15], 0.2f, 1e-4f);  // longest extent
    EXPECT_NEAR(f[14], 0.1f, 1e-4f);  // width
    EXPECT_NEAR(f[13], 0.0f, 1e-4f);  // thickness
    EXPECT_NEAR(f[12], 1.0f, 1e-4f);  // horizontal: normal along up
    EXPECT_NEAR(f[3], 0.0f, 1e-4f);   // e1 / e2: flat
    EXPECT_NEAR(f[4], 0.25f, 0.02f);  // e2 / e3 = (0.1 / 0.2)^2
    EXPECT_NEAR(f[18], 1.0f, 1e-3f);  // symmetric about the mean
    EXPECT_NEAR(f[11], 0.004f * std::sqrt((51.0f * 51.0f - 1.0f) / 12.0f),
                1e-4f);                         // std of 51 steps
    EXPECT_NEAR(f[2], 21 * 11 * 1e-6f, 3e-6f);  // occupied 1 cm voxels
    EXPECT_NEAR(f[1], 0.0f, 1e-4f);             // flat
    EXPECT_GT(f[0], 0.05f);                     // the rim is boundary
    EXPECT_LT(f[0], 0.2f);
    for (int k = 3; k <= 8; ++k) EXPECT_LE(f[k], 1.0f);
    EXPECT_LE(f[23], 1.0f);
    EXPECT_THROW(ComputePartStatistics(board, {.up = Eigen::Vector3f::Zero()}), InvalidArgument);
}

TEST(Registry, NamesAndDimensions) {
    PointCloud c = NoisySphereWithNormals(0.05f, 4);
    for (const auto& f : ClusterFeatures()) {
        const FeatureVector v = ComputeClusterFeature(f.name, c, {.radius = 0.02f});
        EXPECT_EQ(v.size(), f.dimension) << f.name;
        EXPECT_TRUE(v.allFinite()) << f.name;
        EXPECT_EQ(&FindClusterFeature(f.name), &f);
    }
    EXPECT_EQ(FindClusterFeature("vfh").dimension, 308);
    EXPECT_EQ(FindClusterFeature("grsd-minus").dimension, 21);
}

}  // namespace
}  // namespace multicue

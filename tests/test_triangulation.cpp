// Greedy projection triangulation, incremental and per-label meshing, hole filling and the mesh
// quality measures.

#include <algorithm>
#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include "mesh_test_data.hpp"
#include "multicue/core/exceptions.hpp"
#include "multicue/surface/greedy_triangulation.hpp"
#include "multicue/surface/mesh_quality.hpp"

namespace multicue {
namespace {

using test::SampledCylinder;
using test::SampledPlane;
using test::SampledSphere;

double Area(const TriangleMesh& m) {
    double a = 0.0;
    for (const auto& t : m.triangles) {
        a +=
            0.5 *
            (m.vertices[t[1]] - m.vertices[t[0]]).cross(m.vertices[t[2]] - m.vertices[t[0]]).norm();
    }
    return a;
}

// Every triangle's normal agrees with the outward direction given by `outward`.
template <typename F>
std::size_t FacingWrongWay(const TriangleMesh& m, F outward) {
    std::size_t wrong = 0;
    for (const auto& t : m.triangles) {
        const Eigen::Vector3f n =
            (m.vertices[t[1]] - m.vertices[t[0]]).cross(m.vertices[t[2]] - m.vertices[t[0]]);
        const Eigen::Vector3f c = (m.vertices[t[0]] + m.vertices[t[1]] + m.vertices[t[2]]) / 3.0f;
        wrong += n.dot(outward(c)) <= 0.0f;
    }
    return wrong;
}

TEST(MeshQuality, CountsDefectsOfHandMadeMeshes) {
    TriangleMesh m;
    m.vertices = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0.5f, 0.5f, 1}, {5, 5, 5}};
    m.triangles = {{0, 1, 2}, {0, 2, 3}};  // a consistent quad
    MeshQuality q = EvaluateMesh(m);
    EXPECT_EQ(q.triangles, 2u);
    EXPECT_EQ(q.edges, 5u);
    EXPECT_EQ(q.boundary_edges, 4u);
    EXPECT_EQ(q.boundary_loops, 1u);
    EXPECT_EQ(q.inconsistent_edges, 0u);
    EXPECT_EQ(q.unreferenced_vertices, 2u);
    m.triangles[1] = {0, 3, 2};  // flipped
    EXPECT_EQ(EvaluateMesh(m).inconsistent_edges, 1u);
    m.triangles[1] = {0, 2, 3};
    m.triangles.push_back({0, 2, 4});  // a third triangle on edge 0-2
    EXPECT_EQ(EvaluateMesh(m).non_manifold_edges, 1u);
    m.triangles.push_back({1, 1, 2});
    EXPECT_EQ(EvaluateMesh(m).degenerate_triangles, 1u);
    m.triangles.push_back({0, 1, 9});
    EXPECT_THROW(EvaluateMesh(m), DataError);
}

TEST(MeshQuality, DistanceToSurfaceAndCloud) {
    TriangleMesh m;
    m.vertices = {{0, 0, 0.1f}, {1, 0, 0.1f}, {0, 1, 0.1f}};
    m.triangles = {{0, 1, 2}};
    const MeshDistance d = DistanceToSurface(m, [](const Eigen::Vector3f& p) { return p.z(); });
    EXPECT_EQ(d.samples, 4u);
    EXPECT_NEAR(d.mean, 0.1, 1e-6);
    EXPECT_NEAR(d.max, 0.1, 1e-6);
    PointCloud ref({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1.0f / 3, 1.0f / 3, 0}});
    EXPECT_NEAR(DistanceToCloud(m, ref).max, 0.1, 1e-6);
    EXPECT_THROW(DistanceToCloud(m, PointCloud{}), DataError);
}

struct Shape {
    PointCloud cloud;
    float radius;
};

void ExpectCleanSurface(const TriangulationResult& r, std::size_t points, double min_area,
                        std::size_t max_loops) {
    const MeshQuality q = EvaluateMesh(r.mesh);
    EXPECT_EQ(q.vertices, points);
    EXPECT_EQ(q.non_manifold_edges, 0u);
    EXPECT_EQ(q.inconsistent_edges, 0u);
    EXPECT_EQ(q.degenerate_triangles, 0u);
    EXPECT_LE(q.boundary_loops, max_loops);
    EXPECT_LE(r.unconnected, points / 100);
    EXPECT_GE(Area(r.mesh), min_area);
}

TEST(GreedyTriangulation, SphereIsClosedConsistentAndOutward) {
    const PointCloud sphere = SampledSphere(3000, 0.1f);
    const float spacing = std::sqrt(4.0f * 3.14159f * 0.01f / 3000.0f);
    GreedyTriangulationParams p{.search_radius = 4.0f * spacing, .mu = 2.5f};
    const TriangulationResult r = GreedyProjectionTriangulation(sphere, p);
    const double area = 4.0 * 3.14159 * 0.01;
    ExpectCleanSurface(r, sphere.size(), 0.97 * area, 3);
    EXPECT_LE(Area(r.mesh), 1.0 * area);
    EXPECT_EQ(FacingWrongWay(r.mesh, [](const Eigen::Vector3f& c) { return c; }), 0u);
    const MeshDistance d = DistanceToSurface(
        r.mesh, [](const Eigen::Vector3f& x) { return std::abs(x.norm() - 0.1f); });
    EXPECT_LT(d.max, 0.02 * 0.1);
}

TEST(GreedyTriangulation, SphereWithoutNormalsUsesPcaAndStaysConsistent) {
    PointCloud sphere = SampledSphere(2000, 0.1f);
    sphere.normals.clear();
    sphere.sensor_origin = {0.0f, 0.0f, 0.0f};  // PCA normals face the centre
    const float spacing = std::sqrt(4.0f * 3.14159f * 0.01f / 2000.0f);
    const TriangulationResult r =
        GreedyProjectionTriangulation(sphere, {.search_radius = 4.0f * spacing});
    ExpectCleanSurface(r, sphere.size(), 0.95 * 4.0 * 3.14159 * 0.01, 4);
    // Faces towards the viewpoint (inwards) like the PCA normals.
    EXPECT_EQ(FacingWrongWay(r.mesh, [](const Eigen::Vector3f& c) { return Eigen::Vector3f(-c); }),
              0u);
}

TEST(GreedyTriangulation, JitteredPlaneCoversItsArea) {
    const PointCloud plane = SampledPlane(40, 30, 0.01f);
    const TriangulationResult r = GreedyProjectionTriangulation(plane, {.search_radius = 0.03f});
    ExpectCleanSurface(r, plane.size(), 0.9 * 0.39 * 0.29, 1);
    EXPECT_EQ(
        FacingWrongWay(r.mesh, [](const Eigen::Vector3f&) { return Eigen::Vector3f::UnitZ(); }),
        0u);
}

TEST(GreedyTriangulation, CylinderIsConsistentAndOnTheSurface) {
    const PointCloud cyl = SampledCylinder(60, 30, 0.05f, 0.15f);
    const TriangulationResult r = GreedyProjectionTriangulation(cyl, {.search_radius = 0.02f});
    const double area = 2.0 * 3.14159 * 0.05 * 0.15;
    ExpectCleanSurface(r, cyl.size(), 0.85 * area, 2);
    EXPECT_EQ(
        FacingWrongWay(
            r.mesh, [](const Eigen::Vector3f& c) { return Eigen::Vector3f(c.x(), c.y(), 0.0f); }),
        0u);
    const MeshDistance d = DistanceToSurface(
        r.mesh, [](const Eigen::Vector3f& x) { return std::abs(x.head<2>().norm() - 0.05f); });
    EXPECT_LT(d.max, 0.002);
}

TEST(GreedyTriangulation, PerLabelMeshesDoNotJoinLabels) {
    PointCloud plane = SampledPlane(30, 20, 0.01f);
    plane.labels.resize(plane.size());
    for (std::size_t i = 0; i < plane.size(); ++i)
        plane.labels[i] = plane.points[i].x() < 0.15f ? 4 : 9;
    GreedyTriangulationParams p{.search_radius = 0.03f, .num_threads = 2};
    auto crossing = [&](const TriangulationResult& r) {
        std::size_t n = 0;
        for (const auto& t : r.mesh.triangles) {
            const auto& l = r.mesh.vertex_labels;
            n += l[t[0]] != l[t[1]] || l[t[1]] != l[t[2]];
        }
        return n;
    };
    const TriangulationResult joint = GreedyProjectionTriangulation(plane, p);
    EXPECT_GT(crossing(joint), 0u);
    p.per_label = true;
    const TriangulationResult split = GreedyProjectionTriangulation(plane, p);
    EXPECT_EQ(crossing(split), 0u);
    EXPECT_EQ(EvaluateMesh(split.mesh).boundary_loops, 2u);
    EXPECT_EQ(EvaluateMesh(split.mesh).inconsistent_edges, 0u);
    // Vertices map back to their input points.
    ASSERT_EQ(split.source.size(), plane.size());
    for (std::size_t v = 0; v < split.source.size(); ++v)
        EXPECT_EQ(split.mesh.vertices[v], plane.points[split.source[v]]);
    // Same result with one thread.
    p.num_threads = 1;
    const TriangulationResult serial = GreedyProjectionTriangulation(plane, p);
    EXPECT_EQ(serial.mesh.triangles, split.mesh.triangles);
}

TEST(GreedyTriangulation, IncrementalAppendKeepsOldTrianglesAndMatchesRebuild) {
    const PointCloud plane = SampledPlane(40, 30, 0.01f);
    Indices left, right;
    for (Index i = 0; i < plane.size(); ++i) {
        if (plane.points[i].x() < 0.22f) left.push_back(i);
        if (plane.points[i].x() > 0.16f) right.push_back(i);  // overlaps the left part
    }
    const GreedyTriangulationParams p{.search_radius = 0.03f};
    IncrementalTriangulation inc(p);
    inc.Add(SelectByIndex(plane, left));
    const TriangleMesh before = inc.mesh();
    const auto added = inc.Add(SelectByIndex(plane, right));
    const TriangleMesh& after = inc.mesh();
    EXPECT_GT(added.dropped_overlap, 0u);
    EXPECT_GT(added.new_triangles, 0u);
    ASSERT_GE(after.triangles.size(), before.triangles.size());
    EXPECT_TRUE(
        std::equal(before.triangles.begin(), before.triangles.end(), after.triangles.begin()));
    EXPECT_TRUE(std::equal(before.vertices.begin(), before.vertices.end(), after.vertices.begin()));
    const MeshQuality q = EvaluateMesh(after);
    EXPECT_EQ(q.non_manifold_edges, 0u);
    EXPECT_EQ(q.inconsistent_edges, 0u);
    const TriangulationResult full = GreedyProjectionTriangulation(plane, p);
    const MeshQuality qf = EvaluateMesh(full.mesh);
    EXPECT_LE(q.boundary_loops, qf.boundary_loops + 1);
    EXPECT_GE(Area(after), 0.97 * Area(full.mesh));
    EXPECT_LE(Area(after), 1.01 * Area(full.mesh));

    // Continuing from the mesh as a file would give it (no normals): same outcome.
    TriangleMesh bare = before;
    bare.vertex_normals.clear();
    IncrementalTriangulation from_file(bare, p);
    from_file.Add(SelectByIndex(plane, right));
    EXPECT_EQ(EvaluateMesh(from_file.mesh()).inconsistent_edges, 0u);
    EXPECT_GE(Area(from_file.mesh()), 0.97 * Area(full.mesh));
}

TEST(GreedyTriangulation, IncrementalJoinsDifferentlySampledScansIntoAClosedSphere) {
    // Two scans of a sphere, sampled differently, overlapping in a 4 cm band around the equator.
    const PointCloud s1 = SampledSphere(4000, 0.1f), s2 = SampledSphere(3000, 0.1f);
    Indices lower, upper;
    for (Index i = 0; i < s1.size(); ++i)
        if (s1.points[i].z() < 0.02f) lower.push_back(i);
    for (Index i = 0; i < s2.size(); ++i)
        if (s2.points[i].z() > -0.02f) upper.push_back(i);
    IncrementalTriangulation inc({.search_radius = 0.025f});
    inc.Add(SelectByIndex(s1, lower));
    const std::size_t old_triangles = inc.mesh().triangles.size();
    const auto added = inc.Add(SelectByIndex(s2, upper));
    EXPECT_GT(added.dropped_overlap, 500u);  // the second scan's part of the band
    EXPECT_LT(added.old_vertices_touched, old_triangles);
    const MeshQuality q = EvaluateMesh(inc.mesh());
    EXPECT_EQ(q.non_manifold_edges, 0u);
    EXPECT_EQ(q.inconsistent_edges, 0u);
    EXPECT_LE(q.boundary_loops, 2u);
    EXPECT_NEAR(Area(inc.mesh()), 4.0 * 3.14159 * 0.01, 0.02 * 4.0 * 3.14159 * 0.01);
    EXPECT_EQ(FacingWrongWay(inc.mesh(), [](const Eigen::Vector3f& c) { return c; }), 0u);
}

TEST(GreedyTriangulation, SmallHoleIsFilledFromItsBoundaryLoop) {
    PointCloud plane = SampledPlane(30, 30, 0.01f, 0.1f);
    Indices keep;
    const Eigen::Vector3f centre(0.15f, 0.15f, 0.0f);
    for (Index i = 0; i < plane.size(); ++i)
        if ((plane.points[i] - centre).norm() > 0.025f) keep.push_back(i);
    const PointCloud holed = SelectByIndex(plane, keep);
    GreedyTriangulationParams p{.search_radius = 0.025f, .max_hole_edges = 0};
    TriangulationResult r = GreedyProjectionTriangulation(holed, p);
    ASSERT_EQ(EvaluateMesh(r.mesh).boundary_loops, 2u);
    const std::size_t added = FillSmallHoles(r.mesh, {.max_edges = 30});
    EXPECT_GT(added, 0u);
    const MeshQuality q = EvaluateMesh(r.mesh);
    EXPECT_EQ(q.boundary_loops, 1u);  // the outer rim stays open
    EXPECT_EQ(q.inconsistent_edges, 0u);
    EXPECT_EQ(q.non_manifold_edges, 0u);
    // The same through the parameter.
    p.max_hole_edges = 30;
    EXPECT_EQ(EvaluateMesh(GreedyProjectionTriangulation(holed, p).mesh).boundary_loops, 1u);
}

TEST(GreedyTriangulation, BadParametersAndInput) {
    const PointCloud plane = SampledPlane(5, 5, 0.01f);
    EXPECT_THROW(GreedyProjectionTriangulation(plane, {}), InvalidArgument);
    EXPECT_THROW(GreedyProjectionTriangulation(plane, {.search_radius = -1.0f}), InvalidArgument);
    EXPECT_THROW(GreedyProjectionTriangulation(plane, {.search_radius = 0.03f, .mu = 0.0f}),
                 InvalidArgument);
    EXPECT_THROW(
        GreedyProjectionTriangulation(plane, {.search_radius = 0.03f, .max_angle_deg = 200.0f}),
        InvalidArgument);
    EXPECT_THROW(GreedyProjectionTriangulation(plane, {.search_radius = 0.03f, .per_label = true}),
                 InvalidArgument);
    EXPECT_THROW(IncrementalTriangulation({.search_radius = std::nanf("")}), InvalidArgument);
    EXPECT_THROW(FillSmallHoles(*std::make_unique<TriangleMesh>(), {.max_edges = -1}),
                 InvalidArgument);
    PointCloud broken = plane;
    broken.normals.pop_back();
    EXPECT_THROW(GreedyProjectionTriangulation(broken, {.search_radius = 0.03f}), DataError);
}

TEST(GreedyTriangulation, EmptyAndNonFiniteInput) {
    const TriangulationResult empty = GreedyProjectionTriangulation({}, {.search_radius = 0.03f});
    EXPECT_TRUE(empty.mesh.empty());
    PointCloud plane = SampledPlane(10, 10, 0.01f);
    plane.points[5] = Eigen::Vector3f::Constant(std::numeric_limits<float>::quiet_NaN());
    const TriangulationResult r = GreedyProjectionTriangulation(plane, {.search_radius = 0.03f});
    EXPECT_EQ(r.mesh.vertices.size(), plane.size() - 1);
    EXPECT_GT(r.mesh.triangles.size(), 100u);
    IncrementalTriangulation inc({.search_radius = 0.03f});
    EXPECT_EQ(inc.Add(PointCloud{}).new_vertices, 0u);
    EXPECT_TRUE(inc.mesh().empty());
}

TEST(GreedyTriangulation, Deterministic) {
    const PointCloud sphere = SampledSphere(1500, 0.1f, 0.0005f);
    const GreedyTriangulationParams p{.search_radius = 0.03f, .num_threads = 2};
    const TriangulationResult a = GreedyProjectionTriangulation(sphere, p);
    const TriangulationResult b = GreedyProjectionTriangulation(sphere, p);
    EXPECT_EQ(a.mesh.triangles, b.mesh.triangles);
    EXPECT_EQ(EvaluateMesh(a.mesh).inconsistent_edges, 0u);
    EXPECT_EQ(EvaluateMesh(a.mesh).non_manifold_edges, 0u);
}

}  // namespace
}  // namespace multicue

// multicue's greedy projection triangulation beside PCL 1.13's on the same points and normals:
// comparable meshes (the same area, at least as large smallest angles), and none of PCL's
// orientation flips.

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

#include <gtest/gtest.h>
#include <pcl/point_types.h>
#include <pcl/search/kdtree.h>
#include <pcl/surface/gp3.h>

#include "mesh_test_data.hpp"
#include "multicue/surface/greedy_triangulation.hpp"
#include "multicue/surface/mesh_quality.hpp"

namespace multicue {
namespace {

TriangleMesh PclMesh(const PointCloud& c, float radius) {
    auto cloud = std::make_shared<pcl::PointCloud<pcl::PointNormal>>();
    for (std::size_t i = 0; i < c.size(); ++i) {
        pcl::PointNormal p;
        p.x = c.points[i].x();
        p.y = c.points[i].y();
        p.z = c.points[i].z();
        p.normal_x = c.normals[i].x();
        p.normal_y = c.normals[i].y();
        p.normal_z = c.normals[i].z();
        cloud->push_back(p);
    }
    auto tree = std::make_shared<pcl::search::KdTree<pcl::PointNormal>>();
    tree->setInputCloud(cloud);
    pcl::GreedyProjectionTriangulation<pcl::PointNormal> gp3;
    gp3.setSearchRadius(radius);
    gp3.setMu(2.5);
    gp3.setMaximumNearestNeighbors(100);
    gp3.setMaximumSurfaceAngle(std::numbers::pi / 4);
    gp3.setMinimumAngle(std::numbers::pi / 18);
    gp3.setMaximumAngle(2 * std::numbers::pi / 3);
    gp3.setInputCloud(cloud);
    gp3.setSearchMethod(tree);
    std::vector<pcl::Vertices> polygons;
    gp3.reconstruct(polygons);
    TriangleMesh m;
    m.vertices = c.points;
    for (const auto& p : polygons)
        m.triangles.emplace_back(p.vertices[0], p.vertices[1], p.vertices[2]);
    return m;
}

double Area(const TriangleMesh& m) {
    double a = 0.0;
    for (const auto& t : m.triangles) {
        a +=
            0.5 *
            (m.vertices[t[1]] - m.vertices[t[0]]).cross(m.vertices[t[2]] - m.vertices[t[0]]).norm();
    }
    return a;
}

/// Mean of every triangle's smallest angle [rad].
double MeanSmallestAngle(const TriangleMesh& m) {
    double sum = 0.0;
    for (const auto& t : m.triangles) {
        const Eigen::Vector3f a = m.vertices[t[0]], b = m.vertices[t[1]], c = m.vertices[t[2]];
        auto angle = [](const Eigen::Vector3f& u, const Eigen::Vector3f& v) {
            return std::acos(std::clamp(u.normalized().dot(v.normalized()), -1.0f, 1.0f));
        };
        sum += std::min({angle(b - a, c - a), angle(a - b, c - b), angle(a - c, b - c)});
    }
    return sum / static_cast<double>(m.triangles.size());
}

TEST(PclGp3, SameSurfaceWithoutOrientationFlips) {
    for (const PointCloud& cloud :
         {test::SampledSphere(4000, 0.1f), test::SampledCylinder(80, 30, 0.05f, 0.15f)}) {
        const float radius = cloud.size() == 4000 ? 0.02f : 0.015f;
        const TriangulationResult ours =
            GreedyProjectionTriangulation(cloud, {.search_radius = radius});
        const TriangleMesh theirs = PclMesh(cloud, radius);
        const MeshQuality qo = EvaluateMesh(ours.mesh), qp = EvaluateMesh(theirs);
        EXPECT_EQ(qo.non_manifold_edges, 0u);
        EXPECT_EQ(qo.inconsistent_edges, 0u);
        EXPECT_LE(qo.boundary_loops, qp.boundary_loops);
        EXPECT_NEAR(static_cast<double>(qo.triangles), static_cast<double>(qp.triangles),
                    0.03 * static_cast<double>(qp.triangles));
        // The same surface, triangulated at least as well (local Delaunay fans maximise the
        // smallest angles).
        EXPECT_NEAR(Area(ours.mesh), Area(theirs), 0.02 * Area(theirs));
        EXPECT_GE(MeanSmallestAngle(ours.mesh), MeanSmallestAngle(theirs));
        // PCL orients triangles by discovery order (pcl#4123, #4847, #5259); recorded, not
        // required.
        RecordProperty("pcl_inconsistent_edges", static_cast<int>(qp.inconsistent_edges));
    }
}

}  // namespace
}  // namespace multicue

// PLY interoperability with PCL 1.13: files written by WritePly/WritePlyMesh are read by
// pcl::io::loadPLYFile, and files written by pcl::io::savePLYFile are read by ReadPly/ReadPlyMesh.
//
// PCL quirks seen with 1.13 (the tests pin them down):
// - PCL writes its `rgb` field as `red green blue` (no alpha) and `rgba` as `red green blue
//   alpha`, all uchar; reading `red green blue` without alpha, PCL leaves the alpha byte 0, so an
//   opaque colour we write (no alpha property) comes back in PCL with a == 0.
// - PCL writes normals as `nx ny nz`, adds `element face 0` without properties and an
//   `element camera 1` (viewpoint, focal length, viewport, distortion) after the vertices; both
//   are skipped by ReadPly (the sensor pose is not read from the camera element).
// - PCL maps `confidence`, `intensity`, `label` and `curvature` to fields of the same names.
// - PCL's ascii writers print 8 significant digits for clouds and 5 for meshes, too few for a
//   float to round-trip (9 are needed), so values from PCL ascii files are compared with a
//   relative tolerance; binary files and everything PCL reads from us compare exactly.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <pcl/PolygonMesh.h>
#include <pcl/console/print.h>
#include <pcl/conversions.h>
#include <pcl/io/ply_io.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include "multicue/core/logging.hpp"
#include "multicue/io/ply.hpp"
#include "test_util.hpp"

namespace multicue {
namespace {

using io::PlyEncoding;

/// A cloud with every field PCL's PointXYZRGBNormal, PointXYZI and PointXYZL know, opaque colours.
PointCloud InteropCloud(std::size_t n) {
    PointCloud c = test::RandomCloud(n, 21, 10.0f);
    std::mt19937 rng(22);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    for (std::size_t i = 0; i < n; ++i) {
        c.normals.push_back(Eigen::Vector3f(u(rng), u(rng), u(rng)).normalized());
        c.colors.push_back(Color{static_cast<std::uint8_t>(rng()), static_cast<std::uint8_t>(rng()),
                                 static_cast<std::uint8_t>(rng()), 255});
        c.curvature.push_back(std::abs(u(rng)) / 3.0f);
        c.intensity.push_back(u(rng) * 500.0f);
        c.labels.push_back(static_cast<std::uint32_t>(rng()));
    }
    return c;
}

/// PCL logs warnings about the camera element it cannot map; keep the test output readable.
/// Exact for binary files; within the precision PCL prints for ascii files.
void ExpectClose(float ours, float theirs, bool exact, float relative) {
    if (exact) {
        EXPECT_EQ(ours, theirs);
    } else {
        EXPECT_LE(std::abs(ours - theirs), relative * std::max(std::abs(ours), std::abs(theirs)))
            << ours << " vs " << theirs;
    }
}

void ExpectClose(const Eigen::Vector3f& ours, const Eigen::Vector3f& theirs, bool exact,
                 float relative) {
    for (int k = 0; k < 3; ++k) ExpectClose(ours[k], theirs[k], exact, relative);
}

constexpr float kPclCloudAscii = 1e-7f;  // 8 significant digits
constexpr float kPclMeshAscii = 1e-4f;   // 5 significant digits

class QuietPcl {
  public:
    QuietPcl() : level_(pcl::console::getVerbosityLevel()) {
        pcl::console::setVerbosityLevel(pcl::console::L_ERROR);
    }
    ~QuietPcl() { pcl::console::setVerbosityLevel(level_); }
    QuietPcl(const QuietPcl&) = delete;
    QuietPcl& operator=(const QuietPcl&) = delete;

  private:
    pcl::console::VERBOSITY_LEVEL level_;
};

class PclPly : public ::testing::TestWithParam<bool> {  // parameter: binary
  protected:
    QuietPcl quiet_;
};

INSTANTIATE_TEST_SUITE_P(AsciiAndBinary, PclPly, ::testing::Bool(), [](const auto& param_info) {
    return std::string(param_info.param ? "Binary" : "Ascii");
});

TEST_P(PclPly, PclReadsOurCloud) {
    test::TempDir dir;
    const PointCloud c = InteropCloud(500);
    const auto path = (dir / "ours.ply").string();
    io::WritePly(path, c,
                 {.encoding = GetParam() ? PlyEncoding::kBinaryLittleEndian : PlyEncoding::kAscii});

    pcl::PointCloud<pcl::PointXYZRGBNormal> p;
    ASSERT_EQ(pcl::io::loadPLYFile(path, p), 0);
    ASSERT_EQ(p.size(), c.size());
    for (std::size_t i = 0; i < c.size(); ++i) {
        SCOPED_TRACE(i);
        EXPECT_EQ(p[i].x, c.points[i].x());
        EXPECT_EQ(p[i].y, c.points[i].y());
        EXPECT_EQ(p[i].z, c.points[i].z());
        EXPECT_EQ(p[i].normal_x, c.normals[i].x());
        EXPECT_EQ(p[i].normal_y, c.normals[i].y());
        EXPECT_EQ(p[i].normal_z, c.normals[i].z());
        EXPECT_EQ(p[i].r, c.colors[i].r);
        EXPECT_EQ(p[i].g, c.colors[i].g);
        EXPECT_EQ(p[i].b, c.colors[i].b);
        EXPECT_EQ(p[i].a, 0);  // PCL quirk: no alpha property gives alpha 0, not 255
        EXPECT_EQ(p[i].curvature, c.curvature[i]);
        if (testing::Test::HasFailure()) break;
    }

    pcl::PointCloud<pcl::PointXYZI> pi;
    ASSERT_EQ(pcl::io::loadPLYFile(path, pi), 0);
    pcl::PointCloud<pcl::PointXYZL> pl;
    ASSERT_EQ(pcl::io::loadPLYFile(path, pl), 0);
    ASSERT_EQ(pi.size(), c.size());
    ASSERT_EQ(pl.size(), c.size());
    for (std::size_t i = 0; i < c.size(); ++i) {
        EXPECT_EQ(pi[i].intensity, c.intensity[i]) << i;
        EXPECT_EQ(pl[i].label, c.labels[i]) << i;
    }
}

TEST_P(PclPly, PclReadsOurAlpha) {
    test::TempDir dir;
    PointCloud c = test::RandomCloud(50, 4);
    for (std::size_t i = 0; i < c.size(); ++i) {
        c.colors.push_back(Color{static_cast<std::uint8_t>(i), static_cast<std::uint8_t>(2 * i),
                                 static_cast<std::uint8_t>(3 * i),
                                 static_cast<std::uint8_t>(4 * i)});
    }
    const auto path = (dir / "alpha.ply").string();
    io::WritePly(path, c,
                 {.encoding = GetParam() ? PlyEncoding::kBinaryLittleEndian : PlyEncoding::kAscii});
    pcl::PointCloud<pcl::PointXYZRGBA> p;
    ASSERT_EQ(pcl::io::loadPLYFile(path, p), 0);
    ASSERT_EQ(p.size(), c.size());
    for (std::size_t i = 0; i < c.size(); ++i) {
        EXPECT_EQ(p[i].x, c.points[i].x());
        EXPECT_EQ(p[i].r, c.colors[i].r);
        EXPECT_EQ(p[i].g, c.colors[i].g);
        EXPECT_EQ(p[i].b, c.colors[i].b);
        EXPECT_EQ(p[i].a, c.colors[i].a);
    }
}

TEST_P(PclPly, WeReadPclCloud) {
    test::TempDir dir;
    const PointCloud c = InteropCloud(500);
    pcl::PointCloud<pcl::PointXYZRGBNormal> p;
    for (std::size_t i = 0; i < c.size(); ++i) {
        pcl::PointXYZRGBNormal q;
        q.x = c.points[i].x();
        q.y = c.points[i].y();
        q.z = c.points[i].z();
        q.normal_x = c.normals[i].x();
        q.normal_y = c.normals[i].y();
        q.normal_z = c.normals[i].z();
        q.r = c.colors[i].r;
        q.g = c.colors[i].g;
        q.b = c.colors[i].b;
        q.a = 255;
        q.curvature = c.curvature[i];
        p.push_back(q);
    }
    const auto path = (dir / "pcl.ply").string();
    ASSERT_EQ(pcl::io::savePLYFile(path, p, GetParam()), 0);

    const PointCloud r = io::ReadPly(path);
    ASSERT_EQ(r.size(), c.size());
    ASSERT_TRUE(r.HasNormals());
    ASSERT_TRUE(r.HasColors());
    ASSERT_TRUE(r.HasCurvature());
    EXPECT_TRUE(r.extra_fields.empty());
    for (std::size_t i = 0; i < c.size(); ++i) {
        SCOPED_TRACE(i);
        ExpectClose(r.points[i], c.points[i], GetParam(), kPclCloudAscii);
        ExpectClose(r.normals[i], c.normals[i], GetParam(), kPclCloudAscii);
        EXPECT_EQ(r.colors[i], c.colors[i]);  // no alpha in the file: opaque
        ExpectClose(r.curvature[i], c.curvature[i], GetParam(), kPclCloudAscii);
        if (testing::Test::HasFailure()) break;
    }

    // Intensity, label and rgba (with alpha) from PCL's other point types.
    pcl::PointCloud<pcl::PointXYZI> pi;
    pcl::PointCloud<pcl::PointXYZL> pl;
    pcl::PointCloud<pcl::PointXYZRGBA> pa;
    for (std::size_t i = 0; i < c.size(); ++i) {
        pcl::PointXYZI qi;
        qi.x = c.points[i].x();
        qi.y = c.points[i].y();
        qi.z = c.points[i].z();
        qi.intensity = c.intensity[i];
        pi.push_back(qi);
        pcl::PointXYZL ql;
        ql.x = qi.x;
        ql.y = qi.y;
        ql.z = qi.z;
        ql.label = c.labels[i];
        pl.push_back(ql);
        pcl::PointXYZRGBA qa;
        qa.x = qi.x;
        qa.y = qi.y;
        qa.z = qi.z;
        qa.r = c.colors[i].r;
        qa.g = c.colors[i].g;
        qa.b = c.colors[i].b;
        qa.a = static_cast<std::uint8_t>(i);
        pa.push_back(qa);
    }
    ASSERT_EQ(pcl::io::savePLYFile((dir / "i.ply").string(), pi, GetParam()), 0);
    ASSERT_EQ(pcl::io::savePLYFile((dir / "l.ply").string(), pl, GetParam()), 0);
    ASSERT_EQ(pcl::io::savePLYFile((dir / "a.ply").string(), pa, GetParam()), 0);
    const PointCloud ri = io::ReadPly(dir / "i.ply");
    const PointCloud rl = io::ReadPly(dir / "l.ply");
    const PointCloud ra = io::ReadPly(dir / "a.ply");
    ASSERT_EQ(ri.intensity.size(), c.size());
    EXPECT_EQ(rl.labels, c.labels);
    ASSERT_EQ(ra.colors.size(), c.size());
    for (std::size_t i = 0; i < c.size(); ++i) {
        ExpectClose(ri.intensity[i], c.intensity[i], GetParam(), kPclCloudAscii);
        ExpectClose(ra.points[i], c.points[i], GetParam(), kPclCloudAscii);
        EXPECT_EQ(ra.colors[i], (Color{c.colors[i].r, c.colors[i].g, c.colors[i].b,
                                       static_cast<std::uint8_t>(i)}));
    }
}

TEST_P(PclPly, WeReadPclMesh) {
    test::TempDir dir;
    pcl::PointCloud<pcl::PointXYZ> v;
    const PointCloud c = test::RandomCloud(30, 9);
    for (const auto& p : c.points) v.push_back(pcl::PointXYZ(p.x(), p.y(), p.z()));
    pcl::PolygonMesh mesh;
    pcl::toPCLPointCloud2(v, mesh.cloud);
    for (int i = 0; i + 2 < 30; i += 2) {
        pcl::Vertices tri;
        tri.vertices = {i, i + 1, i + 2};
        mesh.polygons.push_back(tri);
    }
    pcl::Vertices quad;
    quad.vertices = {0, 5, 10, 15};
    mesh.polygons.push_back(quad);
    const auto path = (dir / "pcl_mesh.ply").string();
    if (GetParam()) {
        ASSERT_EQ(pcl::io::savePLYFileBinary(path, mesh), 0);
    } else {
        ASSERT_EQ(pcl::io::savePLYFile(path, mesh), 0);
    }

    const TriangleMesh m = io::ReadPlyMesh(path);
    ASSERT_EQ(m.vertices.size(), c.size());
    for (std::size_t i = 0; i < c.size(); ++i) {
        ExpectClose(m.vertices[i], c.points[i], GetParam(), kPclMeshAscii);
    }
    ASSERT_EQ(m.triangles.size(), mesh.polygons.size() + 1);
    for (std::size_t t = 0; t + 1 < mesh.polygons.size(); ++t) {
        const auto& pv = mesh.polygons[t].vertices;
        EXPECT_EQ(m.triangles[t],
                  Triangle(static_cast<std::uint32_t>(pv[0]), static_cast<std::uint32_t>(pv[1]),
                           static_cast<std::uint32_t>(pv[2])));
    }
    EXPECT_EQ(m.triangles[m.triangles.size() - 2], Triangle(0, 5, 10));
    EXPECT_EQ(m.triangles.back(), Triangle(0, 10, 15));
}

TEST_P(PclPly, PclReadsOurMesh) {
    test::TempDir dir;
    TriangleMesh m;
    m.vertices = test::RandomCloud(20, 12).points;
    for (std::uint32_t i = 0; i + 2 < 20; ++i) m.triangles.emplace_back(i, i + 2, i + 1);
    const auto path = (dir / "ours_mesh.ply").string();
    io::WritePlyMesh(
        path, m, {.encoding = GetParam() ? PlyEncoding::kBinaryLittleEndian : PlyEncoding::kAscii});
    pcl::PolygonMesh mesh;
    ASSERT_EQ(pcl::io::loadPLYFile(path, mesh), 0);
    pcl::PointCloud<pcl::PointXYZ> v;
    pcl::fromPCLPointCloud2(mesh.cloud, v);
    ASSERT_EQ(v.size(), m.vertices.size());
    for (std::size_t i = 0; i < v.size(); ++i) {
        EXPECT_EQ(v[i].x, m.vertices[i].x());
        EXPECT_EQ(v[i].y, m.vertices[i].y());
        EXPECT_EQ(v[i].z, m.vertices[i].z());
    }
    ASSERT_EQ(mesh.polygons.size(), m.triangles.size());
    for (std::size_t t = 0; t < m.triangles.size(); ++t) {
        const auto& pv = mesh.polygons[t].vertices;
        ASSERT_EQ(pv.size(), 3u);
        EXPECT_EQ(Triangle(static_cast<std::uint32_t>(pv[0]), static_cast<std::uint32_t>(pv[1]),
                           static_cast<std::uint32_t>(pv[2])),
                  m.triangles[t]);
    }
}

}  // namespace
}  // namespace multicue

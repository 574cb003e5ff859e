// End-to-end tests of `multicue mesh`: outputs, quality summary, append, per-label, errors.

#include <array>
#include <cstdio>
#include <fstream>
#include <string>

#include <gtest/gtest.h>
#include <sys/wait.h>

#include "cli_runner.hpp"
#include "mesh_test_data.hpp"
#include "multicue/io/pcd.hpp"
#include "multicue/io/ply.hpp"
#include "test_util.hpp"

namespace multicue {
namespace {

using test::RunCli;

using test::ReadTextFile;

TEST(CliMesh, TriangulatesSmoothsAppendsAndSplitsByLabel) {
    test::TempDir dir;
    PointCloud plane = test::SampledPlane(30, 20, 0.01f);
    plane.labels.resize(plane.size());
    for (std::size_t i = 0; i < plane.size(); ++i) plane.labels[i] = plane.points[i].x() < 0.15f;
    io::WritePcd(dir / "plane.pcd", plane);
    const auto in = (dir / "plane.pcd").string(), out = (dir / "mesh.ply").string();

    auto r = RunCli("mesh " + in + " --out " + out);
    ASSERT_EQ(r.code, 0) << r.output;
    EXPECT_NE(r.output.find("0 non-manifold edges, 0 inconsistently oriented edges"),
              std::string::npos)
        << r.output;
    const TriangleMesh mesh = io::ReadPlyMesh(out);
    EXPECT_EQ(mesh.vertices.size(), plane.size());
    EXPECT_GT(mesh.triangles.size(), 900u);

    r = RunCli("mesh " + in + " --out " + out + " --smooth --plain --radius 0.03");
    EXPECT_EQ(r.code, 0) << r.output;
    EXPECT_NE(r.output.find("plain MLS"), std::string::npos) << r.output;

    r = RunCli("mesh " + in + " --out " + (dir / "split.ply").string() + " --per-label");
    ASSERT_EQ(r.code, 0) << r.output;
    const TriangleMesh split = io::ReadPlyMesh(dir / "split.ply");
    for (const auto& t : split.triangles) {
        EXPECT_EQ(split.vertex_labels[t[0]], split.vertex_labels[t[1]]);
        EXPECT_EQ(split.vertex_labels[t[1]], split.vertex_labels[t[2]]);
    }

    // A second scan appended to the mesh file, in place.
    PointCloud second = test::SampledPlane(20, 20, 0.01f, 0.2f, 9);
    for (auto& p : second.points) p.x() += 0.25f;
    io::WritePcd(dir / "second.pcd", second);
    r = RunCli("mesh " + (dir / "second.pcd").string() + " --append " + out + " --out " + out +
               " --radius 0.03");
    ASSERT_EQ(r.code, 0) << r.output;
    EXPECT_NE(r.output.find("appended"), std::string::npos) << r.output;
    const TriangleMesh grown = io::ReadPlyMesh(out);
    EXPECT_GT(grown.triangles.size(), mesh.triangles.size());
    EXPECT_NE(r.output.find("0 inconsistently oriented edges"), std::string::npos) << r.output;
}

TEST(CliMesh, BadInputGivesOneLineErrorAndKeepsOutput) {
    test::TempDir dir;
    const auto out = dir / "mesh.ply";
    io::WritePcd(dir / "plane.pcd", test::SampledPlane(10, 10, 0.01f));
    const auto in = (dir / "plane.pcd").string();
    ASSERT_EQ(RunCli("mesh " + in + " --out " + out.string()).code, 0);
    const std::string before = ReadTextFile(out);
    std::ofstream(dir / "garbage.pcd") << "hello\n";
    io::WritePcd(dir / "empty.pcd", PointCloud{});
    struct Case {
        std::string args;
        int code;
    };
    const std::vector<Case> cases = {
        {(dir / "missing.pcd").string(), 1},
        {(dir / "garbage.pcd").string(), 1},
        {(dir / "empty.pcd").string(), 1},
        {in + " --radius -1", 2},
        {in + " --mu 0", 2},
        {in + " --max-angle 400", 2},
        {in + " --robust --plain --smooth", 2},
        {in + " --per-label", 1},
        {in + " --append " + (dir / "missing.ply").string(), 1},
    };
    for (const auto& c : cases) {
        const auto r = RunCli("mesh " + c.args + " --out " + out.string());
        EXPECT_EQ(r.code, c.code) << c.args << "\n" << r.output;
        EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
        EXPECT_EQ(r.output.rfind("multicue: error:", 0), 0u) << r.output;
    }
    EXPECT_EQ(RunCli("mesh " + in + " --out " + (dir / "x.obj").string()).code, 2);
    EXPECT_EQ(ReadTextFile(out), before);
}

}  // namespace
}  // namespace multicue

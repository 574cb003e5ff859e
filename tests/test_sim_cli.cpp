// `multicue simulate` end to end: files, manifest, determinism, exit codes.

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include <gtest/gtest.h>
#include <sys/wait.h>

#include "cli_runner.hpp"
#include "multicue/io/pcd.hpp"
#include "test_util.hpp"

namespace multicue {
namespace {

using test::RunCli;

std::string ReadBytes(const std::filesystem::path& p) {
    std::ifstream in(p, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
}

TEST(Cli, SimulateWritesIdenticalFilesForASeed) {
    test::TempDir dir;
    const std::string base = "simulate scenes --scenes 2 --views 2 --objects 2,4 --seed 9 -q";
    ASSERT_EQ(RunCli("-j 1 " + base + " --out " + (dir / "a").string()).code, 0);
    const auto r = RunCli("-j 2 " + base + " --out " + (dir / "b").string());
    ASSERT_EQ(r.code, 0) << r.output;
    for (const char* f : {"scene_0000_view_00.pcd", "scene_0001_view_01.pcd", "manifest.json"}) {
        ASSERT_TRUE(std::filesystem::exists(dir / "a" / f)) << f;
        EXPECT_EQ(ReadBytes(dir / "a" / f), ReadBytes(dir / "b" / f)) << f;
    }
    const PointCloud c = io::ReadPcd(dir / "a" / "scene_0000_view_00.pcd");
    EXPECT_TRUE(c.IsOrganized());
    EXPECT_TRUE(c.HasLabels());
    EXPECT_NE(c.FindExtraField("category"), nullptr);
    EXPECT_NE(c.FindExtraField("part"), nullptr);
    const std::string manifest = ReadBytes(dir / "a" / "manifest.json");
    EXPECT_NE(manifest.find("\"complete\": true"), std::string::npos);
    EXPECT_NE(manifest.find("\"fx\": 525.0"), std::string::npos);
}

TEST(Cli, SimulateObjectsLaserAndTof) {
    test::TempDir dir;
    auto r = RunCli("simulate objects --count 2 --views 3 --sensor tof -q --out " +
                    (dir / "o").string());
    ASSERT_EQ(r.code, 0) << r.output;
    EXPECT_TRUE(std::filesystem::exists(dir / "o" / "object_0001_view_02.pcd"));
    const PointCloud t = io::ReadPcd(dir / "o" / "object_0000_view_00.pcd");
    EXPECT_TRUE(t.HasIntensity());
    EXPECT_TRUE(t.HasConfidence());
    r = RunCli("simulate scenes --scenes 1 --sensor laser -q --out " + (dir / "l").string());
    ASSERT_EQ(r.code, 0) << r.output;
    EXPECT_TRUE(std::filesystem::exists(dir / "l" / "scene_0000_view_00.pcd"));
}

TEST(Cli, SimulateRefusesBadArguments) {
    test::TempDir dir;
    const std::string out = " --out " + (dir / "x").string();
    EXPECT_EQ(RunCli("simulate teapots" + out).code, 2);
    EXPECT_EQ(RunCli("simulate scenes --sensor sonar" + out).code, 2);
    EXPECT_EQ(RunCli("simulate scenes --objects 5,2" + out).code, 2);
    EXPECT_EQ(RunCli("simulate scenes --clutter 3" + out).code, 2);
    EXPECT_EQ(RunCli("simulate scenes --meshes " + (dir / "none").string() + out).code, 1);
    {
        std::filesystem::create_directories(dir / "lib");
        std::ofstream(dir / "lib" / "labels.csv") << "file,category\nmissing.obj,box\n";
    }
    const auto r = RunCli("simulate scenes --meshes " + (dir / "lib").string() + out);
    EXPECT_EQ(r.code, 1);
    EXPECT_NE(r.output.find("labels.csv:2"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace multicue

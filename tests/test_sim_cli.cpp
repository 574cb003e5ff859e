// `multicue simulate` end to end: files, manifest, determinism, exit codes.

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <set>
#include <string>

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <nlohmann/json.hpp>

#include "cli_runner.hpp"
#include "multicue/io/pcd.hpp"
#include "multicue/sim/mesh_split.hpp"
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

TEST(Cli, SimulateSceneModes) {
    test::TempDir dir;
    auto r = RunCli("simulate scenes --mode complex --scenes 2 --seed 3 -q --out " +
                    (dir / "c").string());
    ASSERT_EQ(r.code, 0) << r.output;
    const auto manifest = nlohmann::json::parse(ReadBytes(dir / "c" / "manifest.json"));
    ASSERT_EQ(manifest["scenes"].size(), 2u);
    std::set<std::string> placements;
    for (const auto& scene : manifest["scenes"]) {
        EXPECT_EQ(scene["scene_mode"], "complex");
        int objects = 0;
        for (const auto& o : scene["objects"]) {
            if (o["label"].get<int>() < 20) continue;
            ++objects;
            placements.insert(o["placement"].get<std::string>());
            EXPECT_GE(o["support"].get<int>(), 1);
        }
        EXPECT_GE(objects, 10);
        EXPECT_LE(objects, 20);
    }
    EXPECT_TRUE(placements.count("stacked")) << manifest.dump();
    // --objects overrides the mode's range.
    r = RunCli("simulate scenes --mode stacked --objects 2,2 --scenes 1 -q --out " +
               (dir / "s").string());
    ASSERT_EQ(r.code, 0) << r.output;
    const auto stacked = nlohmann::json::parse(ReadBytes(dir / "s" / "manifest.json"));
    int objects = 0;
    for (const auto& o : stacked["scenes"][0]["objects"]) objects += o["label"] >= 20 ? 1 : 0;
    EXPECT_EQ(objects, 2);
    // --mode default is the default: the same bytes.
    const std::string base = "simulate scenes --scenes 1 --objects 2,4 --seed 4 -q --out ";
    ASSERT_EQ(RunCli(base + (dir / "d1").string()).code, 0);
    ASSERT_EQ(RunCli(base + (dir / "d2").string() + " --mode default").code, 0);
    EXPECT_EQ(ReadBytes(dir / "d1" / "scene_0000_view_00.pcd"),
              ReadBytes(dir / "d2" / "scene_0000_view_00.pcd"));
}

TEST(Cli, SimulateRefusesBadModesAndSplitsBeforeWorking) {
    test::TempDir dir;
    const auto r = RunCli("simulate scenes --mode jumbled --out " + (dir / "x").string());
    EXPECT_EQ(r.code, 2);
    EXPECT_NE(r.output.find("--mode"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("jumbled"), std::string::npos) << r.output;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
    EXPECT_FALSE(std::filesystem::exists(dir / "x"));
    EXPECT_EQ(RunCli("simulate objects --mode complex --out " + (dir / "x").string()).code, 2);
    EXPECT_EQ(RunCli("simulate scenes --mesh-split tune --out " + (dir / "x").string()).code, 2);
    EXPECT_EQ(RunCli("simulate scenes --mesh-split half --meshes " + dir.path().string() +
                     " --out " + (dir / "x").string())
                  .code,
              2);
    EXPECT_FALSE(std::filesystem::exists(dir / "x"));
}

TEST(Cli, SimulateMeshSplitUsesOneHalf) {
    test::TempDir dir;
    std::filesystem::create_directories(dir / "lib");
    std::string labels = "file,category,scale_to_m\n";
    for (int i = 0; i < 6; ++i) {
        const std::string name = "cube" + std::to_string(i) + ".obj";
        std::ofstream(dir / "lib" / name)
            << "v 0 0 0\nv 0.1 0 0\nv 0.1 0.1 0\nv 0 0.1 0\nv 0 0 0.08\nv 0.1 0 0.08\n"
               "v 0.1 0.1 0.08\nv 0 0.1 0.08\nf 1 3 2\nf 1 4 3\nf 5 6 7\nf 5 7 8\n"
               "f 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n";
        labels += name + ",box,1\n";
    }
    std::ofstream(dir / "lib" / "labels.csv") << labels;
    const auto r =
        RunCli("simulate scenes --meshes " + (dir / "lib").string() +
               " --mesh-split test --scenes 3 --views 1 -q --out " + (dir / "o").string());
    ASSERT_EQ(r.code, 0) << r.output;
    std::vector<sim::MeshEntry> lib;
    for (int i = 0; i < 6; ++i) {
        sim::MeshEntry e;
        e.file = "cube" + std::to_string(i) + ".obj";
        e.category = "box";
        lib.push_back(e);
    }
    std::set<std::string> test_half;
    for (const auto& e : sim::SelectMeshSplit(lib, sim::MeshSplit::kTest)) {
        test_half.insert(e.file.string());
    }
    ASSERT_EQ(test_half.size(), 3u);
    const auto manifest = nlohmann::json::parse(ReadBytes(dir / "o" / "manifest.json"));
    EXPECT_EQ(manifest["mesh_split"], "test");
    int objects = 0;
    for (const auto& scene : manifest["scenes"]) {
        for (const auto& o : scene["objects"]) {
            if (o["label"].get<int>() < 20) continue;
            ++objects;
            EXPECT_TRUE(test_half.count(o["source"].get<std::string>())) << o["source"];
        }
    }
    EXPECT_GT(objects, 0);
}

}  // namespace
}  // namespace multicue

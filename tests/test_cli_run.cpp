// `multicue run` and `multicue db` end to end: a task file over frames, the database it fills.

#include <fstream>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "cli_runner.hpp"
#include "multicue/io/pcd.hpp"
#include "multicue/sim/tabletop_scene.hpp"
#include "test_util.hpp"

namespace multicue {
namespace {

std::string PoseList(const Eigen::Isometry3f& T) {
    std::string s = "[";
    for (int r = 0; r < 4; ++r) {
        for (int c = 0; c < 4; ++c)
            s += std::to_string(T.matrix()(r, c)) + (r * 4 + c < 15 ? ", " : "]");
    }
    return s;
}

TEST(CliRun, EnumeratesFramesLearnsObjectsAndListsThem) {
    test::TempDir dir;
    const auto scene = sim::MakeDemoScene();
    std::string frames;
    for (int i = 0; i < 2; ++i) {
        sim::ScanParams scan;
        scan.T_world_camera =
            Eigen::Isometry3f(Eigen::AngleAxisf(0.3f * i, Eigen::Vector3f::UnitZ())) *
            sim::DefaultCameraPose(scene);
        scan.seed = static_cast<std::uint32_t>(i + 1);
        const std::string name = fmt::format("f{}.pcd", i);
        io::WritePcd(dir / name, sim::ScanTableTopScene(scene, scan));
        frames += fmt::format("  - {{file: {}, time: {}, pose: {}}}\n", name, i,
                              PoseList(scan.T_world_camera));
    }
    std::ofstream(dir / "task.yaml") << "task: enumerate\ndatabase: objects.db\noutput: run.json\n"
                                     << "frames:\n"
                                     << frames;
    const auto r = test::RunCli("run " + (dir / "task.yaml").string());
    ASSERT_EQ(r.code, 0) << r.output;
    const auto result = nlohmann::json::parse(test::ReadTextFile((dir / "run.json").string()));
    ASSERT_EQ(result["frames"].size(), 2u);
    EXPECT_EQ(result["frames"][0]["learnt_objects"], 5);
    EXPECT_EQ(result["frames"][1]["learnt_objects"], 0);
    for (const auto& h : result["frames"][1]["hypotheses"]) EXPECT_FALSE(h["novel"].get<bool>());

    const auto list = test::RunCli("db list --json " + (dir / "objects.db").string());
    ASSERT_EQ(list.code, 0) << list.output;
    EXPECT_EQ(nlohmann::json::parse(list.output).size(), 5u);
    const auto show = test::RunCli("db show " + (dir / "objects.db").string() + " 1");
    EXPECT_EQ(show.code, 0) << show.output;
    EXPECT_NE(show.output.find("view 1"), std::string::npos) << show.output;

    // Export, import into a fresh database: the same objects.
    ASSERT_EQ(test::RunCli("db export " + (dir / "objects.db").string() + " --out " +
                           (dir / "export.json").string())
                  .code,
              0);
    const auto imported = test::RunCli("db import " + (dir / "copy.db").string() + " " +
                                       (dir / "export.json").string());
    EXPECT_EQ(imported.code, 0) << imported.output;
    EXPECT_NE(imported.output.find("imported 5 objects"), std::string::npos) << imported.output;
}

TEST(CliRun, ReadsFramesAndPosesFromASimulatorManifest) {
    test::TempDir dir;
    const auto sim = test::RunCli("simulate scenes --out " + (dir / "sim").string() +
                                  " --scenes 1 --views 2 --objects 3,3 --seed 5 -q");
    ASSERT_EQ(sim.code, 0) << sim.output;
    std::ofstream(dir / "task.yaml") << "task: enumerate\noutput: run.json\n"
                                     << "frames: {manifest: sim/manifest.json, scenes: [0]}\n";
    const auto r = test::RunCli("run " + (dir / "task.yaml").string());
    ASSERT_EQ(r.code, 0) << r.output;
    const auto result = nlohmann::json::parse(test::ReadTextFile((dir / "run.json").string()));
    ASSERT_EQ(result["frames"].size(), 2u);
    EXPECT_EQ(result["frames"][0]["frame"], "scene_0000_view_00.pcd");
    EXPECT_GE(result["frames"][0]["hypotheses"].size(), 2u);

    std::ofstream(dir / "none.yaml") << "frames: {manifest: sim/manifest.json, scenes: [7]}\n";
    EXPECT_EQ(test::RunCli("run " + (dir / "none.yaml").string()).code, 2);
}

TEST(CliRun, BadTaskFilesGiveOneLineErrors) {
    test::TempDir dir;
    std::ofstream(dir / "unknown.yaml") << "task: enumerate\nframes: [a.pcd]\ncolour: blue\n";
    auto r = test::RunCli("run " + (dir / "unknown.yaml").string());
    EXPECT_EQ(r.code, 2) << r.output;
    EXPECT_NE(r.output.find("unknown key 'colour'"), std::string::npos) << r.output;

    std::ofstream(dir / "kind.yaml") << "task: dance\nframes: [a.pcd]\n";
    r = test::RunCli("run " + (dir / "kind.yaml").string());
    EXPECT_EQ(r.code, 2) << r.output;

    std::ofstream(dir / "missing.yaml") << "task: enumerate\nframes: [nothere.pcd]\n";
    r = test::RunCli("run " + (dir / "missing.yaml").string());
    EXPECT_EQ(r.code, 1) << r.output;
    EXPECT_NE(r.output.find("nothere.pcd"), std::string::npos) << r.output;

    std::ofstream(dir / "broken.yaml") << "task: [enumerate\n";
    r = test::RunCli("run " + (dir / "broken.yaml").string());
    EXPECT_EQ(r.code, 1) << r.output;
    EXPECT_NE(r.output.find("malformed YAML"), std::string::npos) << r.output;

    r = test::RunCli("db list " + (dir / "none.db").string());
    EXPECT_EQ(r.code, 1) << r.output;
    r = test::RunCli("db show " + (dir / "unknown.yaml").string() + " 1");  // not a database
    EXPECT_EQ(r.code, 1) << r.output;
}

}  // namespace
}  // namespace multicue

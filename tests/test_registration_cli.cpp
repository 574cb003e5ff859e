// `multicue register`, `multicue map` and `multicue perceive --manifest --register`: outputs,
// exit codes and one-line errors.

#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "cli_runner.hpp"
#include "multicue/io/pcd.hpp"
#include "multicue/search/occupancy_map.hpp"
#include "multicue/sim/scene_gen.hpp"
#include "multicue/sim/sensors.hpp"
#include "reduced_kinect.hpp"
#include "registration_scenes.hpp"
#include "test_util.hpp"

namespace multicue {
namespace {

using test::CliResult;
using test::ReadTextFile;
using test::RunCli;
using test::TempDir;

using namespace std::string_literals;

std::string Q(const std::filesystem::path& p) { return "\""s + p.string() + "\""; }

nlohmann::json ReadJson(const std::filesystem::path& p) {
    return nlohmann::json::parse(ReadTextFile(p));
}

// Two noisy samples of the table scene, the second moved by a known transform.
struct Files {
    TempDir dir;
    std::filesystem::path source, target;
    Eigen::Isometry3d T = test::MakeTransform(4.0, {0.03, -0.02, 0.02});
    Files() {
        source = dir / "source.pcd";
        target = dir / "target.pcd";
        io::WritePcd(source, test::TableWithBoxes(0.001f, 1, 2500.0f));
        io::WritePcd(target, test::Transformed(test::TableWithBoxes(0.001f, 2, 2500.0f), T));
    }
};

TEST(RegisterCli, RecoversTheTransformAndWritesJson) {
    Files f;
    const auto out = f.dir / "T.json";
    const auto aligned = f.dir / "aligned.pcd";
    const CliResult r = RunCli("-j 1 register "s + Q(f.source) + " "s + Q(f.target) +
                               " --method plane --init 1,0,0,0,0,1,0,0,0,0,1,0 --resolution 0.01"
                               " --out "s +
                               Q(out) + " --aligned "s + Q(aligned));
    ASSERT_EQ(r.code, 0) << r.output;
    const auto j = ReadJson(out);
    EXPECT_EQ(j["format"], "multicue.registration/1");
    EXPECT_TRUE(j["converged"].get<bool>());
    EXPECT_EQ(j["status"], "converged");
    Eigen::Matrix4d M;
    for (int a = 0; a < 4; ++a)
        for (int b = 0; b < 4; ++b) M(a, b) = j["T_target_source"][a][b].get<double>();
    Eigen::Isometry3d T(M);
    EXPECT_LT(test::RotationErrorDeg(T, f.T), 0.3);
    EXPECT_LT(test::TranslationError(T, f.T), 0.003);
    EXPECT_EQ(j["information"].size(), 6u);
    EXPECT_TRUE(std::filesystem::exists(aligned));
    // The JSON of one run is an initial guess for the next.
    const CliResult again = RunCli("-j 1 register "s + Q(f.source) + " "s + Q(f.target) +
                                   " --method point-to-plane --init "s + Q(out) +
                                   " --resolution 0.01 --out "s + Q(f.dir / "T2.json") + " -q");
    EXPECT_EQ(again.code, 0) << again.output;
    EXPECT_TRUE(again.output.empty()) << again.output;
}

TEST(RegisterCli, GlobalWithoutAGuess) {
    Files f;
    const auto out = f.dir / "T.json";
    const CliResult r = RunCli("-j 1 register "s + Q(f.source) + " "s + Q(f.target) +
                               " --resolution 0.01 --out "s + Q(out));
    ASSERT_EQ(r.code, 0) << r.output;
    EXPECT_NE(r.output.find("planes:"), std::string::npos) << r.output;
    EXPECT_TRUE(ReadJson(out)["converged"].get<bool>());
}

TEST(RegisterCli, DegenerateInputIsAOneLineErrorWithTheJsonWritten) {
    TempDir dir;
    io::WritePcd(dir / "a.pcd", test::SinglePlane(0.002f, 1));
    io::WritePcd(dir / "b.pcd", test::SinglePlane(0.002f, 2));
    const CliResult r = RunCli("register "s + Q(dir / "a.pcd") + " "s + Q(dir / "b.pcd") +
                               " --method point-to-plane --init 1,0,0,0,0,1,0,0,0,0,1,0"
                               " --resolution 0.02 --out "s +
                               Q(dir / "T.json") + " --aligned "s + Q(dir / "moved.pcd"));
    EXPECT_EQ(r.code, 1) << r.output;
    EXPECT_NE(r.output.find("did not converge (degenerate"), std::string::npos) << r.output;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
    const auto j = ReadJson(dir / "T.json");
    EXPECT_FALSE(j["converged"].get<bool>());
    EXPECT_EQ(j["status"], "degenerate");
    EXPECT_FALSE(std::filesystem::exists(dir / "moved.pcd"));  // no silently wrong output
}

TEST(RegisterCli, BadArgumentsAndFiles) {
    Files f;
    const std::string base = "register "s + Q(f.source) + " "s + Q(f.target) + " ";
    const auto out = " --out "s + Q(f.dir / "T.json");
    EXPECT_EQ(RunCli(base + "--method magic"s + out).code, 2);
    EXPECT_EQ(RunCli(base + "--init 1,2,3"s + out).code, 2);
    EXPECT_EQ(RunCli(base + "--init 2,0,0,0,0,1,0,0,0,0,1,0"s + out).code, 2);  // not a rotation
    EXPECT_EQ(RunCli(base + "--resolution -1"s + out).code, 2);
    EXPECT_EQ(RunCli(base + "--depth-noise abc"s + out).code, 2);
    EXPECT_EQ(RunCli(base).code, 2);  // no --out
    const CliResult missing =
        RunCli("register "s + Q(f.dir / "none.pcd") + " "s + Q(f.target) + out);
    EXPECT_EQ(missing.code, 1);
    EXPECT_NE(missing.output.find("none.pcd"), std::string::npos);
    std::ofstream(f.dir / "broken.pcd") << "VERSION .7\nFIELDS x y z\n";
    EXPECT_EQ(RunCli("register "s + Q(f.dir / "broken.pcd") + " "s + Q(f.target) + out).code, 1);
    EXPECT_EQ(RunCli(base + "--out "s + Q(f.source)).code, 2);  // would overwrite the input
}

// Four views of a small simulated table scene with their true poses, in a manifest of the
// simulator's format; `noisy` perturbs the poses and flags them.
std::filesystem::path WriteManifest(const TempDir& dir, bool noisy) {
    sim::TableSceneParams table = sim::TableSceneParamsFor(sim::TableSceneMode::kBoxes);
    table.min_objects = table.max_objects = 3;
    const sim::Scene scene = sim::MakeTableScene(table, 31);
    const auto views = sim::TableViewpoints(scene, 18, {}, 31);
    const sim::RayCaster caster(scene);
    sim::KinectParams kinect = test::ReducedKinect(2);
    kinect.num_threads = 1;
    nlohmann::json frames = nlohmann::json::array();
    for (int k = 0; k < 3; ++k) {
        const std::string name = "frame"s + std::to_string(k) + ".pcd";
        io::WritePcd(dir / name, sim::ScanKinect(caster, views[k], kinect, 7 + k));
        Eigen::Isometry3d T = views[k].cast<double>();
        if (noisy && k > 0) T = T * test::MakeTransform(3.0, {0.02, 0.01, -0.02});
        nlohmann::json rows = nlohmann::json::array();
        for (int r = 0; r < 4; ++r) rows.push_back({T(r, 0), T(r, 1), T(r, 2), T(r, 3)});
        nlohmann::json f = {{"file", name}, {"T_world_sensor", rows}};
        if (noisy) f["pose_noisy"] = true;
        frames.push_back(f);
    }
    const nlohmann::json manifest = {{"format", "multicue.sim/1"},
                                     {"scenes", {{{"id", 0}, {"frames", frames}}}}};
    std::ofstream(dir / "manifest.json") << manifest.dump(1);
    return dir / "manifest.json";
}

TEST(MapCli, ManifestToOccupancyMeshAndPoses) {
    TempDir dir;
    const auto manifest = WriteManifest(dir, true);
    const auto out = dir / "map";
    const CliResult r = RunCli("-j 1 map --manifest "s + Q(manifest) + " --out "s + Q(out));
    ASSERT_EQ(r.code, 0) << r.output;
    EXPECT_NE(r.output.find("3 of 3 frames aligned"), std::string::npos) << r.output;
    for (const char* name : {"map.bt", "mesh.ply", "cloud.pcd", "poses.json", "report.html"}) {
        EXPECT_TRUE(std::filesystem::exists(out / name)) << name;
    }
    const auto poses = ReadJson(out / "poses.json");
    EXPECT_EQ(poses["format"], "multicue.poses/1");
    ASSERT_EQ(poses["frames"].size(), 3u);
    for (const auto& f : poses["frames"]) EXPECT_TRUE(f["in_map"].get<bool>());
    EXPECT_GT(poses["map"]["occupancy"]["occupied_leaves"].get<int>(), 0);
    std::ifstream bt(out / "map.bt", std::ios::binary);
    EXPECT_FALSE(OccupancyMap::ReadBinary(bt, "map.bt").empty());
    // Scans without poses, no mesh or occupancy.
    const CliResult plain =
        RunCli("-j 1 map "s + Q(dir / "frame0.pcd") + " "s + Q(dir / "frame1.pcd") +
               " --no-mesh --no-occupancy --no-report --out "s + Q(dir / "plain") + " -q");
    EXPECT_EQ(plain.code, 0) << plain.output;
    EXPECT_TRUE(std::filesystem::exists(dir / "plain" / "poses.json"));
    EXPECT_FALSE(std::filesystem::exists(dir / "plain" / "map.bt"));
}

TEST(MapCli, BadArguments) {
    TempDir dir;
    EXPECT_EQ(RunCli("map --out "s + Q(dir / "m")).code, 2);  // no frames
    EXPECT_EQ(RunCli("map a.pcd").code, 2);                   // no --out
    EXPECT_EQ(RunCli("map a.pcd --manifest m.json --out "s + Q(dir / "m")).code, 2);
    EXPECT_EQ(RunCli("map a.pcd --resolution -0.1 --out "s + Q(dir / "m")).code, 2);
    EXPECT_EQ(RunCli("map a.pcd --method teleport --out "s + Q(dir / "m")).code, 2);
    const CliResult missing = RunCli("map "s + Q(dir / "none.pcd") + " --out "s + Q(dir / "m"));
    EXPECT_EQ(missing.code, 1);
    EXPECT_NE(missing.output.find("none.pcd"), std::string::npos);
}

TEST(PerceiveCli, ManifestWithNoisyPosesIsRegistered) {
    TempDir dir;
    const auto manifest = WriteManifest(dir, true);
    const CliResult r =
        RunCli("-j 1 perceive --manifest "s + Q(manifest) + " --no-report --out " + Q(dir / "out"));
    ASSERT_EQ(r.code, 0) << r.output;
    EXPECT_NE(r.output.find("poses: registered (3 of 3 frames aligned)"), std::string::npos)
        << r.output;
    const auto j = ReadJson(dir / "out" / "frame1" / "result.json");
    EXPECT_EQ(j["views"]["poses"], "registered");
    EXPECT_TRUE(j["views"]["registration"]["converged"].get<bool>());
    // Exact poses: the manifest's poses, no registration block.
    TempDir exact;
    const auto exact_manifest = WriteManifest(exact, false);
    const CliResult e = RunCli("-j 1 perceive --manifest "s + Q(exact_manifest) +
                               " --no-report -q --out "s + Q(exact / "out"));
    ASSERT_EQ(e.code, 0) << e.output;
    const auto je = ReadJson(exact / "out" / "frame1" / "result.json");
    EXPECT_FALSE(je["views"].contains("poses"));
    EXPECT_EQ(
        RunCli("perceive "s + Q(dir / "frame0.pcd") + " --register --out " + Q(dir / "x")).code, 2);
}

}  // namespace
}  // namespace multicue

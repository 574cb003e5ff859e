// `multicue features`: per-point and per-cluster outputs, computed normals, bad input.

#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <nlohmann/json.hpp>

#include "features_synthetic.hpp"
#include "multicue/io/point_cloud_io.hpp"
#include "test_util.hpp"

namespace multicue {
namespace {

int RunCli(const std::string& args) {
    const std::string command = std::string(test::CliPath()) + " " + args + " 2>/dev/null";
    const int status = std::system(command.c_str());
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

template <typename... Args>
std::string Cmd(const char* pattern, const Args&... args) {
    std::string out = pattern;
    for (const std::string& a : {std::string(std::filesystem::path(args).string())...}) {
        out.replace(out.find("{}"), 2, a);
    }
    return out;
}

std::string Slurp(const std::filesystem::path& p) {
    std::ifstream in(p);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
}

// Two labelled clusters without normals: a sphere (label 3) and a plane (label 7).
std::filesystem::path WriteScene(const test::TempDir& dir) {
    PointCloud sphere = test::Sphere(0.04f, {0.0f, 0.0f, 0.7f}, 0.005f, true);
    const PointCloud plane = test::Plane(0.1f, 0.8f, 0.005f);
    sphere.labels.assign(sphere.size(), 3);
    for (const auto& p : plane.points) {
        sphere.points.push_back(p + Eigen::Vector3f(0.2f, 0.0f, 0.0f));
        sphere.labels.push_back(7);
    }
    sphere.normals.clear();
    sphere.SetUnorganized();
    const auto path = dir / "scene.pcd";
    io::WritePointCloud(path, sphere);
    return path;
}

TEST(FeaturesCli, PerPointAndPerCluster) {
    const test::TempDir dir;
    const auto in = WriteScene(dir);
    ASSERT_EQ(RunCli(Cmd("features {} --type rsd --out {}", in, dir / "rsd.csv")), 0);
    const std::string csv = Slurp(dir / "rsd.csv");
    EXPECT_EQ(csv.rfind("index,r_min,r_max\n", 0), 0u);
    ASSERT_EQ(RunCli(Cmd("features {} --type fpfh --out {}", in, dir / "fpfh.pcd")), 0);
    const PointCloud out = io::ReadPointCloud(dir / "fpfh.pcd");
    ASSERT_NE(out.FindExtraField("fpfh"), nullptr);
    EXPECT_EQ(out.FindExtraField("fpfh")->count, 33u);
    EXPECT_TRUE(out.HasNormals());
    ASSERT_EQ(RunCli(Cmd("features {} --type grsd-minus --out {}", in, dir / "g.json")), 0);
    const auto j = nlohmann::json::parse(Slurp(dir / "g.json"));
    EXPECT_EQ(j["dimension"], 21);
    ASSERT_EQ(j["clusters"].size(), 2u);
    EXPECT_EQ(j["clusters"][0]["label"], 3);
    EXPECT_EQ(j["clusters"][1]["label"], 7);
    ASSERT_EQ(RunCli(Cmd("features {} --type part-stats --per part --out {}", in, dir / "p.csv")),
              0);
    EXPECT_NE(Slurp(dir / "p.csv").find("\n7,"), std::string::npos);
}

TEST(FeaturesCli, BadInput) {
    const test::TempDir dir;
    const auto in = WriteScene(dir);
    EXPECT_EQ(RunCli(Cmd("features {} --type rsd --out {}", dir / "missing.pcd", dir / "o.csv")),
              1);
    EXPECT_EQ(RunCli(Cmd("features {} --type rsd --radius 0 --out {}", in, dir / "o.csv")), 2);
    EXPECT_EQ(RunCli(Cmd("features {} --type vfh --per point --out {}", in, dir / "o.csv")), 2);
    EXPECT_EQ(RunCli(Cmd("features {} --type shot --out {}", in, dir / "o.csv")), 2);
    EXPECT_EQ(RunCli(Cmd("features {} --type pfhrgb --out {}", in, dir / "o.csv")), 1);  // no rgb
    EXPECT_FALSE(std::filesystem::exists(dir / "o.csv"));
}

}  // namespace
}  // namespace multicue

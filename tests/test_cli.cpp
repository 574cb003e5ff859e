// End-to-end tests of the multicue command-line tool: exit codes, one-line errors, outputs.

#include <array>
#include <cstdio>
#include <fstream>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <sys/wait.h>

#include "cli_runner.hpp"
#include "multicue/io/pcd.hpp"
#include "multicue/io/ply.hpp"
#include "test_util.hpp"

namespace multicue {
namespace {

using test::RunCli;

int CountLines(const std::string& s) {
    int n = 0;
    for (char c : s) n += c == '\n';
    return n;
}

PointCloud SmallCloud() {
    PointCloud c = test::RandomCloud(2000, 3, 0.2f);
    c.colors.assign(c.size(), Color{10, 20, 30, 255});
    return c;
}

using test::ReadTextFile;

TEST(Cli, InfoPrintsFieldsAndCounts) {
    test::TempDir dir;
    PointCloud c = SmallCloud();
    c.points[3].x() = std::numeric_limits<float>::quiet_NaN();
    io::WritePcd(dir / "a.pcd", c);
    const auto r = RunCli("info --json " + (dir / "a.pcd").string());
    ASSERT_EQ(r.code, 0) << r.output;
    EXPECT_NE(r.output.find("\"points\":2000"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("\"nan\":1"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("\"rgba\""), std::string::npos) << r.output;
    const auto t = RunCli("info " + (dir / "a.pcd").string());
    ASSERT_EQ(t.code, 0) << t.output;
    EXPECT_NE(t.output.find("organized:  no"), std::string::npos) << t.output;
}

TEST(Cli, ConvertPcdToPlyAndBack) {
    test::TempDir dir;
    const PointCloud c = SmallCloud();
    io::WritePcd(dir / "a.pcd", c);
    ASSERT_EQ(RunCli("convert " + (dir / "a.pcd").string() + " " + (dir / "a.ply").string() +
                     " --format ascii")
                  .code,
              0);
    ASSERT_EQ(RunCli("convert " + (dir / "a.ply").string() + " " + (dir / "b.pcd").string() +
                     " --format compressed")
                  .code,
              0);
    const PointCloud back = io::ReadPcd(dir / "b.pcd");
    ASSERT_EQ(back.size(), c.size());
    EXPECT_EQ(back.points[17], c.points[17]);
    EXPECT_EQ(back.colors[17], c.colors[17]);
}

TEST(Cli, DownsampleNormalsOutliers) {
    test::TempDir dir;
    io::WritePcd(dir / "a.pcd", SmallCloud());
    const auto a = (dir / "a.pcd").string();
    ASSERT_EQ(RunCli("downsample " + a + " " + (dir / "d.pcd").string() + " --leaf 0.05").code, 0);
    EXPECT_LT(io::ReadPcd(dir / "d.pcd").size(), 2000u);
    ASSERT_EQ(RunCli("normals " + a + " " + (dir / "n.pcd").string() + " --k 10").code, 0);
    EXPECT_TRUE(io::ReadPcd(dir / "n.pcd").HasNormals());
    ASSERT_EQ(RunCli("-j 1 normals " + a + " " + (dir / "n2.pcd").string() + " --radius 0.05").code,
              0);
    ASSERT_EQ(RunCli("outliers " + a + " " + (dir / "o.pcd").string()).code, 0);
    ASSERT_EQ(RunCli("outliers " + a + " " + (dir / "o2.pcd").string() +
                     " --method radius --radius 0.05 --min-neighbors 2")
                  .code,
              0);
}

TEST(Cli, UsageErrorsExitWithTwoAndOneLine) {
    test::TempDir dir;
    io::WritePcd(dir / "a.pcd", SmallCloud());
    const auto a = (dir / "a.pcd").string();
    const auto out = (dir / "x.pcd").string();
    const std::vector<std::string> cases = {"",
                                            "frobnicate",
                                            "downsample " + a + " " + out + " --leaf -1",
                                            "downsample " + a + " " + out + " --leaf 0",
                                            "normals " + a + " " + out + " --k -3",
                                            "normals " + a + " " + out + " --radius -0.1",
                                            "outliers " + a + " " + out + " --k 0",
                                            "convert " + a + " " + out + " --format zip",
                                            "convert " + a + " " + a,
                                            "normals " + a + " " + out + " --organized",
                                            "--threads -2 info " + a,
                                            "normals " + a + " " + out + " --viewpoint 1,2"};
    for (const std::string& args : cases) {
        const auto r = RunCli(args);
        EXPECT_EQ(r.code, 2) << args << "\n" << r.output;
        EXPECT_EQ(CountLines(r.output), 1) << args << "\n" << r.output;
        EXPECT_NE(r.output.find("error"), std::string::npos) << args << "\n" << r.output;
    }
    EXPECT_FALSE(std::filesystem::exists(out));
}

TEST(Cli, DataErrorsExitWithOneAndKeepExistingOutput) {
    test::TempDir dir;
    const auto out = dir / "out.pcd";
    io::WritePcd(out, SmallCloud());
    const std::string before = ReadTextFile(out);
    {
        std::ofstream(dir / "trunc.pcd") << "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\n"
                                            "TYPE F F F\nCOUNT 1 1 1\nWIDTH 10\nHEIGHT 1\n"
                                            "VIEWPOINT 0 0 0 1 0 0 0\nPOINTS 10\nDATA binary\n"
                                            "abc";
        std::ofstream(dir / "garbage.pcd") << "hello world\n";
        std::ofstream(dir / "garbage.ply") << "ply\nformat nonsense 1.0\n";
    }
    PointCloud nan_only;
    nan_only.points.assign(5, Eigen::Vector3f::Constant(std::numeric_limits<float>::quiet_NaN()));
    nan_only.SetUnorganized();
    io::WritePcd(dir / "nan.pcd", nan_only);
    io::WritePcd(dir / "empty.pcd", PointCloud{});
    for (const std::string name :
         {"missing.pcd", "trunc.pcd", "garbage.pcd", "garbage.ply", "nan.pcd", "empty.pcd"}) {
        const auto in = (dir / name).string();
        for (const std::string cmd : {"downsample", "normals", "outliers"}) {
            const auto r = RunCli(cmd + " " + in + " " + out.string());
            EXPECT_EQ(r.code, 1) << cmd << " " << name << "\n" << r.output;
            EXPECT_EQ(CountLines(r.output), 1) << cmd << " " << name << "\n" << r.output;
            EXPECT_NE(r.output.find(name), std::string::npos) << r.output;
        }
    }
    EXPECT_EQ(ReadTextFile(out), before);
    const auto r = RunCli("info " + (dir / "missing.pcd").string());
    EXPECT_EQ(r.code, 1);
    const auto w = RunCli("convert " + (dir / "empty.pcd").string() + " /nonexistent/dir/x.pcd");
    EXPECT_EQ(w.code, 1) << w.output;
}

TEST(Cli, DemoWritesItsOutputs) {
    test::TempDir dir;
    const auto r = RunCli("demo --out " + (dir / "demo").string());
    ASSERT_EQ(r.code, 0) << r.output;
    for (const char* f : {"scene.pcd", "result.json", "labels.pcd", "models.ply"}) {
        EXPECT_TRUE(std::filesystem::exists(dir / "demo" / f)) << f;
    }
    const PointCloud scene = io::ReadPcd(dir / "demo" / "scene.pcd");
    EXPECT_TRUE(scene.IsOrganized());
    EXPECT_TRUE(scene.HasLabels());
}

TEST(Cli, PerceiveWritesTheContractAndRefusesBadInput) {
    test::TempDir dir;
    ASSERT_EQ(RunCli("demo --out " + (dir / "demo").string()).code, 0);
    const auto scene = (dir / "demo" / "scene.pcd").string();
    const auto out = dir / "out";
    const auto r = RunCli("perceive " + scene + " --out " + out.string());
    ASSERT_EQ(r.code, 0) << r.output;
    for (const char* f : {"result.json", "labels.pcd", "models.ply"}) {
        EXPECT_TRUE(std::filesystem::exists(out / f)) << f;
    }
    const std::string before = ReadTextFile(out / "result.json");
    {
        std::ofstream(dir / "typo.json") << R"({"clustering": {"min_pionts": 3}})";
        std::ofstream(dir / "bad.json") << "{ nope";
    }
    struct Case {
        std::string args;
        int code;
    };
    const std::vector<Case> cases = {
        {"perceive " + (dir / "missing.pcd").string() + " --out " + out.string(), 1},
        {"perceive " + scene + " --out " + out.string() + " --config " +
             (dir / "typo.json").string(),
         2},
        {"perceive " + scene + " --out " + out.string() + " --config " +
             (dir / "bad.json").string(),
         2},
        {"perceive " + scene + " --out " + out.string() + " --up 0,0", 2},
        {"perceive " + scene + " --out /dev/null/out", 1},
        {"perceive " + scene, 2},
    };
    for (const auto& c : cases) {
        const auto e = RunCli(c.args);
        EXPECT_EQ(e.code, c.code) << c.args << "\n" << e.output;
        EXPECT_EQ(CountLines(e.output), 1) << c.args << "\n" << e.output;
    }
    EXPECT_EQ(ReadTextFile(out / "result.json"), before);
    const auto dump = RunCli("config --dump");
    ASSERT_EQ(dump.code, 0);
    { std::ofstream(dir / "defaults.json") << dump.output; }
    const auto check = RunCli("config --check " + (dir / "defaults.json").string());
    EXPECT_EQ(check.code, 0) << check.output;
}

TEST(Cli, PerceiveReportOnByDefaultAndOptional) {
    test::TempDir dir;
    ASSERT_EQ(RunCli("demo --no-report --out " + (dir / "demo").string()).code, 0);
    EXPECT_FALSE(std::filesystem::exists(dir / "demo" / "report.html"));
    const auto scene = (dir / "demo" / "scene.pcd").string();
    const auto r = RunCli("perceive " + scene + " --out " + (dir / "a").string());
    ASSERT_EQ(r.code, 0) << r.output;
    const std::string html = ReadTextFile(dir / "a" / "report.html");
    EXPECT_EQ(html.rfind("<!DOCTYPE html>", 0), 0u);
    EXPECT_NE(html.find("data-object=\"1\""), std::string::npos);
    EXPECT_NE(r.output.find("report.html"), std::string::npos);

    const auto q = RunCli("perceive " + scene + " --no-report -q --out " + (dir / "b").string());
    ASSERT_EQ(q.code, 0) << q.output;
    EXPECT_TRUE(q.output.empty()) << q.output;
    EXPECT_TRUE(std::filesystem::exists(dir / "b" / "result.json"));
    EXPECT_FALSE(std::filesystem::exists(dir / "b" / "report.html"));
    {
        std::ofstream(dir / "off.json") << R"({"report": {"enabled": false}})";
        std::ofstream(dir / "typo.json") << R"({"report": {"max_pionts": 10}})";
    }
    ASSERT_EQ(RunCli("perceive " + scene + " -q --config " + (dir / "off.json").string() +
                     " --out " + (dir / "c").string())
                  .code,
              0);
    EXPECT_FALSE(std::filesystem::exists(dir / "c" / "report.html"));
    const auto typo = RunCli("perceive " + scene + " --config " + (dir / "typo.json").string() +
                             " --out " + (dir / "d").string());
    EXPECT_EQ(typo.code, 2);
    EXPECT_NE(typo.output.find("max_pionts"), std::string::npos) << typo.output;
    EXPECT_EQ(CountLines(typo.output), 1) << typo.output;
}

TEST(Cli, TrainPartGraphAndPerceiveWithTheBlend) {
    test::TempDir dir;
    const auto model = (dir / "m.mcpg").string();
    const auto t =
        RunCli("train --out " + model + " --objects 1 --views 1 --table-scenes 1 --table-views 1");
    ASSERT_EQ(t.code, 0) << t.output;
    const auto bad = RunCli("train --out " + (dir / "bad.mcpg").string() + " --size-weight -1");
    EXPECT_EQ(bad.code, 2);
    EXPECT_EQ(CountLines(bad.output), 1) << bad.output;
    EXPECT_FALSE(std::filesystem::exists(dir / "bad.mcpg"));
    const auto bad_q = RunCli("train --out " + (dir / "bad.mcpg").string() + " --rsd-quantile 0");
    EXPECT_EQ(bad_q.code, 2);
    EXPECT_EQ(CountLines(bad_q.output), 1) << bad_q.output;
    EXPECT_FALSE(std::filesystem::exists(dir / "bad.mcpg"));
    ASSERT_EQ(RunCli("demo --no-report --out " + (dir / "demo").string()).code, 0);
    {
        std::ofstream(dir / "blend.json")
            << R"({"category": {"categoriser": "part-graph+rules", "part_graph_weight": 0.5, )"
            << R"("part_graph": {"category_priors": {"other": 0.5, "plate": 2}}, )"
            << R"("part_graph_model": ")" << model << R"("}})";
        std::ofstream(dir / "bad_prior.json")
            << R"({"category": {"categoriser": "part-graph", "part_graph": {"category_priors": {"box": -1}}, )"
            << R"("part_graph_model": ")" << model << R"("}})";
    }
    const auto bad_prior =
        RunCli("perceive " + (dir / "demo" / "scene.pcd").string() + " --no-report -q --config " +
               (dir / "bad_prior.json").string() + " --out " + (dir / "bp").string());
    EXPECT_EQ(bad_prior.code, 2) << bad_prior.output;
    EXPECT_EQ(CountLines(bad_prior.output), 1) << bad_prior.output;
    EXPECT_FALSE(std::filesystem::exists(dir / "bp" / "result.json"));
    const auto r =
        RunCli("perceive " + (dir / "demo" / "scene.pcd").string() + " --no-report -q --config " +
               (dir / "blend.json").string() + " --out " + (dir / "p").string());
    ASSERT_EQ(r.code, 0) << r.output;
    EXPECT_TRUE(std::filesystem::exists(dir / "p" / "result.json"));
    // Three experts: rules, part-graph and the model's whole-object k-NN; bad neighbour counts
    // and weights are refused with one line and no result.
    const std::vector<std::pair<std::string, bool>> three_configs{
        {R"("cluster_k": 5)", true},
        {R"("expert_weights": [0.2, 0.7, 0.1])", true},
        {R"("cluster_k": 0)", false},
        {R"("expert_weights": [1, -1, 1])", false},
        {R"("expert_weights": [1, 1])", false}};
    for (std::size_t i = 0; i < three_configs.size(); ++i) {
        const auto& [keys, ok] = three_configs[i];
        std::ofstream(dir / "three.json")
            << R"({"category": {"categoriser": "part-graph+rules+cluster", )" << keys
            << R"(, "part_graph_model": ")" << model << R"("}})";
        std::filesystem::path out = dir / "q";
        out += std::to_string(i);
        const auto three = RunCli("perceive " + (dir / "demo" / "scene.pcd").string() +
                                  " --no-report -q --config " + (dir / "three.json").string() +
                                  " --out " + out.string());
        if (ok) {
            ASSERT_EQ(three.code, 0) << three.output;
            EXPECT_NE(ReadTextFile(out / "result.json").find("\"probabilities\""),
                      std::string::npos);
        } else {
            EXPECT_EQ(three.code, 2) << keys << ": " << three.output;
            EXPECT_EQ(CountLines(three.output), 1) << three.output;
            EXPECT_FALSE(std::filesystem::exists(out / "result.json"));
        }
    }
    // The stacked categoriser: refused (one line, no result) with a model without a stacker,
    // works with one trained on held-out scenes.
    const auto stacked_model = (dir / "stacked.mcpg").string();
    const auto ts = RunCli("train --out " + stacked_model +
                           " --objects 1 --views 1 --table-scenes 0 --stacker-scenes 1 "
                           "--stacker-views 1");
    ASSERT_EQ(ts.code, 0) << ts.output;
    EXPECT_NE(ts.output.find("stacker"), std::string::npos) << ts.output;
    for (const std::string& m : {model, stacked_model}) {
        std::ofstream(dir / "stacked.json") << R"({"category": {"categoriser": "stacked", )"
                                            << R"("part_graph_model": ")" << m << R"("}})";
        const auto out = dir / (m == model ? "s0" : "s1");
        const auto st = RunCli("perceive " + (dir / "demo" / "scene.pcd").string() +
                               " --no-report -q --config " + (dir / "stacked.json").string() +
                               " --out " + out.string());
        if (m == model) {
            EXPECT_EQ(st.code, 2) << st.output;
            EXPECT_EQ(CountLines(st.output), 1) << st.output;
            EXPECT_FALSE(std::filesystem::exists(out / "result.json"));
        } else {
            ASSERT_EQ(st.code, 0) << st.output;
            EXPECT_TRUE(std::filesystem::exists(out / "result.json"));
        }
    }
}

TEST(Cli, PerceiveFusesTheFramesOfAManifest) {
    test::TempDir dir;
    const auto sim = (dir / "sim").string();
    ASSERT_EQ(
        RunCli("simulate scenes --out " + sim + " --scenes 1 --views 2 --objects 3,3 -q").code, 0);
    const auto manifest = (dir / "sim" / "manifest.json").string();
    const auto r = RunCli("perceive --manifest " + manifest + " --scene 0 --no-report -q --out " +
                          (dir / "out").string());
    ASSERT_EQ(r.code, 0) << r.output;
    for (const char* frame : {"scene_0000_view_00", "scene_0000_view_01"}) {
        const auto json = ReadTextFile(dir / "out" / frame / "result.json");
        EXPECT_NE(json.find("\"views\""), std::string::npos) << frame;
        EXPECT_TRUE(std::filesystem::exists(dir / "out" / frame / "labels.pcd")) << frame;
    }
    const auto both = RunCli("perceive " + manifest + " --manifest " + manifest + " --out " +
                             (dir / "x").string());
    EXPECT_EQ(both.code, 2);
    EXPECT_EQ(CountLines(both.output), 1) << both.output;
    const auto scene =
        RunCli("perceive --manifest " + manifest + " --scene 7 --out " + (dir / "x").string());
    EXPECT_EQ(scene.code, 2);
    { std::ofstream(dir / "bad.json") << R"({"scenes": [{"id": 0, "frames": [{"file": 1}]}]})"; }
    const auto bad = RunCli("perceive --manifest " + (dir / "bad.json").string() + " --out " +
                            (dir / "x").string());
    EXPECT_EQ(bad.code, 1);
    EXPECT_EQ(CountLines(bad.output), 1) << bad.output;
    EXPECT_FALSE(std::filesystem::exists(dir / "x"));
}

TEST(Cli, TrainFromAMeshFolderWithItsOwnLabelsFile) {
    test::TempDir dir;
    std::filesystem::create_directories(dir / "meshes");
    {
        // A 12 x 8 x 6 cm box.
        std::ofstream obj(dir / "meshes" / "crate.obj");
        for (int k = 0; k < 8; ++k) {
            obj << "v " << (k & 1 ? 0.06 : -0.06) << ' ' << (k & 2 ? 0.04 : -0.04) << ' '
                << (k & 4 ? 0.06 : 0.0) << '\n';
        }
        obj << "f 1 3 4 2\nf 5 6 8 7\nf 1 2 6 5\nf 3 7 8 4\nf 1 5 7 3\nf 2 4 8 6\n";
        std::ofstream(dir / "elsewhere.csv") << "file,category\ncrate.obj,box\n";
    }
    const auto model = (dir / "m.mcpg").string();
    const std::string small = " --objects 1 --views 1 --table-scenes 0";
    const auto t =
        RunCli("train --out " + model + small + " --meshes " + (dir / "meshes").string() +
               " --labels " + (dir / "elsewhere.csv").string());
    ASSERT_EQ(t.code, 0) << t.output;
    EXPECT_TRUE(std::filesystem::exists(model));
    EXPECT_NE(t.output.find("; 0 table scenes)"), std::string::npos) << t.output;
    const auto alone = RunCli("train --out " + (dir / "a.mcpg").string() + small + " --labels " +
                              (dir / "elsewhere.csv").string());
    EXPECT_EQ(alone.code, 2);
    EXPECT_EQ(CountLines(alone.output), 1) << alone.output;
    const auto missing =
        RunCli("train --out " + (dir / "b.mcpg").string() + small + " --meshes " +
               (dir / "meshes").string() + " --labels " + (dir / "none.csv").string());
    EXPECT_EQ(missing.code, 1);
    EXPECT_NE(missing.output.find("none.csv"), std::string::npos) << missing.output;
    EXPECT_FALSE(std::filesystem::exists(dir / "b.mcpg"));
}

}  // namespace
}  // namespace multicue

// Feature extraction tool (recognition/dataset_extraction.hpp), the colour histogram and
// `multicue dataset extract` end to end on a tiny simulated set.

#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "cli_runner.hpp"
#include "multicue/core/exceptions.hpp"
#include "multicue/core/progress.hpp"
#include "multicue/features/colour.hpp"
#include "multicue/io/point_cloud_io.hpp"
#include "multicue/ml/dataset.hpp"
#include "multicue/recognition/dataset_extraction.hpp"
#include "test_util.hpp"

namespace multicue {
namespace {

namespace fs = std::filesystem;
using test::TempDir;

// A sphere (kind 0) or an axis-aligned box surface (kind 1) at 1 m in front of the origin,
// 4 mm spacing, one colour, with small deterministic jitter.
PointCloud Shape(int kind, float size, Color colour, std::uint32_t seed) {
    PointCloud c;
    std::uint32_t s = seed * 2654435761u + 1u;
    auto jitter = [&s] {
        s = s * 1664525u + 1013904223u;
        return ((s >> 8) / 16777216.0f - 0.5f) * 0.001f;
    };
    const Eigen::Vector3f centre(0.0f, 0.0f, 1.0f);
    if (kind == 0) {
        const int n = static_cast<int>(size / 0.004f) * 4;
        for (int i = 0; i < n; ++i) {
            const float theta = static_cast<float>(M_PI) * (i + 0.5f) / n;
            const int m = std::max(1, static_cast<int>(2 * n * std::sin(theta)));
            for (int j = 0; j < m; ++j) {
                const float phi = 2.0f * static_cast<float>(M_PI) * j / m;
                const Eigen::Vector3f d(std::sin(theta) * std::cos(phi),
                                        std::sin(theta) * std::sin(phi), std::cos(theta));
                c.points.push_back(centre + (size + jitter()) * d);
            }
        }
    } else {
        const int n = static_cast<int>(size / 0.004f);
        for (int axis = 0; axis < 3; ++axis) {
            for (int side = -1; side <= 1; side += 2) {
                for (int i = 0; i <= 2 * n; ++i) {
                    for (int j = 0; j <= 2 * n; ++j) {
                        Eigen::Vector3f p;
                        p[axis] = side * size + jitter();
                        p[(axis + 1) % 3] = -size + 0.004f * i;
                        p[(axis + 2) % 3] = 0.6f * (-size + 0.004f * j);
                        c.points.push_back(centre + p);
                    }
                }
            }
        }
    }
    c.colors.assign(c.points.size(), colour);
    c.SetUnorganized();
    return c;
}

// root/sphere/ball/*.pcd (2 files) and root/box/box/*.pcd (2 files).
void WriteTree(const fs::path& root) {
    fs::create_directories(root / "sphere" / "ball");
    fs::create_directories(root / "box" / "box");
    io::WritePointCloud(root / "sphere/ball/a.pcd", Shape(0, 0.05f, {200, 20, 20, 255}, 1));
    io::WritePointCloud(root / "sphere/ball/b.pcd", Shape(0, 0.06f, {200, 30, 20, 255}, 2));
    io::WritePointCloud(root / "box/box/a.pcd", Shape(1, 0.05f, {20, 20, 200, 255}, 3));
    io::WritePointCloud(root / "box/box/b.pcd", Shape(1, 0.06f, {30, 20, 200, 255}, 4));
}

DatasetExtractionParams Params() {
    DatasetExtractionParams p;
    p.features = {"vfh", "grsd-minus", "part-stats", "colour"};
    p.feature_params.num_threads = 1;
    return p;
}

TEST(ColourHistogram, KnownColours) {
    EXPECT_TRUE(RgbToHsv({255, 0, 0, 255}).isApprox(Eigen::Vector3f(0, 1, 1)));
    EXPECT_TRUE(RgbToHsv({0, 255, 0, 255}).isApprox(Eigen::Vector3f(120, 1, 1)));
    EXPECT_TRUE(RgbToHsv({0, 0, 255, 255}).isApprox(Eigen::Vector3f(240, 1, 1)));
    const Eigen::Vector3f grey = RgbToHsv({128, 128, 128, 255});
    EXPECT_FLOAT_EQ(grey.y(), 0.0f);

    PointCloud c = Shape(0, 0.03f, {0, 0, 255, 255}, 1);
    for (std::size_t i = 0; i < c.size() / 2; ++i) c.colors[i] = {128, 128, 128, 255};
    c.points.back() = Eigen::Vector3f::Constant(NAN);  // skipped
    const FeatureVector h = ComputeColourHistogram(c);
    ASSERT_EQ(h.size(), kColourHistogramSize);
    const float n = static_cast<float>(c.size() - 1);
    const float blue = static_cast<float>(c.size() - 1 - c.size() / 2) / n;
    EXPECT_NEAR(h[8], blue, 1e-6f);  // 240 degrees: bin 8 of 12
    EXPECT_NEAR(h.head(kColourHueBins).sum(), blue, 1e-6f);
    EXPECT_NEAR(h.segment(kColourHueBins, kColourSatBins).sum(), 1.0f, 1e-5f);
    EXPECT_NEAR(h[kColourHueBins], 1.0f - blue, 1e-6f);  // grey: saturation bin 0
    EXPECT_NEAR(h.tail(kColourValBins).sum(), 1.0f, 1e-5f);
    EXPECT_NEAR(h[kColourHistogramSize - 1], blue, 1e-6f);  // value 1: last bin

    PointCloud bare = c;
    bare.colors.clear();
    EXPECT_THROW(ComputeColourHistogram(bare), InvalidArgument);
    EXPECT_EQ(ComputeColourHistogram(PointCloud{}), FeatureVector::Zero(kColourHistogramSize));
    EXPECT_THROW(ComputeColourHistogram(c, {.min_saturation = 2.0f}), InvalidArgument);
}

TEST(DatasetExtraction, BlocksAndBadFeatureNames) {
    const ml::Dataset d = EmptyFeatureDataset({"vfh", "colour"});
    ASSERT_EQ(d.blocks.size(), 2u);
    EXPECT_EQ(d.blocks[0].name, "vfh");
    EXPECT_EQ(d.blocks[0].count, 308u);
    EXPECT_EQ(d.blocks[1].begin, 308u);
    EXPECT_EQ(d.feature_names[308], "colour0");
    EXPECT_THROW(EmptyFeatureDataset({"vfh", "nope"}), InvalidArgument);
    EXPECT_THROW(EmptyFeatureDataset({"vfh", "vfh"}), InvalidArgument);
    EXPECT_THROW(EmptyFeatureDataset({}), InvalidArgument);
}

TEST(DatasetExtraction, TreeOneRowPerFile) {
    TempDir dir;
    WriteTree(dir / "tree");
    const auto inputs = TreeInputs(dir / "tree", false);
    ASSERT_EQ(inputs.size(), 4u);
    Progress progress;
    const auto s = ExtractDataset(inputs, dir / "d.mcd", Params(), progress);
    EXPECT_EQ(s.rows, 4u);
    EXPECT_EQ(s.files_done, 4u);
    EXPECT_EQ(progress.done(), 4u);
    const ml::Dataset d = ml::LoadDataset(dir / "d.mcd");
    ASSERT_EQ(d.rows(), 4u);
    EXPECT_EQ(d.BlockNames(),
              (std::vector<std::string>{"vfh", "grsd-minus", "part-stats", "colour"}));
    // Sorted order: box/box/a, box/box/b, sphere/ball/a, sphere/ball/b.
    EXPECT_EQ(d.class_names[static_cast<std::size_t>(d.labels[0])], "box/box");
    EXPECT_EQ(d.class_names[static_cast<std::size_t>(d.labels[3])], "sphere/ball");
    EXPECT_EQ(d.groups[0], d.groups[1]);
    EXPECT_NE(d.groups[1], d.groups[2]);
    EXPECT_EQ(d.views[0], 0);
    EXPECT_EQ(d.views[1], 1);
    EXPECT_EQ(d.sources[2], "sphere/ball/a.pcd");
    // Colour: red sphere in hue bin 0, blue box in bin 8.
    const std::size_t colour = d.blocks[d.BlockIndex("colour")].begin;
    EXPECT_GT(d.row(3)[colour + 0], 0.99f);
    EXPECT_GT(d.row(0)[colour + 8], 0.99f);
    // Geometry separates them: the part statistics' extents differ by kind.
    const std::size_t ps = d.blocks[d.BlockIndex("part-stats")].begin;
    EXPECT_NE(d.row(0)[ps + 15], d.row(2)[ps + 15]);

    // Deterministic: a second run gives the same values.
    Progress p2;
    ExtractDataset(inputs, dir / "e.mcd", Params(), p2);
    EXPECT_EQ(ml::LoadDataset(dir / "e.mcd").values, d.values);
}

TEST(DatasetExtraction, ResumeEqualsOneRunAndChecksBlocks) {
    TempDir dir;
    WriteTree(dir / "tree");
    const auto inputs = TreeInputs(dir / "tree", false);
    Progress p1, p2, p3;
    ExtractDataset(inputs, dir / "one.mcd", Params(), p1);

    // An interrupted run: the flag set before the first file writes an empty, valid output.
    RequestInterrupt(true);
    auto s = ExtractDataset(inputs, dir / "part.mcd", Params(), p2);
    RequestInterrupt(false);
    EXPECT_TRUE(s.interrupted);
    EXPECT_EQ(ml::LoadDataset(dir / "part.mcd").rows(), 0u);

    // Half of the files, then a resumed run over all of them.
    const std::vector<ExtractionInput> half(inputs.begin(), inputs.begin() + 2);
    ExtractDataset(half, dir / "part.mcd", Params(), p2);
    DatasetExtractionParams resume = Params();
    resume.resume = true;
    s = ExtractDataset(inputs, dir / "part.mcd", resume, p3);
    EXPECT_EQ(s.files_resumed, 2u);
    EXPECT_EQ(s.rows_added, 2u);
    const ml::Dataset one = ml::LoadDataset(dir / "one.mcd");
    const ml::Dataset two = ml::LoadDataset(dir / "part.mcd");
    EXPECT_EQ(one.values, two.values);
    EXPECT_EQ(one.sources, two.sources);
    EXPECT_EQ(one.groups, two.groups);

    resume.features = {"vfh"};
    Progress p4;
    EXPECT_THROW(ExtractDataset(inputs, dir / "part.mcd", resume, p4), InvalidArgument);
}

TEST(DatasetExtraction, PerClusterAndSmallClusters) {
    TempDir dir;
    fs::create_directories(dir / "tree/mixed");
    PointCloud a = Shape(0, 0.05f, {200, 20, 20, 255}, 1);
    const PointCloud b = Shape(1, 0.05f, {20, 20, 200, 255}, 2);
    a.labels.assign(a.size(), 20);
    for (const auto& p : b.points) a.points.push_back(p + Eigen::Vector3f(0.3f, 0, 0));
    a.colors.insert(a.colors.end(), b.colors.begin(), b.colors.end());
    a.labels.resize(a.points.size(), 30);
    a.labels.back() = 0;  // background: no row
    a.labels[0] = 40;     // one point: too small
    a.SetUnorganized();
    io::WritePointCloud(dir / "tree/mixed/scan.pcd", a);
    Progress progress;
    const auto s =
        ExtractDataset(TreeInputs(dir / "tree", true), dir / "d.mcd", Params(), progress);
    EXPECT_EQ(s.rows, 2u);
    EXPECT_EQ(s.small_clusters, 1u);
    const ml::Dataset d = ml::LoadDataset(dir / "d.mcd");
    EXPECT_EQ(d.sources, (std::vector<std::string>{"mixed/scan.pcd#20", "mixed/scan.pcd#30"}));
}

TEST(DatasetExtraction, BadInput) {
    TempDir dir;
    EXPECT_THROW(TreeInputs(dir / "missing", false), IoError);
    fs::create_directories(dir / "empty");
    EXPECT_THROW(TreeInputs(dir / "empty", false), DataError);
    io::WritePointCloud(dir / "empty/top.pcd", Shape(0, 0.03f, {1, 2, 3, 255}, 1));
    EXPECT_THROW(TreeInputs(dir / "empty", false), DataError);  // no label folder

    // A corrupt file stops the run with its error; the rows before it are saved and the earlier
    // output is not lost.
    WriteTree(dir / "tree");
    {
        std::ofstream bad(dir / "tree/sphere/ball/c.pcd");
        bad << "# .PCD v0.7\nFIELDS x y\nnonsense\n";
    }
    Progress progress;
    EXPECT_THROW(ExtractDataset(TreeInputs(dir / "tree", false), dir / "d.mcd", Params(), progress),
                 IoError);
    EXPECT_EQ(ml::LoadDataset(dir / "d.mcd").rows(), 4u);

    EXPECT_THROW(ManifestInputs(dir / "nope.json"), IoError);
    {
        std::ofstream m(dir / "m.json");
        m << "{\"format\": \"something/1\"}";
    }
    EXPECT_THROW(ManifestInputs(dir / "m.json"), FormatError);
    {
        std::ofstream m(dir / "m.json");
        m << "{\"format\": \"multicue.sim/1\", \"scenes\": [{\"seed\": 1}]}";
    }
    EXPECT_THROW(ManifestInputs(dir / "m.json"), FormatError);
    {
        std::ofstream m(dir / "m.json");
        m << "{not json";
    }
    EXPECT_THROW(ManifestInputs(dir / "m.json"), FormatError);
}

TEST(DatasetExtraction, ManifestLabelsGroupsAndUp) {
    TempDir dir;
    const nlohmann::json object_a = {
        {"label", 20}, {"category", "cylinder"}, {"source", "kit__Cup.obj"}};
    const nlohmann::json object_b = {{"label", 30}, {"category", "box"}, {"source", "box"}};
    const nlohmann::json table = {{"label", 1}, {"category", "none"}, {"source", "table"}};
    const nlohmann::json T = {{1, 0, 0, 0}, {0, 0, 1, 0}, {0, -1, 0, 1}, {0, 0, 0, 1}};
    nlohmann::json m = {{"format", "multicue.sim/1"}, {"scenes", nlohmann::json::array()}};
    for (int s = 0; s < 2; ++s) {
        m["scenes"].push_back(
            {{"id", s},
             {"seed", 100 + s},
             {"objects", {table, object_a, object_b}},
             {"frames",
              {{{"file", "f" + std::to_string(s) + "_0.pcd"}, {"T_world_sensor", T}},
               {{"file", "f" + std::to_string(s) + "_1.pcd"}, {"T_world_sensor", T}}}}});
    }
    std::ofstream(dir / "manifest.json") << m.dump();
    const auto inputs = ManifestInputs(dir / "manifest.json");
    ASSERT_EQ(inputs.size(), 4u);
    EXPECT_EQ(inputs[1].view, 1);
    EXPECT_EQ(inputs[2].file, dir / "f1_0.pcd");
    ASSERT_EQ(inputs[0].objects.size(), 2u);  // the table is not an object
    EXPECT_EQ(inputs[0].objects[0].class_path, "cylinder/kit__Cup");
    EXPECT_EQ(inputs[0].objects[1].class_path, "box/box");
    // The same mesh is one instance in every scene; procedural objects are new in each scene.
    EXPECT_EQ(inputs[0].objects[0].group, inputs[2].objects[0].group);
    EXPECT_NE(inputs[0].objects[1].group, inputs[2].objects[1].group);
    EXPECT_GE(inputs[0].objects[1].group, 0);
    ASSERT_TRUE(inputs[0].up.has_value());
    EXPECT_TRUE(inputs[0].up->isApprox(Eigen::Vector3f(0, -1, 0)));
}

TEST(DatasetExtractionCli, SimulatedObjectsAndErrors) {
    using test::RunCli;
    TempDir dir;
    const std::string sim = (dir / "sim").string();
    auto r = RunCli("-j 2 simulate objects --count 3 --views 2 -q --out " + sim);
    ASSERT_EQ(r.code, 0) << r.output;
    const std::string out = (dir / "d.mcd").string();
    r = RunCli("-j 2 dataset extract --manifest " + sim + "/manifest.json -q -o " + out);
    ASSERT_EQ(r.code, 0) << r.output;
    const ml::Dataset d = ml::LoadDataset(out);
    EXPECT_EQ(d.rows(), 6u);
    EXPECT_EQ(d.BlockNames(),
              (std::vector<std::string>{"vfh", "grsd-minus", "part-stats", "colour"}));
    EXPECT_EQ(std::set<std::int64_t>(d.groups.begin(), d.groups.end()).size(), 3u);
    EXPECT_EQ(std::set<std::int64_t>(d.views.begin(), d.views.end()),
              (std::set<std::int64_t>{0, 1}));
    for (const auto& c : d.class_names) EXPECT_NE(c.find('/'), std::string::npos) << c;
    EXPECT_EQ(d.sources[0], "object_0000_view_00.pcd#20");

    // Resuming a complete output adds nothing and keeps every row.
    r = RunCli("dataset extract --manifest " + sim + "/manifest.json --resume -o " + out);
    ASSERT_EQ(r.code, 0) << r.output;
    EXPECT_NE(r.output.find("6 resumed"), std::string::npos) << r.output;
    EXPECT_EQ(ml::LoadDataset(out).values, d.values);

    r = RunCli("dataset extract --manifest " + sim + "/manifest.json --features vfh,foo -o " + out);
    EXPECT_EQ(r.code, 2) << r.output;
    EXPECT_NE(r.output.find("unknown feature 'foo'"), std::string::npos) << r.output;
    r = RunCli("dataset extract --manifest " + sim + "/missing.json -o " + out);
    EXPECT_EQ(r.code, 1) << r.output;
    r = RunCli("dataset extract -o " + out);
    EXPECT_EQ(r.code, 2) << r.output;
    r = RunCli("dataset extract --manifest " + sim + "/manifest.json --voxel -1 -o " + out);
    EXPECT_EQ(r.code, 2) << r.output;
    EXPECT_EQ(ml::LoadDataset(out).values, d.values);  // nothing lost
}

}  // namespace
}  // namespace multicue

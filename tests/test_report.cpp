// report.html: the page API (escaping, base64, confusion matrices) and the perceive report's
// embedded data, decoded back and compared with the cloud and the result.

#include <cstring>
#include <map>
#include <set>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "multicue/core/exceptions.hpp"
#include "multicue/io/config.hpp"
#include "multicue/io/file_utils.hpp"
#include "multicue/sim/tabletop_scene.hpp"
#include "multicue/system/perceive.hpp"
#include "multicue/system/perceive_output.hpp"
#include "multicue/system/perceive_report.hpp"
#include "multicue/system/report_page.hpp"
#include "multicue/system/report_writer.hpp"
#include "test_util.hpp"

namespace multicue {
namespace {

std::vector<std::uint8_t> Base64Decode(const std::string& s) {
    auto value = [](char c) -> int {
        if (c >= 'A' && c <= 'Z') return c - 'A';
        if (c >= 'a' && c <= 'z') return c - 'a' + 26;
        if (c >= '0' && c <= '9') return c - '0' + 52;
        if (c == '+') return 62;
        if (c == '/') return 63;
        return -1;
    };
    std::vector<std::uint8_t> out;
    unsigned buffer = 0;
    int bits = 0;
    for (const char c : s) {
        const int v = value(c);
        if (v < 0) break;  // padding
        buffer = (buffer << 6) | static_cast<unsigned>(v);
        bits += 6;
        if (bits >= 8) {
            bits -= 8;
            out.push_back(static_cast<std::uint8_t>((buffer >> bits) & 0xff));
        }
    }
    return out;
}

template <typename T>
std::vector<T> Decode(const std::string& b64) {
    const auto bytes = Base64Decode(b64);
    std::vector<T> v(bytes.size() / sizeof(T));
    std::memcpy(v.data(), bytes.data(), v.size() * sizeof(T));
    return v;
}

struct Scene {
    PointCloud cloud;
    PerceiveResult result;
};

const Scene& DemoScene() {
    static const Scene s = [] {
        Scene r;
        const auto scene = sim::MakeDemoScene();
        sim::ScanParams p;
        p.T_world_camera = sim::DefaultCameraPose(scene);
        r.cloud = sim::ScanTableTopScene(scene, p);
        r.result = Perceive(r.cloud, PerceiveParams{});
        return r;
    }();
    return s;
}

// The viewer's JSON embedded in a page, or null when the build has no viewer.
nlohmann::json SceneData(const std::string& html) {
    const std::string open = "<script type=\"application/json\" id=\"mc-data\">";
    const auto a = html.find(open);
    if (a == std::string::npos) return nullptr;
    const auto b = html.find("</script>", a);
    return nlohmann::json::parse(html.substr(a + open.size(), b - a - open.size()));
}

TEST(ReportPage, Base64MatchesTheStandardVectors) {
    const std::map<std::string, std::string> cases = {{"", ""},
                                                      {"f", "Zg=="},
                                                      {"fo", "Zm8="},
                                                      {"foo", "Zm9v"},
                                                      {"foob", "Zm9vYg=="},
                                                      {"fooba", "Zm9vYmE="},
                                                      {"foobar", "Zm9vYmFy"}};
    for (const auto& [in, out] : cases) EXPECT_EQ(Base64Encode(in.data(), in.size()), out) << in;
    std::vector<std::uint8_t> all(256);
    for (int i = 0; i < 256; ++i) all[i] = static_cast<std::uint8_t>(i);
    EXPECT_EQ(Base64Decode(Base64Encode(all.data(), all.size())), all);
}

TEST(ReportPage, EscapesTextAndRendersTables) {
    EXPECT_EQ(HtmlEscape("<a href=\"x\">&'</a>"),
              "&lt;a href=&quot;x&quot;&gt;&amp;&#39;&lt;/a&gt;");
    ReportPage page("title <1>");
    page.AddParagraph("</script><b>");
    page.AddTable({"a", "b"}, {{"1"}, {"2", "<3>"}}, "caption");
    const std::string html = page.Render();
    EXPECT_NE(html.find("<title>title &lt;1&gt;</title>"), std::string::npos);
    EXPECT_EQ(html.find("</script><b>"), std::string::npos);
    EXPECT_NE(html.find("<td>1</td><td></td>"), std::string::npos);  // short row padded
    EXPECT_NE(html.find("<td>&lt;3&gt;</td>"), std::string::npos);
    EXPECT_EQ(html.find("mc-data"), std::string::npos);  // no scene, no viewer data
    EXPECT_EQ(html.find("http"), std::string::npos);     // nothing loaded from a network
}

TEST(ReportPage, ConfusionFiguresOracle) {
    // true a: 8 right, 2 as b; true b: 1 as a, 4 right; true c: nothing, predicted never.
    const std::vector<std::vector<std::size_t>> m = {{8, 2, 0}, {1, 4, 0}, {0, 0, 0}};
    const auto f = ConfusionFigures(m);
    ASSERT_EQ(f.size(), 3u);
    EXPECT_EQ(f[0].support, 10u);
    EXPECT_EQ(f[0].predicted, 9u);
    EXPECT_DOUBLE_EQ(f[0].precision, 8.0 / 9.0);
    EXPECT_DOUBLE_EQ(f[0].recall, 0.8);
    EXPECT_DOUBLE_EQ(f[0].f1, 2 * (8.0 / 9.0) * 0.8 / (8.0 / 9.0 + 0.8));
    EXPECT_DOUBLE_EQ(f[1].precision, 4.0 / 6.0);
    EXPECT_DOUBLE_EQ(f[1].recall, 0.8);
    EXPECT_EQ(f[2].support, 0u);
    EXPECT_DOUBLE_EQ(f[2].f1, 0.0);

    const std::string html = ConfusionMatrixHtml("Per segment", {"a", "b", "c<"}, m);
    EXPECT_NE(html.find("Accuracy 80.0 % (12 of 15)"), std::string::npos) << html;
    EXPECT_NE(html.find("c&lt;"), std::string::npos);
    EXPECT_NE(html.find(">8</td>"), std::string::npos);
    EXPECT_NE(html.find("<td>88.9 %</td>"), std::string::npos);  // precision of a
    EXPECT_TRUE(ConfusionFigures({}).empty());
    EXPECT_THROW(ConfusionFigures({{1, 2}, {3}}), InvalidArgument);
    EXPECT_THROW(ConfusionMatrixHtml("x", {"a"}, {{1, 2}, {3, 4}}), InvalidArgument);
}

TEST(PerceiveReport, ObjectListAndEmbeddedDataMatchTheResult) {
    const auto& s = DemoScene();
    ASSERT_GE(s.result.objects.size(), 3u);
    const auto json = PerceiveResultJson("scene.pcd", s.result);
    ReportParams params;
    params.max_points = 0;  // every finite point
    const std::string html = PerceiveReportPage(s.cloud, s.result, json, params).Render();
    for (const auto& o : s.result.objects) {
        const std::string row = "data-object=\"" + std::to_string(o.id) + "\" data-category=\"" +
                                std::string(CategoryName(o.category.category)) + "\"";
        EXPECT_NE(html.find(row), std::string::npos) << row;
    }
    EXPECT_NE(html.find("<td>normals</td>"), std::string::npos);  // timings table
    const auto data = SceneData(html);
    if (!ReportViewerAvailable()) {
        EXPECT_TRUE(data.is_null());
        EXPECT_NE(html.find("no 3D viewer"), std::string::npos);
        GTEST_SKIP() << "built without the report viewer";
    }
    ASSERT_TRUE(data.is_object());
    EXPECT_EQ(data["format"], "multicue.report-scene/1");
    EXPECT_NE(html.find("three.js"), std::string::npos);
    ASSERT_EQ(data["objects"].size(), s.result.objects.size());
    for (std::size_t k = 0; k < s.result.objects.size(); ++k) {
        const auto& o = s.result.objects[k];
        const auto& oj = data["objects"][k];
        EXPECT_EQ(oj["id"], o.id);
        const auto v = Decode<float>(oj["mesh"]["vertices"]);
        const auto t = Decode<std::uint32_t>(oj["mesh"]["triangles"]);
        ASSERT_EQ(v.size(), 3 * o.model.mesh.vertices.size());
        ASSERT_EQ(t.size(), 3 * o.model.mesh.triangles.size());
        EXPECT_EQ(v[0], o.model.mesh.vertices[0].x());
    }
    EXPECT_EQ(data["support"]["hull"].size(), s.result.support.hull.size());

    // Every finite point, in input order, dequantised within half a step.
    const auto& c = data["cloud"];
    const std::size_t n = c["count"];
    ASSERT_EQ(n, s.cloud.CountFinite());
    const auto q = Decode<std::uint16_t>(c["positions"]);
    const auto rgb = Decode<std::uint8_t>(c["colors"]);
    const auto objects = Decode<std::uint8_t>(c["objects"]);
    const auto cats = Decode<std::uint8_t>(c["categories"]);
    ASSERT_EQ(q.size(), 3 * n);
    ASSERT_EQ(objects.size(), n);
    ASSERT_EQ(cats.size(), n);
    ASSERT_EQ(rgb.size(), 3 * n);
    std::size_t j = 0;
    for (std::size_t i = 0; i < s.cloud.size(); ++i) {
        if (!s.cloud.IsFinite(i)) continue;
        for (int k = 0; k < 3; ++k) {
            const float x = c["origin"][k].get<float>() + q[3 * j + k] * c["scale"][k].get<float>();
            ASSERT_NEAR(x, s.cloud.points[i][k], 0.6 * c["scale"][k].get<float>() + 1e-6);
        }
        ASSERT_EQ(objects[j], s.result.point_objects[i]);
        ASSERT_EQ(cats[j], s.result.point_categories[i]);
        ASSERT_EQ(rgb[3 * j], s.cloud.colors[i].r);
        ++j;
    }
    EXPECT_GT(c["point_size"].get<float>(), 0.0f);
    EXPECT_LT(c["point_size"].get<float>(), 0.05f);
}

TEST(PerceiveReport, ThinningKeepsObjectPointsAndIsDeterministic) {
    const auto& s = DemoScene();
    const auto json = PerceiveResultJson("scene.pcd", s.result);
    std::size_t object_points = 0;
    for (const auto& o : s.result.objects) object_points += o.indices.size();
    ReportParams params;
    params.max_points = object_points + 1000;
    params.models = false;
    const std::string a = PerceiveReportPage(s.cloud, s.result, json, params).Render();
    EXPECT_EQ(a, PerceiveReportPage(s.cloud, s.result, json, params).Render());
    const auto data = SceneData(a);
    if (data.is_null()) GTEST_SKIP() << "built without the report viewer";
    EXPECT_EQ(data["cloud"]["count"], params.max_points);
    EXPECT_FALSE(data["objects"][0].contains("mesh"));
    const auto objects = Decode<std::uint8_t>(data["cloud"]["objects"]);
    std::size_t kept = 0;
    for (const auto id : objects) kept += id != 0;
    EXPECT_EQ(kept, object_points);
}

TEST(PerceiveReport, EmptySceneBadInputAndOutputs) {
    // No objects, no table: a valid page with an empty list.
    PointCloud cloud = test::RandomCloud(500, 7, 0.5f);
    PerceiveResult empty;
    empty.points = cloud.size();
    empty.point_objects.assign(cloud.size(), 0);
    empty.point_categories.assign(cloud.size(), 0);
    const std::string html =
        PerceiveReportPage(cloud, empty, PerceiveResultJson("</script>x", empty)).Render();
    EXPECT_NE(html.find("No objects were found."), std::string::npos);
    EXPECT_NE(html.find("&lt;/script&gt;x"), std::string::npos);
    if (const auto data = SceneData(html); !data.is_null()) {
        EXPECT_EQ(data["cloud"]["count"], 500);
        EXPECT_TRUE(data["support"].is_null());
    }

    PerceiveResult wrong = empty;
    wrong.point_objects.pop_back();
    EXPECT_THROW(PerceiveReportPage(cloud, wrong, PerceiveResultJson("x", wrong)), InvalidArgument);

    // report.html is written with the other outputs, or not at all.
    test::TempDir dir;
    const auto& s = DemoScene();
    const auto json = PerceiveResultJson("scene.pcd", s.result);
    WritePerceiveOutputs(dir / "no", json, PerceiveLabelsCloud(s.cloud, s.result),
                         PerceiveModelsMesh(s.result));
    EXPECT_FALSE(std::filesystem::exists(dir / "no" / "report.html"));
    const std::string page = PerceiveReportPage(s.cloud, s.result, json).Render();
    WritePerceiveOutputs(dir / "yes", json, PerceiveLabelsCloud(s.cloud, s.result),
                         PerceiveModelsMesh(s.result), page);
    EXPECT_EQ(io::ReadFileBytes(dir / "yes" / "report.html"), page);
    WritePerceiveReport(dir / "alone.html", s.cloud, s.result, "scene.pcd");
    EXPECT_TRUE(std::filesystem::exists(dir / "alone.html"));
    EXPECT_THROW(WritePerceiveReport("/dev/null/x.html", s.cloud, s.result), IoError);
}

// Pages written off the stream's path are the pages written in line, in every folder; a page
// that cannot be written is reported by Finish (or the next Submit), and an earlier run's page
// is removed before a folder's new files are written.
TEST(PerceiveReport, WriterThreadWritesThePagesOfAStream) {
    test::TempDir dir;
    const auto& s = DemoScene();
    const auto json = PerceiveResultJson("scene.pcd", s.result);
    const std::string page = PerceiveReportPage(s.cloud, s.result, json).Render();
    {
        ReportWriter writer({}, 1);
        for (int k = 0; k < 4; ++k) {
            const auto frame = dir / ("frame" + std::to_string(k));
            std::filesystem::create_directories(frame);
            writer.Submit(frame, s.cloud, s.result, json);
        }
        writer.Finish();
    }
    for (int k = 0; k < 4; ++k) {
        EXPECT_EQ(io::ReadFileBytes(dir / ("frame" + std::to_string(k)) / "report.html"), page);
    }
    RemoveStaleReport(dir / "frame0");
    EXPECT_FALSE(std::filesystem::exists(dir / "frame0" / "report.html"));
    RemoveStaleReport(dir / "frame0");  // nothing to remove is no error

    ReportWriter failing({});
    failing.Submit(dir / "missing" / "folder", s.cloud, s.result, json);
    EXPECT_THROW(failing.Finish(), IoError);
    failing.Finish();  // reported once
    EXPECT_THROW(ReportWriter({}, 0), InvalidArgument);
}

TEST(PerceiveReport, ConfigSectionReadsAndRejectsUnknownKeys) {
    auto dump = io::ConfigSection::Dump();
    ReportParams defaults;
    ReadReportParams(dump, defaults);
    const std::string text = dump.DumpText();
    EXPECT_NE(text.find("\"report\""), std::string::npos);
    EXPECT_NE(text.find("max_points"), std::string::npos);

    auto set = io::ConfigSection::Parse(
        R"({"report": {"enabled": false, "max_points": 1000, "models": false}})", "r.json");
    ReportParams p;
    ReadReportParams(set, p);
    EXPECT_NO_THROW(set.CheckAllUsed());
    EXPECT_FALSE(p.enabled);
    EXPECT_EQ(p.max_points, 1000u);
    EXPECT_FALSE(p.models);

    auto typo = io::ConfigSection::Parse(R"({"report": {"max_pionts": 5}})", "r.json");
    ReadReportParams(typo, p);
    try {
        typo.CheckAllUsed();
        FAIL() << "unknown key accepted";
    } catch (const InvalidArgument& e) {
        EXPECT_NE(std::string(e.what()).find("max_pionts"), std::string::npos) << e.what();
    }
    auto wrong_type = io::ConfigSection::Parse(R"({"report": {"enabled": "yes"}})", "r.json");
    EXPECT_THROW(ReadReportParams(wrong_type, p), InvalidArgument);
}

}  // namespace
}  // namespace multicue

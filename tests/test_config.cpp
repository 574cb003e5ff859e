#include <gtest/gtest.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/io/config.hpp"
#include "test_util.hpp"

namespace multicue::io {
namespace {

struct Params {
    float radius = 0.02f;
    int k = 20;
    bool organized = false;
    std::string method = "statistical";
    Eigen::Vector3f up{0, 0, 1};
    std::size_t min_points = 10;
};

void Read(ConfigSection& root, Params& p) {
    auto s = root.Section("normals");
    s.Get("radius", p.radius, "neighbourhood radius [m]");
    s.Get("k", p.k, "neighbours");
    s.Get("organized", p.organized);
    root.Get("method", p.method);
    root.Get("up", p.up, "up direction");
    root.Get("min_points", p.min_points);
}

TEST(Config, ReadsValuesAndKeepsDefaults) {
    auto root = ConfigSection::Parse(
        R"({"normals": {"radius": 0.05, // a comment
            "organized": true}, "up": [0, -1, 0]})",
        "test.json");
    Params p;
    Read(root, p);
    root.CheckAllUsed();
    EXPECT_FLOAT_EQ(p.radius, 0.05f);
    EXPECT_EQ(p.k, 20);
    EXPECT_TRUE(p.organized);
    EXPECT_EQ(p.up, Eigen::Vector3f(0, -1, 0));
}

TEST(Config, UnknownKeyIsAnErrorNamingIt) {
    auto root = ConfigSection::Parse(R"({"normals": {"raduis": 0.05}})", "test.json");
    Params p;
    Read(root, p);
    try {
        root.CheckAllUsed();
        FAIL() << "no error";
    } catch (const InvalidArgument& e) {
        EXPECT_NE(std::string(e.what()).find("normals.raduis"), std::string::npos) << e.what();
    }
    auto top = ConfigSection::Parse(R"({"bogus": 1})", "t.json");
    Read(top, p);
    EXPECT_THROW(top.CheckAllUsed(), InvalidArgument);
}

TEST(Config, WrongTypesAndMalformedJson) {
    Params p;
    for (const char* text :
         {R"({"normals": {"k": 2.5}})", R"({"normals": {"organized": 1}})", R"({"up": [1, 2]})",
          R"({"min_points": -3})", R"({"normals": 3})", R"({"method": 7})"}) {
        auto root = ConfigSection::Parse(text, "t.json");
        EXPECT_THROW(Read(root, p), InvalidArgument) << text;
    }
    EXPECT_THROW(ConfigSection::Parse("{ nope", "t.json"), InvalidArgument);
    EXPECT_THROW(ConfigSection::Parse("[1, 2]", "t.json"), InvalidArgument);
    EXPECT_THROW(ConfigSection::Load("/nonexistent/config.json"), IoError);
}

TEST(Config, DumpListsDefaultsWithHelpAndParsesBack) {
    auto dump = ConfigSection::Dump();
    Params p;
    Read(dump, p);
    const std::string text = dump.DumpText();
    EXPECT_NE(text.find("// neighbourhood radius [m]"), std::string::npos) << text;
    EXPECT_NE(text.find("\"radius\": 0.02"), std::string::npos) << text;
    auto again = ConfigSection::Parse(text, "dump");
    Params q;
    q.k = 99;
    Read(again, q);
    again.CheckAllUsed();
    EXPECT_EQ(q.k, 20);
    EXPECT_EQ(q.method, "statistical");
}

}  // namespace
}  // namespace multicue::io

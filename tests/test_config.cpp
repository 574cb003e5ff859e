#include <gtest/gtest.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/io/config.hpp"

#include <array>
#include <string_view>
#include <vector>
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

// A parameter struct that lists its parameters for a visitor, with a nested one and a switch.
struct Inner {
    float distance = 0.02f;
    template <typename V>
    void VisitParams(V& v) {
        v("distance", distance, "axis to axis [m]");
    }
};
struct Step {
    int rows = 5;
    template <typename V>
    void VisitParams(V& v) {
        v("rows", rows, "fewest rows");
    }
};
struct Outer {
    int threads = 0;
    Inner inner;
    Switchable<Step> step;
    std::string kind = "a";
    template <typename V>
    void VisitParams(V& v) {
        v("threads", threads, "worker threads");
        v.Node("inner", inner);
        v.Switch("step", step, "run the step");
        static constexpr std::array<std::string_view, 2> kKinds{"a", "b"};
        v.GetChoice("kind", kind, kKinds, "the kind");
    }
};

TEST(Config, VisitorReadsNodesSwitchesAndChoices) {
    auto root = ConfigSection::Parse(
        R"({"threads": 2, "inner": {"distance": 0.5}, "step": {"enabled": false, "rows": 7},
            "kind": "b"})",
        "v.json");
    Outer o;
    o.VisitParams(root);
    root.CheckAllUsed();
    EXPECT_EQ(o.threads, 2);
    EXPECT_FLOAT_EQ(o.inner.distance, 0.5f);
    EXPECT_FALSE(o.step.enabled);
    EXPECT_EQ(o.step.rows, 7);
    EXPECT_EQ(o.kind, "b");
    auto bad = ConfigSection::Parse(R"({"kind": "c"})", "v.json");
    try {
        o.VisitParams(bad);
        ADD_FAILURE() << "accepted";
    } catch (const InvalidArgument& e) {
        EXPECT_STREQ(e.what(), "v.json: 'kind' must be one of a, b, got 'c'");
    }
    auto dump = ConfigSection::Dump();
    Outer d;
    d.VisitParams(dump);
    EXPECT_EQ(dump.RecordedKeys(), (std::vector<std::string>{"threads", "inner.distance",
                                                             "step.enabled", "step.rows", "kind"}));
    const std::string md = dump.DumpMarkdown();
    EXPECT_NE(md.find("| `threads` | `0` | worker threads |"), std::string::npos) << md;
    EXPECT_NE(md.find("## inner\n"), std::string::npos) << md;
    EXPECT_NE(md.find("| `kind` | `\"a\"` | the kind (a, b) |"), std::string::npos) << md;
}

TEST(Config, FormerKeysMoveToTheirNewPlace) {
    auto root = ConfigSection::Parse(
        R"({"old": {"a": 1, "b": 2}, "flat": 3, "new": {"c": 4}, "keep": {"x": 5, "y": 6}})",
        "r.json");
    root.Rename("old.a", "new.a");        // a value into an existing section
    root.Rename("old", "new");            // the rest of a section merged
    root.Rename("flat", "deep.er.flat");  // sections created on the way
    root.Rename("keep.x", "keep.z");
    root.Rename("missing", "anything");  // absent: nothing happens
    int a = 0, b = 0, c = 0, flat = 0, x = 0, y = 0;
    auto n = root.Section("new");
    n.Get("a", a);
    n.Get("b", b);
    n.Get("c", c);
    root.Section("deep").Section("er").Get("flat", flat);
    auto keep = root.Section("keep");
    keep.Get("z", x);
    keep.Get("y", y);
    EXPECT_NO_THROW(root.CheckAllUsed());  // "old" left no empty section behind
    EXPECT_EQ(std::vector<int>({a, b, c, flat, x, y}), std::vector<int>({1, 2, 4, 3, 5, 6}));
    auto twice = ConfigSection::Parse(R"({"old": {"a": 1}, "new": {"a": 2}})", "t.json");
    EXPECT_THROW(twice.Rename("old", "new"), InvalidArgument);
    auto clash = ConfigSection::Parse(R"({"old": 1, "new": {"a": 2}})", "t.json");
    EXPECT_THROW(clash.Rename("old", "new"), InvalidArgument);
    auto dump = ConfigSection::Dump();
    EXPECT_NO_THROW(dump.Rename("old", "new"));
}

}  // namespace
}  // namespace multicue::io

// `multicue perceive --bag`: a ROS 2 bag written here (SQLite storage, CDR messages as rosbag2
// writes them) is perceived message by message, each with the same result as `perceive` on the
// same frame as a PCD file; bad bags and bad messages give clear errors or logged skips.

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "bag_frames.hpp"
#include "cli_runner.hpp"
#include "multicue/io/pcd.hpp"
#include "multicue/io/point_cloud2.hpp"
#include "multicue/io/ros_messages.hpp"
#include "ros2_bag_writer.hpp"
#include "test_util.hpp"

namespace multicue {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

const std::string kTopic = "/camera/depth_registered/points";

json ReadJson(const fs::path& p) { return json::parse(test::ReadTextFile(p)); }

/// The parts of result.json that depend on the frame only (not on file names or timings).
json Objects(const json& result) {
    json out = json::array();
    for (const auto& o : result.at("objects")) {
        out.push_back({o.at("id"), o.at("category"), o.at("points"), o.at("centroid")});
    }
    return {{"support", result.at("support")}, {"objects", out}};
}

struct BagFixture {
    test::TempDir dir;
    std::vector<io::PointCloud2Message> messages;

    explicit BagFixture(int frames) {
        for (const auto& cloud : test::BagTestFrames(frames, test::SharedDataDir())) {
            auto msg = io::ToPointCloud2(cloud);
            msg.stamp = {1700000000 + static_cast<std::int64_t>(messages.size()), 250000000};
            msg.frame_id = "camera_rgb_optical_frame";
            messages.push_back(std::move(msg));
        }
    }
    std::vector<test::Ros2BagMessage> Records() const {
        std::vector<test::Ros2BagMessage> out;
        for (const auto& m : messages)
            out.push_back({kTopic, m.stamp.Nanoseconds() + 1000, io::EncodePointCloud2Cdr(m)});
        return out;
    }
};

const std::vector<test::Ros2BagTopic> kTopics = {{kTopic, "sensor_msgs/msg/PointCloud2"},
                                                 {"/chatter", "std_msgs/msg/String"}};

TEST(CliBag, PerceivesEveryMessageOfARos2BagAsTheSameFrameFromAFile) {
    BagFixture f(2);
    test::WriteRos2SqliteBag(f.dir / "bag", "bag_0", kTopics, f.Records());
    const auto out = f.dir / "out";
    const auto r = test::RunCli("perceive --no-report --bag " + (f.dir / "bag").string() +
                                " --topic " + kTopic + " --out " + out.string());
    ASSERT_EQ(r.code, 0) << r.output;
    const json index = ReadJson(out / "index.json");
    EXPECT_EQ(index.at("perceived"), 2);
    EXPECT_EQ(index.at("skipped"), 0);
    EXPECT_EQ(index.at("complete"), true);
    for (std::size_t k = 0; k < f.messages.size(); ++k) {
        const std::string stamp = f.messages[k].stamp.ToString();
        EXPECT_EQ(index["messages"][k]["folder"], stamp);
        const json result = ReadJson(out / stamp / "result.json");
        EXPECT_EQ(result["message"]["frame_id"], "camera_rgb_optical_frame");
        EXPECT_EQ(result["message"]["stamp"], stamp);
        EXPECT_TRUE(fs::exists(out / stamp / "labels.pcd"));
        // The same frame as a PCD file through `perceive FILE`.
        const PointCloud cloud = io::FromPointCloud2(f.messages[k]);
        const auto pcd = f.dir / ("frame" + std::to_string(k) + ".pcd");
        io::WritePcd(pcd, cloud);
        const auto ref = f.dir / ("ref" + std::to_string(k));
        const auto rr =
            test::RunCli("perceive --no-report -q " + pcd.string() + " --out " + ref.string());
        ASSERT_EQ(rr.code, 0) << rr.output;
        EXPECT_EQ(Objects(result), Objects(ReadJson(ref / "result.json"))) << stamp;
        EXPECT_GT(result["objects"].size(), 0u) << stamp;
        EXPECT_EQ(test::ReadTextFile(out / stamp / "labels.pcd"),
                  test::ReadTextFile(ref / "labels.pcd"));
    }
}

TEST(CliBag, MissingTopicWrongTypeAndUnknownFilesAreClearErrors) {
    BagFixture f(1);
    test::WriteRos2SqliteBag(f.dir / "bag", "bag_0", kTopics, f.Records());
    const std::string bag = (f.dir / "bag").string();
    const std::string out = " --out " + (f.dir / "out").string();
    auto r = test::RunCli("perceive --bag " + bag + " --topic /nope" + out);
    EXPECT_NE(r.code, 0);
    EXPECT_NE(r.output.find("no topic /nope; the bag has " + kTopic), std::string::npos)
        << r.output;
    r = test::RunCli("perceive --bag " + bag + " --topic /chatter" + out);
    EXPECT_NE(r.code, 0);
    EXPECT_NE(r.output.find("carries std_msgs/msg/String"), std::string::npos) << r.output;
    r = test::RunCli("perceive --bag " + bag + out);
    EXPECT_NE(r.code, 0);
    EXPECT_NE(r.output.find("--bag needs --topic"), std::string::npos) << r.output;
    r = test::RunCli("perceive --bag " + (f.dir / "none.db3").string() + " --topic /x" + out);
    EXPECT_NE(r.code, 0);
    EXPECT_NE(r.output.find("none.db3: no such file"), std::string::npos) << r.output;
    std::ofstream(f.dir / "a.txt") << "text";
    r = test::RunCli("perceive --bag " + (f.dir / "a.txt").string() + " --topic /x" + out);
    EXPECT_NE(r.code, 0);
    EXPECT_NE(r.output.find("not a bag"), std::string::npos) << r.output;
}

TEST(CliBag, BadMessagesAreSkippedAndATruncatedBagStopsWithAnError) {
    BagFixture f(1);
    // Message 0: no x/y/z fields; message 1: data shorter than its layout; message 2: good.
    auto no_xyz = f.messages[0];
    for (auto& field : no_xyz.fields) field.name = "_" + field.name;
    auto cut = f.messages[0];
    cut.data.resize(cut.data.size() / 2);
    cut.stamp.sec += 1;
    auto good = f.messages[0];
    good.stamp.sec += 2;
    std::vector<test::Ros2BagMessage> records;
    std::int64_t t = 1;
    for (const auto* m : {&no_xyz, &cut, &good})
        records.push_back({kTopic, t++, io::EncodePointCloud2Cdr(*m)});
    test::McapWriter writer;
    test::WriteBytes(f.dir / "mixed.mcap", writer.Build(kTopics, records));
    const auto out = f.dir / "out";
    auto r = test::RunCli("perceive --no-report --bag " + (f.dir / "mixed.mcap").string() +
                          " --topic " + kTopic + " --out " + out.string());
    ASSERT_EQ(r.code, 0) << r.output;
    EXPECT_NE(r.output.find("no x/y/z fields"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("truncated"), std::string::npos) << r.output;
    json index = ReadJson(out / "index.json");
    EXPECT_EQ(index["perceived"], 1);
    EXPECT_EQ(index["skipped"], 2);
    EXPECT_TRUE(fs::exists(out / good.stamp.ToString() / "result.json"));

    // Only bad messages: an error.
    records.pop_back();
    test::WriteBytes(f.dir / "bad.mcap", writer.Build(kTopics, records));
    r = test::RunCli("perceive --no-report --bag " + (f.dir / "bad.mcap").string() + " --topic " +
                     kTopic + " --out " + (f.dir / "out2").string());
    EXPECT_NE(r.code, 0);
    EXPECT_NE(r.output.find("no message on " + kTopic + " could be perceived"), std::string::npos)
        << r.output;

    // A bag cut short: the message before the cut is perceived, then a non-zero exit.
    records = {{kTopic, 1, io::EncodePointCloud2Cdr(good)},
               {kTopic, 2, io::EncodePointCloud2Cdr(good)}};
    auto bytes = writer.Build(kTopics, records);
    bytes.resize(bytes.size() * 3 / 4);
    test::WriteBytes(f.dir / "cut.mcap", bytes);
    r = test::RunCli("perceive --no-report --bag " + (f.dir / "cut.mcap").string() + " --topic " +
                     kTopic + " --out " + (f.dir / "out3").string());
    EXPECT_NE(r.code, 0);
    EXPECT_NE(r.output.find("truncated"), std::string::npos) << r.output;
    index = ReadJson(f.dir / "out3" / "index.json");
    EXPECT_EQ(index["perceived"], 1);
    EXPECT_EQ(index["complete"], false);
}

}  // namespace
}  // namespace multicue

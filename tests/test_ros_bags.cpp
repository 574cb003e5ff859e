// ROS 2 bags without ROS: rosbag2's SQLite storage and MCAP, written here as rosbag2 writes them
// and read back; the real bags of the shared data (std_msgs/String, test_msgs/BasicTypes in
// SQLite and zstd-compressed MCAP); truncated and foreign files.

#include <fstream>

#include <gtest/gtest.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/io/bag.hpp"
#include "multicue/io/cdr.hpp"
#include "multicue/io/ros_messages.hpp"
#include "ros2_bag_writer.hpp"
#include "test_util.hpp"

namespace multicue {
namespace {

namespace fs = std::filesystem;

/// Three point clouds on /points and a string on /chatter between them.
std::vector<test::Ros2BagMessage> SampleMessages() {
    std::vector<test::Ros2BagMessage> out;
    for (int k = 0; k < 3; ++k) {
        PointCloud c = test::RandomCloud(50 + 10 * k, 10 + k);
        auto msg = io::ToPointCloud2(c);
        msg.stamp = {1000 + k, 500u * k};
        msg.frame_id = "camera";
        const std::int64_t t = 2'000'000'000LL + k * 100'000'000LL;
        out.push_back({"/points", t, io::EncodePointCloud2Cdr(msg, k == 1)});
        io::CdrWriter w;
        w.String("hello " + std::to_string(k));
        out.push_back({"/chatter", t + 1, w.bytes()});
    }
    return out;
}

const std::vector<test::Ros2BagTopic> kTopics = {{"/points", "sensor_msgs/msg/PointCloud2"},
                                                 {"/chatter", "std_msgs/msg/String"}};

void ExpectSampleClouds(io::BagReader& bag) {
    const io::BagTopic* topic = bag.FindTopic("/points");
    ASSERT_NE(topic, nullptr);
    EXPECT_EQ(topic->messages, 3u);
    EXPECT_EQ(topic->serialization, "cdr");
    io::BagMessage m;
    int k = 0;
    while (bag.Next(m)) {
        ASSERT_EQ(m.topic, "/points");
        const auto msg = io::DecodePointCloud2(*topic, m.data, "test");
        EXPECT_EQ(msg.stamp.sec, 1000 + k);
        EXPECT_EQ(msg.frame_id, "camera");
        const PointCloud cloud = io::FromPointCloud2(msg);
        const PointCloud expected = test::RandomCloud(50 + 10 * k, 10 + k);
        EXPECT_EQ(cloud.points, expected.points);
        ++k;
    }
    EXPECT_EQ(k, 3);
}

TEST(Ros2Bag, ReadsTheSqliteStorageAsRosbag2WritesIt) {
    test::TempDir dir;
    test::WriteRos2SqliteBag(dir / "bag", "bag_0", kTopics, SampleMessages());
    for (const fs::path& p : {dir / "bag", dir / "bag" / "bag_0.db3"}) {
        EXPECT_TRUE(io::IsRos2BagPath(p));
        auto bag = io::OpenRos2Bag(p, {"/points"});
        EXPECT_EQ(bag->Topics().size(), 2u);
        EXPECT_EQ(bag->CountMessages({"/points"}), 3u);
        ExpectSampleClouds(*bag);
    }
    // All topics, in time order.
    auto bag = io::OpenRos2Bag(dir / "bag");
    io::BagMessage m;
    std::vector<std::string> order;
    while (bag->Next(m)) order.push_back(m.topic);
    EXPECT_EQ(order.size(), 6u);
    EXPECT_EQ(order[1], "/chatter");
    // The string topic is no point cloud.
    const auto* chatter = bag->FindTopic("/chatter");
    ASSERT_NE(chatter, nullptr);
    EXPECT_THROW(io::DecodePointCloud2(*chatter, m.data, "chatter"), FormatError);
}

TEST(Ros2Bag, ReadsMcapWithAndWithoutSummary) {
    test::TempDir dir;
    for (const bool summary : {true, false}) {
        test::McapWriter writer;
        test::WriteBytes(dir / "bag.mcap", writer.Build(kTopics, SampleMessages(), summary));
        auto bag = io::OpenRos2Bag(dir / "bag.mcap", {"/points"});
        ExpectSampleClouds(*bag);
    }
}

TEST(Ros2Bag, TruncatedFilesAreFormatErrorsAfterTheMessagesBefore) {
    test::TempDir dir;
    test::McapWriter writer;
    auto bytes = writer.Build(kTopics, SampleMessages());
    bytes.resize(bytes.size() * 2 / 3);
    test::WriteBytes(dir / "cut.mcap", bytes);
    auto bag = io::OpenRos2Bag(dir / "cut.mcap", {"/points"});
    io::BagMessage m;
    int delivered = 0;
    try {
        while (bag->Next(m)) ++delivered;
        ADD_FAILURE() << "no error for a truncated MCAP file";
    } catch (const FormatError& e) {
        EXPECT_NE(std::string(e.what()).find("truncated"), std::string::npos) << e.what();
    }
    EXPECT_GE(delivered, 1);
    EXPECT_LT(delivered, 3);

    // SQLite: a file cut in half is refused when opened or read.
    test::WriteRos2SqliteBag(dir / "db", "db_0", kTopics, SampleMessages());
    std::string db;
    {
        std::ifstream in(dir / "db" / "db_0.db3", std::ios::binary);
        db.assign(std::istreambuf_iterator<char>(in), {});
    }
    {
        std::ofstream out(dir / "cut.db3", std::ios::binary);
        out.write(db.data(), static_cast<std::streamsize>(db.size() / 2));
    }
    EXPECT_THROW(
        {
            auto cut = io::OpenRos2Bag(dir / "cut.db3");
            while (cut->Next(m)) {
            }
        },
        FormatError);
}

TEST(Ros2Bag, MissingAndForeignFiles) {
    test::TempDir dir;
    EXPECT_THROW(io::OpenRos2Bag(dir / "none.db3"), IoError);
    EXPECT_THROW(io::OpenRos2Bag(dir.path()), IoError);  // a folder without storage files
    std::ofstream(dir / "text.db3") << "not a database, just text that is long enough........";
    EXPECT_THROW(io::OpenRos2Bag(dir / "text.db3"), FormatError);
    std::ofstream(dir / "text.mcap") << "not mcap";
    EXPECT_THROW(io::OpenRos2Bag(dir / "text.mcap"), FormatError);
    std::ofstream(dir / "x.pcd") << "x";
    EXPECT_FALSE(io::IsRos2BagPath(dir / "x.pcd"));
    EXPECT_THROW(io::OpenRos2Bag(dir / "x.pcd"), IoError);
}

// --- the real bags of the shared data (rosbag2's own test bags) ---------------------------------

std::vector<std::string> TalkerStrings(const fs::path& path) {
    auto bag = io::OpenRos2Bag(path, {"/topic"});
    const auto* topic = bag->FindTopic("/topic");
    EXPECT_NE(topic, nullptr);
    if (topic == nullptr) return {};
    EXPECT_EQ(topic->type, "std_msgs/msg/String");
    EXPECT_EQ(topic->messages, 10u);
    EXPECT_NE(bag->FindTopic("/rosout"), nullptr);
    std::vector<std::string> out;
    io::BagMessage m;
    while (bag->Next(m)) out.push_back(io::DecodeStringCdr(m.data, path.string()));
    return out;
}

TEST(Ros2Bag, SharedTalkerBagsInSqliteAndZstdMcap) {
    if (!test::HasSharedData()) GTEST_SKIP() << "shared data not found";
    const auto base = test::SharedData("bags/ros2");
    const auto sqlite = TalkerStrings(base / "sqlite3-talker");
    const auto mcap = TalkerStrings(base / "mcap-talker" / "talker.mcap");
    ASSERT_EQ(sqlite.size(), 10u);
    EXPECT_EQ(sqlite.front(), "Hello, world! 0");
    EXPECT_EQ(sqlite.back(), "Hello, world! 9");
    EXPECT_EQ(sqlite, mcap);
}

TEST(Ros2Bag, SharedBasicTypesDecodeWithCdrAlignment) {
    if (!test::HasSharedData()) GTEST_SKIP() << "shared data not found";
    const auto base = test::SharedData("bags/ros2");
    for (const fs::path& p : {base / "sqlite3-cdr_test", base / "mcap-cdr_test"}) {
        auto bag = io::OpenRos2Bag(p, {"/test_topic"});
        ASSERT_NE(bag->FindTopic("/array_topic"), nullptr);
        EXPECT_EQ(bag->FindTopic("/array_topic")->type, "test_msgs/msg/Arrays");
        io::BagMessage m;
        int n = 0;
        while (bag->Next(m)) {
            // test_msgs/BasicTypes: bool byte char float32 float64 int8 uint8 int16 uint16
            // int32 uint32 int64 uint64.
            io::CdrReader r(m.data, p.string());
            r.Bool(), r.U8(), r.U8();
            r.F32();
            r.F64();
            r.I8(), r.U8(), r.I16(), r.U16();
            EXPECT_EQ(r.I32(), 123);
            r.U32();
            r.I64();
            r.U64();
            EXPECT_EQ(r.remaining(), 0u);
            ++n;
        }
        EXPECT_EQ(n, 3) << p;
    }
}

}  // namespace
}  // namespace multicue

// ROS 1 bags: written by librosbag (ros_test_tool write-bag), read by multicue::ros1_bag and by
// `multicue perceive --bag`; a truncated bag is a clear error.

#include <algorithm>
#include <cstdlib>
#include <fstream>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "cli_runner.hpp"
#include "multicue/core/exceptions.hpp"
#include "multicue/io/ros1_bag.hpp"
#include "multicue/io/ros_messages.hpp"
#include "test_util.hpp"

namespace multicue {
namespace {

namespace fs = std::filesystem;
const std::string kTopic = "/camera/depth_registered/points";

int Run(const std::string& command) { return std::system((command + " >/dev/null").c_str()); }

/// Two simulated frames (no shared data: small and the same everywhere) in DIR/test.bag, chunks
/// compressed with `compression` (none, lz4 or bz2).
fs::path WriteBag(const test::TempDir& dir, const std::string& compression = "none") {
    if (!fs::exists(dir / "frames")) {
        EXPECT_EQ(Run(std::string(MULTICUE_ROS_TEST_DATA) + " frames " + (dir / "frames").string() +
                      " 2 /nonexistent"),
                  0);
    }
    const fs::path bag = dir / ("test_" + compression + ".bag");
    EXPECT_EQ(Run(std::string(MULTICUE_ROS_TEST_TOOL) + " write-bag " + (dir / "frames").string() +
                  " " + bag.string() + " " + kTopic + " 0.5 " + compression),
              0);
    return bag;
}

class Ros1BagCompression : public testing::TestWithParam<std::string> {};

TEST_P(Ros1BagCompression, ReadsWhatLibrosbagWrote) {
    test::TempDir dir;
    const fs::path bag_path = WriteBag(dir, GetParam());
    auto bag = io::OpenRos1Bag(bag_path, {kTopic});
    const io::BagTopic* topic = bag->FindTopic(kTopic);
    ASSERT_NE(topic, nullptr);
    EXPECT_EQ(topic->type, "sensor_msgs/PointCloud2");
    EXPECT_EQ(topic->serialization, "ros1");
    EXPECT_EQ(topic->messages, 2u);
    io::BagMessage m;
    int k = 0;
    while (bag->Next(m)) {
        const auto msg = io::DecodePointCloud2(*topic, m.data, "bag");
        EXPECT_EQ(msg.frame_id, "camera_rgb_optical_frame");
        EXPECT_EQ(msg.stamp.sec, 1700000000);
        EXPECT_EQ(msg.stamp.nanosec, k == 0 ? 0u : 500000000u);
        // The same bytes as the frame file the bag was written from.
        std::ifstream in(dir / "frames" / ("frame_00" + std::to_string(k) + ".ros1"),
                         std::ios::binary);
        const std::vector<std::uint8_t> file((std::istreambuf_iterator<char>(in)), {});
        const auto original = io::DecodePointCloud2Ros1(file, "file");
        EXPECT_EQ(msg.data, original.data);
        EXPECT_EQ(msg.fields, original.fields);
        EXPECT_GT(io::FromPointCloud2(msg).CountFinite(), 1000u);
        ++k;
    }
    EXPECT_EQ(k, 2);
    // Another topic selected: no messages.
    auto other = io::OpenRos1Bag(bag_path, {"/other"});
    EXPECT_FALSE(other->Next(m));
}

INSTANTIATE_TEST_SUITE_P(Chunks, Ros1BagCompression, testing::Values("none", "lz4", "bz2"));

// Every length in a bag is checked before it is used: a bag with a byte of a record header
// changed reads or fails with a FormatError, never more (the fuzz target ros1_bag changes bytes
// at random).
TEST(Ros1Bag, DamagedLengthsAreFormatErrors) {
    test::TempDir dir;
    const fs::path bag = WriteBag(dir);
    std::ifstream in(bag, std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), {});
    // The record headers: the bag header, the first connection, chunk and message at the start,
    // the index (connections, chunk infos) at the end.
    std::vector<std::size_t> positions;
    for (std::size_t at = 13; at < std::min<std::size_t>(bytes.size(), 5000); at += 37)
        positions.push_back(at);
    for (std::size_t at = bytes.size() > 2000 ? bytes.size() - 2000 : 13; at < bytes.size();
         at += 23)
        positions.push_back(at);
    for (const std::size_t at : positions) {
        std::string damaged = bytes;
        damaged[at] = static_cast<char>(damaged[at] ^ 0xA5);
        std::ofstream(dir / "damaged.bag", std::ios::binary) << damaged;
        try {
            auto b = io::OpenRos1Bag(dir / "damaged.bag");
            io::BagMessage m;
            while (b->Next(m)) {
            }
        } catch (const FormatError&) {
        }
    }
}

TEST(Ros1Bag, PerceiveReadsTheBagAndRefusesATruncatedOne) {
    test::TempDir dir;
    const fs::path bag = WriteBag(dir);
    auto r = test::RunCli("perceive --no-report --bag " + bag.string() + " --topic " + kTopic +
                          " --out " + (dir / "out").string());
    ASSERT_EQ(r.code, 0) << r.output;
    std::ifstream in(dir / "out" / "index.json");
    const auto index = nlohmann::json::parse(in);
    EXPECT_EQ(index["perceived"], 2);
    EXPECT_TRUE(fs::exists(dir / "out" / "1700000000.500000000" / "result.json"));

    // Cut: the index at the end is gone, the file is refused.
    const auto size = fs::file_size(bag);
    fs::copy_file(bag, dir / "cut.bag");
    fs::resize_file(dir / "cut.bag", size * 2 / 3);
    EXPECT_THROW(
        {
            auto cut = io::OpenRos1Bag(dir / "cut.bag");
            io::BagMessage m;
            while (cut->Next(m)) {
            }
        },
        FormatError);
    r = test::RunCli("perceive --no-report --bag " + (dir / "cut.bag").string() + " --topic " +
                     kTopic + " --out " + (dir / "out2").string());
    EXPECT_NE(r.code, 0);
    EXPECT_NE(r.output.find("cut.bag"), std::string::npos) << r.output;
    EXPECT_THROW(io::OpenRos1Bag(dir / "none.bag"), IoError);
}

}  // namespace
}  // namespace multicue

// ROS 1 bags: written by librosbag (ros_test_tool write-bag), read by multicue::ros1_bag and by
// `multicue perceive --bag`; a truncated bag is a clear error.

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

/// Two simulated frames (no shared data: small and the same everywhere) in DIR/test.bag.
fs::path WriteBag(const test::TempDir& dir) {
    EXPECT_EQ(Run(std::string(MULTICUE_ROS_TEST_DATA) + " frames " + (dir / "frames").string() +
                  " 2 /nonexistent"),
              0);
    const fs::path bag = dir / "test.bag";
    EXPECT_EQ(Run(std::string(MULTICUE_ROS_TEST_TOOL) + " write-bag " + (dir / "frames").string() +
                  " " + bag.string() + " " + kTopic + " 0.5"),
              0);
    return bag;
}

TEST(Ros1Bag, ReadsWhatLibrosbagWrote) {
    test::TempDir dir;
    const fs::path bag_path = WriteBag(dir);
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

    // Cut: the index at the end is gone, librosbag refuses the file.
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

// The ROS side of the node test (C++17, as ROS 1's message headers need):
//   ros_test_tool write-bag FRAMES_DIR OUT.bag TOPIC PERIOD_S [none|lz4|bz2]
//       frames (ROS 1 serialised PointCloud2 files, frame_*.ros1, in name order) into a bag,
//       PERIOD_S apart, each stamped with its recording time; chunks compressed as given
//   ros_test_tool collect OUT_DIR COUNT TIMEOUT_S
//       subscribes to /multicue_node/{labelled_cloud,markers,result,stats}; writes each labelled
//       cloud (<stamp>.labels.ros1), its markers (<stamp>.markers.json) and result
//       (<stamp>.result.json) until COUNT clouds came or TIMEOUT_S passed, then stats.json
//   ros_test_tool call-task TASK_JSON
//       calls /multicue_node/run_task and prints {"ok": ..., "result": ...}
//   ros_test_tool publish FRAMES_DIR TOPIC RATE_HZ REPEAT
//       publishes the frames REPEAT times at RATE_HZ (faster than the node: it must drop)
//   ros_test_tool publish-bad TOPIC
//       publishes a cloud without x/y/z fields and one whose data is shorter than its layout

#include <ros/ros.h>
#include <rosbag/bag.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <mutex>
#include <string>
#include <vector>

#include <sensor_msgs/PointCloud2.h>
#include <std_msgs/String.h>
#include <visualization_msgs/MarkerArray.h>
#include <nlohmann/json.hpp>

#include "multicue/RunTask.h"

namespace fs = std::filesystem;

namespace {

std::vector<fs::path> FrameFiles(const fs::path& dir) {
    std::vector<fs::path> files;
    for (const auto& e : fs::directory_iterator(dir)) {
        if (e.path().extension() == ".ros1") files.push_back(e.path());
    }
    std::sort(files.begin(), files.end());
    return files;
}

sensor_msgs::PointCloud2 ReadFrame(const fs::path& file) {
    std::ifstream in(file, std::ios::binary);
    std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)),
                                    std::istreambuf_iterator<char>());
    sensor_msgs::PointCloud2 msg;
    ros::serialization::IStream stream(bytes.data(), static_cast<std::uint32_t>(bytes.size()));
    ros::serialization::deserialize(stream, msg);
    return msg;
}

template <typename M>
void WriteMessage(const fs::path& file, const M& msg) {
    const std::uint32_t n = ros::serialization::serializationLength(msg);
    std::vector<std::uint8_t> bytes(n);
    ros::serialization::OStream stream(bytes.data(), n);
    ros::serialization::serialize(stream, msg);
    std::ofstream out(file, std::ios::binary);
    out.write(reinterpret_cast<const char*>(bytes.data()), n);
}

std::string Stamp(const ros::Time& t) {
    char buf[64];
    std::snprintf(buf, sizeof(buf), "%u.%09u", t.sec, t.nsec);
    return buf;
}

int WriteBag(const fs::path& frames, const std::string& out, const std::string& topic,
             double period, const std::string& compression) {
    rosbag::Bag bag(out, rosbag::bagmode::Write);
    if (compression == "lz4") bag.setCompression(rosbag::compression::LZ4);
    if (compression == "bz2") bag.setCompression(rosbag::compression::BZ2);
    ros::Time t(1700000000, 0);
    for (const auto& f : FrameFiles(frames)) {
        sensor_msgs::PointCloud2 msg = ReadFrame(f);
        msg.header.stamp = t;
        bag.write(topic, t, msg);
        t += ros::Duration(period);
    }
    bag.close();
    return 0;
}

int Collect(int argc, char** argv, const fs::path& dir, int count, double timeout) {
    ros::init(argc, argv, "multicue_test_collect", ros::init_options::AnonymousName);
    ros::NodeHandle nh;
    fs::create_directories(dir);
    std::mutex mutex;
    int clouds = 0;
    std::string last_stats;
    auto on_cloud = [&](const sensor_msgs::PointCloud2ConstPtr& msg) {
        WriteMessage(dir / (Stamp(msg->header.stamp) + ".labels.ros1"), *msg);
        std::lock_guard<std::mutex> lock(mutex);
        ++clouds;
    };
    auto on_markers = [&](const visualization_msgs::MarkerArrayConstPtr& msg) {
        nlohmann::json j = {{"texts", nlohmann::json::array()}, {"triangles", 0}};
        std::string stamp;
        for (const auto& m : msg->markers) {
            if (m.action == visualization_msgs::Marker::DELETEALL) continue;
            stamp = Stamp(m.header.stamp);
            j["frame_id"] = m.header.frame_id;
            if (m.type == visualization_msgs::Marker::TRIANGLE_LIST) {
                j["triangles"] = m.points.size() / 3;
            } else if (m.type == visualization_msgs::Marker::TEXT_VIEW_FACING) {
                j["texts"].push_back(
                    {{"id", m.id},
                     {"text", m.text},
                     {"position", {m.pose.position.x, m.pose.position.y, m.pose.position.z}}});
            }
        }
        if (stamp.empty()) stamp = Stamp(msg->markers.front().header.stamp);
        std::ofstream(dir / (stamp + ".markers.json")) << j.dump(1);
    };
    auto on_result = [&](const std_msgs::StringConstPtr& msg) {
        const auto j = nlohmann::json::parse(msg->data);
        std::ofstream(dir / (j["message"]["stamp"].get<std::string>() + ".result.json"))
            << msg->data;
    };
    auto on_stats = [&](const std_msgs::StringConstPtr& msg) {
        std::lock_guard<std::mutex> lock(mutex);
        last_stats = msg->data;
    };
    auto s1 = nh.subscribe<sensor_msgs::PointCloud2>("/multicue_node/labelled_cloud", 10, on_cloud);
    auto s2 =
        nh.subscribe<visualization_msgs::MarkerArray>("/multicue_node/markers", 10, on_markers);
    auto s3 = nh.subscribe<std_msgs::String>("/multicue_node/result", 10, on_result);
    auto s4 = nh.subscribe<std_msgs::String>("/multicue_node/stats", 10, on_stats);
    std::ofstream(dir / "ready");
    const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(timeout);
    while (ros::ok() && ros::WallTime::now() < end) {
        ros::spinOnce();
        {
            std::lock_guard<std::mutex> lock(mutex);
            if (clouds >= count) break;
        }
        ros::WallDuration(0.01).sleep();
    }
    // Let the markers and result of the last cloud arrive.
    const ros::WallTime settle = ros::WallTime::now() + ros::WallDuration(1.0);
    while (ros::ok() && ros::WallTime::now() < settle) {
        ros::spinOnce();
        ros::WallDuration(0.01).sleep();
    }
    std::ofstream(dir / "stats.json") << (last_stats.empty() ? "{}" : last_stats);
    std::cout << "collected " << clouds << " labelled clouds\n";
    return clouds >= count ? 0 : 1;
}

int CallTask(int argc, char** argv, const std::string& task) {
    ros::init(argc, argv, "multicue_test_task", ros::init_options::AnonymousName);
    multicue::RunTask srv;
    srv.request.task = task;
    if (!ros::service::waitForService("/multicue_node/run_task", ros::Duration(20.0)) ||
        !ros::service::call("/multicue_node/run_task", srv)) {
        std::cerr << "run_task: service not available\n";
        return 1;
    }
    std::cout << nlohmann::json(
                     {{"ok", static_cast<bool>(srv.response.ok)}, {"result", srv.response.result}})
                     .dump()
              << "\n";
    return 0;
}

int Publish(int argc, char** argv, const fs::path& frames, const std::string& topic, double rate,
            int repeat) {
    ros::init(argc, argv, "multicue_test_publish", ros::init_options::AnonymousName);
    ros::NodeHandle nh;
    auto pub = nh.advertise<sensor_msgs::PointCloud2>(topic, 1);
    std::vector<sensor_msgs::PointCloud2> msgs;
    for (const auto& f : FrameFiles(frames)) msgs.push_back(ReadFrame(f));
    const ros::WallTime wait_end = ros::WallTime::now() + ros::WallDuration(10.0);
    while (pub.getNumSubscribers() == 0 && ros::WallTime::now() < wait_end)
        ros::WallDuration(0.05).sleep();
    ros::WallRate loop(rate);
    const ros::WallTime start = ros::WallTime::now();
    int sent = 0;
    for (int r = 0; r < repeat; ++r) {
        for (auto& m : msgs) {
            m.header.stamp = ros::Time::now();
            pub.publish(m);
            ++sent;
            loop.sleep();
        }
    }
    const double dt = (ros::WallTime::now() - start).toSec();
    ros::WallDuration(0.5).sleep();
    std::cout << "published " << sent << " clouds in " << dt << " s (" << sent / dt << " Hz)\n";
    return 0;
}

int PublishBad(int argc, char** argv, const std::string& topic) {
    ros::init(argc, argv, "multicue_test_bad", ros::init_options::AnonymousName);
    ros::NodeHandle nh;
    auto pub = nh.advertise<sensor_msgs::PointCloud2>(topic, 1);
    const ros::WallTime wait_end = ros::WallTime::now() + ros::WallDuration(10.0);
    while (pub.getNumSubscribers() == 0 && ros::WallTime::now() < wait_end)
        ros::WallDuration(0.05).sleep();
    sensor_msgs::PointCloud2 msg;
    msg.header.frame_id = "bad";
    msg.height = 1;
    msg.width = 10;
    sensor_msgs::PointField f;
    f.name = "intensity";
    f.datatype = sensor_msgs::PointField::FLOAT32;
    f.count = 1;
    msg.fields = {f};
    msg.point_step = 4;
    msg.row_step = 40;
    msg.data.assign(40, 0);
    msg.header.stamp = ros::Time::now();
    pub.publish(msg);  // no x/y/z
    ros::WallDuration(0.5).sleep();
    for (const char* name : {"x", "y", "z"}) {
        f.name = name;
        f.offset = static_cast<std::uint32_t>(msg.fields.size() * 4);
        msg.fields.push_back(f);
    }
    msg.point_step = 16;
    msg.row_step = 160;
    msg.data.assign(100, 0);  // shorter than 10 points of 16 bytes
    msg.header.stamp = ros::Time::now();
    pub.publish(msg);
    ros::WallDuration(0.5).sleep();
    std::cout << "published 2 bad clouds\n";
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    const std::vector<std::string> args(argv + 1, argv + argc);
    try {
        if ((args.size() == 5 || args.size() == 6) && args[0] == "write-bag")
            return WriteBag(args[1], args[2], args[3], std::stod(args[4]),
                            args.size() == 6 ? args[5] : "none");
        if (args.size() == 4 && args[0] == "collect")
            return Collect(argc, argv, args[1], std::stoi(args[2]), std::stod(args[3]));
        if (args.size() == 2 && args[0] == "call-task") return CallTask(argc, argv, args[1]);
        if (args.size() == 2 && args[0] == "publish-bad") return PublishBad(argc, argv, args[1]);
        if (args.size() == 5 && args[0] == "publish")
            return Publish(argc, argv, args[1], args[2], std::stod(args[3]), std::stoi(args[4]));
    } catch (const std::exception& e) {
        std::cerr << "ros_test_tool: " << e.what() << "\n";
        return 1;
    }
    std::cerr << "usage: see the comment at the top of ros_test_tool.cpp\n";
    return 2;
}

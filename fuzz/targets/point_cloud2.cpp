// One serialised sensor_msgs/PointCloud2 message as a bag or a subscription delivers it: the
// first byte picks ROS 2's CDR or ROS 1's serialisation, the rest is the message, which is decoded
// and converted to a cloud (any field layout, byte order, padding) and back.

#include "multicue/io/point_cloud2.hpp"
#include "fuzz_target.hpp"
#include "multicue/io/bag.hpp"
#include "multicue/io/ros_messages.hpp"

MULTICUE_FUZZ_TARGET(point_cloud2) {
    using namespace multicue;
    if (size == 0) return;
    io::BagTopic topic;
    topic.name = "/points";
    const bool ros1 = (data[0] & 1) != 0;
    topic.type = ros1 ? io::kPointCloud2Ros1Type : io::kPointCloud2Ros2Type;
    topic.serialization = ros1 ? "ros1" : "cdr";
    fuzz::AllowTypedErrors([&] {
        const auto message = io::DecodePointCloud2(topic, {data + 1, size - 1}, "message");
        const PointCloud cloud = io::FromPointCloud2(message, "message");
        (void)io::ToPointCloud2(cloud);
    });
}

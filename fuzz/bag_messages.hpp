#pragma once
// Shared by the bag fuzz targets: every message of an opened bag read, point clouds decoded and
// converted as `perceive --bag` does.

#include <cstddef>

#include "fuzz_target.hpp"
#include "multicue/io/bag.hpp"
#include "multicue/io/point_cloud2.hpp"
#include "multicue/io/ros_messages.hpp"

namespace multicue::fuzz {

inline void ReadEveryMessage(io::BagReader& bag) {
    (void)bag.DescribeTopics();
    io::BagMessage message;
    for (std::size_t n = 0; n < 10000 && bag.Next(message); ++n) {
        const io::BagTopic* topic = bag.FindTopic(message.topic);
        if (topic == nullptr || !io::IsPointCloud2Type(topic->type)) continue;
        AllowTypedErrors([&] {
            io::FromPointCloud2(io::DecodePointCloud2(*topic, message.data, "bag"), "bag");
        });
    }
}

}  // namespace multicue::fuzz

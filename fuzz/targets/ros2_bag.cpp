// ROS 2 bags as `perceive --bag` reads them: the first byte picks the storage (an SQLite .db3
// file or an .mcap file), the rest is the file. Every message is read; point cloud messages are
// decoded and converted to a cloud as perceive does.

#include <cstddef>

#include "fuzz_target.hpp"
#include "multicue/io/bag.hpp"
#include "multicue/io/point_cloud2.hpp"
#include "multicue/io/ros_messages.hpp"

MULTICUE_FUZZ_TARGET(ros2_bag) {
    using namespace multicue;
    if (size == 0) return;
    const auto path = fuzz::WriteInput(fuzz::Bytes(data + 1, size - 1),
                                       (data[0] & 1) != 0 ? "input.mcap" : "input.db3");
    fuzz::AllowTypedErrors([&] {
        const auto bag = io::OpenRos2Bag(path);
        (void)bag->DescribeTopics();
        io::BagMessage message;
        for (std::size_t n = 0; n < 10000 && bag->Next(message); ++n) {
            const io::BagTopic* topic = bag->FindTopic(message.topic);
            if (topic == nullptr || !io::IsPointCloud2Type(topic->type)) continue;
            fuzz::AllowTypedErrors([&] {
                io::FromPointCloud2(io::DecodePointCloud2(*topic, message.data, "bag"), "bag");
            });
        }
    });
}

// ROS 1 bags (librosbag) as `perceive --bag` reads them: every message, point clouds decoded and
// converted. librosbag is Debian's build, without coverage instrumentation: this target mostly
// checks what multicue does with what librosbag returns, and that librosbag's own exceptions
// reach the user as multicue's errors.

#include <cstddef>

#include "fuzz_target.hpp"
#include "multicue/io/point_cloud2.hpp"
#include "multicue/io/ros1_bag.hpp"
#include "multicue/io/ros_messages.hpp"

MULTICUE_FUZZ_TARGET(ros1_bag) {
    using namespace multicue;
    const auto path = fuzz::WriteInput(fuzz::Bytes(data, size), "input.bag");
    fuzz::AllowTypedErrors([&] {
        const auto bag = io::OpenRos1Bag(path);
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

// ROS 1 bags as `perceive --bag` reads them: every message, point clouds decoded and converted.

#include "multicue/io/ros1_bag.hpp"
#include "bag_messages.hpp"
#include "fuzz_target.hpp"

MULTICUE_FUZZ_TARGET(ros1_bag) {
    using namespace multicue;
    const auto path = fuzz::WriteInput(fuzz::Bytes(data, size), "input.bag");
    fuzz::AllowTypedErrors([&] { fuzz::ReadEveryMessage(*io::OpenRos1Bag(path)); });
}

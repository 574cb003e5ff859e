// ROS 2 bags as `perceive --bag` reads them: the first byte picks the storage (an SQLite .db3
// file or an .mcap file), the rest is the file. Every message is read; point cloud messages are
// decoded and converted to a cloud as perceive does.

#include "bag_messages.hpp"
#include "fuzz_target.hpp"
#include "multicue/io/bag.hpp"

MULTICUE_FUZZ_TARGET(ros2_bag) {
    using namespace multicue;
    if (size == 0) return;
    const auto path = fuzz::WriteInput(fuzz::Bytes(data + 1, size - 1),
                                       (data[0] & 1) != 0 ? "input.mcap" : "input.db3");
    fuzz::AllowTypedErrors([&] { fuzz::ReadEveryMessage(*io::OpenRos2Bag(path)); });
}

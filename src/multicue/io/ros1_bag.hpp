#pragma once
/// \file ROS 1 `.bag` files through librosbag (Debian's librosbag-dev). Built into the separate
/// library multicue::ros1_bag only when librosbag is installed (cmake/FindRos1.cmake); the
/// message bytes it returns are decoded by io/ros_messages.hpp like those of ROS 2 bags.

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "multicue/io/bag.hpp"

namespace multicue::io {

/// Opens a ROS 1 bag (any version librosbag reads, compressed chunks included). Only messages on
/// `topics` are returned (all when empty), in time order; topics have serialization "ros1".
/// Throws IoError for a missing file, FormatError for a file librosbag refuses (not a bag,
/// truncated or unindexed: `rosbag reindex` repairs the latter).
std::unique_ptr<BagReader> OpenRos1Bag(const std::filesystem::path& path,
                                       const std::vector<std::string>& topics = {});

}  // namespace multicue::io

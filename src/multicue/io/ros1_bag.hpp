#pragma once
/// \file ROS 1 `.bag` files (format 2.0), read by multicue's own code: librosbag took the lengths
/// and offsets of a damaged bag as they were. Built into the separate library multicue::ros1_bag
/// where ROS 1 is installed (cmake/FindRos1.cmake); the message bytes it returns are decoded by
/// io/ros_messages.hpp like those of ROS 2 bags.

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "multicue/io/bag.hpp"

namespace multicue::io {

/// Opens a ROS 1 bag of format 2.0 (chunks uncompressed or compressed with lz4 or bz2). Only
/// messages on `topics` are returned (all when empty), in the order of the file (chunk after
/// chunk, as recorded); topics have serialization "ros1" and their message counts from the
/// bag's index. Throws IoError for a missing file, FormatError for a file that is no such bag,
/// is truncated or corrupt (every length is checked against the file before it is used), or has
/// no index (`rosbag reindex` repairs that).
std::unique_ptr<BagReader> OpenRos1Bag(const std::filesystem::path& path,
                                       const std::vector<std::string>& topics = {});

}  // namespace multicue::io

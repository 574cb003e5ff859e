#pragma once
/// \file The serialised forms of the few ROS messages multicue reads from bags, without any ROS
/// library: sensor_msgs/PointCloud2 in ROS 2's CDR and in ROS 1's serialisation (little endian,
/// no alignment, strings and arrays as a uint32 length and their bytes), and std_msgs/String.

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "multicue/io/point_cloud2.hpp"

namespace multicue::io {

/// Type names of a point cloud message in ROS 2 and ROS 1.
inline constexpr const char* kPointCloud2Ros2Type = "sensor_msgs/msg/PointCloud2";
inline constexpr const char* kPointCloud2Ros1Type = "sensor_msgs/PointCloud2";

/// Whether `type` names sensor_msgs PointCloud2 (ROS 1 or ROS 2 spelling).
bool IsPointCloud2Type(const std::string& type);

/// A CDR-serialised sensor_msgs/msg/PointCloud2 (std_msgs/Header with builtin_interfaces/Time).
/// Throws FormatError naming `source` when the bytes end early or hold more than the message.
PointCloud2Message DecodePointCloud2Cdr(std::span<const std::uint8_t> bytes,
                                        const std::string& source);
/// The CDR bytes rosbag2 stores for `message` (encapsulation header included).
std::vector<std::uint8_t> EncodePointCloud2Cdr(const PointCloud2Message& message,
                                               bool big_endian = false);

/// A ROS 1 serialised sensor_msgs/PointCloud2 (Header with seq, time as uint32 sec and nsec).
PointCloud2Message DecodePointCloud2Ros1(std::span<const std::uint8_t> bytes,
                                         const std::string& source);
std::vector<std::uint8_t> EncodePointCloud2Ros1(const PointCloud2Message& message);

/// A CDR-serialised std_msgs/msg/String.
std::string DecodeStringCdr(std::span<const std::uint8_t> bytes, const std::string& source);

}  // namespace multicue::io

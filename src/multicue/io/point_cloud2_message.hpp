#pragma once
/// \file sensor_msgs/PointCloud2 (ROS 1) and sensor_msgs/msg/PointCloud2 (ROS 2) as a plain
/// struct. This header is C++17 so that code built against ROS 1's message headers (which do not
/// compile as C++20) can fill it; io/point_cloud2.hpp converts it to and from PointCloud.

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace multicue::io {

/// sensor_msgs/PointField datatypes (the numbers are the message's constants).
enum class PointFieldType : std::uint8_t {
    kInt8 = 1,
    kUInt8 = 2,
    kInt16 = 3,
    kUInt16 = 4,
    kInt32 = 5,
    kUInt32 = 6,
    kFloat32 = 7,
    kFloat64 = 8,
};

/// Bytes of one element of a PointField datatype; 0 for a number that is no datatype.
std::size_t PointFieldTypeSize(std::uint8_t datatype);

/// sensor_msgs/PointField.
struct PointField {
    std::string name;
    std::uint32_t offset = 0;  ///< byte offset within a point
    std::uint8_t datatype = static_cast<std::uint8_t>(PointFieldType::kFloat32);
    std::uint32_t count = 1;  ///< elements per point (0 is read as 1, as PCL does)

    bool operator==(const PointField& o) const {
        return name == o.name && offset == o.offset && datatype == o.datatype && count == o.count;
    }
};

/// A message time: seconds and nanoseconds (ROS 1 time, ROS 2 builtin_interfaces/Time).
struct MessageStamp {
    std::int64_t sec = 0;
    std::uint32_t nanosec = 0;

    std::int64_t Nanoseconds() const { return sec * 1000000000LL + nanosec; }
    static MessageStamp FromNanoseconds(std::int64_t ns);
    /// "sec.nanosec" with nine digits after the point (folder names, JSON).
    std::string ToString() const;

    bool operator==(const MessageStamp& o) const { return sec == o.sec && nanosec == o.nanosec; }
};

/// sensor_msgs/PointCloud2 with its std_msgs/Header.
struct PointCloud2Message {
    std::uint32_t seq = 0;     ///< header.seq (ROS 1 only)
    MessageStamp stamp;        ///< header.stamp
    std::string frame_id;      ///< header.frame_id
    std::uint32_t height = 1;  ///< rows; 1 for an unorganized cloud
    std::uint32_t width = 0;   ///< points per row
    std::vector<PointField> fields;
    bool is_bigendian = false;
    std::uint32_t point_step = 0;  ///< bytes per point
    std::uint32_t row_step = 0;    ///< bytes per row (point_step * width or more)
    std::vector<std::uint8_t> data;
    bool is_dense = false;  ///< no invalid points

    /// The field named `name`, nullptr if absent.
    const PointField* FindField(const std::string& name) const;
};

}  // namespace multicue::io

#pragma once
/// \file The ROS point cloud message (sensor_msgs/PointCloud2 of ROS 1 and sensor_msgs/msg/
/// PointCloud2 of ROS 2) as a plain struct, and its conversion to and from PointCloud. The ROS 1
/// node, the ROS 1 bag reader and the ROS 2 bag reader all convert through here, so every source
/// of PointCloud2 messages accepts the same layouts: any field order and offsets, padding between
/// fields and at the end of rows, organized or not, NaN points, colour packed in a float or an
/// unsigned integer, big or little endian data.

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "multicue/core/point_cloud.hpp"

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

    friend bool operator==(const PointField&, const PointField&) = default;
};

/// A message time: seconds and nanoseconds (ROS 1 time, ROS 2 builtin_interfaces/Time).
struct MessageStamp {
    std::int64_t sec = 0;
    std::uint32_t nanosec = 0;

    std::int64_t Nanoseconds() const { return sec * 1000000000LL + nanosec; }
    static MessageStamp FromNanoseconds(std::int64_t ns);
    /// "sec.nanosec" with nine digits after the point (folder names, JSON).
    std::string ToString() const;

    friend bool operator==(const MessageStamp&, const MessageStamp&) = default;
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

/// Fills a PointCloud from a message. Fields x, y, z (any numeric datatype) are the points;
/// normal_x/y/z the normals; rgb or rgba (4 bytes, packed a<<24|r<<16|g<<8|b in a float32 or a
/// uint32; an rgb alpha of 0 reads as opaque) or separate r, g, b uint8 fields the colours;
/// curvature, intensity, confidence and label their vectors; every other field is kept as an
/// ExtraField (machine byte order). height > 1 gives an organized cloud; NaN points keep their
/// place. Throws FormatError naming `source` for a layout that does not fit its data: no x/y/z
/// field, an unknown datatype, a field beyond point_step, points beyond row_step, data shorter
/// than row_step * height, a repeated field name.
PointCloud FromPointCloud2(const PointCloud2Message& message,
                           const std::string& source = "PointCloud2");

/// How ToPointCloud2 lays out the message.
struct PointCloud2Params {
    bool big_endian = false;  ///< write the data big endian (is_bigendian = true)
    /// point_step is rounded up to a multiple of this many bytes (PCL pads XYZ points to 16) [B]
    std::uint32_t point_alignment = 4;
    /// Colours as "rgba" (uint32, alpha kept) instead of "rgb" (float32, as PCL's PointXYZRGB).
    bool rgba = false;
    void Validate() const;
};

/// A message holding every field of `cloud`: x y z (float32), normal_x/y/z and curvature when
/// present, rgb (float32) or rgba (uint32), intensity, confidence (float32), label (uint32) and
/// the extra fields with their types. Organized clouds keep width and height; is_dense is true
/// when every point is finite. The header (stamp, frame_id) is left for the caller.
PointCloud2Message ToPointCloud2(const PointCloud& cloud, const PointCloud2Params& params = {});

}  // namespace multicue::io

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
#include "multicue/io/point_cloud2_message.hpp"

namespace multicue::io {

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

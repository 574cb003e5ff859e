#pragma once
// PointCloud2 layouts as PCL writes them (pcl::toROSMsg through pcl_conversions) and PCL reading
// ours back (pcl::fromROSMsg). C++17 and free of PCL and ROS types, so that the C++20 test can
// call it: pcl_layouts.cpp holds the ROS and PCL code.

#include <cstdint>
#include <string>
#include <vector>

#include "multicue/io/point_cloud2_message.hpp"

namespace multicue::test {

/// The values PCL holds per point, as plain arrays (empty when the type has no such field).
struct PclValues {
    std::vector<float> xyz;      ///< 3 per point
    std::vector<float> normals;  ///< 3 per point
    std::vector<float> curvature;
    std::vector<float> intensity;
    std::vector<std::uint32_t> label;
    std::vector<std::uint8_t> rgba;  ///< r g b a per point
    std::vector<float> extra;        ///< the type's other float fields, in field order
    std::vector<std::string> extra_names;
};

struct PclLayout {
    std::string type;  ///< "PointXYZRGB", ...
    io::PointCloud2Message message;
    PclValues values;
    bool organized = false;
};

/// Every point type below, a few points each with distinct values (one NaN point), through
/// pcl::toROSMsg; one organized 3x2 PointXYZRGB cloud.
std::vector<PclLayout> PclLayouts();

/// `message` read by pcl::fromROSMsg into the PCL type `type`.
PclValues PclRead(const std::string& type, const io::PointCloud2Message& message);

}  // namespace multicue::test

#include "pcl_layouts.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>

#include <pcl/point_types.h>
#include <pcl_conversions/pcl_conversions.h>

#include "msg_conversions.hpp"

namespace multicue::test {
namespace {

constexpr int kPoints = 5;

template <typename P>
void SetXyz(P& p, int i) {
    p.x = 0.1f * i, p.y = -0.2f * i, p.z = 1.0f + 0.05f * i;
    if (i == 2) p.x = p.y = p.z = std::numeric_limits<float>::quiet_NaN();
}

template <typename P>
void Fill(P& p, int i) {
    SetXyz(p, i);
    if constexpr (pcl::traits::has_field<P, pcl::fields::normal_x>::value) {
        p.normal_x = 0.6f, p.normal_y = 0.0f, p.normal_z = 0.8f * (i % 2 ? 1 : -1);
    }
    if constexpr (pcl::traits::has_field<P, pcl::fields::curvature>::value) p.curvature = 0.01f * i;
    if constexpr (pcl::traits::has_field<P, pcl::fields::intensity>::value) p.intensity = 10.0f * i;
    if constexpr (pcl::traits::has_field<P, pcl::fields::label>::value) p.label = 100u + i;
    if constexpr (pcl::traits::has_field<P, pcl::fields::rgb>::value ||
                  pcl::traits::has_field<P, pcl::fields::rgba>::value) {
        p.r = std::uint8_t(10 * i), p.g = std::uint8_t(20 * i), p.b = std::uint8_t(30 * i);
        p.a = std::uint8_t(200 + i);
    }
}

template <typename P>
PclValues Values(const pcl::PointCloud<P>& cloud, const std::vector<std::string>& extra = {}) {
    PclValues v;
    v.extra_names = extra;
    for (const auto& p : cloud.points) {
        v.xyz.insert(v.xyz.end(), {p.x, p.y, p.z});
        if constexpr (pcl::traits::has_field<P, pcl::fields::normal_x>::value)
            v.normals.insert(v.normals.end(), {p.normal_x, p.normal_y, p.normal_z});
        if constexpr (pcl::traits::has_field<P, pcl::fields::curvature>::value)
            v.curvature.push_back(p.curvature);
        if constexpr (pcl::traits::has_field<P, pcl::fields::intensity>::value)
            v.intensity.push_back(p.intensity);
        if constexpr (pcl::traits::has_field<P, pcl::fields::label>::value)
            v.label.push_back(p.label);
        if constexpr (pcl::traits::has_field<P, pcl::fields::rgb>::value ||
                      pcl::traits::has_field<P, pcl::fields::rgba>::value)
            v.rgba.insert(v.rgba.end(), {p.r, p.g, p.b, p.a});
        if constexpr (std::is_same_v<P, pcl::PointWithViewpoint>)
            v.extra.insert(v.extra.end(), {p.vp_x, p.vp_y, p.vp_z});
        if constexpr (std::is_same_v<P, pcl::PointWithRange>) v.extra.push_back(p.range);
        if constexpr (std::is_same_v<P, pcl::InterestPoint>) v.extra.push_back(p.strength);
        if constexpr (std::is_same_v<P, pcl::PointSurfel>)
            v.extra.insert(v.extra.end(), {p.radius, p.confidence});
    }
    return v;
}

template <typename P>
PclLayout Make(const std::string& type, std::uint32_t width = kPoints, std::uint32_t height = 1,
               const std::vector<std::string>& extra = {}) {
    pcl::PointCloud<P> cloud;
    cloud.resize(std::size_t{width} * height);
    cloud.width = width;
    cloud.height = height;
    cloud.is_dense = false;
    for (int i = 0; i < static_cast<int>(cloud.size()); ++i) {
        P& p = cloud.points[static_cast<std::size_t>(i)];
        Fill(p, i);
        if constexpr (std::is_same_v<P, pcl::PointWithViewpoint>)
            p.vp_x = 1.0f + i, p.vp_y = 2.0f, p.vp_z = 3.0f;
        if constexpr (std::is_same_v<P, pcl::PointWithRange>) p.range = 0.5f * i;
        if constexpr (std::is_same_v<P, pcl::InterestPoint>) p.strength = 7.0f * i;
        if constexpr (std::is_same_v<P, pcl::PointSurfel>)
            p.radius = 0.002f * i, p.confidence = 0.9f;
    }
    sensor_msgs::PointCloud2 msg;
    pcl::toROSMsg(cloud, msg);
    msg.header.frame_id = "pcl";
    return {type, ros1::FromRosMsg(msg), Values(cloud, extra), height > 1};
}

template <typename P>
PclValues Read(const io::PointCloud2Message& message) {
    pcl::PointCloud<P> cloud;
    pcl::fromROSMsg(ros1::ToRosMsg(message), cloud);
    return Values(cloud);
}

}  // namespace

std::vector<PclLayout> PclLayouts() {
    return {
        Make<pcl::PointXYZ>("PointXYZ"),
        Make<pcl::PointXYZI>("PointXYZI"),
        Make<pcl::PointXYZL>("PointXYZL"),
        Make<pcl::PointXYZRGB>("PointXYZRGB"),
        Make<pcl::PointXYZRGB>("PointXYZRGB", 3, 2),
        Make<pcl::PointXYZRGBA>("PointXYZRGBA"),
        Make<pcl::PointXYZRGBL>("PointXYZRGBL"),
        Make<pcl::PointNormal>("PointNormal"),
        Make<pcl::PointXYZRGBNormal>("PointXYZRGBNormal"),
        Make<pcl::PointXYZINormal>("PointXYZINormal"),
        Make<pcl::PointXYZLNormal>("PointXYZLNormal"),
        Make<pcl::PointWithViewpoint>("PointWithViewpoint", kPoints, 1, {"vp_x", "vp_y", "vp_z"}),
        Make<pcl::PointWithRange>("PointWithRange", kPoints, 1, {"range"}),
        Make<pcl::InterestPoint>("InterestPoint", kPoints, 1, {"strength"}),
        Make<pcl::PointSurfel>("PointSurfel", kPoints, 1, {"radius", "confidence"})};
}

PclValues PclRead(const std::string& type, const io::PointCloud2Message& message) {
    if (type == "PointXYZ") return Read<pcl::PointXYZ>(message);
    if (type == "PointXYZI") return Read<pcl::PointXYZI>(message);
    if (type == "PointXYZL") return Read<pcl::PointXYZL>(message);
    if (type == "PointXYZRGB") return Read<pcl::PointXYZRGB>(message);
    if (type == "PointXYZRGBA") return Read<pcl::PointXYZRGBA>(message);
    if (type == "PointXYZRGBL") return Read<pcl::PointXYZRGBL>(message);
    if (type == "PointNormal") return Read<pcl::PointNormal>(message);
    if (type == "PointXYZRGBNormal") return Read<pcl::PointXYZRGBNormal>(message);
    if (type == "PointXYZINormal") return Read<pcl::PointXYZINormal>(message);
    if (type == "PointXYZLNormal") return Read<pcl::PointXYZLNormal>(message);
    if (type == "PointWithViewpoint") return Read<pcl::PointWithViewpoint>(message);
    if (type == "PointWithRange") return Read<pcl::PointWithRange>(message);
    if (type == "InterestPoint") return Read<pcl::InterestPoint>(message);
    if (type == "PointSurfel") return Read<pcl::PointSurfel>(message);
    throw std::invalid_argument("unknown PCL point type " + type);
}

}  // namespace multicue::test

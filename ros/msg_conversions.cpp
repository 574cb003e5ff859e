#include "msg_conversions.hpp"

#include <cstring>
#include <stdexcept>

#include <nlohmann/json.hpp>

namespace multicue::ros1 {
namespace {

nlohmann::json ToJson(XmlRpc::XmlRpcValue& v) {
    switch (v.getType()) {
        case XmlRpc::XmlRpcValue::TypeBoolean:
            return static_cast<bool>(v);
        case XmlRpc::XmlRpcValue::TypeInt:
            return static_cast<int>(v);
        case XmlRpc::XmlRpcValue::TypeDouble:
            return static_cast<double>(v);
        case XmlRpc::XmlRpcValue::TypeString:
            return static_cast<std::string>(v);
        case XmlRpc::XmlRpcValue::TypeArray: {
            nlohmann::json a = nlohmann::json::array();
            for (int i = 0; i < v.size(); ++i) a.push_back(ToJson(v[i]));
            return a;
        }
        case XmlRpc::XmlRpcValue::TypeStruct: {
            nlohmann::json o = nlohmann::json::object();
            for (auto& [key, value] : v) o[key] = ToJson(value);
            return o;
        }
        default:
            return nullptr;
    }
}

}  // namespace

io::PointCloud2Message FromRosMsg(const sensor_msgs::PointCloud2& msg) {
    io::PointCloud2Message m;
    m.seq = msg.header.seq;
    m.stamp.sec = msg.header.stamp.sec;
    m.stamp.nanosec = msg.header.stamp.nsec;
    m.frame_id = msg.header.frame_id;
    m.height = msg.height;
    m.width = msg.width;
    for (const auto& f : msg.fields) {
        io::PointField pf;
        pf.name = f.name;
        pf.offset = f.offset;
        pf.datatype = f.datatype;
        pf.count = f.count;
        m.fields.push_back(pf);
    }
    m.is_bigendian = msg.is_bigendian != 0;
    m.point_step = msg.point_step;
    m.row_step = msg.row_step;
    m.data = msg.data;
    m.is_dense = msg.is_dense != 0;
    return m;
}

sensor_msgs::PointCloud2 ToRosMsg(const io::PointCloud2Message& m) {
    sensor_msgs::PointCloud2 msg;
    msg.header.seq = m.seq;
    msg.header.stamp.sec = static_cast<std::uint32_t>(m.stamp.sec);
    msg.header.stamp.nsec = m.stamp.nanosec;
    msg.header.frame_id = m.frame_id;
    msg.height = m.height;
    msg.width = m.width;
    for (const auto& f : m.fields) {
        sensor_msgs::PointField pf;
        pf.name = f.name;
        pf.offset = f.offset;
        pf.datatype = f.datatype;
        pf.count = f.count;
        msg.fields.push_back(pf);
    }
    msg.is_bigendian = m.is_bigendian;
    msg.point_step = m.point_step;
    msg.row_step = m.row_step;
    msg.data = m.data;
    msg.is_dense = m.is_dense;
    return msg;
}

DepthFrame DepthFrameFromRos(const sensor_msgs::Image& image, const sensor_msgs::CameraInfo& info,
                             const sensor_msgs::Image* colour) {
    DepthFrame f;
    f.width = image.width;
    f.height = image.height;
    f.fx = info.K[0], f.fy = info.K[4], f.cx = info.K[2], f.cy = info.K[5];
    const bool mm = image.encoding == "16UC1" || image.encoding == "mono16";
    if (!mm && image.encoding != "32FC1") {
        throw std::runtime_error("depth image encoding '" + image.encoding +
                                 "' (16UC1 or 32FC1 expected)");
    }
    const std::size_t bytes = mm ? 2 : 4;
    if (image.step < image.width * bytes ||
        image.data.size() < std::size_t{image.step} * image.height) {
        throw std::runtime_error("depth image data shorter than its size");
    }
    f.depth.resize(std::size_t{image.width} * image.height);
    for (std::uint32_t v = 0; v < image.height; ++v) {
        for (std::uint32_t u = 0; u < image.width; ++u) {
            std::uint8_t b[4];
            const std::uint8_t* p = image.data.data() + std::size_t{v} * image.step + u * bytes;
            for (std::size_t k = 0; k < bytes; ++k)
                b[k] = image.is_bigendian ? p[bytes - 1 - k] : p[k];
            float z = 0.0f;
            if (mm) {
                std::uint16_t raw;
                std::memcpy(&raw, b, 2);
                z = static_cast<float>(raw) * 0.001f;
            } else {
                std::memcpy(&z, b, 4);
            }
            f.depth[std::size_t{v} * image.width + u] = z;
        }
    }
    if (colour == nullptr) return f;
    const std::string& e = colour->encoding;
    int channels = 0, r = 0, g = 1, b = 2;
    if (e == "rgb8") {
        channels = 3;
    } else if (e == "bgr8") {
        channels = 3, r = 2, b = 0;
    } else if (e == "rgba8") {
        channels = 4;
    } else if (e == "bgra8") {
        channels = 4, r = 2, b = 0;
    } else if (e == "mono8") {
        channels = 1, r = g = b = 0;
    } else {
        throw std::runtime_error("colour image encoding '" + e +
                                 "' (rgb8, bgr8, rgba8, bgra8 or mono8 expected)");
    }
    if (colour->width != image.width || colour->height != image.height ||
        colour->step < colour->width * channels ||
        colour->data.size() < std::size_t{colour->step} * colour->height) {
        throw std::runtime_error("colour image does not match the depth image");
    }
    f.rgb.resize(3 * f.depth.size());
    for (std::uint32_t v = 0; v < image.height; ++v) {
        for (std::uint32_t u = 0; u < image.width; ++u) {
            const std::uint8_t* p =
                colour->data.data() + std::size_t{v} * colour->step + std::size_t{u} * channels;
            std::uint8_t* q = f.rgb.data() + 3 * (std::size_t{v} * image.width + u);
            q[0] = p[r], q[1] = p[g], q[2] = p[b];
        }
    }
    return f;
}

visualization_msgs::MarkerArray MarkersFromOutput(const FrameOutput& out,
                                                  const std_msgs::Header& header) {
    visualization_msgs::MarkerArray array;
    visualization_msgs::Marker clear;
    clear.header = header;
    clear.action = visualization_msgs::Marker::DELETEALL;
    array.markers.push_back(clear);
    if (!out.triangles.empty()) {
        visualization_msgs::Marker models;
        models.header = header;
        models.ns = "models";
        models.type = visualization_msgs::Marker::TRIANGLE_LIST;
        models.action = visualization_msgs::Marker::ADD;
        models.pose.orientation.w = 1.0;
        models.scale.x = models.scale.y = models.scale.z = 1.0;
        models.color.r = models.color.g = models.color.b = models.color.a = 1.0f;
        for (std::size_t i = 0; i + 2 < out.triangles.size(); i += 3) {
            geometry_msgs::Point p;
            p.x = out.triangles[i], p.y = out.triangles[i + 1], p.z = out.triangles[i + 2];
            models.points.push_back(p);
            std_msgs::ColorRGBA c;
            c.r = out.triangle_rgb[i], c.g = out.triangle_rgb[i + 1];
            c.b = out.triangle_rgb[i + 2], c.a = 1.0f;
            models.colors.push_back(c);
        }
        array.markers.push_back(models);
    }
    for (const auto& t : out.texts) {
        visualization_msgs::Marker text;
        text.header = header;
        text.ns = "labels";
        text.id = t.id;
        text.type = visualization_msgs::Marker::TEXT_VIEW_FACING;
        text.action = visualization_msgs::Marker::ADD;
        text.pose.position.x = t.position[0];
        text.pose.position.y = t.position[1];
        text.pose.position.z = t.position[2];
        text.pose.orientation.w = 1.0;
        text.scale.z = 0.03;
        text.color.r = t.rgb[0], text.color.g = t.rgb[1], text.color.b = t.rgb[2];
        text.color.a = 1.0f;
        text.text = t.text;
        array.markers.push_back(text);
    }
    return array;
}

std::string ParamToJson(const XmlRpc::XmlRpcValue& value) {
    XmlRpc::XmlRpcValue copy = value;  // the accessors are not const
    return ToJson(copy).dump();
}

}  // namespace multicue::ros1

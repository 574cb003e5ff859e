#pragma once
/// \file ROS 1 messages to and from the plain structs of node_core.hpp and io/point_cloud2_message
/// .hpp: field copies only. C++17, as ROS 1's message headers need.

#include <xmlrpcpp/XmlRpcValue.h>

#include <string>

#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/PointCloud2.h>
#include <std_msgs/Header.h>
#include <visualization_msgs/MarkerArray.h>

#include "multicue/io/point_cloud2_message.hpp"
#include "node_core.hpp"

namespace multicue::ros1 {

io::PointCloud2Message FromRosMsg(const sensor_msgs::PointCloud2& msg);
sensor_msgs::PointCloud2 ToRosMsg(const io::PointCloud2Message& msg);

/// A depth image (16UC1 in millimetres or 32FC1 in metres), its camera_info and optionally a
/// colour image of the same size (rgb8, bgr8, rgba8, bgra8, mono8). Throws std::runtime_error
/// for another encoding or an image whose data is shorter than its size says.
DepthFrame DepthFrameFromRos(const sensor_msgs::Image& depth, const sensor_msgs::CameraInfo& info,
                             const sensor_msgs::Image* colour);

/// The markers of a frame in `header`'s frame: DELETEALL, one TRIANGLE_LIST with every model
/// (namespace "models", coloured per object as in models.ply) and one TEXT_VIEW_FACING per object
/// at its centroid (namespace "labels", id = object id, "id category confidence").
visualization_msgs::MarkerArray MarkersFromOutput(const FrameOutput& output,
                                                  const std_msgs::Header& header);

/// A ROS parameter tree as JSON text (structs as objects, arrays, numbers, strings, booleans).
std::string ParamToJson(const XmlRpc::XmlRpcValue& value);

}  // namespace multicue::ros1

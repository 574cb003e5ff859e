#pragma once
/// \file Depth images (and a registered colour image) back-projected through a pinhole camera
/// into an organized cloud: what an RGB-D driver publishes as depth, colour and camera_info.

#include <cstdint>
#include <vector>

#include "multicue/core/point_cloud.hpp"

namespace multicue::io {

/// Pinhole intrinsics of the depth image (sensor_msgs/CameraInfo K).
struct CameraIntrinsics {
    double fx = 0.0;  ///< focal length in x [px]
    double fy = 0.0;  ///< focal length in y [px]
    double cx = 0.0;  ///< principal point x [px]
    double cy = 0.0;  ///< principal point y [px]
    /// Throws InvalidArgument unless fx, fy > 0 and all are finite.
    void Validate() const;
};

/// A depth image in metres, row-major; 0, NaN or infinity mark missing depth.
struct DepthImage {
    std::uint32_t width = 0;
    std::uint32_t height = 0;
    std::vector<float> depth;  ///< width * height values [m]
};

/// The organized cloud (width x height) of a depth image in the camera's optical frame (x right,
/// y down, z forward); pixels without depth are NaN points. `colors`, when not empty, holds one
/// colour per pixel of the same image size. Throws InvalidArgument for sizes that do not match.
PointCloud DepthToCloud(const DepthImage& depth, const CameraIntrinsics& intrinsics,
                        const std::vector<Color>& colors = {});

}  // namespace multicue::io

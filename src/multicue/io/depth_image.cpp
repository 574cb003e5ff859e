#include "multicue/io/depth_image.hpp"

#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"

namespace multicue::io {

void CameraIntrinsics::Validate() const {
    if (!(fx > 0.0) || !(fy > 0.0) || !std::isfinite(fx) || !std::isfinite(fy) ||
        !std::isfinite(cx) || !std::isfinite(cy)) {
        throw InvalidArgument(fmt::format(
            "camera intrinsics need fx, fy > 0 and finite cx, cy; got fx {} fy {} cx {} cy {}", fx,
            fy, cx, cy));
    }
}

PointCloud DepthToCloud(const DepthImage& depth, const CameraIntrinsics& intrinsics,
                        const std::vector<Color>& colors) {
    intrinsics.Validate();
    const std::size_t n = std::size_t{depth.width} * depth.height;
    if (depth.depth.size() != n) {
        throw InvalidArgument(fmt::format("depth image {}x{} holds {} values", depth.width,
                                          depth.height, depth.depth.size()));
    }
    if (!colors.empty() && colors.size() != n) {
        throw InvalidArgument(
            fmt::format("colour image holds {} pixels, the depth image {}", colors.size(), n));
    }
    PointCloud cloud;
    cloud.points.resize(n);
    const float nan = std::numeric_limits<float>::quiet_NaN();
    for (std::uint32_t v = 0; v < depth.height; ++v) {
        for (std::uint32_t u = 0; u < depth.width; ++u) {
            const std::size_t i = std::size_t{v} * depth.width + u;
            const float z = depth.depth[i];
            if (!(z > 0.0f) || !std::isfinite(z)) {
                cloud.points[i] = Eigen::Vector3f::Constant(nan);
                continue;
            }
            cloud.points[i] = {static_cast<float>((u - intrinsics.cx) * z / intrinsics.fx),
                               static_cast<float>((v - intrinsics.cy) * z / intrinsics.fy), z};
        }
    }
    cloud.colors = colors;
    cloud.width = depth.width;
    cloud.height = depth.height;
    if (cloud.height <= 1) cloud.SetUnorganized();
    return cloud;
}

}  // namespace multicue::io

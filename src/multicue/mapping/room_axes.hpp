#pragma once
/// \file The main axes of a room from its surface normals: RANSAC on the normal sphere (thesis
/// section 4.1.2, after Marton et al. 2010a). In rooms most normals lie along one of three
/// orthogonal directions (floor and ceiling, two families of walls and furniture faces); two
/// sampled normals that are far enough apart span a candidate frame, which scores the normals
/// within an angle of any of its axes (either sign). The best frame is refined by fitting the
/// rotation to its inliers (orthogonal Procrustes).

#include <cstddef>
#include <cstdint>
#include <optional>

#include <Eigen/Core>

#include "multicue/core/point_cloud.hpp"
#include "multicue/mapping/semantic_map.hpp"

namespace multicue::mapping {

struct RoomAxesParams {
    float angle_threshold_deg = 6.0f;  ///< a normal this close to an axis supports it [deg]
    int max_iterations = 300;          ///< sampled frames [samples]; >= 1
    std::size_t max_normals = 20000;   ///< normals used, evenly strided [normals]; >= 10
    /// Approximate up direction in the cloud's frame; unset: +z when the cloud carries a sensor
    /// position (a world frame), else -y (a camera's optical frame).
    std::optional<Eigen::Vector3f> up = std::nullopt;
    std::uint64_t seed = 1;  ///< sampler seed
    /// Throws InvalidArgument naming the first out-of-range field.
    void Validate() const;
};

struct RoomAxesResult {
    bool found = false;       ///< at least one axis is supported by 10 normals
    RoomFrame frame;          ///< columns x, y (horizontal), z (the axis nearest to up, along it)
    std::size_t inliers = 0;  ///< normals within the threshold of an axis
    std::size_t used = 0;     ///< finite normals considered
    int iterations = 0;       ///< frames sampled
};

/// The room's axes from `cloud.normals`. Throws InvalidArgument for bad parameters, DataError when
/// the cloud has no normals (or not one per point). A cloud without finite normals gives
/// found = false and the identity frame.
RoomAxesResult EstimateRoomAxes(const PointCloud& cloud, const RoomAxesParams& params = {});

}  // namespace multicue::mapping

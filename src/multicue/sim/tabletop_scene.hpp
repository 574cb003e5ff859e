#pragma once
/// \file Analytic table-top scenes (a table, the floor, upright boxes and cylinders) scanned by a
/// pinhole RGB-D camera with depth-dependent noise. Ground truth follows the mOSD label scheme so
/// that the same scorer works on synthetic and real scenes: 0 no return, 1 table, 2 floor,
/// 10*(k+1) object k (k = 1, 2, ...).

#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "multicue/core/point_cloud.hpp"
#include "multicue/core/types.hpp"

namespace multicue::sim {

/// Label of object k (k >= 1) in the mOSD scheme.
constexpr std::uint32_t ObjectLabel(std::uint32_t k) { return 10 * (k + 1); }
constexpr std::uint32_t kTableLabel = 1;
constexpr std::uint32_t kFloorLabel = 2;

/// A box standing on the table, rotated about the vertical axis. World frame: z up, metres.
struct SceneBox {
    Eigen::Vector2f center_xy = Eigen::Vector2f::Zero();  ///< centre of the footprint [m]
    float yaw = 0.0f;                                     ///< rotation about z [rad]
    Eigen::Vector3f extents{0.1f, 0.1f, 0.1f};            ///< width, depth, height [m]
    Color color{200, 60, 40, 255};
};

/// An upright cylinder (can, mug body) standing on the table.
struct SceneCylinder {
    Eigen::Vector2f center_xy = Eigen::Vector2f::Zero();  ///< axis position [m]
    float radius = 0.04f;                                 ///< [m]
    float height = 0.12f;                                 ///< [m]
    Color color{40, 90, 200, 255};
};

struct TableTopScene {
    float table_height = 0.75f;               ///< table top above the floor [m]
    Eigen::Vector2f table_min{-0.6f, -0.4f};  ///< table top rectangle, world x/y [m]
    Eigen::Vector2f table_max{0.6f, 0.4f};    ///< [m]
    Color table_color{170, 140, 100, 255};
    Color floor_color{90, 90, 90, 255};
    std::vector<SceneBox> boxes;           ///< objects 1..B
    std::vector<SceneCylinder> cylinders;  ///< objects B+1..B+C
};

struct PinholeCamera {
    std::uint32_t width = 640;   ///< [px]
    std::uint32_t height = 480;  ///< [px]
    float fx = 525.0f;           ///< focal length [px] (Kinect-class)
    float fy = 525.0f;           ///< [px]
    float cx = 319.5f;           ///< principal point [px]
    float cy = 239.5f;           ///< [px]
};

struct ScanParams {
    PinholeCamera camera;
    /// Camera pose in the world (optical frame: x right, y down, z forward).
    Eigen::Isometry3f T_world_camera = Eigen::Isometry3f::Identity();
    float axial_noise = 1.4e-3f;      ///< depth noise sigma = axial_noise * z^2 [1/m]
    float min_range = 0.4f;           ///< no return closer than this [m]
    float max_range = 4.0f;           ///< no return beyond this [m]
    float max_incidence_deg = 80.0f;  ///< no return at more grazing angles [deg]
    std::uint32_t seed = 1;           ///< noise seed; equal seeds give identical scans
};

/// A camera 0.6 m above the table top, 0.9 m in front of its centre, looking at it.
Eigen::Isometry3f DefaultCameraPose(const TableTopScene& scene);

/// The demo scene: three boxes and two cylinders on a 1.2 m x 0.8 m table.
TableTopScene MakeDemoScene();

/// Scans the scene: an organized cloud (width x height) in the camera frame with NaN where no
/// return, colours, mOSD labels, and the sensor at the origin. Throws InvalidArgument on bad
/// params.
PointCloud ScanTableTopScene(const TableTopScene& scene, const ScanParams& params);

}  // namespace multicue::sim

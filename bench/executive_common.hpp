#pragma once
// Scenes and frames shared by the executive's benchmark and its learning experiment: the analytic
// demo table seen from viewpoints on a circle around it.

#include <Eigen/Geometry>

#include "multicue/sim/tabletop_scene.hpp"
#include "multicue/system/executive.hpp"

namespace multicue::bench {

/// The default camera turned by `angle` [rad] about the table's vertical axis.
inline Frame ViewOfScene(const sim::TableTopScene& scene, float angle, double time,
                         std::uint32_t seed) {
    sim::ScanParams scan;
    scan.T_world_camera = Eigen::Isometry3f(Eigen::AngleAxisf(angle, Eigen::Vector3f::UnitZ())) *
                          sim::DefaultCameraPose(scene);
    scan.seed = seed;
    Frame frame;
    frame.cloud = sim::ScanTableTopScene(scene, scan);
    frame.T_world_sensor = scan.T_world_camera.cast<double>();
    frame.time = time;
    frame.name = "view-" + std::to_string(seed);
    return frame;
}

}  // namespace multicue::bench

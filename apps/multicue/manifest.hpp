#pragma once
// Frames of a `multicue simulate scenes` manifest (or one written by hand in its format), read by
// `perceive --manifest` and `map --manifest`.

#include <filesystem>
#include <optional>
#include <vector>

#include <Eigen/Geometry>

namespace multicue::cli {

/// One frame: its file and, when the manifest gives it, its pose in the scene's world frame.
struct ManifestFrame {
    std::filesystem::path file;
    /// "T_world_sensor" (4x4), or nothing when the frame has no pose.
    std::optional<Eigen::Isometry3f> T_world_sensor;
    /// "pose_noisy": true marks a rough pose (odometry) that should be registered.
    bool pose_noisy = false;
};

/// The frames of scene `scene_id` (the first scene if negative) of a manifest.json: an object
/// with a "scenes" array whose entries have an "id" and a "frames" array of {"file": path
/// relative to the manifest, "T_world_sensor": 4x4 rows (optional), "pose_noisy": bool
/// (optional)}. Throws IoError / FormatError naming the file, InvalidArgument for an unknown id.
std::vector<ManifestFrame> ReadManifestFrames(const std::filesystem::path& path, int scene_id);

}  // namespace multicue::cli

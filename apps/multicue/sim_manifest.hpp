#pragma once
// The manifest.json of `multicue simulate` as the commands that replay its frames read it
// (`perceive --manifest`, `run` with a manifest of frames).

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

namespace multicue::cli {

/// One frame of a simulated scene: its file (relative to the manifest's folder, as written) and
/// the sensor pose in the scene's world frame.
struct ManifestFrame {
    std::string file;
    Eigen::Matrix4d T_world_sensor = Eigen::Matrix4d::Identity();
};

/// One scene with its frames in file order (id -1 when the manifest gives none).
struct ManifestScene {
    long long id = -1;
    std::vector<ManifestFrame> frames;
};

/// The scenes of a manifest. Throws IoError or FormatError naming the file (not JSON, no
/// "scenes" list, a frame without a file name or without a 4x4 T_world_sensor of finite numbers).
std::vector<ManifestScene> ReadSimManifest(const std::filesystem::path& path);

/// Same for text already in memory; `path` names it in messages.
std::vector<ManifestScene> ParseSimManifest(std::string_view text,
                                            const std::filesystem::path& path);

}  // namespace multicue::cli

#include "manifest.hpp"

#include <fstream>
#include <string>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "multicue/core/exceptions.hpp"

namespace multicue::cli {

std::vector<ManifestFrame> ReadManifestFrames(const std::filesystem::path& path, int scene_id) {
    std::ifstream in(path);
    if (!in) throw IoError(path.string() + ": cannot open the manifest");
    nlohmann::json manifest;
    try {
        manifest = nlohmann::json::parse(in);
    } catch (const nlohmann::json::exception& e) {
        throw FormatError(path.string() + ": not a JSON manifest (" + e.what() + ")");
    }
    const auto where = path.string();
    if (!manifest.is_object() || !manifest.contains("scenes") || !manifest["scenes"].is_array()) {
        throw FormatError(where + ": no 'scenes' array (a manifest of `multicue simulate scenes`)");
    }
    const nlohmann::json* scene = nullptr;
    for (const auto& s : manifest["scenes"]) {
        if (scene_id < 0 || (s.contains("id") && s["id"] == scene_id)) {
            scene = &s;
            break;
        }
    }
    if (scene == nullptr) {
        throw InvalidArgument(fmt::format("{}: no scene with id {}", where, scene_id));
    }
    std::vector<ManifestFrame> frames;
    try {
        for (const auto& f : scene->at("frames")) {
            ManifestFrame frame;
            frame.file = path.parent_path() / f.at("file").get<std::string>();
            if (f.contains("T_world_sensor") && !f["T_world_sensor"].is_null()) {
                const auto& T = f["T_world_sensor"];
                if (!T.is_array() || T.size() != 4) throw FormatError("T_world_sensor is not 4x4");
                Eigen::Isometry3f pose = Eigen::Isometry3f::Identity();
                for (int r = 0; r < 4; ++r) {
                    if (!T[r].is_array() || T[r].size() != 4) {
                        throw FormatError("T_world_sensor is not 4x4");
                    }
                    for (int c = 0; c < 4; ++c) pose.matrix()(r, c) = T[r][c].get<float>();
                }
                if (!pose.matrix().allFinite()) throw FormatError("T_world_sensor is not finite");
                frame.T_world_sensor = pose;
            }
            if (f.contains("pose_noisy")) frame.pose_noisy = f["pose_noisy"].get<bool>();
            frames.push_back(std::move(frame));
        }
    } catch (const nlohmann::json::exception& e) {
        throw FormatError(fmt::format("{}: bad frame entry ({})", where, e.what()));
    } catch (const FormatError& e) {
        throw FormatError(fmt::format("{}: {}", where, e.what()));
    }
    if (frames.empty()) throw FormatError(where + ": the scene has no frames");
    return frames;
}

}  // namespace multicue::cli

#include "sim_manifest.hpp"

#include <cmath>
#include <limits>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "multicue/core/exceptions.hpp"
#include "multicue/io/file_utils.hpp"
#include "multicue/io/json_text.hpp"

namespace multicue::cli {
namespace {

Eigen::Matrix4d ReadPose(const nlohmann::json& T, const std::string& where) {
    if (!T.is_array() || T.size() != 4) throw FormatError(where + ": T_world_sensor is not 4x4");
    Eigen::Matrix4d m;
    for (std::size_t r = 0; r < 4; ++r) {
        if (!T[r].is_array() || T[r].size() != 4) {
            throw FormatError(where + ": T_world_sensor is not 4x4");
        }
        for (std::size_t c = 0; c < 4; ++c) {
            const auto& v = T[r][c];
            // Poses are used in single precision too: beyond its range is no pose.
            if (!v.is_number() ||
                !(std::abs(v.get<double>()) <= std::numeric_limits<float>::max())) {
                throw FormatError(where +
                                  ": T_world_sensor holds a value that is not a finite "
                                  "number");
            }
            m(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(c)) = v.get<double>();
        }
    }
    return m;
}

}  // namespace

std::vector<ManifestScene> ParseSimManifest(std::string_view text,
                                            const std::filesystem::path& path) {
    const std::string where = path.string();
    const nlohmann::json manifest = io::ParseJsonText(text, where);
    if (!manifest.is_object() || !manifest.contains("scenes") || !manifest["scenes"].is_array()) {
        throw FormatError(where + ": no 'scenes' list (not a manifest of `multicue simulate`)");
    }
    std::vector<ManifestScene> scenes;
    for (const auto& s : manifest["scenes"]) {
        if (!s.is_object()) throw FormatError(where + ": a scene is not a JSON object");
        ManifestScene scene;
        if (s.contains("id")) {
            if (!s["id"].is_number_integer())
                throw FormatError(where + ": a scene id is not an integer");
            scene.id = s["id"].get<long long>();
        }
        const std::string in_scene = fmt::format("{} scene {}", where, scene.id);
        if (s.contains("frames") && !s["frames"].is_array()) {
            throw FormatError(in_scene + ": 'frames' is not a list");
        }
        for (const auto& f : s.value("frames", nlohmann::json::array())) {
            if (!f.is_object() || !f.contains("file") || !f["file"].is_string()) {
                throw FormatError(in_scene + ": a frame has no 'file' name");
            }
            ManifestFrame frame;
            frame.file = f["file"].get<std::string>();
            if (frame.file.empty()) throw FormatError(in_scene + ": a frame's 'file' is empty");
            if (!f.contains("T_world_sensor")) {
                throw FormatError(in_scene + " " + frame.file + ": no T_world_sensor");
            }
            frame.T_world_sensor = ReadPose(f["T_world_sensor"], in_scene + " " + frame.file);
            scene.frames.push_back(std::move(frame));
        }
        scenes.push_back(std::move(scene));
    }
    return scenes;
}

std::vector<ManifestScene> ReadSimManifest(const std::filesystem::path& path) {
    return ParseSimManifest(io::ReadFileBytes(path), path);
}

}  // namespace multicue::cli

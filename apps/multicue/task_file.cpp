#include "task_file.hpp"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <set>
#include <string>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "multicue/core/exceptions.hpp"
#include "multicue/io/file_utils.hpp"
#include "multicue/system/executive_json.hpp"
#include "sim_manifest.hpp"

namespace multicue::cli {
namespace {

namespace fs = std::filesystem;

/// YAML nodes as JSON values. Nesting is bounded like JSON's (io::kMaxJsonDepth), and so is the
/// number of values: YAML aliases repeat a node wherever they stand, so a few lines can name
/// billions of values.
class YamlConverter {
  public:
    YamlConverter(std::size_t text_size, std::string where)
        : budget_(4 * text_size + 1024), where_(std::move(where)) {}

    nlohmann::json Convert(const YAML::Node& node, int depth = 0) {
        if (depth >= kMaxDepth) {
            throw FormatError(
                fmt::format("{}: YAML nested deeper than {} levels", where_, kMaxDepth));
        }
        if (budget_-- == 0) {
            throw FormatError(fmt::format("{}: YAML aliases expand to too many values", where_));
        }
        switch (node.Type()) {
            case YAML::NodeType::Map: {
                nlohmann::json object = nlohmann::json::object();
                for (const auto& item : node)
                    object[item.first.as<std::string>()] = Convert(item.second, depth + 1);
                return object;
            }
            case YAML::NodeType::Sequence: {
                nlohmann::json array = nlohmann::json::array();
                for (const auto& item : node) array.push_back(Convert(item, depth + 1));
                return array;
            }
            case YAML::NodeType::Scalar:
                return Scalar(node);
            default:
                return nullptr;
        }
    }

  private:
    static constexpr int kMaxDepth = 64;

    static nlohmann::json Scalar(const YAML::Node& node) {
        const std::string& text = node.Scalar();
        if (node.Tag() == "!") return text;  // quoted
        if (text == "true" || text == "false") return text == "true";
        if (text == "null" || text == "~") return nullptr;
        try {
            std::size_t used = 0;
            const double v = std::stod(text, &used);
            // "nan" and "inf" stay text: no value of a task file may be non-finite.
            if (used == text.size() && std::isfinite(v)) return v;
        } catch (const std::exception&) {
        }
        return text;
    }

    std::size_t budget_;
    std::string where_;
};

Eigen::Isometry3d PoseFromList(const nlohmann::json& value, const std::string& where) {
    if (!value.is_array() || value.size() != 16) {
        throw InvalidArgument(where + ": pose must be 16 numbers (row-major 4x4)");
    }
    Eigen::Matrix4d m;
    for (int i = 0; i < 16; ++i) {
        const auto& v = value[static_cast<std::size_t>(i)];
        if (!v.is_number() || !std::isfinite(v.get<double>())) {
            throw InvalidArgument(where + ": pose must be finite numbers");
        }
        m(i / 4, i % 4) = v.get<double>();
    }
    Eigen::Isometry3d T;
    T.matrix() = m;
    return T;
}

void CheckKeys(const nlohmann::json& object, const std::set<std::string>& allowed,
               const std::string& where) {
    if (!object.is_object()) throw InvalidArgument(where + ": expected a mapping of keys");
    for (const auto& [key, value] : object.items()) {
        if (allowed.count(key) == 0) throw InvalidArgument(where + ": unknown key '" + key + "'");
    }
}

/// Frames of a simulator manifest (`multicue simulate`): every frame of the listed scenes (all by
/// default) in file order, with the sensor poses; times count frames.
template <typename Resolve>
void ReadManifestFrames(const nlohmann::json& spec, const Resolve& resolve,
                        const std::string& where, TaskFile& t) {
    CheckKeys(spec, {"manifest", "scenes"}, where + " frames");
    const fs::path manifest_path = resolve(spec.at("manifest").get<std::string>());
    std::set<long long> wanted;
    for (const auto& id : spec.value("scenes", nlohmann::json::array()))
        wanted.insert(id.get<long long>());
    const fs::path base = manifest_path.parent_path();
    for (const auto& scene : ReadSimManifest(manifest_path)) {
        if (!wanted.empty() && wanted.count(scene.id) == 0) continue;
        for (const auto& f : scene.frames) {
            Frame frame;
            frame.T_world_sensor.matrix() = f.T_world_sensor;
            frame.time = static_cast<double>(t.frames.size());
            frame.name = f.file;
            t.files.push_back(base / f.file);
            t.frames.push_back(std::move(frame));
        }
    }
    if (t.frames.empty()) throw InvalidArgument(where + ": the manifest names no frames");
}

}  // namespace

TaskFile ParseTaskFile(std::string_view text, const fs::path& path) {
    const std::string where = path.string();
    nlohmann::json j;
    try {
        j = YamlConverter(text.size(), where).Convert(YAML::Load(std::string(text)));
    } catch (const YAML::Exception& e) {
        throw FormatError(where + ": malformed YAML (" + e.what() + ")");
    }
    if (!j.is_object()) throw FormatError(where + ": a task file is a mapping of keys");
    CheckKeys(j,
              {"task", "target", "database", "learn", "region", "possible_objects", "frames",
               "output", "params"},
              where);
    const fs::path base = path.parent_path();
    auto resolve = [&](const std::string& p) {
        return p.empty() || fs::path(p).is_absolute() ? fs::path(p) : base / p;
    };
    TaskFile t;
    try {
        t.task = TaskFromJson(j, where);
        t.database = resolve(j.value("database", std::string()));
        t.output = resolve(j.value("output", std::string()));
        t.params = resolve(j.value("params", std::string()));
        if (j.contains("frames") && j["frames"].is_object()) {
            ReadManifestFrames(j["frames"], resolve, where, t);
        } else {
            if (!j.contains("frames") || !j["frames"].is_array() || j["frames"].empty()) {
                throw InvalidArgument(where +
                                      ": 'frames' must list at least one frame or name a manifest");
            }
            std::size_t index = 0;
            for (const auto& f : j["frames"]) {
                const std::string fw = fmt::format("{} frame {}", where, index + 1);
                Frame frame;
                std::string file;
                frame.time = static_cast<double>(index);
                if (f.is_string()) {
                    file = f.get<std::string>();
                } else {
                    CheckKeys(f, {"file", "pose", "time"}, fw);
                    file = f.at("file").get<std::string>();
                    if (f.contains("pose")) frame.T_world_sensor = PoseFromList(f["pose"], fw);
                    frame.time = f.value("time", frame.time);
                }
                frame.name = file;
                t.files.push_back(resolve(file));
                t.frames.push_back(std::move(frame));
                ++index;
            }
        }
    } catch (const nlohmann::json::exception& e) {
        throw InvalidArgument(where + ": " + e.what());
    }
    return t;
}

TaskFile ReadTaskFile(const fs::path& path) { return ParseTaskFile(io::ReadFileBytes(path), path); }

}  // namespace multicue::cli

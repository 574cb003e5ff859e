// `multicue run TASK.yaml`: the perception executive over a sequence of frames, identifying what it
// sees against the object model database and learning from it.

#include <yaml-cpp/yaml.h>

#include <cstdio>
#include <filesystem>
#include <memory>
#include <set>
#include <string>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "cli_util.hpp"
#include "commands.hpp"
#include "multicue/core/exceptions.hpp"
#include "multicue/core/progress.hpp"
#include "multicue/io/config.hpp"
#include "multicue/io/file_utils.hpp"
#include "multicue/system/executive.hpp"
#include "multicue/system/executive_json.hpp"
#include "multicue/training/part_graph_training.hpp"

namespace multicue::cli {
namespace {

namespace fs = std::filesystem;

nlohmann::json YamlToJson(const YAML::Node& node) {
    switch (node.Type()) {
        case YAML::NodeType::Map: {
            nlohmann::json object = nlohmann::json::object();
            for (const auto& item : node)
                object[item.first.as<std::string>()] = YamlToJson(item.second);
            return object;
        }
        case YAML::NodeType::Sequence: {
            nlohmann::json array = nlohmann::json::array();
            for (const auto& item : node) array.push_back(YamlToJson(item));
            return array;
        }
        case YAML::NodeType::Scalar: {
            const std::string text = node.Scalar();
            if (node.Tag() == "!") return text;  // quoted
            if (text == "true" || text == "false") return text == "true";
            if (text == "null" || text == "~") return nullptr;
            try {
                std::size_t used = 0;
                const double v = std::stod(text, &used);
                if (used == text.size()) return v;
            } catch (const std::exception&) {
            }
            return text;
        }
        default:
            return nullptr;
    }
}

struct TaskFile {
    Task task;
    fs::path database;
    fs::path output;
    fs::path params;
    std::vector<Frame> frames;  // clouds loaded lazily: names and poses only
    std::vector<fs::path> files;
};

Eigen::Isometry3d PoseFromList(const nlohmann::json& value, const std::string& where) {
    if (!value.is_array() || value.size() != 16) {
        throw InvalidArgument(where + ": pose must be 16 numbers (row-major 4x4)");
    }
    Eigen::Matrix4d m;
    for (int i = 0; i < 16; ++i) {
        if (!value[static_cast<std::size_t>(i)].is_number()) {
            throw InvalidArgument(where + ": pose must be numbers");
        }
        m(i / 4, i % 4) = value[static_cast<std::size_t>(i)].get<double>();
    }
    Eigen::Isometry3d T;
    T.matrix() = m;
    return T;
}

void CheckKeys(const nlohmann::json& object, const std::set<std::string>& allowed,
               const std::string& where) {
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
    nlohmann::json manifest;
    try {
        manifest = nlohmann::json::parse(io::ReadFileBytes(manifest_path));
    } catch (const nlohmann::json::parse_error& e) {
        throw FormatError(manifest_path.string() + ": malformed JSON (" + e.what() + ")");
    }
    if (!manifest.is_object() || !manifest.contains("scenes") || !manifest["scenes"].is_array()) {
        throw FormatError(manifest_path.string() + ": not a simulator manifest (no 'scenes')");
    }
    std::set<long long> wanted;
    for (const auto& id : spec.value("scenes", nlohmann::json::array()))
        wanted.insert(id.get<long long>());
    const fs::path base = manifest_path.parent_path();
    for (const auto& scene : manifest["scenes"]) {
        const long long id = scene.value("id", -1LL);
        if (!wanted.empty() && wanted.count(id) == 0) continue;
        for (const auto& f : scene.value("frames", nlohmann::json::array())) {
            Frame frame;
            const std::string file = f.at("file").get<std::string>();
            const auto& rows = f.at("T_world_sensor");
            nlohmann::json flat = nlohmann::json::array();
            for (const auto& row : rows) {
                for (const auto& v : row) flat.push_back(v);
            }
            frame.T_world_sensor = PoseFromList(flat, manifest_path.string() + " " + file);
            frame.time = static_cast<double>(t.frames.size());
            frame.name = file;
            t.files.push_back(base / file);
            t.frames.push_back(std::move(frame));
        }
    }
    if (t.frames.empty()) throw InvalidArgument(where + ": the manifest names no frames");
}

TaskFile ReadTaskFile(const fs::path& path) {
    const std::string text = io::ReadFileBytes(path);
    nlohmann::json j;
    try {
        j = YamlToJson(YAML::Load(text));
    } catch (const YAML::Exception& e) {
        throw FormatError(path.string() + ": malformed YAML (" + e.what() + ")");
    }
    const std::string where = path.string();
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

}  // namespace

void AddRunCommand(CLI::App& app, const GlobalOptions& global) {
    auto* cmd = app.add_subcommand(
        "run", "run a perception task (enumerate, find, model) over a sequence of frames");
    auto path = std::make_shared<std::string>();
    auto out = std::make_shared<std::string>();
    cmd->add_option("TASK", *path, "task file (.yaml or .json)")->required();
    cmd->add_option("--out", *out, "result JSON (default: the task file's 'output', else stdout)");
    cmd->callback([path, out, &global] {
        TaskFile t = ReadTaskFile(*path);
        ExecutiveParams params;
        if (!t.params.empty()) {
            auto config = io::ConfigSection::Load(t.params);
            ReadPerceiveParams(config, params.perceive);
            config.CheckAllUsed();
        }
        if (global.threads != 0) params.perceive.num_threads = global.threads;
        std::optional<ObjectDatabase> db;
        if (!t.database.empty())
            db = ObjectDatabase::Open(t.database, DatabaseMode::kCreateOrWrite);
        PerceptionExecutive executive(db ? &*db : nullptr, params,
                                      training::LoadPerceiveModels(params.perceive));
        const auto plan = executive.Plan(t.task);

        InstallInterruptHandler();
        Progress progress("run", t.frames.size());
        nlohmann::ordered_json frames = nlohmann::ordered_json::array();
        for (std::size_t i = 0; i < t.frames.size() && !InterruptRequested(); ++i) {
            Frame& frame = t.frames[i];
            frame.cloud = ReadNonEmptyCloud(t.files[i]);
            const FrameReport report = executive.Run(frame, t.task);
            frame.cloud = PointCloud();
            nlohmann::ordered_json jf = FrameReportJson(report, t.task, db ? &*db : nullptr);
            frames.push_back(std::move(jf));
            progress.Advance();
        }
        progress.Finish();
        nlohmann::ordered_json result;
        result["task"] = *path;
        result["plan"] = plan;
        result["interrupted"] = InterruptRequested();
        result["frames"] = frames;
        const fs::path target = !out->empty() ? fs::path(*out) : t.output;
        const std::string text = result.dump(1) + "\n";
        if (target.empty()) {
            std::fwrite(text.data(), 1, text.size(), stdout);
        } else {
            io::WriteFileAtomically(target, [&](std::ostream& o) { o << text; });
            std::fprintf(stderr, "run: %zu frames, result in %s\n", frames.size(), target.c_str());
        }
        if (InterruptRequested())
            throw DataError("interrupted; the frames done so far were written");
    });
}

}  // namespace multicue::cli

// `multicue perceive` (the main job), `multicue config` and `multicue demo`.

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "cli_util.hpp"
#include "commands.hpp"
#include "multicue/core/exceptions.hpp"
#include "multicue/io/config.hpp"
#include "multicue/io/pcd.hpp"
#include "multicue/sim/mesh.hpp"
#include "multicue/sim/rng.hpp"
#include "multicue/sim/scene_gen.hpp"
#include "multicue/sim/sensors.hpp"
#include "multicue/system/perceive.hpp"
#include "multicue/system/perceive_output.hpp"
#include "multicue/system/perceive_report.hpp"
#include "multicue/system/perceive_views.hpp"
#include "multicue/training/part_graph_training.hpp"
#include "sim_manifest.hpp"

namespace multicue::cli {
namespace {

double MsSince(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
        .count();
}

/// Everything a parameter file sets (the pipeline and the report), and the models it names.
struct PerceiveOptions {
    PerceiveParams pipeline;
    ReportParams report;
    PerceiveModels models;
};

/// The parameters of `config_path` (none: the defaults) with the command line's, checked; with
/// `load_models`, the categoriser's models loaded (the default model trained once if needed).
PerceiveOptions LoadParams(const std::string& config_path, const std::string& up, int threads,
                           bool load_models = true) {
    PerceiveOptions options;
    if (!config_path.empty()) {
        auto config = io::ConfigSection::Load(config_path);
        ReadPerceiveParams(config, options.pipeline);
        ReadReportParams(config, options.report);
        config.CheckAllUsed();
    }
    if (!up.empty()) options.pipeline.support.up = ParseVector3(up, "--up");
    if (threads != 0) options.pipeline.num_threads = threads;
    try {
        options.pipeline.Validate();
    } catch (const InvalidArgument& e) {
        throw InvalidArgument(
            fmt::format("{}: {}", config_path.empty() ? "parameters" : config_path, e.what()));
    }
    if (load_models) options.models = training::LoadPerceiveModels(options.pipeline);
    return options;
}

/// Runs the pipeline on `cloud` and writes the outputs; returns the result for a summary. The
/// pipeline works in `cloud` itself (it gains normals), so a large cloud is not held twice.
PerceiveResult RunPerceive(PointCloud& cloud, const std::string& input_name,
                           const std::filesystem::path& out, const PerceiveOptions& options,
                           double load_ms) {
    const PerceiveResult result = PerceiveInPlace(cloud, options.pipeline, options.models);
    const auto json = PerceiveResultJson(input_name, result, {{"load", load_ms}});
    const std::string report =
        options.report.enabled ? PerceiveReportPage(cloud, result, json, options.report).Render()
                               : std::string();
    WritePerceiveOutputs(out, json, PerceiveLabelsCloud(cloud, result), PerceiveModelsMesh(result),
                         report);
    return result;
}

std::string Summary(const PerceiveResult& result, const std::filesystem::path& out,
                    const ReportParams& report) {
    std::string s = fmt::format("support plane: {}\nobjects: {}\n",
                                result.support.found ? "found" : "none", result.objects.size());
    for (const auto& o : result.objects) {
        s += fmt::format("  {:>2}  {:<8} {:.2f}  {:>6} points  centroid ({:.3f}, {:.3f}, {:.3f})\n",
                         o.id, CategoryName(o.category.category), o.category.confidence,
                         o.indices.size(), o.centroid.x(), o.centroid.y(), o.centroid.z());
    }
    double total = 0;
    for (const auto& [stage, ms] : result.timings_ms) total += ms;
    s += fmt::format("pipeline: {:.1f} ms\noutputs: {}, {}, {}", total,
                     (out / "result.json").string(), (out / "labels.pcd").string(),
                     (out / "models.ply").string());
    if (report.enabled) s += ", " + (out / "report.html").string();
    s += "\n";
    if (report.enabled && !ReportViewerAvailable()) {
        s += "note: this build has no 3D viewer; report.html shows the tables only (run "
             "scripts/setup.sh, then configure and build again)\n";
    }
    return s;
}

/// One frame of a simulator manifest: its file and pose in the scene's world frame.
struct ViewFrame {
    std::filesystem::path file;
    Eigen::Isometry3f T_world_sensor = Eigen::Isometry3f::Identity();
};

/// The frames of scene `scene_id` (the first scene if negative) of a `multicue simulate scenes`
/// manifest.json.
std::vector<ViewFrame> ReadManifestFrames(const std::filesystem::path& path, int scene_id) {
    const auto scenes = ReadSimManifest(path);
    const auto where = path.string();
    const ManifestScene* scene = nullptr;
    for (const auto& s : scenes) {
        if (scene_id < 0 || s.id == scene_id) {
            scene = &s;
            break;
        }
    }
    if (scene == nullptr) {
        throw InvalidArgument(fmt::format("{}: no scene with id {}", where, scene_id));
    }
    std::vector<ViewFrame> frames;
    for (const auto& f : scene->frames) {
        ViewFrame frame;
        frame.file = path.parent_path() / f.file;
        frame.T_world_sensor.matrix() = f.T_world_sensor.cast<float>();
        frames.push_back(std::move(frame));
    }
    if (frames.empty()) throw FormatError(where + ": the scene has no frames");
    return frames;
}

/// Several registered frames: perceived one by one, categories fused in a voxel grid, outputs
/// written per frame into OUT/<frame name>/.
void RunPerceiveViews(const std::filesystem::path& manifest, int scene_id,
                      const std::filesystem::path& out, const PerceiveOptions& options,
                      bool quiet) {
    const auto frames = ReadManifestFrames(manifest, scene_id);
    std::vector<PointCloud> clouds;
    std::vector<double> load_ms;
    for (const auto& f : frames) {
        const auto start = std::chrono::steady_clock::now();
        clouds.push_back(ReadNonEmptyCloud(f.file));
        load_ms.push_back(MsSince(start));
    }
    std::vector<PerceiveResult> results;
    std::vector<const PointCloud*> cloud_ptrs;
    std::vector<Eigen::Isometry3f> poses;
    for (std::size_t k = 0; k < frames.size(); ++k) {
        results.push_back(Perceive(clouds[k], options.pipeline, options.models));
        cloud_ptrs.push_back(&clouds[k]);
        poses.push_back(frames[k].T_world_sensor);
    }
    FuseViewCategories(cloud_ptrs, poses, results, options.pipeline);
    for (std::size_t k = 0; k < frames.size(); ++k) {
        const auto dir = out / frames[k].file.stem();
        auto json = PerceiveResultJson(frames[k].file.string(), results[k], {{"load", load_ms[k]}});
        json["views"] = {{"frames", frames.size()}, {"voxel_size", ViewFusionParams{}.voxel_size}};
        const std::string report =
            options.report.enabled
                ? PerceiveReportPage(clouds[k], results[k], json, options.report).Render()
                : std::string();
        WritePerceiveOutputs(dir, json, PerceiveLabelsCloud(clouds[k], results[k]),
                             PerceiveModelsMesh(results[k]), report);
        if (!quiet) {
            std::printf("frame %zu of %zu: %s\n", k + 1, frames.size(), frames[k].file.c_str());
            std::fputs(Summary(results[k], dir, options.report).c_str(), stdout);
        }
    }
}

}  // namespace

void AddPerceiveCommand(CLI::App& app, const GlobalOptions& global) {
    auto* cmd = app.add_subcommand(
        "perceive",
        "Find the support plane and the objects on it, their parts, categories and models");
    auto in = std::make_shared<std::string>();
    auto out = std::make_shared<std::string>();
    auto config = std::make_shared<std::string>();
    auto up = std::make_shared<std::string>();
    auto quiet = std::make_shared<bool>(false);
    auto no_report = std::make_shared<bool>(false);
    auto manifest = std::make_shared<std::string>();
    auto scene = std::make_shared<int>(-1);
    cmd->add_option("INPUT", *in, "point cloud (.pcd or .ply), organized or not");
    cmd->add_option("--manifest", *manifest,
                    "several registered frames instead of INPUT: a manifest.json of `multicue "
                    "simulate scenes`; categories are fused over its frames in 5 mm voxels and "
                    "each frame's outputs go to OUT/<frame name>/");
    cmd->add_option("--scene", *scene, "with --manifest: the scene id (default: the first scene)");
    cmd->add_option("--out", *out,
                    "output folder: result.json, labels.pcd, models.ply, report.html")
        ->required();
    cmd->add_option("--config", *config, "JSON parameter file (see `multicue config --dump`)");
    cmd->add_option("--up", *up, "x,y,z up direction in the cloud's frame");
    cmd->add_flag("--no-report", *no_report,
                  "do not write report.html (same as \"report\": {\"enabled\": false})");
    cmd->add_flag("-q,--quiet", *quiet, "print nothing on success");
    cmd->callback([=, &global] {
        if (in->empty() == manifest->empty()) {
            throw InvalidArgument("perceive: give either INPUT or --manifest");
        }
        if (manifest->empty() && *scene >= 0) {
            throw InvalidArgument("perceive: --scene needs --manifest");
        }
        PerceiveOptions options = LoadParams(*config, *up, global.threads);
        if (*no_report) options.report.enabled = false;
        if (!manifest->empty()) {
            RunPerceiveViews(*manifest, *scene, *out, options, *quiet);
            return;
        }
        const auto start = std::chrono::steady_clock::now();
        PointCloud cloud = ReadNonEmptyCloud(*in);
        const double load_ms = MsSince(start);
        const PerceiveResult result = RunPerceive(cloud, *in, *out, options, load_ms);
        if (!*quiet) std::fputs(Summary(result, *out, options.report).c_str(), stdout);
    });
}

void AddConfigCommand(CLI::App& app, const GlobalOptions& /*global*/) {
    auto* cmd = app.add_subcommand(
        "config", "Print the default parameters of perceive (JSON with comments) or check a file");
    auto dump = std::make_shared<bool>(false);
    auto markdown = std::make_shared<bool>(false);
    auto check = std::make_shared<std::string>();
    cmd->add_flag("--dump", *dump, "print every parameter with its default and meaning");
    cmd->add_flag("--markdown", *markdown,
                  "print the parameter reference as Markdown tables (docs/configuration.md)");
    cmd->add_option("--check", *check,
                    "read a parameter file and report the first problem (unknown key, wrong type "
                    "or value out of range)");
    cmd->callback([=] {
        if (!check->empty()) {
            LoadParams(*check, "", 0, false);
            std::printf("%s: ok\n", check->c_str());
            return;
        }
        if (!*dump && !*markdown)
            throw InvalidArgument("config: give --dump, --markdown or --check FILE");
        auto section = io::ConfigSection::Dump();
        PerceiveOptions options;
        ReadPerceiveParams(section, options.pipeline);
        ReadReportParams(section, options.report);
        if (!*markdown) {
            std::fputs(section.DumpText().c_str(), stdout);
            return;
        }
        std::string text = section.DumpMarkdown();
        text +=
            "## Former keys\n\nFiles of earlier releases are read with these keys under their "
            "current names (`perceive` warns once per key).\n\n| former key | current key |\n"
            "|---|---|\n";
        for (const auto& [from, to] : PerceiveRenamedKeys()) {
            text += fmt::format("| `{}` | `{}` |\n", from, to);
        }
        std::fputs(text.c_str(), stdout);
    });
}

void AddDemoCommand(CLI::App& app, const GlobalOptions& global) {
    auto* cmd = app.add_subcommand(
        "demo", "Build a synthetic table-top scene, run perceive on it and write the results");
    auto out = std::make_shared<std::string>("multicue-demo");
    auto no_report = std::make_shared<bool>(false);
    cmd->add_option("--out", *out, "output folder (created if missing)")->capture_default_str();
    cmd->add_flag("--no-report", *no_report, "do not write report.html");
    cmd->callback([out, no_report, &global] {
        const std::filesystem::path dir = *out;
        // Scene 3 of `multicue simulate scenes --objects 5,5 --clutter 0 --seed 1`: five
        // procedural objects of five categories on a table, one simulated Kinect view.
        sim::TableSceneParams table;
        table.min_objects = table.max_objects = 5;
        table.clutter = 0.0f;
        const std::uint64_t seed = sim::SubSeed(1, 3);
        const sim::Scene scene = sim::MakeTableScene(table, seed);
        const auto pose = sim::TableViewpoints(scene, 1, {}, seed).front();
        PointCloud cloud =
            sim::ScanKinect(scene, pose, sim::KinectParams{}, sim::SubSeed(seed, 100));
        std::error_code ec;
        std::filesystem::create_directories(dir, ec);
        if (!std::filesystem::is_directory(dir)) {
            throw IoError(fmt::format("{}: cannot create output folder", dir.string()));
        }
        io::WritePcd(dir / "scene.pcd", cloud);
        PerceiveOptions options;
        options.pipeline.num_threads = global.threads;
        options.report.enabled = !*no_report;
        const PerceiveResult result =
            RunPerceive(cloud, (dir / "scene.pcd").string(), dir, options, 0.0);
        std::string objects;
        for (const auto& o : scene.objects) {
            if (o.label < sim::ObjectLabel(1)) continue;
            objects += (objects.empty() ? "" : ", ") + o.source;
        }
        std::printf(
            "multicue demo: simulated Kinect view (%ux%u) of a table with %zu objects (%s) "
            "-> %s\n%s",
            cloud.width, cloud.height, scene.NumObjects(), objects.c_str(),
            (dir / "scene.pcd").string().c_str(), Summary(result, dir, options.report).c_str());
    });
}

}  // namespace multicue::cli

// `multicue perceive` (the main job), `multicue config` and `multicue demo`.

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "cli_util.hpp"
#include "commands.hpp"
#include "manifest.hpp"
#include "multicue/core/exceptions.hpp"
#include "multicue/core/logging.hpp"
#include "multicue/io/config.hpp"
#include "multicue/io/pcd.hpp"
#include "multicue/registration/incremental_map.hpp"
#include "multicue/sim/mesh.hpp"
#include "multicue/sim/rng.hpp"
#include "multicue/sim/scene_gen.hpp"
#include "multicue/sim/sensors.hpp"
#include "multicue/system/perceive.hpp"
#include "multicue/system/perceive_output.hpp"
#include "multicue/system/perceive_report.hpp"
#include "multicue/system/perceive_views.hpp"
#include "multicue/system/report_writer.hpp"
#include "multicue/training/part_graph_training.hpp"
#include "perceive_bag.hpp"
#include "registration_json.hpp"

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
/// pipeline works in `cloud` itself (it gains normals) and the labels cloud takes its points, so a
/// large cloud is not held twice; `cloud` is empty afterwards.
PerceiveResult RunPerceive(PointCloud& cloud, const std::string& input_name,
                           const std::filesystem::path& out, const PerceiveOptions& options,
                           double load_ms) {
    const PerceiveResult result = PerceiveInPlace(cloud, options.pipeline, options.models);
    const auto json = PerceiveResultJson(input_name, result, {{"load", load_ms}});
    const std::string report =
        options.report.enabled ? PerceiveReportPage(cloud, result, json, options.report).Render()
                               : std::string();
    WritePerceiveOutputs(out, json, PerceiveLabelsCloud(std::move(cloud), result),
                         PerceiveModelsMesh(result), report);
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

/// The poses of the frames: the manifest's when every frame has one that is not flagged noisy
/// (and `register_frames` is off), else registered frame to map from the manifest's poses as
/// rough guesses (section 5.3 with the robot's poses replaced by registration). Frames that
/// could not be aligned keep their manifest pose, or, without one, are left out of the fusion
/// (`fused[k]` false).
struct ViewPoses {
    std::vector<Eigen::Isometry3f> T_world_sensor;
    std::vector<bool> fused;
    bool registered = false;
    std::vector<MapFrameResult> alignment;
};

ViewPoses FramePoses(const std::vector<ManifestFrame>& frames,
                     const std::vector<PointCloud>& clouds, bool register_frames, int threads) {
    ViewPoses v;
    v.fused.assign(frames.size(), true);
    const bool exact = std::all_of(frames.begin(), frames.end(), [](const ManifestFrame& f) {
        return f.T_world_sensor && !f.pose_noisy;
    });
    if (exact && !register_frames) {
        for (const auto& f : frames) v.T_world_sensor.push_back(*f.T_world_sensor);
        return v;
    }
    v.registered = true;
    MapParams params;
    params.registration = SuggestRegistrationParams(clouds.front());
    params.num_threads = threads;
    std::vector<const PointCloud*> ptrs;
    std::vector<std::optional<Eigen::Isometry3d>> odometry;
    for (std::size_t k = 0; k < frames.size(); ++k) {
        ptrs.push_back(&clouds[k]);
        odometry.push_back(frames[k].T_world_sensor ? std::optional<Eigen::Isometry3d>(
                                                          frames[k].T_world_sensor->cast<double>())
                                                    : std::nullopt);
    }
    v.alignment = AlignFrameSequence(ptrs, odometry, params);
    for (std::size_t k = 0; k < frames.size(); ++k) {
        const auto& a = v.alignment[k];
        if (a.in_map) {
            v.T_world_sensor.push_back(a.T_world_sensor.cast<float>());
        } else if (frames[k].T_world_sensor) {
            LogWarning("perceive: {} could not be registered ({}); its manifest pose is used",
                       frames[k].file.string(), a.registration.reason);
            v.T_world_sensor.push_back(*frames[k].T_world_sensor);
        } else {
            LogWarning(
                "perceive: {} could not be registered ({}) and has no pose; it is not "
                "fused with the other frames",
                frames[k].file.string(), a.registration.reason);
            v.T_world_sensor.push_back(Eigen::Isometry3f::Identity());
            v.fused[k] = false;
        }
    }
    return v;
}

/// Several frames of one scene: perceived one by one, categories fused in a voxel grid over the
/// frames with known poses, outputs written per frame into OUT/<frame name>/.
void RunPerceiveViews(const std::filesystem::path& manifest, int scene_id,
                      const std::filesystem::path& out, const PerceiveOptions& options,
                      bool register_frames, bool quiet) {
    const auto frames = ReadManifestFrames(manifest, scene_id);
    std::vector<PointCloud> clouds;
    std::vector<double> load_ms;
    for (const auto& f : frames) {
        const auto start = std::chrono::steady_clock::now();
        clouds.push_back(ReadNonEmptyCloud(f.file));
        load_ms.push_back(MsSince(start));
    }
    const ViewPoses poses =
        FramePoses(frames, clouds, register_frames, options.pipeline.num_threads);
    std::vector<PerceiveResult> results;
    for (std::size_t k = 0; k < frames.size(); ++k) {
        results.push_back(Perceive(clouds[k], options.pipeline, options.models));
    }
    // Fusion over the frames with a pose (all of them unless registration failed without one).
    std::vector<const PointCloud*> cloud_ptrs;
    std::vector<Eigen::Isometry3f> fused_poses;
    std::vector<PerceiveResult> fused_results;
    for (std::size_t k = 0; k < frames.size(); ++k) {
        if (!poses.fused[k]) continue;
        cloud_ptrs.push_back(&clouds[k]);
        fused_poses.push_back(poses.T_world_sensor[k]);
        fused_results.push_back(std::move(results[k]));
    }
    FuseViewCategories(cloud_ptrs, fused_poses, fused_results, options.pipeline);
    for (std::size_t k = 0, f = 0; k < frames.size(); ++k) {
        if (poses.fused[k]) results[k] = std::move(fused_results[f++]);
    }
    // The pages are written by a thread of their own while the next frames' files are written.
    std::optional<ReportWriter> reports;
    if (options.report.enabled) reports.emplace(options.report);
    for (std::size_t k = 0; k < frames.size(); ++k) {
        const auto dir = out / frames[k].file.stem();
        auto json = PerceiveResultJson(frames[k].file.string(), results[k], {{"load", load_ms[k]}});
        json["views"] = {{"frames", cloud_ptrs.size()},
                         {"voxel_size", ViewFusionParams{}.voxel_size}};
        if (poses.registered) {
            const auto& a = poses.alignment[k];
            json["views"]["poses"] = "registered";
            json["views"]["fused"] = static_cast<bool>(poses.fused[k]);
            json["views"]["T_world_sensor"] = TransformJson(poses.T_world_sensor[k].cast<double>());
            json["views"]["registration"] = RegistrationJson(a.registration);
        }
        RemoveStaleReport(dir);
        WritePerceiveOutputs(dir, json, PerceiveLabelsCloud(clouds[k], results[k]),
                             PerceiveModelsMesh(results[k]));
        if (!quiet) {
            std::printf("frame %zu of %zu: %s\n", k + 1, frames.size(), frames[k].file.c_str());
            std::fputs(Summary(results[k], dir, options.report).c_str(), stdout);
        }
        if (reports) reports->Submit(dir, std::move(clouds[k]), std::move(results[k]), json);
    }
    if (reports) reports->Finish();
    if (!quiet && poses.registered) {
        std::size_t aligned = 0;
        for (const auto& a : poses.alignment) aligned += a.in_map;
        std::printf("poses: registered (%zu of %zu frames aligned)\n", aligned, frames.size());
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
    auto register_frames = std::make_shared<bool>(false);
    cmd->add_option("INPUT", *in, "point cloud (.pcd or .ply), organized or not");
    cmd->add_option("--manifest", *manifest,
                    "several registered frames instead of INPUT: a manifest.json of `multicue "
                    "simulate scenes`; categories are fused over its frames in 5 mm voxels and "
                    "each frame's outputs go to OUT/<frame name>/");
    cmd->add_option("--scene", *scene, "with --manifest: the scene id (default: the first scene)");
    auto bag = std::make_shared<PerceiveBagOptions>();
    cmd->add_option("--bag", bag->bag,
                    "a recorded bag instead of INPUT: ROS 1 .bag, ROS 2 .db3 or .mcap (or a ROS 2 "
                    "bag folder); each message of --topic is perceived and written to "
                    "OUT/<stamp>/, with OUT/index.json listing them");
    cmd->add_option("--topic", bag->topic,
                    "with --bag: the sensor_msgs/PointCloud2 topic, e.g. "
                    "/camera/depth_registered/points");
    cmd->add_option("--max-messages", bag->max_messages,
                    "with --bag: perceive at most this many messages (0 = all)");
    cmd->add_flag("--register", *register_frames,
                  "with --manifest: register the frames (their poses are rough guesses); frames "
                  "without a pose or flagged \"pose_noisy\" are registered without it");
    cmd->add_option("--out", *out,
                    "output folder: result.json, labels.pcd, models.ply, report.html")
        ->required();
    cmd->add_option("--config", *config, "JSON parameter file (see `multicue config --dump`)");
    cmd->add_option("--up", *up, "x,y,z up direction in the cloud's frame");
    cmd->add_flag("--no-report", *no_report,
                  "do not write report.html (same as \"report\": {\"enabled\": false})");
    cmd->add_flag("-q,--quiet", *quiet, "print nothing on success");
    cmd->callback([=, &global] {
        if (int(!in->empty()) + int(!manifest->empty()) + int(!bag->bag.empty()) != 1) {
            throw InvalidArgument("perceive: give one of INPUT, --manifest or --bag");
        }
        if (bag->bag.empty() && (!bag->topic.empty() || bag->max_messages != 0)) {
            throw InvalidArgument("perceive: --topic and --max-messages need --bag");
        }
        if (manifest->empty() && *scene >= 0) {
            throw InvalidArgument("perceive: --scene needs --manifest");
        }
        if (manifest->empty() && *register_frames) {
            throw InvalidArgument("perceive: --register needs --manifest");
        }
        PerceiveOptions options = LoadParams(*config, *up, global.threads);
        if (*no_report) options.report.enabled = false;
        if (!manifest->empty()) {
            RunPerceiveViews(*manifest, *scene, *out, options, *register_frames, *quiet);
            return;
        }
        if (!bag->bag.empty()) {
            bag->out = *out;
            bag->quiet = *quiet;
            RunPerceiveBag(*bag, options.pipeline, options.report, options.models);
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
        const std::uint32_t width = cloud.width, height = cloud.height;  // RunPerceive takes it
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
            width, height, scene.NumObjects(), objects.c_str(),
            (dir / "scene.pcd").string().c_str(), Summary(result, dir, options.report).c_str());
    });
}

}  // namespace multicue::cli

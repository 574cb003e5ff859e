// `multicue map SCANS... | --manifest M --out DIR`: frames aligned one by one to the map of the
// frames before them (rough poses from the manifest, or none), an occupancy map (map.bt), an
// incrementally grown mesh (mesh.ply), the map cloud (cloud.pcd), the poses (poses.json) and a
// report page. Other map jobs attach their own subcommands to the command AddMapCommand returns
// (`multicue map kitchen ...`); the frames' own callback then does nothing.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "cli_util.hpp"
#include "commands.hpp"
#include "manifest.hpp"
#include "multicue/core/exceptions.hpp"
#include "multicue/core/progress.hpp"
#include "multicue/io/file_utils.hpp"
#include "multicue/io/pcd.hpp"
#include "multicue/io/ply.hpp"
#include "multicue/io/point_cloud_io.hpp"
#include "multicue/registration/incremental_map.hpp"
#include "multicue/system/perceive_report.hpp"
#include "registration_json.hpp"

namespace multicue::cli {
namespace {

struct MapOptions {
    std::vector<std::string> scans;
    std::string manifest, out, method = "auto";
    int scene = -1;
    float resolution = 0.0f;
    float occupancy_resolution = 0.0f;
    float max_range = 0.0f;
    float mesh_spacing = 0.0f;
    bool no_register = false, no_occupancy = false, no_mesh = false, no_report = false;
    bool quiet = false;
};

struct FrameInput {
    std::filesystem::path file;
    std::optional<Eigen::Isometry3d> odometry;
};

std::vector<FrameInput> Inputs(const MapOptions& o) {
    std::vector<FrameInput> in;
    if (!o.manifest.empty()) {
        for (const auto& f : ReadManifestFrames(o.manifest, o.scene)) {
            FrameInput fi{f.file, std::nullopt};
            if (f.T_world_sensor) fi.odometry = f.T_world_sensor->cast<double>();
            in.push_back(std::move(fi));
        }
    } else {
        for (const auto& s : o.scans) in.push_back({s, std::nullopt});
    }
    return in;
}

MapParams Params(const MapOptions& o, const PointCloud& first, int threads) {
    MapParams p;
    p.registration = SuggestRegistrationParams(first);
    if (o.resolution > 0.0f) {
        const float depth_noise = p.registration.icp.depth_noise;
        p.registration = RegistrationParams::ForResolution(o.resolution);
        p.registration.icp.depth_noise = depth_noise;
    }
    p.registration.method = ParseRegistrationMethod(o.method);
    const float r = p.registration.preprocess.voxel_size;
    p.map_voxel = r;
    p.register_frames = !o.no_register;
    p.occupancy.enabled = !o.no_occupancy;
    p.occupancy.resolution = o.occupancy_resolution > 0.0f ? o.occupancy_resolution : 2.0 * r;
    p.occupancy.max_range = o.max_range;
    p.mesh.enabled = !o.no_mesh;
    p.mesh.vertex_spacing = o.mesh_spacing > 0.0f ? o.mesh_spacing : 0.5f * r;
    p.num_threads = threads;
    p.Validate();
    return p;
}

nlohmann::ordered_json PosesJson(const std::vector<FrameInput>& inputs, const IncrementalMap& map,
                                 const MapParams& params) {
    nlohmann::ordered_json j;
    j["format"] = "multicue.poses/1";
    j["resolution"] = params.map_voxel;
    j["registered"] = params.register_frames;
    nlohmann::ordered_json frames = nlohmann::ordered_json::array();
    for (std::size_t k = 0; k < map.frames().size(); ++k) {
        const MapFrameResult& f = map.frames()[k];
        nlohmann::ordered_json fj;
        fj["file"] = inputs[k].file.string();
        fj["in_map"] = f.in_map;
        fj["T_world_sensor"] = TransformJson(f.T_world_sensor);
        fj["T_world_sensor_guess"] = TransformJson(f.T_world_sensor_guess);
        fj["global_fallback"] = f.global_fallback_used;
        fj["registration"] = RegistrationJson(f.registration);
        fj["map_points"] = f.map_points;
        fj["mesh"] = {{"new_vertices", f.mesh.new_vertices},
                      {"dropped_overlap", f.mesh.dropped_overlap},
                      {"new_triangles", f.mesh.new_triangles},
                      {"resampled_overlap", f.resampled_overlap}};
        frames.push_back(std::move(fj));
    }
    j["frames"] = std::move(frames);
    j["map"] = {
        {"points", map.cloud().size()},
        {"mesh",
         {{"vertices", map.mesh().vertices.size()}, {"triangles", map.mesh().triangles.size()}}}};
    if (const OccupancyMap* occ = map.occupancy()) {
        const OccupancyCounts c = occ->Counts();
        j["map"]["occupancy"] = {{"resolution", occ->resolution()},
                                 {"free_leaves", c.free_leaves},
                                 {"occupied_leaves", c.occupied_leaves},
                                 {"free_volume", c.free_volume},
                                 {"occupied_volume", c.occupied_volume}};
    }
    return j;
}

void WriteReport(const std::filesystem::path& path, const std::vector<FrameInput>& inputs,
                 const IncrementalMap& map) {
    // The map cloud in the perceive page's viewer (no objects), the frames as a table below.
    PerceiveResult empty;
    empty.points = map.cloud().size();
    empty.point_objects.assign(empty.points, 0);
    empty.point_categories.assign(empty.points, 0);
    nlohmann::ordered_json summary = {
        {"input", "map of " + std::to_string(inputs.size()) + " frames"}};
    ReportPage page = PerceiveReportPage(map.cloud(), empty, summary);
    page.AddHeading("Frames");
    std::vector<std::vector<std::string>> rows;
    for (std::size_t k = 0; k < map.frames().size(); ++k) {
        const auto& f = map.frames()[k];
        const auto& t = f.T_world_sensor.translation();
        rows.push_back(
            {inputs[k].file.filename().string(), f.in_map ? "yes" : "no",
             RegistrationStatusName(f.registration.status),
             fmt::format("{:.3f}", f.registration.fitness),
             fmt::format("{:.2f}", 1000.0 * f.registration.inlier_rmse),
             fmt::format("{:.2f}",
                         RotationAngleDeg(f.T_world_sensor_guess.inverse() * f.T_world_sensor)),
             fmt::format("{:.1f}", 1000.0 * TranslationNorm(f.T_world_sensor_guess.inverse() *
                                                            f.T_world_sensor)),
             fmt::format("{:.3f}, {:.3f}, {:.3f}", t.x(), t.y(), t.z())});
    }
    page.AddTable({"frame", "in map", "status", "fitness", "RMSE [mm]", "correction [deg]",
                   "correction [mm]", "position [m]"},
                  rows);
    page.Write(path);
}

void Run(const MapOptions& o, int threads) {
    if (o.out.empty()) throw InvalidArgument("map: --out DIR is required");
    if (o.manifest.empty() == o.scans.empty()) {
        throw InvalidArgument("map: give either SCANS or --manifest");
    }
    if (o.scene >= 0 && o.manifest.empty()) throw InvalidArgument("map: --scene needs --manifest");
    for (const auto& [name, v] :
         {std::pair{"--resolution", o.resolution},
          std::pair{"--occupancy-resolution", o.occupancy_resolution},
          std::pair{"--max-range", o.max_range}, std::pair{"--mesh-spacing", o.mesh_spacing}}) {
        if (!(v >= 0.0f) || !std::isfinite(v)) {
            throw InvalidArgument(fmt::format("{} must be > 0, got {}", name, v));
        }
    }
    ParseRegistrationMethod(o.method);
    const auto inputs = Inputs(o);
    if (o.no_register &&
        std::any_of(inputs.begin(), inputs.end(), [](const auto& f) { return !f.odometry; }) &&
        inputs.size() > 1) {
        throw InvalidArgument("map: --no-register needs a pose for every frame (a manifest)");
    }
    const std::filesystem::path dir = o.out;
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    if (!std::filesystem::is_directory(dir)) {
        throw IoError(fmt::format("{}: cannot create output folder", dir.string()));
    }
    InstallInterruptHandler();
    std::optional<IncrementalMap> map;
    MapParams params;
    Progress progress("map", inputs.size(),
                      o.quiet ? ProgressStyle::kSilent : ProgressStyle::kAuto);
    std::size_t done = 0;
    for (const auto& in : inputs) {
        if (InterruptRequested()) break;
        const PointCloud frame = io::ReadPointCloud(in.file);
        if (!map) {
            if (frame.CountFinite() < 3) {
                throw DataError(
                    fmt::format("{}: the first frame has no valid points", in.file.string()));
            }
            params = Params(o, frame, threads);
            map.emplace(params);
        }
        map->AddFrame(frame, in.odometry);
        progress.Advance();
        ++done;
    }
    progress.Finish();
    if (!map) throw InvalidArgument("map: no frames");
    // Outputs, each written atomically.
    const std::vector<FrameInput> used(inputs.begin(), inputs.begin() + static_cast<long>(done));
    const std::string poses = PosesJson(used, *map, params).dump(1) + "\n";
    io::WriteFileAtomically(dir / "poses.json", [&](std::ostream& s) { s << poses; });
    io::WritePcd(dir / "cloud.pcd", map->cloud());
    if (const OccupancyMap* occ = map->occupancy()) {
        io::WriteFileAtomically(dir / "map.bt", [&](std::ostream& s) { occ->WriteBinary(s); });
    }
    if (params.mesh.enabled) io::WritePlyMesh(dir / "mesh.ply", map->mesh());
    if (!o.no_report) WriteReport(dir / "report.html", used, *map);
    std::size_t in_map = 0;
    for (const auto& f : map->frames()) in_map += f.in_map;
    if (InterruptRequested()) {
        throw Error(fmt::format("interrupted after {} of {} frames; {} describes them", done,
                                inputs.size(), (dir / "poses.json").string()));
    }
    if (!o.quiet) {
        std::printf("map: %zu of %zu frames aligned and in the map, %zu map points", in_map,
                    inputs.size(), map->cloud().size());
        if (params.mesh.enabled) {
            std::printf(", mesh %zu vertices / %zu triangles", map->mesh().vertices.size(),
                        map->mesh().triangles.size());
        }
        std::printf("\noutputs: %s\n", dir.string().c_str());
        for (std::size_t k = 0; k < map->frames().size(); ++k) {
            const auto& f = map->frames()[k];
            if (!f.in_map) {
                std::printf("  left out: %s (%s)\n", used[k].file.string().c_str(),
                            f.registration.reason.c_str());
            }
        }
    }
}

}  // namespace

CLI::App* AddMapCommand(CLI::App& app, const GlobalOptions& global) {
    auto* cmd = app.add_subcommand(
        "map", "Align frames into one map: occupancy map, incremental mesh, poses");
    auto o = std::make_shared<MapOptions>();
    cmd->add_option("SCANS", o->scans, "frames in acquisition order (.pcd or .ply)");
    cmd->add_option("--manifest", o->manifest,
                    "frames and rough poses from a manifest.json (`multicue simulate scenes`)");
    cmd->add_option("--scene", o->scene, "with --manifest: the scene id (default: the first)");
    // Not required() in CLI11: subcommands attached to `map` have their own outputs.
    cmd->add_option("--out", o->out,
                    "output folder: map.bt, mesh.ply, cloud.pcd, poses.json, report.html");
    cmd->add_option("--method", o->method,
                    "frame-to-map alignment: auto (points and planes), point-to-plane, symmetric, "
                    "icp, plane")
        ->capture_default_str();
    cmd->add_option("--resolution", o->resolution,
                    "map voxel and registration scale [m] (default: 1 cm for depth frames, else "
                    "from the point spacing)");
    cmd->add_option("--occupancy-resolution", o->occupancy_resolution,
                    "smallest occupancy voxel [m] (default: 2 resolutions)");
    cmd->add_option("--max-range", o->max_range,
                    "rays longer than this free space only up to it [m]");
    cmd->add_option("--mesh-spacing", o->mesh_spacing,
                    "vertex spacing of the mesh [m] (default: half the resolution)");
    cmd->add_flag("--no-register", o->no_register, "take the manifest's poses as they are");
    cmd->add_flag("--no-occupancy", o->no_occupancy, "no occupancy map");
    cmd->add_flag("--no-mesh", o->no_mesh, "no mesh");
    cmd->add_flag("--no-report", o->no_report, "no report.html");
    cmd->add_flag("-q,--quiet", o->quiet, "print nothing on success");
    cmd->callback([cmd, o, &global] {
        if (!cmd->get_subcommands().empty()) return;  // `map <subcommand>` ran instead
        Run(*o, global.threads);
    });
    return cmd;
}

}  // namespace multicue::cli

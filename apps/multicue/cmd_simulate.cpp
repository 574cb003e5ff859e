// `multicue simulate`: simulated scans of table-top scenes, single objects on a turntable or
// furniture rooms, with ground truth per point and a manifest (docs/simulation.md).

#include <cstdio>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "commands.hpp"
#include "multicue/core/exceptions.hpp"
#include "multicue/core/progress.hpp"
#include "multicue/io/file_utils.hpp"
#include "multicue/io/point_cloud_io.hpp"
#include "multicue/sim/mesh_split.hpp"
#include "multicue/sim/procedural.hpp"
#include "multicue/sim/scene_gen.hpp"
#include "multicue/sim/sensors.hpp"
#include "registration_json.hpp"

namespace multicue::cli {
namespace {

using Json = nlohmann::json;

struct SimulateOptions {
    std::string mode;
    std::string out;
    std::uint64_t seed = 1;
    std::string sensor = "kinect";
    int scenes = 10;
    int views = 0;                 // 0: 1 per scene, 16 per object
    std::string objects;           // empty: the scene mode's range
    std::optional<float> clutter;  // unset: the scene mode's clutter
    std::string scene_mode = "default";
    std::string mesh_split = "all";
    std::string meshes;
    int count = 0;  // objects mode: procedural objects (default 2 per category)
    bool strict = false;
    bool quiet = false;
};

// A pose as rows of a 4x4 matrix (the float values, exactly, as doubles).

Json SensorJson(const std::string& sensor, const sim::KinectParams& k, const sim::LaserParams& l,
                const sim::TofParams& t) {
    if (sensor == "kinect") {
        return {{"type", "kinect"},
                {"width", k.width},
                {"height", k.height},
                {"fx", k.fx},
                {"fy", k.fy},
                {"cx", k.cx},
                {"cy", k.cy},
                {"baseline", k.baseline},
                {"disparity_step", k.disparity_step},
                {"axial_noise", k.axial_noise},
                {"disparity_sigma", sim::KinectDisparitySigma(k)},
                {"lateral_noise_px", k.lateral_noise_px},
                {"min_range", k.min_range},
                {"max_range", k.max_range},
                {"max_incidence_deg", k.max_incidence_deg},
                {"color_noise", k.color_noise},
                {"frame", "camera optical frame (x right, y down, z forward)"}};
    }
    if (sensor == "laser") {
        return {{"type", "laser"},
                {"fov_deg", l.fov_deg},
                {"beam_step_deg", l.beam_step_deg},
                {"tilt_min_deg", l.tilt_min_deg},
                {"tilt_max_deg", l.tilt_max_deg},
                {"tilt_step_deg", l.tilt_step_deg},
                {"range_noise", l.range_noise},
                {"min_range", l.min_range},
                {"max_range", l.max_range},
                {"max_incidence_deg", l.max_incidence_deg},
                {"frame", "pan-tilt head base frame (x forward, y left, z up)"}};
    }
    return {{"type", "tof"},
            {"width", t.width},
            {"height", t.height},
            {"fx", t.fx},
            {"fy", t.fy},
            {"cx", t.cx},
            {"cy", t.cy},
            {"noise_ref", t.noise_ref},
            {"ambient", t.ambient},
            {"min_amplitude", t.min_amplitude},
            {"max_noise", t.max_noise},
            {"min_range", t.min_range},
            {"max_range", t.max_range},
            {"max_incidence_deg", t.max_incidence_deg},
            {"frame", "camera optical frame (x right, y down, z forward)"}};
}

Json ObjectsJson(const sim::Scene& scene) {
    Json objects = Json::array();
    for (const auto& o : scene.objects) {
        const Eigen::Quaternionf q(o.T_world_object.linear());
        const Eigen::Vector3f t = o.T_world_object.translation();
        const Eigen::Vector3f size = o.mesh->Bounds().sizes();
        objects.push_back({{"label", o.label},
                           {"category", sim::CategoryNames().at(o.category)},
                           {"category_index", o.category},
                           {"source", o.source},
                           {"scale", o.scale},
                           {"extent", {size.x(), size.y(), size.z()}},
                           {"translation", {t.x(), t.y(), t.z()}},
                           {"rotation_wxyz", {q.w(), q.x(), q.y(), q.z()}},
                           {"color", {o.color.r, o.color.g, o.color.b}},
                           {"placement", sim::ObjectPlacementName(o.placement)},
                           {"support", o.support},
                           {"parts", o.mesh->part_names}});
    }
    return objects;
}

std::pair<int, int> ParseRange(const std::string& text) {
    int lo = 0, hi = 0;
    char comma = 0;
    std::istringstream in(text);
    if (!(in >> lo))
        throw InvalidArgument(fmt::format("--objects must be MIN,MAX, got '{}'", text));
    if (in >> comma) {
        if (comma != ',' || !(in >> hi)) {
            throw InvalidArgument(fmt::format("--objects must be MIN,MAX, got '{}'", text));
        }
    } else {
        hi = lo;
    }
    if (lo < 0 || hi < lo) {
        throw InvalidArgument(fmt::format("--objects needs 0 <= MIN <= MAX, got '{}'", text));
    }
    return {lo, hi};
}

void CheckOptions(const SimulateOptions& o) {
    if (o.mode != "scenes" && o.mode != "objects" && o.mode != "rooms") {
        throw InvalidArgument(
            fmt::format("simulate: MODE must be scenes, objects or rooms, got '{}'", o.mode));
    }
    if (o.sensor != "kinect" && o.sensor != "laser" && o.sensor != "tof") {
        throw InvalidArgument(
            fmt::format("--sensor must be kinect, laser or tof, got '{}'", o.sensor));
    }
    if (o.scenes < 0) throw InvalidArgument(fmt::format("--scenes must be >= 0, got {}", o.scenes));
    if (o.views < 0) throw InvalidArgument(fmt::format("--views must be >= 0, got {}", o.views));
    if (o.count < 0) throw InvalidArgument(fmt::format("--count must be >= 0, got {}", o.count));
    if (o.mode == "rooms" && o.meshes.empty()) {
        throw InvalidArgument("simulate rooms needs --meshes with a furniture library");
    }
    try {
        sim::ParseTableSceneMode(o.scene_mode);
    } catch (const InvalidArgument&) {
        throw InvalidArgument(fmt::format(
            "--mode must be default, boxes, stacked, occluded, cylindric, mixed or complex, got "
            "'{}'",
            o.scene_mode));
    }
    if (o.scene_mode != "default" && o.mode != "scenes") {
        throw InvalidArgument(fmt::format("--mode {} needs simulate scenes", o.scene_mode));
    }
    try {
        sim::ParseMeshSplit(o.mesh_split);
    } catch (const InvalidArgument&) {
        throw InvalidArgument(
            fmt::format("--mesh-split must be all, tune or test, got '{}'", o.mesh_split));
    }
    if (o.mesh_split != "all" && o.meshes.empty()) {
        throw InvalidArgument("--mesh-split needs --meshes (procedural objects have no split)");
    }
    if (!o.objects.empty()) ParseRange(o.objects);
    if (o.clutter && !(*o.clutter >= 0.0f && *o.clutter <= 1.0f)) {
        throw InvalidArgument(fmt::format("--clutter must be in [0, 1], got {}", *o.clutter));
    }
}

// The table scene parameters: the scene mode's, with --objects and --clutter when given.
sim::TableSceneParams TableParams(const SimulateOptions& o) {
    sim::TableSceneParams table = sim::TableSceneParamsFor(sim::ParseTableSceneMode(o.scene_mode));
    if (!o.objects.empty()) std::tie(table.min_objects, table.max_objects) = ParseRange(o.objects);
    if (o.clutter) table.clutter = *o.clutter;
    return table;
}

class Simulator {
  public:
    Simulator(const SimulateOptions& o, int threads) : o_(o) {
        kinect_.num_threads = laser_.num_threads = tof_.num_threads = threads;
        if (o.mode == "scenes" || o.mode == "objects") {
            // Table-top laser: a narrower field around the table.
            laser_.fov_deg = 100.0f;
            laser_.tilt_min_deg = 15.0f;
            laser_.tilt_max_deg = 65.0f;
            laser_.tilt_step_deg = 0.25f;
        }
    }

    void Run() {
        const std::filesystem::path dir = o_.out;
        std::error_code ec;
        std::filesystem::create_directories(dir, ec);
        if (!std::filesystem::is_directory(dir)) {
            throw IoError(fmt::format("{}: cannot create output folder", dir.string()));
        }
        sim::ObjectSource source = OpenSource();
        StartManifest();
        const int views = o_.views > 0 ? o_.views : (o_.mode == "objects" ? 16 : 1);
        const sim::TableSceneParams table = TableParams(o_);
        const std::size_t n_jobs = JobCount(source);
        Progress progress("simulate", n_jobs * static_cast<std::size_t>(views),
                          o_.quiet ? ProgressStyle::kSilent : ProgressStyle::kAuto);
        std::size_t written = 0, skipped = 0;
        for (std::size_t i = 0; i < n_jobs; ++i) {
            if (InterruptRequested()) break;
            const std::uint64_t seed = sim::SubSeed(o_.seed, i);
            sim::Scene scene;
            std::vector<Eigen::Isometry3f> poses;
            if (!MakeScene(source, table, i, seed, views, scene, poses)) {
                ++skipped;
                progress.Advance(static_cast<std::size_t>(views));
                continue;
            }
            WriteScene(dir, i, seed, scene, poses, progress);
            ++written;
        }
        progress.Finish();
        const bool interrupted = InterruptRequested();
        manifest_["complete"] = !interrupted;
        manifest_["skipped_meshes"] = skipped;
        SaveManifest(dir);
        if (interrupted) {
            throw Error(fmt::format("interrupted: {} of {} {} written, {} describes them", written,
                                    n_jobs, o_.mode, (dir / "manifest.json").string()));
        }
        if (!o_.quiet) {
            std::printf("multicue simulate: %zu %s, %zu frames (%s) -> %s\n", written,
                        o_.mode.c_str(), frames_, o_.sensor.c_str(),
                        (dir / "manifest.json").string().c_str());
        }
    }

  private:
    // The mesh library of --meshes (table-top or furniture categories), else procedural objects.
    sim::ObjectSource OpenSource() const {
        if (o_.meshes.empty()) return sim::ObjectSource();
        const auto& cats =
            o_.mode == "rooms" ? sim::FurnitureCategories() : sim::TabletopCategories();
        auto library = sim::SelectMeshSplit(sim::ReadMeshLibrary(o_.meshes, cats),
                                            sim::ParseMeshSplit(o_.mesh_split));
        if (library.empty()) {
            throw DataError(
                fmt::format("{}: no meshes in the '{}' half", o_.meshes, o_.mesh_split));
        }
        return sim::ObjectSource(std::move(library), o_.strict);
    }

    // The manifest's header; "complete" stays false until every scene is written.
    void StartManifest() {
        manifest_ = {{"format", "multicue.sim/1"},
                     {"mode", o_.mode},
                     {"seed", o_.seed},
                     {"sensor", SensorJson(o_.sensor, kinect_, laser_, tof_)},
                     {"meshes", o_.meshes},
                     {"mesh_split", o_.mesh_split},
                     {"categories", sim::CategoryNames()},
                     {"labels", "0 none, 1 table, 2 floor, 3 wall, 10*(k+1) object k"},
                     {"fields",
                      "label (mOSD), category (uint8, index into categories), "
                      "part (uint16, 1 + index into the object's parts; 0 none)"},
                     {"complete", false},
                     {"scenes", Json::array()}};
    }

    // Objects mode: one job per library mesh (at most --count) or --count procedural objects;
    // the other modes: --scenes.
    std::size_t JobCount(const sim::ObjectSource& source) const {
        if (o_.mode != "objects") return static_cast<std::size_t>(o_.scenes);
        std::size_t n = source.IsLibrary() ? source.library().size()
                                           : static_cast<std::size_t>(o_.count > 0 ? o_.count : 12);
        if (source.IsLibrary() && o_.count > 0) n = std::min(n, static_cast<std::size_t>(o_.count));
        return n;
    }

    // Scene `i` and its sensor poses; false when its library mesh cannot be used.
    bool MakeScene(sim::ObjectSource& source, const sim::TableSceneParams& table, std::size_t i,
                   std::uint64_t seed, int views, sim::Scene& scene,
                   std::vector<Eigen::Isometry3f>& poses) const {
        if (o_.mode == "objects") {
            const sim::TurntableParams turntable;
            sim::StreamRng rng(seed, 1);
            std::optional<sim::ObjectModel> model;
            if (source.IsLibrary()) {
                model = source.FromEntry(i, rng);
            } else {
                // Categories in turn, so every category gets objects.
                const auto& cats = sim::TabletopCategories();
                auto obj = sim::MakeProceduralObject(cats[i % cats.size()], rng);
                model = sim::ObjectModel{std::make_shared<const sim::PartMesh>(std::move(obj.mesh)),
                                         obj.category, obj.kind, 1.0f};
            }
            if (!model) return false;
            scene = sim::MakeTurntableScene(*model, turntable, seed);
            poses = sim::TurntableViews(scene, views, turntable);
        } else if (o_.mode == "scenes") {
            scene = sim::MakeTableScene(table, source, seed);
            poses =
                sim::TableViewpoints(scene, views, sim::TableViewpointParamsFor(table.mode), seed);
        } else {
            scene = sim::MakeRoomScene({}, source, seed);
            const auto head = sim::RoomLaserPose(scene, 1.5f, seed);
            for (int v = 0; v < views; ++v) {
                Eigen::Isometry3f T = head;
                T.rotate(Eigen::AngleAxisf(2.0f * static_cast<float>(M_PI) * v / views,
                                           Eigen::Vector3f::UnitZ()));
                poses.push_back(T);
            }
        }
        return true;
    }

    PointCloud Scan(const sim::RayCaster& caster, const Eigen::Isometry3f& pose,
                    std::uint64_t seed) const {
        if (o_.sensor == "laser") return sim::ScanLaser(caster, pose, laser_, seed);
        if (o_.sensor == "tof") return sim::ScanTof(caster, pose, tof_, seed);
        return sim::ScanKinect(caster, pose, kinect_, seed);
    }

    /// Sensor pose for a view: camera poses look at the table; the laser head stands at the
    /// camera's place, facing the same way, 1.5 m above the floor.
    Eigen::Isometry3f SensorPose(const sim::Scene& scene, const Eigen::Isometry3f& camera) const {
        if (o_.sensor != "laser" || o_.mode == "rooms") {
            if (o_.sensor != "laser" && o_.mode == "rooms") {
                const Eigen::Vector3f eye = camera.translation();
                const Eigen::Vector3f fwd = camera.linear().col(0);
                return sim::LookAt(eye, eye + fwd - Eigen::Vector3f(0, 0, 0.35f));
            }
            return camera;
        }
        const Eigen::Vector3f eye = camera.translation();
        const Eigen::Vector3f c = scene.support_center;
        const float azimuth = std::atan2(eye.y() - c.y(), eye.x() - c.x());
        const float dist = (eye - c).head<2>().norm();
        return sim::TableLaserPose(scene, azimuth, dist, 1.5f);
    }

    void WriteScene(const std::filesystem::path& dir, std::size_t i, std::uint64_t seed,
                    const sim::Scene& scene, const std::vector<Eigen::Isometry3f>& poses,
                    Progress& progress) {
        const sim::RayCaster caster(scene);
        const std::string prefix = o_.mode == "objects" ? "object"
                                   : o_.mode == "rooms" ? "room"
                                                        : "scene";
        Json frames = Json::array();
        for (std::size_t v = 0; v < poses.size(); ++v) {
            const auto pose = SensorPose(scene, poses[v]);
            const PointCloud cloud = Scan(caster, pose, sim::SubSeed(seed, 100 + v));
            const std::string name = fmt::format("{}_{:04}_view_{:02}.pcd", prefix, i, v);
            io::WritePointCloud(dir / name, cloud, io::Encoding::kCompressed);
            frames.push_back({{"file", name}, {"T_world_sensor", TransformJson(pose)}});
            ++frames_;
            progress.Advance();
        }
        const auto c = scene.support_center;
        Json entry = {{"id", i},
                      {"seed", seed},
                      {"support",
                       {{"center", {c.x(), c.y(), c.z()}},
                        {"size", {scene.support_size.x(), scene.support_size.y()}}}},
                      {"objects", ObjectsJson(scene)},
                      {"frames", frames}};
        if (o_.mode == "scenes") entry["scene_mode"] = o_.scene_mode;
        manifest_["scenes"].push_back(std::move(entry));
        // The manifest always describes every complete scene on disk.
        SaveManifest(dir);
    }

    void SaveManifest(const std::filesystem::path& dir) const {
        const std::string text = manifest_.dump(1);
        io::WriteFileAtomically(dir / "manifest.json",
                                [&](std::ostream& os) { os << text << '\n'; });
    }

    SimulateOptions o_;
    sim::KinectParams kinect_;
    sim::LaserParams laser_;
    sim::TofParams tof_;
    Json manifest_;
    std::size_t frames_ = 0;
};

}  // namespace

void AddSimulateCommand(CLI::App& app, const GlobalOptions& global) {
    auto* cmd = app.add_subcommand("simulate",
                                   "Simulated scans with ground truth: table-top scenes, turntable "
                                   "objects or furniture rooms");
    auto o = std::make_shared<SimulateOptions>();
    // MODE and --out are checked in the callback: `simulate kitchens` (a subcommand) has neither.
    cmd->add_option("MODE", o->mode,
                    "scenes (table-top), objects (turntable) or rooms (furniture)");
    cmd->add_option("--out", o->out, "output folder: PCD files and manifest.json");
    cmd->add_option("--seed", o->seed, "random seed; equal seeds give identical files")
        ->capture_default_str();
    cmd->add_option("--sensor", o->sensor, "kinect, laser or tof")->capture_default_str();
    cmd->add_option("--scenes", o->scenes, "number of scenes (scenes and rooms modes)")
        ->capture_default_str();
    cmd->add_option("--views", o->views, "views per scene (default 1) or per object (default 16)");
    cmd->add_option("--mode", o->scene_mode,
                    "scenes: default, boxes, stacked, occluded, cylindric, mixed or complex")
        ->capture_default_str();
    cmd->add_option("--objects", o->objects,
                    "objects per scene MIN,MAX (default: the mode's range, 3,8 for default)");
    cmd->add_option("--clutter", o->clutter,
                    "chance that an object touches another [0,1] (default: the mode's, 0.3 for "
                    "default)");
    cmd->add_option("--mesh-split", o->mesh_split,
                    "with --meshes: all, or the tune or test half of every category")
        ->capture_default_str();
    cmd->add_option("--meshes", o->meshes,
                    "mesh folder with labels.csv (default: procedural objects)");
    cmd->add_option("--count", o->count,
                    "objects mode: number of objects (procedural default 12; library: all)");
    cmd->add_flag("--strict", o->strict, "stop at the first bad mesh instead of skipping it");
    cmd->add_flag("-q,--quiet", o->quiet, "no progress and no summary");
    cmd->callback([o, cmd, &global] {
        if (!cmd->get_subcommands().empty()) return;  // a subcommand did the work
        if (o->mode.empty()) throw InvalidArgument("simulate: MODE is required");
        if (o->out.empty()) throw InvalidArgument("simulate: --out is required");
        CheckOptions(*o);
        InstallInterruptHandler();
        Simulator(*o, global.threads).Run();
    });
}

}  // namespace multicue::cli

// `multicue simulate kitchens`: simulated kitchens (PartNet-Mobility models in rows against the
// walls) scanned by the tilting laser and the Kinect, with per-point ground truth, a manifest of
// every model's pose and joints, and each kitchen's ground-truth URDF (docs/kitchens.md).

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "commands.hpp"
#include "default_paths.hpp"
#include "multicue/core/exceptions.hpp"
#include "multicue/core/progress.hpp"
#include "multicue/io/file_utils.hpp"
#include "multicue/io/point_cloud_io.hpp"
#include "multicue/io/urdf.hpp"
#include "multicue/sim/kitchen_procedural.hpp"
#include "multicue/sim/kitchen_scene.hpp"
#include "multicue/sim/rng.hpp"
#include "multicue/sim/sensors.hpp"
#include "registration_json.hpp"

namespace multicue::cli {
namespace {

using Json = nlohmann::json;

struct KitchenOptions {
    std::string out;
    std::string models = DefaultKitchenDir();
    std::uint64_t seed = 1;
    int kitchens = 10;
    int views = 3;        // Kinect views per kitchen
    int laser_views = 1;  // laser sweeps per kitchen
    std::string sensor = "both";
    std::string mesh_split = "all";
    bool open_doors = false;
    int open_per_kitchen = 4;
    int procedural = 0;       // procedural units per kind added to the library
    bool appliances = false;  // procedural dishwashers, ovens and fridges too
    bool quiet = false;
};

// A pose as rows of a 4x4 matrix (the float values, exactly, as doubles).

Json Vec(const Eigen::Vector3f& v) { return Json::array({v.x(), v.y(), v.z()}); }

Json KitchenJson(const sim::KitchenScene& k) {
    Json models = Json::array();
    for (std::size_t i = 0; i < k.instances.size(); ++i) {
        const auto& inst = k.instances[i];
        models.push_back({{"name", inst.name},
                          {"model", inst.model->id},
                          {"kind", inst.model->kind},
                          {"container_type", sim::ContainerTypeOfModel(*inst.model)},
                          {"run", inst.run},
                          {"scale", inst.model->scale},
                          {"extent", Vec(inst.model->bounds.sizes())},
                          {"T_world_model", TransformJson(inst.T_world_model)}});
    }
    Json joints = Json::array();
    for (const auto& j : k.joints) {
        const auto& inst = k.instances[static_cast<std::size_t>(j.instance)];
        const auto& aj = inst.model->joints[static_cast<std::size_t>(j.joint)];
        joints.push_back(
            {{"name", j.name},
             {"model", inst.name},
             {"type", io::UrdfJointTypeName(j.type)},
             {"front", j.front},
             {"child",
              inst.name + "__" + inst.model->links[static_cast<std::size_t>(aj.child)].name},
             {"semantic", inst.model->links[static_cast<std::size_t>(aj.child)].semantic},
             {"value", inst.q[static_cast<std::size_t>(j.joint)]},
             {"lower", j.lower},
             {"upper", j.upper},
             {"axis_point", Vec(j.axis_point)},
             {"axis_direction", Vec(j.axis_direction)}});
    }
    Json runs = Json::array();
    for (const auto& r : k.runs) {
        runs.push_back({{"origin", Vec(r.origin)},
                        {"tangent", Vec(r.tangent)},
                        {"normal", Vec(r.normal)},
                        {"begin", r.begin},
                        {"end", r.end}});
    }
    return {{"room", Vec(k.size)}, {"runs", runs}, {"models", models}, {"joints", joints}};
}

class KitchenSimulator {
  public:
    KitchenSimulator(const KitchenOptions& o, int threads) : o_(o) {
        kinect_.num_threads = laser_.num_threads = threads;
        kinect_.shading = 0.3f;
        laser_.tilt_min_deg = -40.0f;  // up to the ceiling
        laser_.tilt_max_deg = 60.0f;
    }

    void Run() {
        const std::filesystem::path dir = o_.out;
        // "none": kitchens of procedural units only (no library needed).
        auto library = o_.models == "none"
                           ? std::vector<sim::KitchenModelEntry>{}
                           : sim::SelectKitchenSplit(sim::ReadKitchenLibrary(o_.models),
                                                     sim::ParseMeshSplit(o_.mesh_split));
        for (auto& e : sim::ProceduralKitchenEntries(o_.procedural, sim::SubSeed(o_.seed, 97),
                                                     o_.appliances)) {
            library.push_back(std::move(e));
        }
        if (library.empty()) {
            throw DataError(
                fmt::format("{}: no kitchen models in the '{}' half", o_.models, o_.mesh_split));
        }
        std::error_code ec;
        std::filesystem::create_directories(dir, ec);
        if (!std::filesystem::is_directory(dir)) {
            throw IoError(fmt::format("{}: cannot create output folder", dir.string()));
        }
        manifest_ = {{"format", "multicue.sim-kitchens/1"},
                     {"seed", o_.seed},
                     {"models", o_.models},
                     {"mesh_split", o_.mesh_split},
                     {"procedural_per_kind", o_.procedural},
                     {"procedural_appliances", o_.appliances},
                     {"classes", sim::KitchenClassNames()},
                     {"container_types", sim::ContainerTypes()},
                     {"frame", "world (z up, metres); the sensor pose is the PCD VIEWPOINT"},
                     {"fields",
                      "rgb (kinect), intensity (laser), label (1 + scene object), semantic "
                      "(uint8, index into classes), model (uint16, 1 + index into models), link "
                      "(uint16, 1 + link of the model's URDF), joint (uint16, 1 + index into "
                      "joints)"},
                     {"complete", false},
                     {"kitchens", Json::array()}};
        const int per_kitchen = (UseKinect() ? o_.views : 0) + (UseLaser() ? o_.laser_views : 0);
        const int opened = o_.open_doors ? o_.open_per_kitchen * (UseKinect() + UseLaser()) : 0;
        Progress progress(
            "simulate kitchens",
            static_cast<std::size_t>(o_.kitchens) * static_cast<std::size_t>(per_kitchen + opened),
            o_.quiet ? ProgressStyle::kSilent : ProgressStyle::kAuto);
        sim::KitchenModelCache cache;
        int written = 0;
        for (int i = 0; i < o_.kitchens && !InterruptRequested(); ++i) {
            const std::uint64_t seed = sim::SubSeed(o_.seed, static_cast<std::uint64_t>(i));
            sim::KitchenScene kitchen = sim::MakeKitchenScene(library, cache, {}, seed);
            WriteKitchen(dir, i, seed, kitchen, progress);
            ++written;
        }
        progress.Finish();
        const bool interrupted = InterruptRequested();
        manifest_["complete"] = !interrupted;
        SaveManifest(dir);
        if (interrupted) {
            throw Error(fmt::format("interrupted: {} of {} kitchens written, {} describes them",
                                    written, o_.kitchens, (dir / "manifest.json").string()));
        }
        if (!o_.quiet) {
            std::printf("multicue simulate kitchens: %d kitchens, %zu frames -> %s\n", written,
                        frames_, (dir / "manifest.json").string().c_str());
        }
    }

  private:
    bool UseKinect() const { return o_.sensor != "laser"; }
    bool UseLaser() const { return o_.sensor != "kinect"; }

    Json Scan(const std::filesystem::path& dir, const std::string& name,
              const sim::KitchenScene& kitchen, const sim::RayCaster& caster, bool laser,
              const Eigen::Isometry3f& pose, std::uint64_t seed) {
        PointCloud cloud = laser ? sim::ScanLaser(caster, pose, laser_, seed)
                                 : sim::ScanKinect(caster, pose, kinect_, seed);
        sim::AddKitchenTruth(kitchen, cloud);
        sim::ScanToWorld(cloud, pose);
        io::WritePointCloud(dir / name, cloud, io::Encoding::kCompressed);
        ++frames_;
        return {{"file", name},
                {"sensor", laser ? "laser" : "kinect"},
                {"T_world_sensor", TransformJson(pose)}};
    }

    void WriteKitchen(const std::filesystem::path& dir, int i, std::uint64_t seed,
                      sim::KitchenScene& kitchen, Progress& progress) {
        const std::string stem = fmt::format("kitchen_{:04}", i);
        const std::string urdf_name = stem + ".urdf";
        io::WriteUrdf(dir / urdf_name, sim::KitchenGroundTruthUrdf(kitchen));
        Json entry = KitchenJson(kitchen);
        entry["id"] = i;
        entry["seed"] = seed;
        entry["urdf"] = urdf_name;
        Json frames = Json::array();
        std::vector<std::pair<bool, Eigen::Isometry3f>> poses;
        if (UseLaser()) {
            for (const auto& p : sim::KitchenLaserPoses(kitchen, o_.laser_views, seed)) {
                poses.emplace_back(true, p);
            }
        }
        if (UseKinect()) {
            for (const auto& p : sim::KitchenCameraPoses(kitchen, o_.views, seed)) {
                poses.emplace_back(false, p);
            }
        }
        {
            const sim::RayCaster caster(kitchen.scene);
            int n_laser = 0, n_kinect = 0;
            for (std::size_t v = 0; v < poses.size() && !InterruptRequested(); ++v) {
                const bool laser = poses[v].first;
                const std::string name =
                    fmt::format("{}_{}_{:02}.pcd", stem, laser ? "laser" : "kinect",
                                laser ? n_laser++ : n_kinect++);
                frames.push_back(Scan(dir, name, kitchen, caster, laser, poses[v].second,
                                      sim::SubSeed(seed, 100 + v)));
                progress.Advance();
            }
        }
        entry["frames"] = frames;
        if (o_.open_doors) entry["opened"] = OpenedPairs(dir, stem, seed, kitchen, poses, progress);
        manifest_["kitchens"].push_back(std::move(entry));
        SaveManifest(dir);
    }

    // The robot opens fronts one at a time: each opened scan is taken from the pose of a closed
    // scan of the same sensor that sees the front, so the two differ only by that front.
    Json OpenedPairs(const std::filesystem::path& dir, const std::string& stem, std::uint64_t seed,
                     sim::KitchenScene& kitchen,
                     const std::vector<std::pair<bool, Eigen::Isometry3f>>& poses,
                     Progress& progress) {
        Json pairs = Json::array();
        std::vector<std::size_t> fronts;
        for (std::size_t j = 0; j < kitchen.joints.size(); ++j) {
            if (kitchen.joints[j].front) fronts.push_back(j);
        }
        sim::StreamRng rng(seed, 17);
        std::shuffle(fronts.begin(), fronts.end(), rng);
        int made = 0;
        for (const std::size_t j : fronts) {
            if (made >= o_.open_per_kitchen || InterruptRequested()) break;
            const auto& joint = kitchen.joints[j];
            // A front whose moving part faces one of the camera views: pick the closest view.
            const Eigen::Vector3f where = joint.axis_point;
            int best_kinect = -1, best_laser = -1;
            float dk = 1e9f, dl = 1e9f;
            for (std::size_t v = 0; v < poses.size(); ++v) {
                const Eigen::Isometry3f& T = poses[v].second;
                const float d = (T.translation() - where).norm();
                if (poses[v].first ? d < dl : d < dk) {
                    (poses[v].first ? dl : dk) = d;
                    (poses[v].first ? best_laser : best_kinect) = static_cast<int>(v);
                }
            }
            if (UseKinect()) {
                const Eigen::Isometry3f& T = poses[static_cast<std::size_t>(best_kinect)].second;
                const Eigen::Vector3f dir_cam = T.linear().col(2);
                if (dir_cam.dot((where - T.translation()).normalized()) < 0.7f) continue;
            }
            const float closed = kitchen.instances[static_cast<std::size_t>(joint.instance)]
                                     .q[static_cast<std::size_t>(joint.joint)];
            const bool revolute = joint.type != io::UrdfJointType::kPrismatic;
            const auto& aj = kitchen.instances[static_cast<std::size_t>(joint.instance)]
                                 .model->joints[static_cast<std::size_t>(joint.joint)];
            // Doors 35-80 degrees (within their limit), drawers 40-90 % of their travel.
            float value = revolute ? static_cast<float>(rng.Uniform(0.6, 1.4)) : 0.0f;
            if (revolute) {
                const float far = aj.Opened(1.0f);
                value =
                    closed + std::copysign(std::min(value, std::abs(far - closed)), far - closed);
            } else {
                value = aj.Opened(static_cast<float>(rng.Uniform(0.4, 0.9)));
            }
            kitchen.SetJoint(j, value);
            {
                const sim::RayCaster caster(kitchen.scene);
                for (const int v : {best_laser, best_kinect}) {
                    if (v < 0) continue;
                    const bool laser = poses[static_cast<std::size_t>(v)].first;
                    const std::string name =
                        fmt::format("{}_{}_open_{:02}.pcd", stem, laser ? "laser" : "kinect", made);
                    Json frame = Scan(dir, name, kitchen, caster, laser,
                                      poses[static_cast<std::size_t>(v)].second,
                                      sim::SubSeed(seed, 500 + 10 * made + (laser ? 1 : 0)));
                    frame["closed_view"] = v;
                    frame["joint"] = joint.name;
                    frame["value"] = value;
                    frame["closed_value"] = closed;
                    pairs.push_back(std::move(frame));
                    progress.Advance();
                }
            }
            kitchen.SetJoint(j, closed);
            ++made;
        }
        return pairs;
    }

    void SaveManifest(const std::filesystem::path& dir) const {
        const std::string text = manifest_.dump(1);
        io::WriteFileAtomically(dir / "manifest.json",
                                [&](std::ostream& os) { os << text << '\n'; });
    }

    KitchenOptions o_;
    sim::KinectParams kinect_;
    sim::LaserParams laser_;
    Json manifest_;
    std::size_t frames_ = 0;
};

void CheckOptions(const KitchenOptions& o) {
    if (o.kitchens < 0) {
        throw InvalidArgument(fmt::format("--kitchens must be >= 0, got {}", o.kitchens));
    }
    if (o.views < 0) throw InvalidArgument(fmt::format("--views must be >= 0, got {}", o.views));
    if (o.laser_views < 0) {
        throw InvalidArgument(fmt::format("--laser-views must be >= 0, got {}", o.laser_views));
    }
    if (o.procedural < 0 || o.procedural > sim::kMaxProceduralPerKind) {
        throw InvalidArgument(fmt::format("--procedural must lie in [0, {}], got {}",
                                          sim::kMaxProceduralPerKind, o.procedural));
    }
    if (o.appliances && o.procedural == 0) {
        throw InvalidArgument("--procedural-appliances needs --procedural N (N > 0)");
    }
    if (o.models == "none" && o.procedural == 0) {
        throw InvalidArgument("--models none needs --procedural N (N > 0)");
    }
    if (o.open_per_kitchen < 0) {
        throw InvalidArgument(fmt::format("--open-count must be >= 0, got {}", o.open_per_kitchen));
    }
    if (o.sensor != "kinect" && o.sensor != "laser" && o.sensor != "both") {
        throw InvalidArgument(
            fmt::format("--sensor must be kinect, laser or both, got '{}'", o.sensor));
    }
    try {
        sim::ParseMeshSplit(o.mesh_split);
    } catch (const InvalidArgument&) {
        throw InvalidArgument(
            fmt::format("--mesh-split must be all, tune or test, got '{}'", o.mesh_split));
    }
}

}  // namespace

void AddSimulateKitchensCommand(CLI::App& simulate, const GlobalOptions& global) {
    auto* cmd = simulate.add_subcommand(
        "kitchens",
        "Simulated kitchens (articulated PartNet-Mobility models) scanned by the tilting laser "
        "and the Kinect, with ground truth per point, a manifest and a URDF per kitchen");
    auto o = std::make_shared<KitchenOptions>();
    cmd->add_option("--out", o->out, "output folder: PCD files, URDF files and manifest.json")
        ->required();
    cmd->add_option("--models", o->models,
                    "kitchen model library (folder with labels.csv); none: procedural units "
                    "only (--procedural)")
        ->capture_default_str();
    cmd->add_option("--seed", o->seed, "random seed; equal seeds give identical files")
        ->capture_default_str();
    cmd->add_option("--kitchens", o->kitchens, "number of kitchens")->capture_default_str();
    cmd->add_option("--views", o->views, "Kinect views per kitchen")->capture_default_str();
    cmd->add_option("--laser-views", o->laser_views, "laser sweeps per kitchen")
        ->capture_default_str();
    cmd->add_option("--sensor", o->sensor, "kinect, laser or both")->capture_default_str();
    cmd->add_option("--mesh-split", o->mesh_split,
                    "all, or the tune or test half of the kitchen models of every kind")
        ->capture_default_str();
    cmd->add_flag("--open-doors", o->open_doors,
                  "also scan each kitchen with fronts opened one at a time (opened-front pairs)");
    cmd->add_option("--open-count", o->open_per_kitchen,
                    "with --open-doors: fronts opened per kitchen")
        ->capture_default_str();
    cmd->add_option("--procedural", o->procedural,
                    "also build kitchens from N procedural units of every cupboard kind "
                    "(cupboards, sink, wall and tall cupboards, drawer units) of random designs")
        ->capture_default_str();
    cmd->add_flag("--procedural-appliances", o->appliances,
                  "with --procedural: N procedural dishwashers, ovens and fridges too");
    cmd->add_flag("-q,--quiet", o->quiet, "no progress and no summary");
    cmd->callback([o, &global] {
        CheckOptions(*o);
        InstallInterruptHandler();
        KitchenSimulator(*o, global.threads).Run();
    });
}

}  // namespace multicue::cli

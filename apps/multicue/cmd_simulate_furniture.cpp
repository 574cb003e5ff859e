// `multicue simulate furniture --out DIR`: furnished rooms (offices, seminar rooms, kitchens)
// scanned by the tilting laser from several head positions, for `multicue map furniture`
// (docs/furniture.md). Every scan is written in the room's frame (z up, floor at z = 0) with its
// sensor pose and per-point labels (2 floor, 3 wall, 10 (k + 1) object k); manifest.json lists
// the scans and the true class, piece and pose of every piece of furniture.

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
#include "multicue/sim/mesh_split.hpp"
#include "multicue/training/furniture_training.hpp"

namespace multicue::cli {
namespace {

struct SimulateFurnitureOptions {
    std::string out;
    std::string furniture = DefaultFurnitureDir();
    std::string kitchen = DefaultKitchenDir();
    std::string split = "test";
    std::vector<std::string> types = {"office", "seminar", "kitchen"};
    int rooms = 3;
    int heads = 3;
    std::uint64_t seed = 2000;
    bool quiet = false;
};

void Run(const SimulateFurnitureOptions& o) {
    if (o.rooms < 1) throw InvalidArgument(fmt::format("--rooms must be >= 1, got {}", o.rooms));
    if (o.heads < 1) throw InvalidArgument(fmt::format("--heads must be >= 1, got {}", o.heads));
    if (o.split != "test" && o.split != "tune" && o.split != "procedural") {
        throw InvalidArgument(
            fmt::format("--split must be test, tune or procedural, got '{}'", o.split));
    }
    std::vector<sim::RoomType> types;
    for (const auto& t : o.types) types.push_back(sim::ParseRoomType(t));
    std::vector<sim::FurniturePiece> library;
    if (o.split != "procedural") {
        const auto entries = sim::SelectFurnitureSplit(
            sim::ReadFurnitureLibrary(o.furniture, o.kitchen),
            o.split == "test" ? sim::MeshSplit::kTest : sim::MeshSplit::kTune);
        for (const auto& e : entries) library.push_back(sim::LoadFurniturePiece(e));
    }
    const sim::FurnitureSource source(library, o.split == "procedural" ? 1.0f : 0.0f);
    training::FurnitureTrainingOptions sensor;
    const std::filesystem::path dir = o.out;
    std::filesystem::create_directories(dir);
    nlohmann::json manifest;
    manifest["rooms"] = nlohmann::json::array();
    InstallInterruptHandler();
    Progress progress("rooms", static_cast<std::size_t>(o.rooms),
                      o.quiet ? ProgressStyle::kSilent : ProgressStyle::kAuto);
    for (int r = 0; r < o.rooms; ++r) {
        if (InterruptRequested()) throw Error("simulate furniture: interrupted");
        sim::FurnitureRoomParams rp;
        rp.type = types[static_cast<std::size_t>(r) % types.size()];
        const std::uint64_t seed = o.seed + static_cast<std::uint64_t>(r);
        const auto room = training::SimulateFurnitureRoom(rp, source, o.heads, sensor, seed);
        nlohmann::json jr;
        jr["type"] = sim::RoomTypeName(rp.type);
        jr["seed"] = seed;
        jr["size"] = {room.room.size.x(), room.room.size.y()};
        jr["scans"] = nlohmann::json::array();
        for (std::size_t v = 0; v < room.scans.size(); ++v) {
            PointCloud world = room.scans[v];
            const Eigen::Isometry3f& T = room.T_world_sensor[v];
            for (auto& p : world.points) p = T * p;
            for (auto& n : world.normals) n = T.linear() * n;
            // The sensor's own pose in the room (the laser sits off the head's origin).
            world.sensor_origin = T * room.scans[v].sensor_origin;
            world.sensor_orientation =
                Eigen::Quaternionf(T.linear()) * room.scans[v].sensor_orientation;
            const std::string name = fmt::format("room_{:02}_scan_{:02}.pcd", r, v);
            io::WritePointCloud(dir / name, world, io::Encoding::kBinary);
            jr["scans"].push_back(name);
        }
        jr["furniture"] = nlohmann::json::array();
        for (const auto& f : room.room.furniture) {
            const Eigen::Vector3f t = f.T_world_object.translation();
            jr["furniture"].push_back({{"class", f.category},
                                       {"piece", f.id},
                                       {"label", f.label},
                                       {"position", {t.x(), t.y(), t.z()}},
                                       {"yaw_deg", f.yaw * 180.0f / static_cast<float>(M_PI)},
                                       {"size", {f.extent.x(), f.extent.y(), f.extent.z()}}});
        }
        manifest["rooms"].push_back(jr);
        progress.Advance();
    }
    progress.Finish();
    const std::string text = manifest.dump(2) + "\n";
    io::WriteFileAtomically(dir / "manifest.json", [&](std::ostream& s) { s << text; });
    if (!o.quiet) {
        std::printf("multicue simulate furniture: %d rooms, %d scans each -> %s\n", o.rooms,
                    o.heads, (dir / "manifest.json").string().c_str());
    }
}

}  // namespace

void AddSimulateFurnitureCommand(CLI::App& simulate, const GlobalOptions& /*global*/) {
    auto* cmd = simulate.add_subcommand(
        "furniture",
        "Furnished rooms (offices, seminar rooms, kitchens) scanned by the tilting laser from "
        "several head positions, with the true pose of every piece (for map furniture)");
    auto o = std::make_shared<SimulateFurnitureOptions>();
    cmd->add_option("--out", o->out, "output folder: PCD scans and manifest.json")->required();
    cmd->add_option("--rooms", o->rooms, "number of rooms")->capture_default_str();
    cmd->add_option("--heads", o->heads, "head positions (scans) per room")->capture_default_str();
    cmd->add_option("--seed", o->seed, "first room's seed; equal seeds give identical files")
        ->capture_default_str();
    cmd->add_option("--types", o->types, "room types in turn: office, seminar, kitchen")
        ->capture_default_str();
    cmd->add_option("--split", o->split,
                    "furniture of the test half (held out of training), the tune half, or "
                    "procedural pieces only")
        ->capture_default_str();
    cmd->add_option("--furniture", o->furniture, "furniture library (labels.csv)")
        ->capture_default_str();
    cmd->add_option("--kitchen", o->kitchen, "kitchen library (tables, cupboards)")
        ->capture_default_str();
    cmd->add_flag("-q,--quiet", o->quiet, "no progress and no summary");
    cmd->callback([o] { Run(*o); });
}

}  // namespace multicue::cli

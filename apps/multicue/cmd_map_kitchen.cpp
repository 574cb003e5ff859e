// `multicue map kitchen SCANS... --out DIR`: the semantic map of a kitchen (thesis section 4.1):
// walls, floor, ceiling, worktops, furniture faces, handles and knobs, door and drawer fronts with
// their joints, furniture typed as containers; written as JSON, URDF and OWL with per-point labels
// and a report page (docs/kitchens.md). Scans must share one frame (as `multicue simulate
// kitchens` writes them, each with its sensor pose).

#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "cli_util.hpp"
#include "commands.hpp"
#include "multicue/core/exceptions.hpp"
#include "multicue/io/file_utils.hpp"
#include "multicue/io/point_cloud_io.hpp"
#include "multicue/mapping/kitchen_map.hpp"
#include "multicue/mapping/map_export.hpp"
#include "multicue/ml/classifier.hpp"
#include "multicue/system/kitchen_report.hpp"

namespace multicue::cli {
namespace {

struct MapKitchenOptions {
    std::vector<std::string> scans;
    std::vector<std::string> opened;
    std::string out;
    std::string sensor = "auto";
    std::string containers;
    std::string fixtures;
    std::string joints;
    std::string name = "kitchen_map";
    bool report = true;
    bool quiet = false;
};

/// The labels of one scan: its points with the map's class, front and piece per point.
PointCloud ScanLabels(const PointCloud& scan, const mapping::KitchenMap& map, std::size_t offset) {
    PointCloud out;
    out.points = scan.points;
    out.width = scan.width;
    out.height = scan.height;
    out.sensor_origin = scan.sensor_origin;
    out.sensor_orientation = scan.sensor_orientation;
    ExtraField semantic{"semantic", 'U', 1, 1, {}};
    ExtraField front{"front", 'U', 4, 1, {}};
    ExtraField piece{"furniture", 'U', 4, 1, {}};
    for (std::size_t i = 0; i < scan.size(); ++i) {
        semantic.data.push_back(static_cast<std::uint8_t>(map.point_class[offset + i]));
        const std::uint32_t f = map.point_front[offset + i];
        const std::uint32_t k =
            f > 0 ? static_cast<std::uint32_t>(map.fronts[f - 1].furniture + 1) : 0u;
        const auto* bf = reinterpret_cast<const std::uint8_t*>(&f);
        const auto* bk = reinterpret_cast<const std::uint8_t*>(&k);
        front.data.insert(front.data.end(), bf, bf + 4);
        piece.data.insert(piece.data.end(), bk, bk + 4);
    }
    out.extra_fields = {std::move(semantic), std::move(front), std::move(piece)};
    return out;
}

const char* SensorName(mapping::KitchenSensor s) {
    return s == mapping::KitchenSensor::kLaser ? "laser" : "kinect";
}

/// The sensor every scan (and opened scan) looks like. One map takes one sensor's parameters, and
/// the other sensor's scans would be mapped with the wrong ones: scans that look like different
/// sensors are refused unless --sensor names the parameters.
mapping::KitchenSensor OneSensor(const MapKitchenOptions& o, const std::vector<PointCloud>& scans,
                                 const std::vector<PointCloud>& opened) {
    const mapping::KitchenSensor first = mapping::GuessKitchenSensor({scans.front()});
    auto check = [&](const PointCloud& scan, const std::string& path) {
        const mapping::KitchenSensor s = mapping::GuessKitchenSensor({scan});
        if (s != first) {
            throw InvalidArgument(fmt::format(
                "map kitchen: {} looks like a {} scan and {} like a {} scan; one map takes one "
                "sensor's parameters: map them apart, or choose the parameters with --sensor",
                o.scans.front(), SensorName(first), path, SensorName(s)));
        }
    };
    for (std::size_t k = 1; k < scans.size(); ++k) check(scans[k], o.scans[k]);
    for (std::size_t k = 0; k < opened.size(); ++k) check(opened[k], o.opened[k]);
    return first;
}

void Run(const MapKitchenOptions& o, const GlobalOptions& global) {
    if (o.sensor != "auto" && o.sensor != "kinect" && o.sensor != "laser") {
        throw InvalidArgument(
            fmt::format("--sensor must be auto, kinect or laser, got '{}'", o.sensor));
    }
    for (const auto& s : o.scans) CheckDistinctPaths(s, o.out);
    // Read and check everything before anything is written.
    std::vector<PointCloud> scans;
    for (const auto& s : o.scans) scans.push_back(ReadNonEmptyCloud(s));
    std::vector<PointCloud> opened;
    for (const auto& s : o.opened) opened.push_back(ReadNonEmptyCloud(s));
    std::unique_ptr<ml::Classifier> classifier;
    if (!o.containers.empty()) {
        classifier = ml::LoadClassifier(o.containers);
        mapping::CheckContainerClassifier(*classifier);
    }
    std::unique_ptr<ml::Classifier> fixture_classifier;
    if (!o.fixtures.empty()) {
        fixture_classifier = ml::LoadClassifier(o.fixtures);
        mapping::CheckFixtureClassifier(*fixture_classifier);
    }
    std::unique_ptr<ml::Classifier> joint_classifier;
    if (!o.joints.empty()) {
        joint_classifier = ml::LoadClassifier(o.joints);
        mapping::CheckJointClassifier(*joint_classifier);
    }
    const mapping::KitchenSensor sensor = o.sensor == "kinect"  ? mapping::KitchenSensor::kKinect
                                          : o.sensor == "laser" ? mapping::KitchenSensor::kLaser
                                                                : OneSensor(o, scans, opened);
    mapping::MapKitchenParams params = mapping::KitchenParamsFor(sensor);
    params.num_threads = global.threads;
    mapping::MapKitchenResult r = mapping::MapKitchen(
        scans, params, classifier.get(), fixture_classifier.get(), joint_classifier.get());
    const mapping::MotionParams motion = mapping::MotionParamsFor(sensor);
    std::vector<int> moved;
    std::vector<std::size_t> split_off;  // fronts cut from the opened front's rectangle
    for (const auto& s : opened) {
        const std::size_t before = r.map.fronts.size();
        moved.push_back(mapping::UpdateArticulationFromOpenedScan(r.map, r.cloud, s, motion));
        split_off.push_back(r.map.fronts.size() - before);
    }
    if (!opened.empty()) {
        // Joint types from motion can change how fronts group and what the pieces are.
        mapping::GroupFurniture(r.map, params.containers);
        mapping::TypeContainers(r.map, classifier.get(), params.containers);
    }
    // Build every output in memory, then write each file atomically.
    const auto page =
        o.report ? std::optional<ReportPage>(KitchenReportPage(
                       r.cloud, r.map, std::filesystem::path(o.scans[0]).filename().string()))
                 : std::nullopt;
    std::vector<PointCloud> labels;
    for (std::size_t s = 0; s < scans.size(); ++s) {
        labels.push_back(ScanLabels(scans[s], r.map, r.scan_offsets[s]));
    }
    const std::filesystem::path dir = o.out;
    mapping::WriteKitchenMap(dir, r.map, o.name);
    for (std::size_t s = 0; s < labels.size(); ++s) {
        const std::string name =
            labels.size() == 1 ? "labels.pcd" : fmt::format("labels_{:02}.pcd", s);
        io::WritePointCloud(dir / name, labels[s], io::Encoding::kCompressed);
    }
    if (page) page->Write(dir / "report.html");
    if (!o.quiet) {
        std::size_t handles = 0;
        for (const auto& f : r.map.fixtures) handles += f.type == mapping::FixtureType::kHandle;
        std::printf(
            "multicue map kitchen: %zu scans (%s), %zu handles, %zu knobs, %zu fronts, %zu "
            "pieces in %.0f ms -> %s\n",
            scans.size(), SensorName(sensor), handles, r.map.fixtures.size() - handles,
            r.map.fronts.size(), r.map.furniture.size(), r.time_ms,
            (dir / "map.json").string().c_str());
        for (std::size_t k = 0; k < moved.size(); ++k) {
            if (moved[k] < 0) {
                std::printf("  %s: no front moved\n", o.opened[k].c_str());
            } else {
                const auto& a = r.map.fronts[static_cast<std::size_t>(moved[k])].articulation;
                std::printf("  %s: front %d opened, %s joint%s\n", o.opened[k].c_str(),
                            moved[k] + 1, mapping::JointTypeName(a.type),
                            split_off[k] > 0
                                ? fmt::format(" (cut from a front spanning several; the rest "
                                              "made {} more)",
                                              split_off[k])
                                      .c_str()
                                : "");
            }
        }
        if (o.report && !ReportViewerAvailable()) {
            std::printf("  report.html has no 3D view: this build lacks the viewer\n");
        }
    }
}

}  // namespace

void AddMapKitchenCommand(CLI::App& map_command, const GlobalOptions& global) {
    auto* cmd = map_command.add_subcommand(
        "kitchen",
        "Semantic map of a kitchen: walls, worktops, handles and knobs, door and drawer fronts "
        "with their joints, furniture typed as containers (JSON, URDF, OWL, report)");
    auto o = std::make_shared<MapKitchenOptions>();
    cmd->add_option("SCANS", o->scans, "PCD or PLY scans in one frame (world, z up)")
        ->required()
        ->check(CLI::ExistingFile);
    cmd->add_option("--out", o->out,
                    "output folder: map.json, map.urdf, map.owl, labels.pcd, report.html")
        ->required();
    cmd->add_option("--opened", o->opened,
                    "scans of the same views with one front opened (repeatable): joints from the "
                    "motion")
        ->check(CLI::ExistingFile);
    cmd->add_option("--sensor", o->sensor,
                    "auto, kinect or laser (parameters); auto refuses scans of both sensors")
        ->capture_default_str();
    cmd->add_option("--containers", o->containers,
                    "container classifier (multicue model file); default: rules");
    cmd->add_option("--fixtures", o->fixtures,
                    "fixture classifier of the sensor (`multicue train fixtures`); default: rules");
    cmd->add_option("--joints", o->joints,
                    "one-scan joint classifier (`multicue train joints`); default: rules");
    cmd->add_option("--name", o->name, "name of the map in the URDF and OWL files")
        ->capture_default_str();
    cmd->add_flag(
        "--no-report", [o](std::int64_t) { o->report = false; }, "skip report.html");
    cmd->add_flag("-q,--quiet", o->quiet, "no summary");
    cmd->callback([o, &global] { Run(*o, global); });
}

}  // namespace multicue::cli

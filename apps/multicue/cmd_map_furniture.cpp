// `multicue map furniture SCANS... --model MODEL --out DIR`: tables, chairs, cabinets and
// sideboards in scans of a room, found by part configurations (Hough votes of a part vocabulary)
// and verified by fitting CAD models against the scans' free space (thesis section 4.2,
// docs/furniture.md). Scans share one z-up world frame with the floor at z = 0 and carry their
// sensor pose (as `multicue simulate furniture` writes them). Writes detections.json (class, pose,
// oriented box, CAD model, score, and the rejected hypotheses with their reasons) and models.ply
// (the fitted CAD meshes). A missing model file is trained from the furniture library first.

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "cli_util.hpp"
#include "commands.hpp"
#include "default_paths.hpp"
#include "furniture_report.hpp"
#include "multicue/core/exceptions.hpp"
#include "multicue/core/progress.hpp"
#include "multicue/io/file_utils.hpp"
#include "multicue/io/ply.hpp"
#include "multicue/mapping/furniture_detection.hpp"
#include "multicue/sim/mesh_split.hpp"
#include "multicue/training/furniture_training.hpp"

namespace multicue::cli {
namespace {

struct MapFurnitureOptions {
    std::vector<std::string> scans;
    std::string model;
    std::string out;
    std::string furniture = DefaultFurnitureDir();
    std::string kitchen = DefaultKitchenDir();
    std::optional<float> threshold_scale;  ///< default: 0.3 with verification, 1 without
    float min_coverage = 0.5f;
    float max_free_share = 0.4f;
    bool verify = true;
    bool free_space = true;
    bool learned = true;
    bool learned_tests = true;
    float min_confidence = FurnitureDetectionParams{}.min_confidence;
    float min_confidence_single = FurnitureDetectionParams{}.min_confidence_single;
    int fit_models = FurnitureDetectionParams{}.fit_models;
    bool quiet = false;
    bool detect = false;  ///< `detect furniture`: the model must exist; result.json, report.html
    bool report = true;
};

/// The scan in its sensor frame and the sensor's pose in the world (from the file's header).
FurnitureView SensorView(const std::string& path, PointCloud& scan) {
    if (!scan.HasSensorPosition()) {
        throw DataError(fmt::format(
            "{}: no sensor pose in the file (PCD VIEWPOINT or PLY obj_info); map furniture needs "
            "it for the free-space test",
            path));
    }
    Eigen::Isometry3f T = Eigen::Isometry3f::Identity();
    T.linear() = scan.sensor_orientation.normalized().toRotationMatrix();
    T.translation() = scan.sensor_origin;
    const Eigen::Isometry3f inv = T.inverse();
    for (auto& p : scan.points) p = inv * p;
    for (auto& n : scan.normals) n = inv.linear() * n;
    scan.sensor_origin = Eigen::Vector3f::Zero();  // now the frame's origin
    scan.sensor_orientation = Eigen::Quaternionf::Identity();
    return {&scan, T};
}

FurnitureModel LoadOrTrain(const MapFurnitureOptions& o, int threads) {
    if (std::filesystem::exists(o.model)) return FurnitureModel::Load(o.model);
    if (o.detect) {
        throw IoError(fmt::format(
            "{}: no such furniture model (train one with `multicue train furniture --out {}`)",
            o.model, o.model));
    }
    training::FurnitureTrainingOptions to;
    to.furniture = o.furniture;
    to.kitchen = o.kitchen;
    to.num_threads = threads;
    to.Validate();
    const auto pieces = training::FurnitureTrainingPieces(to);
    FurnitureModel model;
    Progress progress("training", training::FurnitureTrainingSteps(pieces, to));
    if (!training::TrainFurnitureModel(pieces, to, model, &progress)) {
        throw Error("map furniture: training interrupted, no model written");
    }
    progress.Finish();
    model.Save(o.model);
    return model;
}

/// Yaw in degrees within (-180, 180].
float YawDeg(float yaw) {
    float d =
        std::remainder(yaw, 2.0f * static_cast<float>(M_PI)) * 180.0f / static_cast<float>(M_PI);
    return d <= -180.0f ? d + 360.0f : d;
}

nlohmann::json DetectionJson(const FurnitureDetection& d, const FurnitureModel& model) {
    nlohmann::json j;
    j["class"] = d.category;
    j["score"] = d.score;
    j["votes"] = d.hypothesis.normalized;
    if (d.confidence >= 0.0f) j["confidence"] = d.confidence;
    j["centre"] = {d.centre.x(), d.centre.y()};
    if (!d.rejection.empty()) j["rejection"] = d.rejection;
    if (!d.fitted || d.fit.cad < 0) return j;
    const FurnitureCad& cad = model.cads()[static_cast<std::size_t>(d.fit.cad)];
    const Eigen::Isometry3f& T = d.fit.T_world_model;
    // The piece's box (the fitted model's, grown or shrunk to the scan's parts of the piece) in
    // T's frame.
    const Eigen::AlignedBox3f box =
        d.box.isEmpty() ? Eigen::AlignedBox3f(Eigen::Vector3f::Zero(), Eigen::Vector3f::Zero())
                        : d.box;
    const Eigen::Vector3f box_centre = T * box.center();
    const Eigen::Vector3f box_size = box.sizes();
    nlohmann::json pose = nlohmann::json::array();
    for (int r = 0; r < 4; ++r) {
        pose.push_back({T.matrix()(r, 0), T.matrix()(r, 1), T.matrix()(r, 2), T.matrix()(r, 3)});
    }
    j["cad_model"] = cad.id;
    j["pose"] = pose;
    j["yaw_deg"] = YawDeg(d.fit.yaw);
    j["turned"] = d.fit.turned;
    j["scale"] = {d.fit.scale.x(), d.fit.scale.y(), d.fit.scale.z()};
    j["box"] = {{"centre", {box_centre.x(), box_centre.y(), box_centre.z()}},
                {"size", {box_size.x(), box_size.y(), box_size.z()}},
                {"yaw_deg", YawDeg(d.fit.yaw)}};
    j["coverage"] = d.fit.coverage;
    j["free_share"] = d.fit.free_share;
    j["behind_wall_share"] = d.fit.behind_share;
    const FurnitureShapeEvidence& e = d.shape;
    j["shape"] = {{"inside_share", e.inside_share},
                  {"top", e.top},
                  {"top_ratio", e.top_ratio},
                  {"span_x", e.span_x},
                  {"span_y", e.span_y},
                  {"low_share", e.low_share},
                  {"beyond", e.beyond}};
    return j;
}

void Run(const MapFurnitureOptions& o, const GlobalOptions& global) {
    FurnitureDetectionParams params;
    if (o.threshold_scale) {
        params.selection.threshold_scale = *o.threshold_scale;
    } else if (!o.verify) {
        params.selection.threshold_scale = 1.0f;  // the hypotheses are the detections
    }
    params.fit.min_coverage = o.min_coverage;
    params.fit.max_free_share = o.max_free_share;
    params.verify = o.verify;
    params.free_space = o.free_space;
    params.learned = o.learned;
    params.learned_tests = o.learned_tests;
    params.min_confidence = o.min_confidence;
    params.min_confidence_single = o.min_confidence_single;
    params.fit_models = o.fit_models;
    params.num_threads = global.threads;
    params.Validate();  // before reading or training anything
    for (const auto& s : o.scans) CheckDistinctPaths(s, o.out);
    CheckDistinctPaths(o.model, o.out);
    std::vector<PointCloud> scans;
    scans.reserve(o.scans.size());
    for (const auto& s : o.scans) scans.push_back(ReadNonEmptyCloud(s));
    std::vector<FurnitureView> views;
    for (std::size_t i = 0; i < scans.size(); ++i)
        views.push_back(SensorView(o.scans[i], scans[i]));
    InstallInterruptHandler();
    const FurnitureModel model = LoadOrTrain(o, global.threads);
    const auto context =
        o.verify ? std::make_unique<FurnitureFitContext>(model, params.fit) : nullptr;
    const FurnitureDetectionResult r = DetectFurniture(views, model, context.get(), params);

    // Build the outputs in memory, then write each file atomically.
    nlohmann::json doc;
    doc["scans"] = o.scans;
    doc["model"] = o.model;
    doc["verified"] = o.verify;
    doc["detections"] = nlohmann::json::array();
    doc["rejected"] = nlohmann::json::array();
    TriangleMesh fitted;
    for (const auto& d : r.detections) {
        doc["detections"].push_back(DetectionJson(d, model));
        if (!d.fitted || d.fit.cad < 0) continue;
        const TriangleMesh& m = model.cads()[static_cast<std::size_t>(d.fit.cad)].mesh;
        const Eigen::Affine3f A = d.fit.ModelToWorld();
        const auto base = static_cast<std::uint32_t>(fitted.vertices.size());
        for (const auto& v : m.vertices) fitted.vertices.push_back(A * v);
        for (const auto& t : m.triangles) fitted.triangles.push_back(t.array() + base);
    }
    for (const auto& d : r.rejected) doc["rejected"].push_back(DetectionJson(d, model));
    doc["timing_ms"] = {{"selection", r.selection_ms}, {"fitting", r.fit_ms}};
    const std::filesystem::path dir = o.out;
    std::filesystem::create_directories(dir);
    const std::string text = doc.dump(2) + "\n";
    const std::filesystem::path json_path = dir / (o.detect ? "result.json" : "detections.json");
    io::WriteFileAtomically(json_path, [&](std::ostream& s) { s << text; });
    if (!fitted.triangles.empty()) io::WritePlyMesh(dir / "models.ply", fitted);
    if (o.detect && o.report) {
        const std::string page = FurnitureReportPage(doc, views);
        io::WriteFileAtomically(dir / "report.html", [&](std::ostream& s) { s << page; });
    }
    if (!o.quiet) {
        std::printf(
            "multicue %s furniture: %zu scans, %zu detections (%zu hypotheses rejected) -> %s\n",
            o.detect ? "detect" : "map", scans.size(), r.detections.size(), r.rejected.size(),
            json_path.string().c_str());
        for (const auto& d : r.detections) {
            const std::string yaw =
                d.fitted ? fmt::format("yaw {:4.0f} deg", YawDeg(d.fit.yaw)) : "(not fitted)";
            std::printf("  %-9s at (%6.2f, %6.2f) %s score %.2f\n", d.category.c_str(),
                        d.centre.x(), d.centre.y(), yaw.c_str(), d.score);
        }
    }
}

/// The options `map furniture` and `detect furniture` share.
void AddDetectionOptions(CLI::App* cmd, MapFurnitureOptions* o) {
    cmd->add_option("SCANS", o->scans,
                    "PCD or PLY scans in one world frame (z up, floor at z = 0) with sensor poses")
        ->required()
        ->check(CLI::ExistingFile);
    cmd->add_option("--threshold-scale", o->threshold_scale,
                    "multiplies the class thresholds of the votes (lower: more hypotheses); "
                    "default 0.3 (the fits judge them), 1 with --no-verify");
    cmd->add_option("--min-coverage", o->min_coverage,
                    "share of a hypothesis's points a fitted model must cover, [0, 1] (binding "
                    "without a learned verifier or with --no-learned-tests)")
        ->capture_default_str();
    cmd->add_option("--max-free-share", o->max_free_share,
                    "share of a fitted model allowed in space the scans saw empty, [0, 1] "
                    "(binding without a learned verifier or with --no-learned-tests)")
        ->capture_default_str();
    cmd->add_flag(
        "--no-verify", [o](std::int64_t) { o->verify = false; },
        "hypotheses of the votes without CAD fitting");
    cmd->add_flag(
        "--no-free-space", [o](std::int64_t) { o->free_space = false; },
        "fit without the free-space test");
    cmd->add_option("--min-confidence", o->min_confidence,
                    "fits the model's learned verifier gives a lower probability of being right "
                    "are rejected, [0, 1]")
        ->capture_default_str();
    cmd->add_option("--min-confidence-single", o->min_confidence_single,
                    "the same for a single scan, [0, 1]")
        ->capture_default_str();
    cmd->add_option("--fit-models", o->fit_models,
                    "CAD models whose best poses are finished and judged per hypothesis, >= 1")
        ->capture_default_str();
    cmd->add_flag(
        "--no-learned", [o](std::int64_t) { o->learned = false; },
        "verify fits by the thesis's tests alone, without the model's learned verifier");
    cmd->add_flag(
        "--no-learned-tests", [o](std::int64_t) { o->learned_tests = false; },
        "a fit must pass the coverage, free-space and wall tests as well as the verifier");
    cmd->add_flag("-q,--quiet", o->quiet, "no summary");
}

struct TrainFurnitureOptions {
    std::string out;
    std::string furniture = DefaultFurnitureDir();
    std::string kitchen = DefaultKitchenDir();
    std::string split = "tune";
    std::string features = "full";
    training::FurnitureTrainingOptions t;
    bool quiet = false;
};

void TrainFurniture(TrainFurnitureOptions& o, int threads) {
    o.t.furniture = o.furniture;
    o.t.kitchen = o.kitchen;
    o.t.split = sim::ParseMeshSplit(o.split);
    o.t.vocabulary.features = ParseFurnitureFeatureSet(o.features);
    o.t.num_threads = threads;
    o.t.Validate();  // before loading or simulating anything
    if (o.furniture.empty() && o.kitchen.empty() && o.t.procedural_per_class == 0) {
        throw InvalidArgument(
            "train furniture: no pieces to train on (no library, --procedural 0)");
    }
    InstallInterruptHandler();
    const auto pieces = training::FurnitureTrainingPieces(o.t);
    FurnitureModel model;
    Progress progress("training", training::FurnitureTrainingSteps(pieces, o.t));
    if (!training::TrainFurnitureModel(pieces, o.t, model, &progress)) {
        throw Error("train furniture: interrupted, no model written");
    }
    progress.Finish();
    model.Save(o.out);
    if (!o.quiet) {
        std::printf(
            "multicue train furniture: %zu pieces, %zu classes, %zu training parts, %zu CAD "
            "models -> %s\n",
            pieces.size(), model.classes().size(), model.parts().size(), model.cads().size(),
            o.out.c_str());
    }
}

}  // namespace

void AddMapFurnitureCommand(CLI::App& map_command, const GlobalOptions& global) {
    auto* cmd = map_command.add_subcommand(
        "furniture",
        "Tables, chairs, cabinets and sideboards in scans of a room: part votes, CAD models "
        "fitted and verified against free space (detections.json, models.ply)");
    auto o = std::make_shared<MapFurnitureOptions>();
    AddDetectionOptions(cmd, o.get());
    cmd->add_option("--model", o->model,
                    "furniture model (.mcfm); trained from --furniture and --kitchen and written "
                    "here when missing")
        ->required();
    cmd->add_option("--out", o->out, "output folder: detections.json, models.ply")->required();
    cmd->add_option("--furniture", o->furniture, "furniture library (labels.csv) for training")
        ->capture_default_str();
    cmd->add_option("--kitchen", o->kitchen, "kitchen library for training (tables, cupboards)")
        ->capture_default_str();
    cmd->callback([o, &global] { Run(*o, global); });
}

void AddDetectFurnitureCommand(CLI::App& app, const GlobalOptions& global) {
    auto* detect = app.add_subcommand("detect", "Detect objects of a kind in scans");
    detect->require_subcommand(1);
    auto* cmd = detect->add_subcommand(
        "furniture",
        "Tables, chairs, cabinets and sideboards in scans of a room with a trained model "
        "(result.json, models.ply, report.html)");
    auto o = std::make_shared<MapFurnitureOptions>();
    o->detect = true;
    AddDetectionOptions(cmd, o.get());
    cmd->add_option("--model", o->model, "furniture model of `multicue train furniture` (.mcfm)")
        ->required()
        ->check(CLI::ExistingFile);
    cmd->add_option("--out", o->out, "output folder: result.json, models.ply, report.html")
        ->required();
    cmd->add_flag(
        "--no-report", [o](std::int64_t) { o->report = false; }, "no report.html");
    cmd->callback([o, &global] { Run(*o, global); });
}

void AddTrainFurnitureCommand(CLI::App& train_command, const GlobalOptions& global) {
    auto* cmd = train_command.add_subcommand(
        "furniture",
        "Train the furniture model (part vocabulary, shape models, CAD models) on simulated views "
        "of the furniture and kitchen libraries and procedural pieces");
    auto o = std::make_shared<TrainFurnitureOptions>();
    cmd->add_option("--out", o->out, "model file to write (.mcfm)")->required();
    cmd->add_option("--meshes,--furniture", o->furniture,
                    "furniture library (labels.csv); empty: none")
        ->capture_default_str();
    cmd->add_option("--kitchen", o->kitchen, "kitchen library (tables, cupboards); empty: none")
        ->capture_default_str();
    cmd->add_option("--split", o->split,
                    "library half trained on: tune (the other half stays held out), test, all")
        ->capture_default_str();
    cmd->add_option("--procedural", o->t.procedural_per_class, "procedural pieces per class")
        ->capture_default_str();
    cmd->add_option("--views", o->t.views.views, "training views per piece (thesis: 16)")
        ->capture_default_str();
    cmd->add_option("--words", o->t.vocabulary.words, "words of the vocabulary (k of k-means)")
        ->capture_default_str();
    cmd->add_option("--features", o->features,
                    "part features: full (24 values) or reduced (without features 4, 7, 8)")
        ->capture_default_str();
    cmd->add_option("--cad-spacing", o->t.cad_spacing,
                    "spacing of the CAD models' points used in fitting [m]")
        ->capture_default_str();
    cmd->add_option("--seed", o->t.seed, "views, sensor noise and procedural pieces")
        ->capture_default_str();
    cmd->add_option("--verifier-rooms", o->t.verifier_rooms,
                    "simulated rooms of procedural pieces the learned verifier of fits is trained "
                    "on; 0: no verifier")
        ->capture_default_str();
    cmd->add_option("--verifier-library-rooms", o->t.verifier_library_rooms,
                    "more verifier rooms, of the library's pieces, fitted by stand-in models "
                    "that never saw them (fits of pieces unknown to the model)")
        ->capture_default_str();
    cmd->add_option("--verifier-classifier", o->t.verifier_spec,
                    "classifier of the verifier (spec as in `multicue ml train`)")
        ->capture_default_str();
    cmd->add_flag("-q,--quiet", o->quiet, "no summary");
    cmd->callback([o, &global] { TrainFurniture(*o, global.threads); });
}

}  // namespace multicue::cli

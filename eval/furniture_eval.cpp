// furniture_eval: furniture detection by part configurations (thesis section 4.2.5) on simulated
// rooms whose furniture was never trained on. Trains (or loads) a model on the tune half of the
// furniture library plus procedural pieces, simulates rooms (offices, seminar rooms, kitchens)
// scanned by the tilting laser from several head positions, and scores the detections of every
// single view and of the merged views: the full method, nearest-part activation and the reduced
// feature set, before and after CAD verification; recall vs 1 - precision curves as SVG, yaw
// errors of the fitted models, stage timings. docs/furniture.md gives the protocol and results.

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "driver_options.hpp"
#include "furniture_eval_metrics.hpp"
#include "multicue/core/exceptions.hpp"
#include "multicue/core/progress.hpp"
#include "multicue/io/file_utils.hpp"
#include "multicue/mapping/furniture_detection.hpp"
#include "multicue/training/furniture_training.hpp"

#ifndef MULTICUE_SHARED_DATA_DIR
#define MULTICUE_SHARED_DATA_DIR "../shared/data"
#endif

namespace {

using namespace multicue;
using nlohmann::json;

struct Options {
    std::string furniture = std::string(MULTICUE_SHARED_DATA_DIR) + "/meshes/furniture";
    std::string kitchen = std::string(MULTICUE_SHARED_DATA_DIR) + "/meshes/kitchen";
    std::string model = "furniture_eval.mcfm";
    bool retrain = false;
    std::string set = "test";  // test: held-out library pieces; validation: fresh procedural ones
    int rooms = 21;
    std::uint64_t seed = 0;  // 0: 2000 for test, 1000 for validation
    float procedural_share = -1.0f;
    int heads = 3;
    std::string sensor = "laser";
    std::string out = "furniture_eval_out";
    float floor_cut = 0.3f;
    int min_visible = 50;
    bool variants = true;
    bool single = true;
    int threads = 0;
    // Overrides of the detection settings, to tune on the validation rooms.
    std::vector<std::string> thresholds;
    float window_scale = 1.0f;
    float min_coverage = 0.5f;
    float max_free_share = 0.1f;
    float min_part_share = 0.1f;
};

struct Variant {
    std::string name;
    const FurnitureModel* model = nullptr;
    FurnitureActivation activation = FurnitureActivation::kWords;
    bool verify = false;
};

// The visible objects of views `views` of a room: at least min_visible returns in them.
std::vector<eval::TruthItem> VisibleTruth(const training::ScannedFurnitureRoom& r, const std::vector<int>& views,
                                          const FurnitureModel& model, int min_visible) {
    std::map<std::uint32_t, int> count;
    for (int v : views) {
        for (std::uint32_t l : r.scans[static_cast<std::size_t>(v)].labels) ++count[l];
    }
    std::vector<eval::TruthItem> out;
    for (const auto& f : r.room.furniture) {
        if (count[f.label] < min_visible) continue;
        const int cls = model.ClassIndex(f.category);
        if (cls < 0) continue;
        out.push_back({cls, f.T_world_object.translation().head<2>(), f.width, f.yaw});
    }
    return out;
}

eval::EvalFrame Frame(const FurnitureDetectionResult& det, std::vector<eval::TruthItem> truth,
                      bool verified, const std::string& group) {
    eval::EvalFrame f;
    f.truth = std::move(truth);
    f.group = group;
    auto add = [&](const FurnitureDetection& d, bool accepted) {
        if (verified && !accepted) return;
        eval::DetectionItem item;
        item.cls = d.cls;
        item.score = d.score;
        item.centre = verified ? d.centre : d.hypothesis.centre;
        item.fitted = verified && d.fitted;
        item.yaw = d.fit.yaw;
        f.detections.push_back(item);
    };
    for (const auto& d : det.detections) add(d, true);
    for (const auto& d : det.rejected) add(d, false);
    return f;
}

void SetThresholds(FurnitureModel& model, const std::vector<std::string>& pairs) {
    for (const auto& p : pairs) {
        const auto eq = p.find('=');
        if (eq == std::string::npos) throw InvalidArgument("--threshold needs CLASS=VALUE, got " + p);
        const int c = model.ClassIndex(p.substr(0, eq));
        if (c < 0) throw InvalidArgument("--threshold: unknown class " + p.substr(0, eq));
        model.classes()[static_cast<std::size_t>(c)].threshold = std::stof(p.substr(eq + 1));
    }
}

int Run(const Options& o) {
    InstallInterruptHandler();
    std::filesystem::create_directories(o.out);
    training::FurnitureTrainingOptions to;
    to.furniture = o.furniture;
    to.kitchen = o.kitchen;
    to.sensor = training::ParseFurnitureSensor(o.sensor);
    to.num_threads = o.threads;
    FurnitureModel model;
    auto t0 = std::chrono::steady_clock::now();
    if (!o.retrain && std::filesystem::exists(o.model)) {
        model = FurnitureModel::Load(o.model);
    } else {
        const auto pieces = training::FurnitureTrainingPieces(to);
        Progress progress("training", pieces.size());
        if (!training::TrainFurnitureModel(pieces, to, model, &progress)) return 130;
        progress.Finish();
        model.Save(o.model);
    }
    SetThresholds(model, o.thresholds);
    const double train_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::fprintf(stderr, "model: %zu parts, %zu words, %zu CAD models (%.1f s)\n", model.parts().size(),
                 model.num_words(), model.cads().size(), train_s);
    FurnitureVocabularyParams vp = model.vocabulary_params();
    vp.features = FurnitureFeatureSet::kReduced;
    vp.num_threads = o.threads;
    FurnitureModel reduced = FurnitureModel::Train(model.parts(), model.classes(), {}, model.part_params(), vp);

    FurnitureDetectionParams dp;
    dp.selection.threshold_scale = o.floor_cut;
    dp.selection.window_scale = o.window_scale;
    dp.selection.min_part_share = o.min_part_share;
    dp.fit.min_coverage = o.min_coverage;
    dp.fit.max_free_share = o.max_free_share;
    dp.num_threads = o.threads;
    const FurnitureFitContext context(model, dp.fit);

    // Rooms: held-out library pieces (test) or fresh procedural pieces (validation).
    const bool test = o.set == "test";
    std::vector<sim::FurniturePiece> library;
    if (test) {
        for (const auto& e : sim::SelectFurnitureSplit(sim::ReadFurnitureLibrary(o.furniture, o.kitchen),
                                                      sim::MeshSplit::kTest)) {
            library.push_back(sim::LoadFurniturePiece(e));
        }
    }
    const float share = o.procedural_share >= 0.0f ? o.procedural_share : (test ? 0.0f : 1.0f);
    const sim::FurnitureSource source(library, share);
    const std::uint64_t first_seed = o.seed > 0 ? o.seed : (test ? 2000 : 1000);

    std::vector<Variant> variants = {{"full", &model, FurnitureActivation::kWords, false},
                                     {"full+cad", &model, FurnitureActivation::kWords, true}};
    if (o.variants) {
        variants.push_back({"nearest-part", &model, FurnitureActivation::kNearestPart, false});
        variants.push_back({"reduced", &reduced, FurnitureActivation::kWords, false});
    }
    std::map<std::string, std::vector<eval::EvalFrame>> merged, single;
    double parts_ms = 0, votes_ms = 0, occ_ms = 0, sel_ms = 0, fit_ms = 0;
    std::size_t n_views = 0, n_sel = 0, n_fits = 0;
    std::vector<double> fit_times;
    Progress progress("rooms", static_cast<std::size_t>(o.rooms));
    for (int r = 0; r < o.rooms && !InterruptRequested(); ++r) {
        sim::FurnitureRoomParams rp;
        rp.type = static_cast<sim::RoomType>(r % 3);
        const std::uint64_t seed = first_seed + static_cast<std::uint64_t>(r);
        const auto room = training::SimulateFurnitureRoom(rp, source, o.heads, to, seed);
        std::vector<FurnitureView> views;
        for (std::size_t v = 0; v < room.scans.size(); ++v) views.push_back({&room.scans[v], room.T_world_sensor[v]});
        FurnitureScene scene = PrepareFurnitureScene(views, model, dp);
        parts_ms += scene.parts_ms, votes_ms += scene.votes_ms, occ_ms += scene.occupancy_ms;
        n_views += views.size();
        const auto base_votes = scene.votes;
        const std::string group = sim::RoomTypeName(rp.type);
        std::vector<int> all;
        for (std::size_t v = 0; v < views.size(); ++v) all.push_back(static_cast<int>(v));
        for (const auto& var : variants) {
            FurnitureDetectionParams p = dp;
            p.verify = var.verify;
            p.voting.activation = var.activation;
            if (var.model != &model || var.activation != FurnitureActivation::kWords) {
                for (std::size_t v = 0; v < views.size(); ++v) {
                    scene.votes[v] = CastFurnitureVotes(scene.views[v], *var.model, static_cast<int>(v), p.voting);
                }
            } else {
                scene.votes = base_votes;
            }
            const auto det = DetectFurniture(scene, {}, *var.model, var.verify ? &context : nullptr, p);
            merged[var.name].push_back(Frame(det, VisibleTruth(room, all, model, o.min_visible), var.verify, group));
            if (var.verify) {
                sel_ms += det.selection_ms, fit_ms += det.fit_ms, ++n_sel;
                for (const auto* list : {&det.detections, &det.rejected}) {
                    for (const auto& d : *list) {
                        if (d.fitted || d.fit.iterations > 0) fit_times.push_back(d.fit.ms), ++n_fits;
                    }
                }
            }
            if (!o.single) continue;
            for (int v : all) {
                const auto dv = DetectFurniture(scene, {v}, *var.model, var.verify ? &context : nullptr, p);
                single[var.name].push_back(Frame(dv, VisibleTruth(room, {v}, model, o.min_visible), var.verify, group));
            }
        }
        progress.Advance();
    }
    progress.Finish();
    if (InterruptRequested()) return 130;

    // Report.
    const int table = model.ClassIndex("table");
    json report = {{"set", o.set}, {"rooms", o.rooms}, {"first_seed", first_seed}, {"heads", o.heads},
                   {"procedural_share", share}, {"sensor", o.sensor}, {"model", o.model}};
    std::vector<std::pair<std::string, std::vector<eval::CurvePoint>>> curves;
    std::printf("set %s, %d rooms (seeds %llu..), %d heads, %s\n", o.set.c_str(), o.rooms,
                static_cast<unsigned long long>(first_seed), o.heads, o.sensor.c_str());
    std::printf("%-24s %7s %7s %7s %9s %6s %6s %6s\n", "configuration", "prec", "recall", "R@P.9",
                "frames", "tp", "fp", "fn");
    for (const auto* frames_by : {&single, &merged}) {
        const bool is_merged = frames_by == &merged;
        for (const auto& var : variants) {
            const auto it = frames_by->find(var.name);
            if (it == frames_by->end()) continue;
            const auto& frames = it->second;
            eval::MatchCounts m;
            for (const auto& f : frames) m.Add(eval::MatchFrame(f, 1.0f, -1, table));
            const auto curve = eval::Curve(frames, o.floor_cut, 8.0f, 40, table);
            const std::string name = var.name + (is_merged ? " merged" : " single");
            const double rap = eval::RecallAtPrecision(curve, 0.9);
            std::printf("%-24s %7.3f %7.3f %7.3f %9zu %6zu %6zu %6zu\n", name.c_str(), m.Precision(),
                        m.Recall(), rap, frames.size(), m.tp, m.fp, m.fn);
            json entry = {{"precision", m.Precision()}, {"recall", m.Recall()}, {"recall_at_p90", rap},
                          {"tp", m.tp}, {"fp", m.fp}, {"fn", m.fn}, {"frames", frames.size()}};
            if (!m.yaw_errors.empty()) {
                entry["yaw_median_deg"] = eval::Percentile(m.yaw_errors, 0.5f);
                entry["yaw_p90_deg"] = eval::Percentile(m.yaw_errors, 0.9f);
                std::printf("%-24s yaw error median %.1f deg, 90th percentile %.1f deg (%zu fits)\n", "",
                            eval::Percentile(m.yaw_errors, 0.5f), eval::Percentile(m.yaw_errors, 0.9f),
                            m.yaw_errors.size());
            }
            // Per class and per room type at the operating point.
            for (std::size_t c = 0; c < model.classes().size(); ++c) {
                eval::MatchCounts mc;
                for (const auto& f : frames) mc.Add(eval::MatchFrame(f, 1.0f, static_cast<int>(c), table));
                entry["classes"][model.classes()[c].name] = {{"precision", mc.Precision()}, {"recall", mc.Recall()},
                                                             {"tp", mc.tp}, {"fp", mc.fp}, {"fn", mc.fn}};
            }
            for (const char* g : {"office", "seminar", "kitchen"}) {
                eval::MatchCounts mg;
                for (const auto& f : frames) {
                    if (f.group == g) mg.Add(eval::MatchFrame(f, 1.0f, -1, table));
                }
                entry["room_types"][g] = {{"precision", mg.Precision()}, {"recall", mg.Recall()}};
            }
            json pts = json::array();
            for (const auto& p : curve) pts.push_back({p.cut, p.precision, p.recall});
            entry["curve"] = pts;
            report["results"][name] = entry;
            curves.push_back({name, curve});
        }
    }
    for (const auto& [name, entry] : report["results"].items()) {
        std::string line = fmt::format("{:<24} per class:", name);
        for (const auto& [c, v] : entry["classes"].items()) {
            line += fmt::format(" {} {:.2f}/{:.2f}", c, v["precision"].get<double>(), v["recall"].get<double>());
        }
        line += "  per room type:";
        for (const auto& [g, v] : entry["room_types"].items()) {
            line += fmt::format(" {} {:.2f}/{:.2f}", g, v["precision"].get<double>(), v["recall"].get<double>());
        }
        std::printf("%s\n", line.c_str());
    }
    const double per_view = n_views ? 1.0 / n_views : 0.0;
    report["timings_ms"] = {{"parts_per_view", parts_ms * per_view}, {"votes_per_view", votes_ms * per_view},
                            {"occupancy_per_view", occ_ms * per_view},
                            {"selection_per_room", n_sel ? sel_ms / n_sel : 0.0},
                            {"fit_median", eval::Percentile(std::vector<float>(fit_times.begin(), fit_times.end()), 0.5f)},
                            {"fits", n_fits}};
    std::printf("timings per view: parts %.0f ms, votes %.0f ms, occupancy %.0f ms; selection %.1f ms per "
                "room; fit median %.0f ms (%zu fits)\n",
                parts_ms * per_view, votes_ms * per_view, occ_ms * per_view, n_sel ? sel_ms / n_sel : 0.0,
                report["timings_ms"]["fit_median"].get<double>(), n_fits);
    const std::string title = fmt::format("furniture detection, {} rooms ({} set, seeds {}-{})", o.rooms, o.set,
                                          first_seed, first_seed + o.rooms - 1);
    eval::WriteCurvesSvg((std::filesystem::path(o.out) / "curves.svg").string(), title, curves);
    const std::string text = report.dump(1);
    io::WriteFileAtomically(std::filesystem::path(o.out) / "report.json", [&](std::ostream& os) { os << text << '\n'; });
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    Options o;
    CLI::App app{"furniture_eval: furniture detection on held-out simulated rooms"};
    app.add_option("--furniture", o.furniture, "furniture folder (labels.csv)")->capture_default_str();
    app.add_option("--kitchen", o.kitchen, "kitchen library folder")->capture_default_str();
    app.add_option("--model", o.model, "model file: loaded when present, else trained and written")
        ->capture_default_str();
    app.add_flag("--retrain", o.retrain, "train even when --model exists");
    app.add_option("--set", o.set, "test (held-out library pieces) or validation (fresh procedural pieces)")
        ->check(CLI::IsMember({"test", "validation"}))
        ->capture_default_str();
    app.add_option("--rooms", o.rooms, "rooms (office, seminar, kitchen in turn)")->capture_default_str();
    app.add_option("--seed", o.seed, "first room seed (default 2000 test, 1000 validation)");
    app.add_option("--procedural-share", o.procedural_share,
                   "share of procedural pieces in the rooms (default 0 test, 1 validation)");
    app.add_option("--heads", o.heads, "head positions per room")->capture_default_str();
    app.add_option("--sensor", o.sensor, "laser or kinect")->capture_default_str();
    app.add_option("--out", o.out, "folder for report.json and curves.svg")->capture_default_str();
    app.add_option("--floor", o.floor_cut, "lowest normalised score kept (curves start there)")
        ->capture_default_str();
    app.add_option("--min-visible", o.min_visible, "returns that make an object visible in a view")
        ->capture_default_str();
    app.add_option("--threshold", o.thresholds, "class threshold override CLASS=VALUE (repeatable)");
    app.add_option("--window-scale", o.window_scale, "search window in class widths")->capture_default_str();
    app.add_option("--min-coverage", o.min_coverage, "CAD fit coverage needed")->capture_default_str();
    app.add_option("--max-free-share", o.max_free_share, "share of a model allowed in free space")
        ->capture_default_str();
    app.add_option("--min-part-share", o.min_part_share, "support share of a part for the fit")
        ->capture_default_str();
    app.add_flag("!--no-variants", o.variants, "only the full method");
    app.add_flag("!--no-single", o.single, "merged views only");
    app.add_option("-j,--threads", o.threads, "threads (0 = all cores)")->capture_default_str();
    if (auto code = multicue::eval::ParseDriverOptions(app, "furniture_eval", [&] { app.parse(argc, argv); })) {
        return *code;
    }
    try {
        return Run(o);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "furniture_eval: %s\n", e.what());
        return 1;
    }
}

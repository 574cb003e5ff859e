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
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include <fmt/format.h>
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "driver_options.hpp"
#include "furniture_eval_draw.hpp"
#include "furniture_eval_metrics.hpp"
#include "multicue/core/exceptions.hpp"
#include "multicue/core/progress.hpp"
#include "multicue/io/file_utils.hpp"
#include "multicue/mapping/furniture_detection.hpp"
#include "multicue/ml/classifier.hpp"
#include "multicue/ml/dataset.hpp"
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
    // test: held-out library pieces; validation: fresh procedural ones; library: the tune half's
    // pieces of --library-fold, held out of training
    std::string set = "test";
    int library_fold = 0;
    int verifier_library_rooms = -1;     // -1: the training default
    bool verifier_piece_labels = false;  // the training default
    int rooms = 21;
    std::uint64_t seed = 0;  // 0: 2000 for test, 1000 for validation
    float procedural_share = -1.0f;
    int heads = 3;
    std::string sensor = "laser";
    std::string out = "furniture_eval_out";
    float floor_cut = 0.3f;
    bool other_classes = false;
    std::string verifier_rows;  ///< with --retrain-verifier: rows read from or written to
    int min_visible = 50;
    bool variants = true;
    bool single = true;
    int threads = 0;
    int draw = 0;
    std::string dump_fits;  // TSV of every fit of the primary variant with its verifier features
    // Overrides of the detection settings, to tune on the validation rooms.
    std::vector<std::string> thresholds;
    float window_scale = 1.0f;
    float min_coverage = 0.5f;
    float max_free_share = 0.4f;
    float min_part_share = 0.1f;
    std::string normalization = "per-class";
    std::string frame = "part";
    bool cross_class = false;
    bool fit_cross_class = true;
    bool cross_class_surfaces = true;
    float max_overlap = 0.3f;
    std::size_t words = 0;
    int probe = 0;
    int train_procedural = 8;
    bool class_by_fit = true;
    bool learned = true;
    float min_confidence = FurnitureDetectionParams{}.min_confidence;
    float min_confidence_single = FurnitureDetectionParams{}.min_confidence_single;
    bool retrain_verifier = false;
    bool learned_tests = true;
    int verifier_rooms = -1;    // -1: the training default
    std::string verifier_spec;  // empty: the training default
    std::size_t activations = 2;
    float max_height_error = 0.25f;
    float support_margin = 0.3f;
    float fit_scale = FurnitureFitParams{}.max_scale;
    int fit_scale_steps = FurnitureFitParams{}.scale_steps;
    bool back_to_wall = FurnitureFitParams{}.back_to_wall;
    bool piece_extent = FurniturePieceParams{}.grow;
    bool piece_shrink = FurniturePieceParams{}.shrink;
    bool piece_taken = FurniturePieceParams{}.taken;
    bool piece_walls = FurniturePieceParams{}.walls;
    float piece_member_share = FurniturePieceParams{}.member_share;
    float piece_free_share = FurniturePieceParams{}.free_share;
    float flip_tolerance = FurnitureFitParams{}.flip_tolerance;
    float max_offset = FurnitureFitParams{}.max_offset;
    int fit_models = FurnitureDetectionParams{}.fit_models;
    int verifier_fit_models = 1;  ///< FurnitureTrainingOptions::verifier_fit_models
};

struct Variant {
    std::string name;
    const FurnitureModel* model = nullptr;
    FurnitureActivation activation = FurnitureActivation::kWords;
    bool verify = false;
    bool learned = false;  ///< with the model's learned verifier: scores are its confidences
};

// The visible objects of views `views` of a room: at least min_visible returns in them.
std::vector<eval::TruthItem> VisibleTruth(const training::ScannedFurnitureRoom& r,
                                          const std::vector<int>& views,
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
    return f;
}

// Every hypothesis of a room with its nearest true piece of the same class and its fit.
void ListRoom(int r, const training::ScannedFurnitureRoom& room,
              const FurnitureDetectionResult& det, const FurnitureModel& model) {
    std::fprintf(stderr, "room %d (%s):", r, sim::RoomTypeName(room.room.type));
    for (const auto& f : room.room.furniture) std::fprintf(stderr, " %s", f.category.c_str());
    std::fprintf(stderr, "\n");
    for (const auto* list : {&det.detections, &det.rejected}) {
        for (const auto& d : *list) {
            float best = 1e9f, width = 0.0f, yaw = 0.0f;
            for (const auto& f : room.room.furniture) {
                if (f.category != d.category) continue;
                const float dist =
                    (f.T_world_object.translation().head<2>() - d.hypothesis.centre).norm();
                if (dist < best) best = dist, width = f.width, yaw = f.yaw;
            }
            std::fprintf(
                stderr,
                "  %-9s score %5.2f at (%5.2f %5.2f) parts %2zu | truth %.2f m (w %.2f) | fit %s "
                "cov %.2f "
                "free %.2f yaw %6.1f/%6.1f %s %s\n",
                d.category.c_str(), d.score, d.hypothesis.centre.x(), d.hypothesis.centre.y(),
                d.hypothesis.parts.size(), best, width,
                d.fitted ? model.cads()[static_cast<std::size_t>(d.fit.cad)].id.c_str() : "-",
                d.fit.coverage, d.fit.free_share, d.fit.yaw * 57.3f, yaw * 57.3f,
                d.accepted ? "OK" : "--", d.rejection.c_str());
        }
    }
}

void SetThresholds(FurnitureModel& model, const std::vector<std::string>& pairs) {
    for (const auto& p : pairs) {
        const auto eq = p.find('=');
        if (eq == std::string::npos)
            throw InvalidArgument("--threshold needs CLASS=VALUE, got " + p);
        const int c = model.ClassIndex(p.substr(0, eq));
        if (c < 0) throw InvalidArgument("--threshold: unknown class " + p.substr(0, eq));
        model.classes()[static_cast<std::size_t>(c)].threshold = std::stof(p.substr(eq + 1));
    }
}

// Single fresh procedural pieces on the floor, one view each: per true class, the mean best
// score of every class within half a width of the centre and how often the best is right.
int Probe(const Options& o, const FurnitureModel& model,
          const training::FurnitureTrainingOptions& to, FurnitureDetectionParams dp) {
    {  // Word purity: per class, the mean balanced share of its own class in its parts' words.
        const std::size_t nc = model.classes().size();
        std::vector<double> share(nc, 0.0), purity(nc, 0.0), count(nc, 0.0);
        for (const auto& p : model.parts()) share[static_cast<std::size_t>(p.cls)] += 1.0;
        for (std::size_t w = 0; w < model.num_words(); ++w) {
            double total = 0.0;
            for (std::size_t c = 0; c < nc; ++c)
                total += model.WordClassCount(static_cast<int>(w), static_cast<int>(c)) / share[c];
            for (std::size_t c = 0; c < nc; ++c) {
                const double n = model.WordClassCount(static_cast<int>(w), static_cast<int>(c));
                purity[c] += n * (n / share[c]) / total;
                count[c] += n;
            }
        }
        for (std::size_t c = 0; c < nc; ++c) {
            std::printf("%-10s training parts %6.0f, mean own-class share of their words %.2f\n",
                        model.classes()[c].name.c_str(), count[c], purity[c] / count[c]);
        }
    }
    dp.verify = false;
    dp.selection.threshold_scale = 0.0f;
    const std::size_t nc = model.classes().size();
    for (std::size_t c = 0; c < nc; ++c) {
        std::vector<double> best(nc, 0.0);
        int right = 0;
        for (int k = 0; k < o.probe; ++k) {
            sim::StreamRng rng(9000 + static_cast<std::uint64_t>(k), c);
            const auto piece = sim::MakeProceduralFurniture(model.classes()[c].name, rng);
            const sim::Scene scene =
                sim::MakeFurnitureViewScene(piece, static_cast<float>(rng.Uniform(-3.1, 3.1)));
            const sim::RayCaster caster(scene);
            sim::FurnitureViewParams vp;
            vp.views = 1;
            const auto head =
                sim::FurnitureViewHeads(vp, 77 + static_cast<std::uint64_t>(k)).front();
            Eigen::Isometry3f T;
            const PointCloud scan = training::ScanFurniture(caster, head, {0, 0, 0.4f}, to, 5, T);
            const auto det = DetectFurniture({{&scan, T}}, model, nullptr, dp);
            std::vector<double> b(nc, 0.0);
            for (const auto& d : det.detections) {
                if (d.hypothesis.centre.norm() < FurnitureWidth(*piece.mesh) / 2) {
                    b[static_cast<std::size_t>(d.cls)] =
                        std::max<double>(b[static_cast<std::size_t>(d.cls)], d.score);
                }
            }
            for (std::size_t j = 0; j < nc; ++j) best[j] += b[j] / o.probe;
            if (std::max_element(b.begin(), b.end()) - b.begin() == static_cast<long>(c) &&
                b[c] > 0)
                ++right;
        }
        std::printf("%-10s right %d/%d; mean best normalised score:",
                    model.classes()[c].name.c_str(), right, o.probe);
        for (std::size_t j = 0; j < nc; ++j)
            std::printf(" %s %.2f", model.classes()[j].name.c_str(), best[j]);
        std::printf("\n");
    }
    return 0;
}

// The library pieces of `pieces` split into two folds (training::SplitFurnitureLibrary's halves);
// returns the pieces without fold `fold`, in their order, and that fold's pieces.
std::pair<std::vector<sim::FurniturePiece>, std::vector<sim::FurniturePiece>> LibraryFold(
    const std::vector<sim::FurniturePiece>& pieces, int fold) {
    const training::FurnitureLibraryHalves split = training::SplitFurnitureLibrary(pieces);
    std::set<std::string> out_ids;
    for (const auto& p : split.library[fold]) out_ids.insert(p.id);
    std::vector<sim::FurniturePiece> kept, held;
    for (const auto& p : pieces) (out_ids.count(p.id) ? held : kept).push_back(p);
    if (held.empty()) throw DataError("furniture_eval: the library fold holds no piece");
    for (const auto& p : held)
        std::fprintf(stderr, "held out: %s (%s)\n", p.id.c_str(), p.category.c_str());
    return {std::move(kept), std::move(held)};
}

int Run(const Options& o) {
    InstallInterruptHandler();
    std::filesystem::create_directories(o.out);
    training::FurnitureTrainingOptions to;
    to.furniture = o.furniture;
    to.kitchen = o.kitchen;
    to.sensor = training::ParseFurnitureSensor(o.sensor);
    to.num_threads = o.threads;
    to.procedural_per_class = o.train_procedural;
    to.parts.frame = ParseFurniturePartFrame(o.frame);
    if (o.verifier_rooms >= 0) to.verifier_rooms = o.verifier_rooms;
    if (o.verifier_library_rooms >= 0) to.verifier_library_rooms = o.verifier_library_rooms;
    to.verifier_piece_labels = o.verifier_piece_labels;
    if (!o.verifier_spec.empty()) to.verifier_spec = o.verifier_spec;
    to.verifier_fit.max_scale = o.fit_scale;
    to.verifier_fit.scale_steps = o.fit_scale_steps;
    to.verifier_fit.back_to_wall = o.back_to_wall;
    to.verifier_fit.flip_tolerance = o.flip_tolerance;
    to.verifier_fit.max_offset = o.max_offset;
    to.verifier_fit_models = o.verifier_fit_models;
    // The training pieces; with --set library, without the tune pieces of --library-fold, which
    // furnish the rooms instead.
    std::vector<sim::FurniturePiece> pieces, held_out;
    const bool library_set = o.set == "library";
    auto training_pieces = [&] {
        if (!pieces.empty()) return;
        pieces = training::FurnitureTrainingPieces(to);
        if (library_set) std::tie(pieces, held_out) = LibraryFold(pieces, o.library_fold);
    };
    if (library_set) training_pieces();
    FurnitureModel model;
    auto t0 = std::chrono::steady_clock::now();
    if (!o.retrain && std::filesystem::exists(o.model)) {
        model = FurnitureModel::Load(o.model);
        if (o.retrain_verifier) {  // the verifier alone, on the loaded vocabulary and CAD models
            std::shared_ptr<const ml::Classifier> verifier;  // none with 0 rooms
            std::optional<ml::Dataset> rows;
            if (!o.verifier_rows.empty() && std::filesystem::exists(o.verifier_rows)) {
                rows = ml::ReadDatasetFile(o.verifier_rows);
            } else if (to.verifier_rooms > 0) {
                Progress progress("verifier rooms", static_cast<std::size_t>(to.verifier_rooms));
                rows = training::CollectFurnitureVerifierRows(model, to, &progress);
                if (InterruptRequested()) return 130;
                progress.Finish();
                if (!o.verifier_rows.empty()) ml::WriteDatasetFile(*rows, o.verifier_rows);
            }
            if (rows && to.verifier_library_rooms > 0) {  // not kept in --verifier-rows
                training_pieces();
                Progress more("stand-in models and verifier rooms of library pieces",
                              training::FurnitureLibraryVerifierSteps(pieces, to));
                training::AppendFurnitureLibraryVerifierRows(*rows, model, pieces, to, &more);
                if (InterruptRequested()) return 130;
                more.Finish();
            }
            if (rows) verifier = training::FitFurnitureVerifier(model, *rows, to);
            model.SetVerifier(verifier);
            model.Save(o.model);
        }
    } else {
        training_pieces();
        Progress progress("training", training::FurnitureTrainingSteps(pieces, to));
        if (!training::TrainFurnitureModel(pieces, to, model, &progress)) return 130;
        progress.Finish();
        model.Save(o.model);
    }
    if (o.words > 0 && o.words != model.num_words()) {  // another vocabulary size
        FurnitureVocabularyParams wp = model.vocabulary_params();
        wp.words = o.words;
        wp.num_threads = o.threads;
        model = FurnitureModel::Train(model.parts(), model.classes(), model.cads(),
                                      model.part_params(), wp);
    }
    SetThresholds(model, o.thresholds);
    const double train_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::fprintf(stderr, "model: %zu parts, %zu words, %zu CAD models up to %.2f m (%.1f s)\n",
                 model.parts().size(), model.num_words(), model.cads().size(),
                 model.max_object_height(), train_s);
    FurnitureVocabularyParams vp = model.vocabulary_params();
    vp.features = FurnitureFeatureSet::kReduced;
    vp.num_threads = o.threads;
    FurnitureModel reduced =
        FurnitureModel::Train(model.parts(), model.classes(), {}, model.part_params(), vp);

    FurnitureDetectionParams dp;
    dp.selection.threshold_scale = o.floor_cut;
    dp.selection.window_scale = o.window_scale;
    dp.selection.min_part_share = o.min_part_share;
    dp.voting.normalization = ParseFurnitureVoteNormalization(o.normalization);
    dp.selection.cross_class = o.cross_class;
    dp.other_classes = o.other_classes;
    dp.cross_class = o.fit_cross_class;
    dp.cross_class_surfaces = o.cross_class_surfaces;
    dp.max_overlap = o.max_overlap;
    dp.class_by_fit = o.class_by_fit;
    dp.learned = o.learned;
    dp.min_confidence = o.min_confidence;
    dp.min_confidence_single = o.min_confidence_single;
    dp.learned_tests = o.learned_tests;
    dp.voting.activations = o.activations;
    dp.voting.max_height_error = o.max_height_error;
    dp.support_margin = o.support_margin;
    dp.fit.min_coverage = o.min_coverage;
    dp.fit.max_free_share = o.max_free_share;
    dp.fit.max_scale = o.fit_scale;
    dp.fit.scale_steps = o.fit_scale_steps;
    dp.fit.back_to_wall = o.back_to_wall;
    dp.piece.grow = o.piece_extent;
    dp.piece.shrink = o.piece_shrink;
    dp.piece.free_share = o.piece_free_share;
    dp.piece.taken = o.piece_taken;
    dp.piece.walls = o.piece_walls;
    dp.piece.member_share = o.piece_member_share;
    dp.fit.flip_tolerance = o.flip_tolerance;
    dp.fit.max_offset = o.max_offset;
    dp.fit_models = o.fit_models;
    dp.num_threads = o.threads;
    const FurnitureFitContext context(model, dp.fit);

    if (o.probe > 0) return Probe(o, model, to, dp);
    // Rooms: held-out library pieces (test) or fresh procedural pieces (validation).
    const bool test = o.set == "test";
    std::vector<sim::FurniturePiece> library = held_out;
    if (test) {
        for (const auto& e : sim::SelectFurnitureSplit(
                 sim::ReadFurnitureLibrary(o.furniture, o.kitchen), sim::MeshSplit::kTest)) {
            library.push_back(sim::LoadFurniturePiece(e));
        }
    }
    const float share = o.procedural_share >= 0.0f ? o.procedural_share
                        : (test || library_set)    ? 0.0f
                                                   : 1.0f;
    const sim::FurnitureSource source(library, share);
    const std::uint64_t first_seed = o.seed > 0 ? o.seed
                                                : (test          ? 2000
                                                   : library_set ? 1500 + 100 * o.library_fold
                                                                 : 1000);

    const bool learned = o.learned && model.verifier() != nullptr;
    std::vector<Variant> variants = {
        {"full", &model, FurnitureActivation::kWords, false},
        {"full+cad", &model, FurnitureActivation::kWords, true, learned}};
    if (learned) {  // the thesis's tests alone, for comparison
        variants.push_back({"full+cad-tests", &model, FurnitureActivation::kWords, true, false});
    }
    if (o.variants) {
        variants.push_back({"nearest-part", &model, FurnitureActivation::kNearestPart, false});
        variants.push_back({"reduced", &reduced, FurnitureActivation::kWords, false});
    }
    std::map<std::string, std::vector<eval::EvalFrame>> merged, single;
    double parts_ms = 0, votes_ms = 0, occ_ms = 0, sel_ms = 0, fit_ms = 0;
    std::size_t n_views = 0, n_sel = 0, n_fits = 0;
    std::vector<double> fit_times;
    std::map<std::string, std::map<std::string, int>> fates;
    Progress progress("rooms", static_cast<std::size_t>(o.rooms));
    std::ofstream dump;
    if (!o.dump_fits.empty()) {
        dump.open(o.dump_fits);
        if (!dump) throw IoError("cannot write " + o.dump_fits);
        dump << "room\tclass\tright\tfate\tconfidence\tx\ty\tcad";
        for (const auto& n : FurnitureVerifierFeatureNames(model)) dump << '\t' << n;
        dump << '\n';
    }
    for (int r = 0; r < o.rooms && !InterruptRequested(); ++r) {
        sim::FurnitureRoomParams rp;
        rp.type = static_cast<sim::RoomType>(r % 3);
        const std::uint64_t seed = first_seed + static_cast<std::uint64_t>(r);
        const auto room = training::SimulateFurnitureRoom(rp, source, o.heads, to, seed);
        std::vector<FurnitureView> views;
        for (std::size_t v = 0; v < room.scans.size(); ++v)
            views.push_back({&room.scans[v], room.T_world_sensor[v]});
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
            p.learned = var.learned;
            const bool primary = var.name == "full+cad";  // fates, drawings and timings
            p.voting.activation = var.activation;
            if (var.model != &model || var.activation != FurnitureActivation::kWords) {
                for (std::size_t v = 0; v < views.size(); ++v) {
                    scene.votes[v] = CastFurnitureVotes(scene.views[v], *var.model,
                                                        static_cast<int>(v), p.voting);
                }
            } else {
                scene.votes = base_votes;
            }
            const auto det =
                DetectFurniture(scene, {}, *var.model, var.verify ? &context : nullptr, p);
            merged[var.name].push_back(
                Frame(det, VisibleTruth(room, all, model, o.min_visible), var.verify, group));
            if (primary && dump.is_open()) {
                for (const auto* list : {&det.detections, &det.rejected}) {
                    for (const auto& d : *list) {
                        if (!d.fitted) continue;
                        bool right = false;
                        for (const auto& f : room.room.furniture) {
                            right = right ||
                                    (f.category == d.category &&
                                     (f.T_world_object.translation().head<2>() - d.centre).norm() <
                                         f.width / 2);
                        }
                        dump << r << '\t' << d.category << '\t' << (right ? 1 : 0) << '\t'
                             << (d.accepted ? "accepted" : d.rejection) << '\t' << d.confidence
                             << '\t' << d.centre.x() << '\t' << d.centre.y() << '\t'
                             << model.cads()[static_cast<std::size_t>(d.fit.cad)].id;
                        for (float x : FurnitureVerifierFeatures(d, model)) dump << '\t' << x;
                        dump << '\n';
                    }
                }
            }
            if (primary) {
                // Why true hypotheses (right class, near a true piece) were rejected.
                for (const auto* list : {&det.detections, &det.rejected}) {
                    for (const auto& d : *list) {
                        if ((var.learned ? d.hypothesis.found : d.score) < 0.3f) continue;
                        for (const auto& f : room.room.furniture) {
                            if (f.category != d.category ||
                                (f.T_world_object.translation().head<2>() - d.hypothesis.centre)
                                        .norm() >= f.width / 2) {
                                continue;
                            }
                            ++fates[d.category][d.accepted ? "accepted" : d.rejection];
                            break;
                        }
                    }
                }
            }
            if (primary &&
                o.draw < 0) {  // per piece: its votes, nearest hypothesis and nearest fits
                std::map<std::uint32_t, int> returns;  // per piece, in all scans
                for (const auto& scan : room.scans) {
                    for (std::uint32_t l : scan.labels) ++returns[l];
                }
                // The maxima of every class's merged vote space at any score, without the
                // footprint test: where the votes alone would put hypotheses.
                std::vector<FurnitureVote> room_votes;
                for (const auto& vs : scene.votes)
                    room_votes.insert(room_votes.end(), vs.begin(), vs.end());
                FurnitureSelectionParams sp = p.selection;
                sp.threshold_scale = 0.0f;
                sp.hull_consistency = false;
                const auto maxima = SelectFurnitureHypotheses(
                    room_votes, static_cast<int>(scene.votes.size()), model, sp);
                for (const auto& f : room.room.furniture) {
                    const Eigen::Vector2f fc2 = f.T_world_object.translation().head<2>();
                    // Nearest to the piece: the fit of its class (by the detection's centre),
                    // the hypothesis of its class (by the votes' centre) and the fit of any
                    // class, for pieces found under another name.
                    float best = 1e9f, score = 0.0f, hd = 1e9f, hfit = 1e9f, any = 1e9f;
                    std::string fate, hfate, any_cls, any_fate;
                    const FurnitureDetection* nearest = nullptr;
                    for (const auto* list : {&det.detections, &det.rejected}) {
                        for (const auto& d : *list) {
                            const char* why = d.accepted ? "ok" : d.rejection.c_str();
                            const float dist = (fc2 - d.centre).norm();
                            if (dist < any) any = dist, any_cls = d.category, any_fate = why;
                            if (d.category != f.category) continue;
                            if (dist < best)
                                best = dist, score = d.hypothesis.normalized, fate = why,
                                nearest = &d;
                            const float h = (d.hypothesis.centre - fc2).norm();
                            if (h < hd) hd = h, hfit = dist, hfate = why;
                        }
                    }
                    // The nearest fit's yaw error (a full turn), whether it was turned away from
                    // a wall, the nearest wall the scans saw from the piece's centre, the fitted
                    // model's size and the piece's box.
                    std::string pose;
                    if (nearest != nullptr && nearest->fitted) {
                        float wall = 1e9f;
                        for (const auto& ws : scene.walls) {
                            for (const auto& w : ws) {
                                const float dw = w.Distance(fc2);
                                if (std::isfinite(dw)) wall = std::min(wall, std::abs(dw));
                            }
                        }
                        const auto& cb = nearest->box;
                        const Eigen::Vector3f me =
                            model.cads()[static_cast<std::size_t>(nearest->fit.cad)].extent;
                        pose = fmt::format(
                            " yaw {:.0f} turned {} wall {:.2f} m depth {:.2f} room {} at {:.2f} "
                            "{:.2f} | cad {:.2f}x{:.2f}x{:.2f} box x {:.2f} {:.2f} y {:.2f} "
                            "{:.2f} fitc {:.2f} {:.2f}",
                            eval::YawError(nearest->fit.yaw, f.yaw, false),
                            nearest->fit.turned ? 1 : 0, wall, std::min(f.extent.x(), f.extent.y()),
                            r, fc2.x(), fc2.y(), me.x(), me.y(), me.z(), cb.min().x(), cb.max().x(),
                            cb.min().y(), cb.max().y(),
                            nearest->fit.T_world_model.translation().x(),
                            nearest->fit.T_world_model.translation().y());
                    }
                    // The class's merged votes in a window of the class width at the piece's
                    // centre (over the class threshold), and the nearest maximum of them.
                    const int ci = model.ClassIndex(f.category);
                    const auto& fc = model.classes()[static_cast<std::size_t>(ci)];
                    double at_piece = 0.0;
                    for (const auto& v : room_votes) {
                        if (v.cls == ci &&
                            (v.x.head<2>() - fc2).cwiseAbs().maxCoeff() <= fc.width / 2)
                            at_piece += v.weight;
                    }
                    if (fc.threshold > 0.0f)
                        at_piece /= static_cast<double>(scene.votes.size()) * fc.threshold;
                    float raw = 1e9f, raw_score = 0.0f;
                    for (const auto& h : maxima) {
                        const float dist = (h.centre - fc2).norm();
                        if (h.cls == ci && dist < raw) raw = dist, raw_score = h.normalized;
                    }
                    std::fprintf(stderr,
                                 "NEAREST %-9s w %.2f l %.2f returns %d: %.2f m score %.2f %s | "
                                 "any %.2f m %s %s | votes %.2f peak %.2f m %.2f | hypothesis "
                                 "%.2f m fit %.2f m %s |%s\n",
                                 f.category.c_str(), f.width, std::max(f.extent.x(), f.extent.y()),
                                 returns[f.label], best, score, fate.c_str(), any, any_cls.c_str(),
                                 any_fate.c_str(), at_piece, raw, raw_score, hd, hfit,
                                 hfate.c_str(), pose.c_str());
                }
            }
            if (primary && r < o.draw) {
                eval::DrawRoom(fmt::format("{}/room_{:02}.png", o.out, r), room, scene, det, model);
                ListRoom(r, room, det, model);
            }
            if (primary) {
                sel_ms += det.selection_ms, fit_ms += det.fit_ms, ++n_sel;
                for (const auto* list : {&det.detections, &det.rejected}) {
                    for (const auto& d : *list) {
                        if (d.fitted || d.fit.iterations > 0)
                            fit_times.push_back(d.fit.ms), ++n_fits;
                    }
                }
            }
            if (!o.single) continue;
            for (int v : all) {
                const auto dv =
                    DetectFurniture(scene, {v}, *var.model, var.verify ? &context : nullptr, p);
                single[var.name].push_back(
                    Frame(dv, VisibleTruth(room, {v}, model, o.min_visible), var.verify, group));
            }
        }
        progress.Advance();
    }
    progress.Finish();
    if (InterruptRequested()) return 130;

    // Report.
    const int table = model.ClassIndex("table");
    json report = {{"set", o.set},     {"rooms", o.rooms},          {"first_seed", first_seed},
                   {"heads", o.heads}, {"procedural_share", share}, {"sensor", o.sensor},
                   {"model", o.model}};
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
            // The operating point: the class thresholds of the votes, or, with the learned
            // verifier, every accepted fit (their scores are confidences above min_confidence).
            const float op = var.learned ? 0.0f : 1.0f;
            eval::MatchCounts m;
            for (const auto& f : frames) m.Add(eval::MatchFrame(f, op, -1, table));
            const auto curve = var.learned ? eval::ExactCurve(frames, table)
                                           : eval::Curve(frames, o.floor_cut, 8.0f, 40, table);
            const std::string name = var.name + (is_merged ? " merged" : " single");
            const double rap = eval::RecallAtPrecision(curve, 0.9);
            std::printf("%-24s %7.3f %7.3f %7.3f %9zu %6zu %6zu %6zu\n", name.c_str(),
                        m.Precision(), m.Recall(), rap, frames.size(), m.tp, m.fp, m.fn);
            json entry = {{"precision", m.Precision()},
                          {"recall", m.Recall()},
                          {"recall_at_p90", rap},
                          {"tp", m.tp},
                          {"fp", m.fp},
                          {"fn", m.fn},
                          {"frames", frames.size()}};
            if (!m.yaw_errors.empty()) {
                entry["yaw_median_deg"] = eval::Percentile(m.yaw_errors, 0.5f);
                entry["yaw_p90_deg"] = eval::Percentile(m.yaw_errors, 0.9f);
                std::printf(
                    "%-24s yaw error median %.1f deg, 90th percentile %.1f deg (%zu fits)\n", "",
                    eval::Percentile(m.yaw_errors, 0.5f), eval::Percentile(m.yaw_errors, 0.9f),
                    m.yaw_errors.size());
            }
            // Per class and per room type at the operating point; average precision per class and
            // the cut with the best F1 (as a threshold: cut times the class threshold).
            double map = 0.0;
            for (std::size_t c = 0; c < model.classes().size(); ++c) {
                eval::MatchCounts mc;
                for (const auto& f : frames)
                    mc.Add(eval::MatchFrame(f, op, static_cast<int>(c), table));
                float cut = 1.0f;
                double f1 = 0.0;
                const double ap = eval::AveragePrecision(frames, static_cast<int>(c), &cut, &f1);
                map += ap / static_cast<double>(model.classes().size());
                entry["classes"][model.classes()[c].name] = {
                    {"precision", mc.Precision()},
                    {"recall", mc.Recall()},
                    {"tp", mc.tp},
                    {"fp", mc.fp},
                    {"fn", mc.fn},
                    {"ap", ap},
                    {"best_f1", f1},
                    {"best_f1_threshold", var.learned ? cut : cut * model.classes()[c].threshold}};
                if (!mc.yaw_errors.empty()) {
                    // Fits the wrong way round: more than 90 degrees off.
                    std::size_t over = 0;
                    for (float e : mc.yaw_errors) over += e > 90.0f ? 1 : 0;
                    auto& jc = entry["classes"][model.classes()[c].name];
                    jc["yaw_median_deg"] = eval::Percentile(mc.yaw_errors, 0.5f);
                    jc["yaw_p90_deg"] = eval::Percentile(mc.yaw_errors, 0.9f);
                    jc["yaw_over_90"] = over;
                    jc["yaw_fits"] = mc.yaw_errors.size();
                }
            }
            entry["map"] = map;
            for (const char* g : {"office", "seminar", "kitchen"}) {
                eval::MatchCounts mg;
                for (const auto& f : frames) {
                    if (f.group == g) mg.Add(eval::MatchFrame(f, op, -1, table));
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
        std::string line =
            fmt::format("{:<24} mAP {:.3f}; per class P/R, AP, best-F1 threshold:", name,
                        entry["map"].get<double>());
        for (const auto& [c, v] : entry["classes"].items()) {
            line += fmt::format(" {} {:.2f}/{:.2f} {:.2f} {:.2f}", c, v["precision"].get<double>(),
                                v["recall"].get<double>(), v["ap"].get<double>(),
                                v["best_f1_threshold"].get<double>());
        }
        line += "  per room type:";
        for (const auto& [g, v] : entry["room_types"].items()) {
            line += fmt::format(" {} {:.2f}/{:.2f}", g, v["precision"].get<double>(),
                                v["recall"].get<double>());
        }
        std::printf("%s\n", line.c_str());
    }
    for (const auto& [c, m] : fates) {
        std::string line = "true hypotheses of " + c + ":";
        for (const auto& [why, n] : m) line += fmt::format(" {} {}", why, n);
        std::printf("%s\n", line.c_str());
    }
    const double per_view = n_views ? 1.0 / n_views : 0.0;
    report["timings_ms"] = {
        {"parts_per_view", parts_ms * per_view},
        {"votes_per_view", votes_ms * per_view},
        {"occupancy_per_view", occ_ms * per_view},
        {"selection_per_room", n_sel ? sel_ms / n_sel : 0.0},
        {"fit_median",
         eval::Percentile(std::vector<float>(fit_times.begin(), fit_times.end()), 0.5f)},
        {"fits", n_fits}};
    std::printf(
        "timings per view: parts %.0f ms, votes %.0f ms, occupancy %.0f ms; selection %.1f ms per "
        "room; fit median %.0f ms (%zu fits)\n",
        parts_ms * per_view, votes_ms * per_view, occ_ms * per_view, n_sel ? sel_ms / n_sel : 0.0,
        report["timings_ms"]["fit_median"].get<double>(), n_fits);
    const std::string title = fmt::format("furniture detection, {} rooms ({} set, seeds {}-{})",
                                          o.rooms, o.set, first_seed, first_seed + o.rooms - 1);
    eval::WriteCurvesSvg((std::filesystem::path(o.out) / "curves.svg").string(), title, curves);
    const std::string text = report.dump(1);
    io::WriteFileAtomically(std::filesystem::path(o.out) / "report.json",
                            [&](std::ostream& os) { os << text << '\n'; });
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    Options o;
    CLI::App app{"furniture_eval: furniture detection on held-out simulated rooms"};
    app.add_option("--furniture", o.furniture, "furniture folder (labels.csv)")
        ->capture_default_str();
    app.add_option("--kitchen", o.kitchen, "kitchen library folder")->capture_default_str();
    app.add_option("--model", o.model, "model file: loaded when present, else trained and written")
        ->capture_default_str();
    app.add_flag("--retrain", o.retrain, "train even when --model exists");
    app.add_option("--set", o.set,
                   "test (held-out library pieces), validation (fresh procedural pieces) or "
                   "library (the tune half's pieces of --library-fold, left out of training)")
        ->check(CLI::IsMember({"test", "validation", "library"}))
        ->capture_default_str();
    app.add_option("--library-fold", o.library_fold,
                   "--set library: the fold (0 or 1) of the tune half's pieces held out")
        ->check(CLI::Range(0, 1))
        ->capture_default_str();
    app.add_option("--verifier-library-rooms", o.verifier_library_rooms,
                   "verifier rooms of the training library's pieces, fitted by stand-in models "
                   "that never saw them (default: the training's)")
        ->check(CLI::NonNegativeNumber);
    app.add_flag("--verifier-piece-labels,!--no-verifier-piece-labels", o.verifier_piece_labels,
                 "verifier rows labelled by the piece's box, not the fitted model "
                 "(FurnitureTrainingOptions::verifier_piece_labels)");
    app.add_option("--rooms", o.rooms, "rooms (office, seminar, kitchen in turn)")
        ->capture_default_str();
    app.add_option("--seed", o.seed,
                   "first room seed (default 2000 test, 1000 validation, 1500 / 1600 library "
                   "folds 0 / 1)");
    app.add_option("--procedural-share", o.procedural_share,
                   "share of procedural pieces in the rooms (default 0 test, 1 validation)");
    app.add_option("--heads", o.heads, "head positions per room")->capture_default_str();
    app.add_option("--sensor", o.sensor, "laser or kinect")->capture_default_str();
    app.add_option("--out", o.out, "folder for report.json and curves.svg")->capture_default_str();
    app.add_option("--verifier-rows", o.verifier_rows,
                   "with --retrain-verifier: the verifier's rows are read from this file when it "
                   "exists, else collected and written to it");
    app.add_flag("--other-classes", o.other_classes,
                 "also fit every other class where a hypothesis reaches its class threshold");
    app.add_option("--floor", o.floor_cut, "lowest normalised score kept (curves start there)")
        ->capture_default_str();
    app.add_option("--min-visible", o.min_visible, "returns that make an object visible in a view")
        ->capture_default_str();
    app.add_option("--threshold", o.thresholds,
                   "class threshold override CLASS=VALUE (repeatable)");
    app.add_option("--window-scale", o.window_scale, "search window in class widths")
        ->capture_default_str();
    app.add_option("--min-coverage", o.min_coverage, "CAD fit coverage needed")
        ->capture_default_str();
    app.add_option("--max-free-share", o.max_free_share, "share of a model allowed in free space")
        ->capture_default_str();
    app.add_option("--min-part-share", o.min_part_share, "support share of a part for the fit")
        ->capture_default_str();
    app.add_option("--dump-fits", o.dump_fits,
                   "write every fit of the full method (merged views) with its verifier features "
                   "as TSV");
    app.add_option("--draw", o.draw, "bird's-eye PNGs and listings of the first N rooms");
    app.add_option("--normalization", o.normalization, "per-class, per-word or balanced")
        ->capture_default_str();
    app.add_option("--frame", o.frame,
                   "part frame of the shape vectors when training: bearing or part")
        ->capture_default_str();
    app.add_flag("--cross-class", o.cross_class,
                 "hypotheses of different classes exclude each other");
    app.add_flag("!--no-fit-cross-class", o.fit_cross_class,
                 "overlapping fitted footprints of different classes may both stay");
    app.add_flag("!--cross-class-footprints", o.cross_class_surfaces,
                 "fits of different classes overlap by their footprints, not their surfaces");
    app.add_option("--max-overlap", o.max_overlap,
                   "fitted footprints overlapping more are one piece")
        ->capture_default_str();
    app.add_option("--max-height-error", o.max_height_error, "vote height gate [m]")
        ->capture_default_str();
    app.add_option("--support-margin", o.support_margin,
                   "fit support radius beyond half the class length [m]")
        ->capture_default_str();
    app.add_option("--words", o.words,
                   "rebuild the vocabulary with this many words (0: the model's)");
    app.add_option("--activations", o.activations, "words a part activates")->capture_default_str();
    app.add_option("--probe", o.probe,
                   "only: N single fresh procedural pieces per class, one view each");
    app.add_flag("!--no-class-by-fit", o.class_by_fit, "overlapping fits: the strongest votes win");
    app.add_flag("!--no-learned", o.learned, "without the model's learned verifier");
    app.add_option("--fit-scale", o.fit_scale,
                   "CAD fit: stretch per axis within 1 -+ this (FurnitureFitParams::max_scale; "
                   "the verifier rooms fit with it too)");
    app.add_option("--fit-scale-steps", o.fit_scale_steps,
                   "CAD fit: stretches tried per side of 1 (FurnitureFitParams::scale_steps)");
    app.add_flag(
        "!--no-back-to-wall", o.back_to_wall,
        "CAD fit: leave fits facing a wall as they are (FurnitureFitParams::back_to_wall)");
    app.add_flag("!--no-piece-extent", o.piece_extent,
                 "report the fitted model's box and centre, not grown to the scan's parts of the "
                 "piece (FurniturePieceParams::grow)");
    app.add_option("--piece-member-share", o.piece_member_share,
                   "share of a part's points within the fitted model's grown footprint for the "
                   "part to count as the piece's (FurniturePieceParams::member_share)")
        ->capture_default_str();
    app.add_flag("!--no-piece-taken", o.piece_taken,
                 "the piece's box does not keep out of the more likely pieces' space");
    app.add_flag("!--no-piece-walls", o.piece_walls,
                 "the piece's box does not keep out of the walls' bands");
    app.add_flag("!--no-piece-shrink", o.piece_shrink,
                 "do not shrink the piece's box through observed free space "
                 "(FurniturePieceParams::shrink)");
    app.add_option("--piece-free-share", o.piece_free_share,
                   "share of a slice's samples in free space to cut it off the piece's box");
    app.add_option("--fit-models", o.fit_models,
                   "CAD fit: the best poses of this many models finished per hypothesis "
                   "(FurnitureDetectionParams::fit_models)")
        ->check(CLI::PositiveNumber);
    app.add_option("--verifier-fit-models", o.verifier_fit_models,
                   "training: CAD models finished per hypothesis in the verifier's rooms "
                   "(FurnitureTrainingOptions::verifier_fit_models)")
        ->check(CLI::PositiveNumber);
    app.add_option("--max-offset", o.max_offset,
                   "CAD fit: how far the model's centre may lie from the hypothesis, in class "
                   "widths (FurnitureFitParams::max_offset)");
    app.add_option("--flip-tolerance", o.flip_tolerance,
                   "CAD fit: how much worse a fit turned away from a wall may score "
                   "(FurnitureFitParams::flip_tolerance)");
    app.add_option("--min-confidence", o.min_confidence, "learned verifier: confidence kept")
        ->capture_default_str();
    app.add_option("--min-confidence-single", o.min_confidence_single,
                   "learned verifier: confidence kept, single scans")
        ->capture_default_str();
    app.add_flag("--retrain-verifier", o.retrain_verifier,
                 "train the learned verifier of the loaded model again (written to --model)");
    app.add_flag("!--no-learned-tests", o.learned_tests,
                 "a fit must pass the coverage and free-space tests and the learned verifier");
    app.add_option("--verifier-rooms", o.verifier_rooms,
                   "rooms the verifier is trained on (default: the training's)");
    app.add_option("--verifier-spec", o.verifier_spec,
                   "classifier of the verifier (default: the training's)");
    app.add_option("--train-procedural", o.train_procedural, "procedural training pieces per class")
        ->capture_default_str();
    app.add_flag("!--no-variants", o.variants, "only the full method");
    app.add_flag("!--no-single", o.single, "merged views only");
    app.add_option("-j,--threads", o.threads, "threads (0 = all cores)")->capture_default_str();
    if (auto code = multicue::eval::ParseDriverOptions(app, "furniture_eval",
                                                       [&] { app.parse(argc, argv); })) {
        return *code;
    }
    try {
        return Run(o);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "furniture_eval: %s\n", e.what());
        return 1;
    }
}

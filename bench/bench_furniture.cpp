/// \file bench_furniture: furniture recognition (thesis section 4.2) beside the thesis's own
/// timings, on simulated rooms scanned by the tilting laser from three head positions.
///
///   furniture/train_view              one training view: a laser view of a piece simulated and
///                                     segmented into parts (thesis: 4.67 s per view)
///   furniture/<room>/prepare          per sweep: smoothing, parts and features (thesis: 7.12 s
///                                     per scan), votes, occupancy map
///   furniture/<room>/detect           votes merged, hypotheses selected (thesis: 0.20-0.24 s per
///                                     room), CAD models fitted and verified (thesis: about 15 s
///                                     per good fit)
/// Counters give each stage's time per sweep, per room or per fit and, `x_thesis`, how many times
/// faster than the thesis that is (its figures: one core of a dual-core laptop, Matlab for the
/// selection). The model is trained on procedural pieces only (no data needed) before the runs;
/// the rooms hold procedural pieces the model never saw (other seeds).
///
///   build/bench/bench_furniture [--benchmark_filter=...]

#include <chrono>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include "multicue/mapping/furniture_detection.hpp"
#include "multicue/mapping/furniture_fit.hpp"
#include "multicue/sim/furniture_scenes.hpp"
#include "multicue/training/furniture_training.hpp"

namespace {

using namespace multicue;

constexpr double kThesisTrainView = 4670.0;  // [ms] per simulated training view
constexpr double kThesisPerScan = 7120.0;    // [ms] smoothing, segmenting, features per scan
constexpr double kThesisSelection = 200.0;   // [ms] per room (office; 240 for the seminar room)
constexpr double kThesisPerFit = 15000.0;    // [ms] per good fit

training::FurnitureTrainingOptions TrainingOptions() {
    training::FurnitureTrainingOptions o;
    o.furniture.clear();
    o.kitchen.clear();
    o.procedural_per_class = 4;
    o.num_threads = 1;
    o.verifier_rooms = 6;  // a verifier, so that its features and predictions are timed
    return o;
}

const FurnitureModel& Model() {
    static const FurnitureModel model = [] {
        const auto o = TrainingOptions();
        FurnitureModel m;
        if (!training::TrainFurnitureModel(training::FurnitureTrainingPieces(o), o, m, nullptr)) {
            throw std::runtime_error("training interrupted");
        }
        return m;
    }();
    return model;
}

FurnitureDetectionParams DetectionParams() {
    FurnitureDetectionParams p;
    p.num_threads = 1;
    return p;
}

struct Room {
    training::ScannedFurnitureRoom scanned;
    std::vector<FurnitureView> views;
};

const Room& GetRoom(sim::RoomType type) {
    static std::map<sim::RoomType, std::unique_ptr<Room>> rooms;
    auto& room = rooms[type];
    if (!room) {
        room = std::make_unique<Room>();
        sim::FurnitureRoomParams rp;
        rp.type = type;
        const sim::FurnitureSource procedural({}, 1.0f);
        room->scanned = training::SimulateFurnitureRoom(rp, procedural, 3, TrainingOptions(),
                                                        2000 + static_cast<int>(type));
        for (std::size_t v = 0; v < room->scanned.scans.size(); ++v) {
            room->views.push_back({&room->scanned.scans[v], room->scanned.T_world_sensor[v]});
        }
    }
    return *room;
}

void TrainView(benchmark::State& state) {
    const auto o = TrainingOptions();
    const auto pieces = training::FurnitureTrainingPieces(o);
    const int views = o.views.views;
    double ms = 0.0;
    for (auto _ : state) {
        const auto start = std::chrono::steady_clock::now();
        const auto parts = training::FurnitureTrainingParts(pieces.front(), 0, 0, o);
        benchmark::DoNotOptimize(parts);
        ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
                 .count() /
             views;
    }
    state.counters["ms_per_view"] = ms;
    state.counters["x_thesis"] = kThesisTrainView / ms;
}

void Prepare(benchmark::State& state, sim::RoomType type) {
    const FurnitureModel& model = Model();
    const Room& room = GetRoom(type);
    FurnitureScene scene;
    for (auto _ : state) {
        scene = PrepareFurnitureScene(room.views, model, DetectionParams());
        benchmark::DoNotOptimize(scene);
    }
    const double sweeps = static_cast<double>(room.views.size());
    state.counters["parts_ms_per_sweep"] = scene.parts_ms / sweeps;
    state.counters["votes_ms_per_sweep"] = scene.votes_ms / sweeps;
    state.counters["occupancy_ms_per_sweep"] = scene.occupancy_ms / sweeps;
    state.counters["x_thesis"] = kThesisPerScan / (scene.parts_ms / sweeps);
}

void Detect(benchmark::State& state, sim::RoomType type) {
    const FurnitureModel& model = Model();
    const FurnitureDetectionParams params = DetectionParams();
    const FurnitureFitContext context(model, params.fit);
    const Room& room = GetRoom(type);
    const FurnitureScene scene = PrepareFurnitureScene(room.views, model, params);
    FurnitureDetectionResult r;
    for (auto _ : state) {
        r = DetectFurniture(scene, {}, model, &context, params);
        benchmark::DoNotOptimize(r);
    }
    // A fit is the search of one hypothesis with its finished models (fit_models of them), as
    // the thesis's time per fit is one hypothesis's.
    const std::size_t fits = r.fitted_hypotheses;
    const double per_fit = fits > 0 ? r.fit_ms / static_cast<double>(fits) : 0.0;
    state.counters["selection_ms"] = r.selection_ms;
    state.counters["fits"] = static_cast<double>(fits);
    state.counters["ms_per_fit"] = per_fit;
    state.counters["detections"] = static_cast<double>(r.detections.size());
    state.counters["x_thesis_selection"] = kThesisSelection / r.selection_ms;
    if (per_fit > 0.0) state.counters["x_thesis_fit"] = kThesisPerFit / per_fit;
}

void RegisterAll() {
    benchmark::RegisterBenchmark("furniture/train_view", TrainView)
        ->Unit(benchmark::kMillisecond)
        ->Iterations(1);
    for (const auto type :
         {sim::RoomType::kOffice, sim::RoomType::kSeminar, sim::RoomType::kKitchen}) {
        const std::string name = sim::RoomTypeName(type);
        benchmark::RegisterBenchmark(("furniture/" + name + "/prepare").c_str(),
                                     [type](benchmark::State& s) { Prepare(s, type); })
            ->Unit(benchmark::kMillisecond)
            ->Iterations(3);
        benchmark::RegisterBenchmark(("furniture/" + name + "/detect").c_str(),
                                     [type](benchmark::State& s) { Detect(s, type); })
            ->Unit(benchmark::kMillisecond)
            ->Iterations(3);
    }
}

}  // namespace

int main(int argc, char** argv) {
    benchmark::Initialize(&argc, argv);
    RegisterAll();
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
}

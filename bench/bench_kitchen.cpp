/// \file bench_kitchen: kitchen maps against the table-top pipeline, in one run.
///
/// - perceive/tabletop_kinect: `Perceive` on a simulated 640x480 Kinect frame of a table with ten
///   objects (the frame of bench_sim), the reference;
/// - map_kitchen/kinect: `MapKitchen` on a simulated 640x480 Kinect frame of a kitchen (points to
///   semantic labels, fronts, joints and container types);
/// - map_kitchen/laser: `MapKitchen` on a full tilting-laser sweep of the same kitchen (1081 beams
///   x 201 tilt steps).
///
/// After the run it prints the ratios map_kitchen / perceive of the median real times of the
/// same thread count (docs/kitchens.md: the goals are 1.5 for the Kinect frame and 10 for the
/// sweep). The kitchen needs the kitchen models ($MULTICUE_DATA/meshes/kitchen; the benchmarks
/// are skipped without them).
///
///   build/bench/bench_kitchen [--benchmark_repetitions=5]

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include "multicue/mapping/kitchen_map.hpp"
#include "multicue/sim/kitchen_scene.hpp"
#include "multicue/sim/scene_gen.hpp"
#include "multicue/sim/sensors.hpp"
#include "multicue/system/perceive.hpp"

namespace {

using namespace multicue;

std::filesystem::path DataDir() {
    const char* env = std::getenv("MULTICUE_DATA");
    return env != nullptr ? std::filesystem::path(env)
                          : std::filesystem::path(MULTICUE_DEFAULT_DATA_DIR);
}

const PointCloud& TabletopFrame() {
    static const PointCloud frame = [] {
        sim::TableSceneParams p;
        p.min_objects = p.max_objects = 10;
        p.clutter = 0.3f;
        const sim::Scene scene = sim::MakeTableScene(p, 3);
        const auto pose = sim::TableViewpoints(scene, 1, {}, 3)[0];
        return sim::ScanKinect(scene, pose, sim::KinectParams{}, 1);
    }();
    return frame;
}

/// The Kinect frame and laser sweep of one test kitchen, or nothing without the models.
struct KitchenFrames {
    PointCloud kinect, laser;
};
const std::optional<KitchenFrames>& Kitchen() {
    static const std::optional<KitchenFrames> frames = []() -> std::optional<KitchenFrames> {
        const auto models = DataDir() / "meshes" / "kitchen";
        if (!std::filesystem::is_directory(models)) return std::nullopt;
        const auto lib =
            sim::SelectKitchenSplit(sim::ReadKitchenLibrary(models), sim::MeshSplit::kTest);
        sim::KitchenModelCache cache;
        const sim::KitchenScene k = sim::MakeKitchenScene(lib, cache, {}, 3);
        const sim::RayCaster caster(k.scene);
        KitchenFrames f;
        sim::KinectParams kp;
        kp.shading = 0.3f;
        const auto camera = sim::KitchenCameraPoses(k, 1, 3)[0];
        f.kinect = sim::ScanKinect(caster, camera, kp, 1);
        sim::ScanToWorld(f.kinect, camera);
        sim::LaserParams lp;
        lp.tilt_min_deg = -40.0f;
        lp.tilt_max_deg = 60.0f;
        const auto head = sim::KitchenLaserPoses(k, 1, 3)[0];
        f.laser = sim::ScanLaser(caster, head, lp, 1);
        sim::ScanToWorld(f.laser, head);
        return f;
    }();
    return frames;
}

void BM_PerceiveTabletop(benchmark::State& state) {
    const PointCloud& frame = TabletopFrame();
    PerceiveParams p;
    p.num_threads = static_cast<int>(state.range(0));
    for (auto _ : state) {
        const PerceiveResult r = Perceive(frame, p);
        benchmark::DoNotOptimize(r.objects.data());
    }
}

void BM_MapKitchen(benchmark::State& state, bool laser) {
    const auto& k = Kitchen();
    if (!k) {
        state.SkipWithError("no kitchen models (set MULTICUE_DATA)");
        return;
    }
    const PointCloud& scan = laser ? k->laser : k->kinect;
    mapping::MapKitchenParams p = mapping::KitchenParamsFor(
        laser ? mapping::KitchenSensor::kLaser : mapping::KitchenSensor::kKinect);
    p.num_threads = static_cast<int>(state.range(0));
    std::map<std::string, double> stages;
    for (auto _ : state) {
        const mapping::MapKitchenResult r = mapping::MapKitchen({scan}, p);
        for (const auto& [stage, ms] : r.timings) stages[stage] = ms;
        state.counters["fronts"] = static_cast<double>(r.map.fronts.size());
    }
    for (const auto& [stage, ms] : stages) state.counters[stage + "_ms"] = ms;
}

/// Collects the median (or mean of the plain runs) real time of every benchmark for the ratios.
class RatioReporter : public benchmark::ConsoleReporter {
  public:
    void ReportRuns(const std::vector<Run>& runs) override {
        ConsoleReporter::ReportRuns(runs);
        for (const Run& r : runs) {
            if (r.error_occurred) continue;
            const std::string name = r.benchmark_name();
            const bool median = r.run_type == Run::RT_Aggregate && r.aggregate_name == "median";
            if (r.run_type == Run::RT_Aggregate && !median) continue;
            const std::string key = median ? r.run_name.str() : name;
            times_[key].push_back(r.GetAdjustedRealTime());
            if (median) medians_[key] = r.GetAdjustedRealTime();
        }
    }
    double Time(const std::string& key) const {
        if (const auto it = medians_.find(key); it != medians_.end()) return it->second;
        const auto it = times_.find(key);
        if (it == times_.end() || it->second.empty()) return -1.0;
        std::vector<double> v = it->second;
        std::sort(v.begin(), v.end());
        return v[v.size() / 2];
    }

  private:
    std::map<std::string, std::vector<double>> times_;
    std::map<std::string, double> medians_;
};

}  // namespace

int main(int argc, char** argv) {
    for (const int threads : {1, 2}) {
        benchmark::RegisterBenchmark("perceive/tabletop_kinect", BM_PerceiveTabletop)
            ->Arg(threads)
            ->ArgName("threads")
            ->Unit(benchmark::kMillisecond)
            ->UseRealTime();
        benchmark::RegisterBenchmark("map_kitchen/kinect", BM_MapKitchen, false)
            ->Arg(threads)
            ->ArgName("threads")
            ->Unit(benchmark::kMillisecond)
            ->UseRealTime();
        benchmark::RegisterBenchmark("map_kitchen/laser", BM_MapKitchen, true)
            ->Arg(threads)
            ->ArgName("threads")
            ->Unit(benchmark::kMillisecond)
            ->UseRealTime();
    }
    benchmark::Initialize(&argc, argv);
    if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
    RatioReporter reporter;
    benchmark::RunSpecifiedBenchmarks(&reporter);
    benchmark::Shutdown();
    std::printf("\nratios map_kitchen / perceive on a table-top frame (median real time):\n");
    for (const int threads : {1, 2}) {
        const std::string t = "/threads:" + std::to_string(threads) + "/real_time";
        const double ref = reporter.Time("perceive/tabletop_kinect" + t);
        for (const char* what : {"kinect", "laser"}) {
            const double time = reporter.Time(std::string("map_kitchen/") + what + t);
            if (ref > 0 && time > 0) {
                std::printf("  %-6s frame, %d thread(s): %.2f  (%.1f ms vs %.1f ms)\n", what,
                            threads, time / ref, time, ref);
            }
        }
    }
    return 0;
}

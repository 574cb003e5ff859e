/// \file bench_sim: the scan simulator's hot paths. One 640x480 Kinect frame of a 10-object table
/// scene (single-threaded), and batches of single-object turntable training views.

#include <benchmark/benchmark.h>

#include "multicue/sim/procedural.hpp"
#include "multicue/sim/scene_gen.hpp"
#include "multicue/sim/sensors.hpp"

namespace {

using namespace multicue::sim;

Scene TenObjectScene() {
    TableSceneParams p;
    p.min_objects = p.max_objects = 10;
    p.clutter = 0.3f;
    return MakeTableScene(p, 3);
}

void BM_KinectFrameTenObjects(benchmark::State& state) {
    const Scene scene = TenObjectScene();
    const RayCaster caster(scene);
    const auto pose = TableViewpoints(scene, 1, {}, 3)[0];
    KinectParams p;
    p.num_threads = static_cast<int>(state.range(0));
    std::uint64_t seed = 0;
    for (auto _ : state) {
        auto cloud = ScanKinect(caster, pose, p, ++seed);
        benchmark::DoNotOptimize(cloud.points.data());
    }
    state.counters["objects"] = static_cast<double>(scene.NumObjects());
}
BENCHMARK(BM_KinectFrameTenObjects)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);

void BM_KinectBuildAndFrame(benchmark::State& state) {
    const Scene scene = TenObjectScene();
    const auto pose = TableViewpoints(scene, 1, {}, 3)[0];
    KinectParams p;
    p.num_threads = 1;
    for (auto _ : state) {
        auto cloud = ScanKinect(scene, pose, p, 1);
        benchmark::DoNotOptimize(cloud.points.data());
    }
}
BENCHMARK(BM_KinectBuildAndFrame)->Unit(benchmark::kMillisecond);

/// Training views: `range(0)` objects (procedural, every category in turn), 16 turntable views
/// each, full 640x480 Kinect frames, rendered with `range(1)` threads.
void BM_TrainingViews(benchmark::State& state) {
    const auto n_objects = static_cast<std::size_t>(state.range(0));
    KinectParams p;
    p.num_threads = static_cast<int>(state.range(1));
    const TurntableParams tp;
    std::size_t views = 0;
    for (auto _ : state) {
        for (std::size_t i = 0; i < n_objects; ++i) {
            StreamRng rng(5, i);
            auto obj = MakeProceduralObject(TabletopCategories()[i % 6], rng);
            const ObjectModel model{std::make_shared<const PartMesh>(std::move(obj.mesh)),
                                    obj.category, obj.kind, 1.0f};
            const Scene scene = MakeTurntableScene(model, tp, i);
            const RayCaster caster(scene);
            for (const auto& pose : TurntableViews(scene, 16, tp)) {
                auto cloud = ScanKinect(caster, pose, p, ++views);
                benchmark::DoNotOptimize(cloud.points.data());
            }
        }
    }
    state.counters["views_per_s"] =
        benchmark::Counter(static_cast<double>(views), benchmark::Counter::kIsRate);
}
// 63 objects x 16 views = 1,008 views.
BENCHMARK(BM_TrainingViews)
    ->Args({63, 1})
    ->Args({63, 2})
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1);

}  // namespace

BENCHMARK_MAIN();

// The perception executive on a 640x480 table-top frame: identifying everything (enumerate)
// against active search for one known object (find), with the object database filled from an
// earlier view. Database writes are off while timing (learn = false).
//
//   build/bench/bench_executive

#include <filesystem>

#include <benchmark/benchmark.h>
#include <unistd.h>

#include "executive_common.hpp"

namespace {

using namespace multicue;

struct Fixture {
    std::filesystem::path path;
    std::optional<ObjectDatabase> db;
    Frame frame;
    std::string target;

    Fixture() {
        path = std::filesystem::temp_directory_path() /
               ("multicue-bench-executive-" + std::to_string(::getpid()) + ".db");
        std::filesystem::remove(path);
        db = ObjectDatabase::Open(path, DatabaseMode::kCreateOrWrite);
        const auto scene = sim::MakeDemoScene();
        PerceptionExecutive executive(&*db);
        const auto learnt = executive.Run(bench::ViewOfScene(scene, 0.0f, 1.0, 1), Task{});
        // The tallest object is the one looked for.
        float tallest = 0.0f;
        for (const auto& h : learnt.hypotheses) {
            if (h.extents.x() > tallest) {
                tallest = h.extents.x();
                target = std::to_string(h.object_id);
            }
        }
        frame = bench::ViewOfScene(scene, 0.3f, 2.0, 2);
    }
    ~Fixture() {
        db.reset();
        std::error_code ec;
        for (const char* suffix : {"", "-wal", "-shm"}) {
            std::filesystem::remove(path.string() + suffix, ec);
        }
    }
};

Fixture& Shared() {
    static Fixture fixture;
    return fixture;
}

void BM_ExecutiveEnumerate(benchmark::State& state) {
    auto& f = Shared();
    PerceptionExecutive executive(&*f.db);
    Task task;
    task.learn = false;
    for (auto _ : state) benchmark::DoNotOptimize(executive.Run(f.frame, task));
}

void BM_ExecutiveFind(benchmark::State& state) {
    auto& f = Shared();
    PerceptionExecutive executive(&*f.db);
    Task task;
    task.kind = Task::Kind::kFind;
    task.target = f.target;
    task.learn = false;
    bool found = true;
    for (auto _ : state) {
        const auto report = executive.Run(f.frame, task);
        found = found && report.found.has_value();
    }
    if (!found) state.SkipWithError("the sought object was not found");
}

BENCHMARK(BM_ExecutiveEnumerate)->Unit(benchmark::kMillisecond)->MinTime(2.0);
BENCHMARK(BM_ExecutiveFind)->Unit(benchmark::kMillisecond)->MinTime(2.0);

}  // namespace

BENCHMARK_MAIN();

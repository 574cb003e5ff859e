// Wall time of `multicue perceive` on 640x480 mOSD frames, input and output files included:
// read the PCD, run the pipeline, write result.json, labels.pcd and models.ply. Counters give the
// per-stage breakdown (milliseconds per run) of the last run.
//
//   build/bench/bench_perceive [--benchmark_filter=...]      ($MULTICUE_DATA: the data folder)

#include <cstdlib>
#include <filesystem>
#include <map>
#include <string>

#include <benchmark/benchmark.h>
#include <unistd.h>

#include "multicue/io/pcd.hpp"
#include "multicue/system/perceive.hpp"
#include "multicue/system/perceive_output.hpp"

namespace {

std::filesystem::path DataDir() {
    const char* env = std::getenv("MULTICUE_DATA");
    return env != nullptr ? std::filesystem::path(env)
                          : std::filesystem::path(MULTICUE_DEFAULT_DATA_DIR);
}

void BM_Perceive(benchmark::State& state, const std::string& scene) {
    const auto input = DataDir() / "scans" / "mosd-learn" / (scene + ".pcd");
    if (!std::filesystem::exists(input)) {
        state.SkipWithError(("missing " + input.string() + " (set MULTICUE_DATA)").c_str());
        return;
    }
    const auto out = std::filesystem::temp_directory_path() /
                     ("multicue-bench-perceive-" + std::to_string(::getpid()));
    multicue::PerceiveParams params;
    params.num_threads = static_cast<int>(state.range(0));
    std::map<std::string, double> stages;
    for (auto _ : state) {
        const multicue::PointCloud cloud = multicue::io::ReadPcd(input);
        const multicue::PerceiveResult result = multicue::Perceive(cloud, params);
        multicue::WritePerceiveOutputs(out, multicue::PerceiveResultJson(input.string(), result),
                                       multicue::PerceiveLabelsCloud(cloud, result),
                                       multicue::PerceiveModelsMesh(result));
        for (const auto& [stage, ms] : result.timings_ms) stages[stage] = ms;
        state.counters["objects"] = static_cast<double>(result.objects.size());
    }
    for (const auto& [stage, ms] : stages) state.counters[stage + "_ms"] = ms;
    std::error_code ec;
    std::filesystem::remove_all(out, ec);
}

void Register() {
    for (const char* scene : {"learn0", "learn20", "learn33", "learn38"}) {
        benchmark::RegisterBenchmark((std::string("perceive/") + scene).c_str(), BM_Perceive,
                                     std::string(scene))
            ->Arg(1)
            ->Arg(2)
            ->ArgName("threads")
            ->Unit(benchmark::kMillisecond)
            ->UseRealTime()
            ->MinTime(2.0);
    }
}

}  // namespace

int main(int argc, char** argv) {
    Register();
    benchmark::Initialize(&argc, argv);
    if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
}

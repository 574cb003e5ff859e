#include "bench_common.hpp"

#include <algorithm>
#include <cstdlib>
#include <exception>
#include <map>
#include <memory>
#include <string>
#include <system_error>
#include <thread>
#include <utility>

#include <tbb/global_control.h>

#include "heap_tracker.hpp"

namespace multicue::bench {

std::string_view InputName(Input input) {
    switch (input) {
        case Input::kMosd:
            return "mosd";
        case Input::kTableScene:
            return "table";
    }
    return "unknown";
}

std::filesystem::path InputPath(Input input) {
    const char* env = std::getenv("MULTICUE_DATA");
    const std::filesystem::path root = env != nullptr && *env != '\0'
                                           ? std::filesystem::path(env)
                                           : std::filesystem::path(MULTICUE_DEFAULT_DATA_DIR);
    switch (input) {
        case Input::kMosd:
            // A 640x480 organized frame of the Object Segmentation Database (learn set, scene 0).
            return root / "scans" / "mosd-learn" / "learn0.pcd";
        case Input::kTableScene:
            // PCL's tutorial scene: a 640x480 organized stereo frame of a table with a mug.
            return root / "scans" / "table_scene_mug_stereo_textured.pcd";
    }
    return root;
}

bool CheckInputExists(benchmark::State& state, Input input) {
    const std::filesystem::path path = InputPath(input);
    std::error_code ec;
    if (std::filesystem::is_regular_file(path, ec)) return true;
    const std::string message = "input file " + path.string() +
                                " not found; set MULTICUE_DATA to the folder that holds "
                                "scans/mosd-learn/learn0.pcd and "
                                "scans/table_scene_mug_stereo_textured.pcd";
    state.SkipWithError(message.c_str());
    return false;
}

std::vector<int> ThreadCounts() {
    const int all = std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
    std::vector<int> counts = {1, 2, all};
    std::sort(counts.begin(), counts.end());
    counts.erase(std::unique(counts.begin(), counts.end()), counts.end());
    return counts;
}

namespace {

// Runs the operation once with heap accounting on; returns the peak heap it held [MB].
double MeasurePeakHeapMb(const Operation& operation) {
    StartHeapTracking();
    try {
        benchmark::DoNotOptimize(operation());
    } catch (...) {
        StopHeapTracking();
        throw;
    }
    return static_cast<double>(StopHeapTracking()) / (1024.0 * 1024.0);
}

void RunOne(benchmark::State& state, const Setup& setup, Input input,
            const std::shared_ptr<std::map<int, double>>& peak_heap_mb) {
    const int threads = static_cast<int>(state.range(0));
    // Caps every TBB user in the process (multicue, and Open3D where it uses TBB) for this run.
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism,
                              static_cast<std::size_t>(threads));
    try {
        const Operation operation = setup(state, input, threads);
        if (!operation) return;  // the setup skipped the benchmark and said why
        std::size_t out = 0;
        for (auto _ : state) {
            out = operation();
            benchmark::DoNotOptimize(out);
        }
        // Memory is measured on one extra, untimed call, once per benchmark.
        auto peak = peak_heap_mb->find(threads);
        if (peak == peak_heap_mb->end()) {
            peak = peak_heap_mb->emplace(threads, MeasurePeakHeapMb(operation)).first;
        }
        state.counters["out"] = static_cast<double>(out);
        state.counters["peak_heap_MB"] = peak->second;
    } catch (const std::exception& e) {
        state.SkipWithError(e.what());
    }
}

}  // namespace

void RegisterAll(const std::vector<Library>& libraries) {
    for (std::string_view operation : kOperations) {
        for (Input input : kInputs) {
            for (const Library& library : libraries) {
                const auto found = library.setups.find(operation);
                if (found == library.setups.end()) continue;
                const std::string name = std::string(operation) + "/" +
                                         std::string(InputName(input)) + "/" +
                                         std::string(library.name);
                // Peak heap per thread count, measured on the first run, reused by repetitions.
                auto peak_heap_mb = std::make_shared<std::map<int, double>>();
                auto* bench = benchmark::RegisterBenchmark(
                    name.c_str(),
                    [setup = found->second, input, peak_heap_mb](benchmark::State& state) {
                        RunOne(state, setup, input, peak_heap_mb);
                    });
                bench->ArgName("threads");
                for (int threads : ThreadCounts()) bench->Arg(threads);
                bench->UseRealTime()->Unit(benchmark::kMillisecond);
            }
        }
    }
}

Library MakeLibrary(std::string_view name, Setup load, Setup voxel_grid, NormalsSetup normals,
                    Setup outlier_removal) {
    Library library{name, {}};
    library.setups["load"] = std::move(load);
    library.setups["voxel_grid"] = std::move(voxel_grid);
    library.setups["normals_radius"] = [normals](benchmark::State& s, Input i, int t) {
        return normals(s, i, t, true);
    };
    library.setups["normals_knn"] = [normals](benchmark::State& s, Input i, int t) {
        return normals(s, i, t, false);
    };
    library.setups["outlier_removal"] = std::move(outlier_removal);
    return library;
}

}  // namespace multicue::bench

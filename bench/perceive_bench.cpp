// bench_perceive: the table-top pipeline in a warm process on real 640x480 frames, and PCL's LCCP
// segmentation (the LCCP example program's parameters, eval/peers/) on the same frames in the
// same run when built with -DMULTICUE_BENCH_PEERS=ON.
//
// Every frame is read once before it is timed; what is timed is Perceive() on the loaded cloud
// (the in-process pipeline: no file reading, no result files, no report). Configurations:
//   pipeline/<frame>/threads:1 and :2     the default parameters (rules categoriser)
//   three_experts/<frame>/threads:2       the part-graph+rules+cluster categoriser
//   lccp/<frame>                          PCL's supervoxels + LCCP, one thread
// After the runs a summary gives, per configuration, the median frame time, the worst frame and
// worst/median, the ratio to LCCP's median on the same frames, the median time of every stage and
// the peak heap of one frame (median and largest).
//
//   build/bench/bench_perceive [--frames=learn|validate|all|learn0,test55,...] [--iterations=N]
//                              [--configs=pipeline,three_experts,lccp] [--benchmark_...]
// ($MULTICUE_DATA: the data folder; its scans/mosd-learn and scans/mosd-validate are read.)

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <benchmark/benchmark.h>
#include <sys/resource.h>
#include <time.h>

#include "driver_options.hpp"
#include "heap_tracker.hpp"
#include "multicue/io/pcd.hpp"
#include "multicue/system/perceive.hpp"
#include "multicue/training/part_graph_training.hpp"

#if MULTICUE_BENCH_PEERS
#include <omp.h>
#include <pcl/console/print.h>
#include <pcl/io/pcd_io.h>

#include "peers/segmentation.hpp"
#endif

namespace {

namespace fs = std::filesystem;

fs::path DataDir() {
    const char* env = std::getenv("MULTICUE_DATA");
    return env != nullptr ? fs::path(env) : fs::path(MULTICUE_DEFAULT_DATA_DIR);
}

struct Options {
    std::string frames = "learn";
    int iterations = 3;
    std::vector<std::string> configs = {"pipeline", "three_experts", "lccp"};
};

// Takes this program's own flags out of argv (Google Benchmark rejects flags it does not know).
Options ParseOwnFlags(int& argc, char** argv) {
    Options options;
    int kept = 1;
    for (int i = 1; i < argc; ++i) {
        const std::string arg = argv[i];
        auto value = [&](const char* flag) -> std::optional<std::string> {
            const std::string prefix = std::string(flag) + "=";
            if (arg.rfind(prefix, 0) == 0) return arg.substr(prefix.size());
            return std::nullopt;
        };
        if (auto v = value("--frames")) {
            options.frames = *v;
        } else if (auto n = value("--iterations")) {
            options.iterations = std::atoi(n->c_str());
            if (options.iterations < 1) throw std::invalid_argument("--iterations must be >= 1");
        } else if (auto c = value("--configs")) {
            options.configs = multicue::eval::SplitComma(*c);
        } else {
            argv[kept++] = argv[i];
        }
    }
    argc = kept;
    return options;
}

// Frame name -> file: learnN in mosd-learn, testN in mosd-validate.
fs::path FramePath(const std::string& frame) {
    const char* folder = frame.rfind("test", 0) == 0 ? "mosd-validate" : "mosd-learn";
    return DataDir() / "scans" / folder / (frame + ".pcd");
}

std::vector<std::string> Frames(const std::string& set) {
    std::vector<std::string> frames;
    auto range = [&](const char* prefix, int first, int last) {
        for (int k = first; k <= last; ++k) frames.push_back(prefix + std::to_string(k));
    };
    if (set == "learn" || set == "all") range("learn", 0, 44);
    if (set == "validate" || set == "all") {
        range("test", 43, 48);
        range("test", 55, 59);
    }
    if (frames.empty()) frames = multicue::eval::SplitComma(set);
    return frames;
}

// What the runs measured, per configuration and frame.
struct FrameRecord {
    std::vector<double> ms;      // one per timed iteration
    std::vector<double> cpu_ms;  // process CPU time of each timed iteration (all threads)
    std::map<std::string, double> stage_ms;
    double peak_heap_mb = 0.0;
};
std::map<std::string, std::map<std::string, FrameRecord>> g_records;  // config -> frame -> record

double Median(std::vector<double> v) {
    if (v.empty()) return 0.0;
    std::sort(v.begin(), v.end());
    const std::size_t n = v.size();
    return n % 2 != 0 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// CPU time of the whole process (every thread) [ms]: with one thread, the work of a frame even
// when other programs compete for the cores.
double ProcessCpuMs() {
    timespec t{};
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return static_cast<double>(t.tv_sec) * 1e3 + static_cast<double>(t.tv_nsec) * 1e-6;
}

// Clouds are read once per frame and kept for every configuration.
const multicue::PointCloud& Cloud(const std::string& frame) {
    static std::map<std::string, multicue::PointCloud> clouds;
    auto it = clouds.find(frame);
    if (it == clouds.end())
        it = clouds.emplace(frame, multicue::io::ReadPcd(FramePath(frame))).first;
    return it->second;
}

std::shared_ptr<const multicue::PartGraphModel> DefaultModel() {
    static std::shared_ptr<const multicue::PartGraphModel> model;
    if (!model) {
        multicue::PerceiveParams p;
        p.category.categoriser = multicue::Categoriser::kThreeExperts;
        model = multicue::training::LoadPerceiveModels(p).part_graph;
    }
    return model;
}

void BM_Perceive(benchmark::State& state, const std::string& config, const std::string& frame,
                 multicue::Categoriser categoriser) {
    const fs::path path = FramePath(frame);
    if (!fs::exists(path)) {
        state.SkipWithError(("missing " + path.string() + " (set MULTICUE_DATA)").c_str());
        return;
    }
    const multicue::PointCloud& cloud = Cloud(frame);
    multicue::PerceiveParams params;
    params.num_threads = static_cast<int>(state.range(0));
    params.category.categoriser = categoriser;
    multicue::PerceiveModels models;
    if (categoriser != multicue::Categoriser::kRules) models.part_graph = DefaultModel();

    // One untimed run: the peak heap of a frame (tracking slows allocation down).
    multicue::bench::StartHeapTracking();
    multicue::PerceiveResult result = multicue::Perceive(cloud, params, models);
    const double peak_mb =
        static_cast<double>(multicue::bench::StopHeapTracking()) / (1024.0 * 1024.0);

    FrameRecord& record = g_records[config + "/threads:" + std::to_string(state.range(0))][frame];
    record.peak_heap_mb = peak_mb;
    std::map<std::string, std::vector<double>> stages;
    for (auto _ : state) {
        const double cpu_start = ProcessCpuMs();
        const auto start = std::chrono::steady_clock::now();
        result = multicue::Perceive(cloud, params, models);
        record.ms.push_back(
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
                .count());
        record.cpu_ms.push_back(ProcessCpuMs() - cpu_start);
        for (const auto& [stage, ms] : result.timings_ms) stages[stage].push_back(ms);
    }
    for (const auto& [stage, v] : stages) {
        record.stage_ms[stage] = Median(v);
        state.counters[stage + "_ms"] = record.stage_ms[stage];
    }
    state.counters["objects"] = static_cast<double>(result.objects.size());
    state.counters["peak_heap_MB"] = peak_mb;
}

#if MULTICUE_BENCH_PEERS
void BM_Lccp(benchmark::State& state, const std::string& frame) {
    const fs::path path = FramePath(frame);
    auto cloud = std::make_shared<multicue::peers::PeerCloud>();
    if (!fs::exists(path) || pcl::io::loadPCDFile(path.string(), *cloud) < 0) {
        state.SkipWithError(("cannot read " + path.string()).c_str());
        return;
    }
    omp_set_num_threads(1);
    multicue::bench::StartHeapTracking();
    multicue::peers::PeerSegmentation result = multicue::peers::SegmentLccp(cloud);
    const double peak_mb =
        static_cast<double>(multicue::bench::StopHeapTracking()) / (1024.0 * 1024.0);
    FrameRecord& record = g_records["lccp/threads:1"][frame];
    record.peak_heap_mb = peak_mb;
    for (auto _ : state) {
        const double cpu_start = ProcessCpuMs();
        const auto start = std::chrono::steady_clock::now();
        result = multicue::peers::SegmentLccp(cloud);
        record.ms.push_back(
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
                .count());
        record.cpu_ms.push_back(ProcessCpuMs() - cpu_start);
    }
    state.counters["objects"] = static_cast<double>(result.objects);
    state.counters["peak_heap_MB"] = peak_mb;
}
#endif

bool Wanted(const Options& options, const std::string& config) {
    return std::find(options.configs.begin(), options.configs.end(), config) !=
           options.configs.end();
}

void Register(const Options& options) {
    for (const std::string& frame : Frames(options.frames)) {
        auto add = [&](const std::string& name, auto fn) {
            return benchmark::RegisterBenchmark(name.c_str(), fn)
                ->Iterations(options.iterations)
                ->Unit(benchmark::kMillisecond)
                ->UseRealTime();
        };
        if (Wanted(options, "pipeline")) {
            add("pipeline/" + frame,
                [frame](benchmark::State& s) {
                    BM_Perceive(s, "pipeline", frame, multicue::Categoriser::kRules);
                })
                ->Arg(1)
                ->Arg(2)
                ->ArgName("threads");
        }
        if (Wanted(options, "three_experts")) {
            add("three_experts/" + frame,
                [frame](benchmark::State& s) {
                    BM_Perceive(s, "three_experts", frame, multicue::Categoriser::kThreeExperts);
                })
                ->Arg(2)
                ->ArgName("threads");
        }
#if MULTICUE_BENCH_PEERS
        if (Wanted(options, "lccp")) {
            add("lccp/" + frame, [frame](benchmark::State& s) { BM_Lccp(s, frame); });
        }
#endif
    }
}

// Frame time of a record: the median of its iterations.
double FrameMs(const FrameRecord& r) { return Median(r.ms); }

void PrintSummary() {
    if (g_records.empty()) return;
    std::optional<double> lccp_median;
    if (auto it = g_records.find("lccp/threads:1"); it != g_records.end()) {
        std::vector<double> v;
        for (const auto& [frame, r] : it->second) v.push_back(FrameMs(r));
        lccp_median = Median(v);
    }
    std::printf("\nSummary (frame time = median of its iterations; medians over frames)\n");
    std::printf("%-26s %6s %10s %10s %-8s %8s %9s %10s %12s %11s\n", "configuration", "frames",
                "median_ms", "worst_ms", "(frame)", "worst/md", "x_lccp", "cpu_md_ms", "heap_md_MB",
                "heap_max_MB");
    for (const auto& [config, frames] : g_records) {
        std::vector<double> times, heaps, cpu;
        std::string worst_frame;
        double worst = -1.0;
        for (const auto& [frame, r] : frames) {
            const double ms = FrameMs(r);
            times.push_back(ms);
            heaps.push_back(r.peak_heap_mb);
            cpu.push_back(Median(r.cpu_ms));
            if (ms > worst) worst = ms, worst_frame = frame;
        }
        const double median = Median(times);
        char ratio[32] = "-";
        if (lccp_median && *lccp_median > 0.0)
            std::snprintf(ratio, sizeof ratio, "%.3f", median / *lccp_median);
        std::printf("%-26s %6zu %10.1f %10.1f %-8s %8.2f %9s %10.1f %12.1f %11.1f\n",
                    config.c_str(), times.size(), median, worst, worst_frame.c_str(),
                    median > 0.0 ? worst / median : 0.0, ratio, Median(cpu), Median(heaps),
                    *std::max_element(heaps.begin(), heaps.end()));
    }
    std::printf("\nMedian stage times [ms]\n");
    for (const auto& [config, frames] : g_records) {
        std::map<std::string, std::vector<double>> stages;
        for (const auto& [frame, r] : frames)
            for (const auto& [stage, ms] : r.stage_ms) stages[stage].push_back(ms);
        if (stages.empty()) continue;
        std::printf("%-26s", config.c_str());
        for (const auto& [stage, v] : stages) std::printf(" %s %.1f", stage.c_str(), Median(v));
        std::printf("\n");
    }
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    std::printf("\nPeak resident set of the whole run: %.0f MB\n",
                static_cast<double>(usage.ru_maxrss) / 1024.0);
}

}  // namespace

int main(int argc, char** argv) {
#if MULTICUE_BENCH_PEERS
    pcl::console::setVerbosityLevel(pcl::console::L_ERROR);
#endif
    Options options;
    try {
        options = ParseOwnFlags(argc, argv);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "bench_perceive: %s\n", e.what());
        return 2;
    }
    Register(options);
    benchmark::Initialize(&argc, argv);
    if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    PrintSummary();
    return 0;
}

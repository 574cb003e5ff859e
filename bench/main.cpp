/// \file Entry point of bench_multicue: registers every library's operations, then hands over to
/// Google Benchmark (all of its --benchmark_* flags apply).

#include <cstdlib>
#include <string>
#include <thread>
#include <vector>

#include <benchmark/benchmark.h>

#include "bench_common.hpp"

int main(int argc, char** argv) {
#if MULTICUE_BENCH_PEERS
    // Open3D 0.16 honours omp_set_num_threads only when OMP_NUM_THREADS (or OMP_DYNAMIC) is set;
    // otherwise it uses every physical core whatever the program asks. The value here does not
    // limit anything: each benchmark sets its own thread count.
    const std::string all_cores = std::to_string(std::thread::hardware_concurrency());
    setenv("OMP_NUM_THREADS", all_cores.c_str(), 0);
#endif
    benchmark::Initialize(&argc, argv);
    if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;

    std::vector<multicue::bench::Library> libraries = {multicue::bench::MulticueLibrary()};
#if MULTICUE_BENCH_PEERS
    libraries.push_back(multicue::bench::PclLibrary());
    libraries.push_back(multicue::bench::Open3dLibrary());
#endif
    multicue::bench::RegisterAll(libraries);

    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
}

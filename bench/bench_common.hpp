#pragma once
/// \file Shared pieces of the benchmark program: the input scans, the thread counts and the naming
/// scheme `<operation>/<input>/<library>/threads:<n>` that bench/ratios.py parses.
///
/// Every operation is registered once per library (multicue, pcl, open3d), per input and per thread
/// count, with the same parameters. Inputs are read once per library and cached outside the timed
/// loop; each benchmark then times only the operation itself.

#include <array>
#include <filesystem>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include <benchmark/benchmark.h>

namespace multicue::bench {

/// The scans every operation runs on.
enum class Input { kMosd, kTableScene };

inline constexpr std::array<Input, 2> kInputs = {Input::kMosd, Input::kTableScene};

/// Short name used in benchmark names ("mosd", "table").
std::string_view InputName(Input input);

/// Full path of an input: $MULTICUE_DATA (or the shared data folder the build was configured with)
/// followed by the scan's path inside it.
std::filesystem::path InputPath(Input input);

/// Checks that the input file exists; otherwise marks the benchmark as skipped with a message that
/// names the missing file and the MULTICUE_DATA variable, and returns false.
bool CheckInputExists(benchmark::State& state, Input input);

/// Thread counts every operation is measured with: 1, 2 and all cores (duplicates removed).
std::vector<int> ThreadCounts();

/// Parameters shared by all three libraries, so that no implementation sees other values.
inline constexpr float kVoxelLeaf = 0.005f;        ///< voxel grid leaf size [m]
inline constexpr float kNormalRadius = 0.02f;      ///< normals neighbourhood radius [m]
inline constexpr int kNormalK = 20;                ///< normals neighbours (query point included)
inline constexpr int kOutlierK = 50;               ///< outlier removal neighbours (PCL tutorial)
inline constexpr double kOutlierStdRatio = 1.0;    ///< outlier removal threshold in std devs

using BenchFn = std::function<void(benchmark::State&, Input, int threads)>;

/// Registers `<operation>/<input>/<library>/threads:<n>` for every input and thread count, in real
/// time and milliseconds.
void RegisterOperation(std::string_view operation, std::string_view library, BenchFn fn);

/// Runs `fn` once outside the timed loop with heap accounting on and reports the peak number of
/// heap bytes it held above what was allocated before it started, as the counter `peak_heap_MB`.
void ReportPeakHeap(benchmark::State& state, const std::function<void()>& fn);

/// Each library registers its benchmarks here; the peers are only defined when they are built in.
void RegisterMulticueBenchmarks();
#if MULTICUE_BENCH_PEERS
void RegisterPclBenchmarks();
void RegisterOpen3dBenchmarks();
#endif

}  // namespace multicue::bench

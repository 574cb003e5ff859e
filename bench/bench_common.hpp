#pragma once
/// \file Shared pieces of the benchmark program: the input scans, the thread counts, the common
/// parameters and the naming scheme `<operation>/<input>/<library>/threads:<n>` that
/// bench/ratios.py parses.
///
/// Every operation is registered once per library (multicue, pcl, open3d), input and thread count,
/// with the same parameters. A library supplies a setup function that runs outside the timed loop
/// (reading and caching the input, converting it to the library's type) and returns the operation
/// to time. The operation returns the size of its result (points read, voxels, normals, inliers),
/// reported as the counter `out` so that runs of different libraries can be checked for doing the
/// same work.

#include <array>
#include <cstddef>
#include <filesystem>
#include <functional>
#include <map>
#include <string_view>
#include <vector>

#include <benchmark/benchmark.h>

namespace multicue::bench {

/// The scans every operation runs on.
enum class Input { kMosd, kTableScene };

inline constexpr std::array<Input, 2> kInputs = {Input::kMosd, Input::kTableScene};

/// Short name used in benchmark names ("mosd", "table").
std::string_view InputName(Input input);

/// Full path of an input: $MULTICUE_DATA (default: the shared data folder the build was configured
/// with) followed by the scan's path inside it.
std::filesystem::path InputPath(Input input);

/// Checks that the input file exists; otherwise marks the benchmark as skipped with a message that
/// names the missing file and the MULTICUE_DATA variable, and returns false.
bool CheckInputExists(benchmark::State& state, Input input);

/// Thread counts every operation is measured with: 1, 2 and all cores (duplicates removed).
std::vector<int> ThreadCounts();

// Parameters shared by all three libraries.
/// Voxel grid leaf size [m].
inline constexpr float kVoxelLeaf = 0.005f;
/// Normals neighbourhood radius [m].
inline constexpr float kNormalRadius = 0.02f;
/// Normals neighbours, the query point included as in all three libraries [points].
inline constexpr int kNormalK = 20;
/// Outlier removal neighbours, the query point excluded as in PCL and multicue [points].
inline constexpr int kOutlierK = 50;
/// Outlier threshold: mean + kOutlierStdRatio * standard deviation of the mean distances.
inline constexpr double kOutlierStdRatio = 1.0;

/// The timed operation; returns the size of its result.
using Operation = std::function<std::size_t()>;
/// Untimed preparation for one run. Returns the operation, or an empty function after calling
/// state.SkipWithError. Exceptions it throws also skip the benchmark with their message.
using Setup = std::function<Operation(benchmark::State& state, Input input, int threads)>;

/// The operations, in the order they run; each library supplies a Setup for every one of them.
inline constexpr std::array<std::string_view, 5> kOperations = {
    "load", "voxel_grid", "normals_radius", "normals_knn", "outlier_removal"};

/// One library's implementations, keyed by operation name.
struct Library {
    std::string_view name;
    std::map<std::string_view, Setup> setups;
};

/// Registers `<operation>/<input>/<library>/threads:<n>` for every operation, input, library and
/// thread count, in that nesting, so that the libraries' runs of one operation on one input follow
/// each other. Timed in real time and milliseconds; while a run lasts, TBB is limited to `threads`
/// threads process-wide.
void RegisterAll(const std::vector<Library>& libraries);

/// The libraries; the peers exist only when they are built in.
/// Normals setup of one library; `radius` picks the radius (else the k-NN) variant.
using NormalsSetup =
    std::function<Operation(benchmark::State& state, Input input, int threads, bool radius)>;

/// A library's table of operations, named as bench/ratios.py expects.
Library MakeLibrary(std::string_view name, Setup load, Setup voxel_grid, NormalsSetup normals,
                    Setup outlier_removal);

Library MulticueLibrary();
#if MULTICUE_BENCH_PEERS
Library PclLibrary();
Library Open3dLibrary();
#endif

}  // namespace multicue::bench

/// \file The Open3D 0.16 side of every benchmarked operation.
///
/// Open3D's algorithms do not skip NaN points: VoxelDownSample turns their coordinates into voxel
/// indices (undefined behaviour) and its bounds become NaN, and the k-d tree would index them. Its
/// own answer is ReadPointCloudOption::remove_nan_points, so every operation after `load` runs on
/// the cloud with NaN points removed beforehand, outside the timed call. `load` reads the file as
/// it is, keeping NaN points like the other two readers.
///
/// Threads: Open3D parallelizes with OpenMP; omp_set_num_threads applies because main() sets
/// OMP_NUM_THREADS (see main.cpp).

#if MULTICUE_BENCH_PEERS

#include <cstddef>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>

#include <benchmark/benchmark.h>
#include <omp.h>
#include <open3d/geometry/KDTreeSearchParam.h>
#include <open3d/geometry/PointCloud.h>
#include <open3d/io/PointCloudIO.h>
#include <open3d/utility/Logging.h>

#include "bench_common.hpp"

namespace multicue::bench {
namespace {

using open3d::geometry::PointCloud;

// The scans as Open3D reads them with NaN points removed, read once per input.
const PointCloud* CachedCloud(benchmark::State& state, Input input) {
    static std::map<Input, PointCloud> cache;
    if (!CheckInputExists(state, input)) return nullptr;
    auto found = cache.find(input);
    if (found == cache.end()) {
        PointCloud cloud;
        open3d::io::ReadPointCloudOption option;
        option.remove_nan_points = true;
        option.remove_infinite_points = true;
        if (!open3d::io::ReadPointCloud(InputPath(input).string(), cloud, option)) {
            state.SkipWithError(("Open3D could not read " + InputPath(input).string()).c_str());
            return nullptr;
        }
        found = cache.emplace(input, std::move(cloud)).first;
    }
    return &found->second;
}

Operation Load(benchmark::State& state, Input input, int threads) {
    if (!CheckInputExists(state, input)) return {};
    omp_set_num_threads(threads);
    return [path = InputPath(input).string()] {
        PointCloud cloud;
        if (!open3d::io::ReadPointCloud(path, cloud)) {
            throw std::runtime_error("Open3D failed on " + path);
        }
        benchmark::DoNotOptimize(cloud.points_.data());
        return cloud.points_.size();
    };
}

Operation VoxelDownsample(benchmark::State& state, Input input, int threads) {
    const PointCloud* cloud = CachedCloud(state, input);
    if (cloud == nullptr) return {};
    omp_set_num_threads(threads);
    return [cloud] {
        const std::shared_ptr<PointCloud> down = cloud->VoxelDownSample(kVoxelLeaf);
        benchmark::DoNotOptimize(down->points_.data());
        return down->points_.size();
    };
}

// EstimateNormals builds its k-d tree inside the call. It would orient new normals towards
// existing ones, so it works on a copy made outside the timing whose normals every call drops
// first (freeing them, so that every call allocates its normals as the other libraries do).
Operation Normals(benchmark::State& state, Input input, int threads, bool use_radius) {
    const PointCloud* cloud = CachedCloud(state, input);
    if (cloud == nullptr) return {};
    omp_set_num_threads(threads);
    auto work = std::make_shared<PointCloud>(*cloud);
    return [work, use_radius] {
        work->normals_.clear();
        work->normals_.shrink_to_fit();
        if (use_radius) {
            work->EstimateNormals(open3d::geometry::KDTreeSearchParamRadius(kNormalRadius));
        } else {
            work->EstimateNormals(open3d::geometry::KDTreeSearchParamKNN(kNormalK));
        }
        std::size_t defined = 0;
        for (const auto& n : work->normals_) defined += n.allFinite() && !n.isZero() ? 1 : 0;
        return defined;
    };
}

// Returns the filtered cloud as well as the inlier indices; Open3D has no indices-only variant.
// Open3D counts the query point among its nb_neighbors (at distance 0) where PCL and multicue
// take k others: with k + 1 every mean distance is the same k/(k+1) multiple of theirs, and so are
// the mean and deviation of those, which keeps the same points.
Operation OutlierRemoval(benchmark::State& state, Input input, int threads) {
    const PointCloud* cloud = CachedCloud(state, input);
    if (cloud == nullptr) return {};
    omp_set_num_threads(threads);
    return [cloud] {
        const auto [filtered, inliers] = cloud->RemoveStatisticalOutliers(
            static_cast<std::size_t>(kOutlierK) + 1, kOutlierStdRatio);
        benchmark::DoNotOptimize(filtered->points_.data());
        return inliers.size();
    };
}

}  // namespace

Library Open3dLibrary() {
    open3d::utility::SetVerbosityLevel(open3d::utility::VerbosityLevel::Warning);
    return MakeLibrary("open3d", Load, VoxelDownsample, Normals, OutlierRemoval);
}

}  // namespace multicue::bench

#endif  // MULTICUE_BENCH_PEERS

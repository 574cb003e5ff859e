/// \file The multicue side of every benchmarked operation.

#include <cstddef>
#include <map>
#include <optional>

#include <benchmark/benchmark.h>

#include "bench_common.hpp"
#include "multicue/core/point_cloud.hpp"
#include "multicue/filters/outlier_removal.hpp"
#include "multicue/filters/voxel_grid.hpp"
#include "multicue/io/pcd.hpp"
#include "multicue/search/kdtree.hpp"
#include "multicue/surface/normals.hpp"

namespace multicue::bench {
namespace {

// The scans as multicue reads them (organized, NaN points kept), read once per input.
const PointCloud* CachedCloud(benchmark::State& state, Input input) {
    static std::map<Input, PointCloud> cache;
    if (!CheckInputExists(state, input)) return nullptr;
    auto found = cache.find(input);
    if (found == cache.end()) found = cache.emplace(input, io::ReadPcd(InputPath(input))).first;
    return &found->second;
}

Operation Load(benchmark::State& state, Input input, int /*threads*/) {
    if (!CheckInputExists(state, input)) return {};
    return [path = InputPath(input)] {
        const PointCloud cloud = io::ReadPcd(path);
        benchmark::DoNotOptimize(cloud.points.data());
        return cloud.size();
    };
}

Operation VoxelDownsample(benchmark::State& state, Input input, int threads) {
    const PointCloud* cloud = CachedCloud(state, input);
    if (cloud == nullptr) return {};
    const VoxelGridParams params{.leaf_size = kVoxelLeaf, .num_threads = threads};
    return [cloud, params] {
        const PointCloud down = VoxelGrid(*cloud, params);
        benchmark::DoNotOptimize(down.points.data());
        return down.size();
    };
}

// The k-d tree is built inside the timed call, as PCL and Open3D build theirs. Without a viewpoint
// normals are oriented towards the cloud's sensor origin, as PCL does.
Operation Normals(benchmark::State& state, Input input, int threads, bool use_radius) {
    const PointCloud* cloud = CachedCloud(state, input);
    if (cloud == nullptr) return {};
    const NormalParams params =
        use_radius ? NormalParams{.radius = kNormalRadius,
                                  .viewpoint = std::nullopt,
                                  .num_threads = threads}
                   : NormalParams{.k = kNormalK, .viewpoint = std::nullopt, .num_threads = threads};
    return [cloud, params] {
        const KdTree tree(*cloud);
        const NormalsResult result = EstimateNormals(*cloud, tree, params);
        benchmark::DoNotOptimize(result.normals.data());
        return result.normals.size() - result.undefined;
    };
}

Operation OutlierRemoval(benchmark::State& state, Input input, int threads) {
    const PointCloud* cloud = CachedCloud(state, input);
    if (cloud == nullptr) return {};
    const StatisticalOutlierParams params{
        .k = kOutlierK, .std_ratio = static_cast<float>(kOutlierStdRatio), .num_threads = threads};
    return [cloud, params] {
        const KdTree tree(*cloud);
        const Indices inliers = StatisticalOutlierRemoval(*cloud, tree, params);
        benchmark::DoNotOptimize(inliers.data());
        return inliers.size();
    };
}

}  // namespace

Library MulticueLibrary() {
    return MakeLibrary("multicue", Load, VoxelDownsample, Normals, OutlierRemoval);
}

}  // namespace multicue::bench

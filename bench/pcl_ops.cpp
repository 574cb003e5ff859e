/// \file The PCL 1.13 side of every benchmarked operation.
///
/// Point type: pcl::PointXYZRGBA, what the scans hold. Organized clouds keep their NaN points,
/// which PCL skips itself (is_dense is false). PCL would search organized clouds with
/// OrganizedNeighbor by default; every operation here is given a k-d tree (pcl::search::KdTree,
/// i.e. KdTreeFLANN) so that all three libraries use the same kind of search structure, and the
/// tree is built inside the timed call.

#if MULTICUE_BENCH_PEERS

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>

#include <benchmark/benchmark.h>
#include <pcl/features/normal_3d.h>
#include <pcl/features/normal_3d_omp.h>
#include <pcl/filters/statistical_outlier_removal.h>
#include <pcl/filters/voxel_grid.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/search/kdtree.h>

#include "bench_common.hpp"

namespace multicue::bench {
namespace {

using Point = pcl::PointXYZRGBA;
using Cloud = pcl::PointCloud<Point>;
using Tree = pcl::search::KdTree<Point>;

// The scans as PCL reads them, read once per input.
Cloud::ConstPtr CachedCloud(benchmark::State& state, Input input) {
    static std::map<Input, Cloud::ConstPtr> cache;
    if (!CheckInputExists(state, input)) return nullptr;
    auto found = cache.find(input);
    if (found == cache.end()) {
        auto cloud = std::make_shared<Cloud>();
        if (pcl::io::loadPCDFile(InputPath(input).string(), *cloud) < 0) {
            state.SkipWithError(("PCL could not read " + InputPath(input).string()).c_str());
            return nullptr;
        }
        found = cache.emplace(input, cloud).first;
    }
    return found->second;
}

// StatisticalOutlierRemoval has no way to be given a search structure and searches organized
// input with OrganizedNeighbor. A copy of the scan marked unorganized (same points in the same
// order, NaN points included) makes it build the k-d tree the other libraries use.
Cloud::ConstPtr CachedUnorganizedCloud(benchmark::State& state, Input input) {
    static std::map<Input, Cloud::ConstPtr> cache;
    const Cloud::ConstPtr organized = CachedCloud(state, input);
    if (!organized) return nullptr;
    auto found = cache.find(input);
    if (found == cache.end()) {
        auto cloud = std::make_shared<Cloud>(*organized);
        cloud->width = static_cast<std::uint32_t>(cloud->size());
        cloud->height = 1;
        found = cache.emplace(input, cloud).first;
    }
    return found->second;
}

Operation Load(benchmark::State& state, Input input, int /*threads*/) {
    if (!CheckInputExists(state, input)) return {};
    return [path = InputPath(input).string()] {
        Cloud cloud;
        if (pcl::io::loadPCDFile(path, cloud) < 0)
            throw std::runtime_error("PCL failed on " + path);
        benchmark::DoNotOptimize(cloud.points.data());
        return cloud.size();
    };
}

// pcl::VoxelGrid has no parallel version: every thread count runs the same serial code.
Operation VoxelDownsample(benchmark::State& state, Input input, int /*threads*/) {
    const Cloud::ConstPtr cloud = CachedCloud(state, input);
    if (!cloud) return {};
    return [cloud] {
        pcl::VoxelGrid<Point> grid;
        grid.setInputCloud(cloud);
        grid.setLeafSize(kVoxelLeaf, kVoxelLeaf, kVoxelLeaf);
        Cloud down;
        grid.filter(down);
        benchmark::DoNotOptimize(down.points.data());
        return down.size();
    };
}

// One thread: pcl::NormalEstimation; more: pcl::NormalEstimationOMP with that many threads.
// compute() builds the fresh tree on the input.
Operation Normals(benchmark::State& state, Input input, int threads, bool use_radius) {
    const Cloud::ConstPtr cloud = CachedCloud(state, input);
    if (!cloud) return {};
    return [cloud, threads, use_radius] {
        pcl::PointCloud<pcl::Normal> normals;
        auto estimate = [&](auto& estimator) {
            estimator.setInputCloud(cloud);
            estimator.setSearchMethod(std::make_shared<Tree>(false));
            if (use_radius) {
                estimator.setRadiusSearch(kNormalRadius);
            } else {
                estimator.setKSearch(kNormalK);
            }
            estimator.compute(normals);
        };
        if (threads == 1) {
            pcl::NormalEstimation<Point, pcl::Normal> estimator;
            estimate(estimator);
        } else {
            pcl::NormalEstimationOMP<Point, pcl::Normal> estimator(static_cast<unsigned>(threads));
            estimate(estimator);
        }
        // Normals of NaN points and of points without enough neighbours are NaN.
        std::size_t defined = 0;
        for (const auto& n : normals) defined += std::isfinite(n.normal_x) ? 1 : 0;
        return defined;
    };
}

// pcl::StatisticalOutlierRemoval has no parallel version. filter(Indices&) returns the inlier
// indices, as multicue does, without copying points.
Operation OutlierRemoval(benchmark::State& state, Input input, int /*threads*/) {
    const Cloud::ConstPtr cloud = CachedUnorganizedCloud(state, input);
    if (!cloud) return {};
    return [cloud] {
        pcl::StatisticalOutlierRemoval<Point> filter;
        filter.setInputCloud(cloud);
        filter.setMeanK(kOutlierK);
        filter.setStddevMulThresh(kOutlierStdRatio);
        pcl::Indices inliers;
        filter.filter(inliers);
        // PCL gives NaN points a mean distance of 0 and so keeps them; the other two never keep
        // them, and `out` counts the finite inliers to compare the same thing.
        std::size_t finite = 0;
        for (const auto i : inliers) finite += pcl::isFinite((*cloud)[i]) ? 1 : 0;
        return finite;
    };
}

}  // namespace

Library PclLibrary() { return MakeLibrary("pcl", Load, VoxelDownsample, Normals, OutlierRemoval); }

}  // namespace multicue::bench

#endif  // MULTICUE_BENCH_PEERS

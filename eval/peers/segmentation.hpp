#pragma once
/// \file The three standard PCL 1.13 table-top segmentation pipelines that multicue is measured
/// against (`mosd_peers` for accuracy, `bench_perceive` for speed): PCL's Euclidean cluster
/// extraction tutorial, its region growing tutorial and its LCCP example program, each with the
/// parameters of that tutorial or example (eval/README.md). Built only with
/// -DMULTICUE_BENCH_PEERS=ON; never part of the library.

#include <cstddef>
#include <cstdint>
#include <vector>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

namespace multicue::peers {

using PeerPoint = pcl::PointXYZRGBA;  ///< the mOSD files hold label x y z rgba; label is not read
using PeerCloud = pcl::PointCloud<PeerPoint>;

/// Per input point, the object it belongs to (0 = none: table, background, invalid); objects are
/// numbered 1..objects, largest first.
struct PeerSegmentation {
    std::vector<std::uint32_t> object;
    std::size_t objects = 0;
};

/// Euclidean Cluster Extraction tutorial: 1 cm voxel grid, RANSAC plane removal while more than
/// 30 % of the voxels remain, Euclidean clusters of the rest.
PeerSegmentation SegmentEuclidean(const PeerCloud::ConstPtr& cloud);

/// Region growing tutorial: k = 50 normals, region growing; segments mostly on the dominant
/// RANSAC plane are the table.
PeerSegmentation SegmentRegionGrowing(const PeerCloud::ConstPtr& cloud);

/// LCCP example program: supervoxels, LCCP merging, labels carried to the points; segments mostly
/// on the dominant RANSAC plane are the table.
PeerSegmentation SegmentLccp(const PeerCloud::ConstPtr& cloud);

}  // namespace multicue::peers

#pragma once
/// \file Features of a whole cluster or part by name: a small registry (name -> dimension,
/// compute function) so that tools can extract datasets by feature name.
///
/// Names and dimensions:
///   rsd 2          mean (r_min, r_max) over the points (section 2.5.1)
///   grsd 21        ray-cast GRSD (section 2.5.2)
///   grsd-minus 21  additive GRSD- (section 2.5.2)
///   vfh 308        VFH (Table 2.2)
///   pfh 125        mean PFH over the points (Table 2.2)
///   fpfh 33        mean FPFH over the points
///   pfhrgb 250     mean PFHRGB over the points (Table 2.2); needs colours
///   part-stats 24  part statistics (section 4.2.3.1)
///   colour 20      HSV colour histogram (colour.hpp); needs colours
/// Every compute function takes a cloud with normals that is the whole cluster.

#include <optional>
#include <span>
#include <string>
#include <string_view>

#include "multicue/features/feature_common.hpp"

namespace multicue {

struct ClusterFeatureParams {
    float radius = 0.03f;           ///< neighbourhood radius of the per-point features [m]
    float rsd_radius = 0.02f;       ///< RSD neighbourhood radius [m]
    float voxel_size = 0.025f;      ///< GRSD voxel size [m]
    float part_voxel_size = 0.01f;  ///< voxel size of the part statistics' volume [m]
    /// Viewpoint of VFH and GRSD [m]; default: the cloud's sensor_origin.
    std::optional<Eigen::Vector3f> viewpoint = std::nullopt;
    Eigen::Vector3f up = Eigen::Vector3f::UnitZ();  ///< up direction of the part statistics
    int num_threads = 0;                            ///< 0 = all cores
};

struct ClusterFeature {
    std::string_view name;
    int dimension = 0;
    std::string_view description;
    FeatureVector (*compute)(const PointCloud& cluster, const ClusterFeatureParams& params);
};

/// Every registered feature, in the order of the table above.
std::span<const ClusterFeature> ClusterFeatures();

/// The feature called `name`; throws InvalidArgument naming the known ones otherwise.
const ClusterFeature& FindClusterFeature(std::string_view name);

/// Computes the feature `name` of a cluster; the result has the feature's dimension.
FeatureVector ComputeClusterFeature(std::string_view name, const PointCloud& cluster,
                                    const ClusterFeatureParams& params = {});

}  // namespace multicue

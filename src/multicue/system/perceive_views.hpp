#pragma once
/// \file Categories from several registered frames of one scene (thesis section 5.3, Figures 5.14
/// and 5.16): each frame is perceived on its own, the per-point category distributions of all
/// frames are summed in a voxel grid in the common (world) frame, and every point takes its
/// voxel's distribution — what one view cannot tell, another often can.

#include <vector>

#include <Eigen/Geometry>

#include "multicue/core/point_cloud.hpp"
#include "multicue/system/perceive.hpp"

namespace multicue {

struct ViewFusionParams {
    float voxel_size = 0.005f;  ///< edge of the vote voxels [m] (section 5.3: 5 mm); > 0
    bool remodel = true;        ///< fit the models of objects whose category changes again
};

/// Fuses the categories of frames perceived one by one. `clouds[f]` is frame f as given to
/// Perceive, `T_world_sensor[f]` maps its coordinates into the common frame, `results[f]` is
/// Perceive's result for it (same parameters `params`). Every object point votes with its
/// object's probabilities (which already merge its parts' part-graph votes) into the voxel it falls
/// in. Afterwards, in every frame, each object point's category in point_categories is its
/// voxel's most voted category, and each object's probabilities are the normalised sum of its
/// points' (normalised) voxel votes; objects with category none neither vote nor change. With
/// `remodel`, objects whose category changed get their model fitted again. A single frame leaves
/// the object categories as they were. Throws InvalidArgument for mismatched sizes, a non-finite
/// pose or bad parameters.
void FuseViewCategories(const std::vector<const PointCloud*>& clouds,
                        const std::vector<Eigen::Isometry3f>& T_world_sensor,
                        std::vector<PerceiveResult>& results, const PerceiveParams& params,
                        const ViewFusionParams& fusion = {});

}  // namespace multicue

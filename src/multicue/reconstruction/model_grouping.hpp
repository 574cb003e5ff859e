#pragma once
/// \file Grouping by models (thesis section 5.4.1): segmentation alone cannot tell one object seen
/// as two surfaces from two touching objects; their models can. Each stage looks at the objects
/// and their models (ModelObjects) and merges or splits some of them; the objects it changed must
/// then be categorised and modelled again (perceive does so after every stage), the others are
/// kept as they were. Every stage keeps the objects' order: merged objects take the place of
/// their first member, split ones the place of the object they came from.

#include <cstddef>
#include <vector>

#include <Eigen/Core>

#include "multicue/core/point_cloud.hpp"
#include "multicue/recognition/geometric_category.hpp"
#include "multicue/reconstruction/object_model.hpp"

namespace multicue {

/// What a grouping stage changed.
struct GroupingResult {
    /// Objects (indices into the new list, ascending) that were merged or split off: their
    /// category, part probabilities and model are stale until they are computed again.
    std::vector<std::size_t> changed;
    /// The categories the grouping model leaves the changed objects (two boxes: box or flat);
    /// empty = all.
    std::vector<Category> allowed;
    std::size_t merged = 0;  ///< objects merged into another
    std::size_t split = 0;   ///< objects split in two
};

/// Two cylinders on one axis with about one radius (ConcentricMergeParams), whatever their
/// extent along the axis.
bool CoaxialSameRadius(const CylinderModel& a, const CylinderModel& b,
                       const ConcentricMergeParams& params);

/// Objects whose cylinder models (accepted or not) are coaxial with about one radius and overlap
/// along the axis are one container seen as two surfaces (inside and outside); they are merged
/// (transitively). Two such cylinders that do not overlap are stacked objects and stay apart.
GroupingResult MergeConcentricObjects(std::vector<PerceivedObject>& objects,
                                      const ConcentricMergeParams& params);

/// Objects that lie inside a container's model or against its surface (the bottom inside a bowl,
/// its outer wall below the rim, a mug's handle) join it: an object with at least min_share of
/// its points inside the solid of a larger object's accepted cylinder or surface of revolution,
/// enlarged by margin. Containers are taken from the largest object down.
GroupingResult MergeContainedObjects(const PointCloud& cloud, std::vector<PerceivedObject>& objects,
                                     const ContainedMergeParams& params);

/// Stacked boxes kept together by segmentation: a box or flat object with two horizontal faces at
/// different heights above `plane` is cut at the lower face's height when two upright boxes
/// (params.box) explain the points clearly better than one (params.stacked). Pieces under
/// `min_object_points` cancel the split. Needs a plane and normals; allowed: box, flat.
GroupingResult SplitStackedBoxes(const PointCloud& cloud, std::vector<PerceivedObject>& objects,
                                 const Eigen::Vector4f& plane, const ModelParams& params,
                                 std::size_t min_object_points);

/// Touching boxes kept together by segmentation (side by side, or under a third one): see
/// TouchingSplitParams; tried only where the Poisson part-count model finds two objects likely
/// enough (params.part_counts, params.several_min_ratio). Whole parts go to the box nearer to
/// most of their points, loose points to the nearer box. Needs a plane and normals; allowed:
/// box, flat.
GroupingResult SplitTouchingBoxes(const PointCloud& cloud, std::vector<PerceivedObject>& objects,
                                  const Eigen::Vector4f& plane, const ModelParams& params,
                                  std::size_t min_object_points);

/// Touching round objects kept together by segmentation (a can standing in a bowl): see
/// TouchingSplitParams (round_enabled); the cylinders are params.cylinder fits. Points outside
/// the parts go to the nearer cylinder. Needs normals.
GroupingResult SplitTouchingRound(const PointCloud& cloud, std::vector<PerceivedObject>& objects,
                                  const Eigen::Vector4f& plane, const ModelParams& params,
                                  std::size_t min_object_points);

}  // namespace multicue

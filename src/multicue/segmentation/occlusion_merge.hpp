#pragma once
/// \file Joins the fragments of an object that a nearer object cuts in two. Euclidean clustering
/// cannot bridge the hidden stretch of a box or can standing behind a thinner object, so one
/// object comes back as a hypothesis left and one right of the occluder. Two hypotheses are
/// fragments of one object when (1) in the image, the pixels between them on the rows they share
/// are nearer to the sensor than both (an occluder in front, not table or background showing
/// through), (2) across that gap they are close in 3D and span the same heights above the table,
/// and (3) their surfaces continue each other: the plane of one's largest part, or a cylinder
/// fitted to one, explains the other. This is the occlusion reasoning of amodal completion
/// ("objects continue behind occluders", Kanizsa) reduced to image rows and primitive surfaces.

#include <cstddef>
#include <vector>

#include <Eigen/Core>

#include "multicue/core/params.hpp"
#include "multicue/core/point_cloud.hpp"
#include "multicue/core/types.hpp"
#include "multicue/segmentation/part_segmentation.hpp"

namespace multicue {

struct OcclusionMergeParams {
    float depth_margin = 0.02f;   ///< gap pixels must be this much nearer than both fragments [m]
    float min_near_share = 0.7f;  ///< a row is occluded when this share of its finite gap pixels
                                  ///< is nearer [-], (0, 1]
    float min_occluded_share = 0.5f;  ///< share of the rows both fragments occupy that must be
                                      ///< occluded [-], [0, 1]
    std::size_t min_rows = 5;         ///< fewest occluded rows for a merge [rows]; >= 1
    float max_gap = 0.2f;  ///< largest median 3D distance across the occluded gap [m]; > 0
    float min_height_overlap = 0.6f;    ///< overlap of the fragments' height ranges above the table
                                        ///< over the smaller range [-], [0, 1]; needs a plane
    float surface_distance = 0.006f;    ///< a point lies on the other's surface this close [m]; > 0
    float surface_angle_deg = 20.0f;    ///< ... with its normal this close to the surface's [deg]
    float min_explained_share = 0.3f;   ///< share of a fragment's points the other's surface must
                                        ///< explain [-], (0, 1]
    float min_cylinder_radius = 0.01f;  ///< cylinder continuation: smallest radius [m]
    float max_cylinder_radius = 0.2f;   ///< cylinder continuation: largest radius [m]
    int cylinder_iterations = 300;      ///< cylinder RANSAC sample cap [samples]; >= 1
    int num_threads = 1;  ///< pairs tested in parallel (0 = all cores); never changes the result
    /// Throws InvalidArgument naming the first out-of-range field.
    void Validate() const;
    /// Its parameters once each: configuration key (the field's name), field, meaning. A
    /// visitor reads or records them (io::ConfigSection::operator(); ReadPerceiveParams).
    template <typename V>
    void VisitParams(V& v) {
        v("depth_margin", depth_margin, "gap pixels this much nearer than both [m]");
        v("min_near_share", min_near_share, "share of nearer pixels in an occluded row");
        v("min_occluded_share", min_occluded_share,
          "share of the shared rows that must be occluded");
        v("min_rows", min_rows, "fewest occluded rows for a merge");
        v("max_gap", max_gap, "largest median 3D distance across the gap [m]");
        v("min_height_overlap", min_height_overlap,
          "overlap of the height ranges over the smaller one");
        v("surface_distance", surface_distance, "surface continuation distance [m]");
        v("surface_angle_deg", surface_angle_deg, "surface continuation angle [deg]");
        v("min_explained_share", min_explained_share,
          "share of a fragment the other's surface must explain");
        v("min_cylinder_radius", min_cylinder_radius, "smallest cylinder radius [m]");
        v("max_cylinder_radius", max_cylinder_radius, "largest cylinder radius [m]");
        v("cylinder_iterations", cylinder_iterations, "cylinder RANSAC sample cap");
    }
};

struct OcclusionMergeResult {
    /// The merged objects as lists of input hypotheses (ascending), ordered by their first one;
    /// every input appears in exactly one group.
    std::vector<std::vector<std::size_t>> groups;
    std::size_t candidate_pairs = 0;  ///< pairs that passed the image test (1)
    std::size_t merges = 0;           ///< pairs joined
};

/// Groups the object hypotheses `objects` (indices into `cloud`) into objects, joining fragments
/// split by a nearer occluder; `parts` holds each hypothesis' surface parts (may be empty lists,
/// then only the cylinder test applies). `support_plane` (a, b, c, d, normal up) gives heights;
/// zero skips the height test. Only organized clouds carry the image neighbourhood: other clouds
/// get one group per hypothesis. Points without a finite position are ignored. Throws
/// InvalidArgument for bad parameters, a parts list of the wrong size or an index out of range,
/// DataError if an organized cloud has no normals (unless there are fewer than two hypotheses).
OcclusionMergeResult MergeOccludedFragments(const PointCloud& cloud,
                                            const std::vector<Indices>& objects,
                                            const std::vector<std::vector<Indices>>& parts,
                                            const Eigen::Vector4f& support_plane,
                                            const OcclusionMergeParams& params = {});

/// The objects after joining occluded fragments (MergeOccludedFragments): each merged object
/// takes the points and parts of its group, in the order of the groups; with `enabled` off or
/// fewer than two objects they come back as they were.
std::vector<ObjectSegment> MergeOccludedObjects(const PointCloud& cloud,
                                                std::vector<ObjectSegment> objects,
                                                const Eigen::Vector4f& support_plane,
                                                const Switchable<OcclusionMergeParams>& params);

}  // namespace multicue

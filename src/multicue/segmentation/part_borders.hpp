#pragma once
/// \file Where the parts of one object hypothesis meet (the part graph of thesis sections 4.2.1
/// and 5.1.1, with the geometry of every edge). The object's surface is cut into small voxel
/// patches (mean position, mean normal, majority part); two parts border each other where
/// patches of the two are voxel neighbours. Each border carries what the patch pairs along it
/// say: how many there are, how many meet convexly (or smoothly), how far their normals turn,
/// how far apart they lie and how much of that offset runs along the sensor's line of sight.
/// The concave split (convexity_split.hpp) and the learned grouping (border_classifier.hpp)
/// decide on these borders.

#include <cstddef>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "multicue/core/point_cloud.hpp"
#include "multicue/core/types.hpp"

namespace multicue {

struct PartBorderParams {
    float patch_size = 0.015f;       ///< edge of the voxel patches [m]; > 0
    float smooth_angle_deg = 12.0f;  ///< patch pairs whose normals differ less are smooth (and
                                     ///< count as convex) [deg], in [0, 90]
    float step_height = 0.004f;      ///< smooth pairs this far apart along their normal are a step
                                     ///< [m]; >= 0
    /// Throws InvalidArgument naming the first out-of-range field.
    void Validate() const;
};

/// One voxel patch of the object's surface: the mean of its points with a finite normal.
struct SurfacePatch {
    Eigen::Vector3f centroid = Eigen::Vector3f::Zero();
    Eigen::Vector3f normal = Eigen::Vector3f::Zero();  ///< unit mean normal (zero if they cancel)
    /// Unit normal of the plane through the patch's points (least squares, oriented like
    /// `normal`; `normal` where the points do not span a plane): the surface at the patch's own
    /// scale, without the smoothing of the point normals over neighbouring objects.
    Eigen::Vector3f plane_normal = Eigen::Vector3f::Zero();
    int part = -1;          ///< the part most of its points belong to, -1 if none
    std::size_t count = 0;  ///< points [points]
};

/// The border between parts a < b.
struct PartBorder {
    std::size_t a = 0;
    std::size_t b = 0;
    std::size_t pairs = 0;            ///< neighbouring patch pairs across the border [pairs]
    std::size_t convex = 0;           ///< of which meet convexly or smoothly [pairs]
    float median_angle_deg = 0.0f;    ///< median angle between the normals of a pair [deg]
    float mean_gap = 0.0f;            ///< mean centroid distance of a pair / patch size [-]
    float mean_ray_alignment = 0.0f;  ///< mean |cos| of the angle between a pair's offset and
                                      ///< the sensor's ray to it (1: one behind the other) [-]
    /// Mean of (n1 - n2).d / |d| over the pairs: the convexity test as a magnitude (> 0 convex,
    /// < 0 concave) [-]
    float mean_bend = 0.0f;
    /// Share of the pairs that are parallel (smooth) yet offset along their normal by more than
    /// step_height: two faces one in front of the other, not one face [-]
    float step_share = 0.0f;
    std::size_t plane_convex = 0;  ///< pairs convex by the patches' plane normals [pairs]
    float plane_bend = 0.0f;       ///< mean_bend by the patches' plane normals [-]
    /// Heights of the pairs' midpoints above the support plane (0 without one) [m].
    float min_height = 0.0f;
    float max_height = 0.0f;
    float mean_height = 0.0f;

    float ConvexShare() const {
        return pairs == 0 ? 0.0f : static_cast<float>(convex) / static_cast<float>(pairs);
    }
};

struct PartBorders {
    std::vector<SurfacePatch> patches;
    std::vector<Eigen::Vector3i> patch_cells;  ///< voxel of each patch (neighbours differ by 1)
    /// Per point of the object (in the order of `object`): its part, -1 if in none.
    std::vector<int> point_part;
    /// Per point of the object: its patch, SIZE_MAX without a finite position and normal.
    std::vector<std::size_t> point_patch;
    std::vector<std::size_t> part_patches;  ///< patches per part [patches]
    /// Per part, the mean bend between its own neighbouring patches (as PartBorder::mean_bend):
    /// > 0 a convex surface (the outside of a cup), < 0 a concave one (its inside), 0 flat [-]
    std::vector<float> part_bend;
    std::vector<PartBorder> borders;  ///< ordered by (a, b)
};

/// The patches of `object` (indices into `cloud`, which needs normals) and the borders between
/// its `parts` (subsets of `object`; a point listed in several parts belongs to the last).
/// Convex: for two patches with centroid offset d = c1 - c2, n1.d > n2.d (they bend away from
/// each other, normals oriented towards the sensor), or normals within smooth_angle_deg. The
/// line of sight runs from the cloud's sensor_origin; heights are measured above
/// `support_plane` (a, b, c, d, unit normal up; zero: all heights 0). Deterministic. Throws
/// DataError without normals, InvalidArgument for bad parameters or a part point outside
/// `object`.
PartBorders ComputePartBorders(const PointCloud& cloud, const Indices& object,
                               const std::vector<Indices>& parts, const PartBorderParams& params,
                               const Eigen::Vector4f& support_plane = Eigen::Vector4f::Zero());

}  // namespace multicue

#pragma once
/// \file What a border between two parts of one object hypothesis looks like, as numbers a learned
/// decision can weigh (same object or two): the border's own geometry (part_borders.hpp) and the
/// two parts it separates, measured against the support plane (heights, how upright their
/// surfaces stand, sizes). Thesis sections 5.1.1 (part graphs in clutter) and 5.4.1 (grouping
/// parts into objects).

#include <array>
#include <cstddef>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "multicue/core/point_cloud.hpp"
#include "multicue/core/types.hpp"
#include "multicue/segmentation/part_borders.hpp"

namespace multicue {

inline constexpr std::size_t kBorderFeatureCount = 26;

/// The features' names, in order (configuration keys of the learned weights).
inline constexpr std::array<std::string_view, kBorderFeatureCount> kBorderFeatureNames = {
    "log_pairs",           // log(1 + patch pairs on the border)
    "convex_share",        // share of the pairs meeting convexly or smoothly
    "median_angle",        // median angle between the normals of a pair [rad]
    "part_normal_angle",   // angle between the two parts' mean normals [rad]
    "log_small_part",      // log10 points of the smaller part
    "log_large_part",      // log10 points of the larger part
    "top_difference",      // difference of the parts' highest points above the plane [m]
    "lifted",              // the higher of the parts' lowest points above the plane [m]
    "stack_contact",       // |lowest point of the higher-based part - top of the other| [m]
    "min_upright",         // the smaller |mean normal . up| of the two parts
    "max_upright",         // the larger |mean normal . up|
    "border_length",       // pairs / sqrt(patches of the smaller part)
    "gap",                 // mean distance of a pair's centroids / patch size
    "ray_alignment",       // mean |cos| between a pair's offset and the line of sight
    "bend",                // mean (n1 - n2).d / |d| of the pairs (> 0 convex)
    "step_share",          // share of parallel pairs offset along their normal
    "min_spread",          // the smaller mean angle of a part's patch normals to its mean [rad]
    "max_spread",          // the larger one
    "plane_convex_share",  // convex_share by the patches' own plane normals
    "plane_bend",          // bend by the patches' own plane normals
    "border_span",         // height span of the border / that of the flatter-spanned part
    "at_base_of_upper",    // (border height - base of the higher part) / its height span
    "at_top_of_lower",     // (top of the lower part - border height) / its height span
    "min_part_bend",       // the more concave of the two parts' own bends (< 0: the inside of
                           // a hollow object)
    "max_part_bend",       // the more convex one
    "thin_wall",           // convex_share * max(0, -cos median_angle): surfaces facing away
                           // from each other across a convex edge, the rim of a thin wall
};

using BorderFeatures = std::array<float, kBorderFeatureCount>;

/// One part seen against the support plane, from its patches.
struct PartSummary {
    std::size_t points = 0;
    float top = 0.0f;     ///< highest patch centroid above the plane [m]
    float bottom = 0.0f;  ///< lowest patch centroid above the plane [m]
    Eigen::Vector3f normal = Eigen::Vector3f::Zero();  ///< unit mean normal (point-weighted)
    float spread = 0.0f;  ///< mean angle of its patch normals to `normal` (0: planar) [rad]
};

/// The summary of every part (`parts` as given to ComputePartBorders, `borders` its result)
/// against `plane` (a, b, c, d, unit normal up).
std::vector<PartSummary> SummarizeParts(const std::vector<Indices>& parts,
                                        const PartBorders& borders, const Eigen::Vector4f& plane);

/// The features of `border` between two of the summarised parts; heights are capped at 0.3 m.
/// `up` is the plane's unit normal.
BorderFeatures ComputeBorderFeatures(const PartBorder& border, const PartBorders& borders,
                                     const std::vector<PartSummary>& parts,
                                     const Eigen::Vector3f& up);

}  // namespace multicue

#pragma once
/// \file Surface types from the two RSD radii (thesis section 2.5.2, Figure 2.21).
///
/// The type follows from successive checks of r_min and r_max [m]: planar if r_min > 0.1;
/// otherwise cylindrical if r_max > 0.175; otherwise sharp edge/corner (or noise) if
/// r_min < 0.015; otherwise spherical if r_max - r_min < 0.05; otherwise rim (a transition between
/// surfaces). The numeric values are those of PCL's GRSDEstimation::getSimpleType, so histograms
/// built from them have the same bin layout as PCL's GRSD.

#include <cstdint>
#include <string_view>
#include <vector>

#include "multicue/features/feature_common.hpp"

namespace multicue {

enum class SurfaceType : std::uint8_t {
    kEdge = 0,      ///< sharp edge or corner, or noise
    kPlane = 1,     ///< planar
    kCylinder = 2,  ///< cylindrical
    kSphere = 3,    ///< spherical
    kRim = 4,       ///< the remaining cases: boundaries and transitions between surfaces
    kUndefined = 255,
};

/// Number of surface types (the defined ones).
inline constexpr int kNumSurfaceTypes = 5;

/// Lower-case name ("edge", "plane", "cylinder", "sphere", "rim", "undefined").
std::string_view SurfaceTypeName(SurfaceType type);

/// The thresholds of section 2.5.2 [m].
struct SurfaceTypeThresholds {
    float min_radius_plane = 0.100f;       ///< r_min above this: plane
    float min_radius_cylinder = 0.175f;    ///< r_max above this: cylinder
    float max_radius_edge = 0.015f;        ///< r_min below this: edge/corner/noise
    float max_radius_difference = 0.050f;  ///< r_max - r_min below this: sphere
};

/// The type of a surface with radii r_min <= r_max [m]; kUndefined if either is not finite.
SurfaceType ClassifySurface(float r_min, float r_max, const SurfaceTypeThresholds& thresholds = {});

/// The type of every row of an RSD matrix (n x 2: r_min, r_max); NaN rows give kUndefined.
/// Throws InvalidArgument if the matrix does not have 2 columns.
std::vector<SurfaceType> LabelSurfaceTypes(const FeatureMatrix& rsd,
                                           const SurfaceTypeThresholds& thresholds = {});

}  // namespace multicue

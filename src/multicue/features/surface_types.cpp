#include "multicue/features/surface_types.hpp"

#include <cmath>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"

namespace multicue {

std::string_view SurfaceTypeName(SurfaceType type) {
    switch (type) {
        case SurfaceType::kEdge:
            return "edge";
        case SurfaceType::kPlane:
            return "plane";
        case SurfaceType::kCylinder:
            return "cylinder";
        case SurfaceType::kSphere:
            return "sphere";
        case SurfaceType::kRim:
            return "rim";
        case SurfaceType::kUndefined:
            break;
    }
    return "undefined";
}

SurfaceType ClassifySurface(float r_min, float r_max, const SurfaceTypeThresholds& t) {
    if (!std::isfinite(r_min) || !std::isfinite(r_max)) return SurfaceType::kUndefined;
    // Section 2.5.2: successive checks, the first that holds decides.
    if (r_min > t.min_radius_plane) return SurfaceType::kPlane;
    if (r_max > t.min_radius_cylinder) return SurfaceType::kCylinder;
    if (r_min < t.max_radius_edge) return SurfaceType::kEdge;
    if (r_max - r_min < t.max_radius_difference) return SurfaceType::kSphere;
    return SurfaceType::kRim;
}

std::vector<SurfaceType> LabelSurfaceTypes(const FeatureMatrix& rsd,
                                           const SurfaceTypeThresholds& thresholds) {
    if (rsd.cols() != 2) {
        throw InvalidArgument(
            fmt::format("surface types need an RSD matrix with 2 columns, got {}", rsd.cols()));
    }
    std::vector<SurfaceType> types(static_cast<std::size_t>(rsd.rows()));
    for (Eigen::Index i = 0; i < rsd.rows(); ++i) {
        types[static_cast<std::size_t>(i)] = ClassifySurface(rsd(i, 0), rsd(i, 1), thresholds);
    }
    return types;
}

}  // namespace multicue

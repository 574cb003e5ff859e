#pragma once
/// \file Convex hull of points on a plane and the polygonal prism above it: the region of interest
/// for objects standing on a support surface (thesis section 2.4).

#include <vector>

#include <Eigen/Core>

#include "multicue/core/point_cloud.hpp"
#include "multicue/core/types.hpp"

namespace multicue {

/// Convex hull of the given points (or of all finite points when `subset` is empty) projected onto
/// `plane` (a, b, c, d with unit normal). Vertices are on the plane, counter-clockwise seen from
/// the side the normal points to, without repeated or collinear vertices. Fewer than three distinct
/// projected points give the degenerate hull (those points). Throws InvalidArgument when the plane
/// normal is not unit length.
std::vector<Eigen::Vector3f> PlaneConvexHull(const PointCloud& cloud, const Indices& subset,
                                             const Eigen::Vector4f& plane);

struct PrismParams {
    float min_height = 0.01f;  ///< lowest height above the plane that counts [m]
    float max_height = 0.50f;  ///< highest height above the plane that counts [m]
    /// FindTableRegion: objects standing beyond the visible table (at its back, where the objects
    /// in front hide the table around them) are taken too: clusters above the plane outside the
    /// hull, reaching within 3 cm of it, no farther than this from it, and no higher than
    /// max_height (a wall behind the table rises above it) [m]; 0 = off.
    float edge_reach = 0.15f;
    /// Throws InvalidArgument naming the first out-of-range field.
    void Validate() const;
    /// Its parameters once each: configuration key (the field's name), field, meaning. A
    /// visitor reads or records them (io::ConfigSection::operator(); ReadPerceiveParams).
    template <typename V>
    void VisitParams(V& v) {
        v("min_height", min_height, "lowest object point above the table [m]");
        v("max_height", max_height, "highest object point above the table [m]");
        v("edge_reach", edge_reach,
          "objects standing up to this far beyond the table's visible hull are taken too, 0 = "
          "off [m]");
    }
};

/// Points whose height above `plane` (along its normal) lies in [min_height, max_height] and whose
/// projection falls inside the convex polygon `hull` (as returned by PlaneConvexHull). NaN points
/// are never inside. Indices ascending. Throws InvalidArgument when min_height > max_height or the
/// hull has fewer than three vertices. `num_threads` (0 = all cores) does not change the result.
Indices PolygonalPrism(const PointCloud& cloud, const Eigen::Vector4f& plane,
                       const std::vector<Eigen::Vector3f>& hull, const PrismParams& params,
                       int num_threads = 1);

}  // namespace multicue

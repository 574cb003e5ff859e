#pragma once
/// \file Floors of low objects. A plate's or a tray's inner floor lies a few millimetres above
/// the table, below the prism's lowest height, and is cut away with the table: the object keeps
/// its rim alone. The points of that band that an object's own points enclose on every side,
/// seen from above and, in an organized frame, in the image as well, are its floor: the table
/// cannot show through an object, except through a hole, which every side must close.

#include <vector>

#include <Eigen/Core>

#include "multicue/core/point_cloud.hpp"
#include "multicue/core/types.hpp"

namespace multicue {

struct EnclosedFloorParams {
    /// Objects whose highest point lies at most this far above the plane may have a floor
    /// below the prism (plates are 1.5-3 cm high, trays a little more) [m]
    float max_object_height = 0.05f;
    /// ... and whose bounding rectangle in the plane is at most this long (wider objects are
    /// neither dishes nor trays, and bound the grid's size) [m]
    float max_object_width = 1.0f;
    /// Floor points lie at most this far below the plane (its noise) [m]; >= 0
    float below = 0.012f;
    /// Grid cell of the enclosure test, across the plane [m]; > 0
    float cell = 0.01f;
    /// Throws InvalidArgument naming the first out-of-range field.
    void Validate() const;
    template <typename V>
    void VisitParams(V& v) {
        v("max_object_height", max_object_height,
          "objects up to this high may have a floor below the prism [m]");
        v("max_object_width", max_object_width,
          "objects up to this long across the table may have such a floor [m]");
        v("below", below, "floor points lie at most this far below the table plane [m]");
        v("cell", cell, "grid cell of the enclosure test [m]");
    }
};

/// For each of `objects` (point indices into `cloud`) whose points rise at most
/// max_object_height above `plane` (a, b, c, d, normal pointing up) and span at most
/// max_object_width across it, the points of the band from -below to `min_height` above the plane
/// that lie in a grid cell (cell metres, in the plane) that the object's own cells enclose: in
/// each of the eight grid directions an object cell lies before the object's bounding rectangle
/// ends. In an organized cloud the point's pixel must also be enclosed so by the object's pixels
/// (seen obliquely, the table under an overhanging rim lies inside the outline from above but
/// beside the object in the image). Points of any object are never taken; a point enclosed by
/// two objects goes to the first. Returns one ascending list per object (empty for high ones).
/// Non-finite points and a zero plane give nothing. Throws InvalidArgument for bad parameters, a
/// non-finite plane or an index out of range.
std::vector<Indices> EnclosedFloors(const PointCloud& cloud, const Eigen::Vector4f& plane,
                                    const std::vector<Indices>& objects, float min_height,
                                    const EnclosedFloorParams& params = {});

}  // namespace multicue

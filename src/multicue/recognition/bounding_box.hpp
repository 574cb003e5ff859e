#pragma once
/// \file Bounding geometry of object point sets, shared by the geometric categoriser and the
/// primitive model fits (thesis section 5.4.2.1): the 2D convex hull and its minimum-area
/// rectangle (rotating calipers), the upright box of an object standing on a support plane, an
/// approximate minimum-volume oriented box, and the rotation about "up" that best aligns the
/// surface normals with the faces of a box.

#include <cstddef>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "multicue/core/point_cloud.hpp"
#include "multicue/core/types.hpp"

namespace multicue {

/// A rectangle in the plane.
struct Rectangle2d {
    Eigen::Vector2f center = Eigen::Vector2f::Zero();  ///< centre [m]
    Eigen::Vector2f axis = Eigen::Vector2f::UnitX();   ///< unit direction of the first side
    Eigen::Vector2f size = Eigen::Vector2f::Zero();    ///< side lengths along `axis` and along its
                                                       ///< left perpendicular, size.x() >= size.y()
                                                       ///< [m]
    float Area() const { return size.x() * size.y(); }
};

/// A box in 3D.
struct OrientedBox {
    Eigen::Vector3f center = Eigen::Vector3f::Zero();    ///< centre [m]
    Eigen::Matrix3f axes = Eigen::Matrix3f::Identity();  ///< unit axes as columns, right-handed
    Eigen::Vector3f extents = Eigen::Vector3f::Zero();   ///< side lengths along the axes [m]
};

/// Convex hull of 2D points, counter-clockwise, without repeated or collinear vertices (Andrew's
/// monotone chain). Non-finite points are skipped. Fewer than three distinct points give those
/// points (a segment, a single point or nothing).
std::vector<Eigen::Vector2f> ConvexHull2d(std::vector<Eigen::Vector2f> points);

/// Signed area of a simple polygon, positive for counter-clockwise vertices [m^2].
float PolygonArea(const std::vector<Eigen::Vector2f>& polygon);

/// Minimum-area rectangle enclosing a convex polygon given counter-clockwise (as ConvexHull2d
/// returns it), by rotating calipers: one side of the optimal rectangle is collinear with an edge
/// of the hull (Freeman and Shapira, 1975), so the hull's edges are the only candidates. A single
/// point gives a zero-size rectangle there, two points the segment between them. An empty polygon
/// gives a zero rectangle at the origin.
Rectangle2d MinAreaRectangle(const std::vector<Eigen::Vector2f>& hull);

/// The support plane as a unit-normal plane (a, b, c, d), or none for the zero vector ("unknown").
/// Any other plane is scaled so that (a, b, c) has unit length. Throws InvalidArgument if it is not
/// finite or its normal is zero while d is not.
std::optional<Eigen::Vector4f> NormalizeSupportPlane(const Eigen::Vector4f& plane);

/// Upright bounding box of an object standing on the (unit-normal) support plane: its footprint is
/// the minimum-area rectangle of the points projected onto the plane, its bottom lies in the plane
/// (the object stands on it even though its underside is unseen) and its top at the highest point.
/// axes.col(2) is the plane normal, axes.col(0) the longer side of the footprint, so extents are
/// (length, width, height). Non-finite points are skipped; no usable point gives a zero box.
/// Throws InvalidArgument for an index out of range.
OrientedBox UprightBoundingBox(const PointCloud& cloud, const Indices& indices,
                               const Eigen::Vector4f& unit_plane);

/// Approximate minimum-volume oriented bounding box: each principal axis of the points is tried
/// as one box axis, with the minimum-area rectangle of the points projected onto the orthogonal
/// plane for the two others; the smallest of the three boxes wins. Extents are sorted descending
/// (axes.col(0) along the longest side). Non-finite points are skipped; no usable point gives a
/// zero box. Throws InvalidArgument for an index out of range.
OrientedBox MinVolumeBoundingBox(const PointCloud& cloud, const Indices& indices);

/// How well the normals of a point set match the faces of an upright box.
struct FaceAlignment {
    bool found = false;  ///< enough near-horizontal normals to fix the rotation about up
    /// Unit axes as columns: col(2) = up, col(0) the side normal direction found, col(1) =
    /// up x col(0).
    Eigen::Matrix3f axes = Eigen::Matrix3f::Identity();
    std::size_t num_normals = 0;   ///< points with a finite position and normal [points]
    std::size_t num_aligned = 0;   ///< of which within max_angle of +-col(0), +-col(1) or +-col(2)
    std::size_t num_vertical = 0;  ///< of which within max_angle of +-up [points]
    float aligned_ratio = 0.0f;    ///< num_aligned / num_normals, 0 without normals [-]
};

/// Finds the rotation about `up` (unit) that puts the most near-horizontal normals (elevation at
/// most max_angle) within max_angle of one of the four horizontal axis directions: a sliding
/// window of width 2 max_angle over the normals' azimuths modulo 90 degrees, refined to the mean
/// azimuth inside the best window. The counts then use the exact 3D angle to the three axes
/// ("axis_area" of the data README, per point rather than per area). The cloud must have normals
/// (their sign is ignored). Fewer than `min_side_normals` near-horizontal normals give
/// found = false, axes built from an arbitrary horizontal direction, and counts for those axes.
/// Throws InvalidArgument for an index out of range or max_angle outside (0, pi/4], DataError if
/// the cloud has no normals (unless no index is given).
FaceAlignment AlignUprightAxes(const PointCloud& cloud, const Indices& indices,
                               const Eigen::Vector3f& up, float max_angle,
                               std::size_t min_side_normals = 3);

}  // namespace multicue

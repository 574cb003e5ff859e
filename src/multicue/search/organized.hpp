#pragma once
/// \file Image-space neighbourhoods for organized clouds (RGB-D frames, NaN = invalid pixel).
///
/// A neighbourhood is the set of finite pixels in a square window around a centre pixel, optionally
/// limited to a 3D radius around the centre point. On a 640x480 frame this is much faster than a
/// k-d tree: no build, and a query touches only (2*half_window+1)^2 contiguous pixels.
///
/// The queries allocate nothing once the output vectors (and, for the k-nearest search, one
/// per-thread scratch buffer) have grown to the window size, check their arguments on entry (a few
/// comparisons), and are safe to run from many threads at once.

#include <cstddef>
#include <cstdint>
#include <limits>
#include <optional>
#include <span>
#include <vector>

#include "multicue/core/point_cloud.hpp"
#include "multicue/core/types.hpp"

namespace multicue {

struct OrganizedSearchParams {
    int half_window = 3;  ///< half-size of the square pixel window [pixels]: 3 examines 7x7 pixels
    float radius = std::numeric_limits<float>::infinity();  ///< max 3D distance to the centre
                                                            ///< point [m]; infinity = whole window
    /// Pixels that may be neighbours: one entry per pixel, 0 = never a neighbour (as if it were
    /// invalid). Empty = every finite pixel. The centre need not be in it.
    std::span<const std::uint8_t> mask = {};
};

/// Finite pixels in the window around pixel `center` whose 3D distance to the centre point is
/// <= params.radius, the centre itself included (distance 0). Results come in ascending index
/// order (row-major window scan) with their squared distances. A non-finite centre has no
/// neighbours (returns 0). Throws InvalidArgument if the cloud is not organized, `center` is out
/// of range, half_window < 1, radius is not > 0, or a mask is given whose size is not the cloud's.
std::size_t OrganizedRadiusSearch(const PointCloud& cloud, Index center,
                                  const OrganizedSearchParams& params, Indices& indices,
                                  std::vector<float>& squared_distances);

/// The k finite pixels of the window nearest in 3D to the centre point (and within params.radius),
/// the centre itself included, nearest first; equal distances are ordered by index. Returns how
/// many were found (fewer than k when the window holds fewer). Same errors as
/// OrganizedRadiusSearch, and InvalidArgument if k < 1.
std::size_t OrganizedKnnSearch(const PointCloud& cloud, Index center, int k,
                               const OrganizedSearchParams& params, Indices& indices,
                               std::vector<float>& squared_distances);

/// Approximate focal length [pixels] of the pinhole camera that produced an organized cloud.
///
/// Method: a pinhole camera maps a point to column u = f * x/z + c_x, so in every image row u is a
/// linear function of x/z with slope f. The points are first brought into the sensor frame (the
/// inverse of sensor_origin/sensor_orientation), then a least-squares line u = f * (x/z) + c is
/// fitted per row over its finite points with z != 0, and the median |f| over the rows with at
/// least 8 such points is returned. Clouds computed from a depth image reproduce f to a fraction
/// of a percent; the sign of z (cameras looking along -z) does not matter.
/// Throws InvalidArgument if the cloud is not organized and DataError if no row has 8 usable
/// points spread over at least two columns.
float EstimateFocalLength(const PointCloud& cloud);

/// Window half-size [pixels] that covers a sphere of `radius` [m] around a point at `depth` [m]
/// for a camera of `focal_length` [pixels]: ceil(radius * focal_length / |depth|), at least 1.
/// It is exact for points on the optical axis; towards the corners of a 640x480 frame with
/// f = 525 the sphere spans up to 1.17 times as many pixels (the rays spread less per pixel off
/// axis), so callers that must not miss a neighbour (clustering) should scale the result by 1.2.
/// The result is clamped to 1'000'000. Throws InvalidArgument if radius or focal_length is not > 0
/// and finite or depth is zero or not finite.
int WindowHalfSizeForRadius(float radius, float depth, float focal_length);

/// An unorganized cloud that came from a depth image (a frame saved without its invalid pixels)
/// put back on its pixel grid.
struct ImageGrid {
    PointCloud organized;  ///< width x height, NaN where no input point fell; all input fields
    Indices input_of;      ///< per pixel: the input point's index, or kNoPoint
    Indices pixel_of;      ///< per input point: its pixel, or kNoPoint (a non-finite point)
    static constexpr Index kNoPoint = std::numeric_limits<Index>::max();
};

/// Recovers the pixel grid of an unorganized cloud in the optical frame of a pinhole camera
/// (sensor at the origin; a VIEWPOINT rotation alone is a viewer convention and is ignored; every
/// point in front along +z, or every point along -z): x/z and y/z of such points take values
/// (u - c_x) / f_x and (v - c_y) / f_y on two lattices. The pitch of each lattice is
/// the median gap between neighbouring distinct values; the grid is accepted when at least 99 %
/// of the points lie within a tenth of a pixel of a lattice node, no two points share a pixel,
/// and the image has at most 4096 x 4096 pixels and 8 times as many pixels as points. Returns
/// nothing otherwise (a cloud that was filtered, merged from several views, transformed into a
/// world frame, or from a laser scanner), and for organized or empty clouds. `num_threads`
/// (0 = all cores) does not change the result.
std::optional<ImageGrid> RecoverImageGrid(const PointCloud& cloud, int num_threads = 1);

}  // namespace multicue

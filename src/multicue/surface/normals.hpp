#pragma once
/// \file Surface normals and curvature by principal component analysis of local neighbourhoods
/// (thesis sections 2.3.1 and 3.2.1): the normal at a point is the eigenvector of the smallest
/// eigenvalue of its neighbourhood's covariance matrix, and the curvature is PCL's surface
/// variation lambda0 / (lambda0 + lambda1 + lambda2), 0 on a plane and at most 1/3.
///
/// Every neighbourhood includes the query point itself. A point gets a NaN normal and curvature,
/// and counts as `undefined`, when its coordinates are not finite, when its neighbourhood has
/// fewer than 3 points, or when all of them coincide. Defined normals are unit vectors oriented
/// towards the viewpoint: n . (viewpoint - p) >= 0.
///
/// Results do not depend on the thread count: every point's normal is computed independently
/// with a fixed summation order, so 1, 2 or all threads give bit-identical output.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "multicue/core/point_cloud.hpp"
#include "multicue/search/kdtree.hpp"

namespace multicue {

/// Neighbours used by the k-nearest mode when neither k nor radius is set (PCL's and Open3D's
/// tutorials use 10-30).
inline constexpr int kDefaultNormalK = 20;

struct NormalParams {
    /// Neighbours for k-NN PCA [points], >= 3; used when radius == 0. With radius == 0 too,
    /// 0 means kDefaultNormalK.
    int k = 0;
    /// Neighbourhood radius [m]; when > 0 a radius search is used, and k > 0 then keeps only the
    /// k nearest points within the radius.
    float radius = 0.0f;
    /// Point the normals are oriented towards [m]; default: the cloud's sensor_origin.
    std::optional<Eigen::Vector3f> viewpoint = std::nullopt;
    int num_threads = 0;  ///< 0 = all cores
    /// Throws InvalidArgument naming the first out-of-range field.
    void Validate() const;
    /// Its parameters once each: configuration key (the field's name), field, meaning. A
    /// visitor reads or records them (io::ConfigSection::operator(); ReadPerceiveParams).
    template <typename V>
    void VisitParams(V& v) {
        v("k", k, "neighbours of the PCA [points]");
        v("radius", radius, "neighbourhood radius [m], 0 = use k only");
    }
};

struct NormalsResult {
    std::vector<Eigen::Vector3f> normals;  ///< one unit normal per point, NaN where undefined
    std::vector<float> curvature;          ///< surface variation in [0, 1/3], NaN where undefined
    /// Points with non-finite coordinates, fewer than 3 neighbours or coincident neighbours.
    std::size_t undefined = 0;
};

/// Normals of every point of `cloud` from neighbourhoods found in `tree`, which must have been
/// built from this cloud (all of it or a subset: points outside the subset still get normals
/// from the indexed neighbours around them).
///
/// Radius mode sums precomputed moments of the tree nodes that lie wholly inside the query
/// sphere and visits single points only in the leaves cut by its surface: the neighbourhood is
/// exactly the set of points within the radius, but a large one costs far less than visiting
/// each of its points. k-NN mode finds the neighbourhoods leaf by leaf, each query bounded by the
/// k-th neighbour distances of the queries before it; equal distances are resolved by tree
/// position, so the k nearest are well defined even on the pixel grid of a depth camera.
///
/// Throws InvalidArgument if k < 0, 0 < k < 3, radius < 0 or not finite, num_threads < 0, or the
/// tree was not built from this cloud. An empty cloud gives an empty result.
NormalsResult EstimateNormals(const PointCloud& cloud, const KdTree& tree,
                              const NormalParams& params);

/// Image-space normal estimation for organized clouds (RGB-D frames, NaN = invalid pixel).
///
/// Each pixel's neighbourhood is the square window of pixels around it (sampled every `stride`
/// pixels), without those whose depth differs from the centre's by more than
/// max_depth_change * depth^2. Kinect depth noise (and its disparity quantization step) grows
/// with depth^2, and this threshold separates a foreground object from the background behind it
/// while keeping slanted surfaces whole. Depth is the distance to the cloud's sensor_origin, so
/// the threshold does not depend on the frame the cloud is expressed in.
///
/// Why a window sum rather than integral images of the covariance terms (Holzer et al., 2012):
/// integral images cost O(1) per pixel whatever the window, but box sums cannot drop the
/// neighbours behind a depth edge per centre pixel, so normals along object outlines mix
/// foreground and background (PCL shrinks the window near edges instead). Sampling the window
/// with a stride keeps the cost at 7x7 reads per pixel for any window size (about 30 ms per
/// Kinect frame on one core) while the window spans enough surface to average Kinect noise: on
/// real frames the default 19x19 window agrees with 2 cm radius normals to 2.1 degrees on
/// average (median 1.5), a dense 7x7 window only to 7.6.
struct OrganizedNormalParams {
    /// Half-size of the square pixel window [pixels]: 9 spans 19x19 pixels, about +-1.7 cm at
    /// 1 m on a Kinect (focal length 525 pixels).
    int half_window = 9;
    /// Step between the pixels read in the window [pixels], at most half_window; 0 picks
    /// ceil(half_window / 3), which reads at most 7x7 pixels.
    int stride = 0;
    /// Scale the half-size with depth: half_window at 1 m, proportionally larger further away
    /// (at most 3 * half_window) and smaller nearer (at least 1), so that the averaging keeps up
    /// with noise growing as depth^2. With an automatic stride the cost hardly grows.
    bool depth_dependent_window = false;
    /// A neighbour is used only if its depth differs from the centre's by at most
    /// max_depth_change * depth^2 [1/m].
    float max_depth_change = 0.02f;
    /// Point the normals are oriented towards [m]; default: the cloud's sensor_origin.
    std::optional<Eigen::Vector3f> viewpoint = std::nullopt;
    /// Pixels to compute normals for (non-zero), one entry per pixel; empty = all. The windows
    /// still read every valid pixel; the others get NaN normals (counted as undefined).
    std::vector<std::uint8_t> mask = {};
    int num_threads = 0;  ///< 0 = all cores
    /// Throws InvalidArgument naming the first out-of-range field.
    void Validate() const;
    /// Its parameters once each: configuration key (the field's name), field, meaning. A
    /// visitor reads or records them (io::ConfigSection::operator(); ReadPerceiveParams).
    template <typename V>
    void VisitParams(V& v) {
        v("half_window", half_window, "half-size of the pixel window [px]");
        v("stride", stride, "step between the pixels read, 0 = automatic [px]");
        v("depth_dependent_window", depth_dependent_window, "scale the window with depth");
        v("max_depth_change", max_depth_change,
          "neighbours within this depth difference at 1 m [m]");
    }
};

/// Normals of an organized cloud from image-space windows (see OrganizedNormalParams).
/// Throws InvalidArgument if the cloud is not organized (and not empty), half_window is not in
/// [1, 100], stride is not in [0, half_window], max_depth_change is not > 0 and finite, or
/// num_threads < 0. An empty cloud gives an empty result.
NormalsResult EstimateNormalsOrganized(const PointCloud& organized,
                                       const OrganizedNormalParams& params);

/// Moves the normals and curvature of `result` into `cloud`. Throws InvalidArgument if their
/// sizes differ from the cloud's.
void SetNormals(PointCloud& cloud, NormalsResult result);

/// Normals of a sensor frame, organized or not: the settings of both paths.
struct FrameNormalParams {
    /// Organized frames (image-space fast path). A 15x15 window read every 3rd pixel (about
    /// 2.7 cm at 1 m): wide enough to smooth Kinect noise, narrow enough to keep the faces of a
    /// 9 cm box apart.
    OrganizedNormalParams organized{.half_window = 7};
    /// Unorganized clouds: k-NN PCA on a k-d tree of the whole cloud.
    NormalParams unorganized{.k = 20};
    /// Throws InvalidArgument naming the first out-of-range field of either path.
    void Validate() const;
    /// Its parameters once each: configuration key (the field's name), field, meaning. A
    /// visitor reads or records them (io::ConfigSection::operator(); ReadPerceiveParams).
    template <typename V>
    void VisitParams(V& v) {
        v.Node("organized", organized);
        v.Node("unorganized", unorganized);
    }
};

/// Normals and curvature of the points `region` of a frame (indices into `cloud`): an organized
/// frame takes the image-space path for those pixels only (the others get NaN; `organized.mask`
/// is replaced), any other cloud k-NN PCA over all its points. Throws InvalidArgument for bad
/// parameters or indices out of range.
NormalsResult EstimateFrameNormals(const PointCloud& cloud, const Indices& region,
                                   const FrameNormalParams& params);

/// EstimateFrameNormals set on `cloud`, unless it has normals and curvature already.
void EnsureFrameNormals(PointCloud& cloud, const Indices& region, const FrameNormalParams& params);

}  // namespace multicue

#pragma once
/// \file Box and cylinder models of objects seen from one viewpoint, standing on a support plane
/// (thesis section 5.4.2.1), and their triangle meshes (section 5.4.2.3).
///
/// The unseen back of an object is hypothesised from its symmetry: a box's hidden sides are
/// placed at the far edges of its visible top, its bottom in the table plane; a cylinder is
/// completed around its axis and, when upright, down to the table.

#include <cstddef>
#include <cstdint>
#include <optional>

#include <Eigen/Core>

#include "multicue/core/point_cloud.hpp"
#include "multicue/core/triangle_mesh.hpp"
#include "multicue/core/types.hpp"
#include "multicue/reconstruction/fit_guidance.hpp"
#include "multicue/segmentation/sample_consensus.hpp"

namespace multicue {

struct BoxModel {
    bool found = false;  ///< a box was fitted (false for an object without usable points)
    Eigen::Vector3f center = Eigen::Vector3f::Zero();    ///< centre of the box [m]
    Eigen::Matrix3f axes = Eigen::Matrix3f::Identity();  ///< unit axes as columns, right-handed;
                                                         ///< col(2) = up for standing boxes
    Eigen::Vector3f extents = Eigen::Vector3f::Zero();   ///< full side lengths along the axes [m]
    float inlier_ratio = 0.0f;  ///< share of the object's points within inlier_threshold of the
                                ///< box surface [-]
};

struct CylinderModel {
    bool found = false;                                ///< a cylinder was fitted
    Eigen::Vector3f center = Eigen::Vector3f::Zero();  ///< middle of the axis segment [m]
    Eigen::Vector3f axis = Eigen::Vector3f::UnitZ();   ///< unit axis (along up when upright)
    float radius = 0.0f;                               ///< [m]
    float height = 0.0f;                               ///< length of the axis segment [m]
    float inlier_ratio = 0.0f;  ///< share of the object's points within inlier_threshold of the
                                ///< closed cylinder's surface (side and caps) [-]
};

struct BoxFitParams {
    float inlier_threshold = 0.01f;  ///< distance to the surface counted as inlier [m]; > 0
    bool use_normals = true;  ///< with cloud normals: orientation from the side faces' normals and
                              ///< faces placed at their points, not at the extreme points
    float face_angle_deg = 15.0f;      ///< a normal this close to a face normal marks a face point,
                                       ///< (0, 45] [deg]
    std::size_t min_face_points = 30;  ///< a face is placed at the median of its points only
                                       ///< with at least this many of them [points]; >= 1
    float edge_window = 0.01f;     ///< an unseen side is placed from the point density in the two
                                   ///< strips of this width next to the extreme point, which noise
                                   ///< pushes outwards; should exceed 3 sigma of the noise; 0 = at
                                   ///< the extreme point [m]
    bool rectangle_ransac = true;  ///< with normals: the footprint rectangle RANSAC
                                   ///< (FitFootprintRectangle) proposes an orientation too
    int rectangle_iterations = 500;  ///< its sample cap, >= 1 [samples]
    std::uint64_t seed = 1;          ///< its sampler seed [-]
    /// Throws InvalidArgument naming the first out-of-range field.
    void Validate() const;
    /// Its parameters once each: configuration key (the field's name), field, meaning. A
    /// visitor reads or records them (io::ConfigSection::operator(); ReadPerceiveParams).
    template <typename V>
    void VisitParams(V& v) {
        v("inlier_threshold", inlier_threshold, "box surface inlier distance [m]");
        v("use_normals", use_normals, "orient boxes by their side faces' normals");
        v("face_angle_deg", face_angle_deg, "face point normal tolerance [deg]");
        v("min_face_points", min_face_points, "points needed to place a face");
    }
};

struct FootprintRectangleParams {
    /// RANSAC (the thesis maximises the number of inliers) on the side points; the threshold is
    /// the footprint distance to the rectangle's boundary [m]. Weights are set from the guidance.
    SacParams sac{.method = SacMethod::kRansac,
                  .distance_threshold = 0.01f,
                  .p_success = 0.99,
                  .max_iterations = 500,
                  .seed = 1,
                  .max_refine_rounds = 0,
                  .normal_distance_weight = 0.0f,
                  .num_threads = 1};
    /// Side points have normals within this angle of perpendicular to up; the two normals of a
    /// sample must be parallel or perpendicular within it, (0, 45] [deg]
    float side_angle_deg = 15.0f;
    /// Share of the side points left out at each end of an axis when the rectangle's sides are
    /// placed at the extreme points (the oriented bounding box), against stray points; [0, 0.25]
    float trim = 0.01f;
};

/// A rectangle in the support plane: the footprint of an upright box.
struct FootprintRectangle {
    bool found = false;  ///< a rectangle with at least 2 inliers was found
    Eigen::Vector3f center = Eigen::Vector3f::Zero();   ///< centre, in the support plane [m]
    Eigen::Vector3f axis = Eigen::Vector3f::UnitX();    ///< unit first axis, in the plane
    Eigen::Vector2f extents = Eigen::Vector2f::Zero();  ///< side lengths along axis and
                                                        ///< up x axis [m]
    Indices inliers;              ///< side points within the threshold of its boundary
    double inlier_weight = 0.0;   ///< their summed shape prior (their count without one) [-]
    std::size_t side_points = 0;  ///< points with a normal perpendicular to up [points]
    int iterations = 0;           ///< samples drawn [samples]
    bool converged = false;       ///< stopped by Eq. (4.6) before max_iterations
};

/// Footprint rectangle of an upright box, fitted directly to the points whose normals are
/// perpendicular to up (statically stable boxes stand on a side; section 5.4.2.1), maximising
/// the number of inliers in a RANSAC loop:
/// - sample: two side points whose footprint normals are parallel or perpendicular (within
///   side_angle_deg); the orientation is their mean modulo 90 degrees;
/// - rectangle: the oriented bounding box of the side points in that orientation (trim of them
///   left out at each end);
/// - score: side points within the threshold of the rectangle's boundary in the footprint.
/// With guidance, planar points (large RSD r_min) are drawn more often and the shape prior
/// weights sampling and inlier counting (section 5.4.1). The final rectangle's inliers are
/// counted again. Fewer than 2 side points give found = false.
/// Throws InvalidArgument for bad parameters or guidance, a zero or non-finite plane or an index
/// out of range; DataError if the cloud has no normals (unless `indices` is empty).
FootprintRectangle FitFootprintRectangle(const PointCloud& cloud, const Indices& indices,
                                         const Eigen::Vector4f& support_plane,
                                         const FootprintRectangleParams& params = {},
                                         const FitGuidance& guidance = {});

/// Upright box of an object standing on the support plane (a, b, c, d), normal pointing up
/// (section 5.4.2.1: boxes stand on one of their sides):
/// - orientation about up: the rotation that aligns the most side normals with the box's faces
///   (AlignUprightAxes) when at least min_face_points side normals are seen, else the
///   minimum-area rectangle of the points projected onto the plane (rotating calipers over their
///   2D convex hull); with rectangle_ransac, the footprint rectangle RANSAC's orientation
///   (FitFootprintRectangle, guided by `guidance`) replaces it when its rectangle has more
///   (prior-weighted) inliers; then refined as the least-squares orientation of a rectangle through
///   the points of the seen sides (normals within face_angle_deg of a side's normal);
/// - each side: the median position of its points when at least min_face_points are seen, else
///   the far edge of all points, from their density next to the extreme one (edge_window);
/// - top: the median height of the top face's points when seen, else the highest point; bottom:
///   the plane (the box stands on it although its underside is unseen).
/// Without normals (or use_normals = false) the box is the minimum-area footprint rectangle with
/// such edges and the highest point as top.
/// axes.col(2) is up and axes.col(0) the longer footprint side, so extents = (length, width,
/// height). Points with non-finite coordinates are ignored; no usable point gives found = false.
/// Throws InvalidArgument for bad parameters or guidance, a zero or non-finite plane, or an index
/// out of range.
BoxModel FitUprightBox(const PointCloud& cloud, const Indices& indices,
                       const Eigen::Vector4f& support_plane, const BoxFitParams& params = {},
                       const FitGuidance& guidance = {});

/// Oriented bounding box of any object (for "other" objects): an approximate minimum-volume box
/// (each principal axis in turn with the minimum-area rectangle across it, MinVolumeBoundingBox),
/// extents sorted descending. Only inlier_threshold of `params` is used. No usable point gives
/// found = false. Throws InvalidArgument for bad parameters or an index out of range.
BoxModel FitOrientedBoundingBox(const PointCloud& cloud, const Indices& indices,
                                const BoxFitParams& params = {});

struct CylinderModelParams {
    SacParams sac{.method = SacMethod::kMsac,
                  .distance_threshold = 0.006f,
                  .p_success = 0.99,
                  .max_iterations = 5000,
                  .seed = 1,
                  .max_refine_rounds = 3,
                  .normal_distance_weight = 0.05f,
                  .num_threads = 0};  ///< the cylinder RANSAC (FitCylinder); its threshold mixes
                                      ///< metres and the normal angle, see SacParams
    float min_radius = 0.005f;        ///< smallest accepted radius [m]
    float max_radius = 0.3f;          ///< largest accepted radius [m]
    float upright_angle_deg = 10.0f;  ///< upright prior: axis within this angle of up [deg]
    bool allow_free_axis = true;   ///< with a known plane, also fit without the prior and keep that
                                   ///< cylinder when it explains clearly more points (a lying can)
    float free_axis_gain = 1.25f;  ///< "clearly more": at least this factor more inliers [-]; >= 1
    bool snap_to_support = true;   ///< with a known plane, an axis within upright_angle_deg of up
                                   ///< becomes up, and one within lying_angle_deg of the plane
                                   ///< stays parallel to it in the refinement
    float lying_angle_deg = 10.0f;  ///< lying: axis within this angle of the plane [deg]
    float side_distance = 0.006f;   ///< refinement: side points lie this close to the surface [m]
    float side_normal_angle_deg = 30.0f;  ///< ... with normals this close to radial [deg]
    int refine_rounds = 3;  ///< least-squares refits on the reselected side points [rounds]; >= 0
    bool extend_to_support = true;    ///< upright cylinders reach down to the support plane
    float cap_angle_deg = 15.0f;      ///< a normal this close to the axis marks a cap point [deg]
    std::size_t min_cap_points = 10;  ///< a cap fixes its end of the axis segment only with at
                                      ///< least this many points [points]; >= 1
    float inlier_threshold = 0.01f;   ///< distance to the surface for inlier_ratio [m]; > 0
    /// The hypotheses are drawn and scored on at most this many of the object's points (an even
    /// subset: the share of a surface they cover is the whole object's); the refinement, extent
    /// and inlier ratio use every point [points]; 0 = all
    std::size_t hypothesis_points = 3000;
    /// Throws InvalidArgument naming the first out-of-range field.
    void Validate() const;
    /// Its parameters once each: configuration key (the field's name), field, meaning. A
    /// visitor reads or records them (io::ConfigSection::operator(); ReadPerceiveParams).
    template <typename V>
    void VisitParams(V& v) {
        v.Node("sac", sac);
        v("hypothesis_points", hypothesis_points,
          "hypotheses on at most this many points, an even subset (0 = all)");
        v("min_radius", min_radius, "smallest radius [m]");
        v("max_radius", max_radius, "largest radius [m]");
        v("upright_angle_deg", upright_angle_deg, "upright prior tolerance [deg]");
        v("allow_free_axis", allow_free_axis, "also try a free axis");
        v("free_axis_gain", free_axis_gain, "free axis must explain this factor more");
        v("extend_to_support", extend_to_support, "upright cylinders reach the table");
        v("cap_angle_deg", cap_angle_deg, "cap point normal tolerance [deg]");
        v("min_cap_points", min_cap_points, "points needed to place a cap");
        v("inlier_threshold", inlier_threshold, "surface distance for inlier_ratio [m]");
    }
};

/// A cylinder found earlier (the categoriser's), the start of FitObjectCylinder's refinement.
struct CylinderStart {
    Eigen::Vector3f point = Eigen::Vector3f::Zero();  ///< a point on the axis [m]
    Eigen::Vector3f axis = Eigen::Vector3f::UnitZ();  ///< unit axis
    float radius = 0.0f;                              ///< [m]
};

/// Cylinder of an object (cans, cups, bottles; section 5.4.2.1).
/// 1. Hypothesis: `start` when given (a cylinder already fitted to the object, such as the
///    categoriser's; ignored when its radius is outside [min_radius, max_radius] or fewer than 5
///    side points lie on it), else RANSAC with normals (FitCylinder): two points with their normals
///    give two skew lines, their shortest connection the axis. With a known support plane
///    (non-zero) the axis is first searched within upright_angle_deg of up; with allow_free_axis
///    also without the prior, and the free cylinder wins when it has at least free_axis_gain times
///    the upright one's (prior-weighted) inliers. Without a plane the axis is free. With guidance,
///    curved points (small RSD r_min) are drawn more often and the shape prior weights sampling and
///    scoring (sections 5.4.1, 5.4.2.1); params.sac's own weights are then replaced.
/// 2. Refinement: least squares (Levenberg-Marquardt) of | dist(p, axis) - r | over the side
///    points (within side_distance of the surface, normal within side_normal_angle_deg of
///    radial; cap points never count), reselected refine_rounds times. The RANSAC inliers are
///    only a start: weighting by noisy normals keeps a biased subset of the side. With
///    snap_to_support an upright axis is set to up and only the axis position and radius move
///    ("enforcing an upright position for the axes results are more robust", section 5.4.2.1);
///    a lying axis only turns about up.
/// 3. Extent: the side points' extent along the axis; a visible cap (min_cap_points with normals
///    within cap_angle_deg of the axis, inside the rim, near an end) fixes that end at its median;
///    an upright cylinder with extend_to_support reaches down to the plane.
/// The axis points away from the plane (upright) or has a positive largest component. inlier_ratio
/// is over all object points with finite coordinates. Points without a finite normal do not take
/// part in the fit. No usable point, or no cylinder, gives found = false.
/// Throws InvalidArgument for bad parameters or guidance, a non-finite plane or an index out of
/// range; DataError if the cloud has no normals (unless `indices` is empty).
CylinderModel FitObjectCylinder(const PointCloud& cloud, const Indices& indices,
                                const Eigen::Vector4f& support_plane,
                                const CylinderModelParams& params = {},
                                const FitGuidance& guidance = {},
                                const std::optional<CylinderStart>& start = std::nullopt);

/// Distance of p to the surface of the solid box (inside or outside) [m].
float BoxSurfaceDistance(const BoxModel& box, const Eigen::Vector3f& p);

/// Distance of p to the surface of the solid cylinder, side and caps (inside or outside) [m].
float CylinderSurfaceDistance(const CylinderModel& cylinder, const Eigen::Vector3f& p);

/// Closed box mesh: 8 vertices, 12 triangles, counter-clockwise seen from outside (outward
/// normals). No colours; set vertex_colors to colour it. Throws InvalidArgument if the centre,
/// axes or extents are not finite or an extent is negative.
TriangleMesh BoxMesh(const BoxModel& box);

/// Closed cylinder mesh: `segments` vertices around each rim plus one at the centre of each cap,
/// 4 * segments triangles, counter-clockwise seen from outside. No colours. Throws
/// InvalidArgument if segments < 3, the axis is zero or the model is not finite, or the radius or
/// height is negative.
TriangleMesh CylinderMesh(const CylinderModel& cylinder, int segments = 32);

}  // namespace multicue

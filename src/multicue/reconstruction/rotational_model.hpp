#pragma once
/// \file Surfaces of revolution (bottles, bowls, pitchers, vases) from one view, thesis section
/// 5.4.2.2: first the rotation axis, then the contour (radius as a function of height), and the
/// hidden back side completed by the symmetry.
///
/// Axis. On a surface of revolution the line through a point along its normal meets the axis. For
/// an axis direction a, let m_i = (n_i x a) / |n_i x a|; the distance between the point's normal
/// line and an axis through c with direction a is |m_i . (p_i - c)|, linear in c. So for each
/// direction the best axis position is a small (2 unknowns) least-squares problem, solved with
/// truncated weights (points farther than `line_threshold` drop out, as in a consensus score), and
/// the direction is found by search over the sphere of directions: a Fibonacci grid of about
/// `grid_directions` directions (or within max_tilt_deg of a given up direction), the best few
/// refined by successively finer local grids. Points whose normal is within parallel_angle_deg of
/// the direction (caps, bottoms) carry no information about the axis position and add a small
/// constant cost. The cost is sum_i min(d_i^2, t^2): the truncated line-to-line distances.
///
/// Refinement (profile_refinement). Where the normals barely constrain the direction (a shallow
/// bowl's wall is close to a sphere, whose normal lines all meet in one point) the normal-line
/// axis can be 20 degrees off. The contour itself is a second criterion: about the true axis the
/// points' (height, radius) pairs lie on one thin curve, about a wrong one they smear. The side
/// points (normal more than parallel_angle_deg from the normal-line axis, normal line within
/// 2 line_threshold of it) are fitted by a linear spline of radius over height (knots about
/// profile_step apart) with Huber weights of scale profile_tolerance; points of the inner surface
/// (normal towards the axis: the inside of a bowl or pitcher) share the spline less a fitted wall
/// thickness. Cap points (bottoms, lids) give the same with height over radius (cap_weight). A
/// third score, the level of an end (rim_weight): the second highest point in each of 24 sectors
/// around the axis, at either end, should be at one height. The axis direction (2 angles) and
/// position (2 offsets) are found by Nelder-Mead from the best 3 of about 150 directions within
/// 30 degrees of the normal-line axis scored with all three (on every second point; the best end
/// is searched again on all of them), and the best result is polished on
/// the contour alone (the end level is biased on small tops such as a bottle's cap, where a
/// millimetre is degrees). At most profile_points points take part.
///
/// Contour. Heights h_i = (p_i - c) . a and radii rho_i = |p_i - c - h_i a| of the points within
/// line_threshold; the profile is the median radius per height bin of profile_step, empty bins
/// filled by interpolation, smoothed by a 3-bin median. With a support plane the profile reaches
/// down to it.

#include <vector>

#include <Eigen/Core>

#include "multicue/core/point_cloud.hpp"
#include "multicue/core/triangle_mesh.hpp"
#include "multicue/core/types.hpp"

namespace multicue {

struct RotationalFitParams {
    std::size_t max_points = 1000;     ///< at most this many points, an even stride [points]; >= 10
    float line_threshold = 0.008f;     ///< normal-line to axis distance of a consistent point [m]
    float parallel_angle_deg = 20.0f;  ///< normals this close to the axis do not constrain it [deg]
    int grid_directions = 4000;        ///< directions of the coarse search over the sphere; >= 100
    int refine_candidates = 4;         ///< best coarse directions refined locally; >= 1
    /// With an up direction: the axis within this angle of up [deg] (90 = any axis; small values
    /// give an upright prior).
    float max_tilt_deg = 90.0f;
    float profile_step = 0.005f;  ///< height bin of the contour [m]; > 0
    /// Refine the axis by the thinnest contour (see the file comment).
    bool profile_refinement = true;
    std::size_t profile_points = 1000;  ///< at most this many points in the refinement; >= 10
    float profile_tolerance = 0.003f;   ///< Huber scale of the contour residuals [m]; > 0
    float rim_weight = 1.0f;         ///< weight of the end level when choosing the start [-]; >= 0
    float cap_weight = 1.0f;         ///< weight of the caps' height-over-radius spread [-]; >= 0
    float inlier_threshold = 0.01f;  ///< radial distance to the contour of an inlier [m]; > 0
    float min_radius = 0.003f;       ///< contour radii below this are raised to it [m]
    int num_threads = 1;  ///< threads of the coarse axis search (0 = all cores); same result
    /// Throws InvalidArgument naming the first out-of-range field.
    void Validate() const;
    /// Its parameters once each: configuration key (the field's name), field, meaning. A
    /// visitor reads or records them (io::ConfigSection::operator(); ReadPerceiveParams).
    template <typename V>
    void VisitParams(V& v) {
        v("max_tilt_deg", max_tilt_deg, "axis within this angle of up [deg]");
        v("max_points", max_points, "points used by the axis search");
        v("grid_directions", grid_directions, "coarse axis directions (sphere)");
        v("line_threshold", line_threshold, "normal line to axis distance [m]");
        v("profile_step", profile_step, "contour height bin [m]");
        v("inlier_threshold", inlier_threshold, "surface distance of an inlier [m]");
        v("profile_refinement", profile_refinement,
          "refine the axis by the thinnest contour and the level rim");
    }
};

struct RotationalModel {
    bool found = false;
    Eigen::Vector3f origin = Eigen::Vector3f::Zero();  ///< point on the axis at height 0 [m]
    Eigen::Vector3f axis = Eigen::Vector3f::UnitZ();   ///< unit axis (away from the support)
    std::vector<float> heights;  ///< ascending heights of the contour samples along the axis [m]
    std::vector<float> radii;    ///< radius at each height [m]
    float inlier_ratio = 0.0f;   ///< share of points within inlier_threshold of the surface [-]
    float axis_cost = 0.0f;      ///< mean truncated squared line distance, relative to t^2 [-]
    /// Spread of the contour about the axis: root of the mean Huber loss of the radius residuals
    /// of the side points (0 without profile refinement) [m].
    float profile_spread = 0.0f;

    /// Radius at height h (linear interpolation; 0 outside the contour).
    float RadiusAt(float h) const;
};

/// Fits a surface of revolution to the object's points. `up` (unit, or zero for none) orients the
/// axis and bounds its tilt; `support_plane` (a, b, c, d with unit normal up, or zero for none)
/// extends the contour down to the plane. Points without finite coordinates or normals are
/// ignored; fewer than 10 usable points gives found = false. Deterministic.
/// Throws InvalidArgument for bad parameters or an index out of range; DataError if the cloud has
/// no normals (unless `indices` is empty).
RotationalModel FitRotationalModel(const PointCloud& cloud, const Indices& indices,
                                   const Eigen::Vector3f& up, const Eigen::Vector4f& support_plane,
                                   const RotationalFitParams& params = {});

/// Closed mesh of the surface: one ring of `segments` vertices per contour sample, caps at both
/// ends, counter-clockwise seen from outside. Empty for a model that was not found. Throws
/// InvalidArgument for segments < 3.
TriangleMesh RotationalMesh(const RotationalModel& model, int segments = 32);

}  // namespace multicue

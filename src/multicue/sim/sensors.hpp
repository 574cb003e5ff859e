#pragma once
/// \file Simulated range sensors over a RayCaster. Every scan is a multicue::PointCloud with
/// ground truth per point:
///   - `labels`: mOSD label of the surface hit (0 no return, 1 table, 2 floor, 3 wall,
///     10*(k+1) object k), see scene.hpp;
///   - extra field `category` (uint8): index into CategoryNames() (0: none, table, floor, wall);
///   - extra field `part` (uint16): 1 + index into the hit object's PartMesh::part_names
///     (0: no return).
/// Noise comes only from `seed`: every pixel/beam has its own random stream (rng.hpp), so the
/// output is byte-identical for any `num_threads`. See docs/simulation.md for the models.

#include <cstdint>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "multicue/core/point_cloud.hpp"
#include "multicue/sim/raycaster.hpp"

namespace multicue::sim {

/// Structured-light RGB-D camera (Kinect / Xtion class).
struct KinectParams {
    std::uint32_t width = 640;      ///< [px]
    std::uint32_t height = 480;     ///< [px]
    float fx = 525.0f;              ///< focal length [px]
    float fy = 525.0f;              ///< [px]
    float cx = 319.5f;              ///< principal point [px]
    float cy = 239.5f;              ///< [px]
    float baseline = 0.075f;        ///< projector offset along the camera's +x axis [m]
    float disparity_step = 0.125f;  ///< disparity quantisation [px] (1/8 sub-pixel)
    /// Target axial noise sigma(z) = axial_noise * z^2 [1/m] (Khoshelham & Elberink 2012); the
    /// Gaussian disparity noise is chosen so that it and the quantisation together give it.
    float axial_noise = 1.4e-3f;
    float lateral_noise_px = 0.6f;    ///< sigma of the pixel offset at depth edges [px]
    float edge_jump = 0.02f;          ///< depth difference to a neighbour that makes an edge [m]
    float min_range = 0.5f;           ///< no return closer than this (depth z) [m]
    float max_range = 4.0f;           ///< no return beyond this (depth z) [m]
    float max_incidence_deg = 78.0f;  ///< no return beyond this angle of ray and normal [deg]
    bool projector_shadow = true;     ///< drop points the projector cannot see
    float color_noise = 3.0f;         ///< sigma of the colour noise per channel [0..255]
    /// Share of the colour that follows the light: colour * (1 - shading + shading * cos), cos
    /// of the angle between the surface normal and the ray (a light at the camera). 0 = the
    /// surface colours as they are [0..1]
    float shading = 0.0f;
    int num_threads = 0;  ///< 0 = all cores; output does not depend on it
};

/// Tilting 2D laser (Hokuyo UTM-30LX class) on a pan-tilt head (section 4.2.5).
/// The cloud is organized by tilt step: row i = tilt step i, column j = beam j; NaN for no return.
/// Points are in the head's base frame (x forward, y left, z up; the tilt axis through the
/// origin), whose world pose is given to ScanLaser. `intensity` is the remission: the surface's
/// reflectance (RayCaster::HitReflectance, per material) times the cosine of the incidence angle,
/// with relative noise intensity_noise; 0 where there is no return.
struct LaserParams {
    float fov_deg = 270.0f;           ///< angular field of one scan line [deg]
    float beam_step_deg = 0.25f;      ///< angle between beams [deg]
    float tilt_min_deg = -10.0f;      ///< first tilt (negative = up) [deg]
    float tilt_max_deg = 60.0f;       ///< last tilt (positive = down) [deg]
    float tilt_step_deg = 0.5f;       ///< tilt increment between scan lines [deg]
    float range_noise = 0.01f;        ///< sigma of the range noise [m]
    float min_range = 0.1f;           ///< [m]
    float max_range = 30.0f;          ///< [m]
    float max_incidence_deg = 85.0f;  ///< [deg]
    float intensity_noise = 0.02f;    ///< relative sigma of the intensity [-]
    int num_threads = 0;
};

/// Time-of-flight camera (SwissRanger SR4000 class, section 2.7): organized 176x144 with
/// `intensity` = amplitude and `confidence` in [0, 1]. Radial noise sigma = noise_ref *
/// sqrt(A + ambient) / A (shot noise of signal and background), so it grows as the amplitude A
/// falls; A = albedo * cos(incidence) / r^2 with albedo from the surface colour's luminance.
/// Pixels that straddle a depth edge return a mix of both depths ("flying pixels").
struct TofParams {
    std::uint32_t width = 176;        ///< [px]
    std::uint32_t height = 144;       ///< [px]
    float fx = 223.0f;                ///< [px] (43.6 deg horizontal field)
    float fy = 223.0f;                ///< [px]
    float cx = 87.5f;                 ///< [px]
    float cy = 71.5f;                 ///< [px]
    float noise_ref = 0.0035f;        ///< sigma [m] at amplitude 1 (white surface at 1 m, head-on)
    float ambient = 0.2f;             ///< background light, in amplitude units
    float min_amplitude = 0.02f;      ///< no return below this amplitude
    float max_noise = 0.05f;          ///< no return where sigma exceeds this [m]
    float min_range = 0.3f;           ///< [m]
    float max_range = 5.0f;           ///< non-ambiguity range [m]
    float max_incidence_deg = 85.0f;  ///< [deg]
    float edge_jump = 0.03f;          ///< depth difference that makes a mixed pixel [m]
    int num_threads = 0;
};

/// Organized RGB-D scan in the camera's optical frame (x right, y down, z forward; sensor at the
/// origin): points (NaN where no return), colours, labels, `category`, `part`.
/// Throws InvalidArgument on bad params.
PointCloud ScanKinect(const RayCaster& caster, const Eigen::Isometry3f& T_world_camera,
                      const KinectParams& params, std::uint64_t seed);
/// Builds the BVH and scans once (use the RayCaster overload for several views).
PointCloud ScanKinect(const Scene& scene, const Eigen::Isometry3f& T_world_camera,
                      const KinectParams& params, std::uint64_t seed);

/// Tilting-laser scan in the head's base frame (see LaserParams).
PointCloud ScanLaser(const RayCaster& caster, const Eigen::Isometry3f& T_world_head,
                     const LaserParams& params, std::uint64_t seed);

/// Time-of-flight scan in the camera's optical frame with intensity and confidence.
PointCloud ScanTof(const RayCaster& caster, const Eigen::Isometry3f& T_world_camera,
                   const TofParams& params, std::uint64_t seed);

/// Gaussian disparity sigma [px] that, with the quantisation, gives the target axial noise.
float KinectDisparitySigma(const KinectParams& params);

}  // namespace multicue::sim

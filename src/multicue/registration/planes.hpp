#pragma once
/// \file Planar patches for registration (thesis section 2.2; Stanimirovic et al. 2013): the
/// flat regions of a scan (table top, walls, floor, box faces), found by normal-angle region
/// growing (segmentation module) and least-squares plane fits, matched between two scans and
/// turned into least-squares terms that join the point correspondences of ICP.
///
/// A matched pair (source patch P, target plane n . x + d = 0) contributes
///   sum over the points p of P of w (n . (T p) + d)^2,
/// the point-to-plane distance of every patch point to the infinite target plane. The sum is
/// computed exactly from the patch's moments (count, mean, scatter), so a patch of thousands of
/// points costs as much as one correspondence, and a plane still pulls where few of its points
/// have a partner (little overlap, a rough initial guess).

#include <cstddef>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "multicue/core/point_cloud.hpp"
#include "multicue/core/types.hpp"
#include "multicue/registration/registration_result.hpp"
#include "multicue/search/kdtree.hpp"

namespace multicue {

/// A planar region of a scan.
struct PlanarPatch {
    Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();   ///< unit, towards the sensor side
    double d = 0.0;                                      ///< plane: normal . x + d = 0 [m]
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();  ///< mean of the points [m]
    Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();   ///< sum of (p - c)(p - c)^T [m^2]
    Eigen::Vector2d extent = Eigen::Vector2d::Zero();    ///< RMS spread along the two in-plane
                                                         ///< principal axes, larger first [m]
    double rmse = 0.0;                                   ///< RMS distance to the plane [m]
    Indices indices;                                     ///< its points, ascending

    std::size_t size() const { return indices.size(); }
};

/// The patch moved by T (normal, offset, centroid and scatter).
PlanarPatch TransformPatch(const PlanarPatch& patch, const Eigen::Isometry3d& T);

struct PlaneExtractionParams {
    float radius = 0.03f;         ///< region growing neighbourhood [m]; > 0
    float max_angle_deg = 12.0f;  ///< normal deviation from the region's seed [deg], (0, 90]
    std::size_t min_points = 60;  ///< smaller patches are dropped [points]; >= 3
    float max_rmse = 0.01f;       ///< patches less flat than this are dropped [m]; > 0
    /// Patches narrower than this (RMS spread along their shorter in-plane axis) are dropped:
    /// a depth camera's far quantisation terraces are perfectly flat strips, not planes [m]
    float min_extent = 0.03f;
    /// Patches whose depth noise at their centroid (depth_noise * d^2, d from the cloud's
    /// sensor_origin) exceeds max_rmse are dropped; 0 = no depth model [1/m]
    float depth_noise = 0.0f;
    int max_planes = 16;            ///< the largest patches kept [patches]; >= 1
    float merge_angle_deg = 4.0f;   ///< patches of one plane (a table split by objects) whose
                                    ///< normals differ by less are merged [deg] ...
    float merge_distance = 0.015f;  ///< ... when their offsets differ by less [m]
    /// Throws InvalidArgument naming the first out-of-range field.
    void Validate() const;
};

/// Planar patches of `cloud`, which needs normals and curvature (PreprocessForRegistration),
/// largest first. `tree` indexes `cloud`. Throws InvalidArgument for bad parameters and
/// DataError for a cloud without normals; an empty cloud gives no patches.
std::vector<PlanarPatch> ExtractPlanarPatches(const PointCloud& cloud, const KdTree& tree,
                                              const PlaneExtractionParams& params);

struct PlaneMatchParams {
    float max_angle_deg = 8.0f;  ///< largest angle between matched normals [deg], (0, 90]
    float max_offset = 0.05f;    ///< largest distance of the source centroid from the target
                                 ///< plane [m]; > 0
    /// Largest distance between the centroids, relative to the larger patch's extent plus this
    /// slack [m]: patches of one plane far apart (two coplanar box faces) do not match; >= 0
    float centroid_slack = 0.15f;
    /// Throws InvalidArgument naming the first out-of-range field.
    void Validate() const;
};

/// A matched pair: indices into the source and target patch lists.
struct PlanePair {
    std::size_t source = 0;
    std::size_t target = 0;
};

/// For every source patch moved by T_target_source, among the target patches with a parallel
/// normal (same side), the source centroid within max_offset of their plane and their centroid
/// within reach, the one with the smallest offset / max_offset + centroid distance / reach;
/// source patches without one are left out. Several source patches may match one target patch.
std::vector<PlanePair> MatchPlanes(const std::vector<PlanarPatch>& source,
                                   const std::vector<PlanarPatch>& target,
                                   const Eigen::Isometry3d& T_target_source,
                                   const PlaneMatchParams& params);

/// Adds the Gauss-Newton terms of the pairs (see the file comment) at T_target_source, the twist
/// about `center`, each point of pair k's patch weighing weights[k] (one per pair), to H and g;
/// returns their cost. Throws InvalidArgument when the sizes differ.
double AddPlaneTerms(const std::vector<PlanarPatch>& source, const std::vector<PlanarPatch>& target,
                     const std::vector<PlanePair>& pairs, const std::vector<double>& weights,
                     const Eigen::Isometry3d& T_target_source, const Eigen::Vector3d& center,
                     Matrix6d& H, Vector6d& g);

}  // namespace multicue

#pragma once
/// \file Registration with plane correspondences (thesis section 2.2; Stanimirovic et al. 2013):
///   - RegisterPointsAndPlanes: ICP whose Gauss-Newton system holds the point-to-plane terms of
///     the point pairs and the terms of the matched planar patches (planes.hpp) together, the
///     planes matched again at every iteration;
///   - RegisterPlanesGlobal: alignment without any initial guess from three pairs of
///     non-parallel planes. Three plane normals fix the rotation (the rigid fit of the normals)
///     and the three plane offsets the translation (n_t . t = d_s - d_t per pair); every
///     consistent pairing of source and target triples (same angles between the normals) is a
///     hypothesis, scored by the planes it explains and then by point overlap, and the best few
///     are refined by RegisterPointsAndPlanes.

#include <cstddef>
#include <vector>

#include <Eigen/Geometry>

#include "multicue/core/point_cloud.hpp"
#include "multicue/registration/icp.hpp"
#include "multicue/registration/planes.hpp"
#include "multicue/registration/registration_result.hpp"
#include "multicue/search/kdtree.hpp"

namespace multicue {

struct PointPlaneParams {
    IcpParams icp{};              ///< the point part (method must be point-to-plane or symmetric)
    PlaneMatchParams matching{};  ///< patch pairs, matched again every iteration
    /// Weight of one patch point relative to one point pair (before robust and depth weights);
    /// 0 = points only [-]
    double plane_weight = 0.5;
    /// Throws InvalidArgument naming the first out-of-range field.
    void Validate() const;
};

/// Point and plane correspondences in one least-squares problem, from T_init. The patches are
/// those of ExtractPlanarPatches on `source` and `target` (indices into those clouds). Same
/// requirements, errors and result as RegisterIcp; reason mentions the matched planes.
RegistrationResult RegisterPointsAndPlanes(
    const PointCloud& source, const PointCloud& target, const KdTree* target_tree,
    const std::vector<PlanarPatch>& source_patches, const std::vector<PlanarPatch>& target_patches,
    const PointPlaneParams& params,
    const Eigen::Isometry3d& T_init = Eigen::Isometry3d::Identity());

struct PlaneGlobalParams {
    /// The three normals of a triple must be pairwise at least this far from parallel [deg],
    /// (0, 90]
    float min_triple_angle_deg = 25.0f;
    /// Angles between normals of the source triple and of the target triple may differ by this
    /// much [deg], (0, 45]
    float angle_tolerance_deg = 6.0f;
    /// Plane pairs agreeing with a hypothesis: its patch matching (extent-aware).
    PlaneMatchParams matching{.max_angle_deg = 6.0f, .max_offset = 0.04f};
    /// Hypotheses scored by point overlap, best by plane score first [hypotheses]; >= 1
    int max_point_scored = 200;
    std::size_t score_points = 1500;  ///< source points (evenly strided) scored [points]; >= 10
    float score_distance = 0.02f;     ///< a scored point overlaps within this distance [m]; > 0
    int refine_best = 3;              ///< best hypotheses refined by points and planes; >= 1
    /// Smallest share of the source overlapping the target after refinement for success [-]
    double min_overlap = 0.25;
    PointPlaneParams refine{};  ///< the refinement
    int num_threads = 0;        ///< 0 = all cores; never changes the result
    /// Throws InvalidArgument naming the first out-of-range field.
    void Validate() const;
};

/// Global registration of `source` to `target` from their planar patches, no initial guess.
/// `iterations` in the result counts the hypotheses. Fewer than three mutually non-parallel
/// patches in either cloud, or no hypothesis that overlaps, give converged = false with status
/// kNoHypothesis (or the refinement's status) and the reason.
RegistrationResult RegisterPlanesGlobal(const PointCloud& source, const PointCloud& target,
                                        const KdTree& target_tree,
                                        const std::vector<PlanarPatch>& source_patches,
                                        const std::vector<PlanarPatch>& target_patches,
                                        const PlaneGlobalParams& params);

/// Rigid transform mapping the three source planes onto the three target planes (normals by
/// their rigid fit, offsets by the 3x3 system). Returns false for (nearly) parallel normals.
bool TransformFromPlaneTriple(const PlanarPatch* const source[3],
                              const PlanarPatch* const target[3],
                              Eigen::Isometry3d& T_target_source);

}  // namespace multicue

#pragma once
/// \file Pairwise registration of two scans, the job of `multicue register`: preprocess both
/// (voxel grid, normals), then one of
///   - icp / point-to-plane / symmetric: fine ICP from the initial guess;
///   - plane: points and plane correspondences together from the initial guess (section 2.2);
///   - global: no guess: three plane pairs, else FPFH (and RGB keypoints on coloured organized
///     frames) with RANSAC, then refinement by points and planes;
///   - auto: plane with a guess, global without.
/// Every parameter that depends on the size of the scene is derived from one resolution
/// (ForResolution), so one call suits a table top (1 cm) and a room (5 cm) alike.

#include <optional>
#include <string>

#include <Eigen/Geometry>

#include "multicue/core/params.hpp"
#include "multicue/core/point_cloud.hpp"
#include "multicue/registration/feature_alignment.hpp"
#include "multicue/registration/icp.hpp"
#include "multicue/registration/plane_registration.hpp"
#include "multicue/registration/planes.hpp"
#include "multicue/registration/preprocess.hpp"
#include "multicue/registration/registration_result.hpp"
#include "multicue/registration/rgb_keypoints.hpp"
#include "multicue/registration/visibility.hpp"

namespace multicue {

enum class RegistrationMethod {
    kIcp,           ///< point-to-point ICP
    kPointToPlane,  ///< point-to-plane ICP
    kSymmetric,     ///< symmetric ICP
    kPlane,         ///< points and planes from the guess
    kGlobal,        ///< planes, else features, without a guess; then points and planes
    kAuto,          ///< kPlane with a guess, then kGlobal if that fails; kGlobal without a guess
};

/// "icp", "point-to-plane", "symmetric", "plane", "global", "auto"; and back (InvalidArgument
/// naming the choices).
const char* RegistrationMethodName(RegistrationMethod method);
RegistrationMethod ParseRegistrationMethod(const std::string& name);

struct RegistrationParams {
    RegistrationMethod method = RegistrationMethod::kAuto;
    PreprocessParams preprocess{};     ///< both clouds
    IcpParams icp{};                   ///< the fine stage (its method is set by `method`)
    PlaneExtractionParams planes{};    ///< planar patches of both clouds
    PointPlaneParams point_plane{};    ///< plane pairs and weight (its icp is `icp`)
    PlaneGlobalParams plane_global{};  ///< plane triples (its refine is point_plane)
    FpfhAlignParams fpfh{};            ///< feature alignment when the planes fail
    /// The free-space check of every result when the raw organized frames are known: a result
    /// that puts too much of one frame into space the other saw as free is rejected.
    Switchable<FreeSpaceParams> free_space{};
    bool rgb_keypoints = true;  ///< also try RGB keypoints on coloured organized frames
    RgbKeypointParams rgb{};    ///< their detector and matching
    int num_threads = 0;        ///< 0 = all cores (overrides the stages'); never changes results

    /// The defaults scaled to a scene resolution r [m] (the voxel size): correspondence gate
    /// 3 r shrinking from 15 r, FPFH radius 5 r, plane growing radius 3 r, plane flatness r,
    /// scoring distance 2 r, RANSAC inlier distance 3 r. Throws InvalidArgument unless r > 0.
    static RegistrationParams ForResolution(float r);
    /// Throws InvalidArgument naming the first out-of-range field (as "node.field: ...").
    void Validate() const;
};

/// A resolution suited to a cloud: the larger of its median nearest-neighbour spacing and a
/// 300th of its bounding-box diagonal, rounded to 2 significant digits. Throws DataError for a
/// cloud with fewer than 3 finite points.
float SuggestResolution(const PointCloud& cloud);

/// Parameters suited to a scan: ForResolution of 1 cm for an organized depth frame (in its
/// sensor frame, see EstimatePinhole) with the structured-light depth noise (1.4e-3 / m), else
/// ForResolution(SuggestResolution(cloud)). Throws DataError for fewer than 3 finite points.
RegistrationParams SuggestRegistrationParams(const PointCloud& cloud);

/// Registers `source` to `target` (raw clouds; both are preprocessed here). `T_init` is the
/// initial guess (source -> target); without one, kAuto runs the global method and the fine
/// methods start from the identity. Throws InvalidArgument for bad parameters and DataError for
/// inconsistent clouds; empty, NaN-only or degenerate input gives converged = false with the
/// reason.
RegistrationResult Register(const PointCloud& source, const PointCloud& target,
                            const RegistrationParams& params,
                            const std::optional<Eigen::Isometry3d>& T_init = std::nullopt);

/// The same on clouds already preprocessed (normals present) with their trees; the raw frames
/// (organized; with colours for RGB keypoints) may be given for RGB keypoints and the free-space
/// check (null: none). Only the plane and global methods search the source: its tree may be null,
/// and is then built here when the method needs it.
RegistrationResult RegisterPrepared(const PointCloud& source, const KdTree* source_tree,
                                    const PointCloud& target, const KdTree& target_tree,
                                    const RegistrationParams& params,
                                    const std::optional<Eigen::Isometry3d>& T_init,
                                    const PointCloud* source_frame = nullptr,
                                    const PointCloud* target_frame = nullptr);

/// The free-space check of `result` (visibility.hpp) in both directions, where the raw frames are
/// given (null: skipped): sets free_space_violation and, above params.max_violation, turns a
/// converged result into kInconsistent.
void CheckAgainstFreeSpace(const PointCloud& source, const PointCloud& target,
                           const PointCloud* source_frame, const PointCloud* target_frame,
                           const FreeSpaceParams& params, RegistrationResult& result);

}  // namespace multicue

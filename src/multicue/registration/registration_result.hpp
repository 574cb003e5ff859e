#pragma once
/// \file What every registration method returns, and the checks they share: the quality of an
/// alignment (fitness, inlier RMSE, overlap), how well the geometry constrains it (eigenvalues of
/// the point-to-plane information matrix) and the closed-form rigid fit of point pairs.
///
/// Transforms are named by frames: T_target_source maps source coordinates into the target's
/// frame (p_target = T_target_source * p_source). Poses are computed in double precision.

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "multicue/core/point_cloud.hpp"
#include "multicue/core/types.hpp"
#include "multicue/search/kdtree.hpp"

namespace multicue {

/// Why a registration stopped.
enum class RegistrationStatus {
    kConverged,              ///< the update fell below the tolerances; all checks passed
    kMaxIterations,          ///< the iteration limit came first
    kEmptyInput,             ///< a cloud had no usable point
    kTooFewCorrespondences,  ///< fewer correspondences than the minimum survived the gates
    kLowOverlap,             ///< too small a share of the source found a partner
    kDegenerate,             ///< the geometry leaves a direction unconstrained (one plane,
                             ///< a corridor, a sphere): the transform is not determined
    kNoHypothesis,           ///< a global method found no acceptable hypothesis
    kInconsistent,           ///< the aligned scans contradict each other: one lies in space the
                             ///< other saw as free (visibility.hpp)
};

/// "converged", "max_iterations", "empty_input", "too_few_correspondences", "low_overlap",
/// "degenerate", "no_hypothesis", "inconsistent".
const char* RegistrationStatusName(RegistrationStatus status);

/// 6x6 matrices over the twist (rx, ry, rz, tx, ty, tz): rotation [rad] about the centroid of
/// the source inliers (in the target frame), then translation [m].
using Matrix6d = Eigen::Matrix<double, 6, 6>;
using Vector6d = Eigen::Matrix<double, 6, 1>;

/// How well a set of point-to-plane constraints determines a rigid transform.
struct ConstraintAnalysis {
    /// Information matrix sum_i w_i J_i^T J_i of the point-to-plane residuals n_i . (p_i - q_i),
    /// J_i = [((p_i - c) x n_i)^T, n_i^T], c the centroid of the points.
    Matrix6d information = Matrix6d::Zero();
    /// Eigenvalues of the information with the rotation block scaled by 1 / L^2 (L: RMS distance
    /// of the points from c), ascending: rotations and translations in comparable units [-].
    Vector6d eigenvalues = Vector6d::Zero();
    /// Eigenvector of the smallest scaled eigenvalue: the least constrained motion.
    Vector6d weakest_direction = Vector6d::Zero();
    /// Smallest / largest scaled eigenvalue, in [0, 1]: 0 for one plane or a corridor [-].
    double condition = 0.0;
    double scale = 0.0;  ///< L [m]
};

/// The points `points` (already transformed into the target frame) with the target normals of
/// their partners `normals` (unit, same count) and weights (empty = 1). Throws InvalidArgument
/// for mismatched sizes.
ConstraintAnalysis AnalyzeConstraints(std::span<const Eigen::Vector3d> points,
                                      std::span<const Eigen::Vector3d> normals,
                                      std::span<const double> weights = {});

/// The outcome of a registration.
struct RegistrationResult {
    Eigen::Isometry3d T_target_source = Eigen::Isometry3d::Identity();
    /// True only when the estimate is trusted: it converged, enough of the source overlaps the
    /// target, and the geometry constrains every direction.
    bool converged = false;
    RegistrationStatus status = RegistrationStatus::kEmptyInput;
    std::string reason;               ///< one line saying why, with the deciding figure
    int iterations = 0;               ///< iterations (ICP) or hypotheses tried (global methods)
    std::size_t correspondences = 0;  ///< inlier correspondences at the end
    double inlier_rmse = 0.0;         ///< RMS distance of the inlier correspondences [m]
    double fitness = 0.0;             ///< inlier correspondences / usable source points [-]
    /// Share of the usable source points with a target point within the overlap distance after
    /// alignment [-]
    double overlap = 0.0;
    /// Point-to-plane information at the solution; its inverse times inlier_rmse^2 approximates
    /// the covariance of the twist (rotation about the inlier centroid, then translation).
    ConstraintAnalysis constraints;
    /// Largest share of points found in the other frame's free space (visibility.hpp), when
    /// organized frames were given; 0 otherwise [-]
    double free_space_violation = 0.0;
    double time_ms = 0.0;  ///< wall time of the call [ms]
};

/// Alignment quality of `source` under `T_target_source` against `target` (indexed by `tree`):
/// a source point is an inlier when its nearest target point lies within max_distance.
struct AlignmentQuality {
    std::size_t usable = 0;    ///< finite source points considered
    std::size_t inliers = 0;   ///< of those, with a target point within max_distance
    double fitness = 0.0;      ///< inliers / usable [-]
    double inlier_rmse = 0.0;  ///< RMS nearest distance of the inliers [m]
};

/// Evaluates an alignment with the nearest neighbours of (at most `max_points`, evenly strided;
/// 0 = all) the source points. The same measure is applied to every method and peer in the
/// evaluation programs. Throws InvalidArgument if max_distance is not > 0.
AlignmentQuality EvaluateAlignment(const PointCloud& source, const KdTree& target_tree,
                                   const Eigen::Isometry3d& T_target_source, double max_distance,
                                   std::size_t max_points = 0, int num_threads = 0);

/// Weighted least-squares rigid transform T minimising sum w_i |T a_i - b_i|^2 (closed form:
/// SVD of the weighted cross-covariance, reflections excluded; Umeyama 1991 without scale).
/// Returns false (T untouched) for fewer than 3 pairs, zero total weight or collinear points.
bool FitRigidTransform(std::span<const Eigen::Vector3d> a, std::span<const Eigen::Vector3d> b,
                       std::span<const double> weights, Eigen::Isometry3d& T);

/// exp of a twist (rx, ry, rz, tx, ty, tz): rotation by the angle-axis vector r, then translation
/// t (the linearisation used by the Gauss-Newton steps: T <- Exp(x) * T).
Eigen::Isometry3d TwistToTransform(const Vector6d& x);

/// Rotation angle [deg] and translation [m] of T (the size of an update or of an error).
double RotationAngleDeg(const Eigen::Isometry3d& T);
double TranslationNorm(const Eigen::Isometry3d& T);

}  // namespace multicue

#pragma once
/// \file Fine registration by the iterative closest point algorithm (thesis section 2.2): pair
/// every source point with its nearest target point, move the source to reduce the distances,
/// repeat. Variants:
///   - point-to-point (Besl and McKay 1992): closed-form weighted rigid fit of the pairs;
///   - point-to-plane (Chen and Medioni 1992): Gauss-Newton on n_q . (T p - q), which slides
///     along surfaces and converges in far fewer iterations on scans of planar scenes;
///   - symmetric (Rusinkiewicz 2019): Gauss-Newton on (n_p + n_q) . (T p - q), both normals,
///     which widens the basin of convergence on curved surfaces.
/// Robust kernels (Huber, Tukey, Cauchy) reweight the pairs every iteration (IRLS); the gate may
/// start wide and shrink (coarse to fine) so that a rough initial guess still converges.
///
/// After the loop the result is checked, and `converged` is true only when every check passes:
/// the update fell below the tolerances, at least min_fitness of the source found a partner, and
/// the point-to-plane information matrix is well conditioned (min_condition). One plane, two
/// parallel walls (a corridor) or a sphere leave a motion unconstrained: their smallest scaled
/// eigenvalue is near zero and the result says `degenerate`, whatever the residuals look like.
///
/// Sums over points are taken in fixed blocks, so the result is the same for any thread count.

#include <cstddef>
#include <functional>
#include <string>

#include <Eigen/Geometry>

#include "multicue/core/point_cloud.hpp"
#include "multicue/registration/correspondences.hpp"
#include "multicue/registration/registration_result.hpp"
#include "multicue/search/kdtree.hpp"

namespace multicue {

enum class IcpMethod {
    kPointToPoint,  ///< closed-form rigid fit of the pairs
    kPointToPlane,  ///< Gauss-Newton on the target normals
    kSymmetric,     ///< Gauss-Newton on the sum of both normals
};

/// "point-to-point", "point-to-plane", "symmetric"; and back (InvalidArgument naming the choices).
const char* IcpMethodName(IcpMethod method);
IcpMethod ParseIcpMethod(const std::string& name);

enum class RobustKernelType {
    kNone,    ///< least squares
    kHuber,   ///< weight min(1, k / |r|)
    kTukey,   ///< weight (1 - (r / k)^2)^2 inside k, 0 outside
    kCauchy,  ///< weight 1 / (1 + (r / k)^2)
};

/// "none", "huber", "tukey", "cauchy"; and back (InvalidArgument naming the choices).
const char* RobustKernelName(RobustKernelType type);
RobustKernelType ParseRobustKernel(const std::string& name);

/// IRLS weight of a residual r for kernel scale k > 0.
double RobustWeight(RobustKernelType type, double r, double k);

/// Weight of a pair under the depth-noise model of IcpParams::depth_noise: 2 s0^2 / (2 s0^2 +
/// (k d_s^2)^2 + (k d_t^2)^2), d the distances [m] of the two points to their sensors; 1 when
/// k = 0.
double DepthNoiseWeight(double d_source, double d_target, double depth_noise, double noise_floor);

struct IcpParams {
    IcpMethod method = IcpMethod::kPointToPlane;         ///< objective
    CorrespondenceParams correspondences{};              ///< partner search and final gates
    RobustKernelType kernel = RobustKernelType::kTukey;  ///< reweighting of the residuals
    float kernel_scale = 0.0f;  ///< k of the kernel [m]; 0 = the current distance gate
    /// Coarse to fine: the distance gate starts here and shrinks by gate_decay, each time an
    /// update moved the source less than a tenth of the gate, down to
    /// correspondences.max_distance [m]; 0 = fixed gate.
    float initial_max_distance = 0.0f;
    float gate_decay = 0.7f;               ///< factor per shrinking step, in (0, 1) [-]
    int max_iterations = 60;               ///< [iterations], >= 1
    double translation_tolerance = 5e-5;   ///< stop when an update moves less [m]
    double rotation_tolerance_deg = 5e-3;  ///< and turns less [deg]
    /// Weight every pair by the inverse variance of its residual under a depth-noise model:
    /// structured-light cameras measure depth with sigma = depth_noise * d^2 (Khoshelham and
    /// Elberink 2012; 1.4e-3 for a Kinect), d the distance [m] of a point to its cloud's
    /// sensor_origin, on top of a floor noise_floor of everything else (sampling, calibration):
    /// w = 2 s0^2 / (2 s0^2 + sigma_s^2 + sigma_t^2). Far, coarsely quantised surfaces (a floor
    /// 4 m away) then no longer bias the fit. 0 = off (laser scans: flat noise) [1/m]
    float depth_noise = 0.0f;
    float noise_floor = 0.003f;  ///< s0 of depth_noise [m]; > 0
    /// Source points used (evenly strided over the finite ones); 0 = all [points]
    std::size_t max_source_points = 0;
    /// While the gate is still wider than its final value, only this many source points (evenly
    /// strided) are paired: the coarse iterations need the shape, not every point [points];
    /// 0 = all
    std::size_t coarse_source_points = 5000;
    std::size_t min_correspondences = 20;  ///< fewer pairs stop the loop [pairs]
    double min_fitness = 0.2;  ///< share of source points with a partner for success [-]
    /// Smallest acceptable condition of the scaled information matrix, in [0, 1): below it the
    /// result is `degenerate` [-]
    double min_condition = 2e-3;
    /// Distance within which a source point counts as overlapping after alignment [m];
    /// 0 = half the final gate
    float overlap_distance = 0.0f;
    int num_threads = 0;  ///< 0 = all cores; never changes the result
    /// Throws InvalidArgument naming the first out-of-range field.
    void Validate() const;
};

/// Extra Gauss-Newton terms added to the point terms every iteration (the plane
/// correspondences of plane_registration.hpp): given the current estimate, add J^T W J to H and
/// J^T W r to g, J the derivative of the residuals with respect to the twist (rotation about
/// `center`, in the target frame, then translation) applied on the left of the estimate, and
/// return their cost sum r^T W r. `sampling` is the share of the usable source points paired in
/// this iteration (below 1 in the coarse iterations): terms that stand for source points scale
/// with it to keep their balance with the point pairs. Called from one thread.
using ExtraTerms =
    std::function<double(const Eigen::Isometry3d& T_target_source, const Eigen::Vector3d& center,
                         double sampling, Matrix6d& H, Vector6d& g)>;

/// Registers `source` to `target` from `T_init` (source -> target). `target_tree` must index
/// `target` (it may be null when the projective path applies, see CorrespondenceSearcher).
/// Point-to-plane needs target normals, symmetric needs both clouds' normals (DataError
/// otherwise); the normal gate and the degeneracy check use them when present (point-to-point
/// without normals estimates target normals at the final pairs for the check).
/// Throws InvalidArgument for bad parameters. Empty or NaN-only clouds give converged = false,
/// status kEmptyInput.
RegistrationResult RegisterIcp(const PointCloud& source, const PointCloud& target,
                               const KdTree* target_tree, const IcpParams& params,
                               const Eigen::Isometry3d& T_init = Eigen::Isometry3d::Identity(),
                               const ExtraTerms& extra_terms = {});

/// The same, building the k-d tree of the target when one is needed.
RegistrationResult RegisterIcp(const PointCloud& source, const PointCloud& target,
                               const IcpParams& params,
                               const Eigen::Isometry3d& T_init = Eigen::Isometry3d::Identity());

}  // namespace multicue

#pragma once
/// \file Sample consensus: RANSAC and MSAC over an index subset of a cloud, generic in the model.
///
/// Most callers want the typed fits built on this engine: FitPlane (sac_plane.hpp), FitLine
/// (sac_line.hpp), FitCircle2d and FitCircle3d (sac_circle.hpp), FitSphere (sac_sphere.hpp) and
/// FitCylinder (sac_cylinder.hpp). RunSampleConsensus is for new models (a box side, a handle).
///
/// The loop, for a fixed seed and independent of the thread count:
/// 1. draw a minimal sample (without repetition) from the usable points, uniformly or, with
///    sample_weights, with probability proportional to the points' weights; fit a model;
///    degenerate samples and models violating a constraint still count as drawn samples;
/// 2. score it: RANSAC counts the points outside the threshold, MSAC sums the truncated quadratic
///    cost min(d^2, t^2), each point's term multiplied by its score weight when score_weights are
///    given; the lowest score wins, ties keep the earlier model;
/// 3. after every new best model, update the number of samples needed with Eq. (4.6) of the thesis
///    (section 4.2.4.3): T = log(1 - p_success) / log(1 - w^n), w = the chance that one draw is an
///    inlier (inliers / usable points; with sample_weights the inliers' share of the total sampling
///    weight), n = sample size; stop after T samples or max_iterations, whichever comes first;
/// 4. refine: refit the model to its inliers by least squares, reselect the inliers, and repeat
///    while the truncated quadratic cost does not grow, until the inlier set is stable.
///
/// Hypotheses are scored in parallel batches, but every decision is taken in drawing order, so
/// the result equals that of the serial loop bit for bit.
///
/// Weighted sampling and scoring (thesis section 5.4.1: the categorisation's shape probabilities
/// weight "the sampling (which used to be random) and the scoring"; section 5.4.2.1: RSD tells
/// planar from curved points) are generic: any model can be given per-point weights.

#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "multicue/core/point_cloud.hpp"
#include "multicue/core/types.hpp"

namespace multicue {

/// How hypotheses are scored.
enum class SacMethod {
    kRansac,  ///< number of inliers (Fischler and Bolles, 1981)
    kMsac,    ///< truncated quadratic cost sum(min(d^2, t^2)) (Torr and Zisserman, 2000)
};

struct SacParams {
    SacMethod method = SacMethod::kMsac;  ///< scoring of hypotheses
    float distance_threshold = 0.01f;     ///< inlier threshold t on the point-to-model distance [m]
    double p_success = 0.99;  ///< wanted probability of drawing an all-inlier sample, in (0, 1) [-]
    int max_iterations = 10000;  ///< cap on the number of drawn samples, >= 1 [samples]
    std::uint64_t seed = 1;      ///< sampler seed; equal seeds give identical results [-]
    int max_refine_rounds = 10;  ///< least-squares refit rounds on the inliers, 0 = none [rounds]
    /// Weight w in [0, 1] of the normal deviation, as in PCL's SACSegmentationFromNormals: the
    /// distance becomes d = (1 - w) |euclidean distance| + w * angle, the angle [rad] between the
    /// point's normal and the model's surface normal there (sign-free). Used only by models with a
    /// surface normal (plane, sphere, cylinder); w > 0 needs cloud normals, and points without a
    /// finite normal are then skipped. It rejects points that lie on the model by chance but belong
    /// to another surface (an object's side touching the table plane). The threshold applies to
    /// the blended value, so it mixes metres and radians: keep w small (0.05-0.2) [-]
    float normal_distance_weight = 0.0f;
    int num_threads = 0;  ///< threads scoring hypotheses (0 = all cores); never changes the result
    /// Sampling weights, one per cloud point (indexed like cloud.points), or empty for uniform
    /// sampling. A usable point is drawn with probability proportional to its weight (without
    /// repetition inside one sample); weight 0 is never drawn. Each must be finite and >= 0.
    /// Fewer usable points with a positive weight than the sample size give found = false [-]
    std::vector<float> sample_weights{};
    /// Score weights, one per cloud point, or empty for all 1: RANSAC sums the weights of the
    /// outliers, MSAC multiplies each point's truncated cost by its weight, and the refinement
    /// compares weighted costs. Each must be finite and >= 0 [-]
    std::vector<float> score_weights{};
    /// Its parameters once each: configuration key (the field's name), field, meaning. A
    /// visitor reads or records them (io::ConfigSection::operator(); ReadPerceiveParams).
    template <typename V>
    void VisitParams(V& v) {
        v("distance_threshold", distance_threshold, "RANSAC inlier distance [m]");
        v("max_iterations", max_iterations, "RANSAC sample cap");
        v("normal_distance_weight", normal_distance_weight, "normal term weight");
        v("seed", seed, "RANSAC seed");
    }
};

/// Coefficients of a model as a flat vector; each model defines the layout.
using SacCoefficients = Eigen::VectorXf;

/// A model for the engine: a few callbacks, no class hierarchy. Callbacks must be thread-safe
/// (they are called concurrently on different hypotheses) and deterministic.
struct SacModel {
    int sample_size = 0;         ///< points in a minimal sample, >= 1 [points]
    bool needs_normals = false;  ///< samples need normals; points without a finite one are skipped
    /// Fits a model to a minimal sample; false for a degenerate sample or a violated constraint.
    std::function<bool(const PointCloud&, std::span<const Index> sample, SacCoefficients&)>
        fit_sample{};
    /// Writes the Euclidean distance of each point to the model [m].
    std::function<void(const PointCloud&, const SacCoefficients&, std::span<const Index> points,
                       std::span<float> distances)>
        distances{};
    /// Optional: writes the angle in [0, pi/2] between each point's normal and the model's surface
    /// normal at that point [rad]. Needed for normal_distance_weight > 0.
    std::function<void(const PointCloud&, const SacCoefficients&, std::span<const Index> points,
                       std::span<float> angles)>
        normal_angles{};
    /// Optional: least-squares model of `inliers`, starting from `current`; false if the fit fails
    /// or violates a constraint. Without it the sample's model is returned unrefined.
    std::function<bool(const PointCloud&, std::span<const Index> inliers,
                       const SacCoefficients& current, SacCoefficients& refined)>
        refine{};
};

struct SacResult {
    bool found = false;            ///< a model with at least sample_size inliers was found
    SacCoefficients coefficients;  ///< the model (layout defined by the model); empty if !found
    Indices inliers;     ///< points within the threshold, in input order (ascending for all points)
    int iterations = 0;  ///< samples drawn, degenerate ones included [samples]
    bool converged = false;      ///< stopped by Eq. (4.6) before reaching max_iterations
    float rmse = 0.0f;           ///< root mean square Euclidean distance of the inliers [m]
    double inlier_weight = 0.0;  ///< sum of the inliers' score weights (their count without) [-]
};

/// Runs RANSAC or MSAC for `model` on the points `indices` of `cloud` (all points when empty).
/// Non-finite points are skipped, and so are points without a finite normal when normals are used.
/// Fewer usable points than the sample size, or no acceptable model, give found = false.
/// Throws InvalidArgument for a parameter out of its domain (the message names it), an incomplete
/// model, an index out of range or bad weights (wrong size, negative or not finite; the message
/// names sample_weights or score_weights); throws DataError when normals are needed but the cloud
/// has none (or not one per point).
SacResult RunSampleConsensus(const PointCloud& cloud, const Indices& indices, const SacModel& model,
                             const SacParams& params);

/// Number of samples T of Eq. (4.6) needed to draw one all-inlier sample with probability
/// p_success when a fraction inlier_ratio of the points are inliers: log(1 - p) / log(1 - w^n),
/// rounded up, at least 1; saturates at the largest int when w^n is (numerically) zero.
int AdaptiveIterationCount(double p_success, double inlier_ratio, int sample_size);

/// Throws InvalidArgument if a field of `params` is out of its domain (weights are checked against
/// the cloud by ValidateSacWeights).
void ValidateSacParams(const SacParams& params);

/// Throws InvalidArgument (naming `name`) unless `weights` is empty or has one finite value >= 0
/// per cloud point.
void ValidateSacWeights(std::span<const float> weights, std::size_t cloud_size, const char* name);

}  // namespace multicue

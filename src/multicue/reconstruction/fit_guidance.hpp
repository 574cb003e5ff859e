#pragma once
/// \file Per-point guidance of the box and cylinder fits (thesis sections 5.4.1 and 5.4.2.1):
/// RSD's minimum radius r_min tells planar points (r_min above about 0.1 m, box faces) from curved
/// ones (cylinder sides), and the categorisation's shape probabilities act as priors "in the
/// sampling (which used to be random) and the scoring" (section 5.4.1).
///
/// A fit turns the guidance into the sample-consensus weights of SacParams:
///   sampling weight = RSD preference(r_min) * prior,   score weight = prior.
/// RSD preference: with p(r) = clamp((r - (planar_radius - ramp)) / (2 ramp), 0, 1) the planarity
/// of a point, a box samples with floor + (1 - floor) p(r) and a cylinder with
/// floor + (1 - floor) (1 - p(r)); points with an unknown r_min (NaN) get the floor.

#include <span>
#include <vector>

#include "multicue/core/point_cloud.hpp"
#include "multicue/core/types.hpp"
#include "multicue/features/rsd.hpp"

namespace multicue {

struct RsdSamplingParams {
    float planar_radius = 0.1f;  ///< r_min at which a point is as likely planar as curved [m];
                                 ///< section 5.4.2.1 calls r_min > 0.1 m planar; > 0
    float ramp = 0.03f;          ///< half-width of the transition around planar_radius [m]; > 0
    float floor_weight = 0.05f;  ///< weight of the least preferred points, in (0, 1]: they stay
                                 ///< drawable, so a wrong r_min only slows the search [-]
};

/// Optional guidance of FitUprightBox, FitFootprintRectangle and FitObjectCylinder. Both spans
/// hold one value per cloud point (indexed like cloud.points) or are empty; they must outlive the
/// call.
struct FitGuidance {
    /// RSD r_min per point [m] (column 0 of ComputeRsd, or RsdMinRadii); NaN = unknown. Empty:
    /// uniform sampling.
    std::span<const float> rsd_min_radius{};
    /// Probability in [0, 1] per point that it belongs to an object of the fitted shape type
    /// (for a box the summed box and flat probabilities, for a cylinder the round ones). Empty: 1.
    std::span<const float> shape_prior{};
    RsdSamplingParams rsd{};  ///< mapping of r_min to a sampling preference
};

/// The shape a fit looks for: boxes prefer planar points, cylinders curved ones.
enum class SampledSurface { kPlanar, kCurved };

/// Sampling preference of one point with minimum radius r_min (see the file comment).
float RsdSamplingWeight(float r_min, SampledSurface surface, const RsdSamplingParams& params);

/// Throws InvalidArgument (naming the field) unless each span is empty or has one value per cloud
/// point, r_min values are NaN or finite and >= 0, priors finite in [0, 1], and the RSD mapping's
/// parameters are in their domains.
void ValidateFitGuidance(const FitGuidance& guidance, std::size_t cloud_size);

/// Sample-consensus weights for `surface` from the guidance (one per cloud point; only the
/// entries of `indices` are set, the rest are 0). Leaves a vector empty when the guidance gives
/// nothing for it (no r_min and no prior: uniform sampling; no prior: unweighted scoring).
void MakeSacWeights(const FitGuidance& guidance, SampledSurface surface, std::size_t cloud_size,
                    const Indices& indices, std::vector<float>& sample_weights,
                    std::vector<float>& score_weights);

/// RSD r_min of the points `indices` (section 2.5.1), with neighbourhoods among those points
/// only; one value per cloud point, NaN outside `indices` and for points without a finite
/// position or normal. Throws InvalidArgument for bad RSD parameters or an index out of range,
/// DataError if the cloud has no normals (unless `indices` is empty).
std::vector<float> RsdMinRadii(const PointCloud& cloud, const Indices& indices,
                               const RsdParams& params = {});

}  // namespace multicue

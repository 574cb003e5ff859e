#pragma once
/// \file Initial alignment from point correspondences (thesis section 2.2: "point-to-point
/// correspondences (computed using both 3D and RGB-based features)"): descriptors of both scans
/// are matched (FPFH here, RGB keypoints in rgb_keypoints.hpp), the matches thinned by a fast
/// pairwise length test (a rigid motion keeps distances, so a correct match agrees in length
/// with many other correct matches), and a rigid transform is found by RANSAC over triples of
/// matches, each triple checked for length consistency before it is fitted.
///
/// RANSAC draws its k-th sample from (seed, k) alone and takes every decision in drawing order,
/// so the result is the same for any thread count.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "multicue/core/point_cloud.hpp"
#include "multicue/core/types.hpp"
#include "multicue/features/feature_common.hpp"
#include "multicue/registration/registration_result.hpp"
#include "multicue/search/kdtree.hpp"

namespace multicue {

/// Matched points: source[k] in the source cloud corresponds to target[k] in the target cloud.
struct PointMatches {
    Indices source;
    Indices target;
    std::size_t size() const { return source.size(); }
    bool empty() const { return source.empty(); }
};

struct FeatureMatchParams {
    bool mutual = true;  ///< keep a match only when each is the other's nearest descriptor
    /// Lowe's ratio test: nearest / second-nearest descriptor distance at most this, (0, 1];
    /// 1 = off [-]
    float ratio = 0.95f;
    int num_threads = 0;  ///< 0 = all cores; never changes the result
    /// Throws InvalidArgument naming the first out-of-range field.
    void Validate() const;
};

/// Nearest-descriptor matches of the rows of two feature matrices (L2 distance; NaN rows are
/// never matched), in ascending source row order. Throws InvalidArgument for bad parameters or
/// matrices of different widths.
PointMatches MatchFeatureRows(const FeatureMatrix& source, const FeatureMatrix& target,
                              const FeatureMatchParams& params);

struct LengthConsistencyParams {
    /// Two matches agree when their source and target distances differ by at most
    /// absolute + relative * distance [m] ...
    float absolute = 0.02f;
    float relative = 0.05f;  ///< ... [-]
    int partners = 200;      ///< other matches each match is compared with (evenly spaced); >= 1
    /// Share of the matches kept, those agreeing with the most partners, (0, 1] [-]
    float keep_fraction = 0.4f;
    std::size_t min_keep = 100;  ///< never keep fewer (all when there are fewer) [matches]
    int num_threads = 0;         ///< 0 = all cores; never changes the result
    /// Throws InvalidArgument naming the first out-of-range field.
    void Validate() const;
};

/// Positions (into `matches`) of the matches that agree in length with the most others,
/// ascending. Throws InvalidArgument for bad parameters or indices out of range.
std::vector<std::size_t> PruneByLengthConsistency(const PointCloud& source,
                                                  const PointCloud& target,
                                                  const PointMatches& matches,
                                                  const LengthConsistencyParams& params);

struct RansacParams {
    int max_iterations = 20000;     ///< samples drawn at most [samples]; >= 1
    double p_success = 0.999;       ///< stop once an all-inlier sample is this likely, (0, 1) [-]
    float inlier_distance = 0.03f;  ///< a match is an inlier within this distance [m]; > 0
    /// A sample's three pairwise lengths must agree within this share before it is fitted [-]
    float edge_tolerance = 0.1f;
    float min_edge = 0.02f;       ///< samples with a shorter edge are skipped (degenerate) [m]
    std::size_t min_inliers = 8;  ///< fewer inliers: no hypothesis [matches]; >= 3
    std::uint64_t seed = 1;       ///< equal seeds give equal results
    int num_threads = 0;          ///< 0 = all cores; never changes the result
    /// Throws InvalidArgument naming the first out-of-range field.
    void Validate() const;
};

/// RANSAC over the matches: T_target_source from the best triple refitted to all its inliers.
/// `correspondences` counts the inliers, `fitness` is inliers / matches, `iterations` the
/// samples drawn; converged with status kConverged when at least min_inliers agree, else
/// kNoHypothesis (kEmptyInput without matches). Throws InvalidArgument for bad parameters or
/// indices out of range.
RegistrationResult AlignMatchesRansac(const PointCloud& source, const PointCloud& target,
                                      const PointMatches& matches, const RansacParams& params);

struct FpfhAlignParams {
    PairFeatureParams fpfh{.radius = 0.05f};  ///< FPFH neighbourhood (about 5 voxels)
    /// Points per cloud whose descriptors are matched (evenly strided over those with a
    /// defined descriptor); the matching costs their product [points]; >= 10
    std::size_t max_points = 3000;
    FeatureMatchParams matching{};
    LengthConsistencyParams pruning{};
    RansacParams ransac{};
    int num_threads = 0;  ///< 0 = all cores (overrides the stages'); never changes the result
    /// Throws InvalidArgument naming the first out-of-range field.
    void Validate() const;
};

/// FPFH (features module) of both clouds, which need normals (PreprocessForRegistration);
/// mutual / ratio matching; length pruning; RANSAC. The trees index the clouds.
RegistrationResult AlignFpfh(const PointCloud& source, const KdTree& source_tree,
                             const PointCloud& target, const KdTree& target_tree,
                             const FpfhAlignParams& params);

}  // namespace multicue

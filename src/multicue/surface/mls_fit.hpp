#pragma once
/// \file Internal to the surface module: the per-point fit of moving least squares (plane by
/// weighted RANSAC or weighted PCA, polynomial height field, Eq. 2.2-2.4), shared by the k-d tree
/// and the organized MLS and by the triangulation's normal estimation.

#include <cstdint>
#include <vector>

#include <Eigen/Core>

namespace multicue::detail {

/// SplitMix64: a tiny, fast generator with good statistics, seeded per point so that results do
/// not depend on which thread handles which point.
class SplitMix64 {
  public:
    explicit SplitMix64(std::uint64_t seed) : state_(seed) {}
    std::uint64_t Next() {
        std::uint64_t z = (state_ += 0x9e3779b97f4a7c15ull);
        z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
        z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
        return z ^ (z >> 31);
    }
    /// Uniform in [0, n).
    std::uint32_t Below(std::uint32_t n) {
        return static_cast<std::uint32_t>(((Next() >> 32) * std::uint64_t{n}) >> 32);
    }

  private:
    std::uint64_t state_;
};

/// What the fit needs to know.
struct MlsFitSettings {
    float radius = 0.0f;           ///< neighbourhood radius [m] (scales u, v for conditioning)
    float inv_h2 = 0.0f;           ///< 1 / h^2 of Eq. (2.2)
    int order = 2;                 ///< polynomial order 0..3
    bool robust = true;            ///< weighted RANSAC plane, else weighted least squares
    float inlier_distance = 0.0f;  ///< RANSAC inlier band [m]
    int max_iterations = 100;
    float confidence = 0.99f;
    int min_neighbors = 5;
};

/// Scratch space of one thread (reused from point to point).
struct MlsScratch {
    std::vector<Eigen::Vector3f> offsets;  ///< neighbour - query point [m]
    std::vector<float> weights;            ///< Eq. (2.2)
    std::vector<std::uint8_t> inlier;      ///< 1 for plane inliers
};

struct MlsFit {
    Eigen::Vector3f offset;  ///< fitted point - query point [m]
    Eigen::Vector3f normal;  ///< unit normal, unoriented
    float curvature = 0.0f;  ///< surface variation of the inliers
    int inliers = 0;
    bool plane_only = false;  ///< the polynomial fit was skipped or singular
};

/// Fits the surface around a query point from the neighbours' offsets (scratch.offsets, the query
/// point itself included) and fills scratch.weights and scratch.inlier. Returns false for fewer
/// than min_neighbors neighbours or a degenerate neighbourhood.
bool FitMls(MlsScratch& scratch, const MlsFitSettings& settings, SplitMix64& rng, MlsFit& fit);

}  // namespace multicue::detail

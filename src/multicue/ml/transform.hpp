#pragma once
/// \file Feature pre-processing fitted on training data only and saved for reuse on test data
/// (section 3.1.4 and 3.3.5.1): min-max scaling to [0, 1], z-score standardisation, and PCA with
/// optional whitening.

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "multicue/ml/dataset.hpp"

namespace multicue::ml {

enum class TransformKind : std::uint32_t { kMinMax = 0, kZScore = 1, kPca = 2 };

struct PcaParams {
    std::size_t components = 0;  ///< kept components; 0 = enough for `variance`
    double variance = 0.99;      ///< kept fraction of the variance when components == 0, (0, 1]
    bool whiten = false;         ///< scale each component to unit variance
};

/// A fitted transform. Apply() checks the column count and names the mismatch.
struct FeatureTransform {
    TransformKind kind = TransformKind::kMinMax;
    std::vector<std::string> input_names;  ///< column names seen when fitting
    Eigen::VectorXf offset;                ///< subtracted first: min (min-max) or mean
    Eigen::VectorXf scale;                 ///< min-max / z-score: multiplied after the offset
    Eigen::MatrixXf components;            ///< PCA: k x d, rows are unit principal axes
    Eigen::VectorXf variances;             ///< PCA: variance along each kept axis
    bool whiten = false;

    std::size_t input_dims() const { return static_cast<std::size_t>(offset.size()); }
    FeatureMatrix Apply(const FeaturesRef& features) const;
    /// Transforms the features of a dataset; min-max and z-score keep columns and blocks, PCA
    /// gives one block "pca" with columns pc0, pc1, ...
    Dataset Apply(const Dataset& data) const;
};

/// Per column: (x - min) / (max - min); constant columns map to 0. Throws DataError on an empty
/// or non-finite training set.
FeatureTransform FitMinMax(const Dataset& train);
/// Per column: (x - mean) / std; constant columns map to 0.
FeatureTransform FitZScore(const Dataset& train);
/// Principal components of the training rows (eigen-decomposition of the covariance).
FeatureTransform FitPca(const Dataset& train, const PcaParams& params);

inline constexpr std::uint32_t kTransformFormatVersion = 1;
void SaveTransform(const FeatureTransform& t, const std::filesystem::path& path);
FeatureTransform LoadTransform(const std::filesystem::path& path);

}  // namespace multicue::ml

#pragma once
/// \file k-means with k-means++ seeding, and bag-of-words global descriptors built from local
/// features with a codebook (section 3.1.4, 3.3.5.1).

#include <cstdint>
#include <string>
#include <vector>

#include "multicue/ml/dataset.hpp"

namespace multicue::ml {

struct KMeansParams {
    std::size_t k = 100;               ///< number of clusters (words), >= 1
    std::size_t max_iterations = 100;  ///< Lloyd iterations at most
    double tolerance = 1e-6;           ///< stop when the relative change of the inertia is below
    std::uint32_t seed = 1;            ///< k-means++ seeding
    int num_threads = 0;               ///< 0 = all cores
};

struct KMeansResult {
    FeatureMatrix centers;        ///< k x d
    std::vector<int> assignment;  ///< per row: nearest center
    double inertia = 0.0;         ///< sum of squared distances to the assigned centers
    std::size_t iterations = 0;
    bool converged = false;
};

/// Clusters the rows of `x`. Throws InvalidArgument when k is 0 or exceeds the row count and
/// DataError on non-finite values. Empty clusters are refilled with the farthest row.
KMeansResult KMeans(const FeaturesRef& x, const KMeansParams& params);

/// Index of the nearest center (squared L2) for every row.
std::vector<int> AssignClusters(const FeaturesRef& x, const FeatureMatrix& centers,
                                int num_threads = 0);

/// A codebook as a dataset (one row per word, block "codebook") so it can be saved and loaded
/// like any dataset; column names are those of the local features.
Dataset CodebookToDataset(const FeatureMatrix& centers, const std::vector<std::string>& names);

/// Bag of words: rows of `local` (local descriptors) are grouped into bags by (source, group,
/// view), each descriptor votes for its nearest word, and each bag becomes one row: the word
/// histogram scaled to sum 1, block `block`, with the label/group/view/source of the bag.
Dataset BagOfWords(const Dataset& local, const FeatureMatrix& codebook,
                   const std::string& block = "bow", int num_threads = 0);

}  // namespace multicue::ml

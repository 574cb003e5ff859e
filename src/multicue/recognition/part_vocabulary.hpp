#pragma once
/// \file Baselines for categorisation in clutter (thesis Table 5.9): a vocabulary of parts
/// (section 4.2.3, Mozos et al. 2011, as compared in section 5.2.3) and a descriptor of a whole
/// perceived cluster (GRSD- and VFH) for a classifier of whole objects. See docs/part-graph.md.
///
/// Vocabulary of parts. The feature vectors of the training parts (any fixed-length descriptor:
/// the part-graph model's mapped values (kPartMappedSize), or the 24 statistical features of
/// features/part_stats.hpp) are clustered by k-means into words. A part activates its
/// `activations` nearest words with p(A_i | f) proportional to 1 / (distance + 1e-6) (equation
/// 4.3), normalised over the activated words. Two uses:
/// - part votes (section 5.2.3): every word keeps the category counts of the training parts
///   assigned to it; a part's category distribution is sum_i p(A_i | f) p(o | A_i), with
///   p(o | A_i) the word's category frequencies (optionally divided by the category's share of
///   all training parts, `balanced`);
/// - bag of words: an object is the sum of its parts' activations, normalised to unit sum (a
///   histogram over the words), the input of any classifier trained on training objects.
/// With `normalize`, every feature column is first scaled to [0, 1] by the minimum and maximum
/// of the training parts (section 4.2.3.1); values outside are clamped.

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "multicue/core/point_cloud.hpp"
#include "multicue/core/types.hpp"
#include "multicue/features/feature_common.hpp"
#include "multicue/features/rsd.hpp"
#include "multicue/recognition/geometric_category.hpp"

namespace multicue {

struct PartVocabularyParams {
    std::size_t words = 100;           ///< k-means words, >= 1 (at most one per training part)
    std::size_t activations = 2;       ///< words a part activates (section 4.2.4.1: two), >= 1
    std::size_t max_iterations = 100;  ///< k-means iterations at most, >= 1
    std::uint32_t seed = 1;            ///< k-means++ seeding
    bool normalize = false;            ///< min-max scale the columns over the training parts
    bool balanced = true;  ///< part votes: divide by the category's share of the training parts
    int num_threads = 1;   ///< k-means threads (0 = all cores); never changes the result
};

class PartVocabulary {
  public:
    PartVocabulary() = default;

    /// Clusters `parts` (one feature row per training part) into min(words, rows) words and
    /// counts the categories of each word. Throws InvalidArgument for no rows, a category count
    /// different from the row count, a kNone or out-of-range category, or a bad parameter;
    /// DataError for non-finite features.
    static PartVocabulary Train(const FeatureMatrix& parts, const std::vector<Category>& categories,
                                const PartVocabularyParams& params = {});

    /// The activated words of one part, (word, p(A | f)), nearest first, summing to 1.
    /// InvalidArgument on a length mismatch or before training; DataError for non-finite values.
    std::vector<std::pair<int, float>> Activate(std::span<const float> feature) const;
    /// Category distribution of one part from the activated words' category frequencies.
    std::array<float, kNumCategories> PartProbabilities(std::span<const float> feature) const;
    /// Bag of words of a group of parts (rows): summed activations, unit sum; all zero for no
    /// rows.
    FeatureVector BagOfWords(const FeatureMatrix& parts) const;

    bool trained() const { return words_.rows() > 0; }
    std::size_t num_words() const { return static_cast<std::size_t>(words_.rows()); }
    std::size_t dims() const { return static_cast<std::size_t>(words_.cols()); }
    /// Word centres (in the normalised space when `normalize`).
    const FeatureMatrix& words() const { return words_; }
    /// Training parts per word and category.
    const std::vector<std::array<float, kNumCategories>>& word_counts() const {
        return word_counts_;
    }
    const PartVocabularyParams& params() const { return params_; }

  private:
    void Normalize(std::span<const float> in, float* out) const;
    PartVocabularyParams params_;
    FeatureMatrix words_;
    std::vector<float> lo_, scale_;  ///< min-max normalisation per column
    std::vector<std::array<float, kNumCategories>> word_counts_;
    std::vector<std::array<float, kNumCategories>> word_probabilities_;
};

/// Columns of a whole-cluster descriptor: GRSD- (21), VFH (308), three extents.
inline constexpr int kClusterDescriptorSize = 21 + 308 + 3;

struct ClusterDescriptorParams {
    VoxelRsdParams voxels = {};  ///< GRSD- voxel map (2.5 cm voxels)
    /// Weight of the extents [1/m] (sqrt(12 lambda) of the points' covariance, descending);
    /// 0 leaves them zero (GRSD- and VFH only).
    float size_weight = 0.0f;
};

/// Descriptor of one perceived object (indices into `cloud`, which needs normals): its GRSD-
/// normalised to unit sum and square-rooted (Euclidean distance = Jeffries-Matusita), its VFH
/// (viewpoint: the cloud's sensor origin) with each of the five blocks normalised to unit sum,
/// square-rooted and scaled by 1/2 (so that GRSD- and VFH weigh alike), then the weighted
/// extents. Non-finite points are skipped; fewer than 3 finite points give zeros. Throws
/// InvalidArgument for an index out of range or a negative size weight, DataError without
/// normals.
FeatureVector ComputeClusterDescriptor(const PointCloud& cloud, const Indices& indices,
                                       const ClusterDescriptorParams& params = {});

}  // namespace multicue

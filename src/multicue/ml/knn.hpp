#pragma once
/// \file Exact k-nearest-neighbour classification (section 2.5, Tables 2.2 and 2.3; section 3.1.4)
/// with the L1, L2, Hellinger, chi-squared and Jeffries-Matusita distances.
///
/// Hellinger is L2 on the square roots of the features, so L2 and Hellinger can search a k-d
/// tree; every metric can scan all rows with a vectorised loop over feature columns. Hellinger,
/// chi-squared and Jeffries-Matusita are histogram distances and need non-negative features
/// (DataError otherwise).

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "multicue/ml/classifier.hpp"

namespace multicue::ml {

enum class KnnMetric : std::uint32_t {
    kL1 = 0,         ///< sum |a - b|
    kL2 = 1,         ///< sqrt(sum (a - b)^2)
    kHellinger = 2,  ///< sqrt(sum (sqrt a - sqrt b)^2)
    kChi2 = 3,       ///< sum (a - b)^2 / (a + b), terms with a + b = 0 skipped
    kJm = 4          ///< sqrt(2 (1 - BC)), BC = sum sqrt(a_i b_i) of the unit-sum histograms
};
std::string ToString(KnnMetric m);
KnnMetric ParseKnnMetric(const std::string& name);

enum class KnnIndex : std::uint32_t {
    kAuto = 0,    ///< k-d tree for L2 and Hellinger, the column scan otherwise
    kKdTree = 1,  ///< only valid for L2 and Hellinger
    kBrute = 2
};

struct KnnParams {
    std::size_t k = 5;  ///< neighbours voting, >= 1
    KnnMetric metric = KnnMetric::kL2;
    bool distance_weighted = false;  ///< votes weighted by 1 / (distance + 1e-6)
    KnnIndex index = KnnIndex::kAuto;
    std::size_t leaf_size = 16;  ///< k-d tree bucket size
    int num_threads = 1;         ///< threads for batch prediction, 0 = all cores

    static KnnParams FromSpec(SpecArgs& args);
};

/// One neighbour: training row and distance under the metric.
struct Neighbour {
    std::uint32_t row;
    float distance;
};

/// Exact k-d tree over row-major points (squared L2), used by the classifier for L2 and
/// Hellinger. Buckets of `leaf_size` rows, split at the median of the widest dimension.
class KdTreeNd {
  public:
    KdTreeNd() = default;
    KdTreeNd(const float* data, std::size_t rows, std::size_t dims, std::size_t leaf_size);
    /// The k nearest rows by squared L2, ascending (ties by row index).
    void Search(const float* query, std::size_t k, std::vector<Neighbour>& out) const;
    std::size_t rows() const { return order_.size(); }

  private:
    struct Node {
        std::uint32_t begin, end;  ///< range in order_ (leaves)
        std::int32_t left = -1, right = -1;
        std::uint32_t dim = 0;
        float split = 0.0f;
    };
    int Build(std::uint32_t begin, std::uint32_t end);
    void SearchNode(int node, const float* q, float mindist, float* offsets,
                    std::vector<Neighbour>& heap, std::size_t k) const;
    std::vector<float> points_;  ///< rows in tree order
    std::vector<std::uint32_t> order_;
    std::vector<Node> nodes_;
    std::size_t dims_ = 0;
    std::size_t leaf_size_ = 16;
};

class KnnClassifier : public Classifier {
  public:
    explicit KnnClassifier(KnnParams params = {});
    std::string type() const override { return "knn"; }
    std::string spec() const override;
    const KnnParams& params() const { return params_; }

    /// The k nearest training rows of one query (after the metric's feature mapping).
    std::vector<Neighbour> Neighbours(std::span<const float> query) const;

  protected:
    bool NeedsScaledInput() const override {
        return params_.metric == KnnMetric::kL1 || params_.metric == KnnMetric::kL2;
    }
    void FitImpl(const FeaturesRef& x, const std::vector<int>& y, int num_classes,
                 Progress* progress) override;
    FeatureMatrix PredictImpl(const FeaturesRef& x) const override;
    void WriteModel(ByteWriter& w) const override;
    void ReadModel(ByteReader& r) override;

  private:
    void BuildIndex();
    void MapRow(const float* in, float* out) const;
    void SearchMapped(const float* q, std::vector<Neighbour>& out,
                      std::vector<float>& scratch) const;
    bool UsesTree() const;

    KnnParams params_;
    FeatureMatrix train_;   ///< training rows after the metric's mapping
    Eigen::MatrixXf cols_;  ///< train_ column-major, for the brute-force scan
    std::vector<int> labels_;
    int num_classes_ = 0;
    KdTreeNd tree_;
};

}  // namespace multicue::ml

#pragma once
/// \file Classifiers wrapping OpenCV's ml module (section 3.1.4): a multi-layer perceptron
/// (cv::ml::ANN_MLP; Bishop, 1995) and a random forest (cv::ml::RTrees).

#include <memory>
#include <string>
#include <vector>

#include "multicue/ml/classifier.hpp"

namespace multicue::ml {

struct MlpParams {
    std::vector<int> hidden = {32};  ///< neurons per hidden layer (spec: hidden=64x32)
    int iterations = 300;            ///< training iterations at most
    bool rprop = true;               ///< RPROP (else plain back-propagation)

    static MlpParams FromSpec(SpecArgs& args);
};

/// Confidences: the network's outputs (trained on one-hot targets) clamped to [0, 1] plus 1e-3,
/// normalised.
class MlpClassifier : public Classifier {
  public:
    explicit MlpClassifier(MlpParams params = {});
    ~MlpClassifier() override;
    std::string type() const override { return "mlp"; }
    std::string spec() const override;

  protected:
    void FitImpl(const FeaturesRef& x, const std::vector<int>& y, int num_classes,
                 Progress* progress) override;
    FeatureMatrix PredictImpl(const FeaturesRef& x) const override;
    void WriteModel(ByteWriter& w) const override;
    void ReadModel(ByteReader& r) override;

  private:
    struct Model;
    MlpParams params_;
    std::unique_ptr<Model> model_;
};

struct RTreesParams {
    int trees = 100;      ///< forest size, >= 1
    int max_depth = 10;   ///< >= 1
    int min_samples = 2;  ///< rows needed to split a node, >= 1
    int active_vars = 0;  ///< features tried per split; 0 = sqrt(number of features)

    static RTreesParams FromSpec(SpecArgs& args);
};

/// Confidences: the fraction of trees voting for each class.
class RTreesClassifier : public Classifier {
  public:
    explicit RTreesClassifier(RTreesParams params = {});
    ~RTreesClassifier() override;
    std::string type() const override { return "rtrees"; }
    std::string spec() const override;

  protected:
    void FitImpl(const FeaturesRef& x, const std::vector<int>& y, int num_classes,
                 Progress* progress) override;
    FeatureMatrix PredictImpl(const FeaturesRef& x) const override;
    void WriteModel(ByteWriter& w) const override;
    void ReadModel(ByteReader& r) override;

  private:
    struct Model;
    RTreesParams params_;
    std::unique_ptr<Model> model_;
};

}  // namespace multicue::ml

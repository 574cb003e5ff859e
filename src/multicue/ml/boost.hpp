#pragma once
/// \file One-against-all boosting of decision trees (OpenCV's cv::ml::Boost; Friedman et al.,
/// 1998; sections 3.1.4 and 3.3): Real, Gentle, Logit and Discrete AdaBoost. One binary model
/// per class; its summed weak responses f_c(x) (half the log-odds of the class for Real
/// AdaBoost) give the class confidences p_c = exp(2 f_c) / sum_k exp(2 f_k).

#include <memory>
#include <string>

#include "multicue/ml/classifier.hpp"

namespace multicue::ml {

enum class BoostType : std::uint32_t { kDiscrete = 0, kReal = 1, kLogit = 2, kGentle = 3 };

struct BoostParams {
    BoostType type = BoostType::kReal;
    int weak_count = 100;       ///< weak learners per class, >= 1
    int max_depth = 1;          ///< depth of each weak tree (1 = stumps), >= 1
    double weight_trim = 0.95;  ///< OpenCV weight trimming rate, [0, 1]

    static BoostParams FromSpec(SpecArgs& args);
};

class BoostClassifier : public Classifier {
  public:
    explicit BoostClassifier(BoostParams params = {});
    ~BoostClassifier() override;
    std::string type() const override { return "boost"; }
    std::string spec() const override;
    std::size_t FitSteps(std::size_t num_classes) const override { return num_classes; }
    /// Summed weak responses f_c(x), rows x classes (before the logistic link).
    FeatureMatrix RawResponses(const FeaturesRef& x) const;

  protected:
    void FitImpl(const FeaturesRef& x, const std::vector<int>& y, int num_classes,
                 Progress* progress) override;
    FeatureMatrix PredictImpl(const FeaturesRef& x) const override;
    void WriteModel(ByteWriter& w) const override;
    void ReadModel(ByteReader& r) override;

  private:
    struct Models;
    BoostParams params_;
    std::unique_ptr<Models> models_;
};

}  // namespace multicue::ml

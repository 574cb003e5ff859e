#pragma once
/// \file Support vector machines through libsvm (Chang and Lin; sections 2.5, 3.1.4, 3.3):
/// linear and RBF kernels, probability outputs (Platt scaling, pairwise coupling), and a grid
/// search over C and gamma scored by cross-validation.

#include <memory>
#include <string>
#include <vector>

#include "multicue/ml/classifier.hpp"

struct svm_model;

namespace multicue::ml {

enum class SvmKernel : std::uint32_t { kLinear = 0, kRbf = 2 };

struct SvmParams {
    SvmKernel kernel = SvmKernel::kRbf;
    double c = 1.0;           ///< soft-margin cost C, > 0
    double gamma = 0.0;       ///< RBF width; 0 = 1 / number of features
    bool probability = true;  ///< train libsvm's probability model (confidences); else votes
    bool grid_search = false;
    std::vector<double> grid_c = {0.03125, 0.125, 0.5, 2, 8, 32, 128, 512};
    std::vector<double> grid_gamma = {0.0001220703125, 0.00048828125, 0.001953125, 0.0078125,
                                      0.03125,         0.125,         0.5,         2};
    int folds = 5;            ///< cross-validation folds of the grid search, >= 2
    double cache_mb = 100.0;  ///< kernel cache
    double epsilon = 1e-3;    ///< stopping tolerance

    static SvmParams FromSpec(SpecArgs& args);
};

/// Result of a grid search: every (C, gamma) tried with its cross-validation accuracy.
struct SvmGridPoint {
    double c;
    double gamma;
    double accuracy;
};

class SvmClassifier : public Classifier {
  public:
    explicit SvmClassifier(SvmParams params = {});
    ~SvmClassifier() override;
    std::string type() const override { return "svm"; }
    std::string spec() const override;
    std::size_t FitSteps(std::size_t) const override {
        return 1 + (params_.grid_search
                        ? params_.grid_c.size() *
                              (params_.kernel == SvmKernel::kRbf ? params_.grid_gamma.size() : 1)
                        : 0);
    }
    const SvmParams& params() const { return params_; }
    /// Filled by a training run with grid_search.
    const std::vector<SvmGridPoint>& grid() const { return grid_; }
    /// C and gamma of the trained model.
    double trained_c() const { return c_; }
    double trained_gamma() const { return gamma_; }

  protected:
    bool NeedsScaledInput() const override { return params_.kernel == SvmKernel::kRbf; }
    void FitImpl(const FeaturesRef& x, const std::vector<int>& y, int num_classes,
                 Progress* progress) override;
    FeatureMatrix PredictImpl(const FeaturesRef& x) const override;
    void WriteModel(ByteWriter& w) const override;
    void ReadModel(ByteReader& r) override;

  private:
    struct ModelDeleter {
        void operator()(svm_model* m) const;
    };
    SvmParams params_;
    std::unique_ptr<svm_model, ModelDeleter> model_;
    std::string model_text_;  ///< libsvm's text form of model_ (what is saved)
    std::vector<SvmGridPoint> grid_;
    double c_ = 0.0, gamma_ = 0.0;
    int num_classes_ = 0;
};

}  // namespace multicue::ml

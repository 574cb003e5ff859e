#pragma once
/// \file One interface for every classifier (section 3.1.4, the classifier manager's contract):
/// Fit on a dataset, per-class confidences for feature rows, Save/Load in one versioned format,
/// and a factory that creates a classifier from a short text spec or loads any saved one.
///
/// The base class owns the checks every classifier needs, so none can give a silently wrong
/// answer: the number of feature columns (and, for datasets, their names) must match training,
/// features must be finite, training rows must be labelled, a model must be fitted before use.

#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "multicue/core/progress.hpp"
#include "multicue/ml/dataset.hpp"

namespace multicue::ml {

class ByteWriter;
class ByteReader;

/// Current version of the classifier model format (docs/ml.md). Version 2 added the input
/// scaling; version 1 files are still read (no scaling).
inline constexpr std::uint32_t kModelFormatVersion = 2;

/// Input scaling inside a classifier (spec key `scale`): each feature column standardised to
/// zero mean and unit variance over the training rows, the same transform applied to every
/// query. `auto` scales for the classifiers whose result depends on the features' units (SVM with
/// an RBF kernel, k-NN with the L1 or L2 metric) and not for the others (the MLP scales its
/// inputs itself, as OpenCV's network does by default).
enum class InputScaling : std::uint8_t { kAuto = 0, kNone = 1, kZScore = 2 };

class Classifier {
  public:
    virtual ~Classifier() = default;

    /// Short type name ("knn", "svm", "boost", "mlp", "rtrees"), stored in model files.
    virtual std::string type() const = 0;
    /// The parameters as a spec string that CreateClassifier accepts.
    virtual std::string spec() const = 0;

    /// Trains on every row of `train` (all must be labelled, at least 2 classes present). The
    /// model's classes are the classes present in `train`, in the dataset's order.
    void Fit(const Dataset& train, Progress* progress = nullptr);

    /// Per-class confidences, rows x num_classes, each row non-negative and summing to 1.
    FeatureMatrix PredictProba(const FeaturesRef& features) const;
    /// Same, after checking that the dataset's columns are those seen in training.
    FeatureMatrix PredictProba(const Dataset& data) const;
    /// Index into class_names() of the most confident class (lowest index on ties).
    std::vector<int> Predict(const FeaturesRef& features) const;
    std::vector<int> Predict(const Dataset& data) const;

    bool fitted() const { return !class_names_.empty(); }
    const std::vector<std::string>& class_names() const { return class_names_; }
    const std::vector<std::string>& feature_names() const { return feature_names_; }
    std::size_t num_features() const { return feature_names_.size(); }
    std::size_t num_classes() const { return class_names_.size(); }

    /// Model file bytes (a container holding type, classes, columns and the model).
    std::string Serialize() const;
    void Save(const std::filesystem::path& path) const;

    /// Progress steps Fit advances for `num_classes` classes (to size a Progress).
    virtual std::size_t FitSteps(std::size_t num_classes) const {
        (void)num_classes;
        return 1;
    }

    /// Seed of every random choice in training.
    std::uint32_t seed = 1;
    /// Scaling of the features, resolved by Fit (CreateClassifier sets it from the spec; a
    /// classifier constructed directly does not scale).
    InputScaling scaling = InputScaling::kNone;
    /// Whether the trained model standardises its inputs.
    bool scales_input() const { return scale_mean_.size() > 0; }

  protected:
    /// Whether the classifier's result depends on the units of its features (InputScaling).
    virtual bool NeedsScaledInput() const { return false; }
    /// `row` (num_features values) with the model's input scaling applied, in place.
    void ScaleRow(float* row) const;
    /// x: rows x num_features (finite); y: class index per row in [0, num_classes).
    virtual void FitImpl(const FeaturesRef& x, const std::vector<int>& y, int num_classes,
                         Progress* progress) = 0;
    /// Unnormalised non-negative scores, rows x num_classes.
    virtual FeatureMatrix PredictImpl(const FeaturesRef& x) const = 0;
    virtual void WriteModel(ByteWriter& w) const = 0;
    virtual void ReadModel(ByteReader& r) = 0;

  private:
    void CheckInput(const FeaturesRef& features) const;
    FeatureMatrix Scaled(const FeaturesRef& features) const;
    std::vector<std::string> class_names_;
    std::vector<std::string> feature_names_;
    Eigen::RowVectorXf scale_mean_;     ///< empty: no input scaling
    Eigen::RowVectorXf scale_inv_std_;  ///< 1 / standard deviation (1 for constant columns)

    friend std::unique_ptr<Classifier> DeserializeClassifier(const std::string& bytes,
                                                             const std::string& what);
};

/// Creates an unfitted classifier from a spec "type" or "type:key=value,key=value", e.g.
/// "knn:k=5,metric=hellinger", "svm:kernel=rbf,grid=1", "boost:type=real,weak=100",
/// "mlp:hidden=32", "rtrees:trees=100". Every type also takes `seed` and `scale=auto|zscore|none`
/// (InputScaling; default auto). Unknown types or keys are InvalidArgument.
std::unique_ptr<Classifier> CreateClassifier(const std::string& spec);
/// Loads any saved classifier; FormatError for another format version or a corrupt file.
std::unique_ptr<Classifier> LoadClassifier(const std::filesystem::path& path);
std::unique_ptr<Classifier> DeserializeClassifier(const std::string& bytes,
                                                  const std::string& what);

/// Throws InvalidArgument unless `classifier` is trained on exactly the columns `features`, in
/// order, and predicts only classes among `classes`. `what` prefixes the message ("fixtures"),
/// `kind` names the features in it ("fixture").
void CheckClassifierFor(const Classifier& classifier, const std::vector<std::string>& features,
                        const std::vector<std::string>& classes, const std::string& what,
                        const std::string& kind);

/// Key=value arguments of a spec; every key must be consumed (unknown keys are an error).
class SpecArgs {
  public:
    SpecArgs(const std::string& type, const std::string& args);
    std::string GetString(const std::string& key, const std::string& fallback);
    double GetDouble(const std::string& key, double fallback);
    long GetInt(const std::string& key, long fallback);
    /// Throws InvalidArgument naming the first key no Get* asked for.
    void CheckAllUsed() const;

  private:
    std::string type_;
    std::map<std::string, std::string> values_;
    std::map<std::string, bool> used_;
};

/// Index of the largest value per row (lowest index on ties).
std::vector<int> ArgMaxRows(const FeatureMatrix& scores);

}  // namespace multicue::ml

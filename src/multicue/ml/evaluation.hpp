#pragma once
/// \file Evaluation of classifiers (sections 3.1.4 and 3.3.5): accuracy, error rate, per-class
/// accuracy, confusion matrices (text and image), the adjusted Rand index, k-fold
/// cross-validation, and training and prediction times.

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "multicue/core/progress.hpp"
#include "multicue/ml/classifier.hpp"

namespace multicue::ml {

struct ConfusionMatrix {
    std::vector<std::string> class_names;
    Eigen::MatrixXi counts;  ///< rows: true class, columns: predicted class

    std::size_t total() const { return static_cast<std::size_t>(counts.sum()); }
    double Accuracy() const;  ///< trace / total (0 when empty)
    /// Entries in the rows of every true class but `excluded` (e.g. a "none" class that is not
    /// scored as truth; its column still counts as a wrong prediction). InvalidArgument for an
    /// index out of range.
    std::size_t TotalExcluding(int excluded) const;
    /// Correct / TotalExcluding(excluded) (0 when those rows are empty).
    double AccuracyExcluding(int excluded) const;
    double ErrorRate() const;  ///< 1 - accuracy
    /// Per true class: correct / rows of that class (NaN for a class without rows).
    std::vector<double> PerClassAccuracy() const;
    /// A table with class names, counts and per-class accuracy.
    std::string ToText() const;
    /// Writes a binary PPM (P6) heat map of the row-normalised matrix, `cell` pixels per entry:
    /// white = 0, dark blue = 1. Atomic write.
    void WriteImage(const std::filesystem::path& path, int cell = 16) const;
};

/// Confusion of `predicted` against `truth` (class indices into class_names; rows with truth
/// kNoLabel are skipped). InvalidArgument on length mismatch or an index out of range.
ConfusionMatrix Confusion(const std::vector<int>& truth, const std::vector<int>& predicted,
                          const std::vector<std::string>& class_names);

/// Confusion counts gathered one (truth, predicted) pair at a time, over a fixed set of classes.
/// Counts are 64-bit; ToMatrix gives the ConfusionMatrix once counting is done.
class ConfusionCounter {
  public:
    explicit ConfusionCounter(std::vector<std::string> class_names);

    /// Counts `count` items of class `truth` predicted as `predicted` (class indices; truth
    /// kNoLabel is skipped as in Confusion). InvalidArgument for an index out of range.
    void Add(int truth, int predicted, std::size_t count = 1);
    /// Adds the counts of `other`; InvalidArgument unless both have the same class names.
    void Merge(const ConfusionCounter& other);
    /// Sets every count to zero.
    void Clear();

    const std::vector<std::string>& class_names() const { return class_names_; }
    std::size_t num_classes() const { return class_names_.size(); }
    std::size_t count(int truth, int predicted) const;
    std::size_t total() const;
    /// The counts as a ConfusionMatrix; DataError if one does not fit its int entries.
    ConfusionMatrix ToMatrix() const;

  private:
    std::size_t At(int truth, int predicted) const;
    std::vector<std::string> class_names_;
    std::vector<std::uint64_t> counts_;  ///< row-major, rows: true class
};

/// Fraction of equal entries (rows with truth kNoLabel skipped).
double Accuracy(const std::vector<int>& truth, const std::vector<int>& predicted);

/// Adjusted Rand index of two partitions of the same items (Hubert and Arabie, 1985): 1 for
/// identical partitions up to renaming, about 0 for independent ones.
double AdjustedRandIndex(const std::vector<int>& a, const std::vector<int>& b);

struct EvaluationResult {
    ConfusionMatrix confusion;
    double accuracy = 0.0;
    double predict_seconds = 0.0;  ///< whole test set
    double predict_ms_per_row = 0.0;
};

/// Predicts `test` and compares with its labels, mapped onto the classifier's classes by name
/// (DataError for a label the classifier has not seen in training).
EvaluationResult Evaluate(const Classifier& classifier, const Dataset& test);

struct CrossValidationResult {
    std::vector<double> fold_accuracy;
    double mean_accuracy = 0.0;
    double stddev_accuracy = 0.0;
    double train_seconds = 0.0;    ///< summed over folds
    double predict_seconds = 0.0;  ///< summed over folds
    ConfusionMatrix confusion;     ///< pooled over the folds
};

/// k-fold cross-validation of a classifier spec (CreateClassifier); by_group keeps instances
/// inside one fold. Progress advances once per fold.
CrossValidationResult CrossValidate(const std::string& spec, const Dataset& data, std::size_t k,
                                    std::uint32_t seed, bool by_group,
                                    Progress* progress = nullptr);

}  // namespace multicue::ml

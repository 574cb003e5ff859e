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
    double Accuracy() const;   ///< trace / total (0 when empty)
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

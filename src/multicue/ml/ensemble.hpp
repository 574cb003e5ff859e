#pragma once
/// \file Ensembles of strong learners trained on subsets of the feature blocks (section 3.3):
/// max rules and the product rule (3.3.1), weighted voting (3.3.2), the error-correlation linear
/// combination (3.3.3, Bishop) and stacking with a three-way split (3.3.4). Every rule consumes
/// per-class confidences, so any classifier can be a member. Formulas: docs/ml.md.

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "multicue/core/progress.hpp"
#include "multicue/ml/classifier.hpp"

namespace multicue::ml {

enum class EnsembleRule : std::uint32_t {
    kMaxAccuracy = 0,               ///< member whose decision has the best class-cond. accuracy
    kMaxConfidence = 1,             ///< member most confident in its decision
    kMaxAccuracyConfidence = 2,     ///< member maximising class-cond. accuracy x confidence
    kProduct = 3,                   ///< product of the members' confidences
    kAccuracyVoting = 4,            ///< votes weighted by the member's accuracy
    kConfidenceVoting = 5,          ///< votes weighted by the member's confidence
    kAccuracyConfidenceVoting = 6,  ///< votes weighted by class-cond. accuracy x confidence
    kErrorCorrelation = 7,          ///< linear combination minimising the correlated error
    kStacking = 8                   ///< a level-1 classifier on the members' confidences
};
std::string ToString(EnsembleRule rule);
EnsembleRule ParseEnsembleRule(const std::string& name);
/// Every rule except stacking, in enum order.
std::vector<EnsembleRule> SimpleRules();

/// What the rules know about a member, estimated on a validation set.
struct MemberStatistics {
    double accuracy = 0.0;  ///< fraction of validation rows the member gets right
    /// Class-conditional accuracy a(c) = P(true class = c | member decides c); a class the member
    /// never decided on the validation set gets the overall accuracy.
    std::vector<double> class_accuracy;
};

/// Statistics of one member from its validation confidences and the true classes.
MemberStatistics EstimateMemberStatistics(const FeatureMatrix& confidences,
                                          const std::vector<int>& truth);

/// Error-correlation weights (section 3.3.3; Bishop): with e_m the member's error vector
/// (confidences minus one-hot truth) over all validation rows, C_ij = mean(e_i . e_j) and
/// w = C^-1 1 / (1' C^-1 1). `ridge` (relative to mean(diag C)) keeps C invertible.
Eigen::VectorXd ErrorCorrelationWeights(const std::vector<FeatureMatrix>& confidences,
                                        const std::vector<int>& truth, double ridge = 1e-6);

/// Combines the members' confidences (each rows x classes) with a simple rule; the result has
/// non-negative rows summing to 1, its argmax is the ensemble's decision. Ties go to the lowest
/// member or class index. `stats` is needed by the accuracy rules, `weights` by the
/// error-correlation rule.
FeatureMatrix CombineConfidences(EnsembleRule rule, const std::vector<FeatureMatrix>& confidences,
                                 const std::vector<MemberStatistics>& stats,
                                 const Eigen::VectorXd& weights = {});

/// One member: a classifier on the columns of some feature blocks.
struct EnsembleMember {
    std::string name;                 ///< blocks joined by '+', e.g. "vfh+grsd"
    std::vector<std::string> blocks;  ///< feature blocks it sees, in this order
    std::unique_ptr<Classifier> classifier;
};

/// All subsets of `blocks` with min_size..max_size elements, ordered by size then
/// lexicographically by position ("singles, doubles, triples", section 3.3.5.1).
std::vector<std::vector<std::string>> FeatureSubsets(const std::vector<std::string>& blocks,
                                                     std::size_t min_size, std::size_t max_size);

struct EnsembleParams {
    std::string member_spec = "boost:type=real";    ///< CreateClassifier spec of every member
    std::vector<std::vector<std::string>> subsets;  ///< block subsets; empty = every single block
    std::string level1_spec;                        ///< stacking's level-1 classifier ("" = none)
    std::uint32_t seed = 1;
};

class Ensemble {
  public:
    EnsembleRule rule = EnsembleRule::kAccuracyConfidenceVoting;
    std::vector<std::string> class_names;
    std::vector<EnsembleMember> members;
    std::vector<MemberStatistics> stats;       ///< per member, from the level-1 training part
    Eigen::VectorXd weights;                   ///< error-correlation weights
    std::unique_ptr<Classifier> level1;        ///< stacking
    std::vector<std::int64_t> level1_row_ids;  ///< rows the statistics and level 1 were fitted on

    /// Each member's confidences on `data` (its own blocks), columns in class_names order.
    std::vector<FeatureMatrix> MemberConfidences(const Dataset& data) const;
    /// The level-1 dataset: members' confidences side by side (block per member) with data's
    /// labels, groups and row ids.
    Dataset Level1Dataset(const Dataset& data) const;
    /// Combined confidences under `rule` (the stored rule unless given).
    FeatureMatrix PredictProba(const Dataset& data) const;
    FeatureMatrix PredictProba(const Dataset& data, EnsembleRule with_rule) const;
    std::vector<int> Predict(const Dataset& data) const;

    void Save(const std::filesystem::path& path) const;
    static Ensemble Load(const std::filesystem::path& path);
};

/// Trains an ensemble with the three-way split of section 3.3.4: members on `level0_train`,
/// member statistics, error-correlation weights and (if params.level1_spec) the level-1
/// classifier on the members' predictions for `level1_train`. The two parts must not share a
/// row id (DataError): level 1 never sees rows the members were trained on.
Ensemble TrainEnsemble(const Dataset& level0_train, const Dataset& level1_train,
                       const EnsembleParams& params, Progress* progress = nullptr);

inline constexpr std::uint32_t kEnsembleFormatVersion = 1;

}  // namespace multicue::ml

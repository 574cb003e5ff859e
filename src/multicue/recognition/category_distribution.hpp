#pragma once
/// \file Category distributions and every way multicue combines them (thesis sections 3.3.1 and
/// 5.1.2): priors, the weighted product of experts behind perceive's fused categorisers, the
/// restriction to the categories a model allows, and the most probable category. Distributions
/// are indexed by Category; kNone is the "no category" entry. (Classifier ensembles over feature
/// datasets, which know nothing of categories, combine their members' confidences in
/// ml/ensemble.hpp.)

#include <array>
#include <span>

#include <Eigen/Core>

#include "multicue/recognition/geometric_category.hpp"

namespace multicue {

/// One probability per category (indexed by the enum value).
using CategoryDistribution = std::array<float, kNumCategories>;

/// Equal prior weights for every category.
constexpr CategoryDistribution UniformCategoryPriors() {
    CategoryDistribution p{};
    for (float& x : p) x = 1.0f;
    return p;
}

/// `p` times `priors` per category (kNone kept as is), normalised; all zero stays all zero.
CategoryDistribution ApplyCategoryPriors(const CategoryDistribution& p,
                                         const CategoryDistribution& priors);

/// Weighted product of experts: per real category the product over the experts of
/// max(p, 0.01)^(w / sum of the weights), normalised (kNone gets 0). The floor keeps one expert's
/// zero from vetoing a category outright. InvalidArgument unless there is one weight per expert,
/// each >= 0 and finite, and not all 0.
CategoryDistribution WeightedProductOfExperts(std::span<const CategoryDistribution* const> experts,
                                              std::span<const float> weights);

/// Product of experts of two distributions: per real category
/// max(a, 0.01)^(1 - w) * max(b, 0.01)^w, normalised (kNone gets 0). InvalidArgument unless
/// w is in [0, 1].
CategoryDistribution BlendCategoryProbabilities(const CategoryDistribution& a,
                                                const CategoryDistribution& b, float w);

/// Throws InvalidArgument unless the three expert weights are finite, >= 0 and not all 0.
void CheckExpertWeights(const Eigen::Vector3f& weights);

/// The three experts of perceive's "part-graph+rules+cluster": rules^a * part-graph^b *
/// cluster^c, normalised, with (a, b, c) = `weights` / their sum and each probability floored at
/// 0.01 first; an all-zero cluster expert (a model without cluster rows) leaves rules and
/// part-graph, their weights renormalised (only the rules when only the cluster was weighted).
/// Throws InvalidArgument for negative, non-finite or all-zero weights.
CategoryDistribution BlendThreeExperts(const CategoryDistribution& rules,
                                       const CategoryDistribution& part_graph,
                                       const CategoryDistribution& cluster,
                                       const Eigen::Vector3f& weights = Eigen::Vector3f::Ones());

/// The most probable category of a distribution (ties to the lower value).
Category ArgMaxCategory(const CategoryDistribution& p);

/// Keeps only the `allowed` categories of `c` (renormalised; uniform over them when none has
/// any probability) and sets its category and confidence; empty `allowed` or category kNone
/// leave it unchanged. Used when a model decides what an object can be (two boxes: box or flat).
void RestrictCategories(CategoryResult& c, std::span<const Category> allowed);

}  // namespace multicue

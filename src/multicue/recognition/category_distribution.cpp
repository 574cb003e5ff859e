#include "multicue/recognition/category_distribution.hpp"

#include <algorithm>
#include <cmath>

#include "multicue/core/exceptions.hpp"

namespace multicue {

CategoryDistribution ApplyCategoryPriors(const CategoryDistribution& p,
                                         const CategoryDistribution& priors) {
    CategoryDistribution out = p;
    float sum = 0.0f;
    for (std::size_t c = 1; c < kNumCategories; ++c) out[c] *= priors[c];
    for (float x : out) sum += x;
    if (sum > 0.0f) {
        for (float& x : out) x /= sum;
    }
    return out;
}

CategoryDistribution WeightedProductOfExperts(std::span<const CategoryDistribution* const> experts,
                                              std::span<const float> weights) {
    if (experts.size() != weights.size()) {
        throw InvalidArgument("product of experts: one weight per expert");
    }
    float total = 0.0f;
    for (float w : weights) {
        if (!(w >= 0.0f) || !std::isfinite(w)) {
            throw InvalidArgument("product of experts: weights must be >= 0 and finite");
        }
        total += w;
    }
    if (!(total > 0.0f)) throw InvalidArgument("product of experts: all weights are 0");
    constexpr float kFloor = 0.01f;
    CategoryDistribution p{};
    float sum = 0.0f;
    for (std::size_t c = 1; c < kNumCategories; ++c) {
        float log_p = 0.0f;
        for (std::size_t e = 0; e < experts.size(); ++e) {
            log_p += weights[e] / total * std::log(std::max((*experts[e])[c], kFloor));
        }
        p[c] = std::exp(log_p);
        sum += p[c];
    }
    for (float& x : p) x /= sum;
    return p;
}

CategoryDistribution BlendCategoryProbabilities(const CategoryDistribution& a,
                                                const CategoryDistribution& b, float w) {
    if (!(w >= 0.0f && w <= 1.0f)) throw InvalidArgument("blend weight must be in [0, 1]");
    const std::array<const CategoryDistribution*, 2> experts{&a, &b};
    const std::array<float, 2> weights{1.0f - w, w};
    return WeightedProductOfExperts(experts, weights);
}

void CheckExpertWeights(const Eigen::Vector3f& w) {
    if (!w.allFinite() || !(w.minCoeff() >= 0.0f) || !(w.sum() > 0.0f)) {
        throw InvalidArgument("category.expert_weights must be finite, >= 0 and not all 0");
    }
}

CategoryDistribution BlendThreeExperts(const CategoryDistribution& rules,
                                       const CategoryDistribution& part_graph,
                                       const CategoryDistribution& cluster,
                                       const Eigen::Vector3f& weights) {
    CheckExpertWeights(weights);
    const std::array<const CategoryDistribution*, 3> experts{&rules, &part_graph, &cluster};
    const std::array<float, 3> w{weights[0], weights[1], weights[2]};
    // A model without cluster rows gives an all-zero cluster expert: it drops out.
    const bool has_cluster = *std::max_element(cluster.begin(), cluster.end()) > 0.0f;
    const std::size_t n = has_cluster ? 3 : 2;
    if (!(w[0] + w[1] > 0.0f) && !has_cluster) return rules;  // only the absent one was weighted
    return WeightedProductOfExperts(std::span(experts).first(n), std::span(w).first(n));
}

Category ArgMaxCategory(const CategoryDistribution& p) {
    std::size_t best = 0;
    for (std::size_t c = 1; c < kNumCategories; ++c) {
        if (p[c] > p[best]) best = c;
    }
    return static_cast<Category>(best);
}

void RestrictCategories(CategoryResult& c, std::span<const Category> allowed) {
    if (allowed.empty() || c.category == Category::kNone) return;
    CategoryDistribution p{};
    float sum = 0.0f;
    for (Category a : allowed) {
        const auto k = static_cast<std::size_t>(a);
        p[k] = c.probabilities[k];
        sum += p[k];
    }
    for (Category a : allowed) {
        const auto k = static_cast<std::size_t>(a);
        p[k] = sum > 0.0f ? p[k] / sum : 1.0f / static_cast<float>(allowed.size());
    }
    c.probabilities = p;
    c.category = ArgMaxCategory(p);
    c.confidence = p[static_cast<std::size_t>(c.category)];
}

}  // namespace multicue

#include "multicue/system/object_categories.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/core/parallel.hpp"
#include "multicue/core/params.hpp"
#include "multicue/core/task_order.hpp"
#include "multicue/recognition/category_stacker.hpp"
#include "multicue/recognition/part_vocabulary.hpp"

namespace multicue {
namespace {

// The objects `which` refers to: all of them when it is empty.
std::vector<std::size_t> Targets(std::size_t n, std::span<const std::size_t> which) {
    std::vector<std::size_t> out;
    if (which.empty()) {
        for (std::size_t k = 0; k < n; ++k) out.push_back(k);
        return out;
    }
    for (std::size_t k : which) {
        if (k >= n) throw InvalidArgument(fmt::format("object {} of {} to categorise", k, n));
        out.push_back(k);
    }
    return out;
}

// One object's fused distribution from the rules' (c) and the part-graph's (p).
CategoryDistribution Fuse(const CategorizationParams& params, const PartGraphModel& model,
                          const PointCloud& cloud, const PerceivedObject& o,
                          const CategoryResult& c, const CategoryDistribution& p) {
    switch (params.categoriser) {
        case Categoriser::kPartGraphRules:
            return BlendCategoryProbabilities(c.probabilities, p, params.part_graph_weight);
        case Categoriser::kThreeExperts:
            return BlendThreeExperts(c.probabilities, p,
                                     ClusterExpert(model, cloud, o.indices, params),
                                     params.expert_weights);
        case Categoriser::kStacked:
            return model.stacker.Predict(
                StackerInputs(c, p, ClusterExpert(model, cloud, o.indices, params)));
        case Categoriser::kRules:
        case Categoriser::kPartGraph:
            break;
    }
    return p;
}

}  // namespace

std::string_view CategoriserName(Categoriser categoriser) {
    const auto k = static_cast<std::size_t>(categoriser);
    if (k >= kCategoriserNames.size()) throw InvalidArgument("unknown categoriser");
    return kCategoriserNames[k];
}

Categoriser ParseCategoriser(std::string_view name) {
    for (std::size_t k = 0; k < kCategoriserNames.size(); ++k) {
        if (kCategoriserNames[k] == name) return static_cast<Categoriser>(k);
    }
    throw InvalidArgument(fmt::format(
        "categoriser must be rules, part-graph, part-graph+rules, part-graph+rules+cluster or "
        "stacked, got '{}'",
        name));
}

void CategorizationParams::Validate() const {
    CategoriserName(categoriser);  // one of the enumerators
    ValidateNode("rules", [&] { rules.Validate(); });
    ValidateNode("part_graph", [&] { part_graph.Validate(); });
    if (!(part_graph_weight >= 0.0f && part_graph_weight <= 1.0f)) {
        throw InvalidArgument("part_graph_weight must be in [0, 1]");
    }
    CheckExpertWeights(expert_weights);
    if (cluster_k < 1) throw InvalidArgument("cluster_k must be >= 1");
    if (!(cylinder_profile_ratio == 0.0f || cylinder_profile_ratio >= 1.0f) ||
        !std::isfinite(cylinder_profile_ratio)) {
        throw InvalidArgument(fmt::format("cylinder_profile_ratio must be 0 or >= 1, got {}",
                                          cylinder_profile_ratio));
    }
    ResolveThreadCount(num_threads);
}

void CategorizeByModels(std::vector<PerceivedObject>& objects, const CategorizationParams& params) {
    if (params.cylinder_profile_ratio == 0.0f) return;
    for (PerceivedObject& o : objects) {
        const Category c = o.category.category;
        const auto& rot = o.model.rotational;
        if ((c != Category::kOther && c != Category::kSphere) || !o.model.accepted || !rot ||
            rot->radii.size() < 2) {
            continue;
        }
        const auto [lo, hi] = std::minmax_element(rot->radii.begin(), rot->radii.end());
        const float height = rot->heights.back() - rot->heights.front();
        if (*lo > 0.0f && *hi <= params.cylinder_profile_ratio * *lo && height >= *hi) {
            o.category.category = Category::kCylinder;
            o.category.confidence =
                o.category.probabilities[static_cast<std::size_t>(Category::kCylinder)];
            o.category_from_model = true;
        }
    }
}

void CheckCategorizationModel(const CategorizationParams& params, const PartGraphModel* model) {
    if (!params.NeedsPartGraph()) return;
    if (model == nullptr) {
        throw InvalidArgument(fmt::format(
            "category.categoriser {} needs a part-graph model (category.part_graph_model, or the "
            "default model)",
            CategoriserName(params.categoriser)));
    }
    if (params.categoriser == Categoriser::kStacked && !model->stacker.trained()) {
        throw InvalidArgument(
            "category.categoriser stacked needs a part-graph model with a stacker "
            "(multicue train --stacker-scenes N)");
    }
}

CategoryDistribution ClusterExpert(const PartGraphModel& model, const PointCloud& cloud,
                                   const Indices& object, const CategorizationParams& params) {
    ClusterDescriptorParams cp;
    cp.size_weight = model.cluster_size_weight;
    return ApplyCategoryPriors(
        model.ClassifyCluster(ComputeClusterDescriptor(cloud, object, cp), params.cluster_k),
        params.part_graph.category_priors);
}

PartGraphVotes VotePartGraph(const PartGraphModel& model, const PointCloud& cloud,
                             const std::vector<PerceivedObject>& objects,
                             const Eigen::Vector4f& plane, const CategorizationParams& params,
                             std::span<const std::size_t> which) {
    const std::vector<std::size_t> targets = Targets(objects.size(), which);
    std::vector<Indices> parts;
    std::vector<std::uint32_t> groups;
    std::vector<std::vector<std::size_t>> ids(targets.size());
    for (std::size_t r = 0; r < targets.size(); ++r) {
        for (const auto& part : objects[targets[r]].parts) {
            ids[r].push_back(parts.size());
            parts.push_back(part);
            groups.push_back(static_cast<std::uint32_t>(r));
        }
    }
    const PartGraphResult votes =
        RecognizeParts(model, cloud, parts, params.part_graph, plane.head<3>(), groups);
    PartGraphVotes out;
    out.parts.resize(targets.size());
    out.objects.resize(targets.size());
    for (std::size_t r = 0; r < targets.size(); ++r) {
        for (std::size_t id : ids[r]) out.parts[r].push_back(votes.part_probabilities[id]);
        out.objects[r] = MergePartProbabilities(votes, parts, ids[r]);
    }
    return out;
}

void CategorizeObjects(const PointCloud& cloud, std::vector<PerceivedObject>& objects,
                       const Eigen::Vector4f& plane, const CategorizationParams& params,
                       const PartGraphModel* model, std::span<const std::size_t> which,
                       std::span<const Category> allowed) {
    params.Validate();
    CheckCategorizationModel(params, model);
    const std::vector<std::size_t> targets = Targets(objects.size(), which);
    CategoryParams rules = params.rules;
    // Objects run in parallel; the fits inside one (its consensus scoring) help where objects
    // are few or of unequal size, nested in the same threads. The result does not depend on it.
    rules.num_threads = params.num_threads;
    // The largest objects first: a large one started last would keep one thread busy alone.
    const std::vector<std::size_t> order = LargestFirst(
        targets.size(), [&](std::size_t r) { return objects[targets[r]].indices.size(); });
    ParallelFor(
        order.size(), params.num_threads,
        [&](std::size_t q) {
            PerceivedObject& o = objects[targets[order[q]]];
            o.category = CategorizeObject(cloud, o.indices, o.parts, plane, rules);
            RestrictCategories(o.category, allowed);
        },
        1);
    if (!params.NeedsPartGraph() || targets.empty()) return;
    PartGraphVotes votes = VotePartGraph(*model, cloud, objects, plane, params, targets);
    for (std::size_t r = 0; r < targets.size(); ++r) {
        PerceivedObject& o = objects[targets[r]];
        o.part_probabilities = std::move(votes.parts[r]);
        CategoryResult& c = o.category;
        if (c.category != Category::kNone && !o.parts.empty()) {
            const CategoryDistribution p = Fuse(params, *model, cloud, o, c, votes.objects[r]);
            c.probabilities = p;
            c.category = ArgMaxCategory(p);
            c.confidence = p[static_cast<std::size_t>(c.category)];
        }
        RestrictCategories(c, allowed);
    }
}

}  // namespace multicue

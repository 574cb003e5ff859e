#pragma once
/// \file The categories of perceived objects (thesis sections 3.1, 3.3 and 5.1): the rule-based
/// categoriser (CategorizeObject), part-graph hashing over the objects' parts and the model's
/// whole-object k-NN, alone or fused as a weighted product of experts or by a trained stacker.

#include <array>
#include <cstddef>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "multicue/core/point_cloud.hpp"
#include "multicue/recognition/category_distribution.hpp"
#include "multicue/recognition/geometric_category.hpp"
#include "multicue/recognition/part_graph_model.hpp"
#include "multicue/reconstruction/object_model.hpp"

namespace multicue {

/// Who decides an object's category.
enum class Categoriser {
    kRules,           ///< "rules": CategorizeObject's geometric rules alone
    kPartGraph,       ///< "part-graph": the parts' part-graph votes (docs: recognition)
    kPartGraphRules,  ///< "part-graph+rules": rules^(1 - w) * part-graph^w, w = part_graph_weight
    /// "part-graph+rules+cluster": rules^a * part-graph^b * cluster^c, (a, b, c) = expert_weights
    /// normalised, cluster being the model's whole-object k-NN (BlendThreeExperts); without
    /// cluster rows in the model, rules and part-graph alone.
    kThreeExperts,
    /// "stacked": the model's level-1 classifier over the three experts and the rules' evidence
    /// (CategoryStacker; the model must have been trained with stacker scenes).
    kStacked,
};

/// The configuration names of the categorisers, in the order of the enum.
inline constexpr std::array<std::string_view, 5> kCategoriserNames = {
    "rules", "part-graph", "part-graph+rules", "part-graph+rules+cluster", "stacked"};

/// The configuration name of a categoriser ("rules", "part-graph", ...).
std::string_view CategoriserName(Categoriser categoriser);
/// The categoriser of a configuration name; InvalidArgument listing the names otherwise.
Categoriser ParseCategoriser(std::string_view name);

struct CategorizationParams {
    Categoriser categoriser = Categoriser::kRules;
    /// Part-graph model file of the learned categorisers; empty: the caller's default model
    /// (perceive itself takes the loaded model, PerceiveModels).
    std::string part_graph_model;
    /// The rules. Fewer samples than the defaults of a one-off call keep a frame within budget
    /// at the same accuracy on the mOSD learn scenes.
    CategoryParams rules{.max_points = 1500, .max_iterations = 400};
    /// Part-graph recognition: parts grouped by object, and "other" with a third of the weight
    /// of the other categories. The balanced votes treat every category as equally likely, while
    /// "other" (pitchers, tools, irregular shapes) is the rarest category on tables and the one
    /// whose training shapes overlap most with cups, mugs and bottles (chosen on simulated
    /// clutter scenes of held-out meshes).
    PartGraphRecognitionParams part_graph = [] {
        PartGraphRecognitionParams p;
        p.category_priors[static_cast<std::size_t>(Category::kOther)] = 0.3f;
        return p;
    }();
    float part_graph_weight = 0.4f;  ///< w of "part-graph+rules" [-]; [0, 1]
    /// Weights of the rules, the part-graph and the cluster expert in "part-graph+rules+cluster"
    /// (normalised to sum 1), chosen on simulated clutter scenes of seeds other than those the
    /// evaluation reports; finite, >= 0, not all 0.
    Eigen::Vector3f expert_weights{0.25f, 0.65f, 0.10f};
    std::size_t cluster_k = 5;  ///< neighbours of the whole-object expert [-]; >= 1
    /// Categories by the model (CategorizeByModels): an "other" or "sphere" object whose kept
    /// model is a surface of revolution at least as high as its largest radius, with radii
    /// within this ratio of each other, is a cylinder (a mug whose handle and noise split it
    /// into many parts) [-]; 0 = off, else >= 1.
    float cylinder_profile_ratio = 1.15f;
    int num_threads = 0;  ///< objects categorised in parallel; 0 = all cores
    /// Whether the categoriser needs a part-graph model (every one but the rules).
    bool NeedsPartGraph() const { return categoriser != Categoriser::kRules; }
    /// Throws InvalidArgument (ParameterError for a sub-node) naming the first bad field.
    void Validate() const;
    /// Its parameters once each: configuration key (the field's name), field, meaning. A
    /// visitor reads or records them (io::ConfigSection::operator(); ReadPerceiveParams).
    template <typename V>
    void VisitParams(V& v) {
        std::string name(CategoriserName(categoriser));
        v.GetChoice("categoriser", name, kCategoriserNames, "who decides the categories");
        categoriser = ParseCategoriser(name);
        v("part_graph_model", part_graph_model,
          "part-graph model file (empty: the default model, trained once and cached)");
        v.Node("rules", rules);
        v.Node("part_graph", part_graph);
        v("part_graph_weight", part_graph_weight,
          "weight of the part-graph votes against the rules in part-graph+rules, [0, 1]");
        v("expert_weights", expert_weights,
          "weights of the rules, part-graph and cluster experts in part-graph+rules+cluster");
        v("cluster_k", cluster_k,
          "neighbours of the whole-object expert (part-graph+rules+cluster, stacked)");
        v("cylinder_profile_ratio", cylinder_profile_ratio,
          "other/sphere objects whose kept surface of revolution has radii within this ratio "
          "(and is as high as wide) are cylinders, 0 = off");
    }
};

/// Categories by the kept models: see CategorizationParams::cylinder_profile_ratio. Sets
/// `category.category` (the experts' probabilities stay) and `category_from_model`.
void CategorizeByModels(std::vector<PerceivedObject>& objects, const CategorizationParams& params);

/// Throws InvalidArgument when `params` needs a part-graph model and `model` is null, or the
/// stacked categoriser's model has no stacker.
void CheckCategorizationModel(const CategorizationParams& params, const PartGraphModel* model);

/// The whole-object expert: the model's cluster k-NN (params.cluster_k) on the object's GRSD-
/// and VFH descriptor, weighted by the part-graph category priors; all zero when the model has
/// no cluster rows.
CategoryDistribution ClusterExpert(const PartGraphModel& model, const PointCloud& cloud,
                                   const Indices& object, const CategorizationParams& params);

/// The part-graph expert: one graph over the parts of the objects `which` (indices into
/// `objects`; empty = all), each part grouped with its object (params.part_graph), up from
/// `plane` (a, b, c, d; zero when unknown).
struct PartGraphVotes {
    std::vector<std::vector<CategoryDistribution>> parts;  ///< per object, one per part
    std::vector<CategoryDistribution> objects;  ///< per object: point-weighted merge of its parts
};
PartGraphVotes VotePartGraph(const PartGraphModel& model, const PointCloud& cloud,
                             const std::vector<PerceivedObject>& objects,
                             const Eigen::Vector4f& plane, const CategorizationParams& params,
                             std::span<const std::size_t> which = {});

/// Categorises the objects `which` (empty = all; indices and parts set, `cloud` with normals)
/// on the support plane `plane` (zero when unknown): the rules for each, then, for the learned
/// categorisers, the part-graph votes over all of them (which also set the objects'
/// part_probabilities) fused per object as params.categoriser says. Objects the rules leave
/// without a category (too few points) or without parts keep the rules' result. With `allowed`
/// (a grouping model's categories), the rules' distribution is restricted to them before it is
/// fused and the result after. `model` must be given for the learned categorisers
/// (CheckCategorizationModel). Deterministic for any thread count.
void CategorizeObjects(const PointCloud& cloud, std::vector<PerceivedObject>& objects,
                       const Eigen::Vector4f& plane, const CategorizationParams& params,
                       const PartGraphModel* model, std::span<const std::size_t> which = {},
                       std::span<const Category> allowed = {});

}  // namespace multicue

#include "multicue/system/perceive.hpp"

#include <map>
#include <mutex>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <string_view>
#include <vector>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/core/logging.hpp"
#include "multicue/core/parallel.hpp"
#include "multicue/recognition/part_vocabulary.hpp"
#include "multicue/search/kdtree.hpp"

namespace multicue {
namespace {

class StageTimer {
  public:
    explicit StageTimer(std::vector<std::pair<std::string, double>>& out) : out_(out) {}
    void Done(const char* stage) {
        const auto now = std::chrono::steady_clock::now();
        out_.emplace_back(stage, std::chrono::duration<double, std::milli>(now - start_).count());
        start_ = now;
    }

  private:
    std::vector<std::pair<std::string, double>>& out_;
    std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
};

}  // namespace

void EnsurePerceiveNormals(PointCloud& cloud, const Indices& roi, const PerceiveParams& params) {
    if (cloud.HasNormals() && cloud.HasCurvature()) return;
    NormalsResult normals;
    if (cloud.IsOrganized()) {
        OrganizedNormalParams p = params.organized_normals;
        p.num_threads = params.num_threads;
        p.mask.assign(cloud.size(), 0);
        for (Index i : roi) p.mask[i] = 1;
        normals = EstimateNormalsOrganized(cloud, p);
    } else {
        NormalParams p = params.normals;
        p.num_threads = params.num_threads;
        const KdTree tree(cloud);
        normals = EstimateNormals(cloud, tree, p);
    }
    SetNormals(cloud, std::move(normals));
}

namespace {

ClusteringResult ClusterObjects(const PointCloud& cloud, const Indices& roi,
                                const PerceiveParams& params) {
    if (cloud.IsOrganized()) {
        OrganizedClusteringParams p;
        p.tolerance = params.cluster_tolerance;
        p.min_cluster_size = params.min_object_points;
        p.max_cluster_size = params.max_object_points;
        p.subset = roi;
        p.half_window = params.organized_half_window;
        return EuclideanClusteringOrganized(cloud, p);
    }
    const KdTree tree(cloud, roi);
    EuclideanClusteringParams p;
    p.tolerance = params.cluster_tolerance;
    p.min_cluster_size = params.min_object_points;
    p.max_cluster_size = params.max_object_points;
    p.subset = roi;
    return EuclideanClustering(cloud, tree, p);
}

Eigen::Vector3f Centroid(const PointCloud& cloud, const Indices& indices) {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (Index i : indices) sum += cloud.points[i].cast<double>();
    return (sum / std::max<std::size_t>(1, indices.size())).cast<float>();
}

// Fragments of one object split by a nearer occluder become one object (MergeOccludedFragments);
// ids are renumbered in the order of the merged objects' first fragments.
std::vector<PerceivedObject> MergeOccluded(const PointCloud& cloud,
                                           std::vector<PerceivedObject> objects,
                                           const Eigen::Vector4f& plane,
                                           const PerceiveParams& params) {
    std::vector<Indices> indices;
    std::vector<std::vector<Indices>> parts;
    indices.reserve(objects.size());
    parts.reserve(objects.size());
    for (const auto& o : objects) {
        indices.push_back(o.indices);
        parts.push_back(o.parts);
    }
    const OcclusionMergeResult merged =
        MergeOccludedFragments(cloud, indices, parts, plane, params.occlusion);
    if (merged.merges == 0) return objects;
    std::vector<PerceivedObject> out;
    out.reserve(merged.groups.size());
    for (const auto& group : merged.groups) {
        PerceivedObject o = std::move(objects[group.front()]);
        for (std::size_t k = 1; k < group.size(); ++k) {
            auto& other = objects[group[k]];
            o.indices.insert(o.indices.end(), other.indices.begin(), other.indices.end());
            for (auto& part : other.parts) o.parts.push_back(std::move(part));
        }
        std::sort(o.indices.begin(), o.indices.end());
        o.id = static_cast<int>(out.size() + 1);
        out.push_back(std::move(o));
    }
    LogDebug("perceive: {} occluded fragments joined", merged.merges);
    return out;
}

}  // namespace

CategoryDistribution ClusterExpert(const PartGraphModel& model, const PointCloud& cloud,
                                   const Indices& object, const PerceiveParams& params) {
    ClusterDescriptorParams cp;
    cp.size_weight = model.cluster_size_weight;
    return ApplyCategoryPriors(
        model.ClassifyCluster(ComputeClusterDescriptor(cloud, object, cp), params.cluster_k),
        params.part_graph_recognition.category_priors);
}

PartGraphVotes VotePartGraph(const PartGraphModel& model, const PointCloud& cloud,
                             const std::vector<PerceivedObject>& objects,
                             const Eigen::Vector4f& plane, const PerceiveParams& params) {
    std::vector<Indices> parts;
    std::vector<std::uint32_t> groups;
    std::vector<std::vector<std::size_t>> ids(objects.size());
    for (std::size_t k = 0; k < objects.size(); ++k) {
        for (const auto& part : objects[k].parts) {
            ids[k].push_back(parts.size());
            parts.push_back(part);
            groups.push_back(static_cast<std::uint32_t>(k));
        }
    }
    const PartGraphResult r =
        RecognizeParts(model, cloud, parts, params.part_graph_recognition, plane.head<3>(), groups);
    PartGraphVotes out;
    out.parts.resize(objects.size());
    out.objects.resize(objects.size());
    for (std::size_t k = 0; k < objects.size(); ++k) {
        for (std::size_t id : ids[k]) out.parts[k].push_back(r.part_probabilities[id]);
        out.objects[k] = MergePartProbabilities(r, parts, ids[k]);
    }
    return out;
}

static void CheckExpertWeights(const Eigen::Vector3f& w) {
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

// Part-graph hashing over the parts of every object (one graph for the scene, so groups may span
// touching objects, as in section 5.1.1); object distributions are the point-weighted mean of
// their parts'.
static void CategorizeByPartGraph(const PointCloud& cloud, std::vector<PerceivedObject>& objects,
                                  const Eigen::Vector4f& plane, const PerceiveParams& params) {
    std::shared_ptr<const PartGraphModel> model = params.part_graph;
    if (!model) {
        if (params.part_graph_model.empty()) {
            throw InvalidArgument("category.part_graph_model: no part-graph model given");
        }
        static std::mutex mutex;
        static std::map<std::string, std::shared_ptr<const PartGraphModel>> cache;
        const std::lock_guard lock(mutex);
        auto& cached = cache[params.part_graph_model];
        if (!cached) {
            cached = std::make_shared<const PartGraphModel>(
                PartGraphModel::Load(params.part_graph_model));
        }
        model = cached;
    }
    PartGraphVotes votes = VotePartGraph(*model, cloud, objects, plane, params);
    for (std::size_t k = 0; k < objects.size(); ++k) {
        objects[k].part_probabilities = std::move(votes.parts[k]);
        CategoryResult& c = objects[k].category;
        if (c.category == Category::kNone || objects[k].parts.empty()) continue;  // too few points
        auto p = votes.objects[k];
        if (params.categoriser == "part-graph+rules") {
            p = BlendCategoryProbabilities(c.probabilities, p, params.part_graph_weight);
        } else if (params.categoriser == "part-graph+rules+cluster") {
            p = BlendThreeExperts(c.probabilities, p,
                                  ClusterExpert(*model, cloud, objects[k].indices, params),
                                  params.expert_weights);
        } else if (params.categoriser == "stacked") {
            if (!model->stacker.trained()) {
                throw InvalidArgument(
                    "category.categoriser stacked needs a part-graph model with a stacker "
                    "(multicue train --stacker-scenes N)");
            }
            const auto cluster = ClusterExpert(*model, cloud, objects[k].indices, params);
            p = model->stacker.Predict(StackerInputs(c, p, cluster));
        }
        c.probabilities = p;
        c.category = ArgMaxCategory(p);
        c.confidence = p[static_cast<std::size_t>(c.category)];
    }
}

// After objects were merged or split: categories and models again for the `changed` ones, and
// ids renumbered in order.
// The categories a grouping model allows (two boxes explain a split: box or flat), all if empty.
using CategorySet = std::vector<Category>;

static void RestrictCategories(CategoryResult& c, const CategorySet& allowed) {
    if (allowed.empty() || c.category == Category::kNone) return;
    std::array<float, kNumCategories> p{};
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

static void Regroup(const PointCloud& cloud, std::vector<PerceivedObject>& objects,
                    const std::vector<std::size_t>& changed, const Eigen::Vector4f& plane,
                    const PerceiveParams& params, const CategorySet& allowed = {}) {
    std::vector<PerceivedObject> redo;
    for (std::size_t k : changed) {
        auto& o = objects[k];
        CategoryParams p = params.category;
        p.num_threads = 1;
        o.category = CategorizeObject(cloud, o.indices, o.parts, plane, p);
        RestrictCategories(o.category, allowed);
        o.centroid = Centroid(cloud, o.indices);
        if (params.categoriser != "rules") redo.push_back(o);
    }
    if (!redo.empty()) {
        CategorizeByPartGraph(cloud, redo, plane, params);
        for (std::size_t r = 0; r < changed.size(); ++r) {
            objects[changed[r]].category = redo[r].category;
            RestrictCategories(objects[changed[r]].category, allowed);
        }
    }
    ParallelFor(
        changed.size(), params.num_threads,
        [&](std::size_t r) {
            auto& o = objects[changed[r]];
            o.model = ModelObject(cloud, o, plane, params);
        },
        1);
    for (std::size_t k = 0; k < objects.size(); ++k) objects[k].id = static_cast<int>(k + 1);
}

// The objects after a regrouping step: kept ones as they were, new ones (Add) to be categorised
// and modelled again.
struct Regrouped {
    std::vector<PerceivedObject> objects;
    std::vector<std::size_t> changed;
    void Keep(PerceivedObject&& o) { objects.push_back(std::move(o)); }
    void Add(PerceivedObject&& o) {
        changed.push_back(objects.size());
        objects.push_back(std::move(o));
    }
};

static void FinishRegroup(const PointCloud& cloud, Regrouped& r,
                          std::vector<PerceivedObject>& objects, const Eigen::Vector4f& plane,
                          const PerceiveParams& params, const CategorySet& allowed,
                          std::string_view what) {
    if (!r.changed.empty()) {
        Regroup(cloud, r.objects, r.changed, plane, params, allowed);
        LogDebug("perceive: {} {} split", r.changed.size() / 2, what);
    }
    objects = std::move(r.objects);
}

// Two cylinders on one axis with about one radius (models.concentric): the inside and outside
// of one container, or two such containers stacked (their overlap along the axis tells).
static bool CoaxialSameRadius(const CylinderModel& a, const CylinderModel& b,
                              const PerceiveParams& params) {
    const Eigen::Vector3f axis = a.axis.normalized();
    const Eigen::Vector3f d = b.center - a.center;
    return std::abs(axis.dot(b.axis.normalized())) >=
               std::cos(params.concentric_angle_deg * 3.14159265f / 180.0f) &&
           (d - d.dot(axis) * axis).norm() <= params.concentric_distance &&
           std::abs(a.radius - b.radius) <=
               params.concentric_radius_ratio * std::max(a.radius, b.radius);
}

// Objects whose cylinder models share their axis and radius and overlap along it are one
// container seen as two surfaces (inside and outside); merged, categorised and modelled again.
static void MergeConcentric(const PointCloud& cloud, std::vector<PerceivedObject>& objects,
                            const Eigen::Vector4f& plane, const PerceiveParams& params) {
    if (!(params.concentric_angle_deg >= 0.0f) || !(params.concentric_distance >= 0.0f) ||
        !(params.concentric_radius_ratio >= 0.0f)) {
        throw InvalidArgument("models.concentric: angle, distance and radius ratio must be >= 0");
    }
    const std::size_t n = objects.size();
    auto cylinder = [&](std::size_t k) -> const CylinderModel* {
        const auto& m = objects[k].model;
        return m.cylinder && m.cylinder->found ? &*m.cylinder : nullptr;
    };
    std::vector<std::size_t> root(n);
    for (std::size_t k = 0; k < n; ++k) root[k] = k;
    auto find = [&](std::size_t k) {
        while (root[k] != k) k = root[k] = root[root[k]];
        return k;
    };
    bool any = false;
    for (std::size_t i = 0; i < n; ++i) {
        const CylinderModel* a = cylinder(i);
        if (a == nullptr) continue;
        for (std::size_t j = i + 1; j < n; ++j) {
            const CylinderModel* b = cylinder(j);
            if (b == nullptr) continue;
            if (!CoaxialSameRadius(*a, *b, params)) continue;
            const float along = (b->center - a->center).dot(a->axis.normalized());
            if (std::abs(along) > 0.5f * (a->height + b->height)) continue;  // stacked
            root[find(j)] = find(i);
            any = true;
        }
    }
    if (!any) return;
    std::vector<PerceivedObject> merged;
    std::vector<std::size_t> slot(n, n);
    std::vector<std::size_t> changed;
    for (std::size_t k = 0; k < n; ++k) {
        const std::size_t r = find(k);
        if (slot[r] == n) {
            slot[r] = merged.size();
            merged.push_back(std::move(objects[k]));
            continue;
        }
        auto& into = merged[slot[r]];
        Indices both;
        std::merge(into.indices.begin(), into.indices.end(), objects[k].indices.begin(),
                   objects[k].indices.end(), std::back_inserter(both));
        into.indices = std::move(both);
        for (auto& part : objects[k].parts) into.parts.push_back(std::move(part));
        if (changed.empty() || changed.back() != slot[r]) changed.push_back(slot[r]);
    }
    std::sort(changed.begin(), changed.end());
    changed.erase(std::unique(changed.begin(), changed.end()), changed.end());
    Regroup(cloud, merged, changed, plane, params);
    LogDebug("perceive: {} concentric objects merged", n - merged.size());
    objects = std::move(merged);
}

// Objects that lie inside a container's model or against its surface (the bottom inside a bowl,
// its outer wall below the rim, a mug's handle) are part of it: an object with most of its points
// inside the solid of another's cylinder or surface of revolution, enlarged by contained_margin,
// joins that object (grouping by models, section 5.4.1).
static void MergeContained(const PointCloud& cloud, std::vector<PerceivedObject>& objects,
                           const Eigen::Vector4f& plane, const PerceiveParams& params) {
    if (!(params.contained_margin >= 0.0f) ||
        !(params.contained_min_share > 0.0f && params.contained_min_share <= 1.0f)) {
        throw InvalidArgument("models.contained: margin must be >= 0 and min_share in (0, 1]");
    }
    const float margin = params.contained_margin;
    auto inside = [&](const ObjectModel& m, const Eigen::Vector3f& point) {
        if (m.rotational && m.rotational->found && !m.rotational->heights.empty()) {
            const RotationalModel& r = *m.rotational;
            const Eigen::Vector3f p = point - r.origin;
            const float h = p.dot(r.axis);
            const float h0 = r.heights.front(), h1 = r.heights.back();
            if (h < h0 - margin || h > h1 + margin) return false;
            return (p - h * r.axis).norm() <= r.RadiusAt(std::clamp(h, h0, h1)) + margin;
        }
        if (m.cylinder && m.cylinder->found) {
            const CylinderModel& c = *m.cylinder;
            const Eigen::Vector3f p = point - c.center;
            const Eigen::Vector3f axis = c.axis.normalized();
            const float h = p.dot(axis);
            return std::abs(h) <= 0.5f * c.height + margin &&
                   (p - h * axis).norm() <= c.radius + margin;
        }
        return false;
    };
    const std::size_t n = objects.size();
    std::vector<std::size_t> order(n);
    for (std::size_t k = 0; k < n; ++k) order[k] = k;
    std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
        return objects[a].indices.size() > objects[b].indices.size();
    });
    std::vector<std::size_t> into(n, n);
    for (std::size_t x = 0; x < n; ++x) {
        const std::size_t a = order[x];
        const ObjectModel& m = objects[a].model;
        if (into[a] != n || !m.accepted) continue;
        if (!(m.rotational && m.rotational->found) && !(m.cylinder && m.cylinder->found)) continue;
        for (std::size_t y = x + 1; y < n; ++y) {
            const std::size_t b = order[y];
            if (into[b] != n) continue;
            std::size_t in = 0;
            for (Index i : objects[b].indices) in += inside(m, cloud.points[i]);
            if (static_cast<float>(in) >=
                params.contained_min_share * static_cast<float>(objects[b].indices.size())) {
                into[b] = a;
            }
        }
    }
    std::vector<PerceivedObject> out;
    std::vector<std::size_t> slot(n, n), changed;
    for (std::size_t k = 0; k < n; ++k) {
        if (into[k] != n) continue;
        slot[k] = out.size();
        out.push_back(std::move(objects[k]));
    }
    for (std::size_t k = 0; k < n; ++k) {
        if (into[k] == n) continue;
        auto& target = out[slot[into[k]]];
        Indices both;
        std::merge(target.indices.begin(), target.indices.end(), objects[k].indices.begin(),
                   objects[k].indices.end(), std::back_inserter(both));
        target.indices = std::move(both);
        for (auto& part : objects[k].parts) target.parts.push_back(std::move(part));
        changed.push_back(slot[into[k]]);
    }
    if (changed.empty()) {
        objects = std::move(out);
        return;
    }
    std::sort(changed.begin(), changed.end());
    changed.erase(std::unique(changed.begin(), changed.end()), changed.end());
    LogDebug("perceive: {} objects joined the container they lie in", n - out.size());
    Regroup(cloud, out, changed, plane, params);
    objects = std::move(out);
}

// Stacked boxes that segmentation kept together: two horizontal faces at different heights
// above the table say "two boxes"; the split at the lower face's height is kept when two upright
// boxes explain the points clearly better than one (grouping by models, section 5.4.1).
static void SplitStacked(const PointCloud& cloud, std::vector<PerceivedObject>& objects,
                         const Eigen::Vector4f& plane, const PerceiveParams& params) {
    if (!(params.stack_min_step > 0.0f) || !(params.stack_min_gain >= 0.0f)) {
        throw InvalidArgument("models.stacked: min_step must be > 0 and min_gain >= 0");
    }
    const Eigen::Vector3f up = plane.head<3>();
    if (!(up.norm() > 0.5f)) return;
    const float scale = 1.0f / up.norm();
    auto height = [&](Index i) { return (up.dot(cloud.points[i]) + plane.w()) * scale; };
    const float cos_up = std::cos(10.0f * 3.14159265f / 180.0f);
    Regrouped out;
    for (auto& o : objects) {
        const Category c = o.category.category;
        if ((c != Category::kBox && c != Category::kFlat) || !cloud.HasNormals()) {
            out.Keep(std::move(o));
            continue;
        }
        // Heights of the horizontal faces.
        std::vector<float> faces;
        for (const auto& part : o.parts) {
            if (part.size() < params.stack_min_face_points) continue;
            Eigen::Vector3f n = Eigen::Vector3f::Zero();
            for (Index i : part) {
                if (cloud.normals[i].allFinite()) n += cloud.normals[i];
            }
            if (!(n.norm() > 0.0f) || std::abs(n.normalized().dot(up * scale)) < cos_up) continue;
            std::vector<float> h;
            h.reserve(part.size());
            for (Index i : part) h.push_back(height(i));
            std::nth_element(h.begin(), h.begin() + static_cast<std::ptrdiff_t>(h.size() / 2),
                             h.end());
            faces.push_back(h[h.size() / 2]);
        }
        std::sort(faces.begin(), faces.end());
        if (faces.size() < 2 || faces.front() < params.stack_min_step ||
            faces.back() - faces.front() < params.stack_min_step) {
            out.Keep(std::move(o));
            continue;
        }
        const float cut = faces.front() + 0.5f * params.stack_min_step;
        PerceivedObject lower, upper;
        for (Index i : o.indices) (height(i) <= cut ? lower : upper).indices.push_back(i);
        for (const auto& part : o.parts) {
            Indices a, b;
            for (Index i : part) (height(i) <= cut ? a : b).push_back(i);
            if (!a.empty()) lower.parts.push_back(std::move(a));
            if (!b.empty()) upper.parts.push_back(std::move(b));
        }
        if (lower.indices.size() < params.min_object_points ||
            upper.indices.size() < params.min_object_points) {
            out.Keep(std::move(o));
            continue;
        }
        const float one = FitUprightBox(cloud, o.indices, plane, params.box).inlier_ratio;
        const float n_low = static_cast<float>(lower.indices.size());
        const float n_up = static_cast<float>(upper.indices.size());
        const float two =
            (FitUprightBox(cloud, lower.indices, plane, params.box).inlier_ratio * n_low +
             FitUprightBox(cloud, upper.indices, plane, params.box).inlier_ratio * n_up) /
            (n_low + n_up);
        if (two < one + params.stack_min_gain) {
            out.Keep(std::move(o));
            continue;
        }
        out.Add(std::move(lower));
        out.Add(std::move(upper));
    }
    FinishRegroup(cloud, out, objects, plane, params, {Category::kBox, Category::kFlat},
                  "stacked objects");
}

// Share of the solid `a` inside the solid `b`, from a 6 x 6 x 6 grid of cell centres in `a`.
static float BoxOverlap(const BoxModel& a, const BoxModel& b) {
    constexpr int kSteps = 6;
    int inside = 0;
    const Eigen::Vector3f half_b = 0.5f * b.extents;
    for (int i = 0; i < kSteps; ++i) {
        for (int j = 0; j < kSteps; ++j) {
            for (int k = 0; k < kSteps; ++k) {
                const Eigen::Vector3f u((i + 0.5f) / kSteps - 0.5f, (j + 0.5f) / kSteps - 0.5f,
                                        (k + 0.5f) / kSteps - 0.5f);
                const Eigen::Vector3f p = a.center + a.axes * u.cwiseProduct(a.extents);
                const Eigen::Vector3f q = (b.axes.transpose() * (p - b.center)).cwiseAbs();
                if ((q.array() <= half_b.array()).all()) ++inside;
            }
        }
    }
    return static_cast<float>(inside) / (kSteps * kSteps * kSteps);
}

// Touching boxes that segmentation kept together (side by side, or under a third one): a box or
// flat object that one upright box explains poorly is tried as every split of its larger parts
// into two groups, each modelled by an upright box. The best split is kept when the two boxes
// together explain clearly more of the points, each explains its own group, and their solids
// hardly overlap (grouping by models, section 5.4.1).
static void SplitTouchingBoxes(const PointCloud& cloud, std::vector<PerceivedObject>& objects,
                               const Eigen::Vector4f& plane, const PerceiveParams& params) {
    if (!(params.several_min_ratio >= 0.0f)) {
        throw InvalidArgument("models.several_min_ratio must be >= 0");
    }
    if (!(params.touching_min_gain >= 0.0f) || !(params.touching_max_overlap >= 0.0f) ||
        params.touching_max_parts < 2 || params.touching_max_parts > 12) {
        throw InvalidArgument(
            "models.touching: min_gain and max_overlap must be >= 0, max_parts in [2, 12]");
    }
    if (!(plane.head<3>().norm() > 0.5f) || !cloud.HasNormals()) return;
    const float threshold = params.box.inlier_threshold;
    auto subsample = [](const Indices& in, std::size_t max) {
        if (in.size() <= max) return in;
        Indices out;
        out.reserve(max);
        for (std::size_t k = 0; k < max; ++k) out.push_back(in[k * in.size() / max]);
        return out;
    };
    auto explained = [&](const BoxModel& box, const Indices& points) {
        std::size_t n = 0;
        for (Index i : points) n += BoxSurfaceDistance(box, cloud.points[i]) <= threshold;
        return points.empty() ? 0.0f : static_cast<float>(n) / static_cast<float>(points.size());
    };
    Regrouped out;
    for (auto& o : objects) {
        const Category c = o.category.category;
        const bool boxy = c == Category::kBox || c == Category::kFlat;
        const Indices sample = subsample(o.indices, params.touching_max_points);
        BoxModel one;
        if (boxy) one = FitUprightBox(cloud, sample, plane, params.box);
        const float one_ratio = one.found ? explained(one, sample) : 0.0f;
        std::vector<std::size_t> big;
        for (std::size_t k = 0; k < o.parts.size(); ++k) {
            if (o.parts[k].size() >= params.touching_min_part_points) big.push_back(k);
        }
        const double several =
            TwoObjectsLikelihoodRatio(ObjectTypeOf(c), o.parts.size(), params.part_counts);
        if (!boxy || !one.found || one_ratio >= params.min_model_inlier_ratio || big.size() < 2 ||
            several < params.several_min_ratio) {
            out.Keep(std::move(o));
            continue;
        }
        std::sort(big.begin(), big.end(), [&](std::size_t a, std::size_t b) {
            return o.parts[a].size() > o.parts[b].size() ||
                   (o.parts[a].size() == o.parts[b].size() && a < b);
        });
        if (big.size() > static_cast<std::size_t>(params.touching_max_parts)) {
            big.resize(static_cast<std::size_t>(params.touching_max_parts));
        }
        const std::size_t m = big.size();
        float best = one_ratio + params.touching_min_gain;
        BoxModel best_a, best_b;
        bool found = false;
        // Part big[0] is always in group a; each mask picks group b among the others.
        for (std::uint32_t mask = 1; mask < (1u << (m - 1)); ++mask) {
            Indices ga, gb;
            for (std::size_t k = 0; k < m; ++k) {
                const bool in_b = k > 0 && (mask >> (k - 1)) & 1u;
                const Indices& part = o.parts[big[k]];
                (in_b ? gb : ga).insert((in_b ? gb : ga).end(), part.begin(), part.end());
            }
            std::sort(ga.begin(), ga.end());
            std::sort(gb.begin(), gb.end());
            ga = subsample(ga, params.touching_max_points / 2);
            gb = subsample(gb, params.touching_max_points / 2);
            const BoxModel a = FitUprightBox(cloud, ga, plane, params.box);
            const BoxModel b = FitUprightBox(cloud, gb, plane, params.box);
            if (!a.found || !b.found) continue;
            if (explained(a, ga) < params.min_model_inlier_ratio ||
                explained(b, gb) < params.min_model_inlier_ratio) {
                continue;
            }
            if (std::max(BoxOverlap(a, b), BoxOverlap(b, a)) > params.touching_max_overlap)
                continue;
            std::size_t n = 0;
            for (Index i : sample) {
                n += std::min(BoxSurfaceDistance(a, cloud.points[i]),
                              BoxSurfaceDistance(b, cloud.points[i])) <= threshold;
            }
            const float both = static_cast<float>(n) / static_cast<float>(sample.size());
            LogDebug("perceive: touching boxes {} | {}: {:.2f} (one box {:.2f})", ga.size(),
                     gb.size(), both, one_ratio);
            if (both > best) {
                best = both;
                best_a = a;
                best_b = b;
                found = true;
            }
        }
        if (!found) {
            out.Keep(std::move(o));
            continue;
        }
        // Whole parts go to the box nearer to most of their points; loose points to the nearer.
        auto nearer_a = [&](Index i) {
            return BoxSurfaceDistance(best_a, cloud.points[i]) <=
                   BoxSurfaceDistance(best_b, cloud.points[i]);
        };
        std::vector<bool> part_to_a(o.parts.size());
        std::vector<std::pair<Index, bool>> owner;  // part point -> goes to a
        for (std::size_t k = 0; k < o.parts.size(); ++k) {
            std::size_t to_a = 0;
            for (Index i : o.parts[k]) to_a += nearer_a(i);
            part_to_a[k] = 2 * to_a >= o.parts[k].size();
            for (Index i : o.parts[k]) owner.emplace_back(i, part_to_a[k]);
        }
        std::sort(owner.begin(), owner.end());
        PerceivedObject pa, pb;
        for (Index i : o.indices) {
            const auto it = std::lower_bound(owner.begin(), owner.end(), std::pair{i, false});
            const bool to_a = it != owner.end() && it->first == i ? it->second : nearer_a(i);
            (to_a ? pa : pb).indices.push_back(i);
        }
        if (pa.indices.size() < params.min_object_points ||
            pb.indices.size() < params.min_object_points) {
            out.Keep(std::move(o));
            continue;
        }
        for (std::size_t k = 0; k < o.parts.size(); ++k) {
            (part_to_a[k] ? pa : pb).parts.push_back(std::move(o.parts[k]));
        }
        out.Add(std::move(pa));
        out.Add(std::move(pb));
    }
    FinishRegroup(cloud, out, objects, plane, params, {Category::kBox, Category::kFlat},
                  "touching boxes");
}

// Touching round objects that segmentation kept together (a can standing in a bowl): the parts
// one cylinder explains become one object and the remaining parts another, when each has a
// cylinder explaining its points, together they explain clearly more than one cylinder, and they
// are not the inside and outside of one container (grouping by models, section 5.4.1).
static void SplitTouchingRound(const PointCloud& cloud, std::vector<PerceivedObject>& objects,
                               const Eigen::Vector4f& plane, const PerceiveParams& params) {
    if (!cloud.HasNormals()) return;
    const float threshold = params.cylinder.inlier_threshold;
    auto explained = [&](const CylinderModel& m, const Indices& points) {
        std::size_t n = 0;
        for (Index i : points) n += CylinderSurfaceDistance(m, cloud.points[i]) <= threshold;
        return points.empty() ? 0.0f : static_cast<float>(n) / static_cast<float>(points.size());
    };
    auto gather = [](const std::vector<Indices>& parts) {
        Indices all;
        for (const auto& p : parts) all.insert(all.end(), p.begin(), p.end());
        std::sort(all.begin(), all.end());
        return all;
    };
    Regrouped out;
    for (auto& o : objects) {
        const Category c = o.category.category;
        const bool round =
            c == Category::kSphere || c == Category::kCylinder || c == Category::kOther;
        const double several =
            TwoObjectsLikelihoodRatio(ObjectTypeOf(c), o.parts.size(), params.part_counts);
        if (!round || o.parts.size() < 2 || several < params.several_min_ratio) {
            out.Keep(std::move(o));
            continue;
        }
        const CylinderModel one = FitObjectCylinder(cloud, o.indices, plane, params.cylinder);
        const float one_ratio = one.found ? explained(one, o.indices) : 0.0f;
        if (!one.found || one_ratio >= params.min_model_inlier_ratio) {
            out.Keep(std::move(o));
            continue;
        }
        std::vector<Indices> pa, pb;
        for (auto& part : o.parts) {
            (2.0f * explained(one, part) >= 1.0f ? pa : pb).push_back(part);
        }
        const Indices ga = gather(pa), gb = gather(pb);
        if (ga.size() < params.min_object_points || gb.size() < params.min_object_points) {
            out.Keep(std::move(o));
            continue;
        }
        const CylinderModel a = FitObjectCylinder(cloud, ga, plane, params.cylinder);
        const CylinderModel b = FitObjectCylinder(cloud, gb, plane, params.cylinder);
        bool keep = !a.found || !b.found || explained(a, ga) < params.min_model_inlier_ratio ||
                    explained(b, gb) < params.min_model_inlier_ratio;
        if (!keep) {
            std::size_t n = 0;
            for (Index i : o.indices) {
                n += std::min(CylinderSurfaceDistance(a, cloud.points[i]),
                              CylinderSurfaceDistance(b, cloud.points[i])) <= threshold;
            }
            const float both = static_cast<float>(n) / static_cast<float>(o.indices.size());
            const bool concentric = CoaxialSameRadius(a, b, params);
            LogDebug("perceive: touching round {} | {}: {:.2f} (one cylinder {:.2f}){}", ga.size(),
                     gb.size(), both, one_ratio, concentric ? ", concentric" : "");
            keep = concentric || both < one_ratio + params.touching_min_gain;
        }
        if (keep) {
            out.Keep(std::move(o));
            continue;
        }
        // Points outside the parts go to the nearer cylinder.
        PerceivedObject oa, ob;
        oa.parts = std::move(pa);
        ob.parts = std::move(pb);
        for (Index i : o.indices) {
            const bool to_a = std::binary_search(ga.begin(), ga.end(), i) ||
                              (!std::binary_search(gb.begin(), gb.end(), i) &&
                               CylinderSurfaceDistance(a, cloud.points[i]) <=
                                   CylinderSurfaceDistance(b, cloud.points[i]));
            (to_a ? oa : ob).indices.push_back(i);
        }
        out.Add(std::move(oa));
        out.Add(std::move(ob));
    }
    FinishRegroup(cloud, out, objects, plane, params, {}, "touching round objects");
}

PerceiveResult Perceive(const PointCloud& input, const PerceiveParams& params) {
    input.Validate();
    if (input.CountFinite() == 0) {
        throw DataError(fmt::format("no valid points: all {} points are NaN or the cloud is empty",
                                    input.size()));
    }
    ResolveThreadCount(params.num_threads);  // validates
    if (!(params.part_graph_weight >= 0.0f && params.part_graph_weight <= 1.0f)) {
        throw InvalidArgument("category.part_graph_weight must be in [0, 1]");
    }
    CheckExpertWeights(params.expert_weights);
    PerceiveResult result;
    result.points = input.size();
    StageTimer timer(result.timings_ms);

    PointCloud cloud = input;
    SupportPlaneParams sp = params.support;
    sp.num_threads = params.num_threads;
    result.support = FindSupportPlane(cloud, sp);
    Indices roi;
    if (result.support.found && result.support.hull.size() >= 3) {
        roi = PolygonalPrism(cloud, result.support.plane, result.support.hull, params.prism);
    }
    if (roi.empty()) {
        // No table, or a plane that supports nothing (the top of a box in a cloud of objects):
        // every valid point may belong to an object.
        result.support = SupportPlane{};
        for (std::size_t i = 0; i < cloud.size(); ++i) {
            if (cloud.IsFinite(i)) roi.push_back(static_cast<Index>(i));
        }
    }
    timer.Done("support_plane");

    EnsurePerceiveNormals(cloud, roi, params);
    timer.Done("normals");

    ClusteringResult clusters = ClusterObjects(cloud, roi, params);
    timer.Done("clustering");

    // Parts: normal-angle region growing inside each hypothesis, on one tree over all of them;
    // then hypotheses are split where their parts meet in concave creases.
    Indices cluster_points;
    for (const auto& c : clusters.clusters) {
        cluster_points.insert(cluster_points.end(), c.begin(), c.end());
    }
    std::sort(cluster_points.begin(), cluster_points.end());
    const KdTree cluster_tree(cloud, cluster_points);
    std::vector<std::vector<PerceivedObject>> split(clusters.clusters.size());
    ParallelFor(
        clusters.clusters.size(), params.num_threads,
        [&](std::size_t k) {
            RegionGrowingParams p = params.parts;
            p.subset = clusters.clusters[k];
            std::vector<Indices> parts = RegionGrowing(cloud, cluster_tree, p).parts;
            std::vector<Indices> groups;
            if (params.split_concave) {
                ConvexitySplitParams cp = params.convexity;
                cp.min_object_points = params.min_object_points;
                groups = SplitByConvexity(
                             cloud, clusters.clusters[k], parts, cp,
                             result.support.found ? result.support.plane : Eigen::Vector4f::Zero())
                             .objects;
            } else {
                groups.push_back(clusters.clusters[k]);
            }
            for (auto& g : groups) {
                PerceivedObject o;
                o.indices = std::move(g);
                for (auto& part : parts) {
                    if (!part.empty() &&
                        std::binary_search(o.indices.begin(), o.indices.end(), part.front())) {
                        o.parts.push_back(part);
                    }
                }
                split[k].push_back(std::move(o));
            }
        },
        1);
    for (auto& list : split) {
        for (auto& o : list) {
            if (o.indices.size() < params.min_object_points) continue;
            o.id = static_cast<int>(result.objects.size() + 1);
            result.objects.push_back(std::move(o));
        }
    }
    timer.Done("parts");

    const Eigen::Vector4f plane =
        result.support.found ? result.support.plane : Eigen::Vector4f::Zero();
    if (params.merge_occluded && result.objects.size() >= 2) {
        result.objects = MergeOccluded(cloud, std::move(result.objects), plane, params);
    }
    timer.Done("occlusion");

    ParallelFor(
        result.objects.size(), params.num_threads,
        [&](std::size_t k) {
            auto& o = result.objects[k];
            CategoryParams p = params.category;
            p.num_threads = 1;
            o.category = CategorizeObject(cloud, o.indices, o.parts, plane, p);
            o.centroid = Centroid(cloud, o.indices);
        },
        1);
    if (params.categoriser == "part-graph" || params.categoriser == "part-graph+rules" ||
        params.categoriser == "part-graph+rules+cluster" || params.categoriser == "stacked") {
        if (params.cluster_k < 1) throw InvalidArgument("category.cluster_k must be >= 1");
        CategorizeByPartGraph(cloud, result.objects, plane, params);
    } else if (params.categoriser != "rules") {
        throw InvalidArgument(
            "category.categoriser must be rules, part-graph, part-graph+rules, "
            "part-graph+rules+cluster or stacked, got '" +
            params.categoriser + "'");
    }
    timer.Done("categories");

    ParallelFor(
        result.objects.size(), params.num_threads,
        [&](std::size_t k) {
            result.objects[k].model = ModelObject(cloud, result.objects[k], plane, params);
        },
        1);
    if (params.merge_concentric && result.objects.size() >= 2) {
        MergeConcentric(cloud, result.objects, plane, params);
    }
    if (params.merge_contained && result.objects.size() >= 2) {
        MergeContained(cloud, result.objects, plane, params);
    }
    if (params.split_stacked && !result.objects.empty()) {
        SplitStacked(cloud, result.objects, plane, params);
    }
    if (params.split_touching && !result.objects.empty()) {
        SplitTouchingBoxes(cloud, result.objects, plane, params);
    }
    if (params.split_touching_round && !result.objects.empty()) {
        SplitTouchingRound(cloud, result.objects, plane, params);
    }
    timer.Done("models");

    result.point_objects.assign(cloud.size(), 0);
    result.point_categories.assign(cloud.size(), 0);
    for (const auto& o : result.objects) {
        const auto cat = static_cast<std::uint8_t>(o.category.category);
        for (Index i : o.indices) {
            result.point_objects[i] = static_cast<std::uint32_t>(o.id);
            result.point_categories[i] = cat;
        }
    }
    LogInfo("perceive: support {}, {} objects", result.support.found ? "found" : "none",
            result.objects.size());
    return result;
}

}  // namespace multicue

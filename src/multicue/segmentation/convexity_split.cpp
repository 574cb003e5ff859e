#include "multicue/segmentation/convexity_split.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

#include <fmt/format.h>

#include "multicue/core/disjoint_sets.hpp"
#include "multicue/core/exceptions.hpp"
#include "multicue/segmentation/border_features.hpp"
#include "multicue/segmentation/part_borders.hpp"

namespace multicue {
namespace {

void CheckParams(const ConvexitySplitParams& p) {
    PartBorderParams{.patch_size = p.patch_size, .smooth_angle_deg = p.smooth_angle_deg}.Validate();
    ValidateNode("classifier", [&] { p.classifier.Validate(); });
    ValidateNode("fold", [&] { p.fold.Validate(); });
    if (!(p.min_convex_share >= 0.0f && p.min_convex_share <= 1.0f)) {
        throw InvalidArgument(
            fmt::format("min_convex_share must be in [0, 1], got {}", p.min_convex_share));
    }
    if (!(p.bend_angle_deg >= 0.0f && p.bend_angle_deg <= 180.0f)) {
        throw InvalidArgument(
            fmt::format("bend_angle_deg must be in [0, 180], got {}", p.bend_angle_deg));
    }
    if (!(p.max_top_difference >= 0.0f) || !std::isfinite(p.max_top_difference)) {
        throw InvalidArgument(
            fmt::format("max_top_difference must be >= 0, got {}", p.max_top_difference));
    }
}

/// Groups of parts (union-find over part numbers; a group is named by its smallest part).
class PartGroups {
  public:
    explicit PartGroups(std::size_t parts) : sets_(parts) {}
    std::size_t Find(std::size_t k) {
        return static_cast<std::size_t>(sets_.Find(static_cast<Index>(k)));
    }
    void Unite(std::size_t a, std::size_t b) {
        sets_.Unite(static_cast<Index>(a), static_cast<Index>(b));
    }

  private:
    detail::DisjointSets sets_;
};

/// Joins the parts across every mostly convex border (enough patch pairs to judge); returns the
/// concave borders that bend gently, candidates for the inside of a hollow object.
std::vector<std::pair<std::size_t, std::size_t>> JoinConvexBorders(
    const std::vector<PartBorder>& borders, const ConvexitySplitParams& params, PartGroups& groups,
    ConvexitySplitResult& result) {
    std::vector<std::pair<std::size_t, std::size_t>> bends;
    for (const PartBorder& border : borders) {
        if (border.pairs < params.min_border) continue;
        if (border.ConvexShare() >= params.min_convex_share) {
            groups.Unite(border.a, border.b);
            ++result.convex_borders;
        } else {
            ++result.concave_borders;
            if (border.median_angle_deg < params.bend_angle_deg) {
                bends.emplace_back(border.a, border.b);
            }
        }
    }
    return bends;
}

/// Hollow objects: a gentle concave bend between groups whose tops are level is the inside of one
/// object meeting its outer wall or another stretch of its inside. A crease between stacked objects
/// may look gentle too once normals are smoothed over it, but there the upper group rises above
/// the lower one by its own height.
void JoinLevelBends(const PointCloud& cloud, const std::vector<Indices>& parts,
                    const std::vector<std::pair<std::size_t, std::size_t>>& bends,
                    const Eigen::Vector4f& support_plane, float max_top_difference,
                    PartGroups& groups, ConvexitySplitResult& result) {
    const Eigen::Vector3f up = support_plane.head<3>();
    std::vector<float> top(parts.size(), -std::numeric_limits<float>::infinity());
    for (std::size_t k = 0; k < parts.size(); ++k) {
        for (Index i : parts[k]) {
            const Eigen::Vector3f& p = cloud.points[i];
            if (p.allFinite()) top[k] = std::max(top[k], up.dot(p) + support_plane.w());
        }
    }
    std::vector<float> group_top(parts.size(), -std::numeric_limits<float>::infinity());
    for (std::size_t k = 0; k < parts.size(); ++k) {
        group_top[groups.Find(k)] = std::max(group_top[groups.Find(k)], top[k]);
    }
    for (const auto& [a, b] : bends) {
        const std::size_t ga = groups.Find(a);
        const std::size_t gb = groups.Find(b);
        if (ga == gb || !(std::abs(group_top[ga] - group_top[gb]) < max_top_difference)) {
            continue;
        }
        const float joined_top = std::max(group_top[ga], group_top[gb]);
        groups.Unite(ga, gb);
        group_top[groups.Find(ga)] = joined_top;
        ++result.bend_joins;
    }
}

/// Folds groups too small to be objects into their best-connected neighbour (the most patch pairs
/// on their common borders), in up to 3 rounds; returns the point count of every group by root.
std::vector<std::size_t> FoldSmallGroups(const std::vector<Indices>& parts,
                                         const std::vector<PartBorder>& borders,
                                         std::size_t min_object_points, PartGroups& groups) {
    std::vector<std::size_t> group_size(parts.size(), 0);
    for (std::size_t k = 0; k < parts.size(); ++k) group_size[groups.Find(k)] += parts[k].size();
    for (int round = 0; round < 3; ++round) {
        bool changed = false;
        for (std::size_t k = 0; k < parts.size(); ++k) {
            const std::size_t g = groups.Find(k);
            if (g != k || group_size[g] >= min_object_points) continue;
            std::map<std::size_t, std::size_t> links;
            for (const PartBorder& border : borders) {
                const std::size_t ga = groups.Find(border.a);
                const std::size_t gb = groups.Find(border.b);
                if (ga == g && gb != g) links[gb] += border.pairs;
                if (gb == g && ga != g) links[ga] += border.pairs;
            }
            if (links.empty()) continue;
            const auto best =
                std::max_element(links.begin(), links.end(),
                                 [](const auto& x, const auto& y) { return x.second < y.second; });
            const std::size_t target = best->first;
            const std::size_t total = group_size[g] + group_size[target];
            groups.Unite(g, target);
            group_size[groups.Find(g)] = total;
            changed = true;
        }
        if (!changed) break;
    }
    return group_size;
}

/// The object's points by group, largest first: by their part, else by their patch's part, else
/// the largest group.
std::vector<Indices> GroupPoints(const Indices& object, std::size_t part_count,
                                 const PartBorders& borders,
                                 const std::vector<std::size_t>& group_size, PartGroups& groups) {
    std::map<std::size_t, Indices> by_root;
    std::size_t largest_root = groups.Find(0);
    for (std::size_t k = 0; k < part_count; ++k) {
        const std::size_t r = groups.Find(k);
        if (group_size[r] > group_size[largest_root]) largest_root = r;
    }
    for (std::size_t n = 0; n < object.size(); ++n) {
        int part = borders.point_part[n];
        if (part < 0 && borders.point_patch[n] != SIZE_MAX) {
            part = borders.patches[borders.point_patch[n]].part;
        }
        const std::size_t root =
            part >= 0 ? groups.Find(static_cast<std::size_t>(part)) : largest_root;
        by_root[root].push_back(object[n]);
    }
    std::vector<Indices> objects;
    for (auto& [root, indices] : by_root) {
        std::sort(indices.begin(), indices.end());
        objects.push_back(std::move(indices));
    }
    std::stable_sort(objects.begin(), objects.end(),
                     [](const Indices& a, const Indices& b) { return a.size() > b.size(); });
    return objects;
}

/// The learned decision: large parts join across borders the classifier finds likely enough
/// to be inside one object; then every small part joins the neighbour whose border scores best
/// (a large one before a small one), so that a small part never bridges two objects.
void JoinByClassifier(const std::vector<Indices>& parts, const PartBorders& borders,
                      const Eigen::Vector4f& plane, const ConvexitySplitParams& params,
                      PartGroups& groups, ConvexitySplitResult& result) {
    const auto& cp = params.classifier;
    const std::vector<PartSummary> summaries = SummarizeParts(parts, borders, plane);
    std::vector<float> p(borders.borders.size());
    for (std::size_t e = 0; e < p.size(); ++e) {
        p[e] = JoinProbability(
            ComputeBorderFeatures(borders.borders[e], borders, summaries, plane.head<3>()), cp);
    }
    const auto large = [&](std::size_t k) { return parts[k].size() >= cp.large_part_points; };
    for (std::size_t e = 0; e < p.size(); ++e) {
        const PartBorder& b = borders.borders[e];
        if (!large(b.a) || !large(b.b) || b.pairs < params.min_border) continue;
        if (p[e] >= cp.threshold) {
            groups.Unite(b.a, b.b);
            ++result.convex_borders;
        } else {
            ++result.concave_borders;
        }
    }
    std::vector<std::size_t> small;
    for (std::size_t k = 0; k < parts.size(); ++k) {
        if (!large(k)) small.push_back(k);
    }
    std::stable_sort(small.begin(), small.end(), [&](std::size_t x, std::size_t y) {
        return parts[x].size() > parts[y].size();
    });
    for (std::size_t k : small) {
        float best_score = -1.0f;
        std::size_t best = k;
        for (std::size_t e = 0; e < p.size(); ++e) {
            const PartBorder& b = borders.borders[e];
            if (b.a != k && b.b != k) continue;
            const std::size_t other = b.a == k ? b.b : b.a;
            const float score = p[e] * (large(other) ? 1.0f : 0.5f);
            if (score > best_score) {
                best_score = score;
                best = other;
            }
        }
        if (best != k) groups.Unite(k, best);
    }
}

// The parts (of `parts`) of each object: a part lies wholly in one group.
std::vector<std::vector<Indices>> PartsByObject(const std::vector<Indices>& objects,
                                                const std::vector<Indices>& parts) {
    std::vector<std::vector<Indices>> out(objects.size());
    for (const auto& part : parts) {
        if (part.empty()) continue;
        for (std::size_t o = 0; o < objects.size(); ++o) {
            if (std::binary_search(objects[o].begin(), objects[o].end(), part.front())) {
                out[o].push_back(part);
                break;
            }
        }
    }
    return out;
}

}  // namespace

void ConvexitySplitParams::Validate() const { CheckParams(*this); }

ConvexitySplitResult SplitByConvexity(const PointCloud& cloud, const Indices& object,
                                      const std::vector<Indices>& parts,
                                      const ConvexitySplitParams& params,
                                      const Eigen::Vector4f& support_plane) {
    params.Validate();
    if (!cloud.HasNormals()) throw DataError("convexity split needs normals");
    ConvexitySplitResult result;
    if (object.empty()) return result;
    if (parts.size() < 2) {
        result.objects.push_back(object);
        result.parts.push_back(parts);
        return result;
    }
    const PartBorderParams border_params{.patch_size = params.patch_size,
                                         .smooth_angle_deg = params.smooth_angle_deg};
    const bool learned = params.learned && support_plane.head<3>().norm() > 0.5f;
    PartBorders borders = ComputePartBorders(cloud, object, parts, border_params, support_plane);
    std::vector<Indices> refined;
    if (learned && params.fold.enabled) {
        refined = SplitFoldedParts(cloud, object, parts, borders, params.fold);
        if (refined.size() != parts.size()) {
            result.folded_parts = refined.size() - parts.size();
            borders = ComputePartBorders(cloud, object, refined, border_params, support_plane);
        }
    }
    const std::vector<Indices>& used = refined.empty() ? parts : refined;
    PartGroups groups(used.size());
    if (learned) {
        JoinByClassifier(used, borders, support_plane, params, groups, result);
    } else {
        const auto bends = JoinConvexBorders(borders.borders, params, groups, result);
        if (!bends.empty() && support_plane.head<3>().norm() > 0.5f) {
            JoinLevelBends(cloud, used, bends, support_plane, params.max_top_difference, groups,
                           result);
        }
    }
    const std::vector<std::size_t> group_size =
        FoldSmallGroups(used, borders.borders, params.min_object_points, groups);
    result.objects = GroupPoints(object, used.size(), borders, group_size, groups);
    result.parts = PartsByObject(result.objects, used);
    return result;
}

}  // namespace multicue

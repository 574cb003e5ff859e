#include "multicue/segmentation/convexity_split.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <unordered_map>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/segmentation/disjoint_sets.hpp"

namespace multicue {
namespace {

struct Patch {
    Eigen::Vector3f centroid = Eigen::Vector3f::Zero();
    Eigen::Vector3f normal = Eigen::Vector3f::Zero();
    int part = -1;  // majority part of its points, -1 if none
    std::size_t count = 0;
};

std::uint64_t PackKey(const Eigen::Vector3i& c) {
    constexpr std::int64_t kBias = 1 << 20;
    return (static_cast<std::uint64_t>(c.x() + kBias) << 42) |
           (static_cast<std::uint64_t>(c.y() + kBias) << 21) |
           static_cast<std::uint64_t>(c.z() + kBias);
}

void CheckParams(const ConvexitySplitParams& p) {
    if (!(p.patch_size > 0.0f) || !std::isfinite(p.patch_size)) {
        throw InvalidArgument(fmt::format("patch_size must be > 0, got {}", p.patch_size));
    }
    if (!(p.smooth_angle_deg >= 0.0f && p.smooth_angle_deg <= 90.0f)) {
        throw InvalidArgument(
            fmt::format("smooth_angle_deg must be in [0, 90], got {}", p.smooth_angle_deg));
    }
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

struct Border {
    std::size_t convex = 0;
    std::vector<float> angles;  // between the normals of each patch pair [deg]
};

using Borders = std::map<std::pair<int, int>, Border>;

float Median(std::vector<float> values) {
    const auto mid = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
    std::nth_element(values.begin(), mid, values.end());
    return *mid;
}

/// The part of each point of a part (the last part listed wins for a point in several).
std::unordered_map<Index, int> PartOfPoints(const Indices& object,
                                            const std::vector<Indices>& parts) {
    std::unordered_map<Index, int> part_of;
    part_of.reserve(object.size());
    for (std::size_t k = 0; k < parts.size(); ++k) {
        for (Index i : parts[k]) part_of[i] = static_cast<int>(k);
    }
    return part_of;
}

/// Voxel patches over the object's points with a finite normal: mean position, mean normal and
/// majority part, so that borders are judged on smoothed surface pieces rather than noisy points.
struct PatchGrid {
    std::unordered_map<std::uint64_t, std::size_t> patch_of_key;
    std::vector<Patch> patches;
    std::vector<Eigen::Vector3i> coords;
    std::vector<std::size_t> point_patch;  // per object point, SIZE_MAX without a finite normal
};

PatchGrid BuildPatches(const PointCloud& cloud, const Indices& object,
                       const std::unordered_map<Index, int>& part_of, float patch_size) {
    const float inv = 1.0f / patch_size;
    PatchGrid grid;
    auto& patches = grid.patches;
    std::vector<std::map<int, std::size_t>> votes;
    grid.point_patch.assign(object.size(), SIZE_MAX);
    for (std::size_t n = 0; n < object.size(); ++n) {
        const Index i = object[n];
        const Eigen::Vector3f& p = cloud.points[i];
        const Eigen::Vector3f& nv = cloud.normals[i];
        if (!p.allFinite() || !nv.allFinite()) continue;
        const Eigen::Vector3i c = (p * inv).array().floor().cast<int>();
        auto [it, inserted] = grid.patch_of_key.try_emplace(PackKey(c), patches.size());
        if (inserted) {
            patches.emplace_back();
            grid.coords.push_back(c);
            votes.emplace_back();
        }
        Patch& patch = patches[it->second];
        patch.centroid += p;
        patch.normal += nv;
        ++patch.count;
        const auto pit = part_of.find(i);
        if (pit != part_of.end()) ++votes[it->second][pit->second];
        grid.point_patch[n] = it->second;
    }
    for (std::size_t v = 0; v < patches.size(); ++v) {
        Patch& patch = patches[v];
        patch.centroid /= static_cast<float>(patch.count);
        if (patch.normal.norm() > 0.0f) patch.normal.normalize();
        std::size_t best = 0;
        for (const auto& [part, count] : votes[v]) {
            if (count > best) {
                best = count;
                patch.part = part;
            }
        }
    }
    return grid;
}

/// Border votes between parts, from every pair of neighbouring patches of different parts:
/// convex when n1.d > n2.d for d = c1 - c2 (the patches bend away from each other, seen from the
/// sensor), or when the normals hardly differ.
Borders VoteBorders(const PatchGrid& grid, float smooth_angle_deg) {
    const auto& patches = grid.patches;
    const float smooth_cos = std::cos(smooth_angle_deg * static_cast<float>(M_PI) / 180.0f);
    const float rad_to_deg = 180.0f / static_cast<float>(M_PI);
    Borders borders;
    for (std::size_t v = 0; v < patches.size(); ++v) {
        const Patch& a = patches[v];
        if (a.part < 0) continue;
        for (int dx = -1; dx <= 1; ++dx) {
            for (int dy = -1; dy <= 1; ++dy) {
                for (int dz = -1; dz <= 1; ++dz) {
                    const auto it = grid.patch_of_key.find(
                        PackKey(grid.coords[v] + Eigen::Vector3i(dx, dy, dz)));
                    if (it == grid.patch_of_key.end() || it->second <= v) continue;
                    const Patch& b = patches[it->second];
                    if (b.part < 0 || b.part == a.part) continue;
                    const Eigen::Vector3f d = a.centroid - b.centroid;
                    const bool convex =
                        a.normal.dot(b.normal) >= smooth_cos || a.normal.dot(d) > b.normal.dot(d);
                    auto& border = borders[{std::min(a.part, b.part), std::max(a.part, b.part)}];
                    border.convex += convex ? 1 : 0;
                    border.angles.push_back(
                        std::acos(std::clamp(a.normal.dot(b.normal), -1.0f, 1.0f)) * rad_to_deg);
                }
            }
        }
    }
    return borders;
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
    const Borders& borders, const ConvexitySplitParams& params, PartGroups& groups,
    ConvexitySplitResult& result) {
    std::vector<std::pair<std::size_t, std::size_t>> bends;
    for (const auto& [pair, border] : borders) {
        if (border.angles.size() < params.min_border) continue;
        const auto a = static_cast<std::size_t>(pair.first);
        const auto b = static_cast<std::size_t>(pair.second);
        const float share =
            static_cast<float>(border.convex) / static_cast<float>(border.angles.size());
        if (share >= params.min_convex_share) {
            groups.Unite(a, b);
            ++result.convex_borders;
        } else {
            ++result.concave_borders;
            if (Median(border.angles) < params.bend_angle_deg) bends.emplace_back(a, b);
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
std::vector<std::size_t> FoldSmallGroups(const std::vector<Indices>& parts, const Borders& borders,
                                         std::size_t min_object_points, PartGroups& groups) {
    std::vector<std::size_t> group_size(parts.size(), 0);
    for (std::size_t k = 0; k < parts.size(); ++k) group_size[groups.Find(k)] += parts[k].size();
    for (int round = 0; round < 3; ++round) {
        bool changed = false;
        for (std::size_t k = 0; k < parts.size(); ++k) {
            const std::size_t g = groups.Find(k);
            if (g != k || group_size[g] >= min_object_points) continue;
            std::map<std::size_t, std::size_t> links;
            for (const auto& [pair, border] : borders) {
                const std::size_t ga = groups.Find(static_cast<std::size_t>(pair.first));
                const std::size_t gb = groups.Find(static_cast<std::size_t>(pair.second));
                if (ga == g && gb != g) links[gb] += border.angles.size();
                if (gb == g && ga != g) links[ga] += border.angles.size();
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
                                 const std::unordered_map<Index, int>& part_of,
                                 const PatchGrid& grid, const std::vector<std::size_t>& group_size,
                                 PartGroups& groups) {
    std::map<std::size_t, Indices> by_root;
    std::size_t largest_root = groups.Find(0);
    for (std::size_t k = 0; k < part_count; ++k) {
        const std::size_t r = groups.Find(k);
        if (group_size[r] > group_size[largest_root]) largest_root = r;
    }
    for (std::size_t n = 0; n < object.size(); ++n) {
        const Index i = object[n];
        const auto pit = part_of.find(i);
        int part = pit != part_of.end() ? pit->second : -1;
        if (part < 0 && grid.point_patch[n] != SIZE_MAX) {
            part = grid.patches[grid.point_patch[n]].part;
        }
        const std::size_t root =
            part >= 0 ? groups.Find(static_cast<std::size_t>(part)) : largest_root;
        by_root[root].push_back(i);
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
        return result;
    }
    const std::unordered_map<Index, int> part_of = PartOfPoints(object, parts);
    const PatchGrid grid = BuildPatches(cloud, object, part_of, params.patch_size);
    const Borders borders = VoteBorders(grid, params.smooth_angle_deg);
    PartGroups groups(parts.size());
    const auto bends = JoinConvexBorders(borders, params, groups, result);
    if (!bends.empty() && support_plane.head<3>().norm() > 0.5f) {
        JoinLevelBends(cloud, parts, bends, support_plane, params.max_top_difference, groups,
                       result);
    }
    const std::vector<std::size_t> group_size =
        FoldSmallGroups(parts, borders, params.min_object_points, groups);
    result.objects = GroupPoints(object, parts.size(), part_of, grid, group_size, groups);
    return result;
}

}  // namespace multicue

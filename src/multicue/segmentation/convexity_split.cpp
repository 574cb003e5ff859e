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

float Median(std::vector<float> values) {
    const auto mid = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
    std::nth_element(values.begin(), mid, values.end());
    return *mid;
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
    std::unordered_map<Index, int> part_of;
    part_of.reserve(object.size());
    for (std::size_t k = 0; k < parts.size(); ++k) {
        for (Index i : parts[k]) part_of[i] = static_cast<int>(k);
    }

    // Voxel patches over the object's points with a finite normal.
    const float inv = 1.0f / params.patch_size;
    std::unordered_map<std::uint64_t, std::size_t> patch_of_key;
    std::vector<Patch> patches;
    std::vector<Eigen::Vector3i> coords;
    std::vector<std::map<int, std::size_t>> votes;
    std::vector<std::size_t> point_patch(object.size(), SIZE_MAX);
    for (std::size_t n = 0; n < object.size(); ++n) {
        const Index i = object[n];
        const Eigen::Vector3f& p = cloud.points[i];
        const Eigen::Vector3f& nv = cloud.normals[i];
        if (!p.allFinite() || !nv.allFinite()) continue;
        const Eigen::Vector3i c = (p * inv).array().floor().cast<int>();
        auto [it, inserted] = patch_of_key.try_emplace(PackKey(c), patches.size());
        if (inserted) {
            patches.emplace_back();
            coords.push_back(c);
            votes.emplace_back();
        }
        Patch& patch = patches[it->second];
        patch.centroid += p;
        patch.normal += nv;
        ++patch.count;
        const auto pit = part_of.find(i);
        if (pit != part_of.end()) ++votes[it->second][pit->second];
        point_patch[n] = it->second;
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

    // Border votes between parts: convex when n1.d > n2.d for d = c1 - c2 (the patches bend away
    // from each other, seen from the sensor), or when the normals hardly differ.
    const float smooth_cos = std::cos(params.smooth_angle_deg * static_cast<float>(M_PI) / 180.0f);
    const float rad_to_deg = 180.0f / static_cast<float>(M_PI);
    std::map<std::pair<int, int>, Border> borders;
    for (std::size_t v = 0; v < patches.size(); ++v) {
        const Patch& a = patches[v];
        if (a.part < 0) continue;
        for (int dx = -1; dx <= 1; ++dx) {
            for (int dy = -1; dy <= 1; ++dy) {
                for (int dz = -1; dz <= 1; ++dz) {
                    const auto it =
                        patch_of_key.find(PackKey(coords[v] + Eigen::Vector3i(dx, dy, dz)));
                    if (it == patch_of_key.end() || it->second <= v) continue;
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
    detail::DisjointSets sets(parts.size());
    auto find = [&sets](std::size_t k) {
        return static_cast<std::size_t>(sets.Find(static_cast<Index>(k)));
    };
    auto unite = [&sets](std::size_t a, std::size_t b) {
        sets.Unite(static_cast<Index>(a), static_cast<Index>(b));
    };
    std::vector<std::pair<std::size_t, std::size_t>> bends;  // concave borders that bend gently
    for (const auto& [pair, border] : borders) {
        if (border.angles.size() < params.min_border) continue;
        const auto a = static_cast<std::size_t>(pair.first);
        const auto b = static_cast<std::size_t>(pair.second);
        const float share =
            static_cast<float>(border.convex) / static_cast<float>(border.angles.size());
        if (share >= params.min_convex_share) {
            unite(a, b);
            ++result.convex_borders;
        } else {
            ++result.concave_borders;
            if (Median(border.angles) < params.bend_angle_deg) bends.emplace_back(a, b);
        }
    }

    // Hollow objects: a gentle concave bend between groups whose tops are level is the inside of
    // one object meeting its outer wall or another stretch of its inside. A crease between stacked
    // objects may look gentle too once normals are smoothed over it, but there the upper group
    // rises above the lower one by its own height.
    if (!bends.empty() && support_plane.head<3>().norm() > 0.5f) {
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
            group_top[find(k)] = std::max(group_top[find(k)], top[k]);
        }
        for (const auto& [a, b] : bends) {
            const std::size_t ga = find(a);
            const std::size_t gb = find(b);
            if (ga == gb ||
                !(std::abs(group_top[ga] - group_top[gb]) < params.max_top_difference)) {
                continue;
            }
            const float joined_top = std::max(group_top[ga], group_top[gb]);
            unite(ga, gb);
            group_top[find(ga)] = joined_top;
            ++result.bend_joins;
        }
    }

    // Group sizes, then fold groups too small to be objects into their best-connected neighbour.
    std::vector<std::size_t> group_size(parts.size(), 0);
    for (std::size_t k = 0; k < parts.size(); ++k) group_size[find(k)] += parts[k].size();
    for (int round = 0; round < 3; ++round) {
        bool changed = false;
        for (std::size_t k = 0; k < parts.size(); ++k) {
            const std::size_t g = find(k);
            if (g != k || group_size[g] >= params.min_object_points) continue;
            std::map<std::size_t, std::size_t> links;
            for (const auto& [pair, border] : borders) {
                const std::size_t ga = find(static_cast<std::size_t>(pair.first));
                const std::size_t gb = find(static_cast<std::size_t>(pair.second));
                if (ga == g && gb != g) links[gb] += border.angles.size();
                if (gb == g && ga != g) links[ga] += border.angles.size();
            }
            if (links.empty()) continue;
            const auto best =
                std::max_element(links.begin(), links.end(),
                                 [](const auto& x, const auto& y) { return x.second < y.second; });
            const std::size_t target = best->first;
            const std::size_t total = group_size[g] + group_size[target];
            unite(g, target);
            group_size[find(g)] = total;
            changed = true;
        }
        if (!changed) break;
    }

    // Points to groups: by their part, else by their patch's part, else the largest group.
    std::map<std::size_t, Indices> groups;
    std::size_t largest_root = find(0);
    for (std::size_t k = 0; k < parts.size(); ++k) {
        const std::size_t r = find(k);
        if (group_size[r] > group_size[largest_root]) largest_root = r;
    }
    for (std::size_t n = 0; n < object.size(); ++n) {
        const Index i = object[n];
        const auto pit = part_of.find(i);
        int part = pit != part_of.end() ? pit->second : -1;
        if (part < 0 && point_patch[n] != SIZE_MAX) part = patches[point_patch[n]].part;
        const std::size_t root = part >= 0 ? find(static_cast<std::size_t>(part)) : largest_root;
        groups[root].push_back(i);
    }
    for (auto& [root, indices] : groups) {
        std::sort(indices.begin(), indices.end());
        result.objects.push_back(std::move(indices));
    }
    std::stable_sort(result.objects.begin(), result.objects.end(),
                     [](const Indices& a, const Indices& b) { return a.size() > b.size(); });
    return result;
}

}  // namespace multicue

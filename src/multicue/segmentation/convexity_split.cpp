#include "multicue/segmentation/convexity_split.hpp"

#include <algorithm>
#include <cmath>
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

void Validate(const PointCloud& cloud, const ConvexitySplitParams& p) {
    if (!cloud.HasNormals()) throw DataError("convexity split needs normals");
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
}

}  // namespace

ConvexitySplitResult SplitByConvexity(const PointCloud& cloud, const Indices& object,
                                      const std::vector<Indices>& parts,
                                      const ConvexitySplitParams& params) {
    Validate(cloud, params);
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
    std::map<std::pair<int, int>, std::pair<std::size_t, std::size_t>> borders;  // convex, total
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
                    border.first += convex ? 1 : 0;
                    border.second += 1;
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
    for (const auto& [pair, votes_ab] : borders) {
        if (votes_ab.second < params.min_border) continue;
        const float share =
            static_cast<float>(votes_ab.first) / static_cast<float>(votes_ab.second);
        if (share >= params.min_convex_share) {
            unite(static_cast<std::size_t>(pair.first), static_cast<std::size_t>(pair.second));
            ++result.convex_borders;
        } else {
            ++result.concave_borders;
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
            for (const auto& [pair, votes_ab] : borders) {
                const std::size_t ga = find(static_cast<std::size_t>(pair.first));
                const std::size_t gb = find(static_cast<std::size_t>(pair.second));
                if (ga == g && gb != g) links[gb] += votes_ab.second;
                if (gb == g && ga != g) links[ga] += votes_ab.second;
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

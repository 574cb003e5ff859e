#include "multicue/segmentation/folded_parts.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <unordered_map>

#include <fmt/format.h>

#include "multicue/core/cell_key.hpp"
#include "multicue/core/disjoint_sets.hpp"
#include "multicue/core/exceptions.hpp"

namespace multicue {
namespace {

constexpr float kRadToDeg = 180.0f / static_cast<float>(M_PI);
constexpr std::size_t kMaxSample = 1500;  // normals per part for the mode test

float AngleDeg(const Eigen::Vector3f& a, const Eigen::Vector3f& b) {
    return std::acos(std::clamp(a.dot(b), -1.0f, 1.0f)) * kRadToDeg;
}

// Two modes of a set of unit normals (spherical 2-means from the two most distant directions).
std::array<Eigen::Vector3f, 2> TwoModes(const std::vector<Eigen::Vector3f>& normals) {
    Eigen::Vector3f all = Eigen::Vector3f::Zero();
    for (const auto& n : normals) all += n;
    all = all.norm() > 0.0f ? all.normalized() : Eigen::Vector3f::UnitZ();
    const auto farthest = [&](const Eigen::Vector3f& from) {
        std::size_t best = 0;
        float lowest = 2.0f;
        for (std::size_t i = 0; i < normals.size(); ++i) {
            const float d = normals[i].dot(from);
            if (d < lowest) {
                lowest = d;
                best = i;
            }
        }
        return normals[best];
    };
    std::array<Eigen::Vector3f, 2> mean = {farthest(all), Eigen::Vector3f::Zero()};
    mean[1] = farthest(mean[0]);
    for (int round = 0; round < 8; ++round) {
        std::array<Eigen::Vector3f, 2> sum = {Eigen::Vector3f::Zero(), Eigen::Vector3f::Zero()};
        for (const auto& n : normals) sum[n.dot(mean[1]) > n.dot(mean[0]) ? 1 : 0] += n;
        for (int k = 0; k < 2; ++k) {
            if (sum[k].norm() > 0.0f) mean[k] = sum[k].normalized();
        }
    }
    return mean;
}

// Whether the normals gather around the two modes (far enough apart, both well filled) with
// little in the middle third between them.
bool IsFold(const std::vector<Eigen::Vector3f>& normals, const std::array<Eigen::Vector3f, 2>& m,
            const FoldSplitParams& params) {
    const float fold = AngleDeg(m[0], m[1]);
    if (!(fold >= params.min_fold_deg)) return false;
    std::size_t side[2] = {0, 0};
    std::size_t middle = 0;
    for (const auto& n : normals) {
        ++side[n.dot(m[1]) > n.dot(m[0]) ? 1 : 0];
        const float t = AngleDeg(n, m[0]) / fold;
        if (t > 1.0f / 3.0f && t < 2.0f / 3.0f) ++middle;
    }
    const auto total = static_cast<float>(normals.size());
    return static_cast<float>(std::min(side[0], side[1])) >= params.min_side_share * total &&
           static_cast<float>(middle) <= params.max_middle_share * total;
}

// The pieces of one folded part: its points by mode, connected through neighbouring patches;
// pieces under min_piece_points join the neighbouring piece they touch most, or the largest.
std::vector<Indices> FoldPieces(const PointCloud& cloud, const Indices& object,
                                const PartBorders& borders, int part,
                                const std::array<Eigen::Vector3f, 2>& m, std::size_t min_points) {
    // Node = (patch, mode); its points.
    std::map<std::pair<std::size_t, int>, Indices> nodes;
    Indices unplaced;
    for (std::size_t n = 0; n < object.size(); ++n) {
        if (borders.point_part[n] != part) continue;
        const Eigen::Vector3f& nv = cloud.normals[object[n]];
        const std::size_t v = borders.point_patch[n];
        if (v == SIZE_MAX || !nv.allFinite()) {
            unplaced.push_back(object[n]);
            continue;
        }
        nodes[{v, nv.dot(m[1]) > nv.dot(m[0]) ? 1 : 0}].push_back(object[n]);
    }
    std::vector<std::pair<std::size_t, int>> keys;
    std::unordered_map<std::uint64_t, std::array<int, 2>> node_at;  // cell -> node per mode
    for (const auto& [key, pts] : nodes) {
        auto [it, inserted] = node_at.try_emplace(
            detail::PackCellKey(borders.patch_cells[key.first]), std::array<int, 2>{-1, -1});
        it->second[key.second] = static_cast<int>(keys.size());
        keys.push_back(key);
    }
    detail::DisjointSets sets(keys.size());
    // Touching counts between nodes of different modes, for folding small pieces.
    std::map<std::pair<Index, Index>, std::size_t> touching;
    for (std::size_t i = 0; i < keys.size(); ++i) {
        const Eigen::Vector3i& c = borders.patch_cells[keys[i].first];
        for (int dx = -1; dx <= 1; ++dx) {
            for (int dy = -1; dy <= 1; ++dy) {
                for (int dz = -1; dz <= 1; ++dz) {
                    const auto it =
                        node_at.find(detail::PackCellKey(c + Eigen::Vector3i(dx, dy, dz)));
                    if (it == node_at.end()) continue;
                    for (int mode = 0; mode < 2; ++mode) {
                        const int j = it->second[mode];
                        if (j < 0 || static_cast<std::size_t>(j) == i) continue;
                        if (mode == keys[i].second) {
                            sets.Unite(static_cast<Index>(i), static_cast<Index>(j));
                        } else {
                            ++touching[{static_cast<Index>(i), static_cast<Index>(j)}];
                        }
                    }
                }
            }
        }
    }
    std::map<Index, std::size_t> size;
    for (std::size_t i = 0; i < keys.size(); ++i) {
        size[sets.Find(static_cast<Index>(i))] += nodes[keys[i]].size();
    }
    // Small pieces join the piece they touch most (in order of their root).
    for (auto& [root, count] : size) {
        if (count >= min_points || sets.Find(root) != root) continue;
        std::map<Index, std::size_t> links;
        for (const auto& [pair, n] : touching) {
            const Index a = sets.Find(pair.first), b = sets.Find(pair.second);
            if (a == root && b != root) links[b] += n;
        }
        if (links.empty()) continue;
        const Index target = std::max_element(links.begin(), links.end(), [](auto& x, auto& y) {
                                 return x.second < y.second;
                             })->first;
        const std::size_t total = count + size[sets.Find(target)];
        sets.Unite(root, target);
        size[sets.Find(root)] = total;
    }
    std::map<Index, Indices> by_root;
    for (std::size_t i = 0; i < keys.size(); ++i) {
        Indices& out = by_root[sets.Find(static_cast<Index>(i))];
        const Indices& pts = nodes[keys[i]];
        out.insert(out.end(), pts.begin(), pts.end());
    }
    std::vector<Indices> pieces;
    for (auto& [root, pts] : by_root) pieces.push_back(std::move(pts));
    std::stable_sort(pieces.begin(), pieces.end(),
                     [](const Indices& a, const Indices& b) { return a.size() > b.size(); });
    if (pieces.empty()) pieces.emplace_back();
    pieces.front().insert(pieces.front().end(), unplaced.begin(), unplaced.end());
    for (auto& p : pieces) std::sort(p.begin(), p.end());
    return pieces;
}

}  // namespace

void FoldSplitParams::Validate() const {
    if (!(min_fold_deg > 0.0f && min_fold_deg <= 180.0f)) {
        throw InvalidArgument(
            fmt::format("min_fold_deg must be in (0, 180], got {}", min_fold_deg));
    }
    if (!(max_middle_share >= 0.0f && max_middle_share <= 1.0f)) {
        throw InvalidArgument(
            fmt::format("max_middle_share must be in [0, 1], got {}", max_middle_share));
    }
    if (!(min_side_share >= 0.0f && min_side_share <= 0.5f)) {
        throw InvalidArgument(
            fmt::format("min_side_share must be in [0, 0.5], got {}", min_side_share));
    }
}

std::vector<Indices> SplitFoldedParts(const PointCloud& cloud, const Indices& object,
                                      const std::vector<Indices>& parts, const PartBorders& borders,
                                      const FoldSplitParams& params) {
    params.Validate();
    if (borders.point_part.size() != object.size() ||
        borders.patch_cells.size() != borders.patches.size()) {
        throw InvalidArgument("part borders do not belong to this object");
    }
    if (!parts.empty() && !cloud.HasNormals()) throw DataError("folded parts need normals");
    std::vector<Indices> out = parts;
    std::vector<Indices> tail;
    for (std::size_t k = 0; k < parts.size(); ++k) {
        if (parts[k].size() < params.min_part_points) continue;
        const std::size_t stride = (parts[k].size() + kMaxSample - 1) / kMaxSample;
        std::vector<Eigen::Vector3f> normals;
        for (std::size_t i = 0; i < parts[k].size(); i += stride) {
            const Eigen::Vector3f& n = cloud.normals[parts[k][i]];
            if (n.allFinite() && n.norm() > 0.5f) normals.push_back(n.normalized());
        }
        if (normals.size() < 2) continue;
        const auto modes = TwoModes(normals);
        if (!IsFold(normals, modes, params)) continue;
        auto pieces =
            FoldPieces(cloud, object, borders, static_cast<int>(k), modes, params.min_piece_points);
        if (pieces.size() < 2) continue;
        out[k] = std::move(pieces.front());
        for (std::size_t p = 1; p < pieces.size(); ++p) tail.push_back(std::move(pieces[p]));
    }
    for (auto& t : tail) out.push_back(std::move(t));
    return out;
}

}  // namespace multicue

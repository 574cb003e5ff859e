#include "multicue/segmentation/part_borders.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <unordered_map>

#include <fmt/format.h>
#include <Eigen/Eigenvalues>

#include "multicue/core/cell_key.hpp"
#include "multicue/core/exceptions.hpp"

namespace multicue {
namespace {

float Median(std::vector<float> values) {
    if (values.empty()) return 0.0f;
    const auto mid = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
    std::nth_element(values.begin(), mid, values.end());
    return *mid;
}

// The part of every object point (-1: none), from the parts' points by binary search.
std::vector<int> PointParts(const Indices& object, const std::vector<Indices>& parts) {
    std::vector<int> point_part(object.size(), -1);
    for (std::size_t k = 0; k < parts.size(); ++k) {
        for (Index i : parts[k]) {
            const auto it = std::lower_bound(object.begin(), object.end(), i);
            if (it == object.end() || *it != i) {
                throw InvalidArgument(
                    fmt::format("part {} has point {}, which is not in the object", k, i));
            }
            point_part[static_cast<std::size_t>(it - object.begin())] = static_cast<int>(k);
        }
    }
    return point_part;
}

// The least-squares plane's normal of a patch's points from their moments about one of them,
// oriented like `normal`; `normal` itself for fewer than 4 points or no clear smallest axis.
Eigen::Vector3f PlaneNormal(const Eigen::Matrix3d& second, const Eigen::Vector3d& first,
                            std::size_t count, const Eigen::Vector3f& normal) {
    if (count < 4) return normal;
    const double n = static_cast<double>(count);
    const Eigen::Matrix3d cov = second / n - (first / n) * (first / n).transpose();
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
    const Eigen::Vector3d ev = eig.eigenvalues();  // ascending
    if (!(ev(1) > 4.0 * ev(0))) return normal;
    Eigen::Vector3f m = eig.eigenvectors().col(0).cast<float>();
    if (m.dot(normal) < 0.0f) m = -m;
    return m;
}

struct Grid {
    std::unordered_map<std::uint64_t, std::size_t> patch_of_key;
    std::vector<Eigen::Vector3i> coords;
};

// Patches: mean position and normal of the points with finite values in each voxel, majority part.
Grid BuildPatches(const PointCloud& cloud, const Indices& object, float patch_size,
                  PartBorders& out) {
    const float inv = 1.0f / patch_size;
    Grid grid;
    std::vector<std::map<int, std::size_t>> votes;
    std::vector<Eigen::Matrix3d> second;  // sums of (p - first) (p - first)^T per patch
    std::vector<Eigen::Vector3d> first_moment;
    std::vector<Eigen::Vector3f> origin;
    out.point_patch.assign(object.size(), SIZE_MAX);
    for (std::size_t n = 0; n < object.size(); ++n) {
        const Index i = object[n];
        const Eigen::Vector3f& p = cloud.points[i];
        const Eigen::Vector3f& nv = cloud.normals[i];
        if (!p.allFinite() || !nv.allFinite()) continue;
        const Eigen::Vector3i c = (p * inv).array().floor().cast<int>();
        auto [it, inserted] =
            grid.patch_of_key.try_emplace(detail::PackCellKey(c), out.patches.size());
        if (inserted) {
            out.patches.emplace_back();
            grid.coords.push_back(c);
            votes.emplace_back();
            second.push_back(Eigen::Matrix3d::Zero());
            first_moment.push_back(Eigen::Vector3d::Zero());
            origin.push_back(p);
        }
        SurfacePatch& patch = out.patches[it->second];
        patch.centroid += p;
        patch.normal += nv;
        ++patch.count;
        const Eigen::Vector3d q = (p - origin[it->second]).cast<double>();
        first_moment[it->second] += q;
        second[it->second] += q * q.transpose();
        if (out.point_part[n] >= 0) ++votes[it->second][out.point_part[n]];
        out.point_patch[n] = it->second;
    }
    for (std::size_t v = 0; v < out.patches.size(); ++v) {
        SurfacePatch& patch = out.patches[v];
        patch.centroid /= static_cast<float>(patch.count);
        if (patch.normal.norm() > 0.0f) patch.normal.normalize();
        patch.plane_normal = PlaneNormal(second[v], first_moment[v], patch.count, patch.normal);
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

struct Accumulator {
    std::size_t convex = 0;
    std::vector<float> angles;
    double gap = 0.0;
    double ray = 0.0;
    double bend = 0.0;
    std::size_t steps = 0;
    std::size_t plane_convex = 0;
    double plane_bend = 0.0;
    float min_height = std::numeric_limits<float>::infinity();
    float max_height = -std::numeric_limits<float>::infinity();
    double height = 0.0;
};

}  // namespace

void PartBorderParams::Validate() const {
    if (!(patch_size > 0.0f) || !std::isfinite(patch_size)) {
        throw InvalidArgument(fmt::format("patch_size must be > 0, got {}", patch_size));
    }
    if (!(smooth_angle_deg >= 0.0f && smooth_angle_deg <= 90.0f)) {
        throw InvalidArgument(
            fmt::format("smooth_angle_deg must be in [0, 90], got {}", smooth_angle_deg));
    }
    if (!(step_height >= 0.0f) || !std::isfinite(step_height)) {
        throw InvalidArgument(fmt::format("step_height must be >= 0, got {}", step_height));
    }
}

PartBorders ComputePartBorders(const PointCloud& cloud, const Indices& object,
                               const std::vector<Indices>& parts, const PartBorderParams& params,
                               const Eigen::Vector4f& support_plane) {
    params.Validate();
    PartBorders out;
    if (object.empty()) return out;
    if (!cloud.HasNormals()) throw DataError("part borders need normals");
    for (Index i : object) {
        if (i >= cloud.size()) {
            throw InvalidArgument(fmt::format("object point {} of a cloud of {}", i, cloud.size()));
        }
    }
    out.point_part = PointParts(object, parts);
    const Grid grid = BuildPatches(cloud, object, params.patch_size, out);
    out.part_patches.assign(parts.size(), 0);
    for (const SurfacePatch& p : out.patches) {
        if (p.part >= 0) ++out.part_patches[static_cast<std::size_t>(p.part)];
    }
    const float smooth_cos = std::cos(params.smooth_angle_deg * static_cast<float>(M_PI) / 180.0f);
    const float rad_to_deg = 180.0f / static_cast<float>(M_PI);
    const Eigen::Vector3f eye = cloud.sensor_origin;
    std::map<std::pair<std::size_t, std::size_t>, Accumulator> acc;
    std::vector<double> inner_bend(parts.size(), 0.0);
    std::vector<std::size_t> inner_pairs(parts.size(), 0);
    const auto& patches = out.patches;
    for (std::size_t v = 0; v < patches.size(); ++v) {
        const SurfacePatch& a = patches[v];
        if (a.part < 0) continue;
        for (int dx = -1; dx <= 1; ++dx) {
            for (int dy = -1; dy <= 1; ++dy) {
                for (int dz = -1; dz <= 1; ++dz) {
                    const auto it = grid.patch_of_key.find(
                        detail::PackCellKey(grid.coords[v] + Eigen::Vector3i(dx, dy, dz)));
                    if (it == grid.patch_of_key.end() || it->second <= v) continue;
                    const SurfacePatch& b = patches[it->second];
                    if (b.part < 0) continue;
                    const Eigen::Vector3f d = a.centroid - b.centroid;
                    if (b.part == a.part) {
                        const float dist = d.norm();
                        if (dist > 0.0f) {
                            inner_bend[static_cast<std::size_t>(a.part)] +=
                                (a.normal - b.normal).dot(d) / dist;
                            ++inner_pairs[static_cast<std::size_t>(a.part)];
                        }
                        continue;
                    }
                    const bool convex =
                        a.normal.dot(b.normal) >= smooth_cos || a.normal.dot(d) > b.normal.dot(d);
                    auto& border = acc[{static_cast<std::size_t>(std::min(a.part, b.part)),
                                        static_cast<std::size_t>(std::max(a.part, b.part))}];
                    border.convex += convex ? 1 : 0;
                    border.angles.push_back(
                        std::acos(std::clamp(a.normal.dot(b.normal), -1.0f, 1.0f)) * rad_to_deg);
                    const float dist = d.norm();
                    if (dist > 0.0f) {
                        border.bend += (a.normal - b.normal).dot(d) / dist;
                        border.plane_bend += (a.plane_normal - b.plane_normal).dot(d) / dist;
                    }
                    const bool plane_convex = a.plane_normal.dot(b.plane_normal) >= smooth_cos ||
                                              a.plane_normal.dot(d) > b.plane_normal.dot(d);
                    border.plane_convex += plane_convex ? 1 : 0;
                    const float h = support_plane.head<3>().dot(0.5f * (a.centroid + b.centroid)) +
                                    support_plane.w();
                    border.min_height = std::min(border.min_height, h);
                    border.max_height = std::max(border.max_height, h);
                    border.height += h;
                    const Eigen::Vector3f mean_normal = a.normal + b.normal;
                    if (a.normal.dot(b.normal) >= smooth_cos && mean_normal.norm() > 0.0f &&
                        std::abs(d.dot(mean_normal.normalized())) > params.step_height) {
                        ++border.steps;
                    }
                    border.gap += dist / params.patch_size;
                    const Eigen::Vector3f ray = 0.5f * (a.centroid + b.centroid) - eye;
                    if (dist > 0.0f && ray.norm() > 0.0f) {
                        border.ray += std::abs(d.dot(ray)) / (dist * ray.norm());
                    }
                }
            }
        }
    }
    out.patch_cells = grid.coords;
    out.part_bend.assign(parts.size(), 0.0f);
    for (std::size_t k = 0; k < parts.size(); ++k) {
        if (inner_pairs[k] > 0) {
            out.part_bend[k] =
                static_cast<float>(inner_bend[k] / static_cast<double>(inner_pairs[k]));
        }
    }
    out.borders.reserve(acc.size());
    for (auto& [pair, a] : acc) {
        PartBorder b;
        b.a = pair.first;
        b.b = pair.second;
        b.pairs = a.angles.size();
        b.convex = a.convex;
        const auto n = static_cast<double>(b.pairs);
        b.mean_gap = static_cast<float>(a.gap / n);
        b.mean_ray_alignment = static_cast<float>(a.ray / n);
        b.mean_bend = static_cast<float>(a.bend / n);
        b.step_share = static_cast<float>(static_cast<double>(a.steps) / n);
        b.plane_convex = a.plane_convex;
        b.plane_bend = static_cast<float>(a.plane_bend / n);
        b.min_height = a.min_height;
        b.max_height = a.max_height;
        b.mean_height = static_cast<float>(a.height / n);
        b.median_angle_deg = Median(std::move(a.angles));
        out.borders.push_back(b);
    }
    return out;
}

}  // namespace multicue

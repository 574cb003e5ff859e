#include "multicue/segmentation/occlusion_merge.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>
#include <Eigen/Eigenvalues>

#include "multicue/core/disjoint_sets.hpp"
#include "multicue/core/exceptions.hpp"
#include "multicue/core/parallel.hpp"
#include "multicue/segmentation/sac_cylinder.hpp"

namespace multicue {
namespace {

constexpr float kMergeDegToRad = 3.14159265358979f / 180.0f;

void CheckParams(const OcclusionMergeParams& p) {
    const auto in_unit = [](float v) { return v >= 0.0f && v <= 1.0f; };
    const auto positive = [](float v) { return v > 0.0f && std::isfinite(v); };
    if (!(p.depth_margin >= 0.0f) || !std::isfinite(p.depth_margin)) {
        throw InvalidArgument(fmt::format("depth_margin must be >= 0, got {}", p.depth_margin));
    }
    if (!(p.min_near_share > 0.0f && p.min_near_share <= 1.0f)) {
        throw InvalidArgument(
            fmt::format("min_near_share must be in (0, 1], got {}", p.min_near_share));
    }
    if (!in_unit(p.min_occluded_share)) {
        throw InvalidArgument(
            fmt::format("min_occluded_share must be in [0, 1], got {}", p.min_occluded_share));
    }
    if (p.min_rows < 1) throw InvalidArgument("min_rows must be >= 1, got 0");
    if (!positive(p.max_gap)) {
        throw InvalidArgument(fmt::format("max_gap must be > 0, got {}", p.max_gap));
    }
    if (!in_unit(p.min_height_overlap)) {
        throw InvalidArgument(
            fmt::format("min_height_overlap must be in [0, 1], got {}", p.min_height_overlap));
    }
    if (!positive(p.surface_distance)) {
        throw InvalidArgument(
            fmt::format("surface_distance must be > 0, got {}", p.surface_distance));
    }
    if (!(p.surface_angle_deg > 0.0f && p.surface_angle_deg <= 90.0f)) {
        throw InvalidArgument(
            fmt::format("surface_angle_deg must be in (0, 90], got {}", p.surface_angle_deg));
    }
    if (!(p.min_explained_share > 0.0f && p.min_explained_share <= 1.0f)) {
        throw InvalidArgument(
            fmt::format("min_explained_share must be in (0, 1], got {}", p.min_explained_share));
    }
    if (!positive(p.min_cylinder_radius) || !positive(p.max_cylinder_radius) ||
        p.max_cylinder_radius < p.min_cylinder_radius) {
        throw InvalidArgument(
            fmt::format("cylinder radii must satisfy 0 < min <= max, got {} and {}",
                        p.min_cylinder_radius, p.max_cylinder_radius));
    }
    if (p.cylinder_iterations < 1) {
        throw InvalidArgument(
            fmt::format("cylinder_iterations must be >= 1, got {}", p.cylinder_iterations));
    }
    ResolveThreadCount(p.num_threads);  // throws on negative values
}

// What the image and height tests need of one hypothesis.
struct Fragment {
    Indices points;                 // finite points only
    std::vector<int> row_min;       // per image row: leftmost column, -1 if none
    std::vector<int> row_max;       // per image row: rightmost column
    double mean_column = 0.0;       // orders a pair left to right
    float low = 0.0f, high = 0.0f;  // height range above the plane (2nd-98th percentile) [m]
};

Fragment Describe(const PointCloud& cloud, const Indices& object, const Eigen::Vector4f& plane) {
    Fragment f;
    f.row_min.assign(cloud.height, -1);
    f.row_max.assign(cloud.height, -1);
    std::vector<float> heights;
    for (Index i : object) {
        if (!cloud.IsFinite(i)) continue;
        f.points.push_back(i);
        const int row = static_cast<int>(i / cloud.width);
        const int col = static_cast<int>(i % cloud.width);
        f.row_min[row] = f.row_min[row] < 0 ? col : std::min(f.row_min[row], col);
        f.row_max[row] = std::max(f.row_max[row], col);
        f.mean_column += col;
        heights.push_back(plane.head<3>().dot(cloud.points[i]) + plane[3]);
    }
    if (f.points.empty()) return f;
    f.mean_column /= static_cast<double>(f.points.size());
    std::sort(heights.begin(), heights.end());
    f.low = heights[heights.size() / 50];
    f.high = heights[heights.size() - 1 - heights.size() / 50];
    return f;
}

// Test (1) and (2a): on the rows both fragments occupy, the pixels between the left one's right
// end and the right one's left end are nearer than both ends (an occluder in front); returns the
// median 3D distance across the occluded rows, or infinity when the gap is not occluded.
float OccludedGap(const PointCloud& cloud, const Fragment& left, const Fragment& right,
                  const OcclusionMergeParams& p) {
    const auto range = [&](std::size_t i) {
        return (cloud.points[i] - cloud.sensor_origin).norm();
    };
    std::size_t shared = 0;
    std::vector<float> gaps;
    for (std::size_t row = 0; row < cloud.height; ++row) {
        if (left.row_max[row] < 0 || right.row_min[row] < 0) continue;
        ++shared;
        const int a = left.row_max[row], b = right.row_min[row];
        if (b - a < 2) continue;  // touching or interleaved: nothing hides between them
        const std::size_t base = row * cloud.width;
        const float limit = std::min(range(base + a), range(base + b)) - p.depth_margin;
        std::size_t near = 0, other = 0;
        for (int c = a + 1; c < b; ++c) {
            if (!cloud.IsFinite(base + c)) continue;  // shadows next to occluders have no depth
            (range(base + c) < limit ? near : other) += 1;
        }
        if (near == 0 || static_cast<float>(near) < p.min_near_share * (near + other)) continue;
        gaps.push_back((cloud.points[base + a] - cloud.points[base + b]).norm());
    }
    if (gaps.size() < p.min_rows ||
        static_cast<float>(gaps.size()) < p.min_occluded_share * static_cast<float>(shared)) {
        return std::numeric_limits<float>::infinity();
    }
    std::nth_element(gaps.begin(), gaps.begin() + gaps.size() / 2, gaps.end());
    return gaps[gaps.size() / 2];
}

bool HeightsOverlap(const Fragment& a, const Fragment& b, const OcclusionMergeParams& p) {
    const float overlap = std::min(a.high, b.high) - std::max(a.low, b.low);
    const float smaller = std::min(a.high - a.low, b.high - b.low);
    return smaller <= 0.0f ? overlap >= 0.0f : overlap >= p.min_height_overlap * smaller;
}

// Test (3), planes (box faces): the least-squares plane of `from`'s largest part, when that part
// is planar, holds enough of `to`'s points with matching normals.
bool PlaneContinues(const PointCloud& cloud, const std::vector<Indices>& from_parts,
                    const Indices& to, const OcclusionMergeParams& p) {
    const Indices* largest = nullptr;
    for (const auto& part : from_parts) {
        if (largest == nullptr || part.size() > largest->size()) largest = &part;
    }
    if (largest == nullptr || largest->size() < 3) return false;
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    std::size_t n = 0;
    for (Index i : *largest) {
        if (!cloud.IsFinite(i)) continue;
        mean += cloud.points[i].cast<double>();
        ++n;
    }
    if (n < 3) return false;
    mean /= static_cast<double>(n);
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (Index i : *largest) {
        if (!cloud.IsFinite(i)) continue;
        const Eigen::Vector3d d = cloud.points[i].cast<double>() - mean;
        cov += d * d.transpose();
    }
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(cov);
    const Eigen::Vector3f normal = solver.eigenvectors().col(0).cast<float>();
    const Eigen::Vector3f centre = mean.cast<float>();
    const float min_cos = std::cos(p.surface_angle_deg * kMergeDegToRad);
    const auto on_plane = [&](Index i) {
        const Eigen::Vector3f& nrm = cloud.normals[i];
        return std::abs(normal.dot(cloud.points[i] - centre)) < p.surface_distance &&
               nrm.allFinite() && std::abs(normal.dot(nrm)) > min_cos;
    };
    // A curved part has no plane to continue.
    const auto planar =
        static_cast<std::size_t>(std::count_if(largest->begin(), largest->end(), [&](Index i) {
            return cloud.IsFinite(i) && on_plane(i);
        }));
    if (planar < n * 4 / 5) return false;
    const auto explained = static_cast<std::size_t>(std::count_if(to.begin(), to.end(), on_plane));
    return static_cast<float>(explained) >= p.min_explained_share * static_cast<float>(to.size());
}

// Test (3), cylinders (cans, bottles): a cylinder fitted to `from` explains enough of `to`.
bool CylinderContinues(const PointCloud& cloud, const Indices& from, const Indices& to,
                       const OcclusionMergeParams& p) {
    CylinderFitParams cp;
    cp.sac.distance_threshold = p.surface_distance;
    cp.sac.max_iterations = p.cylinder_iterations;
    cp.sac.max_refine_rounds = 3;
    cp.sac.normal_distance_weight = 0.05f;
    cp.sac.num_threads = 1;
    cp.min_radius = p.min_cylinder_radius;
    cp.max_radius = p.max_cylinder_radius;
    const CylinderFit fit = FitCylinder(cloud, from, cp);
    if (!fit.found ||
        static_cast<float>(fit.inliers.size()) < p.min_explained_share * from.size()) {
        return false;
    }
    const float min_cos = std::cos(p.surface_angle_deg * kMergeDegToRad);
    const auto explained =
        static_cast<std::size_t>(std::count_if(to.begin(), to.end(), [&](Index i) {
            const Eigen::Vector3f d = cloud.points[i] - fit.point;
            const Eigen::Vector3f radial = d - fit.axis.dot(d) * fit.axis;
            const float r = radial.norm();
            const Eigen::Vector3f& nrm = cloud.normals[i];
            return r > 0.0f && std::abs(r - fit.radius) < p.surface_distance && nrm.allFinite() &&
                   std::abs(nrm.dot(radial) / r) > min_cos;
        }));
    return static_cast<float>(explained) >= p.min_explained_share * static_cast<float>(to.size());
}

}  // namespace

void OcclusionMergeParams::Validate() const { CheckParams(*this); }

OcclusionMergeResult MergeOccludedFragments(const PointCloud& cloud,
                                            const std::vector<Indices>& objects,
                                            const std::vector<std::vector<Indices>>& parts,
                                            const Eigen::Vector4f& support_plane,
                                            const OcclusionMergeParams& params) {
    CheckParams(params);
    if (parts.size() != objects.size()) {
        throw InvalidArgument(fmt::format("parts must have one list per object ({}), got {}",
                                          objects.size(), parts.size()));
    }
    if (!support_plane.allFinite()) throw InvalidArgument("support_plane must be finite");
    for (const auto& object : objects) {
        for (Index i : object) {
            if (i >= cloud.size()) {
                throw InvalidArgument(
                    fmt::format("index {} out of range for a cloud of {} points", i, cloud.size()));
            }
        }
    }
    OcclusionMergeResult result;
    const std::size_t n = objects.size();
    detail::DisjointSets sets(n);
    if (n >= 2 && cloud.IsOrganized()) {
        if (!cloud.HasNormals()) throw DataError("occlusion merge needs normals");
        const bool has_plane = support_plane.head<3>().norm() > 0.5f;
        std::vector<Fragment> fragments(n);
        ParallelFor(
            n, params.num_threads,
            [&](std::size_t k) { fragments[k] = Describe(cloud, objects[k], support_plane); }, 1);
        // Every pair's tests in parallel (they do not depend on the merges), the merges in pair
        // order: a pair already joined through others is skipped as before.
        struct Pair {
            std::size_t a, b;
            float gap = std::numeric_limits<float>::infinity();
            bool continues = false;
        };
        std::vector<Pair> pairs;
        for (std::size_t a = 0; a < n; ++a) {
            for (std::size_t b = a + 1; b < n; ++b) {
                if (!fragments[a].points.empty() && !fragments[b].points.empty())
                    pairs.push_back({a, b});
            }
        }
        ParallelFor(
            pairs.size(), params.num_threads,
            [&](std::size_t k) {
                Pair& pair = pairs[k];
                const Fragment& fa = fragments[pair.a];
                const Fragment& fb = fragments[pair.b];
                const bool a_left = fa.mean_column <= fb.mean_column;
                pair.gap = OccludedGap(cloud, a_left ? fa : fb, a_left ? fb : fa, params);
                if (!(pair.gap <= params.max_gap)) return;
                if (has_plane && !HeightsOverlap(fa, fb, params)) return;
                pair.continues = PlaneContinues(cloud, parts[pair.a], fb.points, params) ||
                                 PlaneContinues(cloud, parts[pair.b], fa.points, params) ||
                                 CylinderContinues(cloud, fa.points, fb.points, params) ||
                                 CylinderContinues(cloud, fb.points, fa.points, params);
            },
            1);
        for (const Pair& pair : pairs) {
            const auto a = static_cast<Index>(pair.a), b = static_cast<Index>(pair.b);
            if (sets.Find(a) == sets.Find(b) || !std::isfinite(pair.gap)) continue;
            ++result.candidate_pairs;
            if (!pair.continues) continue;
            sets.Unite(a, b);
            ++result.merges;
        }
    }
    std::vector<long> group_of(n, -1);
    for (std::size_t k = 0; k < n; ++k) {
        const Index root = sets.Find(static_cast<Index>(k));
        if (group_of[root] < 0) {
            group_of[root] = static_cast<long>(result.groups.size());
            result.groups.emplace_back();
        }
        result.groups[static_cast<std::size_t>(group_of[root])].push_back(k);
    }
    return result;
}

std::vector<ObjectSegment> MergeOccludedObjects(const PointCloud& cloud,
                                                std::vector<ObjectSegment> objects,
                                                const Eigen::Vector4f& support_plane,
                                                const Switchable<OcclusionMergeParams>& params) {
    params.Validate();
    if (!params.enabled || objects.size() < 2) return objects;
    std::vector<Indices> indices;
    std::vector<std::vector<Indices>> parts;
    indices.reserve(objects.size());
    parts.reserve(objects.size());
    for (const auto& o : objects) {
        indices.push_back(o.indices);
        parts.push_back(o.parts);
    }
    const OcclusionMergeResult merged =
        MergeOccludedFragments(cloud, indices, parts, support_plane, params);
    if (merged.merges == 0) return objects;
    std::vector<ObjectSegment> out;
    out.reserve(merged.groups.size());
    for (const auto& group : merged.groups) {
        ObjectSegment o = std::move(objects[group.front()]);
        for (std::size_t k = 1; k < group.size(); ++k) {
            auto& other = objects[group[k]];
            o.indices.insert(o.indices.end(), other.indices.begin(), other.indices.end());
            for (auto& part : other.parts) o.parts.push_back(std::move(part));
        }
        std::sort(o.indices.begin(), o.indices.end());
        out.push_back(std::move(o));
    }
    return out;
}

}  // namespace multicue

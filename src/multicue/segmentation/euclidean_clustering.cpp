#include "multicue/segmentation/euclidean_clustering.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>
#include <unordered_map>
#include <utility>

#include <fmt/format.h>

#include "multicue/core/disjoint_sets.hpp"
#include "multicue/core/exceptions.hpp"
#include "multicue/core/parallel.hpp"

namespace multicue {
namespace {

void CheckClusterParams(float tolerance, std::size_t min_size, std::size_t max_size) {
    if (!(tolerance > 0.0f) || !std::isfinite(tolerance)) {
        throw InvalidArgument(fmt::format("cluster tolerance must be > 0, got {}", tolerance));
    }
    if (max_size == 0) throw InvalidArgument("max_cluster_size must be >= 1, got 0");
    if (min_size > max_size) {
        throw InvalidArgument(fmt::format(
            "min_cluster_size ({}) must not exceed max_cluster_size ({})", min_size, max_size));
    }
}

// Marks with 1 the finite points to cluster: those of `subset` (or of `mask`), or all when both
// are empty. Returns how many were marked.
std::size_t MarkPoints(const PointCloud& cloud, const Indices& subset,
                       const std::vector<std::uint8_t>& mask, std::vector<std::uint8_t>& marked) {
    const std::size_t n = cloud.size();
    marked.assign(n, 0);
    std::size_t count = 0;
    auto mark = [&](std::size_t i) {
        if (marked[i] == 0 && cloud.IsFinite(i)) {
            marked[i] = 1;
            ++count;
        }
    };
    if (!subset.empty()) {
        for (Index i : subset) {
            if (i >= n) {
                throw InvalidArgument(
                    fmt::format("subset index {} is out of range for a cloud of {} points", i, n));
            }
            mark(i);
        }
    } else if (!mask.empty()) {
        for (std::size_t i = 0; i < n; ++i) {
            if (mask[i] != 0) mark(i);
        }
    } else {
        for (std::size_t i = 0; i < n; ++i) mark(i);
    }
    return count;
}

// Applies the size filters, orders the clusters (largest first, then by smallest index) and
// fills the labels. Each component must already be sorted ascending.
ClusteringResult Finish(std::vector<Indices> components, std::size_t cloud_size,
                        std::size_t num_points, std::size_t min_size, std::size_t max_size,
                        bool compute_labels) {
    ClusteringResult result;
    result.num_points = num_points;
    for (auto& c : components) {
        if (c.size() < min_size) {
            ++result.num_too_small;
        } else if (c.size() > max_size) {
            ++result.num_too_large;
        } else {
            result.clusters.push_back(std::move(c));
        }
    }
    std::sort(result.clusters.begin(), result.clusters.end(),
              [](const Indices& a, const Indices& b) {
                  if (a.size() != b.size()) return a.size() > b.size();
                  return a.front() < b.front();
              });
    if (compute_labels) {
        result.labels.assign(cloud_size, kNoCluster);
        for (std::size_t c = 0; c < result.clusters.size(); ++c) {
            for (Index i : result.clusters[c]) result.labels[i] = static_cast<std::int32_t>(c);
        }
    }
    return result;
}

}  // namespace

ClusteringResult EuclideanClustering(const PointCloud& cloud, const KdTree& tree,
                                     const EuclideanClusteringParams& params) {
    CheckClusterParams(params.tolerance, params.min_cluster_size, params.max_cluster_size);
    const std::size_t n = cloud.size();
    // 0: not clustered, 1: waiting, 2: taken by a cluster.
    std::vector<std::uint8_t> state;
    const std::size_t num_points = MarkPoints(cloud, params.subset, {}, state);

    std::vector<Indices> components;
    Indices neighbors;
    std::vector<float> squared_distances;
    for (std::size_t seed = 0; seed < n; ++seed) {
        if (state[seed] != 1) continue;
        // Breadth-first flood fill; the component doubles as the queue.
        Indices component{static_cast<Index>(seed)};
        state[seed] = 2;
        for (std::size_t head = 0; head < component.size(); ++head) {
            const Index q = component[head];
            tree.SearchRadius(cloud.points[q], params.tolerance, neighbors, squared_distances);
            bool found_self = false;
            for (Index j : neighbors) {
                if (j >= n) {
                    throw InvalidArgument(fmt::format(
                        "the k-d tree holds point {}, but the cloud has only {} points", j, n));
                }
                found_self = found_self || j == q;
                if (state[j] == 1) {
                    state[j] = 2;
                    component.push_back(j);
                }
            }
            if (!found_self) {
                throw InvalidArgument(fmt::format(
                    "point {} is to be clustered but the k-d tree does not index it", q));
            }
        }
        std::sort(component.begin(), component.end());
        components.push_back(std::move(component));
    }
    return Finish(std::move(components), n, num_points, params.min_cluster_size,
                  params.max_cluster_size, params.compute_labels);
}

namespace {

// One cell of the clustering grid: its points (ascending) and their bounding box.
struct GridCell {
    std::int64_t x = 0, y = 0, z = 0;
    std::uint32_t begin = 0, end = 0;  // range in the grid's point list
    Eigen::Vector3f lo, hi;
};

// 21 bits per axis; coordinates are >= 0 (counted from the points' lower corner, plus 2) so that
// the neighbours at -2 .. +2 never wrap around.
std::uint64_t CellKey(std::int64_t x, std::int64_t y, std::int64_t z) {
    constexpr std::uint64_t kMask = (1u << 21) - 1u;
    return ((static_cast<std::uint64_t>(x) & kMask) << 42) |
           ((static_cast<std::uint64_t>(y) & kMask) << 21) |
           (static_cast<std::uint64_t>(z) & kMask);
}

float BoxGapSquared(const GridCell& a, const GridCell& b) {
    const Eigen::Vector3f gap =
        (a.lo - b.hi).cwiseMax(b.lo - a.hi).cwiseMax(Eigen::Vector3f::Zero());
    return gap.squaredNorm();
}

// The marked points binned into cells of edge tolerance / sqrt(3): two points of one cell are
// always neighbours, and neighbours lie at most two cells apart along each axis.
struct ClusterGrid {
    std::vector<GridCell> cells;  // ascending key order
    Indices points;               // grouped by cell
    std::unordered_map<std::uint64_t, std::uint32_t> cell_of_key;
};

// Nothing when the points span more than 2^21 - 5 cells along an axis (coordinates are counted
// from their lower corner).
std::optional<ClusterGrid> BuildClusterGrid(const PointCloud& cloud, const Indices& members,
                                            float tolerance) {
    const double inv = 1.0 / (static_cast<double>(tolerance) / std::sqrt(3.0) * (1.0 - 1e-6));
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::max());
    Eigen::Vector3d hi = -lo;
    for (Index i : members) {
        lo = lo.cwiseMin(cloud.points[i].cast<double>());
        hi = hi.cwiseMax(cloud.points[i].cast<double>());
    }
    if (((hi - lo) * inv).maxCoeff() > static_cast<double>((1 << 21) - 5)) return std::nullopt;
    auto cell_of = [&](const Eigen::Vector3f& p) -> Eigen::Vector3i {
        return ((p.cast<double>() - lo) * inv).array().floor().cast<int>() + 2;
    };
    std::vector<std::pair<std::uint64_t, Index>> keyed;
    keyed.reserve(members.size());
    for (Index i : members) {
        const Eigen::Vector3i c = cell_of(cloud.points[i]);
        keyed.emplace_back(CellKey(c.x(), c.y(), c.z()), i);
    }
    std::sort(keyed.begin(), keyed.end());
    ClusterGrid grid;
    grid.points.resize(keyed.size());
    grid.cell_of_key.reserve(keyed.size() / 2 + 1);
    for (std::size_t k = 0; k < keyed.size(); ++k) {
        grid.points[k] = keyed[k].second;
        const Eigen::Vector3f& p = cloud.points[grid.points[k]];
        if (k == 0 || keyed[k].first != keyed[k - 1].first) {
            const Eigen::Vector3i c = cell_of(p);
            grid.cell_of_key.emplace(keyed[k].first, static_cast<std::uint32_t>(grid.cells.size()));
            grid.cells.push_back({c.x(), c.y(), c.z(), static_cast<std::uint32_t>(k), 0, p, p});
        }
        GridCell& g = grid.cells.back();
        g.end = static_cast<std::uint32_t>(k + 1);
        g.lo = g.lo.cwiseMin(p);
        g.hi = g.hi.cwiseMax(p);
    }
    return grid;
}

float PointBoxGapSquared(const Eigen::Vector3f& p, const GridCell& c) {
    return (c.lo - p).cwiseMax(p - c.hi).cwiseMax(Eigen::Vector3f::Zero()).squaredNorm();
}

// Whether some point of cell a and some point of cell b are within the tolerance. Only the points
// of each cell within the tolerance of the other cell's box can be such a pair.
bool CellsLinked(const PointCloud& cloud, const ClusterGrid& grid, const GridCell& a,
                 const GridCell& b, float tol_sq) {
    thread_local std::vector<Eigen::Vector3f> near_b;
    near_b.clear();
    for (std::uint32_t j = b.begin; j < b.end; ++j) {
        const Eigen::Vector3f& q = cloud.points[grid.points[j]];
        if (PointBoxGapSquared(q, a) <= tol_sq) near_b.push_back(q);
    }
    if (near_b.empty()) return false;
    for (std::uint32_t i = a.begin; i < a.end; ++i) {
        const Eigen::Vector3f& p = cloud.points[grid.points[i]];
        if (PointBoxGapSquared(p, b) > tol_sq) continue;
        for (const Eigen::Vector3f& q : near_b) {
            if ((q - p).squaredNorm() <= tol_sq) return true;
        }
    }
    return false;
}

// Union-find over cells: a pair of cells within reach is joined as soon as one pair of their
// points is within the tolerance (the relation of EuclideanClustering); the points of each
// component, ascending.
std::vector<Indices> GridComponents(const PointCloud& cloud, const ClusterGrid& grid,
                                    float tolerance) {
    const float tol_sq = tolerance * tolerance;
    const auto& cells = grid.cells;
    detail::DisjointSets sets(cells.size());
    for (std::uint32_t a = 0; a < cells.size(); ++a) {
        const GridCell& ca = cells[a];
        // Only the cells of larger keys (cells are in key order, keys in (x, y, z) order): the
        // others were paired with this one when they were `a`.
        for (int dx = 0; dx <= 2; ++dx) {
            for (int dy = dx == 0 ? 0 : -2; dy <= 2; ++dy) {
                for (int dz = dx == 0 && dy == 0 ? 1 : -2; dz <= 2; ++dz) {
                    const auto it = grid.cell_of_key.find(CellKey(ca.x + dx, ca.y + dy, ca.z + dz));
                    if (it == grid.cell_of_key.end() || it->second <= a) continue;
                    const std::uint32_t b = it->second;
                    if (sets.Find(a) == sets.Find(b) || BoxGapSquared(ca, cells[b]) > tol_sq)
                        continue;
                    if (CellsLinked(cloud, grid, ca, cells[b], tol_sq)) sets.Unite(a, b);
                }
            }
        }
    }
    std::vector<std::int32_t> component_of_root(cells.size(), -1);
    std::vector<Indices> components;
    for (std::uint32_t c = 0; c < cells.size(); ++c) {
        const Index root = sets.Find(c);
        if (component_of_root[root] < 0) {
            component_of_root[root] = static_cast<std::int32_t>(components.size());
            components.emplace_back();
        }
        Indices& out = components[static_cast<std::size_t>(component_of_root[root])];
        out.insert(out.end(), grid.points.begin() + cells[c].begin,
                   grid.points.begin() + cells[c].end);
    }
    for (auto& c : components) std::sort(c.begin(), c.end());
    return components;
}

}  // namespace

ClusteringResult EuclideanClusteringGrid(const PointCloud& cloud,
                                         const EuclideanClusteringParams& params) {
    CheckClusterParams(params.tolerance, params.min_cluster_size, params.max_cluster_size);
    const std::size_t n = cloud.size();
    std::vector<std::uint8_t> marked;
    const std::size_t num_points = MarkPoints(cloud, params.subset, {}, marked);
    if (num_points == 0) {
        return Finish({}, n, 0, params.min_cluster_size, params.max_cluster_size,
                      params.compute_labels);
    }
    // The marked points as a list, so that a small subset of a large cloud costs its own size.
    Indices members;
    members.reserve(num_points);
    if (params.subset.empty()) {
        for (std::size_t i = 0; i < n; ++i)
            if (marked[i] != 0) members.push_back(static_cast<Index>(i));
    } else {
        for (Index i : params.subset) {
            if (marked[i] != 1) continue;
            marked[i] = 2;  // listed
            members.push_back(i);
        }
    }
    const std::optional<ClusterGrid> grid = BuildClusterGrid(cloud, members, params.tolerance);
    if (!grid) {  // kilometres wide at this tolerance: the k-d tree
        const KdTree tree = params.subset.empty() ? KdTree(cloud) : KdTree(cloud, params.subset);
        return EuclideanClustering(cloud, tree, params);
    }
    return Finish(GridComponents(cloud, *grid, params.tolerance), n, num_points,
                  params.min_cluster_size, params.max_cluster_size, params.compute_labels);
}

ClusteringResult EuclideanClusteringOrganized(const PointCloud& organized,
                                              const OrganizedClusteringParams& params) {
    CheckClusterParams(params.tolerance, params.min_cluster_size, params.max_cluster_size);
    if (params.connectivity != 4 && params.connectivity != 8) {
        throw InvalidArgument(
            fmt::format("connectivity must be 4 or 8, got {}", params.connectivity));
    }
    if (params.half_window < 1) {
        throw InvalidArgument(
            fmt::format("half_window must be >= 1 pixel, got {}", params.half_window));
    }
    if (!params.subset.empty() && !params.mask.empty()) {
        throw InvalidArgument("give either a subset or a mask for organized clustering, not both");
    }
    ResolveThreadCount(params.num_threads);  // throws on negative values
    const std::size_t n = organized.size();
    if (!params.mask.empty() && params.mask.size() != n) {
        throw InvalidArgument(
            fmt::format("mask has {} entries for a cloud of {} points", params.mask.size(), n));
    }
    if (n == 0) return Finish({}, 0, 0, params.min_cluster_size, params.max_cluster_size, false);
    if (!organized.IsOrganized()) {
        throw InvalidArgument(
            fmt::format("organized clustering needs an organized cloud, got {}x{} for {} points",
                        organized.width, organized.height, n));
    }

    std::vector<std::uint8_t> active;
    const std::size_t num_points = MarkPoints(organized, params.subset, params.mask, active);

    // Forward half of the neighbourhood (later rows, or the same row to the right): each pixel
    // pair is examined once.
    const int h = params.half_window;
    std::vector<std::pair<int, int>> offsets;  // (du, dv)
    for (int dv = 0; dv <= h; ++dv) {
        for (int du = -h; du <= h; ++du) {
            if (dv == 0 && du <= 0) continue;
            if (params.connectivity == 4 && std::abs(du) + dv > h) continue;
            offsets.emplace_back(du, dv);
        }
    }

    const int width = static_cast<int>(organized.width);
    const int height = static_cast<int>(organized.height);
    const float tolerance_sq = params.tolerance * params.tolerance;
    // Blocks of rows are linked in parallel: a link inside a block touches only the block's own
    // pixels (their sets hold nothing else yet), so blocks never share an entry of `sets`. Links
    // reaching into a later block are joined afterwards, in order. With the smallest index as
    // every set's representative, the sets do not depend on the order of the unions.
    constexpr int kBlockRows = 16;
    const int blocks = (height + kBlockRows - 1) / kBlockRows;
    detail::DisjointSets sets(n);
    std::vector<std::vector<std::pair<Index, Index>>> crossing(static_cast<std::size_t>(blocks));
    ParallelFor(
        static_cast<std::size_t>(blocks), params.num_threads,
        [&](std::size_t b) {
            const int v0 = static_cast<int>(b) * kBlockRows;
            const int v1 = std::min(height, v0 + kBlockRows);
            for (int v = v0; v < v1; ++v) {
                for (int u = 0; u < width; ++u) {
                    const auto i = static_cast<Index>(v * width + u);
                    if (active[i] == 0) continue;
                    const Eigen::Vector3f& p = organized.points[i];
                    for (const auto& [du, dv] : offsets) {
                        const int uu = u + du;
                        const int vv = v + dv;
                        if (uu < 0 || uu >= width || vv >= height) continue;
                        const auto j = static_cast<Index>(vv * width + uu);
                        if (active[j] == 0) continue;
                        if (!((organized.points[j] - p).squaredNorm() < tolerance_sq)) continue;
                        if (vv < v1) {
                            sets.Unite(i, j);
                        } else {
                            crossing[b].emplace_back(i, j);
                        }
                    }
                }
            }
        },
        1);
    for (const auto& links : crossing) {
        for (const auto& [i, j] : links) sets.Unite(i, j);
    }

    // Roots are the smallest indices, so visiting pixels in order creates each component at its
    // root and appends its pixels in ascending order.
    std::vector<std::int32_t> component_of_root(n, -1);
    std::vector<Indices> components;
    for (std::size_t k = 0; k < n; ++k) {
        if (active[k] == 0) continue;
        const auto i = static_cast<Index>(k);
        const Index root = sets.Find(i);
        if (component_of_root[root] < 0) {
            component_of_root[root] = static_cast<std::int32_t>(components.size());
            components.emplace_back();
        }
        components[static_cast<std::size_t>(component_of_root[root])].push_back(i);
    }
    return Finish(std::move(components), n, num_points, params.min_cluster_size,
                  params.max_cluster_size, params.compute_labels);
}

void ObjectClusteringParams::Validate() const {
    CheckClusterParams(tolerance, min_points, max_points);
    if (organized_half_window < 1) {
        throw InvalidArgument(
            fmt::format("organized_half_window must be >= 1 pixel, got {}", organized_half_window));
    }
    ResolveThreadCount(num_threads);  // throws on negative values
}

ClusteringResult ClusterObjects(const PointCloud& cloud, const Indices& region,
                                const ObjectClusteringParams& params) {
    params.Validate();
    if (region.empty()) return {};
    if (cloud.IsOrganized()) {
        return EuclideanClusteringOrganized(cloud, {.tolerance = params.tolerance,
                                                    .min_cluster_size = params.min_points,
                                                    .max_cluster_size = params.max_points,
                                                    .subset = region,
                                                    .half_window = params.organized_half_window,
                                                    .num_threads = params.num_threads});
    }
    return EuclideanClusteringGrid(cloud, {.tolerance = params.tolerance,
                                           .min_cluster_size = params.min_points,
                                           .max_cluster_size = params.max_points,
                                           .subset = region});
}

}  // namespace multicue

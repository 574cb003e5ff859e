#include "multicue/features/grsd.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <unordered_map>

#include <fmt/format.h>

#include "multicue/core/cell_key.hpp"
#include "multicue/core/exceptions.hpp"
#include "multicue/search/voxel_traversal.hpp"

namespace multicue {
namespace {

constexpr int kEmpty = kNumSurfaceTypes;  // class 5
constexpr int kClasses = kNumSurfaceTypes + 1;
constexpr std::int64_t kCoordinateLimit = std::int64_t{1} << 20;

std::uint64_t Key(const Eigen::Vector3i& c) {
    for (int a = 0; a < 3; ++a) {
        if (c[a] <= -kCoordinateLimit || c[a] >= kCoordinateLimit) {
            throw InvalidArgument(fmt::format(
                "voxel coordinate {} is outside the +-2^20 range of GRSD; crop the cloud", c[a]));
        }
    }
    return detail::PackCellKey(c);
}

const std::array<Eigen::Vector3i, 26>& NeighbourOffsets() {
    static const std::array<Eigen::Vector3i, 26> offsets = [] {
        std::array<Eigen::Vector3i, 26> o;
        int k = 0;
        for (int dx = -1; dx <= 1; ++dx)
            for (int dy = -1; dy <= 1; ++dy)
                for (int dz = -1; dz <= 1; ++dz)
                    if (dx != 0 || dy != 0 || dz != 0) o[k++] = {dx, dy, dz};
        return o;
    }();
    return offsets;
}

bool Defined(const VoxelRsdResult& voxels, std::uint32_t v) {
    return voxels.types[v] != SurfaceType::kUndefined;
}

// Voxel key -> voxel id for the defined voxels of a subset; checks the indices.
std::unordered_map<std::uint64_t, std::uint32_t> IndexSubset(const VoxelRsdResult& voxels,
                                                             std::span<const std::uint32_t> subset,
                                                             std::vector<bool>& seen) {
    std::unordered_map<std::uint64_t, std::uint32_t> map;
    map.reserve(subset.size() * 2);
    for (std::uint32_t v : subset) {
        if (v >= voxels.size()) {
            throw InvalidArgument(
                fmt::format("voxel index {} is out of range ({} voxels)", v, voxels.size()));
        }
        if (seen[v]) throw InvalidArgument(fmt::format("voxel index {} is repeated", v));
        seen[v] = true;
        if (Defined(voxels, v)) map.emplace(Key(voxels.coordinates[v]), v);
    }
    return map;
}

// One count T(i, j) in the folded bin T(i, j) + T(j, i): it appears twice on the diagonal.
float FoldWeight(int a, int b) { return a == b ? 2.0f : 1.0f; }

int TypeOf(const VoxelRsdResult& voxels, std::uint32_t v) {
    return static_cast<int>(voxels.types[v]);
}

}  // namespace

int GrsdBin(int a, int b) {
    if (a < 0 || b < 0 || a >= kClasses || b >= kClasses) {
        throw InvalidArgument(fmt::format("GRSD classes must be in [0, 5], got {} and {}", a, b));
    }
    if (a > b) std::swap(a, b);
    // Rows 0..a-1 of the upper triangle hold 6 + 5 + ... entries.
    return a * kClasses - a * (a - 1) / 2 + (b - a);
}

FeatureVector GrsdMinusOfVoxels(const VoxelRsdResult& voxels,
                                std::span<const std::uint32_t> subset) {
    std::vector<bool> seen(voxels.size(), false);
    const auto members = IndexSubset(voxels, subset, seen);
    FeatureVector hist = FeatureVector::Zero(kGrsdSize);
    for (std::uint32_t v : subset) {
        if (!Defined(voxels, v)) continue;
        const int source = TypeOf(voxels, v);
        for (const Eigen::Vector3i& o : NeighbourOffsets()) {
            const auto found = members.find(Key(voxels.coordinates[v] + o));
            const int target = found == members.end() ? kEmpty : TypeOf(voxels, found->second);
            hist[GrsdBin(source, target)] += FoldWeight(source, target);
        }
    }
    return hist;
}

FeatureVector GrsdMinusBoundaryCorrection(const VoxelRsdResult& voxels,
                                          std::span<const std::uint32_t> a,
                                          std::span<const std::uint32_t> b) {
    std::vector<bool> seen(voxels.size(), false);
    IndexSubset(voxels, a, seen);
    const auto members_b = IndexSubset(voxels, b, seen);  // also rejects common voxels
    FeatureVector correction = FeatureVector::Zero(kGrsdSize);
    for (std::uint32_t v : a) {
        if (!Defined(voxels, v)) continue;
        const int ta = TypeOf(voxels, v);
        for (const Eigen::Vector3i& o : NeighbourOffsets()) {
            const auto found = members_b.find(Key(voxels.coordinates[v] + o));
            if (found == members_b.end()) continue;
            const int tb = TypeOf(voxels, found->second);
            correction[GrsdBin(ta, tb)] += 2.0f * FoldWeight(ta, tb);
            correction[GrsdBin(ta, kEmpty)] -= 1.0f;
            correction[GrsdBin(tb, kEmpty)] -= 1.0f;
        }
    }
    return correction;
}

namespace {

VoxelRsdResult ClusterVoxels(const PointCloud& cluster, const GrsdParams& params) {
    detail::CheckNormals(cluster, "GRSD");
    const KdTree tree(cluster);
    return ComputeVoxelRsd(cluster, tree, params.voxels);
}

std::vector<std::uint32_t> AllVoxels(const VoxelRsdResult& voxels) {
    std::vector<std::uint32_t> all(voxels.size());
    for (std::size_t v = 0; v < all.size(); ++v) all[v] = static_cast<std::uint32_t>(v);
    return all;
}

}  // namespace

FeatureVector ComputeGrsdMinus(const PointCloud& cluster, const GrsdParams& params) {
    detail::CheckPositive(params.voxels.voxel_size, "voxel_size");
    if (cluster.empty()) return FeatureVector::Zero(kGrsdSize);
    const VoxelRsdResult voxels = ClusterVoxels(cluster, params);
    return GrsdMinusOfVoxels(voxels, AllVoxels(voxels));
}

FeatureVector GrsdOfVoxels(const PointCloud& cloud, const VoxelRsdResult& voxels,
                           const Eigen::Vector3f& viewpoint) {
    if (!viewpoint.allFinite()) throw InvalidArgument("GRSD viewpoint must be finite");
    FeatureVector hist = FeatureVector::Zero(kGrsdSize);
    std::vector<std::uint32_t> occupied;
    for (std::uint32_t v = 0; v < voxels.size(); ++v) {
        if (Defined(voxels, v)) occupied.push_back(v);
    }
    if (occupied.empty()) return hist;
    // Dense grid over the occupied voxels grown by one cell: -1 unknown, 0-4 type, 5 free.
    Eigen::Vector3i lo = voxels.coordinates[occupied[0]];
    Eigen::Vector3i hi = lo;
    for (std::uint32_t v : occupied) {
        lo = lo.cwiseMin(voxels.coordinates[v]);
        hi = hi.cwiseMax(voxels.coordinates[v]);
    }
    lo.array() -= 1;
    hi.array() += 1;
    const Eigen::Vector3i dims = hi - lo + Eigen::Vector3i::Ones();
    const std::int64_t cells = std::int64_t{dims.x()} * dims.y() * dims.z();
    if (cells > (std::int64_t{1} << 26)) {
        throw InvalidArgument(
            fmt::format("GRSD grid of {}x{}x{} voxels is too large; use a cluster, not a scene",
                        dims.x(), dims.y(), dims.z()));
    }
    std::vector<std::int8_t> grid(static_cast<std::size_t>(cells), -1);
    auto at = [&](const Eigen::Vector3i& c) -> std::int8_t& {
        return grid[(static_cast<std::size_t>(c.x()) * dims.y() + c.y()) * dims.z() + c.z()];
    };
    auto inside = [&](const Eigen::Vector3i& c) {
        return (c.array() >= 0).all() && (c.array() < dims.array()).all();
    };
    for (std::uint32_t v : occupied) {
        at(voxels.coordinates[v] - lo) = static_cast<std::int8_t>(TypeOf(voxels, v));
    }
    // Free space: rays from the viewpoint to every point.
    const double inv = 1.0 / voxels.voxel_size;
    const Eigen::Vector3d origin = lo.cast<double>();
    const Eigen::Vector3d box = dims.cast<double>();
    const Eigen::Vector3d eye = viewpoint.cast<double>() * inv - origin;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        if (!cloud.points[i].allFinite() || voxels.point_voxel[i] == VoxelRsdResult::kNoVoxel)
            continue;
        const Eigen::Vector3i target = voxels.coordinates[voxels.point_voxel[i]] - lo;
        const Eigen::Vector3d end = cloud.points[i].cast<double>() * inv - origin;
        Eigen::Vector3d start = eye;
        if (!ClipSegmentToBox(start, end, box)) continue;
        auto mark = [&](const Eigen::Vector3i& c) {
            if (!inside(c) || c == target) return false;
            std::int8_t& cls = at(c);
            if (cls == -1) cls = static_cast<std::int8_t>(kEmpty);
            return true;
        };
        Eigen::Vector3i first(static_cast<int>(std::floor(start.x())),
                              static_cast<int>(std::floor(start.y())),
                              static_cast<int>(std::floor(start.z())));
        if (!mark(first)) continue;
        WalkCells(start, end, mark);
    }
    // Transitions along the line between every pair of occupied voxels.
    for (std::size_t a = 0; a < occupied.size(); ++a) {
        const Eigen::Vector3i ca = voxels.coordinates[occupied[a]] - lo;
        const Eigen::Vector3d sa = ca.cast<double>() + Eigen::Vector3d::Constant(0.5);
        for (std::size_t b = a + 1; b < occupied.size(); ++b) {
            const Eigen::Vector3d sb = (voxels.coordinates[occupied[b]] - lo).cast<double>() +
                                       Eigen::Vector3d::Constant(0.5);
            int previous = at(ca);
            WalkCells(sa, sb, [&](const Eigen::Vector3i& c) {
                const int cls = at(c);
                if (cls < 0) return true;  // unknown: stepped over
                hist[GrsdBin(previous, cls)] += 1.0f;
                previous = cls;
                return true;
            });
        }
    }
    return hist;
}

FeatureVector ComputeGrsd(const PointCloud& cluster, const GrsdParams& params) {
    detail::CheckPositive(params.voxels.voxel_size, "voxel_size");
    const Eigen::Vector3f viewpoint = params.viewpoint.value_or(cluster.sensor_origin);
    if (!viewpoint.allFinite()) throw InvalidArgument("GRSD viewpoint must be finite");
    if (cluster.empty()) return FeatureVector::Zero(kGrsdSize);
    const VoxelRsdResult voxels = ClusterVoxels(cluster, params);
    return GrsdOfVoxels(cluster, voxels, viewpoint);
}

}  // namespace multicue

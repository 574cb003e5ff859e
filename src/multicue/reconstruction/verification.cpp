#include "multicue/reconstruction/verification.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/core/parallel.hpp"
#include "multicue/search/voxel_traversal.hpp"

namespace multicue {
namespace {

enum : std::uint8_t { kUnknown = 0, kFree = 1, kOccupied = 2 };

struct Grid {
    Eigen::Vector3f origin;  // corner of cell (0, 0, 0)
    float size = 0.0f;
    Eigen::Vector3i dims;
    Eigen::Vector3d inside;  // per axis the largest coordinate inside the grid (grid units)
    std::vector<std::uint8_t> cells;

    bool Inside(const Eigen::Vector3i& c) const {
        return (c.array() >= 0).all() && (c.array() < dims.array()).all();
    }
    std::size_t Index(const Eigen::Vector3i& c) const {
        return (static_cast<std::size_t>(c.z()) * static_cast<std::size_t>(dims.y()) +
                static_cast<std::size_t>(c.y())) *
                   static_cast<std::size_t>(dims.x()) +
               static_cast<std::size_t>(c.x());
    }
    Eigen::Vector3i Cell(const Eigen::Vector3f& p) const {
        return ((p - origin) / size).array().floor().cast<int>();
    }
};

/// The cells whose free state is read: those holding a sample, grown by one cell (so that the
/// walks' rounding at cell boundaries cannot matter), [lo, hi] inclusive.
struct ReadCells {
    Eigen::Vector3i lo, hi;
};

/// Whether the segment s -> e (grid units) meets the cells [lo, hi] (the box [lo, hi + 1]).
bool SegmentMeetsCells(const Eigen::Vector3d& s, const Eigen::Vector3d& e, const ReadCells& box) {
    double t0 = 0.0, t1 = 1.0;
    return SegmentInBox(s, e, box.lo.cast<double>(), box.hi.cast<double>().array() + 1.0, t0, t1);
}

/// Marks the cells the ray from o to p crosses (within the grid) free, the cell of p occupied.
/// Only the free state of the `read` cells is ever looked at, so a ray that misses them is not
/// walked and a walk stops once it has passed them (it moves monotonically along each axis): the
/// cells that matter get the marks a whole walk would give them.
void CastRay(Grid& grid, const Eigen::Vector3f& o, const Eigen::Vector3f& p,
             const ReadCells& read) {
    // Grid units: cell c covers [c, c + 1).
    Eigen::Vector3d s = ((o - grid.origin) / grid.size).cast<double>();
    const Eigen::Vector3d e = ((p - grid.origin) / grid.size).cast<double>();
    if (!ClipSegmentToBox(s, e, grid.dims.cast<double>(), grid.inside)) return;
    const Eigen::Vector3i end = e.array().floor().cast<int>();
    if (SegmentMeetsCells(s, e, read)) {
        const Eigen::Vector3d d = e - s;
        auto mark_free = [&](const Eigen::Vector3i& cell) {
            if (cell == end || !grid.Inside(cell)) return false;
            auto& c = grid.cells[grid.Index(cell)];
            if (c == kUnknown) c = kFree;
            for (int a = 0; a < 3; ++a) {
                if ((d[a] > 0.0 && cell[a] > read.hi[a]) || (d[a] < 0.0 && cell[a] < read.lo[a]))
                    return false;
            }
            return true;
        };
        if (mark_free(s.array().floor().cast<int>())) WalkCells(s, e, mark_free);
    }
    if (grid.Inside(end)) grid.cells[grid.Index(end)] = kOccupied;
}

}  // namespace

void VerificationParams::Validate() const {
    if (!(voxel_size > 0.0f)) {
        throw InvalidArgument(
            fmt::format("verification: voxel_size must be > 0, got {}", voxel_size));
    }
    if (!(margin >= 0.0f)) throw InvalidArgument("verification: margin must be >= 0");
    if (tolerance_voxels < 0) throw InvalidArgument("verification: tolerance_voxels must be >= 0");
    if (!(max_invalid_ratio >= 0.0f && max_invalid_ratio <= 1.0f)) {
        throw InvalidArgument("verification: max_invalid_ratio must be in [0, 1]");
    }
    if (!(sample_spacing > 0.0f)) {
        throw InvalidArgument(
            fmt::format("verification: sample_spacing must be > 0, got {}", sample_spacing));
    }
    ResolveThreadCount(num_threads);  // throws on negative values
}

std::vector<Eigen::Vector3f> SampleMeshSurface(const TriangleMesh& mesh, float spacing) {
    if (!(spacing > 0.0f))
        throw InvalidArgument(fmt::format("sample spacing must be > 0, got {}", spacing));
    mesh.Validate();
    std::vector<Eigen::Vector3f> samples;
    for (const auto& t : mesh.triangles) {
        // Rows parallel to the longest edge (b, c), from the opposite vertex a to it: about
        // area / spacing^2 samples, so long thin triangles (a cylinder's sides) are not
        // oversampled.
        Eigen::Vector3f a = mesh.vertices[t[0]], b = mesh.vertices[t[1]], c = mesh.vertices[t[2]];
        const float ab = (b - a).squaredNorm(), bc = (c - b).squaredNorm(),
                    ca = (a - c).squaredNorm();
        if (ab >= bc && ab >= ca) {
            const Eigen::Vector3f apex = c;  // longest edge a-b becomes b-c
            c = b;
            b = a;
            a = apex;
        } else if (ca >= bc && ca >= ab) {
            const Eigen::Vector3f apex = b;  // longest edge c-a becomes b-c
            b = c;
            c = a;
            a = apex;
        }
        const float base = (c - b).norm();
        const float height = base > 0.0f ? (b - a).cross(c - a).norm() / base : 0.0f;
        const int rows = std::max(1, static_cast<int>(std::ceil(height / spacing)));
        for (int r = 0; r <= rows; ++r) {
            const float f = static_cast<float>(r) / static_cast<float>(rows);
            const Eigen::Vector3f from = a + f * (b - a), to = a + f * (c - a);
            const int n = std::max(0, static_cast<int>(std::ceil(f * base / spacing)));
            if (n == 0) {
                samples.push_back(from);
                continue;
            }
            // Each row's last point lies on the edge a-c, which the neighbouring triangle
            // samples too; shared edges are only weighted twice.
            for (int k = 0; k <= n; ++k) {
                samples.push_back(from +
                                  (static_cast<float>(k) / static_cast<float>(n)) * (to - from));
            }
        }
    }
    return samples;
}

VerificationResult VerifyModel(const TriangleMesh& model, const PointCloud& scan,
                               const Eigen::Vector3f& sensor_origin,
                               const VerificationParams& params) {
    params.Validate();
    if (!sensor_origin.allFinite())
        throw InvalidArgument("verification: sensor origin must be finite");
    VerificationResult result;
    result.samples = SampleMeshSurface(model, params.sample_spacing);
    if (result.samples.empty()) return result;

    Eigen::Vector3f lo = result.samples.front(), hi = lo;
    for (const auto& s : result.samples) {
        lo = lo.cwiseMin(s);
        hi = hi.cwiseMax(s);
    }
    lo.array() -= params.margin;
    hi.array() += params.margin;
    Grid grid;
    grid.origin = lo;
    grid.size = params.voxel_size;
    grid.dims = ((hi - lo) / params.voxel_size).array().ceil().cast<int>().cwiseMax(1);
    const double cells = static_cast<double>(grid.dims.x()) * grid.dims.y() * grid.dims.z();
    if (cells > static_cast<double>(params.max_cells)) {
        throw InvalidArgument(fmt::format(
            "verification: a {}x{}x{} grid exceeds max_cells ({}); use a larger voxel_size",
            grid.dims.x(), grid.dims.y(), grid.dims.z(), params.max_cells));
    }
    grid.cells.assign(static_cast<std::size_t>(cells), kUnknown);
    for (int a = 0; a < 3; ++a)
        grid.inside[a] = std::nextafter(static_cast<double>(grid.dims[a]), 0.0);
    ReadCells read{grid.Cell(result.samples.front()), grid.Cell(result.samples.front())};
    for (const auto& sample : result.samples) {
        const Eigen::Vector3i c = grid.Cell(sample);
        read.lo = read.lo.cwiseMin(c);
        read.hi = read.hi.cwiseMax(c);
    }
    read.lo.array() -= 1;
    read.hi.array() += 1;
    // A cell ends occupied when some ray ends in it, else free when some ray crosses it, whatever
    // the order of the rays: blocks of rays are cast into grids of their own, joined by taking
    // each cell's highest state (unknown < free < occupied).
    const std::size_t threads = static_cast<std::size_t>(ArenaThreadCount(params.num_threads));
    const std::size_t blocks = scan.size() >= 4096 ? threads : 1;
    std::vector<Grid> grids(blocks - 1, grid);
    ParallelFor(
        blocks, params.num_threads,
        [&](std::size_t b) {
            Grid& g = b == 0 ? grid : grids[b - 1];
            const std::size_t end = scan.size() * (b + 1) / blocks;
            for (std::size_t i = scan.size() * b / blocks; i < end; ++i) {
                if (scan.points[i].allFinite()) CastRay(g, sensor_origin, scan.points[i], read);
            }
        },
        1);
    for (const Grid& g : grids) {
        for (std::size_t c = 0; c < grid.cells.size(); ++c)
            grid.cells[c] = std::max(grid.cells[c], g.cells[c]);
    }

    result.states.resize(result.samples.size());
    std::size_t counts[3] = {0, 0, 0};
    const int r = params.tolerance_voxels;
    for (std::size_t i = 0; i < result.samples.size(); ++i) {
        const Eigen::Vector3i c = grid.Cell(result.samples[i]);
        bool occupied_near = false;
        for (int dz = -r; dz <= r && !occupied_near; ++dz) {
            for (int dy = -r; dy <= r && !occupied_near; ++dy) {
                for (int dx = -r; dx <= r && !occupied_near; ++dx) {
                    const Eigen::Vector3i n = c + Eigen::Vector3i(dx, dy, dz);
                    occupied_near = grid.Inside(n) && grid.cells[grid.Index(n)] == kOccupied;
                }
            }
        }
        SurfaceState state = SurfaceState::kOccluded;
        if (occupied_near) {
            state = SurfaceState::kVerified;
        } else if (grid.Inside(c) && grid.cells[grid.Index(c)] == kFree) {
            state = SurfaceState::kInvalid;
        }
        result.states[i] = state;
        ++counts[static_cast<int>(state)];
    }
    const float n = static_cast<float>(result.samples.size());
    result.verified_ratio = counts[0] / n;
    result.occluded_ratio = counts[1] / n;
    result.invalid_ratio = counts[2] / n;
    result.accepted = result.invalid_ratio <= params.max_invalid_ratio;
    return result;
}

}  // namespace multicue

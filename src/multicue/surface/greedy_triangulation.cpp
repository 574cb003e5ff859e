#include "multicue/surface/greedy_triangulation.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <unordered_map>
#include <unordered_set>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/core/parallel.hpp"
#include "multicue/search/kdtree.hpp"
#include "multicue/surface/normals.hpp"
#include "multicue/surface/triangulation_engine.hpp"

namespace multicue {
namespace {

using detail::MeshState;

float Rad(float deg) { return deg * std::numbers::pi_v<float> / 180.0f; }

detail::GrowSettings Settings(const GreedyTriangulationParams& p) {
    detail::GrowSettings s;
    s.search_radius = p.search_radius;
    s.mu = p.mu;
    s.max_neighbors = p.max_neighbors;
    s.cos_min_angle = std::cos(Rad(p.min_angle_deg));
    s.cos_max_angle = std::cos(Rad(p.max_angle_deg));
    s.max_angle = Rad(p.max_angle_deg);
    s.cos_surface = std::cos(Rad(p.max_surface_angle_deg));
    return s;
}

/// Normals of the finite points of `cloud` (all finite): the input ones where defined, PCA
/// (k nearest, oriented towards the viewpoint) elsewhere. NaN where neither exists.
std::vector<Eigen::Vector3f> PointNormals(const PointCloud& cloud,
                                          const GreedyTriangulationParams& params, int threads) {
    std::vector<Eigen::Vector3f> normals(cloud.size(), Eigen::Vector3f::Constant(NAN));
    bool missing = !cloud.HasNormals();
    for (std::size_t i = 0; i < cloud.size() && !missing; ++i) {
        if (cloud.normals[i].allFinite() && cloud.normals[i].squaredNorm() > 0.0f)
            normals[i] = cloud.normals[i].normalized();
        else
            missing = true;
    }
    if (!missing || cloud.size() < 3) return normals;
    const KdTree tree(cloud);
    NormalParams np;
    np.k = params.normal_k;
    np.viewpoint = params.viewpoint.value_or(cloud.sensor_origin);
    np.num_threads = threads;
    const NormalsResult pca = EstimateNormals(cloud, tree, np);
    for (std::size_t i = 0; i < cloud.size(); ++i)
        if (!normals[i].allFinite()) normals[i] = pca.normals[i];
    return normals;
}

/// Triangulates a cloud whose points are all finite.
TriangulationResult TriangulateFinite(const PointCloud& cloud,
                                      const GreedyTriangulationParams& params, int threads) {
    TriangulationResult result;
    const std::vector<Eigen::Vector3f> normals = PointNormals(cloud, params, threads);
    MeshState m;
    m.pos.reserve(cloud.size());
    Indices working;
    working.reserve(cloud.size());
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        m.AddVertex(cloud.points[i], normals[i].allFinite() ? normals[i] : Eigen::Vector3f::Zero());
        if (normals[i].allFinite()) working.push_back(static_cast<Index>(i));
    }
    const detail::GrowStats stats = detail::Grow(m, working, {}, Settings(params), 0);
    result.seeds = stats.seeds;
    result.gap_triangles = stats.gap_triangles;
    result.hole_triangles = detail::FillHoles(m, working, params.max_hole_edges);

    TriangleMesh& mesh = result.mesh;
    mesh.vertices = cloud.points;
    mesh.vertex_normals.resize(cloud.size());
    for (std::size_t i = 0; i < cloud.size(); ++i)
        mesh.vertex_normals[i] = normals[i].allFinite() ? m.nrm[i] : Eigen::Vector3f::Zero();
    if (cloud.HasColors()) mesh.vertex_colors = cloud.colors;
    if (cloud.HasLabels()) mesh.vertex_labels = cloud.labels;
    mesh.triangles = std::move(m.tris);
    for (std::size_t i = 0; i < cloud.size(); ++i) result.unconnected += !m.HasTriangles(i);
    return result;
}

}  // namespace

void GreedyTriangulationParams::Validate() const {
    const GreedyTriangulationParams& p = *this;
    if (!(p.search_radius > 0.0f) || !std::isfinite(p.search_radius))
        throw InvalidArgument(fmt::format("search_radius must be > 0, got {}", p.search_radius));
    if (!(p.mu > 0.0f) || !std::isfinite(p.mu))
        throw InvalidArgument(fmt::format("mu must be > 0, got {}", p.mu));
    if (p.max_neighbors < 3)
        throw InvalidArgument(fmt::format("max_neighbors must be >= 3, got {}", p.max_neighbors));
    if (!(p.min_angle_deg >= 0.0f && p.min_angle_deg < 60.0f))
        throw InvalidArgument(
            fmt::format("min_angle must be in [0, 60) degrees, got {}", p.min_angle_deg));
    if (!(p.max_angle_deg > 60.0f && p.max_angle_deg < 180.0f))
        throw InvalidArgument(
            fmt::format("max_angle must be in (60, 180) degrees, got {}", p.max_angle_deg));
    if (!(p.max_surface_angle_deg > 0.0f && p.max_surface_angle_deg < 90.0f)) {
        throw InvalidArgument(fmt::format("max_surface_angle must be in (0, 90) degrees, got {}",
                                          p.max_surface_angle_deg));
    }
    if (p.normal_k < 3)
        throw InvalidArgument(fmt::format("normal_k must be >= 3, got {}", p.normal_k));
    if (p.max_hole_edges < 0)
        throw InvalidArgument(fmt::format("max_hole_edges must be >= 0, got {}", p.max_hole_edges));
    if (!(p.overlap_distance >= 0.0f) || !std::isfinite(p.overlap_distance)) {
        throw InvalidArgument(fmt::format(
            "overlap_distance must be >= 0 (0 = search_radius / 5), got {}", p.overlap_distance));
    }
    ResolveThreadCount(p.num_threads);
}

TriangulationResult GreedyProjectionTriangulation(const PointCloud& cloud,
                                                  const GreedyTriangulationParams& params) {
    params.Validate();
    cloud.Validate();
    if (params.per_label && !cloud.HasLabels() && !cloud.empty())
        throw InvalidArgument("per_label needs a cloud with labels");
    Indices finite;
    finite.reserve(cloud.size());
    for (std::size_t i = 0; i < cloud.size(); ++i)
        if (cloud.IsFinite(i)) finite.push_back(static_cast<Index>(i));
    if (finite.empty()) return {};

    std::vector<Indices> groups;
    if (params.per_label) {
        std::map<std::uint32_t, Indices> by_label;
        for (Index i : finite) by_label[cloud.labels[i]].push_back(i);
        for (auto& [label, idx] : by_label) groups.push_back(std::move(idx));
    } else {
        groups.push_back(std::move(finite));
    }
    std::vector<TriangulationResult> parts(groups.size());
    const int outer = groups.size() > 1 ? params.num_threads : 1;
    const int inner = groups.size() > 1 ? 1 : params.num_threads;
    ParallelFor(
        groups.size(), outer,
        [&](std::size_t g) {
            const PointCloud sub = SelectByIndex(cloud, groups[g]);
            parts[g] = TriangulateFinite(sub, params, inner);
            for (Index& s : parts[g].source) s = groups[g][s];
        },
        1);
    TriangulationResult result;
    for (std::size_t g = 0; g < parts.size(); ++g) {
        TriangulationResult& part = parts[g];
        result.mesh.Append(part.mesh);
        result.source.insert(result.source.end(), groups[g].begin(), groups[g].end());
        result.unconnected += part.unconnected;
        result.seeds += part.seeds;
        result.gap_triangles += part.gap_triangles;
        result.hole_triangles += part.hole_triangles;
    }
    return result;
}

// ------------------------------------------------------------------------ incremental meshing

struct IncrementalTriangulation::Impl {
    GreedyTriangulationParams params;
    MeshState state;
    TriangleMesh mesh;
    bool colors = false, labels = false, started = false;
    std::unordered_map<std::uint64_t, std::vector<std::uint32_t>> grid;

    std::uint64_t Key(const Eigen::Vector3i& c) const {
        auto u = [](int x) {
            return static_cast<std::uint64_t>(static_cast<std::uint32_t>(x)) & 0x1fffffu;
        };
        return (u(c.x()) << 42) | (u(c.y()) << 21) | u(c.z());
    }
    Eigen::Vector3i Cell(const Eigen::Vector3f& p) const {
        return (p / params.search_radius).array().floor().cast<int>();
    }
    void Insert(std::uint32_t v) { grid[Key(Cell(state.pos[v]))].push_back(v); }
    template <typename F>
    void ForNear(const Eigen::Vector3f& p, F&& f) const {
        const Eigen::Vector3i c = Cell(p);
        for (int dx = -1; dx <= 1; ++dx)
            for (int dy = -1; dy <= 1; ++dy)
                for (int dz = -1; dz <= 1; ++dz) {
                    const auto it = grid.find(Key(c + Eigen::Vector3i(dx, dy, dz)));
                    if (it == grid.end()) continue;
                    for (std::uint32_t v : it->second) f(v);
                }
    }

    /// Is q within `tol` of an existing triangle at one of its nearest old vertices, or of a
    /// vertex?
    bool OnSurface(const Eigen::Vector3f& q, float tol) const {
        std::uint32_t nearest[3] = {detail::kNone, detail::kNone, detail::kNone};
        float d[3] = {INFINITY, INFINITY, INFINITY};
        ForNear(q, [&](std::uint32_t v) {
            const float dv = (state.pos[v] - q).squaredNorm();
            for (int k = 0; k < 3; ++k) {
                if (dv < d[k]) {
                    for (int j = 2; j > k; --j) {
                        d[j] = d[j - 1];
                        nearest[j] = nearest[j - 1];
                    }
                    d[k] = dv;
                    nearest[k] = v;
                    break;
                }
            }
        });
        if (nearest[0] == detail::kNone) return false;
        if (d[0] <= tol * tol) return true;
        for (std::uint32_t v : nearest) {
            if (v == detail::kNone) continue;
            bool hit = false;
            state.ForEachFan(v, [&](std::uint32_t x, std::uint32_t y) {
                if (hit) return;
                const Eigen::Vector3f &a = state.pos[v], &b = state.pos[x], &c = state.pos[y];
                const Eigen::Vector3f n = (b - a).cross(c - a);
                const float area2 = n.squaredNorm();
                if (!(area2 > 0.0f)) return;
                const float dist = n.dot(q - a) / std::sqrt(area2);
                if (std::abs(dist) > tol) return;
                // Barycentric inside test of the projection.
                const float w0 = (b - q).cross(c - q).dot(n), w1 = (c - q).cross(a - q).dot(n),
                            w2 = (a - q).cross(b - q).dot(n);
                if (w0 >= 0.0f && w1 >= 0.0f && w2 >= 0.0f) hit = true;
            });
            if (hit) return true;
        }
        return false;
    }
};

IncrementalTriangulation::IncrementalTriangulation(const GreedyTriangulationParams& params)
    : impl_(std::make_unique<Impl>()) {
    params.Validate();
    impl_->params = params;
}

IncrementalTriangulation::IncrementalTriangulation(const TriangleMesh& mesh,
                                                   const GreedyTriangulationParams& params)
    : IncrementalTriangulation(params) {
    mesh.Validate();
    for (const auto& v : mesh.vertices) {
        if (!v.allFinite()) throw DataError("the existing mesh has a non-finite vertex");
    }
    Impl& s = *impl_;
    s.state = detail::StateFromMesh(mesh);
    s.mesh = mesh;
    s.mesh.vertex_normals = s.state.nrm;
    s.colors = mesh.HasVertexColors();
    s.labels = mesh.HasVertexLabels();
    s.started = !mesh.empty();
    for (std::uint32_t v = 0; v < s.state.size(); ++v) s.Insert(v);
}

IncrementalTriangulation::~IncrementalTriangulation() = default;
IncrementalTriangulation::IncrementalTriangulation(IncrementalTriangulation&&) noexcept = default;
IncrementalTriangulation& IncrementalTriangulation::operator=(IncrementalTriangulation&&) noexcept =
    default;

const TriangleMesh& IncrementalTriangulation::mesh() const { return impl_->mesh; }

IncrementalTriangulation::AddResult IncrementalTriangulation::Add(const PointCloud& scan) {
    scan.Validate();
    Impl& s = *impl_;
    AddResult result;
    Indices finite;
    for (std::size_t i = 0; i < scan.size(); ++i)
        if (scan.IsFinite(i)) finite.push_back(static_cast<Index>(i));
    if (finite.empty()) return result;
    const PointCloud cloud = SelectByIndex(scan, finite);
    if (!s.started) {
        s.colors = cloud.HasColors();
        s.labels = cloud.HasLabels();
        s.started = true;
    }
    const std::vector<Eigen::Vector3f> normals =
        PointNormals(cloud, s.params, s.params.num_threads);
    const float tol =
        s.params.overlap_distance > 0.0f ? s.params.overlap_distance : s.params.search_radius / 5;

    // Points on the existing surface are dropped; the rest become vertices.
    const auto old_count = static_cast<std::uint32_t>(s.state.size());
    const std::size_t old_tris = s.state.tris.size();
    Indices working, first;
    std::unordered_set<std::uint32_t> old_near;
    const float r2 = s.params.search_radius * s.params.search_radius;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        if (!normals[i].allFinite()) continue;
        if (s.OnSurface(cloud.points[i], tol)) {
            ++result.dropped_overlap;
            continue;
        }
        s.ForNear(cloud.points[i], [&](std::uint32_t v) {
            if (v < old_count && (s.state.pos[v] - cloud.points[i]).squaredNorm() <= r2)
                old_near.insert(v);
        });
        const auto v = static_cast<std::uint32_t>(s.state.size());
        s.state.AddVertex(cloud.points[i], normals[i]);
        working.push_back(v);
        s.mesh.vertices.push_back(cloud.points[i]);
        if (s.colors) s.mesh.vertex_colors.push_back(cloud.HasColors() ? cloud.colors[i] : Color{});
        if (s.labels) s.mesh.vertex_labels.push_back(cloud.HasLabels() ? cloud.labels[i] : 0u);
    }
    result.new_vertices = working.size();
    if (working.empty()) return result;
    Indices old(old_near.begin(), old_near.end());
    std::sort(old.begin(), old.end());
    for (std::uint32_t v : old) {
        if (s.state.HasTriangles(v)) {
            if (!s.state.IsInterior(v)) first.push_back(v);
        } else {
            s.state.processed[v] = 0;  // an old unconnected point gets another chance
        }
    }
    result.old_vertices_touched = old.size();
    working.insert(working.begin(), old.begin(), old.end());

    detail::Grow(s.state, working, first, Settings(s.params), 1);
    detail::FillHoles(s.state, working, s.params.max_hole_edges);
    for (std::uint32_t v : working)
        if (s.state.comp[v] != detail::kNone) s.state.comp[v] = 0;
    for (std::uint32_t v = old_count; v < s.state.size(); ++v) s.Insert(v);

    s.mesh.vertex_normals.resize(s.state.size());
    for (std::uint32_t v = old_count; v < s.state.size(); ++v)
        s.mesh.vertex_normals[v] = s.state.nrm[v];
    s.mesh.triangles.insert(s.mesh.triangles.end(),
                            s.state.tris.begin() + static_cast<std::ptrdiff_t>(old_tris),
                            s.state.tris.end());
    result.new_triangles = s.state.tris.size() - old_tris;
    return result;
}

std::size_t FillSmallHoles(TriangleMesh& mesh, const HoleFillingParams& params) {
    if (params.max_edges < 0)
        throw InvalidArgument(fmt::format("max_edges must be >= 0, got {}", params.max_edges));
    mesh.Validate();
    if (mesh.triangles.empty()) return 0;
    MeshState m = detail::StateFromMesh(mesh);
    Indices all(m.size());
    for (std::uint32_t i = 0; i < all.size(); ++i) all[i] = i;
    const std::size_t before = m.tris.size();
    const std::size_t added = detail::FillHoles(m, all, params.max_edges);
    mesh.triangles.insert(mesh.triangles.end(),
                          m.tris.begin() + static_cast<std::ptrdiff_t>(before), m.tris.end());
    return added;
}

}  // namespace multicue

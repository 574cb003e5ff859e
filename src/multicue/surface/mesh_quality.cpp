#include "multicue/surface/mesh_quality.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "multicue/core/disjoint_sets.hpp"
#include "multicue/core/exceptions.hpp"
#include "multicue/search/kdtree.hpp"

namespace multicue {
namespace {

/// Half-edge record: undirected key (low, high) and whether it runs low -> high.
struct HalfEdge {
    std::uint64_t key;
    bool forward;
    bool operator<(const HalfEdge& o) const {
        return key != o.key ? key < o.key : forward < o.forward;
    }
};

}  // namespace

MeshQuality EvaluateMesh(const TriangleMesh& mesh) {
    mesh.Validate();
    MeshQuality q;
    q.vertices = mesh.vertices.size();
    q.triangles = mesh.triangles.size();
    std::vector<std::uint8_t> used(q.vertices, 0);
    std::vector<HalfEdge> half;
    half.reserve(3 * q.triangles);
    for (const Triangle& t : mesh.triangles) {
        for (int k = 0; k < 3; ++k) used[t[k]] = 1;
        const Eigen::Vector3f a = mesh.vertices[t[1]] - mesh.vertices[t[0]];
        const Eigen::Vector3f b = mesh.vertices[t[2]] - mesh.vertices[t[0]];
        if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2] || !(a.cross(b).squaredNorm() > 0.0f)) {
            ++q.degenerate_triangles;
        }
        for (int k = 0; k < 3; ++k) {
            const std::uint32_t u = t[k], v = t[(k + 1) % 3];
            if (u == v) continue;
            const std::uint32_t lo = std::min(u, v), hi = std::max(u, v);
            half.push_back({(std::uint64_t{lo} << 32) | hi, u == lo});
        }
    }
    q.unreferenced_vertices = static_cast<std::size_t>(std::count(used.begin(), used.end(), 0));
    std::sort(half.begin(), half.end());
    detail::DisjointSets loops(q.vertices);  // boundary vertices joined along boundary edges
    std::vector<std::uint8_t> on_boundary(q.vertices, 0);
    for (std::size_t i = 0; i < half.size();) {
        std::size_t j = i;
        std::size_t fwd = 0;
        while (j < half.size() && half[j].key == half[i].key) fwd += half[j++].forward;
        const std::size_t count = j - i;
        ++q.edges;
        if (count == 1) {
            ++q.boundary_edges;
            const auto lo = static_cast<std::uint32_t>(half[i].key >> 32);
            const auto hi = static_cast<std::uint32_t>(half[i].key & 0xffffffffu);
            on_boundary[lo] = on_boundary[hi] = 1;
            loops.Unite(lo, hi);
        } else if (count == 2) {
            if (fwd != 1) ++q.inconsistent_edges;
        } else {
            ++q.non_manifold_edges;
        }
        i = j;
    }
    for (std::uint32_t v = 0; v < q.vertices; ++v)
        if (on_boundary[v] && loops.Find(v) == v) ++q.boundary_loops;
    return q;
}

MeshDistance DistanceToSurface(const TriangleMesh& mesh,
                               const std::function<float(const Eigen::Vector3f&)>& surface) {
    mesh.Validate();
    MeshDistance d;
    double sum = 0.0, sum2 = 0.0;
    auto add = [&](const Eigen::Vector3f& p) {
        const double e = std::abs(static_cast<double>(surface(p)));
        sum += e;
        sum2 += e * e;
        d.max = std::max(d.max, e);
        ++d.samples;
    };
    std::vector<std::uint8_t> used(mesh.vertices.size(), 0);
    for (const Triangle& t : mesh.triangles) {
        for (int k = 0; k < 3; ++k) used[t[k]] = 1;
        add((mesh.vertices[t[0]] + mesh.vertices[t[1]] + mesh.vertices[t[2]]) / 3.0f);
    }
    for (std::size_t v = 0; v < used.size(); ++v)
        if (used[v]) add(mesh.vertices[v]);
    if (d.samples > 0) {
        d.mean = sum / static_cast<double>(d.samples);
        d.rms = std::sqrt(sum2 / static_cast<double>(d.samples));
    }
    return d;
}

MeshDistance DistanceToCloud(const TriangleMesh& mesh, const PointCloud& reference) {
    if (!reference.HasFinite()) throw DataError("the reference cloud has no finite point");
    const KdTree tree(reference);
    return DistanceToSurface(mesh, [&](const Eigen::Vector3f& p) {
        Index i;
        float d2;
        tree.SearchNearest(p, i, d2);
        return std::sqrt(d2);
    });
}

}  // namespace multicue

#pragma once
/// \file Internal to the surface module: the growing mesh of the greedy projection triangulation
/// (vertices, oriented normals, triangles with per-vertex incidence lists) and the growth step
/// shared by the one-shot, per-label and incremental triangulation and by hole filling.

#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include <Eigen/Core>

#include "multicue/core/triangle_mesh.hpp"
#include "multicue/core/types.hpp"

namespace multicue::detail {

inline constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();

/// Vertices and triangles with incidence lists: corner k of triangle t is entry 3 t + k, and
/// next_corner links the corners of each vertex (head[v] is the first). Triangles are only ever
/// appended.
struct MeshState {
    std::vector<Eigen::Vector3f> pos;
    std::vector<Eigen::Vector3f> nrm;      ///< unit normals; oriented once `oriented` is set
    std::vector<Eigen::Vector3f> nrm_in;   ///< normals as given (for the final orientation vote)
    std::vector<std::uint8_t> oriented;    ///< orientation fixed by the front (or a seed)
    std::vector<std::uint8_t> processed;   ///< the vertex has been the source of a fan
    std::vector<std::uint32_t> comp;       ///< orientation component, kNone before orienting
    std::vector<std::int32_t> open_edges;  ///< edges at the vertex with a triangle on one side
    std::vector<Triangle> tris;
    std::vector<std::uint32_t> head;
    std::vector<std::uint32_t> next_corner;

    std::size_t size() const { return pos.size(); }
    void AddVertex(const Eigen::Vector3f& p, const Eigen::Vector3f& n);
    /// Appends triangle (a, b, c) and links its corners.
    void AddTriangle(std::uint32_t a, std::uint32_t b, std::uint32_t c);
    bool HasTriangles(std::uint32_t v) const { return head[v] != kNone; }
    /// True if some triangle holds the directed edge a -> b.
    bool HasDirected(std::uint32_t a, std::uint32_t b) const;
    /// Calls f(x, y) for every triangle (v, x, y) around v (rotated so that v comes first).
    template <typename F>
    void ForEachFan(std::uint32_t v, F&& f) const {
        for (std::uint32_t c = head[v]; c != kNone; c = next_corner[c]) {
            const Triangle& t = tris[c / 3];
            const std::uint32_t k = c % 3;
            f(t[(k + 1) % 3], t[(k + 2) % 3]);
        }
    }
    /// Every edge at v has a triangle on both sides (kept up to date by AddTriangle).
    bool IsInterior(std::uint32_t v) const { return head[v] != kNone && open_edges[v] <= 0; }
    /// Calls out(x) for every front edge v -> x and in(y) for every front edge y -> v (edges
    /// with a triangle on one side only). The twin of an edge at v is always in v's own fan.
    template <typename Out, typename In>
    void ForEachFrontEdge(std::uint32_t v, Out&& out, In&& in) const {
        std::uint32_t xs[48], ys[48];
        std::size_t n = 0;
        for (std::uint32_t c = head[v]; c != kNone && n < 48; c = next_corner[c], ++n) {
            const Triangle& t = tris[c / 3];
            xs[n] = t[(c % 3 + 1) % 3];
            ys[n] = t[(c % 3 + 2) % 3];
        }
        for (std::size_t i = 0; i < n; ++i) {
            bool twin_out = false, twin_in = false;
            for (std::size_t j = 0; j < n; ++j) {
                twin_out |= ys[j] == xs[i];
                twin_in |= xs[j] == ys[i];
            }
            if (!twin_out) out(xs[i]);
            if (!twin_in) in(ys[i]);
        }
    }
};

struct GrowSettings {
    float search_radius = 0.0f;
    float mu = 2.5f;
    int max_neighbors = 100;
    float cos_min_angle = 0.0f;  ///< cos(min_angle): a triangle angle's cosine must be <= it
    float cos_max_angle = 0.0f;  ///< cos(max_angle): a triangle angle's cosine must be >= it
    float max_angle = 0.0f;      ///< [rad], widest gap closed
    float cos_surface = 0.0f;    ///< cos(max_surface_angle)
};

struct GrowStats {
    std::size_t seeds = 0;
    std::size_t triangles = 0;
    std::size_t gap_triangles = 0;
};

/// Grows the mesh over the vertices `working` (all of them; an old vertex there keeps its
/// triangles and becomes a source again if it is on the boundary). `first` are processed before
/// any new seed (the old front, in incremental updates). Components whose normals disagree with
/// the given ones by majority are flipped, except those attached to a vertex with a component
/// below `first_new_comp` (existing mesh). Returns statistics.
GrowStats Grow(MeshState& mesh, const Indices& working, const Indices& first,
               const GrowSettings& settings, std::uint32_t first_new_comp);

/// Fills boundary loops of at most max_edges edges through the vertices `around` (see
/// FillSmallHoles). Returns the number of triangles added.
std::size_t FillHoles(MeshState& mesh, const Indices& around, int max_edges);

/// Builds the state from a mesh (normals from its vertex normals, or averaged from triangles
/// where it has none); every vertex is oriented and belongs to component 0.
MeshState StateFromMesh(const TriangleMesh& mesh);

}  // namespace multicue::detail

#pragma once
/// \file Greedy projection triangulation (GP3, thesis section 2.3.2) with per-label decoupled
/// meshes and incremental updates (section 4.1.1).
///
/// The mesh grows from seed points outwards. Each point p, taken in breadth-first order from the
/// advancing front, looks at its k nearest neighbours within r = mu * d0 (d0: distance to its
/// nearest neighbour; r at most search_radius), projects them onto its tangent plane (normal from
/// the input or by PCA, never from averaged triangle normals) and connects consecutive neighbours
/// of its local Delaunay fan (the neighbours whose bisectors bound p's Voronoi cell in that plane)
/// into triangles. A triangle is written only if
///   - its angles lie in [min_angle, max_angle] and its edges are at most search_radius long;
///   - the normals of its vertices differ by at most max_surface_angle from p's;
///   - it points to the same side as all three vertex normals (normals are oriented consistently
///     by propagation along the front, so adjacent triangles agree);
///   - none of its directed edges exists already: each edge then has at most one triangle per
///     direction, so no edge is non-manifold and adjacent triangles are never oriented
///     inconsistently, by construction;
///   - at each of its vertices it does not overlap the triangles already there (the angular
///     sectors around a vertex, the fringe point's front, stay disjoint) and its edges cross no
///     front edge of the neighbourhood (visibility).
/// Where two parts of the front meet in one point (Figure 2.10) that point has several gaps
/// between its triangles; every gap narrower than max_angle whose triangle passes the tests above
/// and holds no unconnected point is closed, so the fronts merge rather than leaving slivers.
/// Finally boundary loops of at most max_hole_edges edges are filled (FillSmallHoles).
/// Edges are written once and never deleted; the cost is linear in the number of points.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "multicue/core/point_cloud.hpp"
#include "multicue/core/triangle_mesh.hpp"

namespace multicue {

struct GreedyTriangulationParams {
    float search_radius = 0.0f;    ///< longest edge and largest neighbourhood [m]; must be > 0
    float mu = 2.5f;               ///< neighbourhood radius = mu * nearest-neighbour distance
    int max_neighbors = 100;       ///< neighbours looked at per point
    float min_angle_deg = 10.0f;   ///< smallest triangle angle [deg]
    float max_angle_deg = 120.0f;  ///< largest triangle angle [deg]
    float max_surface_angle_deg = 45.0f;  ///< largest angle between connected normals [deg]
    /// Neighbours for PCA normals of points without an input normal (NaN or no normals field).
    int normal_k = 20;
    /// Point the PCA normals and the mesh's outside face towards [m]; default: sensor_origin.
    std::optional<Eigen::Vector3f> viewpoint = std::nullopt;
    /// Boundary loops with at most this many edges are closed (0 = no hole filling).
    int max_hole_edges = 8;
    /// Group the points by the cloud's labels and triangulate every group on its own (in
    /// parallel), so that no triangle joins two labels.
    bool per_label = false;
    /// Incremental updates: a new point closer than this to an existing triangle (or vertex) is a
    /// repeated measurement of the existing surface and is dropped [m]; 0 = search_radius / 5.
    float overlap_distance = 0.0f;
    int num_threads = 0;  ///< 0 = all cores (used by per-label meshing and normal estimation)
    /// Throws InvalidArgument naming the first out-of-range field.
    void Validate() const;
    /// Its parameters once each: configuration key (the field's name), field, meaning. A
    /// visitor reads or records them (io::ConfigSection::operator(); ReadPerceiveParams).
    template <typename V>
    void VisitParams(V& v) {
        v("search_radius", search_radius, "longest edge and neighbourhood [m]");
        v("mu", mu, "neighbourhood / nearest distance");
        v("max_surface_angle_deg", max_surface_angle_deg,
          "largest angle between connected normals [deg]");
    }
};

struct TriangulationResult {
    /// Every finite input point is a vertex (in input order), with its oriented normal, colour
    /// and label when the input has them; unconnected points are vertices without triangles.
    TriangleMesh mesh;
    Indices source;                  ///< input index of every vertex
    std::size_t unconnected = 0;     ///< vertices without a triangle
    std::size_t seeds = 0;           ///< times the growth restarted from a new seed
    std::size_t gap_triangles = 0;   ///< triangles that closed gaps between touching fronts
    std::size_t hole_triangles = 0;  ///< triangles added by hole filling
};

/// Triangulates the finite points of `cloud` (NaN points are skipped). Throws InvalidArgument for
/// bad parameters or, with per_label, a cloud without labels. An empty cloud gives an empty mesh.
/// The result does not depend on num_threads.
TriangulationResult GreedyProjectionTriangulation(const PointCloud& cloud,
                                                  const GreedyTriangulationParams& params);

/// A mesh that grows scan by scan (section 4.1.1). Each Add() takes a new registered scan, drops
/// its points that lie on the existing surface (closer than overlap_distance to a triangle), and
/// triangulates the rest into the mesh: the existing boundary (the previous advancing front) is
/// the front that grows into the new area, so the new triangles join the old mesh without
/// changing any existing triangle or vertex. The work is proportional to the new points and the
/// old vertices near them, not to the size of the mesh.
class IncrementalTriangulation {
  public:
    explicit IncrementalTriangulation(const GreedyTriangulationParams& params);
    /// Continues from an existing mesh (e.g. read from a file). Its vertices need no normals: the
    /// normals of vertices without one come from their triangles. Throws DataError for an invalid
    /// mesh and InvalidArgument for bad parameters.
    IncrementalTriangulation(const TriangleMesh& mesh, const GreedyTriangulationParams& params);
    ~IncrementalTriangulation();
    IncrementalTriangulation(IncrementalTriangulation&&) noexcept;
    IncrementalTriangulation& operator=(IncrementalTriangulation&&) noexcept;

    struct AddResult {
        std::size_t new_vertices = 0;     ///< points of the scan added as vertices
        std::size_t dropped_overlap = 0;  ///< points dropped as already on the surface
        std::size_t new_triangles = 0;
        std::size_t old_vertices_touched = 0;  ///< existing vertices in the working set
    };
    /// Adds the finite points of `scan` (per_label is ignored here). An empty scan adds nothing.
    AddResult Add(const PointCloud& scan);

    /// The current mesh: old vertices and triangles first, in their original order.
    const TriangleMesh& mesh() const;

  private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

struct HoleFillingParams {
    int max_edges = 8;  ///< loops with more edges are left open
};

/// Closes boundary loops of at most max_edges edges by ear clipping (no new vertices), each new
/// triangle oriented like the triangles around the hole and never adding a second triangle to an
/// edge in the same direction. Loops whose triangles would face away from the surrounding mesh
/// (the outer rim of an open surface) are left open. Returns the number of triangles added.
std::size_t FillSmallHoles(TriangleMesh& mesh, const HoleFillingParams& params);

}  // namespace multicue

#pragma once
/// \file Quality measures of triangle meshes: topology (non-manifold edges, inconsistently
/// oriented neighbours, boundary loops) and distance to a reference surface or cloud.

#include <cstddef>
#include <functional>

#include <Eigen/Core>

#include "multicue/core/point_cloud.hpp"
#include "multicue/core/triangle_mesh.hpp"

namespace multicue {

struct MeshQuality {
    std::size_t vertices = 0;
    std::size_t triangles = 0;
    std::size_t unreferenced_vertices = 0;  ///< vertices in no triangle
    std::size_t degenerate_triangles = 0;   ///< a repeated vertex index or zero area
    std::size_t edges = 0;                  ///< distinct undirected edges
    std::size_t boundary_edges = 0;         ///< edges with one triangle
    std::size_t non_manifold_edges = 0;     ///< edges with more than two triangles
    /// Edges with exactly two triangles that traverse them in the same direction: the pair is
    /// oriented inconsistently (one of them is flipped).
    std::size_t inconsistent_edges = 0;
    /// Connected sets of boundary edges: the rim of each open surface plus one per hole.
    std::size_t boundary_loops = 0;
};

/// Counts the topological defects of `mesh`. Throws DataError for an invalid mesh.
MeshQuality EvaluateMesh(const TriangleMesh& mesh);

struct MeshDistance {
    std::size_t samples = 0;  ///< vertices in triangles and triangle centroids measured
    double mean = 0.0;        ///< [m]
    double rms = 0.0;         ///< [m]
    double max = 0.0;         ///< [m]
};

/// Distance from every referenced vertex and every triangle centroid to `surface` (a function
/// returning the unsigned distance of a point to the reference surface [m]).
MeshDistance DistanceToSurface(const TriangleMesh& mesh,
                               const std::function<float(const Eigen::Vector3f&)>& surface);

/// The same with the distance to the nearest point of `reference` (a dense sample of the
/// reference surface, e.g. the original scan). Throws DataError for an empty reference.
MeshDistance DistanceToCloud(const TriangleMesh& mesh, const PointCloud& reference);

}  // namespace multicue

#pragma once
/// \file Triangle mesh with optional per-vertex normals, colours and labels.

#include <cstddef>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "multicue/core/types.hpp"

namespace multicue {

/// Vertex indices of one triangle, counter-clockwise seen from the side its normal points to.
using Triangle = Eigen::Matrix<std::uint32_t, 3, 1>;

struct TriangleMesh {
    std::vector<Eigen::Vector3f> vertices;
    std::vector<Eigen::Vector3f> vertex_normals;  ///< empty or one per vertex
    std::vector<Color> vertex_colors;             ///< empty or one per vertex
    std::vector<std::uint32_t> vertex_labels;     ///< empty or one per vertex
    std::vector<Triangle> triangles;

    bool HasVertexNormals() const { return !vertex_normals.empty(); }
    bool HasVertexColors() const { return !vertex_colors.empty(); }
    bool HasVertexLabels() const { return !vertex_labels.empty(); }
    bool empty() const { return vertices.empty(); }

    /// Throws DataError if a per-vertex field has the wrong size or a triangle index is out of
    /// range.
    void Validate() const;
    /// Unit normal of every triangle (zero for degenerate triangles).
    std::vector<Eigen::Vector3f> ComputeTriangleNormals() const;
    /// Appends another mesh, offsetting its indices. Optional fields survive only if both have
    /// them.
    void Append(const TriangleMesh& other);
};

}  // namespace multicue

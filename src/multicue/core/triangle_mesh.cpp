#include "multicue/core/triangle_mesh.hpp"

#include <fmt/format.h>
#include <Eigen/Geometry>

#include "multicue/core/exceptions.hpp"

namespace multicue {

void TriangleMesh::Validate() const {
    const std::size_t n = vertices.size();
    auto check = [n](std::size_t size, const char* name) {
        if (size != 0 && size != n) {
            throw DataError(
                fmt::format("mesh field '{}' has {} entries for {} vertices", name, size, n));
        }
    };
    check(vertex_normals.size(), "vertex_normals");
    check(vertex_colors.size(), "vertex_colors");
    check(vertex_labels.size(), "vertex_labels");
    for (std::size_t t = 0; t < triangles.size(); ++t) {
        if (triangles[t].maxCoeff() >= n) {
            throw DataError(fmt::format("triangle {} refers to vertex {} of {}", t,
                                        triangles[t].maxCoeff(), n));
        }
    }
}

std::vector<Eigen::Vector3f> TriangleMesh::ComputeTriangleNormals() const {
    std::vector<Eigen::Vector3f> out(triangles.size(), Eigen::Vector3f::Zero());
    for (std::size_t t = 0; t < triangles.size(); ++t) {
        const auto& tri = triangles[t];
        const Eigen::Vector3f n =
            (vertices[tri[1]] - vertices[tri[0]]).cross(vertices[tri[2]] - vertices[tri[0]]);
        const float len = n.norm();
        if (len > 0.0f) out[t] = n / len;
    }
    return out;
}

void TriangleMesh::Append(const TriangleMesh& other) {
    const auto offset = static_cast<std::uint32_t>(vertices.size());
    const bool both_normals = (HasVertexNormals() || vertices.empty()) && other.HasVertexNormals();
    const bool both_colors = (HasVertexColors() || vertices.empty()) && other.HasVertexColors();
    const bool both_labels = (HasVertexLabels() || vertices.empty()) && other.HasVertexLabels();
    vertices.insert(vertices.end(), other.vertices.begin(), other.vertices.end());
    if (both_normals) {
        vertex_normals.insert(vertex_normals.end(), other.vertex_normals.begin(),
                              other.vertex_normals.end());
    } else {
        vertex_normals.clear();
    }
    if (both_colors) {
        vertex_colors.insert(vertex_colors.end(), other.vertex_colors.begin(),
                             other.vertex_colors.end());
    } else {
        vertex_colors.clear();
    }
    if (both_labels) {
        vertex_labels.insert(vertex_labels.end(), other.vertex_labels.begin(),
                             other.vertex_labels.end());
    } else {
        vertex_labels.clear();
    }
    for (const auto& t : other.triangles) {
        triangles.push_back(t + Triangle::Constant(offset));
    }
}

}  // namespace multicue

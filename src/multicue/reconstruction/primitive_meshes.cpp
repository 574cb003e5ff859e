// Triangle meshes of the primitive models (declared in primitive_models.hpp).

#include <array>
#include <cmath>
#include <numbers>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/reconstruction/primitive_models.hpp"

namespace multicue {

TriangleMesh BoxMesh(const BoxModel& box) {
    if (!box.center.allFinite() || !box.axes.allFinite() || !box.extents.allFinite() ||
        (box.extents.array() < 0.0f).any()) {
        throw InvalidArgument(fmt::format(
            "box must have a finite centre and axes and finite extents >= 0, got extents "
            "({}, {}, {})",
            box.extents.x(), box.extents.y(), box.extents.z()));
    }
    TriangleMesh mesh;
    // Vertex v has coordinate +half along axis k if bit k of v is set, else -half.
    mesh.vertices.resize(8);
    for (std::uint32_t v = 0; v < 8; ++v) {
        Eigen::Vector3f p = box.center;
        for (int k = 0; k < 3; ++k) {
            const float sign = ((v >> k) & 1u) != 0u ? 0.5f : -0.5f;
            p += sign * box.extents[k] * box.axes.col(k);
        }
        mesh.vertices[v] = p;
    }
    // Two triangles per face. For the face of axis k at side s, the corners in the order
    // (0,0) (1,0) (1,1) (0,1) over the bits of axes k+1 and k+2 turn counter-clockwise about +k
    // in a right-handed frame; the -k faces take them reversed.
    const bool right_handed = box.axes.col(0).cross(box.axes.col(1)).dot(box.axes.col(2)) >= 0.0f;
    for (std::uint32_t k = 0; k < 3; ++k) {
        const std::uint32_t b1 = 1u << ((k + 1) % 3), b2 = 1u << ((k + 2) % 3);
        for (std::uint32_t s = 0; s < 2; ++s) {
            const std::uint32_t base = s != 0u ? (1u << k) : 0u;
            std::array<std::uint32_t, 4> q{base, base | b1, base | b1 | b2, base | b2};
            if ((s != 0u) != right_handed) std::swap(q[1], q[3]);
            mesh.triangles.emplace_back(q[0], q[1], q[2]);
            mesh.triangles.emplace_back(q[0], q[2], q[3]);
        }
    }
    return mesh;
}

TriangleMesh CylinderMesh(const CylinderModel& cylinder, int segments) {
    if (segments < 3) {
        throw InvalidArgument(fmt::format("segments must be >= 3, got {}", segments));
    }
    if (!cylinder.center.allFinite() || !cylinder.axis.allFinite() ||
        !(cylinder.axis.norm() > 0.0f) || !std::isfinite(cylinder.radius) ||
        !std::isfinite(cylinder.height) || cylinder.radius < 0.0f || cylinder.height < 0.0f) {
        throw InvalidArgument(fmt::format(
            "cylinder must have a finite centre, a non-zero axis and finite radius and height "
            ">= 0, got radius {} height {}",
            cylinder.radius, cylinder.height));
    }
    const Eigen::Vector3f a = cylinder.axis.normalized();
    const Eigen::Vector3f u = a.unitOrthogonal();
    const Eigen::Vector3f v = a.cross(u);  // (u, v, a) right-handed: angles turn about +a
    const Eigen::Vector3f bottom = cylinder.center - 0.5f * cylinder.height * a;
    const Eigen::Vector3f top = cylinder.center + 0.5f * cylinder.height * a;
    const auto n = static_cast<std::uint32_t>(segments);
    TriangleMesh mesh;
    // Vertices: bottom ring 0..n-1, top ring n..2n-1, bottom centre 2n, top centre 2n+1.
    mesh.vertices.resize(2 * std::size_t{n} + 2);
    for (std::uint32_t k = 0; k < n; ++k) {
        const double angle = 2.0 * std::numbers::pi * k / n;
        const Eigen::Vector3f radial =
            static_cast<float>(std::cos(angle)) * u + static_cast<float>(std::sin(angle)) * v;
        mesh.vertices[k] = bottom + cylinder.radius * radial;
        mesh.vertices[n + k] = top + cylinder.radius * radial;
    }
    mesh.vertices[2 * n] = bottom;
    mesh.vertices[2 * n + 1] = top;
    mesh.triangles.reserve(4 * std::size_t{n});
    for (std::uint32_t k = 0; k < n; ++k) {
        const std::uint32_t k1 = (k + 1) % n;
        // Side: (b_k, b_k+1, t_k+1) has normal (tangent) x (tangent + h a) = h radial, outward.
        mesh.triangles.emplace_back(k, k1, n + k1);
        mesh.triangles.emplace_back(k, n + k1, n + k);
        mesh.triangles.emplace_back(2 * n + 1, n + k, n + k1);  // top cap, normal +a
        mesh.triangles.emplace_back(2 * n, k1, k);              // bottom cap, normal -a
    }
    return mesh;
}

}  // namespace multicue

#pragma once
// Synthetic surfaces for the feature tests: points on spheres, cylinders, planes and boxes with
// exact normals, optionally with Kinect-like depth noise (sigma = 1.4e-3 z^2 m along the ray
// from the sensor at the origin).

#include <cmath>
#include <cstdint>
#include <random>

#include "multicue/core/point_cloud.hpp"

namespace multicue::test {

/// Moves every point along its ray from the origin by N(0, 1.4e-3 z^2) [m].
inline void AddKinectNoise(PointCloud& cloud, std::uint32_t seed) {
    std::mt19937 rng(seed);
    std::normal_distribution<float> unit(0.0f, 1.0f);
    for (auto& p : cloud.points) {
        const float z = p.z();
        p += p.normalized() * (unit(rng) * 1.4e-3f * z * z);
    }
}

/// Points on a sphere of the given radius and centre, about `spacing` apart (Fibonacci lattice),
/// only those facing the sensor at the origin when `visible_only`. Exact outward normals.
inline PointCloud Sphere(float radius, const Eigen::Vector3f& centre, float spacing,
                         bool visible_only = false) {
    PointCloud c;
    const float area = 4.0f * static_cast<float>(M_PI) * radius * radius;
    const int n = std::max(50, static_cast<int>(area / (spacing * spacing)));
    const float golden = static_cast<float>(M_PI) * (3.0f - std::sqrt(5.0f));
    for (int i = 0; i < n; ++i) {
        const float y = 1.0f - 2.0f * (static_cast<float>(i) + 0.5f) / static_cast<float>(n);
        const float r = std::sqrt(std::max(0.0f, 1.0f - y * y));
        const Eigen::Vector3f d(std::cos(golden * i) * r, y, std::sin(golden * i) * r);
        const Eigen::Vector3f p = centre + radius * d;
        if (visible_only && d.dot(-p) <= 0.0f) continue;
        c.points.push_back(p);
        c.normals.push_back(d);
    }
    c.SetUnorganized();
    return c;
}

/// Points on the lateral surface of a cylinder along y through `centre`, grid spacing `spacing`.
inline PointCloud Cylinder(float radius, float height, const Eigen::Vector3f& centre, float spacing,
                           bool visible_only = false) {
    PointCloud c;
    const int around = std::max(12, static_cast<int>(2.0f * M_PI * radius / spacing));
    const int along = std::max(2, static_cast<int>(height / spacing));
    for (int j = 0; j <= along; ++j) {
        const float y = -0.5f * height + height * static_cast<float>(j) / static_cast<float>(along);
        for (int i = 0; i < around; ++i) {
            const float a = 2.0f * static_cast<float>(M_PI) * static_cast<float>(i) / around;
            const Eigen::Vector3f d(std::cos(a), 0.0f, std::sin(a));
            const Eigen::Vector3f p = centre + radius * d + Eigen::Vector3f(0.0f, y, 0.0f);
            if (visible_only && d.dot(-p) <= 0.0f) continue;
            c.points.push_back(p);
            c.normals.push_back(d);
        }
    }
    c.SetUnorganized();
    return c;
}

/// A square patch of the plane z = z0 (normal towards the origin), side `side`.
inline PointCloud Plane(float side, float z0, float spacing) {
    PointCloud c;
    const int n = static_cast<int>(side / spacing);
    for (int i = 0; i <= n; ++i) {
        for (int j = 0; j <= n; ++j) {
            c.points.emplace_back(-0.5f * side + i * spacing, -0.5f * side + j * spacing, z0);
            c.normals.emplace_back(0.0f, 0.0f, -1.0f);
        }
    }
    c.SetUnorganized();
    return c;
}

/// Two faces of a box meeting at a sharp edge along y: x in [-side, 0] at z = z0 and the face
/// x = 0 for z in [z0, z0 + side].
inline PointCloud Edge(float side, float z0, float spacing) {
    PointCloud c;
    const int n = static_cast<int>(side / spacing);
    for (int i = 0; i <= n; ++i) {
        for (int j = 0; j <= n; ++j) {
            const float y = -0.5f * side + j * spacing;
            c.points.emplace_back(-side + i * spacing, y, z0);
            c.normals.emplace_back(0.0f, 0.0f, -1.0f);
            if (i > 0) {
                c.points.emplace_back(0.0f, y, z0 + i * spacing);
                c.normals.emplace_back(-1.0f, 0.0f, 0.0f);
            }
        }
    }
    c.SetUnorganized();
    return c;
}

}  // namespace multicue::test

#pragma once
// Synthetic surfaces for the MLS and triangulation tests: evenly spread samples with a fixed seed.

#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>

#include "multicue/core/point_cloud.hpp"

namespace multicue::test {

/// n points on a sphere (Fibonacci spiral, even spacing), outward normals, optional radial noise.
inline PointCloud SampledSphere(std::size_t n, float radius, float noise = 0.0f,
                                std::uint32_t seed = 3) {
    std::mt19937 rng(seed);
    std::normal_distribution<float> g(0.0f, 1.0f);
    PointCloud c;
    // In double: the spiral angle grows to about 2.4 n radians.
    const double golden = std::numbers::pi * (3.0 - std::sqrt(5.0));
    for (std::size_t i = 0; i < n; ++i) {
        const double z = 1.0 - 2.0 * (static_cast<double>(i) + 0.5) / static_cast<double>(n);
        const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
        const double t = golden * static_cast<double>(i);
        const Eigen::Vector3f d =
            Eigen::Vector3d(r * std::cos(t), r * std::sin(t), z).cast<float>();
        c.points.push_back(d * (radius + noise * g(rng)));
        c.normals.push_back(d);
    }
    c.SetUnorganized();
    return c;
}

/// Jittered grid on the plane z = 0 over [0, nx*step) x [0, ny*step), normals +z.
inline PointCloud SampledPlane(int nx, int ny, float step, float jitter = 0.2f,
                               std::uint32_t seed = 5) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(-jitter * step, jitter * step);
    PointCloud c;
    for (int y = 0; y < ny; ++y) {
        for (int x = 0; x < nx; ++x) {
            c.points.emplace_back(static_cast<float>(x) * step + u(rng),
                                  static_cast<float>(y) * step + u(rng), 0.0f);
            c.normals.emplace_back(0.0f, 0.0f, 1.0f);
        }
    }
    c.SetUnorganized();
    return c;
}

/// Jittered samples of an open cylinder around the z axis, outward normals.
inline PointCloud SampledCylinder(int around, int along, float radius, float height,
                                  std::uint32_t seed = 7) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(-0.2f, 0.2f);
    PointCloud c;
    for (int j = 0; j < along; ++j) {
        for (int i = 0; i < around; ++i) {
            const float t = 2.0f * std::numbers::pi_v<float> * (static_cast<float>(i) + u(rng)) /
                            static_cast<float>(around);
            const float z = height * (static_cast<float>(j) + u(rng)) / static_cast<float>(along);
            c.points.emplace_back(radius * std::cos(t), radius * std::sin(t), z);
            c.normals.emplace_back(std::cos(t), std::sin(t), 0.0f);
        }
    }
    c.SetUnorganized();
    return c;
}

}  // namespace multicue::test

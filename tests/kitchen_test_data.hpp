#pragma once
// Small synthetic kitchens for the mapping tests: points with normals on a floor, a ceiling, two
// walls, a cupboard face with a door and a handle, and a worktop, in a world frame (z up) that
// can be rotated. No files and no simulator: every test builds what it needs in milliseconds.

#include <cmath>
#include <cstdint>
#include <random>

#include <Eigen/Geometry>

#include "multicue/core/point_cloud.hpp"

namespace multicue::test {

/// Adds a rectangle of points: origin o, edges e1 and e2, grid step, normal n (unit, towards the
/// viewer), colour c and grey-level noise. Noise on the position along n with sigma `noise`.
inline void AddPatch(PointCloud& cloud, const Eigen::Vector3f& o, const Eigen::Vector3f& e1,
                     const Eigen::Vector3f& e2, float step, const Eigen::Vector3f& n, Color c,
                     float noise, std::mt19937& rng) {
    std::normal_distribution<float> g(0.0f, 1.0f);
    const int n1 = std::max(1, static_cast<int>(e1.norm() / step));
    const int n2 = std::max(1, static_cast<int>(e2.norm() / step));
    for (int i = 0; i <= n1; ++i) {
        for (int j = 0; j <= n2; ++j) {
            const Eigen::Vector3f p = o + e1 * (static_cast<float>(i) / n1) +
                                      e2 * (static_cast<float>(j) / n2) + n * (noise * g(rng));
            cloud.points.push_back(p);
            cloud.normals.push_back(n);
            const auto jitter = [&](std::uint8_t v) {
                return static_cast<std::uint8_t>(std::clamp(v + 1.5f * g(rng), 0.0f, 255.0f));
            };
            cloud.colors.push_back(Color{jitter(c.r), jitter(c.g), jitter(c.b), 255});
        }
    }
}

/// A horizontal bar handle (box of points) centred at `c`, along x, standing out along -y.
inline void AddHandle(PointCloud& cloud, const Eigen::Vector3f& c, float length, std::mt19937& rng,
                      bool vertical = false) {
    const Eigen::Vector3f along = vertical ? Eigen::Vector3f::UnitZ() : Eigen::Vector3f::UnitX();
    const Eigen::Vector3f across = vertical ? Eigen::Vector3f::UnitX() : Eigen::Vector3f::UnitZ();
    const Color metal{180, 180, 190, 255};
    // Front face of the bar, 3.5 cm out of the door, and its two sides.
    AddPatch(cloud, c - along * (length / 2) - across * 0.006f - Eigen::Vector3f(0, 0.035f, 0),
             along * length, across * 0.012f, 0.003f, -Eigen::Vector3f::UnitY(), metal, 0.0f, rng);
    for (const float s : {-1.0f, 1.0f}) {
        AddPatch(
            cloud, c - along * (length / 2) + across * (0.006f * s) - Eigen::Vector3f(0, 0.035f, 0),
            along * length, Eigen::Vector3f(0, 0.012f, 0), 0.003f, across * s, metal, 0.0f, rng);
    }
}

/// A knob: a small square stud, 3 cm out of the door.
inline void AddKnob(PointCloud& cloud, const Eigen::Vector3f& c, std::mt19937& rng) {
    const Color metal{180, 180, 190, 255};
    AddPatch(cloud, c + Eigen::Vector3f(-0.012f, -0.03f, -0.012f), Eigen::Vector3f(0.024f, 0, 0),
             Eigen::Vector3f(0, 0, 0.024f), 0.003f, -Eigen::Vector3f::UnitY(), metal, 0.0f, rng);
    for (const float s : {-1.0f, 1.0f}) {
        AddPatch(cloud, c + Eigen::Vector3f(0.012f * s, -0.03f, -0.012f),
                 Eigen::Vector3f(0, 0.02f, 0), Eigen::Vector3f(0, 0, 0.024f), 0.003f,
                 Eigen::Vector3f(s, 0, 0), metal, 0.0f, rng);
    }
}

struct SyntheticKitchen {
    PointCloud cloud;
    Eigen::Vector3f door_min, door_max;  ///< the door's rectangle on the face plane y = face_y
    float face_y = 2.4f;
};

/// A 3 x 3 m room, 2.5 m high: floor, ceiling, back wall (y = 3), left wall (x = 0), a row of
/// cupboards whose face is the plane y = 2.4 (x 0.3 .. 2.7, z 0.1 .. 0.85), a worktop at 0.9 m,
/// one dark door (x 0.6 .. 1.1, z 0.15 .. 0.8) with a vertical handle near its right edge, and a
/// drawer (x 1.3 .. 2.0, z 0.6 .. 0.8) with a horizontal handle. Sensor at (1.5, 0.6, 1.4).
inline SyntheticKitchen MakeSyntheticKitchen(std::uint32_t seed = 1, float step = 0.02f,
                                             float noise = 0.002f) {
    std::mt19937 rng(seed);
    SyntheticKitchen k;
    PointCloud& c = k.cloud;
    const Color wall{225, 222, 215, 255}, floor{120, 110, 100, 255}, body{235, 235, 235, 255};
    AddPatch(c, {0, 0, 0}, {3, 0, 0}, {0, 3, 0}, step, Eigen::Vector3f::UnitZ(), floor, noise, rng);
    AddPatch(c, {0, 0, 2.5f}, {3, 0, 0}, {0, 3, 0}, step, -Eigen::Vector3f::UnitZ(),
             Color{245, 245, 245, 255}, noise, rng);
    AddPatch(c, {0, 3, 0}, {3, 0, 0}, {0, 0, 2.5f}, step, -Eigen::Vector3f::UnitY(), wall, noise,
             rng);
    AddPatch(c, {0, 0, 0}, {0, 3, 0}, {0, 0, 2.5f}, step, Eigen::Vector3f::UnitX(), wall, noise,
             rng);
    // Cupboard face pieces around the door and the drawer (the frame), then the fronts.
    const float y = k.face_y;
    const Eigen::Vector3f n = -Eigen::Vector3f::UnitY();
    AddPatch(c, {0.3f, y, 0.1f}, {0.3f, 0, 0}, {0, 0, 0.75f}, step / 2, n, body, noise, rng);
    AddPatch(c, {0.6f, y, 0.1f}, {0.5f, 0, 0}, {0, 0, 0.05f}, step / 2, n, body, noise, rng);
    AddPatch(c, {0.6f, y, 0.8f}, {0.5f, 0, 0}, {0, 0, 0.05f}, step / 2, n, body, noise, rng);
    AddPatch(c, {1.1f, y, 0.1f}, {0.2f, 0, 0}, {0, 0, 0.75f}, step / 2, n, body, noise, rng);
    AddPatch(c, {1.3f, y, 0.1f}, {0.7f, 0, 0}, {0, 0, 0.5f}, step / 2, n, body, noise, rng);
    AddPatch(c, {1.3f, y, 0.8f}, {0.7f, 0, 0}, {0, 0, 0.05f}, step / 2, n, body, noise, rng);
    AddPatch(c, {2.0f, y, 0.1f}, {0.7f, 0, 0}, {0, 0, 0.75f}, step / 2, n, body, noise, rng);
    k.door_min = {0.6f, y, 0.15f};
    k.door_max = {1.1f, y, 0.8f};
    AddPatch(c, {0.6f, y, 0.15f}, {0.5f, 0, 0}, {0, 0, 0.65f}, step / 2, n, Color{90, 60, 40, 255},
             noise, rng);
    AddPatch(c, {1.3f, y, 0.6f}, {0.7f, 0, 0}, {0, 0, 0.2f}, step / 2, n, Color{60, 90, 140, 255},
             noise, rng);
    AddHandle(c, {1.03f, y, 0.55f}, 0.16f, rng, true);
    AddHandle(c, {1.65f, y, 0.72f}, 0.2f, rng, false);
    // Worktop: top and front edge.
    AddPatch(c, {0.3f, y - 0.02f, 0.9f}, {2.4f, 0, 0}, {0, 0.62f, 0}, step,
             Eigen::Vector3f::UnitZ(), Color{70, 70, 75, 255}, noise, rng);
    c.width = static_cast<std::uint32_t>(c.size());
    c.height = 1;
    c.sensor_origin = Eigen::Vector3f(1.5f, 0.6f, 1.4f);
    return k;
}

/// Rotates a cloud (points, normals and sensor origin) about the origin.
inline void RotateCloud(PointCloud& c, const Eigen::Matrix3f& R) {
    for (auto& p : c.points) p = R * p;
    for (auto& n : c.normals) n = R * n;
    c.sensor_origin = R * c.sensor_origin;
}

}  // namespace multicue::test

#pragma once
// Synthetic scenes for the registration tests: surfaces sampled with Gaussian noise, fixed seeds,
// and helpers for known transforms and their errors.

#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>
#include <vector>

#include <Eigen/Geometry>

#include "multicue/core/point_cloud.hpp"

namespace multicue::test {

/// Samples an axis-aligned rectangle (a face of a box or a wall): `origin` + s * u + t * v with
/// s, t uniform in [0, 1), `n` points, Gaussian noise `sigma` along the face normal.
inline void SampleRectangle(std::vector<Eigen::Vector3f>& out, const Eigen::Vector3f& origin,
                            const Eigen::Vector3f& u, const Eigen::Vector3f& v, int n, float sigma,
                            std::mt19937& rng) {
    std::uniform_real_distribution<float> uni(0.0f, 1.0f);
    std::normal_distribution<float> noise(0.0f, sigma);
    const Eigen::Vector3f normal = u.cross(v).normalized();
    for (int i = 0; i < n; ++i) {
        out.push_back(origin + uni(rng) * u + uni(rng) * v + noise(rng) * normal);
    }
}

/// The five visible faces of a box standing on z = 0 (no bottom), points per square metre
/// `density`.
inline void SampleBox(std::vector<Eigen::Vector3f>& out, const Eigen::Vector3f& min,
                      const Eigen::Vector3f& size, float density, float sigma, std::mt19937& rng) {
    const Eigen::Vector3f x(size.x(), 0, 0), y(0, size.y(), 0), z(0, 0, size.z());
    auto n = [&](const Eigen::Vector3f& a, const Eigen::Vector3f& b) {
        return static_cast<int>(a.norm() * b.norm() * density);
    };
    SampleRectangle(out, min + z, x, y, n(x, y), sigma, rng);  // top
    SampleRectangle(out, min, x, z, n(x, z), sigma, rng);      // front
    SampleRectangle(out, min + y, x, z, n(x, z), sigma, rng);  // back
    SampleRectangle(out, min, y, z, n(y, z), sigma, rng);      // left
    SampleRectangle(out, min + x, y, z, n(y, z), sigma, rng);  // right
}

/// A table top (1.2 x 0.8 m at z = 0) with three boxes of different sizes and yaw-free poses:
/// every rigid motion is constrained.
inline PointCloud TableWithBoxes(float sigma, std::uint32_t seed, float density = 4000.0f) {
    std::mt19937 rng(seed);
    std::vector<Eigen::Vector3f> pts;
    SampleRectangle(pts, {-0.6f, -0.4f, 0.0f}, {1.2f, 0, 0}, {0, 0.8f, 0},
                    static_cast<int>(0.96f * density), sigma, rng);
    SampleBox(pts, {-0.4f, -0.2f, 0.0f}, {0.2f, 0.1f, 0.15f}, density, sigma, rng);
    SampleBox(pts, {0.1f, 0.0f, 0.0f}, {0.1f, 0.25f, 0.08f}, density, sigma, rng);
    SampleBox(pts, {0.2f, -0.3f, 0.0f}, {0.12f, 0.12f, 0.3f}, density, sigma, rng);
    PointCloud c(std::move(pts));
    c.sensor_origin = {0.0f, -1.0f, 1.0f};  // normals face up and towards -y
    return c;
}

/// A room corner: floor, two walls at right angles and a box, as a laser would see it.
inline PointCloud RoomCorner(float sigma, std::uint32_t seed, float density = 300.0f) {
    std::mt19937 rng(seed);
    std::vector<Eigen::Vector3f> pts;
    SampleRectangle(pts, {0, 0, 0}, {4.0f, 0, 0}, {0, 3.0f, 0}, static_cast<int>(12 * density),
                    sigma, rng);
    SampleRectangle(pts, {0, 0, 0}, {4.0f, 0, 0}, {0, 0, 2.5f}, static_cast<int>(10 * density),
                    sigma, rng);
    SampleRectangle(pts, {0, 0, 0}, {0, 3.0f, 0}, {0, 0, 2.5f}, static_cast<int>(7.5f * density),
                    sigma, rng);
    SampleBox(pts, {1.5f, 1.0f, 0.0f}, {0.8f, 0.5f, 0.9f}, density, sigma, rng);
    PointCloud c(std::move(pts));
    c.sensor_origin = {3.0f, 2.5f, 1.5f};
    return c;
}

/// One plane (z = 0), 2 x 2 m: every motion in the plane is unconstrained.
inline PointCloud SinglePlane(float sigma, std::uint32_t seed, int n = 4000) {
    std::mt19937 rng(seed);
    std::vector<Eigen::Vector3f> pts;
    SampleRectangle(pts, {-1, -1, 0}, {2, 0, 0}, {0, 2, 0}, n, sigma, rng);
    PointCloud c(std::move(pts));
    c.sensor_origin = {0, 0, 1.5f};
    return c;
}

/// A corridor along x: floor and two parallel walls; translation along x is unconstrained.
inline PointCloud Corridor(float sigma, std::uint32_t seed, int n = 2000) {
    std::mt19937 rng(seed);
    std::vector<Eigen::Vector3f> pts;
    SampleRectangle(pts, {-3, -1, 0}, {6, 0, 0}, {0, 2, 0}, n, sigma, rng);
    SampleRectangle(pts, {-3, -1, 0}, {6, 0, 0}, {0, 0, 2.5f}, n, sigma, rng);
    SampleRectangle(pts, {-3, 1, 0}, {6, 0, 0}, {0, 0, 2.5f}, n, sigma, rng);
    PointCloud c(std::move(pts));
    c.sensor_origin = {0, 0, 1.2f};
    return c;
}

/// A rigid transform of the given rotation (about a fixed oblique axis) and translation.
inline Eigen::Isometry3d MakeTransform(double angle_deg, const Eigen::Vector3d& t) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = Eigen::AngleAxisd(angle_deg * std::numbers::pi / 180.0,
                                   Eigen::Vector3d(0.3, -0.5, 0.8).normalized())
                     .toRotationMatrix();
    T.translation() = t;
    return T;
}

/// `cloud` with every point (and the sensor origin) moved by T.
inline PointCloud Transformed(const PointCloud& cloud, const Eigen::Isometry3d& T) {
    PointCloud out = cloud;
    const Eigen::Isometry3f Tf = T.cast<float>();
    for (auto& p : out.points) p = Tf * p;
    for (auto& n : out.normals) n = Tf.linear() * n;
    out.sensor_origin = Tf * cloud.sensor_origin;
    return out;
}

/// Rotation [deg] and translation [m] of A^-1 B.
inline double RotationErrorDeg(const Eigen::Isometry3d& A, const Eigen::Isometry3d& B) {
    const Eigen::Quaterniond q((A.inverse() * B).linear());
    return 2.0 * std::atan2(q.vec().norm(), std::abs(q.w())) * 180.0 / std::numbers::pi;
}
inline double TranslationError(const Eigen::Isometry3d& A, const Eigen::Isometry3d& B) {
    return (A.inverse() * B).translation().norm();
}

}  // namespace multicue::test

#pragma once
/// \file Internal to the surface module: neighbourhood moments and the PCA normal computed from
/// them, shared by the k-d tree and the organized normal estimators.

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace multicue::detail {

/// Moments of a point set about a reference point c (the query point): the count, the sum of
/// d = p - c and the upper triangle of the sum of d d^T. Summing offsets from a point of the
/// neighbourhood keeps the numbers small (of the order of the neighbourhood size), so the
/// covariance below loses no precision to large coordinates.
struct Moments {
    double n = 0.0;
    double sx = 0.0, sy = 0.0, sz = 0.0;
    double xx = 0.0, xy = 0.0, xz = 0.0, yy = 0.0, yz = 0.0, zz = 0.0;

    Moments& operator+=(const Moments& o) {
        n += o.n;
        sx += o.sx;
        sy += o.sy;
        sz += o.sz;
        xx += o.xx;
        xy += o.xy;
        xz += o.xz;
        yy += o.yy;
        yz += o.yz;
        zz += o.zz;
        return *this;
    }

    void Add(const Eigen::Vector3f& d) {
        const double x = d.x(), y = d.y(), z = d.z();
        n += 1.0;
        sx += x;
        sy += y;
        sz += z;
        xx += x * x;
        xy += x * y;
        xz += x * z;
        yy += y * y;
        yz += y * z;
        zz += z * z;
    }
};

/// Eigenvalues of the symmetric matrix `c` in ascending order, in closed form (the
/// trigonometric solution of the characteristic cubic, Smith 1961). In double precision the
/// smallest one, which carries the curvature, keeps an absolute error of about 1e-16 times the
/// largest.
inline Eigen::Vector3d SymmetricEigenvalues(const Eigen::Matrix3d& c) {
    const double off = c(0, 1) * c(0, 1) + c(0, 2) * c(0, 2) + c(1, 2) * c(1, 2);
    const double mean = c.trace() / 3.0;
    const double a = c(0, 0) - mean, b = c(1, 1) - mean, d = c(2, 2) - mean;
    const double p = std::sqrt((a * a + b * b + d * d + 2.0 * off) / 6.0);
    if (!(p > 0.0)) return Eigen::Vector3d::Constant(mean);  // a multiple of the identity
    // det((C - mean I) / p) / 2 = cos(3 phi)
    const double half_det =
        (a * (b * d - c(1, 2) * c(1, 2)) - c(0, 1) * (c(0, 1) * d - c(1, 2) * c(0, 2)) +
         c(0, 2) * (c(0, 1) * c(1, 2) - b * c(0, 2))) /
        (2.0 * p * p * p);
    // With phi = acos(half_det) / 3 in [0, pi / 3], the eigenvalues are mean + 2p cos(phi) and
    // mean + 2p cos(phi +- 2 pi / 3); cos(phi + 2 pi / 3) = -(cos(phi) + sqrt(3) sin(phi)) / 2
    // saves a second cosine.
    const double cos_phi = std::cos(std::acos(std::clamp(half_det, -1.0, 1.0)) / 3.0);
    const double sin_phi = std::sqrt(std::max(0.0, 1.0 - cos_phi * cos_phi));
    constexpr double kSqrt3 = 1.7320508075688772935;
    const double largest = mean + 2.0 * p * cos_phi;
    const double smallest = mean - p * (cos_phi + kSqrt3 * sin_phi);
    return {smallest, 3.0 * mean - largest - smallest, largest};
}

/// Unit eigenvector of the symmetric matrix `c` for its eigenvalue `lambda`: the null space of
/// C - lambda I, given by the largest cross product of two of its rows. Where that matrix has
/// rank 1 (lambda is a double eigenvalue, e.g. points along a line) every vector orthogonal to
/// its largest row qualifies, and one of those is returned.
inline Eigen::Vector3d SymmetricEigenvector(const Eigen::Matrix3d& c, double lambda) {
    const Eigen::Matrix3d m = c - lambda * Eigen::Matrix3d::Identity();
    const Eigen::Vector3d r0 = m.row(0), r1 = m.row(1), r2 = m.row(2);
    const Eigen::Vector3d c01 = r0.cross(r1), c02 = r0.cross(r2), c12 = r1.cross(r2);
    const double n01 = c01.squaredNorm(), n02 = c02.squaredNorm(), n12 = c12.squaredNorm();
    const double rows = std::max({r0.squaredNorm(), r1.squaredNorm(), r2.squaredNorm()});
    if (std::max({n01, n02, n12}) > 1e-20 * rows * rows) {
        if (n01 >= n02 && n01 >= n12) return c01 / std::sqrt(n01);
        return n02 >= n12 ? c02 / std::sqrt(n02) : c12 / std::sqrt(n12);
    }
    // Rank 1 (or 0): any unit vector orthogonal to the largest row.
    const Eigen::Vector3d r = r0.squaredNorm() == rows ? r0 : (r1.squaredNorm() == rows ? r1 : r2);
    if (!(rows > 0.0)) return Eigen::Vector3d::UnitZ();
    return r.unitOrthogonal();
}

/// The same in float, for a few dozen offsets of a few centimetres (k-NN neighbourhoods, image
/// windows): float sums are exact enough there (relative rounding 1e-7 of terms of at most
/// r^2) and cheaper.
struct FloatMoments {
    float n = 0.0f;
    float sx = 0.0f, sy = 0.0f, sz = 0.0f;
    float xx = 0.0f, xy = 0.0f, xz = 0.0f, yy = 0.0f, yz = 0.0f, zz = 0.0f;

    void Add(const Eigen::Vector3f& d) { AddWeighted(d, 1.0f); }
    void AddWeighted(const Eigen::Vector3f& d, float w) {
        const float wx = w * d.x(), wy = w * d.y(), wz = w * d.z();
        n += w;
        sx += wx;
        sy += wy;
        sz += wz;
        xx += wx * d.x();
        xy += wx * d.y();
        xz += wx * d.z();
        yy += wy * d.y();
        yz += wy * d.z();
        zz += wz * d.z();
    }
    Moments ToDouble() const { return {n, sx, sy, sz, xx, xy, xz, yy, yz, zz}; }
};

/// Unit normal (unoriented) and surface variation of the neighbourhood described by `m`.
/// Returns false, leaving the outputs untouched, for fewer than 3 points or coincident points.
inline bool NormalFromMoments(const Moments& m, Eigen::Vector3f& normal, float& curvature) {
    if (m.n < 3.0) return false;
    const double inv = 1.0 / m.n;
    const double mx = m.sx * inv, my = m.sy * inv, mz = m.sz * inv;
    // Covariance about the neighbourhood mean: E[d d^T] - E[d] E[d]^T.
    Eigen::Matrix3d c;
    c(0, 0) = m.xx * inv - mx * mx;
    c(1, 0) = m.xy * inv - mx * my;
    c(2, 0) = m.xz * inv - mx * mz;
    c(1, 1) = m.yy * inv - my * my;
    c(2, 1) = m.yz * inv - my * mz;
    c(2, 2) = m.zz * inv - mz * mz;
    c(0, 1) = c(1, 0);
    c(0, 2) = c(2, 0);
    c(1, 2) = c(2, 1);
    if (!(c.trace() > 0.0)) return false;  // all points coincide (or a NaN crept in)
    // Rounding can push the smallest eigenvalue slightly below zero.
    const Eigen::Vector3d l = SymmetricEigenvalues(c).cwiseMax(0.0);
    const double sum = l.sum();
    if (!(sum > 0.0)) return false;
    normal = SymmetricEigenvector(c, l(0)).cast<float>();
    curvature = static_cast<float>(l(0) / sum);
    return normal.allFinite();
}

/// Flips `normal` if needed so that it points towards `viewpoint` from `p`.
inline void OrientTowards(Eigen::Vector3f& normal, const Eigen::Vector3f& p,
                          const Eigen::Vector3f& viewpoint) {
    if (normal.dot(viewpoint - p) < 0.0f) normal = -normal;
}

inline constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

/// condition ? a : b without a branch (compilers branch on float selects in loops, and these
/// conditions are unpredictable).
inline float Select(bool condition, float a, float b) {
    const std::uint32_t mask = 0u - static_cast<std::uint32_t>(condition);
    return std::bit_cast<float>((std::bit_cast<std::uint32_t>(a) & mask) |
                                (std::bit_cast<std::uint32_t>(b) & ~mask));
}

/// 1 if value <= limit, else 0 (both finite, or value infinite), computed from the sign bit of
/// limit - value. Compilers turn `value <= limit ? 1.0f : 0.0f` into a branch when the weight
/// multiplies other terms, and in the loops using this it mispredicts about half the time.
inline float WeightIfAtMost(float value, float limit) {
    const auto sign = static_cast<std::int32_t>(std::bit_cast<std::uint32_t>(limit - value)) >> 31;
    return std::bit_cast<float>(0x3f800000u & ~static_cast<std::uint32_t>(sign));
}

}  // namespace multicue::detail

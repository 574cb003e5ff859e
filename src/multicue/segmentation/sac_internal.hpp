#pragma once
/// \file Helpers shared by the sample-consensus models (moments, bases, parameter checks, a small
/// Levenberg-Marquardt solver). Internal to the segmentation module, not part of its API.

#include <algorithm>
#include <cmath>
#include <span>
#include <utility>

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include "multicue/core/point_cloud.hpp"
#include "multicue/core/types.hpp"
#include "multicue/segmentation/sample_consensus.hpp"

namespace multicue::sac_internal {

/// Mean and covariance (divided by n) of the points `idx`, accumulated in double around the first
/// point so that clouds far from the origin keep their precision.
struct Moments {
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
};
Moments ComputeMoments(const PointCloud& cloud, std::span<const Index> idx);

/// Unit vectors u, v such that (u, v, a) is orthonormal, for a unit vector a. A deterministic
/// function of a, so a linearisation and the update that follows it use the same basis.
void OrthonormalBasis(const Eigen::Vector3d& a, Eigen::Vector3d& u, Eigen::Vector3d& v);

/// Unit-length copy of a constraint axis; throws InvalidArgument naming `what` unless the axis is
/// finite and non-zero.
Eigen::Vector3f NormalizedAxis(const Eigen::Vector3f& axis, const char* what);
/// Throws InvalidArgument naming `what` unless max_angle is in [0, pi/2].
void ValidateMaxAngle(float max_angle, const char* what);
/// Throws InvalidArgument naming `what` unless 0 <= min_radius <= max_radius (max may be inf).
void ValidateRadiusLimits(float min_radius, float max_radius, const char* what);

/// The midpoint of the closest approach of the lines p1 + s n1 and p2 + t n2 (unit directions, not
/// parallel: the caller checks that 1 - (n1 . n2)^2 is well above 0). Samples of oriented points
/// meet there: on a cylinder's axis, at a sphere's centre.
inline Eigen::Vector3d NormalLinesMidpoint(const Eigen::Vector3d& p1, const Eigen::Vector3d& n1,
                                           const Eigen::Vector3d& p2, const Eigen::Vector3d& n2) {
    const Eigen::Vector3d w0 = p1 - p2;
    const double b = n1.dot(n2);
    const double d = n1.dot(w0);
    const double e = n2.dot(w0);
    const double denom = 1.0 - b * b;
    const double s1 = (b * e - d) / denom;
    const double t2 = (e - b * d) / denom;
    return 0.5 * ((p1 + s1 * n1) + (p2 + t2 * n2));
}

/// True if r is finite and in [min_radius, max_radius].
inline bool RadiusAccepted(double r, float min_radius, float max_radius) {
    return std::isfinite(r) && r >= min_radius && r <= max_radius;
}

/// acos(x) for x in [0, 1]: sqrt(1 - x) times a degree-7 polynomial (Abramowitz and Stegun
/// 4.4.46; within 1e-7 rad of acos, a float's rounding). Consensus scoring takes the normal
/// angles of millions of points per frame; this is a third cheaper than glibc's acosf there.
inline float AcosUnit(float x) {
    const double t = static_cast<double>(x);
    const double p =
        1.5707963050 +
        t * (-0.2145988016 +
             t * (0.0889789874 +
                  t * (-0.0501743046 +
                       t * (0.0308918810 +
                            t * (-0.0170881256 + t * (0.0066700901 + t * -0.0012624911))))));
    return static_cast<float>(std::sqrt(1.0 - t) * p);
}

/// Sign-free angle between two unit vectors, in [0, pi/2] [rad].
inline float UnsignedAngle(const Eigen::Vector3f& a, const Eigen::Vector3f& b) {
    return AcosUnit(std::min(1.0f, std::abs(a.dot(b))));
}

/// `v` with the sign that makes its largest-magnitude component positive: a deterministic
/// orientation for directions that have no natural one.
Eigen::Vector3f CanonicalDirection(const Eigen::Vector3f& v);

/// Copies the outcome fields of an engine result into a typed fit.
template <typename Fit>
void CopyOutcome(SacResult& r, Fit& fit) {
    fit.found = r.found;
    fit.inliers = std::move(r.inliers);
    fit.iterations = r.iterations;
    fit.converged = r.converged;
    fit.rmse = r.rmse;
}

/// Levenberg-Marquardt on a local parameterisation with P parameters.
/// `linearize(x, JtJ, Jtr)` returns the sum of squared residuals at x and fills the normal
/// equations; `update(x, delta)` returns x moved by delta. Returns false if the start is not
/// finite; otherwise x is the last accepted state (never worse than the start).
template <int P, typename State, typename Linearize, typename Update>
bool LevenbergMarquardt(State& x, Linearize&& linearize, Update&& update, int max_iterations = 50) {
    using Mat = Eigen::Matrix<double, P, P>;
    using Vec = Eigen::Matrix<double, P, 1>;
    Mat jtj;
    Vec jtr;
    double cost = linearize(x, jtj, jtr);
    if (!std::isfinite(cost)) return false;
    double lambda = 1e-3;
    Mat cand_jtj;
    Vec cand_jtr;
    for (int it = 0; it < max_iterations; ++it) {
        bool accepted = false;
        while (lambda < 1e12) {
            Mat a = jtj;
            a.diagonal() += lambda * (jtj.diagonal().array() + 1e-12).matrix();
            const Vec delta = a.ldlt().solve(-jtr);
            if (!delta.allFinite()) {
                lambda *= 10.0;
                continue;
            }
            State cand = update(x, delta);
            const double cand_cost = linearize(cand, cand_jtj, cand_jtr);
            if (std::isfinite(cand_cost) && cand_cost < cost) {
                const bool tiny = cost - cand_cost <= 1e-12 * cost;
                x = std::move(cand);
                cost = cand_cost;
                jtj = cand_jtj;
                jtr = cand_jtr;
                lambda = std::max(lambda * 0.1, 1e-12);
                accepted = true;
                if (tiny) return true;
                break;
            }
            lambda *= 10.0;
        }
        if (!accepted) return true;  // no step lowers the cost: a minimum
    }
    return true;
}

}  // namespace multicue::sac_internal

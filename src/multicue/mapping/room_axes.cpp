#include "multicue/mapping/room_axes.hpp"

#include <cmath>
#include <random>

#include <fmt/format.h>
#include <Eigen/SVD>

#include "multicue/core/exceptions.hpp"

namespace multicue::mapping {
namespace {

constexpr float kDegToRad = 0.017453292519943295f;

/// Normals within `cos_t` of an axis of R (either sign).
std::size_t Score(const std::vector<Eigen::Vector3f>& n, const Eigen::Matrix3f& R, float cos_t) {
    std::size_t count = 0;
    for (const auto& v : n) {
        const Eigen::Vector3f c = (R.transpose() * v).cwiseAbs();
        count += c.maxCoeff() >= cos_t;
    }
    return count;
}

/// The rotation that best maps each inlier's nearest signed axis onto it (Procrustes).
Eigen::Matrix3f Refine(const std::vector<Eigen::Vector3f>& n, const Eigen::Matrix3f& R,
                       float cos_t) {
    Eigen::Matrix3f M = Eigen::Matrix3f::Zero();
    for (const auto& v : n) {
        const Eigen::Vector3f c = R.transpose() * v;
        int k = 0;
        c.cwiseAbs().maxCoeff(&k);
        if (std::abs(c[k]) < cos_t) continue;
        Eigen::Vector3f e = Eigen::Vector3f::Zero();
        e[k] = c[k] > 0 ? 1.0f : -1.0f;
        M += v * e.transpose();
    }
    Eigen::JacobiSVD<Eigen::Matrix3f> svd(M, Eigen::ComputeFullU | Eigen::ComputeFullV);
    Eigen::Matrix3f out = svd.matrixU() * svd.matrixV().transpose();
    if (out.determinant() < 0) {
        Eigen::Matrix3f U = svd.matrixU();
        U.col(2) = -U.col(2);
        out = U * svd.matrixV().transpose();
    }
    return out;
}

}  // namespace

void RoomAxesParams::Validate() const {
    if (!(angle_threshold_deg > 0.0f && angle_threshold_deg < 45.0f)) {
        throw InvalidArgument(fmt::format(
            "room axes: angle_threshold_deg must be in (0, 45), got {}", angle_threshold_deg));
    }
    if (max_iterations < 1) {
        throw InvalidArgument(
            fmt::format("room axes: max_iterations must be >= 1, got {}", max_iterations));
    }
    if (max_normals < 10) {
        throw InvalidArgument(
            fmt::format("room axes: max_normals must be >= 10, got {}", max_normals));
    }
    if (up && (!up->allFinite() || up->norm() < 1e-6f)) {
        throw InvalidArgument("room axes: up must be a finite non-zero vector");
    }
}

RoomAxesResult EstimateRoomAxes(const PointCloud& cloud, const RoomAxesParams& params) {
    params.Validate();
    RoomAxesResult result;
    if (cloud.empty()) return result;
    if (cloud.normals.size() != cloud.size()) {
        throw DataError(fmt::format("room axes: the cloud has {} normals for {} points",
                                    cloud.normals.size(), cloud.size()));
    }
    Indices finite;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const auto& v = cloud.normals[i];
        if (v.allFinite() && v.squaredNorm() > 0.25f) finite.push_back(static_cast<Index>(i));
    }
    const Indices chosen = EvenSubset(finite, params.max_normals);
    std::vector<Eigen::Vector3f> n;
    n.reserve(chosen.size());
    for (const Index i : chosen) n.push_back(cloud.normals[i].normalized());
    result.used = n.size();
    if (n.size() < 10) return result;
    const float cos_t = std::cos(params.angle_threshold_deg * kDegToRad);
    std::mt19937_64 rng(params.seed);
    Eigen::Matrix3f best = Eigen::Matrix3f::Identity();
    std::size_t best_score = 0;
    for (int it = 0; it < params.max_iterations; ++it) {
        ++result.iterations;
        const Eigen::Vector3f& a = n[rng() % n.size()];
        const Eigen::Vector3f& b = n[rng() % n.size()];
        // Two normals closer than 45 degrees to each other (or to each other's opposite) span
        // their frame badly.
        if (std::abs(a.dot(b)) > 0.7071f) continue;
        Eigen::Matrix3f R;
        R.col(0) = a;
        R.col(1) = (b - b.dot(a) * a).normalized();
        R.col(2) = R.col(0).cross(R.col(1));
        const std::size_t s = Score(n, R, cos_t);
        if (s > best_score) {
            best_score = s;
            best = R;
        }
    }
    if (best_score < 10) {
        // One direction only (a floor seen alone): the frame around it, the horizontal axes
        // arbitrary, so that later stages can say what is missing.
        const Eigen::Vector3f up =
            params.up ? params.up->normalized()
                      : (cloud.HasSensorPosition() ? Eigen::Vector3f::UnitZ()
                                                   : Eigen::Vector3f(0.0f, -1.0f, 0.0f));
        Eigen::Vector3f sum = Eigen::Vector3f::Zero();
        std::size_t support = 0;
        for (const auto& v : n) {
            if (std::abs(v.dot(up)) >= cos_t) {
                sum += v.dot(up) > 0 ? v : Eigen::Vector3f(-v);
                ++support;
            }
        }
        if (support < 10) return result;
        const Eigen::Vector3f z = sum.normalized();
        Eigen::Vector3f x = Eigen::Vector3f::UnitX() - z.x() * z;
        if (x.norm() < 0.1f) x = Eigen::Vector3f::UnitY() - z.y() * z;
        x.normalize();
        result.frame.axes.col(0) = x;
        result.frame.axes.col(1) = z.cross(x);
        result.frame.axes.col(2) = z;
        result.inliers = support;
        result.found = true;
        return result;
    }
    for (int round = 0; round < 3; ++round) best = Refine(n, best, cos_t);
    result.inliers = Score(n, best, cos_t);
    // Order the axes: z nearest to up (and along it), then x, y right-handed.
    const Eigen::Vector3f up =
        params.up ? params.up->normalized()
                  : (cloud.HasSensorPosition() ? Eigen::Vector3f::UnitZ()
                                               : Eigen::Vector3f(0.0f, -1.0f, 0.0f));
    int k = 0;
    (best.transpose() * up).cwiseAbs().maxCoeff(&k);
    Eigen::Vector3f z = best.col(k);
    if (z.dot(up) < 0) z = -z;
    Eigen::Vector3f x = best.col((k + 1) % 3);
    // A stable choice of x among the two horizontal axes: the one nearest to the cloud's x.
    const Eigen::Vector3f other = best.col((k + 2) % 3);
    if (std::abs(other.x()) > std::abs(x.x())) x = other;
    if (x.x() < 0) x = -x;
    result.frame.axes.col(0) = x;
    result.frame.axes.col(1) = z.cross(x);
    result.frame.axes.col(2) = z;
    result.found = true;
    return result;
}

}  // namespace multicue::mapping

#include "multicue/registration/registration_result.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

#include <fmt/format.h>
#include <Eigen/Eigenvalues>
#include <Eigen/SVD>

#include "multicue/core/exceptions.hpp"
#include "multicue/core/parallel.hpp"

namespace multicue {

const char* RegistrationStatusName(RegistrationStatus status) {
    switch (status) {
        case RegistrationStatus::kConverged:
            return "converged";
        case RegistrationStatus::kMaxIterations:
            return "max_iterations";
        case RegistrationStatus::kEmptyInput:
            return "empty_input";
        case RegistrationStatus::kTooFewCorrespondences:
            return "too_few_correspondences";
        case RegistrationStatus::kLowOverlap:
            return "low_overlap";
        case RegistrationStatus::kDegenerate:
            return "degenerate";
        case RegistrationStatus::kNoHypothesis:
            return "no_hypothesis";
        case RegistrationStatus::kInconsistent:
            return "inconsistent";
    }
    return "unknown";
}

ConstraintAnalysis AnalyzeConstraints(std::span<const Eigen::Vector3d> points,
                                      std::span<const Eigen::Vector3d> normals,
                                      std::span<const double> weights) {
    if (points.size() != normals.size() || (!weights.empty() && weights.size() != points.size())) {
        throw InvalidArgument(
            fmt::format("constraint analysis: {} points, {} normals and {} weights do not match",
                        points.size(), normals.size(), weights.size()));
    }
    ConstraintAnalysis a;
    double total = 0.0;
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    for (std::size_t i = 0; i < points.size(); ++i) {
        const double w = weights.empty() ? 1.0 : weights[i];
        centroid += w * points[i];
        total += w;
    }
    if (!(total > 0.0)) return a;
    centroid /= total;
    double spread = 0.0;
    for (std::size_t i = 0; i < points.size(); ++i) {
        const double w = weights.empty() ? 1.0 : weights[i];
        const Eigen::Vector3d d = points[i] - centroid;
        spread += w * d.squaredNorm();
        Vector6d J;
        J.head<3>() = d.cross(normals[i]);
        J.tail<3>() = normals[i];
        a.information.noalias() += w * J * J.transpose();
    }
    a.scale = std::sqrt(spread / total);
    if (!(a.scale > 0.0)) return a;
    // Rotation about the centroid moves a point by about L per radian: dividing the rotation
    // rows and columns by L makes both blocks "squared metres per point".
    Vector6d s;
    s << 1.0 / a.scale, 1.0 / a.scale, 1.0 / a.scale, 1.0, 1.0, 1.0;
    const Matrix6d scaled = s.asDiagonal() * a.information * s.asDiagonal();
    Eigen::SelfAdjointEigenSolver<Matrix6d> eig(scaled);
    a.eigenvalues = eig.eigenvalues().cwiseMax(0.0);
    a.weakest_direction = eig.eigenvectors().col(0);
    const double largest = a.eigenvalues(5);
    a.condition = largest > 0.0 ? a.eigenvalues(0) / largest : 0.0;
    return a;
}

AlignmentQuality EvaluateAlignment(const PointCloud& source, const KdTree& target_tree,
                                   const Eigen::Isometry3d& T_target_source, double max_distance,
                                   std::size_t max_points, int num_threads) {
    if (!(max_distance > 0.0) || !std::isfinite(max_distance)) {
        throw InvalidArgument(
            fmt::format("alignment evaluation max_distance must be > 0, got {}", max_distance));
    }
    Indices finite;
    finite.reserve(source.size());
    for (std::size_t i = 0; i < source.size(); ++i) {
        if (source.IsFinite(i)) finite.push_back(static_cast<Index>(i));
    }
    if (max_points > 0) finite = EvenSubset(finite, max_points);
    AlignmentQuality q;
    q.usable = finite.size();
    if (finite.empty() || target_tree.empty()) return q;
    std::vector<double> d2(finite.size(), -1.0);
    const double limit2 = max_distance * max_distance;
    const Eigen::Isometry3f T = T_target_source.cast<float>();
    ParallelFor(finite.size(), num_threads, [&](std::size_t k) {
        Index j = 0;
        float dist2 = 0.0f;
        if (target_tree.SearchNearestWithin(T * source.points[finite[k]],
                                            static_cast<float>(max_distance), j, dist2) &&
            dist2 <= limit2) {
            d2[k] = dist2;
        }
    });
    double sum = 0.0;
    for (double v : d2) {
        if (v < 0.0) continue;
        ++q.inliers;
        sum += v;
    }
    q.fitness = static_cast<double>(q.inliers) / static_cast<double>(q.usable);
    q.inlier_rmse = q.inliers > 0 ? std::sqrt(sum / static_cast<double>(q.inliers)) : 0.0;
    return q;
}

bool FitRigidTransform(std::span<const Eigen::Vector3d> a, std::span<const Eigen::Vector3d> b,
                       std::span<const double> weights, Eigen::Isometry3d& T) {
    if (a.size() != b.size() || a.size() < 3 || (!weights.empty() && weights.size() != a.size())) {
        return false;
    }
    double total = 0.0;
    Eigen::Vector3d ca = Eigen::Vector3d::Zero();
    Eigen::Vector3d cb = Eigen::Vector3d::Zero();
    for (std::size_t i = 0; i < a.size(); ++i) {
        const double w = weights.empty() ? 1.0 : weights[i];
        total += w;
        ca += w * a[i];
        cb += w * b[i];
    }
    if (!(total > 0.0)) return false;
    ca /= total;
    cb /= total;
    Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
    double spread = 0.0;
    for (std::size_t i = 0; i < a.size(); ++i) {
        const double w = weights.empty() ? 1.0 : weights[i];
        const Eigen::Vector3d da = a[i] - ca;
        H.noalias() += w * da * (b[i] - cb).transpose();
        spread += w * da.squaredNorm();
    }
    Eigen::JacobiSVD<Eigen::Matrix3d> svd(H, Eigen::ComputeFullU | Eigen::ComputeFullV);
    const Eigen::Vector3d sv = svd.singularValues();
    // Collinear (or coincident) points leave the rotation about their line free.
    if (!(spread > 0.0) || sv(1) <= 1e-12 * std::max(sv(0), 1e-300)) return false;
    Eigen::Matrix3d D = Eigen::Matrix3d::Identity();
    if ((svd.matrixV() * svd.matrixU().transpose()).determinant() < 0.0) D(2, 2) = -1.0;
    const Eigen::Matrix3d R = svd.matrixV() * D * svd.matrixU().transpose();
    T = Eigen::Isometry3d::Identity();
    T.linear() = R;
    T.translation() = cb - R * ca;
    return true;
}

Eigen::Isometry3d TwistToTransform(const Vector6d& x) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    const Eigen::Vector3d r = x.head<3>();
    const double angle = r.norm();
    if (angle > 0.0) T.linear() = Eigen::AngleAxisd(angle, r / angle).toRotationMatrix();
    T.translation() = x.tail<3>();
    return T;
}

double RotationAngleDeg(const Eigen::Isometry3d& T) {
    // Through the quaternion (2 atan2(|v|, w)): exact for small angles, unlike acos of the trace.
    const Eigen::Quaterniond q(T.linear());
    return 2.0 * std::atan2(q.vec().norm(), std::abs(q.w())) * 180.0 / std::numbers::pi;
}

double TranslationNorm(const Eigen::Isometry3d& T) { return T.translation().norm(); }

}  // namespace multicue

#include "multicue/segmentation/sac_line.hpp"

#include <cmath>

#include <Eigen/Eigenvalues>

#include "multicue/segmentation/sac_internal.hpp"

namespace multicue {
namespace {

// Coefficients: (point, unit direction).
SacModel MakeLineModel(bool constrained, const Eigen::Vector3f& axis, float cos_max) {
    auto accepts = [constrained, axis, cos_max](const Eigen::Vector3f& d) {
        return !constrained || std::abs(d.dot(axis)) >= cos_max;
    };
    SacModel m;
    m.sample_size = 2;
    m.fit_sample = [accepts](const PointCloud& cloud, std::span<const Index> s,
                             SacCoefficients& c) {
        const Eigen::Vector3f& p0 = cloud.points[s[0]];
        const Eigen::Vector3f d = cloud.points[s[1]] - p0;
        const float norm = d.norm();
        // Coincident points (relative to their distance from the origin) define no direction.
        if (!(norm > 1e-6f * (1.0f + p0.norm()))) return false;
        const Eigen::Vector3f unit = d / norm;
        if (!accepts(unit)) return false;
        c.resize(6);
        c.head<3>() = p0;
        c.tail<3>() = unit;
        return true;
    };
    m.distances = [](const PointCloud& cloud, const SacCoefficients& c, std::span<const Index> idx,
                     std::span<float> dist) {
        const Eigen::Vector3f p0 = c.head<3>();
        const Eigen::Vector3f dir = c.tail<3>();
        for (std::size_t k = 0; k < idx.size(); ++k) {
            dist[k] = (cloud.points[idx[k]] - p0).cross(dir).norm();
        }
    };
    m.refine = [accepts](const PointCloud& cloud, std::span<const Index> inliers,
                         const SacCoefficients& current, SacCoefficients& refined) {
        const sac_internal::Moments mom = sac_internal::ComputeMoments(cloud, inliers);
        const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(mom.covariance);
        if (eig.info() != Eigen::Success) return false;
        Eigen::Vector3d d = eig.eigenvectors().col(2);  // eigenvalues ascend
        if (d.dot(current.tail<3>().cast<double>()) < 0.0) d = -d;
        const Eigen::Vector3f df = d.cast<float>().normalized();
        if (!df.allFinite() || !accepts(df)) return false;
        refined.resize(6);
        refined.head<3>() = mom.mean.cast<float>();
        refined.tail<3>() = df;
        return true;
    };
    return m;
}

}  // namespace

LineFit FitLine(const PointCloud& cloud, const Indices& indices, const LineFitParams& params) {
    Eigen::Vector3f axis = Eigen::Vector3f::UnitX();
    float cos_max = 0.0f;
    if (params.axis) {
        sac_internal::ValidateMaxAngle(params.max_angle, "line");
        axis = sac_internal::NormalizedAxis(*params.axis, "line constraint");
        cos_max = std::cos(params.max_angle);
    }
    SacResult r = RunSampleConsensus(
        cloud, indices, MakeLineModel(params.axis.has_value(), axis, cos_max), params.sac);
    LineFit fit;
    if (r.found) {
        Eigen::Vector3f dir = r.coefficients.tail<3>();
        if (params.axis) {
            if (dir.dot(axis) < 0.0f) dir = -dir;
        } else {
            dir = sac_internal::CanonicalDirection(dir);
        }
        const Eigen::Vector3f p0 = r.coefficients.head<3>();
        const Eigen::Vector3f centroid =
            sac_internal::ComputeMoments(cloud, r.inliers).mean.cast<float>();
        fit.point = p0 + (centroid - p0).dot(dir) * dir;
        fit.direction = dir;
    }
    sac_internal::CopyOutcome(r, fit);
    return fit;
}

}  // namespace multicue

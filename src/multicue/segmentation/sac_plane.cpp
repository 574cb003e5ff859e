#include "multicue/segmentation/sac_plane.hpp"

#include <cmath>

#include <Eigen/Eigenvalues>

#include "multicue/segmentation/sac_internal.hpp"

namespace multicue {
namespace {

// Coefficients: (a, b, c, d), unit normal.
struct PlaneConstraint {
    bool active = false;
    Eigen::Vector3f axis = Eigen::Vector3f::UnitZ();
    PlaneAxisMode mode = PlaneAxisMode::kParallel;
    float cos_max = 1.0f;  // kParallel: |n . axis| >= cos(max_angle)
    float sin_max = 0.0f;  // kPerpendicular: |n . axis| <= sin(max_angle)

    bool Accepts(const Eigen::Vector3f& n) const {
        if (!active) return true;
        const float c = std::abs(n.dot(axis));
        return mode == PlaneAxisMode::kParallel ? c >= cos_max : c <= sin_max;
    }
};

SacModel MakePlaneModel(const PlaneConstraint& constraint) {
    SacModel m;
    m.sample_size = 3;
    m.fit_sample = [constraint](const PointCloud& cloud, std::span<const Index> s,
                                SacCoefficients& c) {
        const Eigen::Vector3f& p0 = cloud.points[s[0]];
        const Eigen::Vector3f a = cloud.points[s[1]] - p0;
        const Eigen::Vector3f b = cloud.points[s[2]] - p0;
        const Eigen::Vector3f n = a.cross(b);
        const float norm = n.norm();
        // Collinear (or coincident) points: the sine of their angle is below 1e-4.
        if (!(norm > 1e-4f * a.norm() * b.norm())) return false;
        const Eigen::Vector3f unit = n / norm;
        if (!constraint.Accepts(unit)) return false;
        c.resize(4);
        c.head<3>() = unit;
        c[3] = -unit.dot(p0);
        return true;
    };
    m.distances = [](const PointCloud& cloud, const SacCoefficients& c, std::span<const Index> idx,
                     std::span<float> d) {
        const Eigen::Vector3f n = c.head<3>();
        const float offset = c[3];
        for (std::size_t k = 0; k < idx.size(); ++k) d[k] = n.dot(cloud.points[idx[k]]) + offset;
    };
    m.normal_angles = [](const PointCloud& cloud, const SacCoefficients& c,
                         std::span<const Index> idx, std::span<float> angles) {
        const Eigen::Vector3f n = c.head<3>();
        for (std::size_t k = 0; k < idx.size(); ++k) {
            angles[k] = sac_internal::UnsignedAngle(n, cloud.normals[idx[k]]);
        }
    };
    m.refine = [constraint](const PointCloud& cloud, std::span<const Index> inliers,
                            const SacCoefficients& current, SacCoefficients& refined) {
        const sac_internal::Moments mom = sac_internal::ComputeMoments(cloud, inliers);
        const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(mom.covariance);
        if (eig.info() != Eigen::Success) return false;
        Eigen::Vector3d n = eig.eigenvectors().col(0);  // eigenvalues ascend
        if (n.dot(current.head<3>().cast<double>()) < 0.0) n = -n;
        const Eigen::Vector3f nf = n.cast<float>().normalized();
        if (!nf.allFinite() || !constraint.Accepts(nf)) return false;
        refined.resize(4);
        refined.head<3>() = nf;
        refined[3] = static_cast<float>(-n.dot(mom.mean));
        return true;
    };
    return m;
}

}  // namespace

PlaneFit FitPlane(const PointCloud& cloud, const Indices& indices, const PlaneFitParams& params) {
    PlaneConstraint constraint;
    if (params.axis) {
        sac_internal::ValidateMaxAngle(params.max_angle, "plane");
        constraint.active = true;
        constraint.axis = sac_internal::NormalizedAxis(*params.axis, "plane constraint");
        constraint.mode = params.axis_mode;
        constraint.cos_max = std::cos(params.max_angle);
        constraint.sin_max = std::sin(params.max_angle);
    }
    SacResult r = RunSampleConsensus(cloud, indices, MakePlaneModel(constraint), params.sac);
    PlaneFit fit;
    if (r.found) {
        Eigen::Vector4f plane = r.coefficients;
        bool flip = false;
        if (constraint.active && constraint.mode == PlaneAxisMode::kParallel) {
            flip = plane.head<3>().dot(constraint.axis) < 0.0f;
        } else {
            const Eigen::Vector3f v = params.viewpoint.value_or(cloud.sensor_origin);
            flip = plane.head<3>().dot(v) + plane[3] < 0.0f;
        }
        fit.plane = flip ? Eigen::Vector4f(-plane) : plane;
    }
    sac_internal::CopyOutcome(r, fit);
    return fit;
}

}  // namespace multicue

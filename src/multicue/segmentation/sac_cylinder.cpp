#include "multicue/segmentation/sac_cylinder.hpp"

#include <cmath>

#include "multicue/segmentation/cylinder_least_squares.hpp"
#include "multicue/segmentation/sac_internal.hpp"

namespace multicue {
namespace {

struct CylinderLimits {
    float min_radius = 0.0f;
    float max_radius = 0.0f;
    bool constrained = false;
    Eigen::Vector3f axis = Eigen::Vector3f::UnitZ();
    float cos_max = 0.0f;

    bool Accepts(const Eigen::Vector3f& a, double r) const {
        return sac_internal::RadiusAccepted(r, min_radius, max_radius) &&
               (!constrained || std::abs(a.dot(axis)) >= cos_max);
    }
};

// Coefficients: (point on axis, unit axis, r).
SacModel MakeCylinderModel(const CylinderLimits& limits) {
    SacModel m;
    m.sample_size = 2;
    m.needs_normals = true;
    m.fit_sample = [limits](const PointCloud& cloud, std::span<const Index> s, SacCoefficients& c) {
        const Eigen::Vector3d p1 = cloud.points[s[0]].cast<double>();
        const Eigen::Vector3d p2 = cloud.points[s[1]].cast<double>();
        const Eigen::Vector3d n1 = cloud.normals[s[0]].cast<double>().normalized();
        const Eigen::Vector3d n2 = cloud.normals[s[1]].cast<double>().normalized();
        // Both normals are orthogonal to the axis: it is along their cross product. Parallel
        // normals (sine below 1e-3) leave the axis undetermined.
        const Eigen::Vector3d cross = n1.cross(n2);
        const double sine = cross.norm();
        if (!(sine > 1e-3)) return false;
        const Eigen::Vector3d axis = cross / sine;
        // The segment connecting the normal lines' closest points is along the axis, so both ends
        // lie on it and so does their midpoint.
        const Eigen::Vector3d point = sac_internal::NormalLinesMidpoint(p1, n1, p2, n2);
        auto radial = [&](const Eigen::Vector3d& p) {
            const Eigen::Vector3d w = p - point;
            return (w - w.dot(axis) * axis).norm();
        };
        const double r = 0.5 * (radial(p1) + radial(p2));
        const Eigen::Vector3f axis_f = axis.cast<float>();
        if (!point.allFinite() || !limits.Accepts(axis_f, r)) return false;
        c.resize(7);
        c.head<3>() = point.cast<float>();
        c.segment<3>(3) = axis_f;
        c[6] = static_cast<float>(r);
        return true;
    };
    m.distances = [](const PointCloud& cloud, const SacCoefficients& c, std::span<const Index> idx,
                     std::span<float> dist) {
        const Eigen::Vector3f p0 = c.head<3>();
        const Eigen::Vector3f a = c.segment<3>(3);
        for (std::size_t k = 0; k < idx.size(); ++k) {
            const Eigen::Vector3f w = cloud.points[idx[k]] - p0;
            dist[k] = (w - w.dot(a) * a).norm() - c[6];
        }
    };
    m.normal_angles = [](const PointCloud& cloud, const SacCoefficients& c,
                         std::span<const Index> idx, std::span<float> angles) {
        const Eigen::Vector3f p0 = c.head<3>();
        const Eigen::Vector3f a = c.segment<3>(3);
        for (std::size_t k = 0; k < idx.size(); ++k) {
            const Eigen::Vector3f w = cloud.points[idx[k]] - p0;
            const Eigen::Vector3f radial = (w - w.dot(a) * a).normalized();
            angles[k] = sac_internal::UnsignedAngle(radial, cloud.normals[idx[k]]);
        }
    };
    m.refine = [limits](const PointCloud& cloud, std::span<const Index> inliers,
                        const SacCoefficients& current, SacCoefficients& refined) {
        CylinderEstimate x{current.head<3>().cast<double>(),
                           current.segment<3>(3).cast<double>().normalized(), double{current[6]}};
        if (!RefineCylinder(cloud, inliers, {.freedom = CylinderAxisFreedom::kFree}, x)) {
            return false;
        }
        const Eigen::Vector3f axis_f = x.axis.cast<float>();
        if (!x.point.allFinite() || !axis_f.allFinite() || !limits.Accepts(axis_f, x.radius)) {
            return false;
        }
        refined.resize(7);
        refined.head<3>() = x.point.cast<float>();
        refined.segment<3>(3) = axis_f;
        refined[6] = static_cast<float>(x.radius);
        return true;
    };
    return m;
}

}  // namespace

CylinderFit FitCylinder(const PointCloud& cloud, const Indices& indices,
                        const CylinderFitParams& params) {
    CylinderLimits limits;
    sac_internal::ValidateRadiusLimits(params.min_radius, params.max_radius, "cylinder");
    limits.min_radius = params.min_radius;
    limits.max_radius = params.max_radius;
    if (params.axis) {
        sac_internal::ValidateMaxAngle(params.max_angle, "cylinder");
        limits.constrained = true;
        limits.axis = sac_internal::NormalizedAxis(*params.axis, "cylinder constraint");
        limits.cos_max = std::cos(params.max_angle);
    }
    SacResult r = RunSampleConsensus(cloud, indices, MakeCylinderModel(limits), params.sac);
    CylinderFit fit;
    if (r.found) {
        Eigen::Vector3f a = r.coefficients.segment<3>(3).normalized();
        if (limits.constrained) {
            if (a.dot(limits.axis) < 0.0f) a = -a;
        } else {
            a = sac_internal::CanonicalDirection(a);
        }
        const Eigen::Vector3f p0 = r.coefficients.head<3>();
        const Eigen::Vector3f centroid =
            sac_internal::ComputeMoments(cloud, r.inliers).mean.cast<float>();
        fit.point = p0 + (centroid - p0).dot(a) * a;
        fit.axis = a;
        fit.radius = r.coefficients[6];
    }
    sac_internal::CopyOutcome(r, fit);
    return fit;
}

}  // namespace multicue

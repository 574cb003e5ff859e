#include "multicue/segmentation/sac_sphere.hpp"

#include <cmath>

#include <Eigen/LU>

#include "multicue/segmentation/sac_internal.hpp"

namespace multicue {
namespace {

// A sphere through two points whose normals point along its radii: the centre is the midpoint
// of the normal lines' closest approach, the radius the mean distance of the points from it.
// Parallel normals (sine below 1e-3) leave the centre undetermined.
bool SphereFromOrientedPair(const PointCloud& cloud, std::span<const Index> s, float min_radius,
                            float max_radius, SacCoefficients& c) {
    const Eigen::Vector3d p1 = cloud.points[s[0]].cast<double>();
    const Eigen::Vector3d p2 = cloud.points[s[1]].cast<double>();
    const Eigen::Vector3d n1 = cloud.normals[s[0]].cast<double>().normalized();
    const Eigen::Vector3d n2 = cloud.normals[s[1]].cast<double>().normalized();
    const double b = n1.dot(n2);
    if (!(1.0 - b * b > 1e-6)) return false;
    const Eigen::Vector3d centre = sac_internal::NormalLinesMidpoint(p1, n1, p2, n2);
    const double r = 0.5 * ((p1 - centre).norm() + (p2 - centre).norm());
    if (!centre.allFinite() || !sac_internal::RadiusAccepted(r, min_radius, max_radius)) {
        return false;
    }
    c.resize(4);
    c.head<3>() = centre.cast<float>();
    c[3] = static_cast<float>(r);
    return true;
}

// Coefficients: (centre, r).
SacModel MakeSphereModel(float min_radius, float max_radius, bool oriented) {
    SacModel m;
    m.sample_size = oriented ? 2 : 4;
    m.needs_normals = oriented;
    m.fit_sample = [=](const PointCloud& cloud, std::span<const Index> s, SacCoefficients& c) {
        if (oriented) return SphereFromOrientedPair(cloud, s, min_radius, max_radius, c);
        // |p_i - c|^2 = r^2 for all four points; subtracting the first equation leaves the linear
        // system 2 (p_i - p_0) . (c - p_0) = |p_i - p_0|^2, i = 1..3.
        const Eigen::Vector3d p0 = cloud.points[s[0]].cast<double>();
        Eigen::Matrix3d a;
        Eigen::Vector3d b;
        for (int i = 0; i < 3; ++i) {
            const Eigen::Vector3d d =
                cloud.points[s[static_cast<std::size_t>(i) + 1]].cast<double>() - p0;
            a.row(i) = 2.0 * d.transpose();
            b[i] = d.squaredNorm();
        }
        // Coplanar points: the volume they span is tiny relative to their edge lengths.
        const double scale = a.row(0).norm() * a.row(1).norm() * a.row(2).norm();
        if (!(std::abs(a.determinant()) > 1e-6 * scale)) return false;
        const Eigen::Vector3d rel = a.partialPivLu().solve(b);
        const double r = rel.norm();
        if (!sac_internal::RadiusAccepted(r, min_radius, max_radius)) return false;
        c.resize(4);
        c.head<3>() = (p0 + rel).cast<float>();
        c[3] = static_cast<float>(r);
        return true;
    };
    m.distances = [](const PointCloud& cloud, const SacCoefficients& c, std::span<const Index> idx,
                     std::span<float> d) {
        const Eigen::Vector3f centre = c.head<3>();
        for (std::size_t k = 0; k < idx.size(); ++k) {
            d[k] = (cloud.points[idx[k]] - centre).norm() - c[3];
        }
    };
    m.normal_angles = [](const PointCloud& cloud, const SacCoefficients& c,
                         std::span<const Index> idx, std::span<float> angles) {
        const Eigen::Vector3f centre = c.head<3>();
        for (std::size_t k = 0; k < idx.size(); ++k) {
            const Eigen::Vector3f radial = (cloud.points[idx[k]] - centre).normalized();
            angles[k] = sac_internal::UnsignedAngle(radial, cloud.normals[idx[k]]);
        }
    };
    m.refine = [=](const PointCloud& cloud, std::span<const Index> inliers,
                   const SacCoefficients& current, SacCoefficients& refined) {
        // Residual e = |p - c| - r; de/dc = -(p - c)/|p - c|, de/dr = -1.
        using Mat4 = Eigen::Matrix4d;
        using Vec4 = Eigen::Vector4d;
        Vec4 x = current.cast<double>();
        auto linearize = [&](const Vec4& st, Mat4& jtj, Vec4& jtr) {
            jtj.setZero();
            jtr.setZero();
            double cost = 0.0;
            for (Index i : inliers) {
                const Eigen::Vector3d w = cloud.points[i].cast<double>() - st.head<3>();
                const double rho = w.norm();
                const double e = rho - st[3];
                Vec4 j(0.0, 0.0, 0.0, -1.0);
                if (rho > 0.0) j.head<3>() = -w / rho;
                jtj += j * j.transpose();
                jtr += j * e;
                cost += e * e;
            }
            return cost;
        };
        auto update = [](const Vec4& st, const Vec4& delta) { return Vec4(st + delta); };
        if (!sac_internal::LevenbergMarquardt<4>(x, linearize, update)) return false;
        if (!x.allFinite() || !sac_internal::RadiusAccepted(x[3], min_radius, max_radius))
            return false;
        refined = x.cast<float>();
        return true;
    };
    return m;
}

}  // namespace

SphereFit FitSphere(const PointCloud& cloud, const Indices& indices,
                    const SphereFitParams& params) {
    sac_internal::ValidateRadiusLimits(params.min_radius, params.max_radius, "sphere");
    SacResult r = RunSampleConsensus(
        cloud, indices,
        MakeSphereModel(params.min_radius, params.max_radius, params.oriented_samples), params.sac);
    SphereFit fit;
    if (r.found) {
        fit.center = r.coefficients.head<3>();
        fit.radius = r.coefficients[3];
    }
    sac_internal::CopyOutcome(r, fit);
    return fit;
}

}  // namespace multicue

#include "multicue/segmentation/sac_circle.hpp"

#include <cmath>

#include "multicue/segmentation/sac_internal.hpp"

namespace multicue {
namespace {

// ---- 2D circle. Coefficients: (cx, cy, r).

SacModel MakeCircle2dModel(float min_radius, float max_radius) {
    SacModel m;
    m.sample_size = 3;
    m.fit_sample = [=](const PointCloud& cloud, std::span<const Index> s, SacCoefficients& c) {
        // Circumcentre of three points, relative to the third one.
        const Eigen::Vector2d p2 = cloud.points[s[2]].head<2>().cast<double>();
        const Eigen::Vector2d a = cloud.points[s[0]].head<2>().cast<double>() - p2;
        const Eigen::Vector2d b = cloud.points[s[1]].head<2>().cast<double>() - p2;
        const double det = 2.0 * (a.x() * b.y() - a.y() * b.x());
        // Collinear points: the sine of their angle is below 1e-4.
        if (!(std::abs(det) > 2e-4 * a.norm() * b.norm())) return false;
        const Eigen::Vector2d centre(
            p2.x() + (b.y() * a.squaredNorm() - a.y() * b.squaredNorm()) / det,
            p2.y() + (a.x() * b.squaredNorm() - b.x() * a.squaredNorm()) / det);
        const double r = (centre - p2).norm();
        if (!sac_internal::RadiusAccepted(r, min_radius, max_radius)) return false;
        c.resize(3);
        c.head<2>() = centre.cast<float>();
        c[2] = static_cast<float>(r);
        return true;
    };
    m.distances = [](const PointCloud& cloud, const SacCoefficients& c, std::span<const Index> idx,
                     std::span<float> d) {
        const Eigen::Vector2f centre = c.head<2>();
        for (std::size_t k = 0; k < idx.size(); ++k) {
            d[k] = (cloud.points[idx[k]].head<2>() - centre).norm() - c[2];
        }
    };
    m.refine = [=](const PointCloud& cloud, std::span<const Index> inliers,
                   const SacCoefficients& current, SacCoefficients& refined) {
        // Residual e = |q - c| - r; de/dc = -(q - c)/|q - c|, de/dr = -1.
        Eigen::Vector3d x = current.cast<double>();
        auto linearize = [&](const Eigen::Vector3d& s, Eigen::Matrix3d& jtj, Eigen::Vector3d& jtr) {
            jtj.setZero();
            jtr.setZero();
            double cost = 0.0;
            for (Index i : inliers) {
                const Eigen::Vector2d q = cloud.points[i].head<2>().cast<double>() - s.head<2>();
                const double rho = q.norm();
                const double e = rho - s[2];
                Eigen::Vector3d j(0.0, 0.0, -1.0);
                if (rho > 0.0) j.head<2>() = -q / rho;
                jtj += j * j.transpose();
                jtr += j * e;
                cost += e * e;
            }
            return cost;
        };
        auto update = [](const Eigen::Vector3d& s, const Eigen::Vector3d& delta) {
            return Eigen::Vector3d(s + delta);
        };
        if (!sac_internal::LevenbergMarquardt<3>(x, linearize, update)) return false;
        if (!x.allFinite() || !sac_internal::RadiusAccepted(x[2], min_radius, max_radius))
            return false;
        refined = x.cast<float>();
        return true;
    };
    return m;
}

// ---- 3D circle. Coefficients: (centre, unit normal, r).

struct Circle3dState {
    Eigen::Vector3d centre;
    Eigen::Vector3d normal;
    double radius = 0.0;
};

SacModel MakeCircle3dModel(float min_radius, float max_radius) {
    SacModel m;
    m.sample_size = 3;
    m.fit_sample = [=](const PointCloud& cloud, std::span<const Index> s, SacCoefficients& c) {
        const Eigen::Vector3d p2 = cloud.points[s[2]].cast<double>();
        const Eigen::Vector3d a = cloud.points[s[0]].cast<double>() - p2;
        const Eigen::Vector3d b = cloud.points[s[1]].cast<double>() - p2;
        const Eigen::Vector3d axb = a.cross(b);
        const double n2 = axb.squaredNorm();
        if (!(std::sqrt(n2) > 1e-4 * a.norm() * b.norm())) return false;  // collinear
        // Circumcentre of a triangle: p2 + ((|a|^2 b - |b|^2 a) x (a x b)) / (2 |a x b|^2).
        const Eigen::Vector3d centre =
            p2 + (a.squaredNorm() * b - b.squaredNorm() * a).cross(axb) / (2.0 * n2);
        const double r = (centre - p2).norm();
        if (!sac_internal::RadiusAccepted(r, min_radius, max_radius)) return false;
        c.resize(7);
        c.head<3>() = centre.cast<float>();
        c.segment<3>(3) = axb.normalized().cast<float>();
        c[6] = static_cast<float>(r);
        return true;
    };
    m.distances = [](const PointCloud& cloud, const SacCoefficients& c, std::span<const Index> idx,
                     std::span<float> d) {
        const Eigen::Vector3f centre = c.head<3>();
        const Eigen::Vector3f n = c.segment<3>(3);
        for (std::size_t k = 0; k < idx.size(); ++k) {
            const Eigen::Vector3f w = cloud.points[idx[k]] - centre;
            const float h = w.dot(n);
            const float rho = (w - h * n).norm();
            d[k] = std::hypot(h, rho - c[6]);
        }
    };
    m.refine = [=](const PointCloud& cloud, std::span<const Index> inliers,
                   const SacCoefficients& current, SacCoefficients& refined) {
        // Two residuals per point: the height h = w.n above the plane and s = rho - r in it,
        // w = p - c, rho = |w - h n|. Local parameters: dc (3), the normal tilted by
        // d1 u + d2 v (2), dr (1). With q^ the unit in-plane direction of w:
        // dh/dc = -n, dh/dd1 = w.u; ds/dc = -q^, ds/dd1 = -h (q^.u), ds/dr = -1.
        using Mat6 = Eigen::Matrix<double, 6, 6>;
        using Vec6 = Eigen::Matrix<double, 6, 1>;
        Circle3dState x{current.head<3>().cast<double>(),
                        current.segment<3>(3).cast<double>().normalized(), double{current[6]}};
        auto linearize = [&](const Circle3dState& st, Mat6& jtj, Vec6& jtr) {
            Eigen::Vector3d u;
            Eigen::Vector3d v;
            sac_internal::OrthonormalBasis(st.normal, u, v);
            jtj.setZero();
            jtr.setZero();
            double cost = 0.0;
            for (Index i : inliers) {
                const Eigen::Vector3d w = cloud.points[i].cast<double>() - st.centre;
                const double h = w.dot(st.normal);
                const Eigen::Vector3d q = w - h * st.normal;
                const double rho = q.norm();
                const Eigen::Vector3d qhat = rho > 0.0 ? Eigen::Vector3d(q / rho) : q;
                const double s = rho - st.radius;
                Vec6 jh;
                jh << -st.normal, w.dot(u), w.dot(v), 0.0;
                Vec6 js;
                js << -qhat, -h * qhat.dot(u), -h * qhat.dot(v), -1.0;
                jtj += jh * jh.transpose() + js * js.transpose();
                jtr += jh * h + js * s;
                cost += h * h + s * s;
            }
            return cost;
        };
        auto update = [](const Circle3dState& st, const Vec6& delta) {
            Eigen::Vector3d u;
            Eigen::Vector3d v;
            sac_internal::OrthonormalBasis(st.normal, u, v);
            return Circle3dState{st.centre + delta.head<3>(),
                                 (st.normal + delta[3] * u + delta[4] * v).normalized(),
                                 st.radius + delta[5]};
        };
        if (!sac_internal::LevenbergMarquardt<6>(x, linearize, update)) return false;
        if (!x.centre.allFinite() || !x.normal.allFinite() ||
            !sac_internal::RadiusAccepted(x.radius, min_radius, max_radius)) {
            return false;
        }
        refined.resize(7);
        refined.head<3>() = x.centre.cast<float>();
        refined.segment<3>(3) = x.normal.cast<float>();
        refined[6] = static_cast<float>(x.radius);
        return true;
    };
    return m;
}

}  // namespace

Circle2dFit FitCircle2d(const PointCloud& cloud, const Indices& indices,
                        const Circle2dFitParams& params) {
    sac_internal::ValidateRadiusLimits(params.min_radius, params.max_radius, "circle");
    SacResult r = RunSampleConsensus(
        cloud, indices, MakeCircle2dModel(params.min_radius, params.max_radius), params.sac);
    Circle2dFit fit;
    if (r.found) {
        fit.center = r.coefficients.head<2>();
        fit.radius = r.coefficients[2];
    }
    sac_internal::CopyOutcome(r, fit);
    return fit;
}

Circle3dFit FitCircle3d(const PointCloud& cloud, const Indices& indices,
                        const Circle3dFitParams& params) {
    sac_internal::ValidateRadiusLimits(params.min_radius, params.max_radius, "circle");
    SacResult r = RunSampleConsensus(
        cloud, indices, MakeCircle3dModel(params.min_radius, params.max_radius), params.sac);
    Circle3dFit fit;
    if (r.found) {
        fit.center = r.coefficients.head<3>();
        Eigen::Vector3f n = r.coefficients.segment<3>(3).normalized();
        const Eigen::Vector3f v = params.viewpoint.value_or(cloud.sensor_origin);
        if (n.dot(v - fit.center) < 0.0f) n = -n;
        fit.normal = n;
        fit.radius = r.coefficients[6];
    }
    sac_internal::CopyOutcome(r, fit);
    return fit;
}

}  // namespace multicue

#include "multicue/reconstruction/cylinder_refinement.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Cholesky>

namespace multicue::detail {

Indices SidePoints(const PointCloud& cloud, const Indices& usable, const CylinderState& x,
                   double max_distance, double min_cos) {
    Indices out;
    for (Index i : usable) {
        const Eigen::Vector3d w = cloud.points[i].cast<double>() - x.point;
        const Eigen::Vector3d q = w - w.dot(x.axis) * x.axis;
        const double rho = q.norm();
        if (!(rho > 0.0) || std::abs(rho - x.radius) > max_distance) continue;
        const double c = std::abs(cloud.normals[i].cast<double>().normalized().dot(q / rho));
        if (c >= min_cos) out.push_back(i);
    }
    return out;
}

// Local parameters: axis tilt along u and v, axis position along u and v, radius, with (u, v)
// orthonormal to the axis. de/d(tilt_u) = -(w.a)(q^.u), de/d(shift_u) = -q^.u, de/dr = -1.
// Frozen tilts get zero columns (and a unit diagonal so the system stays solvable).
bool RefineCylinder(const PointCloud& cloud, const Indices& points, const Eigen::Vector3d& up,
                    AxisFreedom freedom, CylinderState& x) {
    using Mat5 = Eigen::Matrix<double, 5, 5>;
    using Vec5 = Eigen::Matrix<double, 5, 1>;
    // Re-centre the axis point on the points' centroid so the tilt is well conditioned.
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    for (Index i : points) centroid += cloud.points[i].cast<double>();
    centroid /= static_cast<double>(points.size());
    x.point += (centroid - x.point).dot(x.axis) * x.axis;

    auto basis = [&](const CylinderState& s, Eigen::Vector3d& u, Eigen::Vector3d& v) {
        if (freedom == AxisFreedom::kAboutUp) {
            u = up.cross(s.axis).normalized();  // horizontal: tilting along it keeps s level
        } else {
            u = s.axis.unitOrthogonal();
        }
        v = s.axis.cross(u);
    };
    const bool tilt_u = freedom != AxisFreedom::kFixed;
    const bool tilt_v = freedom == AxisFreedom::kFree;
    auto linearize = [&](const CylinderState& s, Mat5& jtj, Vec5& jtr) {
        Eigen::Vector3d u, v;
        basis(s, u, v);
        jtj.setZero();
        jtr.setZero();
        double cost = 0.0;
        for (Index i : points) {
            const Eigen::Vector3d w = cloud.points[i].cast<double>() - s.point;
            const double along = w.dot(s.axis);
            const Eigen::Vector3d q = w - along * s.axis;
            const double rho = q.norm();
            const double e = rho - s.radius;
            Vec5 j = Vec5::Zero();
            j[4] = -1.0;
            if (rho > 0.0) {
                const Eigen::Vector3d qhat = q / rho;
                if (tilt_u) j[0] = -along * qhat.dot(u);
                if (tilt_v) j[1] = -along * qhat.dot(v);
                j[2] = -qhat.dot(u);
                j[3] = -qhat.dot(v);
            }
            jtj += j * j.transpose();
            jtr += j * e;
            cost += e * e;
        }
        return cost;
    };
    auto update = [&](const CylinderState& s, const Vec5& d) {
        Eigen::Vector3d u, v;
        basis(s, u, v);
        return CylinderState{s.point + d[2] * u + d[3] * v,
                             (s.axis + d[0] * u + d[1] * v).normalized(), s.radius + d[4]};
    };
    Mat5 jtj;
    Vec5 jtr;
    double cost = linearize(x, jtj, jtr);
    if (!std::isfinite(cost)) return false;
    double lambda = 1e-3;
    for (int it = 0; it < 50; ++it) {
        bool accepted = false;
        while (lambda < 1e10) {
            Mat5 a = jtj;
            for (int k = 0; k < 5; ++k) a(k, k) += lambda * std::max(jtj(k, k), 1e-12);
            if (!tilt_u) a(0, 0) = 1.0;
            if (!tilt_v) a(1, 1) = 1.0;
            const Vec5 delta = a.ldlt().solve(-jtr);
            const CylinderState cand = update(x, delta);
            Mat5 cand_jtj;
            Vec5 cand_jtr;
            const double cand_cost = linearize(cand, cand_jtj, cand_jtr);
            if (std::isfinite(cand_cost) && cand_cost <= cost) {
                const bool converged = cost - cand_cost <= 1e-12 * std::max(cost, 1e-30);
                x = cand;
                jtj = cand_jtj;
                jtr = cand_jtr;
                cost = cand_cost;
                lambda = std::max(lambda * 0.1, 1e-12);
                accepted = true;
                if (converged) return true;
                break;
            }
            lambda *= 10.0;
        }
        if (!accepted) break;
    }
    return true;
}

}  // namespace multicue::detail

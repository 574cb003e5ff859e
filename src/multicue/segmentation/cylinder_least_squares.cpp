#include "multicue/segmentation/cylinder_least_squares.hpp"

#include <cmath>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/segmentation/sac_internal.hpp"

namespace multicue {
namespace {

// Local parameters, in this order: axis position along u and v, radius, then the free axis
// tilts along u and v, with (u, v) orthonormal to the axis. Frozen tilts are left out of the
// system, so P = 3 + number of free tilts. With q^ = q / rho (orthogonal to a):
// de/d(shift_u) = -q^.u, de/dr = -1, de/d(tilt_u) = -(w.a)(q^.u) (same for v).
template <int P>
bool Solve(const PointCloud& cloud, std::span<const Index> points, const Eigen::Vector3d& up,
           bool about_up, int max_iterations, CylinderEstimate& x) {
    using Mat = Eigen::Matrix<double, P, P>;
    using Vec = Eigen::Matrix<double, P, 1>;
    using Vec5 = Eigen::Matrix<double, 5, 1>;
    // A deterministic function of the axis, so a linearisation and the update that follows it
    // use the same basis. About `up`, u is orthogonal to it: tilting along u keeps the axis
    // orthogonal to `up` when it was.
    auto basis = [&](const CylinderEstimate& s, Eigen::Vector3d& u, Eigen::Vector3d& v) {
        if (about_up) {
            u = up.cross(s.axis).normalized();
            v = s.axis.cross(u);
        } else {
            sac_internal::OrthonormalBasis(s.axis, u, v);
        }
    };
    auto linearize = [&](const CylinderEstimate& s, Mat& jtj, Vec& jtr) {
        Eigen::Vector3d u;
        Eigen::Vector3d v;
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
            j[2] = -1.0;
            if (rho > 0.0) {
                const Eigen::Vector3d qhat = q / rho;
                j[0] = -qhat.dot(u);
                j[1] = -qhat.dot(v);
                j[3] = along * j[0];
                j[4] = along * j[1];
            }
            const Vec jp = j.template head<P>();
            jtj += jp * jp.transpose();
            jtr += jp * e;
            cost += e * e;
        }
        return cost;
    };
    auto update = [&](const CylinderEstimate& s, const Vec& d) {
        Eigen::Vector3d u;
        Eigen::Vector3d v;
        basis(s, u, v);
        Eigen::Vector3d axis = s.axis;
        if constexpr (P > 3) axis += d[3] * u;
        if constexpr (P > 4) axis += d[4] * v;
        return CylinderEstimate{s.point + d[0] * u + d[1] * v, axis.normalized(), s.radius + d[2]};
    };
    return sac_internal::LevenbergMarquardt<P>(x, linearize, update, max_iterations);
}

}  // namespace

bool RefineCylinder(const PointCloud& cloud, std::span<const Index> points,
                    const CylinderRefineParams& params, CylinderEstimate& x) {
    if (params.max_iterations < 0) {
        throw InvalidArgument(fmt::format("cylinder refinement max_iterations must be >= 0, got {}",
                                          params.max_iterations));
    }
    for (Index i : points) {
        if (i >= cloud.size()) {
            throw InvalidArgument(
                fmt::format("index {} is out of range for a cloud of {} points", i, cloud.size()));
        }
    }
    switch (params.freedom) {
        case CylinderAxisFreedom::kFree:
            return Solve<5>(cloud, points, params.up, false, params.max_iterations, x);
        case CylinderAxisFreedom::kAboutUp: {
            const double norm = params.up.norm();
            if (!params.up.allFinite() || !(norm > 0.0) || !std::isfinite(norm)) {
                throw InvalidArgument(fmt::format(
                    "cylinder refinement up must be finite and non-zero, got ({}, {}, {})",
                    params.up.x(), params.up.y(), params.up.z()));
            }
            return Solve<4>(cloud, points, params.up / norm, true, params.max_iterations, x);
        }
        case CylinderAxisFreedom::kFixed:
            return Solve<3>(cloud, points, params.up, false, params.max_iterations, x);
    }
    return false;
}

}  // namespace multicue

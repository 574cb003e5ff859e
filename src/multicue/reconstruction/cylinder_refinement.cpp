#include "multicue/reconstruction/cylinder_refinement.hpp"

#include <cmath>

namespace multicue::detail {

Indices SidePoints(const PointCloud& cloud, const Indices& usable, const CylinderEstimate& x,
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

void CentreOnPoints(const PointCloud& cloud, const Indices& points, CylinderEstimate& x) {
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    for (Index i : points) centroid += cloud.points[i].cast<double>();
    centroid /= static_cast<double>(points.size());
    x.point += (centroid - x.point).dot(x.axis) * x.axis;
}

}  // namespace multicue::detail

#include "multicue/mapping/fixtures.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>
#include <Eigen/Eigenvalues>

#include "multicue/core/exceptions.hpp"
#include "multicue/segmentation/euclidean_clustering.hpp"
#include "multicue/segmentation/sac_circle.hpp"
#include "multicue/segmentation/sac_line.hpp"

namespace multicue::mapping {

void FixtureParams::Validate() const {
    auto positive = [](const char* name, float v) {
        if (!(v > 0.0f) || !std::isfinite(v)) {
            throw InvalidArgument(fmt::format("fixtures: {} must be > 0, got {}", name, v));
        }
    };
    positive("max_height", max_height);
    positive("cluster_tolerance", cluster_tolerance);
    positive("max_diameter", max_diameter);
    positive("max_protrusion_extent", max_protrusion_extent);
    positive("min_handle_length", min_handle_length);
    positive("min_elongation", min_elongation);
    positive("max_knob_size", max_knob_size);
    positive("line_threshold", line_threshold);
    positive("circle_threshold", circle_threshold);
    if (!(min_height >= 0.0f && min_height < max_height)) {
        throw InvalidArgument(fmt::format(
            "fixtures: need 0 <= min_height < max_height, got {} and {}", min_height, max_height));
    }
    if (!(face_margin >= 0.0f)) {
        throw InvalidArgument(
            fmt::format("fixtures: face_margin must be >= 0, got {}", face_margin));
    }
    if (min_points < 3) {
        throw InvalidArgument(fmt::format("fixtures: min_points must be >= 3, got {}", min_points));
    }
}

bool ClassifyFixture(const PointCloud& cloud, const Indices& cluster, const PlanarComponent& face,
                     const RoomFrame& frame, const FixtureParams& p, Fixture& out) {
    if (cluster.size() < 3) return false;
    const Eigen::Vector3f n = face.plane.head<3>();
    const Eigen::Vector3f u = PlaneU(face, frame), v = PlaneV(face, frame);
    Eigen::Vector3f centroid = Eigen::Vector3f::Zero();
    for (const Index i : cluster) centroid += cloud.points[i];
    centroid /= static_cast<float>(cluster.size());
    // The footprint on the face: principal axes of the projected points.
    Eigen::Matrix2f cov = Eigen::Matrix2f::Zero();
    float protrusion = 0.0f, dmin = std::numeric_limits<float>::infinity(), dmax = -dmin;
    for (const Index i : cluster) {
        const Eigen::Vector3f d = cloud.points[i] - centroid;
        const Eigen::Vector2f q(d.dot(u), d.dot(v));
        cov += q * q.transpose();
        const float h = n.dot(cloud.points[i]) + face.plane.w();
        protrusion = std::max(protrusion, h);
        dmin = std::min(dmin, h);
        dmax = std::max(dmax, h);
    }
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix2f> eig(cov);
    const Eigen::Vector2f e1 = eig.eigenvectors().col(1);  // largest eigenvalue last
    const Eigen::Vector2f e2 = eig.eigenvectors().col(0);
    float a0 = std::numeric_limits<float>::infinity(), a1 = -a0, b0 = a0, b1 = -a0;
    for (const Index i : cluster) {
        const Eigen::Vector3f d = cloud.points[i] - centroid;
        const Eigen::Vector2f q(d.dot(u), d.dot(v));
        a0 = std::min(a0, q.dot(e1));
        a1 = std::max(a1, q.dot(e1));
        b0 = std::min(b0, q.dot(e2));
        b1 = std::max(b1, q.dot(e2));
    }
    const float length = a1 - a0, width = std::max(b1 - b0, 0.004f);
    if (dmax - dmin > p.max_protrusion_extent) return false;
    // RANSAC line and circle on the cluster: the handle's bar, the knob's rim.
    LineFitParams lp;
    lp.sac.distance_threshold = p.line_threshold;
    lp.sac.seed = p.seed;
    lp.sac.num_threads = 1;
    lp.sac.max_iterations = 200;
    const LineFit line = FitLine(cloud, cluster, lp);
    Circle3dFitParams cp;
    cp.sac.distance_threshold = p.circle_threshold;
    cp.sac.seed = p.seed;
    cp.sac.num_threads = 1;
    cp.sac.max_iterations = 200;
    cp.max_radius = p.max_knob_size / 2;
    cp.viewpoint = centroid + n;
    const Circle3dFit circle = FitCircle3d(cloud, cluster, cp);
    const auto count = static_cast<float>(cluster.size());
    out.line_inlier_ratio = line.found ? static_cast<float>(line.inliers.size()) / count : 0.0f;
    out.circle_inlier_ratio =
        circle.found ? static_cast<float>(circle.inliers.size()) / count : 0.0f;
    out.center = centroid;
    out.length = length;
    out.width = width;
    out.protrusion = protrusion;
    out.indices = cluster;
    const Eigen::Vector3f dir = (e1.x() * u + e1.y() * v).normalized();
    if (length >= p.min_handle_length && length / width >= p.min_elongation) {
        out.type = FixtureType::kHandle;
        // The bar's direction: the line's, once it lies along the footprint (a line fitted to
        // the stand-offs of a short handle can point away from the face).
        Eigen::Vector3f d = dir;
        if (line.found) {
            Eigen::Vector3f l = line.direction - line.direction.dot(n) * n;
            if (l.norm() > 0.5f && std::abs(l.normalized().dot(dir)) > 0.9f) d = l.normalized();
        }
        // A fixed sign: handles point along +u or +v.
        if (d.dot(u) + d.dot(v) * 1e-3f < 0) d = -d;
        out.direction = d;
        return true;
    }
    if (std::max(length, width) <= p.max_knob_size) {
        out.type = FixtureType::kKnob;
        out.direction = n;
        return true;
    }
    return false;
}

FixtureResult DetectFixtures(const PointCloud& cloud, const RoomFrame& frame,
                             const RoomStructure& s, const FixtureParams& p) {
    p.Validate();
    FixtureResult result;
    if (cloud.empty()) return result;
    // Each free point goes to the nearest face whose prism holds it.
    std::vector<Indices> prism(s.components.size());
    std::vector<int> faces;
    for (std::size_t c = 0; c < s.components.size(); ++c) {
        if (s.components[c].label == MapClass::kFace) faces.push_back(static_cast<int>(c));
    }
    if (faces.empty()) return result;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        if (!cloud.IsFinite(i) || (i < s.on_plane.size() && s.on_plane[i])) continue;
        const Eigen::Vector3f& x = cloud.points[i];
        int best = -1;
        float best_h = std::numeric_limits<float>::infinity();
        for (const int f : faces) {
            const PlanarComponent& c = s.components[static_cast<std::size_t>(f)];
            const float h = c.plane.head<3>().dot(x) + c.plane.w();
            if (h < p.min_height || h > p.max_height || h >= best_h) continue;
            const Eigen::Vector2f q = PlaneCoordinates(c, frame, x);
            if ((q.array() < c.min.array() - p.face_margin).any() ||
                (q.array() > c.max.array() + p.face_margin).any()) {
                continue;
            }
            best = f;
            best_h = h;
        }
        if (best >= 0) prism[static_cast<std::size_t>(best)].push_back(static_cast<Index>(i));
    }
    for (const int f : faces) {
        const Indices& region = prism[static_cast<std::size_t>(f)];
        if (region.size() < p.min_points) continue;
        EuclideanClusteringParams cp;
        cp.tolerance = p.cluster_tolerance;
        cp.min_cluster_size = p.min_points;
        cp.subset = region;
        const ClusteringResult clusters = EuclideanClusteringGrid(cloud, cp);
        const PlanarComponent& face = s.components[static_cast<std::size_t>(f)];
        for (const Indices& cluster : clusters.clusters) {
            Eigen::AlignedBox3f box;
            for (const Index i : cluster) box.extend(cloud.points[i]);
            if (box.sizes().norm() > p.max_diameter) {
                ++result.too_large;
                continue;
            }
            Fixture fx;
            fx.face = f;
            if (ClassifyFixture(cloud, cluster, face, frame, p, fx)) {
                result.fixtures.push_back(std::move(fx));
            } else {
                ++result.unclassified;
            }
        }
    }
    return result;
}

}  // namespace multicue::mapping

#include "multicue/mapping/fixtures.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string_view>
#include <unordered_map>
#include <unordered_set>

#include <fmt/format.h>
#include <Eigen/Eigenvalues>

#include "multicue/core/exceptions.hpp"
#include "multicue/core/logging.hpp"
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
    positive("min_protrusion", min_protrusion);
    positive("footprint_reach", footprint_reach);
    if (!(aligned_noise >= 0.0f)) {
        throw InvalidArgument(
            fmt::format("fixtures: aligned_noise must be >= 0, got {}", aligned_noise));
    }
    positive("attach_cell", attach_cell);
    positive("min_blocking_area", min_blocking_area);
    if (!(max_attached_share >= 0.0f && max_attached_share <= 1.0f)) {
        throw InvalidArgument(fmt::format("fixtures: max_attached_share must be in [0, 1], got {}",
                                          max_attached_share));
    }
    if (!(merge_gap >= 0.0f)) {
        throw InvalidArgument(fmt::format("fixtures: merge_gap must be >= 0, got {}", merge_gap));
    }
    positive("min_handle_length", min_handle_length);
    positive("min_elongation", min_elongation);
    positive("max_knob_size", max_knob_size);
    if (!(min_knob_size >= 0.0f) || !(min_knob_roundness >= 0.0f && min_knob_roundness <= 1.0f) ||
        border_px < 0) {
        throw InvalidArgument(fmt::format(
            "fixtures: need min_knob_size >= 0, min_knob_roundness in [0, 1], border_px >= 0 (got "
            "{}, {}, {})",
            min_knob_size, min_knob_roundness, border_px));
    }
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
    if (dmax - dmin > p.max_protrusion_extent || protrusion < p.min_protrusion) return false;
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
    if (std::max(length, width) <= p.max_knob_size && width >= p.min_knob_size &&
        width >= p.min_knob_roundness * length) {
        out.type = FixtureType::kKnob;
        out.direction = n;
        return true;
    }
    return false;
}

FixtureResult DetectFixtures(const PointCloud& cloud, const RoomFrame& frame,
                             const RoomStructure& s, const FixtureParams& p,
                             const std::vector<float>& ranges) {
    p.Validate();
    FixtureResult result;
    if (cloud.empty()) return result;
    if (!ranges.empty() && ranges.size() != cloud.size()) {
        throw InvalidArgument(
            fmt::format("fixtures: {} ranges for {} points", ranges.size(), cloud.size()));
    }
    // Each free point goes to the nearest face whose prism holds it.
    std::vector<Indices> prism(s.components.size());
    std::vector<int> faces;
    for (std::size_t c = 0; c < s.components.size(); ++c) {
        if (s.components[c].label == MapClass::kFace) faces.push_back(static_cast<int>(c));
    }
    if (faces.empty()) return result;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        if (!cloud.IsFinite(i)) continue;
        // The orientation of the plane the point lies on; only planes of some size block (a flat
        // handle's sides are planes too, but small ones).
        int axis = i < s.plane_axis.size() ? s.plane_axis[i] : -1;
        const int comp = i < s.point_component.size() ? s.point_component[i] : -1;
        const bool blocking =
            comp >= 0 && s.components[static_cast<std::size_t>(comp)].area >= p.min_blocking_area;
        if (!blocking && axis >= 0 && comp >= 0) axis = -1;
        const Eigen::Vector3f& x = cloud.points[i];
        const float r = ranges.empty() ? (x - cloud.sensor_origin).norm() : ranges[i];
        const float aligned_min = std::max(p.min_height, p.aligned_noise * r * r);
        int best = -1;
        float best_h = std::numeric_limits<float>::infinity();
        bool on_surface = false;
        for (const int f : faces) {
            const PlanarComponent& c = s.components[static_cast<std::size_t>(f)];
            // Points on planes of other orientations (a worktop, a side panel) are no fixtures.
            if (blocking && axis != c.axis) continue;
            const float h = c.plane.head<3>().dot(x) + c.plane.w();
            if (h > p.max_height || h < -p.min_height || h >= best_h) continue;
            const Eigen::Vector2f q = PlaneCoordinates(c, frame, x);
            if ((q.array() < c.min.array() - p.face_margin).any() ||
                (q.array() > c.max.array() + p.face_margin).any()) {
                continue;
            }
            // A point on some face's surface (the edge of a door standing in front of the
            // frame, where normals bend) is no fixture point.
            if (h < p.min_height) {
                if (c.area < p.min_blocking_area) continue;
                on_surface = true;
                break;
            }
            if (axis == c.axis && h < aligned_min) continue;
            best = f;
            best_h = h;
        }
        if (best >= 0 && !on_surface) {
            prism[static_cast<std::size_t>(best)].push_back(static_cast<Index>(i));
        }
    }
    // Cells holding points of axis-aligned planes, with the axes present (bit k for axis k).
    std::unordered_map<std::uint64_t, std::uint8_t> plane_cells;
    auto cell_key = [&](const Eigen::Vector3f& x) {
        const Eigen::Vector3f q = frame.axes.transpose() * x / p.attach_cell;
        auto c = [](float v) {
            return static_cast<std::uint64_t>(std::floor(v) + (1 << 20)) & 0x1fffff;
        };
        return (c(q.x()) << 42) | (c(q.y()) << 21) | c(q.z());
    };
    for (const PlanarComponent& c : s.components) {
        if (c.area < p.min_blocking_area) continue;
        for (const Index i : c.indices) plane_cells[cell_key(cloud.points[i])] |= 1u << c.axis;
    }
    auto attached_share = [&](const Indices& cluster, int axis) {
        std::size_t attached = 0;
        const std::uint8_t others = static_cast<std::uint8_t>(7u & ~(1u << axis));
        for (const Index i : cluster) {
            const Eigen::Vector3f q = frame.axes.transpose() * cloud.points[i] / p.attach_cell;
            bool found = false;
            for (int dx = -1; dx <= 1 && !found; ++dx) {
                for (int dy = -1; dy <= 1 && !found; ++dy) {
                    for (int dz = -1; dz <= 1 && !found; ++dz) {
                        const Eigen::Vector3f x =
                            frame.axes * ((q + Eigen::Vector3f(dx, dy, dz)) * p.attach_cell);
                        const auto it = plane_cells.find(cell_key(x));
                        found = it != plane_cells.end() && (it->second & others) != 0;
                    }
                }
            }
            attached += found;
        }
        return static_cast<float>(attached) /
               static_cast<float>(std::max<std::size_t>(1, cluster.size()));
    };
    for (const int f : faces) {
        const Indices& region = prism[static_cast<std::size_t>(f)];
        if (region.size() < p.min_points) continue;
        EuclideanClusteringParams cp;
        cp.tolerance = p.cluster_tolerance;
        cp.min_cluster_size = p.min_points;
        cp.subset = region;
        const ClusteringResult clusters = EuclideanClusteringGrid(cloud, cp);
        const PlanarComponent& face = s.components[static_cast<std::size_t>(f)];
        // Occupied cells of the face, to check that a fixture stands in front of it.
        const float cell = p.footprint_reach / 3;
        std::unordered_set<std::uint64_t> occupied;
        auto key = [](std::int64_t a, std::int64_t b) {
            return (static_cast<std::uint64_t>(a + (1 << 30)) << 32) ^
                   static_cast<std::uint64_t>(b + (1 << 30));
        };
        for (const Index i : face.indices) {
            const Eigen::Vector2f q = PlaneCoordinates(face, frame, cloud.points[i]);
            occupied.insert(key(static_cast<std::int64_t>(std::floor(q.x() / cell)),
                                static_cast<std::int64_t>(std::floor(q.y() / cell))));
        }
        auto occupied_near = [&](const Eigen::Vector2f& q, int reach) {
            const auto cu = static_cast<std::int64_t>(std::floor(q.x() / cell));
            const auto cv = static_cast<std::int64_t>(std::floor(q.y() / cell));
            for (std::int64_t du = -reach; du <= reach; ++du) {
                for (std::int64_t dv = -reach; dv <= reach; ++dv) {
                    if (occupied.count(key(cu + du, cv + dv))) return true;
                }
            }
            return false;
        };
        // The face lies behind the fixture and around it (a worktop's edge has the worktop
        // above it, not the face).
        auto in_front = [&](const Indices& cluster) {
            Eigen::Vector2f lo = Eigen::Vector2f::Constant(std::numeric_limits<float>::infinity());
            Eigen::Vector2f hi = -lo;
            for (const Index i : cluster) {
                const Eigen::Vector2f q = PlaneCoordinates(face, frame, cloud.points[i]);
                lo = lo.cwiseMin(q);
                hi = hi.cwiseMax(q);
            }
            const Eigen::Vector2f mid = (lo + hi) / 2;
            const float d = p.footprint_reach / 2;
            // Three sides suffice: seen at a slant, a fixture's shadow hides the face on one.
            const int sides =
                occupied_near({lo.x() - d, mid.y()}, 1) + occupied_near({hi.x() + d, mid.y()}, 1) +
                occupied_near({mid.x(), lo.y() - d}, 1) + occupied_near({mid.x(), hi.y() + d}, 1);
            return occupied_near(mid, 3) && sides >= 3;
        };
        // Pieces of one fixture (a handle's bar and its posts, split by a shadow) whose boxes
        // nearly touch become one cluster.
        std::vector<Indices> merged = clusters.clusters;
        for (bool changed = true; changed;) {
            changed = false;
            for (std::size_t a = 0; a < merged.size() && !changed; ++a) {
                Eigen::AlignedBox3f ba;
                for (const Index i : merged[a]) ba.extend(cloud.points[i]);
                for (std::size_t b = a + 1; b < merged.size(); ++b) {
                    Eigen::AlignedBox3f bb;
                    for (const Index i : merged[b]) bb.extend(cloud.points[i]);
                    const Eigen::Vector3f gap =
                        (ba.min() - bb.max()).cwiseMax(bb.min() - ba.max()).cwiseMax(0.0f);
                    if (gap.norm() <= p.merge_gap) {
                        merged[a].insert(merged[a].end(), merged[b].begin(), merged[b].end());
                        std::sort(merged[a].begin(), merged[a].end());
                        merged.erase(merged.begin() + static_cast<long>(b));
                        changed = true;
                        break;
                    }
                }
            }
        }
        for (const Indices& cluster : merged) {
            Eigen::AlignedBox3f box;
            for (const Index i : cluster) box.extend(cloud.points[i]);
            const char* reason = nullptr;
            Fixture fx;
            fx.face = f;
            if (box.sizes().norm() > p.max_diameter) {
                reason = "too large";
                ++result.too_large;
            }
            if (reason == nullptr && cloud.IsOrganized() && p.border_px > 0) {
                const auto b = static_cast<std::uint32_t>(p.border_px);
                for (const Index i : cluster) {
                    const std::uint32_t u = i % cloud.width, v = i / cloud.width;
                    if (u < b || v < b || u + b >= cloud.width || v + b >= cloud.height) {
                        reason = "image border";
                    }
                }
            }
            if (reason == nullptr && !ClassifyFixture(cloud, cluster, face, frame, p, fx)) {
                reason = "shape";
            }
            if (reason == nullptr && !in_front(cluster)) reason = "not in front of the face";
            if (reason == nullptr && attached_share(cluster, face.axis) > p.max_attached_share) {
                reason = "attached to another plane";
            }
            if (reason == nullptr) {
                result.fixtures.push_back(std::move(fx));
                continue;
            }
            if (std::string_view(reason) != "too large") ++result.unclassified;
            result.rejected.push_back({box.center(), cluster.size(), reason});
        }
    }
    return result;
}

}  // namespace multicue::mapping

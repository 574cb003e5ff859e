#include "multicue/mapping/room_structure.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <unordered_set>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/core/parallel.hpp"
#include "multicue/segmentation/euclidean_clustering.hpp"

namespace multicue::mapping {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

/// One plane: axis, offset along it and its points.
struct AxisPlane {
    int axis = 0;
    float offset = 0.0f;
    float sign = 1.0f;  ///< normal = sign * axis (facing the sensors)
    Indices points;
};

/// Planes along one axis: peaks of the histogram of the aligned points' coordinates.
std::vector<AxisPlane> PlanesAlong(const PointCloud& cloud, const Eigen::Vector3f& a, int axis,
                                   const RoomStructureParams& p, float cos_n,
                                   const std::vector<float>& tolerance) {
    Indices cand;
    std::vector<float> coord, tol;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const auto& n = cloud.normals[i];
        if (!cloud.IsFinite(i) || !n.allFinite()) continue;
        if (std::abs(n.dot(a)) < cos_n) continue;
        cand.push_back(static_cast<Index>(i));
        coord.push_back(cloud.points[i].dot(a));
        tol.push_back(tolerance[i]);
    }
    std::vector<AxisPlane> planes;
    if (cand.size() < p.min_plane_points) return planes;
    const auto [lo_it, hi_it] = std::minmax_element(coord.begin(), coord.end());
    const float lo = *lo_it - p.bin_size, hi = *hi_it + p.bin_size;
    const auto bins = static_cast<std::size_t>(std::ceil((hi - lo) / p.bin_size)) + 1;
    if (bins > 20'000'000) {
        throw DataError(fmt::format("room structure: the cloud spans {} m along an axis", hi - lo));
    }
    // Histogram summed over the plane's thickness: a bin counts the points within +-threshold.
    std::vector<std::uint32_t> hist(bins, 0);
    for (const float c : coord) ++hist[static_cast<std::size_t>((c - lo) / p.bin_size)];
    const int half = std::max(1, static_cast<int>(std::lround(p.distance_threshold / p.bin_size)));
    std::vector<std::uint32_t> window(bins, 0);
    std::uint64_t run = 0;
    for (std::size_t b = 0; b < bins + static_cast<std::size_t>(half); ++b) {
        if (b < bins) run += hist[b];
        if (b >= static_cast<std::size_t>(2 * half + 1)) run -= hist[b - 2 * half - 1];
        if (b >= static_cast<std::size_t>(half)) window[b - half] = static_cast<std::uint32_t>(run);
    }
    std::vector<std::uint8_t> claimed(cand.size(), 0);
    std::vector<std::uint8_t> blocked(bins, 0);
    for (int guard = 0; guard < 200; ++guard) {
        std::size_t best = bins;
        std::uint32_t best_count = 0;
        for (std::size_t b = 0; b < bins; ++b) {
            if (!blocked[b] && window[b] > best_count) {
                best_count = window[b];
                best = b;
            }
        }
        if (best == bins || best_count < p.min_plane_points) break;
        float offset = lo + (static_cast<float>(best) + 0.5f) * p.bin_size;
        // Two passes: the median of the points around the peak, then the points around it.
        AxisPlane plane;
        plane.axis = axis;
        for (int pass = 0; pass < 2; ++pass) {
            std::vector<float> near;
            for (std::size_t j = 0; j < cand.size(); ++j) {
                if (!claimed[j] && std::abs(coord[j] - offset) <= p.distance_threshold) {
                    near.push_back(coord[j]);
                }
            }
            if (near.empty()) break;
            std::nth_element(near.begin(), near.begin() + static_cast<long>(near.size() / 2),
                             near.end());
            offset = near[near.size() / 2];
        }
        plane.offset = offset;
        double sign_sum = 0.0;
        for (std::size_t j = 0; j < cand.size(); ++j) {
            if (claimed[j] || std::abs(coord[j] - offset) > tol[j]) continue;
            claimed[j] = 1;
            plane.points.push_back(cand[j]);
            sign_sum += cloud.normals[cand[j]].dot(a);
        }
        plane.sign = sign_sum >= 0.0 ? 1.0f : -1.0f;
        const auto b0 = static_cast<long>((offset - p.distance_threshold - lo) / p.bin_size) - 1;
        const auto b1 = static_cast<long>((offset + p.distance_threshold - lo) / p.bin_size) + 1;
        for (long b = std::max(0L, b0); b <= std::min(static_cast<long>(bins) - 1, b1); ++b) {
            blocked[static_cast<std::size_t>(b)] = 1;
        }
        if (plane.points.size() >= p.min_plane_points) planes.push_back(std::move(plane));
    }
    return planes;
}

float OccupiedArea(const std::vector<Eigen::Vector2f>& uv, float cell) {
    std::unordered_set<std::uint64_t> cells;
    for (const auto& q : uv) {
        const auto x = static_cast<std::int64_t>(std::floor(q.x() / cell)) + (1 << 30);
        const auto y = static_cast<std::int64_t>(std::floor(q.y() / cell)) + (1 << 30);
        cells.insert((static_cast<std::uint64_t>(x) << 32) ^ static_cast<std::uint64_t>(y));
    }
    return static_cast<float>(cells.size()) * cell * cell;
}

/// Horizontal distance from a horizontal component's box to a vertical plane.
float DistanceToPlane(const PlanarComponent& h, const RoomFrame& f, const PlanarComponent& wall) {
    float best = std::numeric_limits<float>::infinity();
    const float z = -h.plane.w();  // height along up of the horizontal plane
    for (const float u : {h.min.x(), h.max.x()}) {
        for (const float v : {h.min.y(), h.max.y()}) {
            const Eigen::Vector3f p = f.axes.col(0) * u + f.axes.col(1) * v + f.Up() * z;
            best = std::min(best, std::abs(wall.plane.head<3>().dot(p) + wall.plane.w()));
        }
    }
    return best;
}

/// Whether a vertical component at least `worktop_face_height` tall stands under the horizontal
/// component `h` (at height `height` along up), its top within 15 cm below it, at least 15 cm
/// wide, filling half of its box, along at least 30 cm or half of its own width or of the
/// counter's length. The face need not lie under the counter's edge: a worktop may overhang its
/// cupboards by a dozen centimetres, and the box of an L-shaped worktop has no edge above the
/// fronts of one of its runs. A table's legs are too narrow, its apron too low.
bool FaceUnder(const PlanarComponent& h, float height, const RoomFrame& f,
               const std::vector<PlanarComponent>& components, const RoomStructureParams& p) {
    constexpr float kMargin = 0.1f, kDrop = 0.15f, kOverlap = 0.3f, kMinWidth = 0.15f,
                    kMinFill = 0.5f;
    for (const PlanarComponent& v : components) {
        if (v.axis == 2 || v.label == MapClass::kWall || v.indices.empty()) continue;
        if (v.max.y() > height + 0.05f || v.max.y() < height - kDrop ||
            v.max.y() - v.min.y() < p.worktop_face_height) {
            continue;
        }
        // The face's position along its axis k and its extent along the other horizontal axis.
        const int k = v.axis, j = 1 - v.axis;
        const Eigen::Vector3f n = v.plane.head<3>();
        const float pos = -v.plane.w() / n.dot(f.axes.col(k));
        if (pos < h.min[k] - kMargin || pos > h.max[k] + kMargin) continue;
        const float s = f.Up().cross(n).dot(f.axes.col(j));
        const float lo = s > 0.0f ? v.min.x() : -v.max.x(), hi = s > 0.0f ? v.max.x() : -v.min.x();
        if (hi - lo < kMinWidth) continue;
        // Solid: a table's legs and apron in one plane make a frame, not a front.
        if (v.area < kMinFill * (hi - lo) * (v.max.y() - v.min.y())) continue;
        const float overlap = std::min(hi, h.max[j]) - std::max(lo, h.min[j]);
        if (overlap >= std::min({kOverlap, 0.5f * (hi - lo), 0.5f * (h.max[j] - h.min[j])}))
            return true;
    }
    return false;
}

}  // namespace

void RoomStructureParams::Validate() const {
    auto positive = [](const char* name, float v) {
        if (!(v > 0.0f) || !std::isfinite(v)) {
            throw InvalidArgument(fmt::format("room structure: {} must be > 0, got {}", name, v));
        }
    };
    if (!(normal_angle_deg > 0.0f && normal_angle_deg < 60.0f)) {
        throw InvalidArgument(fmt::format(
            "room structure: normal_angle_deg must be in (0, 60), got {}", normal_angle_deg));
    }
    positive("distance_threshold", distance_threshold);
    positive("bin_size", bin_size);
    positive("component_tolerance", component_tolerance);
    positive("cell_size", cell_size);
    positive("min_room_height", min_room_height);
    positive("behind_margin", behind_margin);
    positive("max_distance_threshold", max_distance_threshold);
    positive("min_floor_area", min_floor_area);
    positive("min_ceiling_area", min_ceiling_area);
    if (!(worktop_face_height >= 0.0f && worktop_face_height <= 3.0f)) {
        throw InvalidArgument(
            fmt::format("room structure: worktop_face_height must be in [0, 3] m, got {}",
                        worktop_face_height));
    }
    if (!(range_noise >= 0.0f) || !(min_floor_depth >= 0.0f)) {
        throw InvalidArgument(fmt::format(
            "room structure: range_noise and min_floor_depth must be >= 0, got {} and {}",
            range_noise, min_floor_depth));
    }
    if (min_plane_points < 3 || min_component_points < 3) {
        throw InvalidArgument(
            "room structure: min_plane_points and min_component_points must be "
            ">= 3");
    }
    if (!(min_counter_height < max_counter_height)) {
        throw InvalidArgument(
            fmt::format("room structure: min_counter_height {} must be below max_counter_height {}",
                        min_counter_height, max_counter_height));
    }
    if (!(max_behind_share >= 0.0f && max_behind_share < 1.0f)) {
        throw InvalidArgument(fmt::format(
            "room structure: max_behind_share must be in [0, 1), got {}", max_behind_share));
    }
    if (!(max_below_floor_share >= 0.0f && max_below_floor_share <= 1.0f) ||
        !(floor_below_margin >= 0.0f)) {
        throw InvalidArgument(fmt::format(
            "room structure: need max_below_floor_share in [0, 1] and floor_below_margin >= 0, "
            "got {} and {}",
            max_below_floor_share, floor_below_margin));
    }
    if (num_threads < 0) {
        throw InvalidArgument(
            fmt::format("room structure: num_threads must be >= 0, got {}", num_threads));
    }
}

Eigen::Vector3f PlaneV(const PlanarComponent& c, const RoomFrame& frame) {
    return c.axis == 2 ? Eigen::Vector3f(frame.axes.col(1)) : frame.Up();
}

Eigen::Vector3f PlaneU(const PlanarComponent& c, const RoomFrame& frame) {
    if (c.axis == 2) return frame.axes.col(0);
    return frame.Up().cross(Eigen::Vector3f(c.plane.head<3>()));
}

Eigen::Vector2f PlaneCoordinates(const PlanarComponent& c, const RoomFrame& frame,
                                 const Eigen::Vector3f& p) {
    return {p.dot(PlaneU(c, frame)), p.dot(PlaneV(c, frame))};
}

RoomStructure SegmentRoomStructure(const PointCloud& cloud, const RoomFrame& frame,
                                   const RoomStructureParams& p, const std::vector<float>& ranges) {
    p.Validate();
    RoomStructure out;
    out.floor_height = out.ceiling_height = kNaN;
    out.point_component.assign(cloud.size(), -1);
    out.plane_axis.assign(cloud.size(), -1);
    if (cloud.empty()) return out;
    if (cloud.normals.size() != cloud.size()) {
        throw DataError(fmt::format("room structure: the cloud has {} normals for {} points",
                                    cloud.normals.size(), cloud.size()));
    }
    if (!ranges.empty() && ranges.size() != cloud.size()) {
        throw InvalidArgument(
            fmt::format("room structure: {} ranges for {} points", ranges.size(), cloud.size()));
    }
    // Each point's plane tolerance, growing with its range.
    std::vector<float> tolerance(cloud.size(), p.distance_threshold);
    if (p.range_noise > 0.0f) {
        ParallelFor(cloud.size(), p.num_threads, [&](std::size_t i) {
            const float r =
                ranges.empty() ? (cloud.points[i] - cloud.sensor_origin).norm() : ranges[i];
            if (std::isfinite(r)) {
                tolerance[i] = std::clamp(p.range_noise * r * r, p.distance_threshold,
                                          p.max_distance_threshold);
            }
        });
    }
    const float cos_n = std::cos(p.normal_angle_deg * 0.017453292519943295f);
    const Eigen::Vector3f up = frame.Up();

    // Planes along each axis, then their connected components.
    struct PlaneInfo {
        AxisPlane plane;
        std::vector<int> components;
    };
    std::vector<PlaneInfo> planes;
    // The axes in parallel, joined in axis order (a point on planes of two axes keeps the later).
    std::array<std::vector<AxisPlane>, 3> along;
    ParallelFor(
        3, p.num_threads,
        [&](std::size_t k) {
            along[k] = PlanesAlong(cloud, frame.axes.col(static_cast<int>(k)), static_cast<int>(k),
                                   p, cos_n, tolerance);
        },
        1);
    for (int k = 0; k < 3; ++k) {
        for (auto& pl : along[static_cast<std::size_t>(k)]) {
            for (const Index i : pl.points) out.plane_axis[i] = static_cast<std::int8_t>(k);
            planes.push_back({std::move(pl), {}});
        }
    }
    // Each plane's connected components in parallel, numbered in plane order.
    std::vector<std::vector<PlanarComponent>> plane_components(planes.size());
    ParallelFor(
        planes.size(), p.num_threads,
        [&](std::size_t pi) {
            const AxisPlane& pl = planes[pi].plane;
            EuclideanClusteringParams cp;
            cp.tolerance = p.component_tolerance;
            cp.min_cluster_size = p.min_component_points;
            cp.subset = pl.points;
            const ClusteringResult clusters = EuclideanClusteringGrid(cloud, cp);
            for (const Indices& cluster : clusters.clusters) {
                PlanarComponent c;
                c.axis = pl.axis;
                const Eigen::Vector3f n = pl.sign * frame.axes.col(pl.axis);
                c.plane = Eigen::Vector4f(n.x(), n.y(), n.z(), -pl.sign * pl.offset);
                c.indices = cluster;
                std::vector<Eigen::Vector2f> uv;
                uv.reserve(cluster.size());
                c.min = Eigen::Vector2f::Constant(std::numeric_limits<float>::infinity());
                c.max = -c.min;
                for (const Index i : cluster) {
                    uv.push_back(PlaneCoordinates(c, frame, cloud.points[i]));
                    c.min = c.min.cwiseMin(uv.back());
                    c.max = c.max.cwiseMax(uv.back());
                }
                c.area = OccupiedArea(uv, p.cell_size);
                plane_components[pi].push_back(std::move(c));
            }
        },
        1);
    for (std::size_t pi = 0; pi < planes.size(); ++pi) {
        for (PlanarComponent& c : plane_components[pi]) {
            planes[pi].components.push_back(static_cast<int>(out.components.size()));
            out.components.push_back(std::move(c));
        }
    }
    auto plane_area = [&](const PlaneInfo& pl) {
        float a = 0.0f;
        for (const int c : pl.components) a += out.components[static_cast<std::size_t>(c)].area;
        return a;
    };

    // Floor: the lowest large horizontal plane seen from above; ceiling: the highest large one
    // seen from below, high enough above the floor.
    const PlaneInfo* floor = nullptr;
    const PlaneInfo* ceiling = nullptr;
    const float sensor_height = cloud.HasSensorPosition() ? cloud.sensor_origin.dot(up)
                                                          : std::numeric_limits<float>::infinity();
    std::size_t num_finite = 0;
    for (std::size_t i = 0; i < cloud.size(); ++i) num_finite += cloud.IsFinite(i);
    const auto finite = static_cast<float>(num_finite);
    // The points more than `margin` behind a plane (on the side its normal points away from).
    auto behind = [&](const PlaneInfo& pl, float margin) {
        const Eigen::Vector3f n = pl.plane.sign * frame.axes.col(pl.plane.axis);
        const float d = -pl.plane.sign * pl.plane.offset;
        std::size_t count = 0;
        for (std::size_t i = 0; i < cloud.size(); ++i) {
            if (cloud.IsFinite(i)) count += n.dot(cloud.points[i]) + d < -margin;
        }
        return static_cast<float>(count);
    };
    for (const auto& pl : planes) {
        if (pl.plane.axis != 2 || pl.plane.sign <= 0 || plane_area(pl) < p.min_floor_area) continue;
        if (pl.plane.offset > sensor_height - p.min_floor_depth) continue;
        if (floor && pl.plane.offset >= floor->plane.offset) continue;
        // The floor has (almost) nothing below it; a table top taken for it, where the view
        // holds too little floor, has the furniture under it.
        if (behind(pl, p.floor_below_margin) > p.max_below_floor_share * finite) continue;
        floor = &pl;
    }
    for (const auto& pl : planes) {
        if (pl.plane.axis != 2 || pl.plane.sign > 0 || plane_area(pl) < p.min_ceiling_area) {
            continue;
        }
        if (floor && pl.plane.offset < floor->plane.offset + p.min_room_height) continue;
        if (!ceiling || pl.plane.offset > ceiling->plane.offset) ceiling = &pl;
    }
    if (floor) {
        out.floor_height = floor->plane.offset;
        for (const int c : floor->components) {
            out.components[static_cast<std::size_t>(c)].label = MapClass::kFloor;
        }
    }
    if (ceiling) {
        out.ceiling_height = ceiling->plane.offset;
        for (const int c : ceiling->components) {
            out.components[static_cast<std::size_t>(c)].label = MapClass::kCeiling;
        }
    }

    // Walls: vertical planes reaching the ceiling; with no ceiling in view, large vertical planes
    // with (almost) nothing behind them.
    std::vector<const PlaneInfo*> walls;
    for (const auto& pl : planes) {
        if (pl.plane.axis == 2 || pl.components.empty() || plane_area(pl) < p.min_wall_area) {
            continue;
        }
        bool wall = false;
        if (ceiling) {
            for (const int c : pl.components) {
                const auto& comp = out.components[static_cast<std::size_t>(c)];
                wall = wall || comp.max.y() >= out.ceiling_height - p.wall_ceiling_gap;
            }
        }
        if (!wall) wall = behind(pl, p.behind_margin) <= p.max_behind_share * finite;
        if (!wall) continue;
        walls.push_back(&pl);
        for (const int c : pl.components) {
            out.components[static_cast<std::size_t>(c)].label = MapClass::kWall;
        }
    }

    // Counters (worktops along walls, free-standing tables) and furniture faces.
    for (auto& c : out.components) {
        if (c.label != MapClass::kNone) continue;
        if (c.axis == 2) {
            const float h = -c.plane.w() * (c.plane.head<3>().dot(up) > 0 ? 1.0f : -1.0f);
            const float above = std::isnan(out.floor_height) ? h : h - out.floor_height;
            if (c.plane.head<3>().dot(up) < 0 || above < p.min_counter_height ||
                above > p.max_counter_height || c.area < p.min_counter_area) {
                continue;
            }
            bool by_wall = false;
            for (const PlaneInfo* w : walls) {
                for (const int wc : w->components) {
                    by_wall =
                        by_wall ||
                        DistanceToPlane(c, frame, out.components[static_cast<std::size_t>(wc)]) <=
                            p.worktop_wall_distance;
                }
            }
            c.label = by_wall || (p.worktop_face_height > 0.0f &&
                                  FaceUnder(c, h, frame, out.components, p))
                          ? MapClass::kWorktop
                          : MapClass::kTable;
        } else if (c.area >= p.min_face_area) {
            c.label = MapClass::kFace;
        }
    }
    // Drop components without a role; index the rest per point.
    std::vector<PlanarComponent> kept;
    for (auto& c : out.components) {
        if (c.label != MapClass::kNone) kept.push_back(std::move(c));
    }
    out.components = std::move(kept);
    for (std::size_t c = 0; c < out.components.size(); ++c) {
        for (const Index i : out.components[c].indices) {
            out.point_component[i] = static_cast<std::int32_t>(c);
        }
    }
    return out;
}

}  // namespace multicue::mapping

#include "multicue/sim/tabletop_scene.hpp"

#include <cmath>
#include <limits>
#include <random>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/sim/scene.hpp"

namespace multicue::sim {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

struct Hit {
    float t = kInf;
    Eigen::Vector3f normal = Eigen::Vector3f::UnitZ();
    std::uint32_t label = 0;
    Color color;
};

void Consider(Hit& best, float t, const Eigen::Vector3f& n, std::uint32_t label, Color c) {
    if (t > 0.0f && t < best.t) best = Hit{t, n, label, c};
}

// Ray against the horizontal plane z = h, limited to a rectangle (or unlimited).
float IntersectHorizontal(const Eigen::Vector3f& o, const Eigen::Vector3f& d, float h) {
    if (std::abs(d.z()) < 1e-9f) return kInf;
    return (h - o.z()) / d.z();
}

// Ray against an upright box (slab test in the box frame).
void IntersectBox(const Eigen::Vector3f& o, const Eigen::Vector3f& d, const SceneBox& box,
                  float base, std::uint32_t label, Hit& best) {
    const float c = std::cos(box.yaw), s = std::sin(box.yaw);
    const Eigen::Vector3f center(box.center_xy.x(), box.center_xy.y(), base + box.extents.z() / 2);
    const Eigen::Vector3f rel = o - center;
    // World -> box: rotate by -yaw about z.
    const Eigen::Vector3f ol(c * rel.x() + s * rel.y(), -s * rel.x() + c * rel.y(), rel.z());
    const Eigen::Vector3f dl(c * d.x() + s * d.y(), -s * d.x() + c * d.y(), d.z());
    const Eigen::Vector3f half = box.extents / 2;
    float t_near = -kInf, t_far = kInf;
    int axis = -1;
    float sign = 1.0f;
    for (int a = 0; a < 3; ++a) {
        if (std::abs(dl[a]) < 1e-12f) {
            if (std::abs(ol[a]) > half[a]) return;
            continue;
        }
        float t1 = (-half[a] - ol[a]) / dl[a], t2 = (half[a] - ol[a]) / dl[a];
        float entry_sign = -1.0f;
        if (t1 > t2) {
            std::swap(t1, t2);
            entry_sign = 1.0f;
        }
        if (t1 > t_near) {
            t_near = t1;
            axis = a;
            sign = entry_sign;
        }
        t_far = std::min(t_far, t2);
        if (t_near > t_far) return;
    }
    if (axis < 0 || t_near <= 0.0f) return;
    Eigen::Vector3f nl = Eigen::Vector3f::Zero();
    nl[axis] = sign;
    const Eigen::Vector3f n(c * nl.x() - s * nl.y(), s * nl.x() + c * nl.y(), nl.z());
    Consider(best, t_near, n, label, box.color);
}

// Ray against an upright closed cylinder (side and top cap; the bottom rests on the table).
void IntersectCylinder(const Eigen::Vector3f& o, const Eigen::Vector3f& d, const SceneCylinder& cyl,
                       float base, std::uint32_t label, Hit& best) {
    const Eigen::Vector2f oc(o.x() - cyl.center_xy.x(), o.y() - cyl.center_xy.y());
    const Eigen::Vector2f dxy(d.x(), d.y());
    const float a = dxy.squaredNorm();
    const float top = base + cyl.height;
    if (a > 1e-12f) {
        const float b = 2.0f * oc.dot(dxy);
        const float cc = oc.squaredNorm() - cyl.radius * cyl.radius;
        const float disc = b * b - 4 * a * cc;
        if (disc >= 0.0f) {
            const float t = (-b - std::sqrt(disc)) / (2 * a);
            const float z = o.z() + t * d.z();
            if (t > 0.0f && z >= base && z <= top) {
                const Eigen::Vector2f p = oc + t * dxy;
                Consider(best, t, Eigen::Vector3f(p.x(), p.y(), 0.0f).normalized(), label,
                         cyl.color);
            }
        }
    }
    const float t_cap = IntersectHorizontal(o, d, top);
    if (t_cap > 0.0f && t_cap < kInf && d.z() < 0.0f) {
        const Eigen::Vector2f p = oc + t_cap * dxy;
        if (p.squaredNorm() <= cyl.radius * cyl.radius) {
            Consider(best, t_cap, Eigen::Vector3f::UnitZ(), label, cyl.color);
        }
    }
}

}  // namespace

Eigen::Isometry3f DefaultCameraPose(const TableTopScene& scene) {
    const Eigen::Vector2f mid = (scene.table_min + scene.table_max) / 2;
    const Eigen::Vector3f target(mid.x(), mid.y(), scene.table_height);
    const Eigen::Vector3f eye(mid.x(), scene.table_min.y() - 0.5f, scene.table_height + 0.6f);
    return LookAt(eye, target);
}

TableTopScene MakeDemoScene() {
    TableTopScene s;
    s.boxes = {
        {{-0.30f, 0.05f}, 0.3f, {0.16f, 0.10f, 0.08f}, {210, 70, 50, 255}},
        {{0.00f, 0.15f}, -0.2f, {0.06f, 0.20f, 0.28f}, {230, 200, 60, 255}},
        {{0.28f, -0.05f}, 0.8f, {0.09f, 0.09f, 0.09f}, {60, 170, 80, 255}},
    };
    s.cylinders = {
        {{-0.08f, -0.12f}, 0.035f, 0.12f, {50, 100, 210, 255}},
        {{0.20f, 0.20f}, 0.05f, 0.20f, {180, 60, 170, 255}},
    };
    return s;
}

PointCloud ScanTableTopScene(const TableTopScene& scene, const ScanParams& params) {
    const auto& cam = params.camera;
    if (cam.width == 0 || cam.height == 0) {
        throw InvalidArgument(
            fmt::format("camera size must be positive, got {}x{}", cam.width, cam.height));
    }
    if (!(cam.fx > 0.0f) || !(cam.fy > 0.0f)) {
        throw InvalidArgument(fmt::format("focal lengths must be > 0, got {} {}", cam.fx, cam.fy));
    }
    if (!(params.axial_noise >= 0.0f)) {
        throw InvalidArgument(fmt::format("axial_noise must be >= 0, got {}", params.axial_noise));
    }
    if (!(params.min_range >= 0.0f) || !(params.max_range > params.min_range)) {
        throw InvalidArgument(fmt::format("range must satisfy 0 <= min < max, got {} .. {}",
                                          params.min_range, params.max_range));
    }
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const std::size_t n = std::size_t{cam.width} * cam.height;
    PointCloud cloud;
    cloud.points.assign(n, Eigen::Vector3f::Constant(nan));
    cloud.colors.assign(n, Color{0, 0, 0, 255});
    cloud.labels.assign(n, 0);
    cloud.width = cam.width;
    cloud.height = cam.height;

    const Eigen::Matrix3f R = params.T_world_camera.linear();
    const Eigen::Vector3f eye = params.T_world_camera.translation();
    const float cos_max = std::cos(params.max_incidence_deg * static_cast<float>(M_PI) / 180.0f);
    std::mt19937 rng(params.seed);
    std::normal_distribution<float> gauss(0.0f, 1.0f);
    const auto num_boxes = static_cast<std::uint32_t>(scene.boxes.size());

    for (std::uint32_t v = 0; v < cam.height; ++v) {
        for (std::uint32_t u = 0; u < cam.width; ++u) {
            const float noise = gauss(rng);  // drawn for every pixel: scans repeat exactly
            const Eigen::Vector3f ray_cam((u - cam.cx) / cam.fx, (v - cam.cy) / cam.fy, 1.0f);
            const Eigen::Vector3f d = R * ray_cam;
            Hit best;
            const float t_table = IntersectHorizontal(eye, d, scene.table_height);
            if (t_table > 0.0f && t_table < kInf) {
                const Eigen::Vector3f p = eye + t_table * d;
                if (p.x() >= scene.table_min.x() && p.x() <= scene.table_max.x() &&
                    p.y() >= scene.table_min.y() && p.y() <= scene.table_max.y() && d.z() < 0) {
                    Consider(best, t_table, Eigen::Vector3f::UnitZ(), kTableLabel,
                             scene.table_color);
                }
            }
            const float t_floor = IntersectHorizontal(eye, d, 0.0f);
            if (t_floor < kInf && d.z() < 0) {
                Consider(best, t_floor, Eigen::Vector3f::UnitZ(), kFloorLabel, scene.floor_color);
            }
            for (std::uint32_t b = 0; b < num_boxes; ++b) {
                IntersectBox(eye, d, scene.boxes[b], scene.table_height, ObjectLabel(b + 1), best);
            }
            for (std::uint32_t c = 0; c < scene.cylinders.size(); ++c) {
                IntersectCylinder(eye, d, scene.cylinders[c], scene.table_height,
                                  ObjectLabel(num_boxes + c + 1), best);
            }
            if (best.t == kInf) continue;
            // t is the depth along the optical axis because ray_cam has z = 1.
            const float z = best.t;
            if (z < params.min_range || z > params.max_range) continue;
            const float cos_inc = std::abs(best.normal.dot(d.normalized()));
            if (cos_inc < cos_max) continue;
            const float z_noisy = z + params.axial_noise * z * z * noise;
            const std::size_t i = std::size_t{v} * cam.width + u;
            cloud.points[i] = ray_cam * z_noisy;
            cloud.colors[i] = best.color;
            cloud.labels[i] = best.label;
        }
    }
    return cloud;
}

}  // namespace multicue::sim

#include "multicue/sim/scene_gen.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/sim/placement_internal.hpp"
#include "multicue/sim/procedural.hpp"
#include "multicue/sim/sim_math_internal.hpp"

namespace multicue::sim {
namespace {

using math_internal::kObjectStream;
using math_internal::kPi;

using namespace placement_internal;

void CheckTableParams(const TableSceneParams& p) {
    if (p.min_objects < 0 || p.max_objects < p.min_objects) {
        throw InvalidArgument(
            fmt::format("objects per scene must satisfy 0 <= min <= max, got {}..{}", p.min_objects,
                        p.max_objects));
    }
    if (!(p.clutter >= 0.0f && p.clutter <= 1.0f)) {
        throw InvalidArgument(fmt::format("clutter must be in [0, 1], got {}", p.clutter));
    }
    if (!(p.table_min_size.minCoeff() > 0.2f) ||
        !(p.table_max_size.array() >= p.table_min_size.array()).all() ||
        !(p.table_min_height > 0.1f) || !(p.table_max_height >= p.table_min_height)) {
        throw InvalidArgument("table size and height ranges must be positive and ordered");
    }
    if (!(p.min_gap >= 0.0f) || !(p.edge_margin >= 0.0f) ||
        !(p.upright_probability >= 0.0f && p.upright_probability <= 1.0f)) {
        throw InvalidArgument(
            fmt::format("min_gap and edge_margin must be >= 0 and upright_probability in [0, 1], "
                        "got {}, {}, {}",
                        p.min_gap, p.edge_margin, p.upright_probability));
    }
}

/// The original table scene (TableSceneMode::kDefault); its random draws must not change.
Scene MakeDefaultTableScene(const TableSceneParams& p, ObjectSource& source, std::uint64_t seed) {
    StreamRng rng(seed, 0);
    Scene scene;
    const float h = AddTableAndFloor(p, rng, scene);
    const Eigen::Vector2f size = scene.support_size;

    const Eigen::Vector2f lo = -size / 2 + Eigen::Vector2f::Constant(p.edge_margin);
    const Eigen::Vector2f hi = size / 2 - Eigen::Vector2f::Constant(p.edge_margin);
    const int n = rng.UniformInt(p.min_objects, p.max_objects);
    std::vector<Polygon> placed;
    std::vector<Eigen::Vector2f> centres;
    for (int k = 0; k < n; ++k) {
        // Each object has its own stream: adding an object never changes the ones before it.
        StreamRng orng(seed, kObjectStream + static_cast<std::uint64_t>(k));
        const ObjectModel model = source.Random(orng);
        const Color color = RandomColor(orng);
        bool done = false;
        for (int attempt = 0; attempt < 8 && !done; ++attempt) {
            const Pose pose = ChoosePose(*model.mesh, h, p.upright_probability, orng);
            const bool touch = !placed.empty() && orng.Uniform() < p.clutter;
            for (int tries = 0; tries < 40 && !done; ++tries) {
                Eigen::Vector2f at;
                if (touch) {
                    const auto j = static_cast<std::size_t>(
                        orng.UniformInt(0, static_cast<int>(placed.size()) - 1));
                    const float a = static_cast<float>(orng.Uniform(0.0, 2.0 * kPi));
                    const Eigen::Vector2f dir(std::cos(a), std::sin(a));
                    float s_lo = 0.0f, s_hi = 1.5f;  // overlapping .. apart
                    for (int it = 0; it < 24; ++it) {
                        const float s = (s_lo + s_hi) / 2;
                        const auto poly = Translated(pose.footprint, centres[j] + s * dir);
                        (PolygonSeparation(poly, placed[j]) < 1e-3f ? s_lo : s_hi) = s;
                    }
                    at = centres[j] + s_hi * dir;
                    const auto poly = Translated(pose.footprint, at);
                    if (MinSeparation(poly, placed) < 5e-4f || !Inside(poly, lo, hi)) continue;
                } else {
                    at = Eigen::Vector2f(static_cast<float>(orng.Uniform(lo.x(), hi.x())),
                                         static_cast<float>(orng.Uniform(lo.y(), hi.y())));
                    const auto poly = Translated(pose.footprint, at);
                    if (!Inside(poly, lo, hi) || MinSeparation(poly, placed) < p.min_gap) continue;
                }
                const auto label = ObjectLabel(static_cast<std::uint32_t>(placed.size() + 1));
                scene.objects.push_back(MakeInstance(model, pose, at, label, color));
                if (touch) scene.objects.back().placement = ObjectPlacement::kTouching;
                placed.push_back(Translated(pose.footprint, at));
                centres.push_back(at);
                done = true;
            }
        }
    }
    return scene;
}

}  // namespace

Scene MakeTableScene(const TableSceneParams& p, ObjectSource& source, std::uint64_t seed) {
    CheckTableParams(p);
    if (p.mode == TableSceneMode::kDefault) return MakeDefaultTableScene(p, source, seed);
    return MakeModeTableScene(p, source, seed);
}

Scene MakeTableScene(const TableSceneParams& params, std::uint64_t seed) {
    ObjectSource source;
    return MakeTableScene(params, source, seed);
}

std::vector<Eigen::Isometry3f> TableViewpoints(const Scene& scene, int n, const ViewpointParams& p,
                                               std::uint64_t seed) {
    if (n < 0) throw InvalidArgument(fmt::format("number of views must be >= 0, got {}", n));
    if (!(p.min_height > 0.0f) || !(p.max_height >= p.min_height) || !(p.min_distance > 0.0f) ||
        !(p.max_distance >= p.min_distance)) {
        throw InvalidArgument("viewpoint height and distance ranges must be positive and ordered");
    }
    StreamRng rng(seed, 7);
    const float a_random = static_cast<float>(rng.Uniform(0.0, 2.0 * kPi));
    const float a0 = std::isfinite(scene.view_azimuth) ? scene.view_azimuth : a_random;
    const float height = static_cast<float>(rng.Uniform(p.min_height, p.max_height));
    const float dist = static_cast<float>(rng.Uniform(p.min_distance, p.max_distance));
    std::vector<Eigen::Isometry3f> poses;
    const Eigen::Vector3f c = scene.support_center;
    for (int k = 0; k < n; ++k) {
        const float a = a0 + 2 * kPi * static_cast<float>(k) / static_cast<float>(n);
        const Eigen::Vector2f dir(std::cos(a), std::sin(a));
        // Stay outside the table top: at least 0.25 m beyond its edge in this direction.
        const float edge =
            std::min(std::abs(scene.support_size.x() / 2 / std::max(std::abs(dir.x()), 1e-6f)),
                     std::abs(scene.support_size.y() / 2 / std::max(std::abs(dir.y()), 1e-6f)));
        const float d = std::max(dist, edge + 0.25f);
        const Eigen::Vector3f eye(c.x() + d * dir.x(), c.y() + d * dir.y(), height);
        const Eigen::Vector3f target =
            c + Eigen::Vector3f(static_cast<float>(rng.Uniform(-1.0, 1.0)) * p.target_jitter,
                                static_cast<float>(rng.Uniform(-1.0, 1.0)) * p.target_jitter, 0.0f);
        poses.push_back(LookAt(eye, target));
    }
    return poses;
}

Scene MakeTurntableScene(const ObjectModel& object, const TurntableParams& p, std::uint64_t seed) {
    if (!(p.table_height > 0.0f) || !(p.camera_height > 0.0f) || !(p.distance > 0.0f)) {
        throw InvalidArgument("turntable heights and distance must be > 0");
    }
    StreamRng rng(seed, 3);
    Scene scene;
    const float h = p.table_height;
    scene.support_center = Eigen::Vector3f(0.0f, 0.0f, h);
    scene.support_size = Eigen::Vector2f(0.6f, 0.6f);
    scene.objects.push_back(
        Fixed(TableMesh(scene.support_size, h), kTableLabel, {180, 150, 110, 255}, "table"));
    scene.objects.push_back(Floor(3.0f));
    // Upright (or first stable pose), yaw 0: the views turn around it.
    Pose pose = ChoosePose(*object.mesh, h, 1.0f, rng, false);
    scene.objects.push_back(
        MakeInstance(object, pose, Eigen::Vector2f::Zero(), ObjectLabel(1), RandomColor(rng)));
    return scene;
}

std::vector<Eigen::Isometry3f> TurntableViews(const Scene& scene, int n, const TurntableParams& p) {
    if (n <= 0) throw InvalidArgument(fmt::format("number of views must be > 0, got {}", n));
    std::vector<Eigen::Isometry3f> poses;
    const Eigen::Vector3f c = scene.support_center;
    // Aim at the middle of the object when there is one.
    Eigen::Vector3f target = c;
    const int obj = FindObject(scene, ObjectLabel(1));
    if (obj >= 0) {
        const auto& o = scene.objects[static_cast<std::size_t>(obj)];
        Eigen::AlignedBox3f box;
        for (const auto& v : o.mesh->mesh.vertices) box.extend(o.T_world_object * v);
        target = box.center();
    }
    for (int k = 0; k < n; ++k) {
        const float a = 2 * kPi * static_cast<float>(k) / static_cast<float>(n);
        const Eigen::Vector3f eye(c.x() - p.distance * std::cos(a),
                                  c.y() - p.distance * std::sin(a), p.camera_height);
        poses.push_back(LookAt(eye, target));
    }
    return poses;
}

Scene MakeRoomScene(const RoomParams& p, ObjectSource& source, std::uint64_t seed) {
    if (!(p.min_size > 1.0f) || !(p.max_size >= p.min_size) || !(p.wall_height > 0.0f) ||
        p.min_furniture < 0 || p.max_furniture < p.min_furniture) {
        throw InvalidArgument("room size, wall height and furniture count ranges must be valid");
    }
    StreamRng rng(seed, 0);
    const float sx = static_cast<float>(rng.Uniform(p.min_size, p.max_size));
    const float sy = static_cast<float>(rng.Uniform(p.min_size, p.max_size));
    Scene scene;
    scene.support_center = Eigen::Vector3f::Zero();
    scene.support_size = Eigen::Vector2f(sx, sy);
    AddFloorAndWalls(sx, sy, p.wall_height, scene);
    const Eigen::Vector2f lo(-sx / 2 + 0.05f, -sy / 2 + 0.05f), hi = -lo;
    const int n = rng.UniformInt(p.min_furniture, p.max_furniture);
    std::vector<Polygon> placed;
    for (int k = 0; k < n; ++k) {
        StreamRng orng(seed, kObjectStream + static_cast<std::uint64_t>(k));
        const ObjectModel model = source.Random(orng);
        const Color color = RandomColor(orng);
        const Pose pose = ChoosePose(*model.mesh, 0.0f, 1.0f, orng, false);
        for (int tries = 0; tries < 100; ++tries) {
            const Eigen::Vector2f at(static_cast<float>(orng.Uniform(lo.x(), hi.x())),
                                     static_cast<float>(orng.Uniform(lo.y(), hi.y())));
            const auto poly = Translated(pose.footprint, at);
            if (!Inside(poly, lo, hi) || MinSeparation(poly, placed) < p.min_gap) continue;
            scene.objects.push_back(
                MakeInstance(model, pose, at,
                             ObjectLabel(static_cast<std::uint32_t>(placed.size() + 1)), color));
            scene.objects.back().support = kFloorLabel;
            placed.push_back(poly);
            break;
        }
    }
    return scene;
}

Eigen::Isometry3f RoomLaserPose(const Scene& room, float height, std::uint64_t seed) {
    StreamRng rng(seed, 11);
    const Eigen::Vector2f half = room.support_size / 2 - Eigen::Vector2f::Constant(0.4f);
    Eigen::Vector2f at = Eigen::Vector2f::Zero();
    for (int tries = 0; tries < 200; ++tries) {
        at = Eigen::Vector2f(static_cast<float>(rng.Uniform(-half.x(), half.x())),
                             static_cast<float>(rng.Uniform(-half.y(), half.y())));
        bool free = true;
        for (const auto& o : room.objects) {
            if (o.label < ObjectLabel(1)) continue;
            Eigen::AlignedBox3f box;
            for (const auto& v : o.mesh->mesh.vertices) box.extend(o.T_world_object * v);
            const Eigen::Vector2f lo = box.min().head<2>().array() - 0.3f;
            const Eigen::Vector2f hi = box.max().head<2>().array() + 0.3f;
            free = free && !((at.array() >= lo.array()).all() && (at.array() <= hi.array()).all());
        }
        if (free) break;
    }
    const float yaw = std::atan2(-at.y(), -at.x());
    Eigen::Isometry3f T = Eigen::Isometry3f::Identity();
    T.linear() = Eigen::AngleAxisf(yaw, Eigen::Vector3f::UnitZ()).toRotationMatrix();
    T.translation() = Eigen::Vector3f(at.x(), at.y(), height);
    return T;
}

Eigen::Isometry3f TableLaserPose(const Scene& scene, float azimuth, float distance, float height) {
    const Eigen::Vector3f c = scene.support_center;
    Eigen::Isometry3f T = Eigen::Isometry3f::Identity();
    T.linear() = Eigen::AngleAxisf(azimuth + kPi, Eigen::Vector3f::UnitZ()).toRotationMatrix();
    T.translation() = Eigen::Vector3f(c.x() + distance * std::cos(azimuth),
                                      c.y() + distance * std::sin(azimuth), height);
    return T;
}

}  // namespace multicue::sim

#include "multicue/sim/placement_internal.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "multicue/sim/procedural.hpp"
#include "multicue/sim/scene_gen.hpp"

namespace multicue::sim::placement_internal {

Pose RestingPose(const PartMesh& mesh, const Eigen::Matrix3f& R, float h) {
    Pose pose;
    pose.R = R;
    float zmin = std::numeric_limits<float>::infinity();
    Polygon pts;
    pts.reserve(mesh.mesh.vertices.size());
    for (const auto& v : mesh.mesh.vertices) {
        const Eigen::Vector3f w = pose.R * v;
        zmin = std::min(zmin, w.z());
        pts.emplace_back(w.x(), w.y());
    }
    pose.z = h - zmin;
    Polygon hull = ConvexHull2D(std::move(pts));
    Eigen::Vector2f lo = hull.front(), hi = hull.front();
    for (const auto& p : hull) {
        lo = lo.cwiseMin(p);
        hi = hi.cwiseMax(p);
    }
    const Eigen::Vector2f c = (lo + hi) / 2;
    for (auto& p : hull) p -= c;
    pose.offset = -c;
    pose.footprint = std::move(hull);
    return pose;
}

Pose ChoosePose(const PartMesh& mesh, float h, float upright_probability, StreamRng& rng,
                bool allow_tilted) {
    const auto rotations = StableRotations(mesh);
    const bool upright_ok = rotations.front().isApprox(Eigen::Matrix3f::Identity(), 1e-4f);
    Eigen::Matrix3f Rs = rotations.front();
    const double pick = rng.Uniform();
    if (allow_tilted && !(upright_ok && pick < upright_probability) && rotations.size() > 1) {
        const std::size_t first = upright_ok ? 1 : 0;
        Rs = rotations[first + static_cast<std::size_t>(rng.UniformInt(
                                   0, static_cast<int>(rotations.size() - first) - 1))];
    }
    const float yaw = static_cast<float>(rng.Uniform(0.0, 2.0 * std::numbers::pi));
    return RestingPose(mesh,
                       Eigen::AngleAxisf(yaw, Eigen::Vector3f::UnitZ()).toRotationMatrix() * Rs, h);
}

Polygon Translated(const Polygon& p, const Eigen::Vector2f& t) {
    Polygon out = p;
    for (auto& q : out) q += t;
    return out;
}

bool Inside(const Polygon& p, const Eigen::Vector2f& lo, const Eigen::Vector2f& hi) {
    for (const auto& q : p) {
        if ((q.array() < lo.array()).any() || (q.array() > hi.array()).any()) return false;
    }
    return true;
}

float MinSeparation(const Polygon& p, const std::vector<Polygon>& others) {
    float best = std::numeric_limits<float>::infinity();
    for (const auto& o : others) best = std::min(best, PolygonSeparation(p, o));
    return best;
}

SceneObject MakeInstance(const ObjectModel& model, const Pose& pose, const Eigen::Vector2f& at,
                         std::uint32_t label, Color color) {
    SceneObject obj;
    obj.mesh = model.mesh;
    obj.T_world_object.linear() = pose.R;
    obj.T_world_object.translation() =
        Eigen::Vector3f(at.x() + pose.offset.x(), at.y() + pose.offset.y(), pose.z);
    obj.label = label;
    obj.category = static_cast<std::uint32_t>(std::max(0, CategoryIndex(model.category)));
    obj.color = color;
    obj.source = model.source;
    obj.scale = model.scale;
    obj.placement = ObjectPlacement::kStanding;
    obj.support = kTableLabel;
    return obj;
}

std::shared_ptr<const PartMesh> TableMesh(const Eigen::Vector2f& size, float h) {
    const float thick = 0.03f, leg = 0.05f;
    PartMesh m = MakeBoxMesh({size.x(), size.y(), thick}, "top");
    for (auto& v : m.mesh.vertices) v.z() += h - thick;
    for (int i = 0; i < 4; ++i) {
        PartMesh l = MakeBoxMesh({leg, leg, h - thick}, "leg");
        const float x = (i & 1 ? 1.0f : -1.0f) * (size.x() / 2 - leg);
        const float y = (i & 2 ? 1.0f : -1.0f) * (size.y() / 2 - leg);
        for (auto& v : l.mesh.vertices) v += Eigen::Vector3f(x, y, 0.0f);
        m.AppendParts(l);
    }
    m.name = "table";
    return std::make_shared<const PartMesh>(std::move(m));
}

SceneObject Fixed(std::shared_ptr<const PartMesh> mesh, std::uint32_t label, Color color,
                  const std::string& source) {
    SceneObject o;
    o.mesh = std::move(mesh);
    o.label = label;
    o.color = color;
    o.source = source;
    return o;
}

SceneObject Floor(float half) {
    PartMesh m = MakeBoxMesh({2 * half, 2 * half, 0.02f}, "floor");
    for (auto& v : m.mesh.vertices) v.z() -= 0.02f;
    m.name = "floor";
    return Fixed(std::make_shared<const PartMesh>(std::move(m)), kFloorLabel, {110, 110, 105, 255},
                 "floor");
}

void AddFloorAndWalls(float sx, float sy, float wall_height, Scene& scene) {
    scene.objects.push_back(Floor(std::max(sx, sy)));
    const float t = 0.1f;
    for (int w = 0; w < 4; ++w) {
        const bool along_x = w < 2;
        PartMesh m = MakeBoxMesh(along_x ? Eigen::Vector3f(sx + 2 * t, t, wall_height)
                                         : Eigen::Vector3f(t, sy + 2 * t, wall_height),
                                 "wall");
        const float off = (w % 2 == 0 ? -1.0f : 1.0f) * ((along_x ? sy : sx) / 2 + t / 2);
        for (auto& v : m.mesh.vertices) {
            v += along_x ? Eigen::Vector3f(0, off, 0) : Eigen::Vector3f(off, 0, 0);
        }
        m.name = "wall";
        scene.objects.push_back(Fixed(std::make_shared<const PartMesh>(std::move(m)), kWallLabel,
                                      {225, 220, 210, 255}, "wall"));
    }
}

float AddTableAndFloor(const TableSceneParams& p, StreamRng& rng, Scene& scene) {
    const Eigen::Vector2f size(
        static_cast<float>(rng.Uniform(p.table_min_size.x(), p.table_max_size.x())),
        static_cast<float>(rng.Uniform(p.table_min_size.y(), p.table_max_size.y())));
    const float h = static_cast<float>(rng.Uniform(p.table_min_height, p.table_max_height));
    scene.support_center = Eigen::Vector3f(0.0f, 0.0f, h);
    scene.support_size = size;
    const auto wood = static_cast<std::uint8_t>(rng.UniformInt(120, 200));
    scene.objects.push_back(Fixed(TableMesh(size, h), kTableLabel,
                                  Color{wood, static_cast<std::uint8_t>(wood * 0.8f),
                                        static_cast<std::uint8_t>(wood * 0.55f), 255},
                                  "table"));
    scene.objects.push_back(Floor(5.0f));
    return h;
}

}  // namespace multicue::sim::placement_internal

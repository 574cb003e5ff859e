#include "multicue/mapping/map_export.hpp"

#include <cmath>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/io/file_utils.hpp"
#include "multicue/mapping/containers.hpp"

namespace multicue::mapping {

Eigen::Matrix3f FrontRotation(const Front& f) {
    Eigen::Matrix3f R;
    R.col(0) = f.u_axis;
    R.col(1) = f.normal;
    R.col(2) = f.v_axis;
    if (R.determinant() < 0) R.col(0) = -R.col(0);
    return R;
}

namespace {

using nlohmann::ordered_json;

ordered_json V3(const Eigen::Vector3f& v) { return ordered_json::array({v.x(), v.y(), v.z()}); }
ordered_json V2(const Eigen::Vector2f& v) { return ordered_json::array({v.x(), v.y()}); }

ordered_json JointJson(const Articulation& a) {
    return {{"type", JointTypeName(a.type)},
            {"origin", V3(a.origin)},
            {"axis", V3(a.axis)},
            {"lower", a.lower},
            {"upper", a.upper},
            {"source", a.source},
            {"hinge_seen", a.hinge_seen}};
}

Eigen::Isometry3d Pose(const Eigen::Matrix3f& R, const Eigen::Vector3f& t) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = R.cast<double>();
    T.translation() = t.cast<double>();
    return T;
}

io::UrdfVisual Box(const std::string& name, const Eigen::Isometry3d& origin,
                   const Eigen::Vector3f& size, const Eigen::Vector4d& rgba) {
    io::UrdfVisual v;
    v.name = name;
    v.origin = origin;
    v.geometry.kind = io::UrdfGeometry::Kind::kBox;
    v.geometry.size = size.cwiseMax(0.002f).cast<double>();
    v.rgba = rgba;
    v.material = name + "_material";
    return v;
}

}  // namespace

ordered_json KitchenMapJson(const KitchenMap& map) {
    ordered_json j;
    j["format"] = "multicue.kitchen-map/1";
    j["frame"] = {{"x", V3(map.frame.axes.col(0))},
                  {"y", V3(map.frame.axes.col(1))},
                  {"up", V3(map.frame.axes.col(2))}};
    auto num = [](float v) { return std::isnan(v) ? ordered_json(nullptr) : ordered_json(v); };
    j["floor_height"] = num(map.floor_height);
    j["ceiling_height"] = num(map.ceiling_height);
    j["classes"] = MapClassNames();
    j["container_types"] = ContainerTypeNames();
    ordered_json comps = ordered_json::array();
    for (std::size_t i = 0; i < map.components.size(); ++i) {
        const auto& c = map.components[i];
        comps.push_back({{"id", i},
                         {"class", MapClassNames()[static_cast<std::size_t>(c.label)]},
                         {"plane", {c.plane.x(), c.plane.y(), c.plane.z(), c.plane.w()}},
                         {"min", V2(c.min)},
                         {"max", V2(c.max)},
                         {"area", c.area},
                         {"points", c.indices.size()}});
    }
    j["components"] = comps;
    ordered_json fixtures = ordered_json::array();
    for (std::size_t i = 0; i < map.fixtures.size(); ++i) {
        const auto& f = map.fixtures[i];
        fixtures.push_back({{"id", i},
                            {"type", f.type == FixtureType::kHandle ? "handle" : "knob"},
                            {"face", f.face},
                            {"center", V3(f.center)},
                            {"direction", V3(f.direction)},
                            {"length", f.length},
                            {"width", f.width},
                            {"protrusion", f.protrusion},
                            {"line_inlier_ratio", f.line_inlier_ratio},
                            {"circle_inlier_ratio", f.circle_inlier_ratio},
                            {"points", f.indices.size()}});
    }
    j["fixtures"] = fixtures;
    ordered_json fronts = ordered_json::array();
    for (std::size_t i = 0; i < map.fronts.size(); ++i) {
        const auto& f = map.fronts[i];
        fronts.push_back({{"id", i},
                          {"face", f.face},
                          {"furniture", f.furniture},
                          {"fixtures", f.fixtures},
                          {"center", V3(f.center)},
                          {"u_axis", V3(f.u_axis)},
                          {"v_axis", V3(f.v_axis)},
                          {"normal", V3(f.normal)},
                          {"min", V2(f.min)},
                          {"max", V2(f.max)},
                          {"size", V2(f.max - f.min)},
                          {"joint", JointJson(f.articulation)},
                          {"overlapping", f.overlapping},
                          {"appearance",
                           {{"median", f.appearance_median},
                            {"mad", f.appearance_mad},
                            {"rounds", f.model_iterations}}},
                          {"points", f.indices.size()}});
    }
    j["fronts"] = fronts;
    ordered_json furniture = ordered_json::array();
    for (std::size_t i = 0; i < map.furniture.size(); ++i) {
        const auto& f = map.furniture[i];
        furniture.push_back({{"id", i},
                             {"type", f.type},
                             {"confidence", f.confidence},
                             {"kitchenette", f.kitchenette},
                             {"fronts", f.fronts},
                             {"center", V3(f.center)},
                             {"axes", {V3(f.axes.col(0)), V3(f.axes.col(1)), V3(f.axes.col(2))}},
                             {"extents", V3(f.extents)}});
    }
    j["furniture"] = furniture;
    ordered_json kitchenettes = ordered_json::array();
    for (std::size_t i = 0; i < map.kitchenettes.size(); ++i) {
        kitchenettes.push_back({{"id", i},
                                {"wall", map.kitchenettes[i].wall},
                                {"furniture", map.kitchenettes[i].furniture}});
    }
    j["kitchenettes"] = kitchenettes;
    return j;
}

io::UrdfModel KitchenMapUrdf(const KitchenMap& map, const std::string& name) {
    io::UrdfModel m;
    m.name = name;
    m.root = "kitchen_map";
    m.links.push_back(io::UrdfLink{"kitchen_map", {}, {}});
    auto fixed = [&](const std::string& child, const std::string& parent,
                     const Eigen::Isometry3d& origin) {
        io::UrdfJoint j;
        j.name = child + "_joint";
        j.parent = parent;
        j.child = child;
        j.origin = origin;
        m.joints.push_back(std::move(j));
    };
    // Worktops, tables and walls as boxes: the environment's collision model.
    for (std::size_t c = 0; c < map.components.size(); ++c) {
        const PlanarComponent& pc = map.components[c];
        if (pc.label != MapClass::kWorktop && pc.label != MapClass::kTable &&
            pc.label != MapClass::kWall) {
            continue;
        }
        const std::string link =
            fmt::format("{}_{}", MapClassNames()[static_cast<std::size_t>(pc.label)], c);
        const Eigen::Vector3f n = pc.plane.head<3>();
        Eigen::Vector3f u = pc.axis == 2 ? Eigen::Vector3f(map.frame.axes.col(0))
                                         : Eigen::Vector3f(map.frame.Up().cross(n));
        const Eigen::Vector3f v = n.cross(u);
        const Eigen::Vector2f mid = (pc.min + pc.max) / 2;
        Eigen::Matrix3f R;
        R << u, v, n;
        const Eigen::Vector3f center = u * mid.x() + v * mid.y() - n * pc.plane.w() - n * 0.015f;
        // (u, v) of a horizontal component are the room x and y; of a vertical one u and up.
        const Eigen::Vector2f size = pc.max - pc.min;
        const float su = size.x();
        const float sv = pc.axis == 2 ? size.y() : size.y();
        m.links.push_back(io::UrdfLink{
            link,
            {Box(link, Eigen::Isometry3d::Identity(), {su, sv, 0.03f}, {0.7, 0.7, 0.7, 1.0})},
            {}});
        m.links.back().collisions = m.links.back().visuals;
        fixed(link, "kitchen_map", Pose(R, center));
    }
    for (std::size_t k = 0; k < map.furniture.size(); ++k) {
        const Furniture& f = map.furniture[k];
        const std::string link = fmt::format("furniture_{}", k);
        Eigen::Matrix3f R = f.axes;
        if (R.determinant() < 0) R.col(0) = -R.col(0);
        m.links.push_back(io::UrdfLink{link,
                                       {Box(link + "_" + f.type, Eigen::Isometry3d::Identity(),
                                            f.extents, {0.55, 0.6, 0.8, 1.0})},
                                       {}});
        m.links.back().collisions = m.links.back().visuals;
        fixed(link, "kitchen_map", Pose(R, f.center));
        const Eigen::Isometry3d T_world_furniture = Pose(R, f.center);
        for (const int fi : f.fronts) {
            const Front& fr = map.fronts[static_cast<std::size_t>(fi)];
            const std::string front = fmt::format("front_{}", fi);
            const Articulation& a = fr.articulation;
            // The joint frame: at the axis origin (the front's centre for drawers), oriented
            // like the world, so the axis is written in world coordinates.
            const Eigen::Vector3f at = a.type == JointType::kRevolute ? a.origin : fr.center;
            const Eigen::Isometry3d T_world_joint = Pose(Eigen::Matrix3f::Identity(), at);
            const Eigen::Vector2f size = fr.max - fr.min;
            const Eigen::Isometry3d T_joint_front =
                Pose(FrontRotation(fr), fr.center - at + fr.normal * 0.01f);
            m.links.push_back(io::UrdfLink{
                front,
                {Box(front, T_joint_front, {size.x(), 0.02f, size.y()}, {0.3, 0.75, 0.3, 1.0})},
                {}});
            m.links.back().collisions = m.links.back().visuals;
            io::UrdfJoint j;
            j.name = front + "_joint";
            j.parent = link;
            j.child = front;
            j.origin = T_world_furniture.inverse() * T_world_joint;
            j.type = a.type == JointType::kRevolute    ? io::UrdfJointType::kRevolute
                     : a.type == JointType::kPrismatic ? io::UrdfJointType::kPrismatic
                                                       : io::UrdfJointType::kFixed;
            j.axis = a.axis.cast<double>();
            j.has_limits = j.type != io::UrdfJointType::kFixed;
            j.lower = a.lower;
            j.upper = a.upper;
            m.joints.push_back(std::move(j));
            for (const int xi : fr.fixtures) {
                const Fixture& fx = map.fixtures[static_cast<std::size_t>(xi)];
                const std::string fl =
                    fmt::format("{}_{}", fx.type == FixtureType::kHandle ? "handle" : "knob", xi);
                Eigen::Matrix3f Rf;
                Rf.col(2) = fx.direction;
                Rf.col(1) = fr.normal;
                Rf.col(0) = Rf.col(1).cross(Rf.col(2)).normalized();
                Rf.col(1) = Rf.col(2).cross(Rf.col(0));
                const Eigen::Vector3f size3(std::max(fx.width, 0.01f),
                                            std::max(fx.protrusion, 0.01f),
                                            std::max(fx.length, 0.01f));
                m.links.push_back(io::UrdfLink{
                    fl, {Box(fl, Eigen::Isometry3d::Identity(), size3, {0.9, 0.2, 0.2, 1.0})}, {}});
                // Fixed to the front: its pose relative to the joint frame (the front's link).
                fixed(fl, front, T_world_joint.inverse() * Pose(Rf, fx.center));
            }
        }
    }
    return m;
}

void WriteKitchenMap(const std::filesystem::path& dir, const KitchenMap& map,
                     const std::string& name) {
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    if (!std::filesystem::is_directory(dir)) {
        throw IoError(fmt::format("{}: cannot create output folder", dir.string()));
    }
    // Everything is built before the first write: a failure leaves no partial map behind.
    const std::string json = KitchenMapJson(map).dump(1) + "\n";
    const std::string urdf = io::UrdfToXml(KitchenMapUrdf(map, name));
    const std::string owl = KitchenMapOwl(map, name);
    io::WriteFileAtomically(dir / "map.json", [&](std::ostream& os) { os << json; });
    io::WriteFileAtomically(dir / "map.urdf", [&](std::ostream& os) { os << urdf; });
    io::WriteFileAtomically(dir / "map.owl", [&](std::ostream& os) { os << owl; });
}

}  // namespace multicue::mapping

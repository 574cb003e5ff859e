#include "multicue/mapping/map_export.hpp"

#include <cmath>

#include <fmt/format.h>
#include <tinyxml.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/io/file_utils.hpp"
#include "multicue/mapping/containers.hpp"

namespace multicue::mapping {
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
            {"source", a.source}};
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

/// A right-handed rotation whose columns are the front's u, normal and v.
Eigen::Matrix3f FrontRotation(const Front& f) {
    Eigen::Matrix3f R;
    R.col(0) = f.u_axis;
    R.col(1) = f.normal;
    R.col(2) = f.v_axis;
    if (R.determinant() < 0) R.col(0) = -R.col(0);
    return R;
}

/// KnowRob's class of a container type.
const char* KnowRobClass(const std::string& type) {
    if (type == "drawer_unit") return "Cupboard";  // a cupboard of drawers
    if (type == "oven") return "Oven";
    if (type == "dishwasher") return "Dishwasher";
    if (type == "fridge") return "Refrigerator";
    if (type == "microwave") return "MicrowaveOven";
    if (type == "table") return "KitchenTable";
    return "Cupboard";
}

class OwlWriter {
  public:
    explicit OwlWriter(const std::string& name) : base_("http://knowrob.org/kb/" + name + ".owl") {
        doc_.LinkEndChild(new TiXmlDeclaration("1.0", "utf-8", ""));
        rdf_ = new TiXmlElement("rdf:RDF");
        rdf_->SetAttribute("xmlns:rdf", "http://www.w3.org/1999/02/22-rdf-syntax-ns#");
        rdf_->SetAttribute("xmlns:rdfs", "http://www.w3.org/2000/01/rdf-schema#");
        rdf_->SetAttribute("xmlns:owl", "http://www.w3.org/2002/07/owl#");
        rdf_->SetAttribute("xmlns:xsd", "http://www.w3.org/2001/XMLSchema#");
        rdf_->SetAttribute("xmlns:knowrob", "http://knowrob.org/kb/knowrob.owl#");
        rdf_->SetAttribute("xml:base", base_);
        doc_.LinkEndChild(rdf_);
        auto* onto = new TiXmlElement("owl:Ontology");
        onto->SetAttribute("rdf:about", base_);
        auto* imp = new TiXmlElement("owl:imports");
        imp->SetAttribute("rdf:resource", "package://knowrob_common/owl/knowrob.owl");
        onto->LinkEndChild(imp);
        rdf_->LinkEndChild(onto);
    }

    std::string Iri(const std::string& id) const { return base_ + "#" + id; }

    TiXmlElement* Individual(const std::string& id, const std::string& cls) {
        auto* e = new TiXmlElement("owl:NamedIndividual");
        e->SetAttribute("rdf:about", Iri(id));
        auto* t = new TiXmlElement("rdf:type");
        t->SetAttribute("rdf:resource", "http://knowrob.org/kb/knowrob.owl#" + cls);
        e->LinkEndChild(t);
        rdf_->LinkEndChild(e);
        return e;
    }

    static void Link(TiXmlElement* e, const std::string& property, const std::string& iri) {
        auto* p = new TiXmlElement("knowrob:" + property);
        p->SetAttribute("rdf:resource", iri);
        e->LinkEndChild(p);
    }

    static void Value(TiXmlElement* e, const std::string& property, double v,
                      const char* type = "double") {
        auto* p = new TiXmlElement("knowrob:" + property);
        p->SetAttribute("rdf:datatype", std::string("http://www.w3.org/2001/XMLSchema#") + type);
        p->LinkEndChild(new TiXmlText(fmt::format("{:.6g}", v)));
        e->LinkEndChild(p);
    }

    /// A pose as KnowRob records it: a SemanticMapPerception of the object that occurs at a
    /// RotationMatrix3D with elements m00 .. m33.
    void PoseOf(const std::string& object, const Eigen::Matrix3f& R, const Eigen::Vector3f& t) {
        const std::string m = fmt::format("RotationMatrix3D_{}", counter_);
        const std::string p = fmt::format("SemanticMapPerception_{}", counter_++);
        TiXmlElement* perception = Individual(p, "SemanticMapPerception");
        Link(perception, "objectActedOn", Iri(object));
        Link(perception, "eventOccursAt", Iri(m));
        TiXmlElement* matrix = Individual(m, "RotationMatrix3D");
        Eigen::Matrix4f T = Eigen::Matrix4f::Identity();
        T.topLeftCorner<3, 3>() = R;
        T.topRightCorner<3, 1>() = t;
        for (int r = 0; r < 4; ++r) {
            for (int c = 0; c < 4; ++c) Value(matrix, fmt::format("m{}{}", r, c), T(r, c));
        }
    }

    std::string Text() {
        TiXmlPrinter printer;
        printer.SetIndent("  ");
        doc_.Accept(&printer);
        return printer.CStr();
    }

  private:
    std::string base_;
    TiXmlDocument doc_;
    TiXmlElement* rdf_ = nullptr;
    int counter_ = 0;
};

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

std::string KitchenMapOwl(const KitchenMap& map, const std::string& name) {
    OwlWriter w(name);
    const std::string map_id = "SemanticEnvironmentMap_" + name;
    w.Individual(map_id, "SemanticEnvironmentMap");
    for (std::size_t e = 0; e < map.kitchenettes.size(); ++e) {
        TiXmlElement* k = w.Individual(fmt::format("Kitchenette_{}", e), "Kitchen");
        OwlWriter::Link(k, "describedInMap", w.Iri(map_id));
        for (const int f : map.kitchenettes[e].furniture) {
            OwlWriter::Link(k, "properPhysicalParts", w.Iri(fmt::format("Furniture_{}", f)));
        }
    }
    for (std::size_t c = 0; c < map.components.size(); ++c) {
        const PlanarComponent& pc = map.components[c];
        if (pc.label != MapClass::kWorktop && pc.label != MapClass::kTable) continue;
        const std::string id = fmt::format("CounterTop_{}", c);
        TiXmlElement* e =
            w.Individual(id, pc.label == MapClass::kWorktop ? "CounterTop" : "KitchenTable");
        OwlWriter::Link(e, "describedInMap", w.Iri(map_id));
        OwlWriter::Value(e, "widthOfObject", pc.max.x() - pc.min.x());
        OwlWriter::Value(e, "depthOfObject", pc.max.y() - pc.min.y());
        OwlWriter::Value(e, "heightOfObject", 0.03);
        const Eigen::Vector2f mid = (pc.min + pc.max) / 2;
        const Eigen::Vector3f t = map.frame.axes.col(0) * mid.x() +
                                  map.frame.axes.col(1) * mid.y() -
                                  pc.plane.head<3>() * pc.plane.w();
        w.PoseOf(id, map.frame.axes, t);
    }
    for (std::size_t k = 0; k < map.furniture.size(); ++k) {
        const Furniture& f = map.furniture[k];
        const std::string id = fmt::format("Furniture_{}", k);
        TiXmlElement* e = w.Individual(id, KnowRobClass(f.type));
        OwlWriter::Link(e, "describedInMap", w.Iri(map_id));
        OwlWriter::Value(e, "widthOfObject", f.extents.x());
        OwlWriter::Value(e, "depthOfObject", f.extents.y());
        OwlWriter::Value(e, "heightOfObject", f.extents.z());
        for (const int fi : f.fronts) {
            OwlWriter::Link(e, "properPhysicalParts", w.Iri(fmt::format("Front_{}", fi)));
            OwlWriter::Link(e, "properPhysicalParts", w.Iri(fmt::format("Joint_{}", fi)));
        }
        Eigen::Matrix3f R = f.axes;
        if (R.determinant() < 0) R.col(0) = -R.col(0);
        w.PoseOf(id, R, f.center);
    }
    for (std::size_t i = 0; i < map.fronts.size(); ++i) {
        const Front& fr = map.fronts[i];
        const Articulation& a = fr.articulation;
        const std::string id = fmt::format("Front_{}", i);
        TiXmlElement* e = w.Individual(id, a.type == JointType::kPrismatic ? "Drawer" : "Door");
        OwlWriter::Link(e, "describedInMap", w.Iri(map_id));
        const Eigen::Vector2f size = fr.max - fr.min;
        OwlWriter::Value(e, "widthOfObject", size.x());
        OwlWriter::Value(e, "depthOfObject", 0.02);
        OwlWriter::Value(e, "heightOfObject", size.y());
        for (const int x : fr.fixtures) {
            OwlWriter::Link(e, "properPhysicalParts", w.Iri(fmt::format("Fixture_{}", x)));
        }
        w.PoseOf(id, FrontRotation(fr), fr.center);
        if (a.type == JointType::kUnknown) continue;
        const std::string jid = fmt::format("Joint_{}", i);
        TiXmlElement* j =
            w.Individual(jid, a.type == JointType::kRevolute ? "HingedJoint" : "PrismaticJoint");
        OwlWriter::Link(j, "describedInMap", w.Iri(map_id));
        OwlWriter::Link(j, "properPhysicalParts", w.Iri(id));
        if (fr.furniture >= 0) {
            OwlWriter::Link(j, "connectedTo-Rigidly",
                            w.Iri(fmt::format("Furniture_{}", fr.furniture)));
        }
        OwlWriter::Link(j, "connectedTo-Rigidly", w.Iri(id));
        OwlWriter::Value(j, "minJointValue", a.lower, "float");
        OwlWriter::Value(j, "maxJointValue", a.upper, "float");
        const std::string vid = fmt::format("Vector_{}", i);
        OwlWriter::Link(j, "direction", w.Iri(vid));
        TiXmlElement* v = w.Individual(vid, "Vector");
        OwlWriter::Value(v, "vectorX", a.axis.x(), "float");
        OwlWriter::Value(v, "vectorY", a.axis.y(), "float");
        OwlWriter::Value(v, "vectorZ", a.axis.z(), "float");
        // The joint's pose: at its axis, the axis as the frame's z.
        Eigen::Matrix3f R;
        R.col(2) = a.axis;
        R.col(0) =
            (std::abs(a.axis.z()) < 0.9f ? Eigen::Vector3f::UnitZ() : Eigen::Vector3f::UnitX())
                .cross(a.axis)
                .normalized();
        R.col(1) = R.col(2).cross(R.col(0));
        w.PoseOf(jid, R, a.origin);
    }
    for (std::size_t x = 0; x < map.fixtures.size(); ++x) {
        const Fixture& fx = map.fixtures[x];
        const std::string id = fmt::format("Fixture_{}", x);
        TiXmlElement* e =
            w.Individual(id, fx.type == FixtureType::kHandle ? "Handle" : "ControlKnob");
        OwlWriter::Link(e, "describedInMap", w.Iri(map_id));
        OwlWriter::Value(e, "widthOfObject", fx.width);
        OwlWriter::Value(e, "depthOfObject", fx.protrusion);
        OwlWriter::Value(e, "heightOfObject", fx.length);
        w.PoseOf(id, map.frame.axes, fx.center);
    }
    return w.Text();
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

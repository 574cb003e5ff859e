#include "multicue/io/urdf.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <mutex>
#include <set>
#include <sstream>

#include <console_bridge/console.h>
#include <fmt/format.h>
#include <tinyxml.h>
#include <urdf_parser/urdf_parser.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/core/logging.hpp"
#include "multicue/io/file_utils.hpp"

namespace multicue::io {
namespace {

/// Collects urdfdom's console messages while one parse runs, so that the library prints nothing
/// and the first error becomes part of the exception's message. console_bridge's handler is
/// process-wide: parses are serialised.
class CollectingHandler : public console_bridge::OutputHandler {
  public:
    void log(const std::string& text, console_bridge::LogLevel level, const char*, int) override {
        if (level >= console_bridge::CONSOLE_BRIDGE_LOG_ERROR && first_error.empty()) {
            first_error = text;
        }
        LogDebug("urdfdom: {}", text);
    }
    std::string first_error;
};

std::mutex& ParseMutex() {
    static std::mutex m;
    return m;
}

Eigen::Isometry3d ToIsometry(const urdf::Pose& p) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = Eigen::Quaterniond(p.rotation.w, p.rotation.x, p.rotation.y, p.rotation.z)
                     .normalized()
                     .toRotationMatrix();
    T.translation() = Eigen::Vector3d(p.position.x, p.position.y, p.position.z);
    return T;
}

UrdfGeometry ToGeometry(const urdf::GeometrySharedPtr& g) {
    UrdfGeometry out;
    if (!g) return out;
    switch (g->type) {
        case urdf::Geometry::MESH: {
            const auto* m = static_cast<const urdf::Mesh*>(g.get());
            out.kind = UrdfGeometry::Kind::kMesh;
            out.filename = m->filename;
            out.scale = Eigen::Vector3d(m->scale.x, m->scale.y, m->scale.z);
            break;
        }
        case urdf::Geometry::BOX: {
            const auto* b = static_cast<const urdf::Box*>(g.get());
            out.kind = UrdfGeometry::Kind::kBox;
            out.size = Eigen::Vector3d(b->dim.x, b->dim.y, b->dim.z);
            break;
        }
        case urdf::Geometry::CYLINDER: {
            const auto* c = static_cast<const urdf::Cylinder*>(g.get());
            out.kind = UrdfGeometry::Kind::kCylinder;
            out.radius = c->radius;
            out.length = c->length;
            break;
        }
        case urdf::Geometry::SPHERE: {
            out.kind = UrdfGeometry::Kind::kSphere;
            out.radius = static_cast<const urdf::Sphere*>(g.get())->radius;
            break;
        }
    }
    return out;
}

UrdfJointType ToJointType(int type) {
    switch (type) {
        case urdf::Joint::REVOLUTE:
            return UrdfJointType::kRevolute;
        case urdf::Joint::CONTINUOUS:
            return UrdfJointType::kContinuous;
        case urdf::Joint::PRISMATIC:
            return UrdfJointType::kPrismatic;
        case urdf::Joint::FLOATING:
            return UrdfJointType::kFloating;
        case urdf::Joint::PLANAR:
            return UrdfJointType::kPlanar;
        default:
            return UrdfJointType::kFixed;
    }
}

/// Names of the <link> and <joint> children of <robot> in document order.
void ElementOrder(const TiXmlElement* robot, std::vector<std::string>& links,
                  std::vector<std::string>& joints) {
    for (const TiXmlElement* e = robot->FirstChildElement(); e; e = e->NextSiblingElement()) {
        const char* name = e->Attribute("name");
        if (name == nullptr) continue;
        if (std::string(e->Value()) == "link") links.emplace_back(name);
        if (std::string(e->Value()) == "joint") joints.emplace_back(name);
    }
}

void CompleteLimits(TiXmlElement* robot) {
    for (TiXmlElement* j = robot->FirstChildElement("joint"); j;
         j = j->NextSiblingElement("joint")) {
        for (TiXmlElement* l = j->FirstChildElement("limit"); l;
             l = l->NextSiblingElement("limit")) {
            if (l->Attribute("effort") == nullptr) l->SetAttribute("effort", "0");
            if (l->Attribute("velocity") == nullptr) l->SetAttribute("velocity", "0");
        }
    }
}

std::string Num(double v) { return fmt::format("{:.9g}", v); }

std::string Vec(const Eigen::Vector3d& v) {
    return fmt::format("{} {} {}", Num(v.x()), Num(v.y()), Num(v.z()));
}

TiXmlElement* OriginElement(const Eigen::Isometry3d& T) {
    auto* e = new TiXmlElement("origin");
    e->SetAttribute("xyz", Vec(T.translation()));
    // Roll, pitch, yaw about fixed x, y, z: R = Rz(yaw) Ry(pitch) Rx(roll).
    const Eigen::Matrix3d R = T.linear();
    const double pitch = std::asin(std::clamp(-R(2, 0), -1.0, 1.0));
    double roll = 0.0, yaw = 0.0;
    if (std::abs(R(2, 0)) < 1.0 - 1e-12) {
        roll = std::atan2(R(2, 1), R(2, 2));
        yaw = std::atan2(R(1, 0), R(0, 0));
    } else {
        yaw = std::atan2(-R(0, 1), R(1, 1));
    }
    e->SetAttribute("rpy", Vec(Eigen::Vector3d(roll, pitch, yaw)));
    return e;
}

TiXmlElement* VisualElement(const char* tag, const UrdfVisual& v) {
    auto* e = new TiXmlElement(tag);
    if (!v.name.empty()) e->SetAttribute("name", v.name);
    e->LinkEndChild(OriginElement(v.origin));
    auto* geometry = new TiXmlElement("geometry");
    const UrdfGeometry& g = v.geometry;
    switch (g.kind) {
        case UrdfGeometry::Kind::kMesh: {
            auto* m = new TiXmlElement("mesh");
            m->SetAttribute("filename", g.filename);
            if (!g.scale.isOnes()) m->SetAttribute("scale", Vec(g.scale));
            geometry->LinkEndChild(m);
            break;
        }
        case UrdfGeometry::Kind::kBox: {
            auto* b = new TiXmlElement("box");
            b->SetAttribute("size", Vec(g.size));
            geometry->LinkEndChild(b);
            break;
        }
        case UrdfGeometry::Kind::kCylinder: {
            auto* c = new TiXmlElement("cylinder");
            c->SetAttribute("radius", Num(g.radius));
            c->SetAttribute("length", Num(g.length));
            geometry->LinkEndChild(c);
            break;
        }
        case UrdfGeometry::Kind::kSphere: {
            auto* s = new TiXmlElement("sphere");
            s->SetAttribute("radius", Num(g.radius));
            geometry->LinkEndChild(s);
            break;
        }
        case UrdfGeometry::Kind::kNone:
            throw InvalidArgument(fmt::format("urdf: visual '{}' has no geometry", v.name));
    }
    e->LinkEndChild(geometry);
    if (std::string(tag) == "visual" && (!v.material.empty() || v.rgba)) {
        auto* m = new TiXmlElement("material");
        m->SetAttribute("name", v.material.empty() ? v.name + "_material" : v.material);
        if (v.rgba) {
            auto* c = new TiXmlElement("color");
            c->SetAttribute("rgba", fmt::format("{} {} {} {}", Num((*v.rgba)[0]), Num((*v.rgba)[1]),
                                                Num((*v.rgba)[2]), Num((*v.rgba)[3])));
            m->LinkEndChild(c);
        }
        e->LinkEndChild(m);
    }
    return e;
}

void CheckTree(const UrdfModel& model) {
    std::set<std::string> links, joints, children;
    for (const auto& l : model.links) {
        if (l.name.empty()) throw InvalidArgument("urdf: a link has an empty name");
        if (!links.insert(l.name).second) {
            throw InvalidArgument(fmt::format("urdf: duplicate link name '{}'", l.name));
        }
    }
    for (const auto& j : model.joints) {
        if (j.name.empty()) throw InvalidArgument("urdf: a joint has an empty name");
        if (!joints.insert(j.name).second) {
            throw InvalidArgument(fmt::format("urdf: duplicate joint name '{}'", j.name));
        }
        if (!links.count(j.parent) || !links.count(j.child)) {
            throw InvalidArgument(fmt::format(
                "urdf: joint '{}' connects missing links '{}' -> '{}'", j.name, j.parent, j.child));
        }
        if (!children.insert(j.child).second) {
            throw InvalidArgument(fmt::format("urdf: link '{}' has two parents", j.child));
        }
    }
    if (links.size() != children.size() + 1) {
        throw InvalidArgument(fmt::format("urdf: model '{}' needs exactly one root link, has {}",
                                          model.name, links.size() - children.size()));
    }
}

}  // namespace

const char* UrdfJointTypeName(UrdfJointType type) {
    switch (type) {
        case UrdfJointType::kRevolute:
            return "revolute";
        case UrdfJointType::kContinuous:
            return "continuous";
        case UrdfJointType::kPrismatic:
            return "prismatic";
        case UrdfJointType::kFloating:
            return "floating";
        case UrdfJointType::kPlanar:
            return "planar";
        case UrdfJointType::kFixed:
            break;
    }
    return "fixed";
}

const UrdfLink* UrdfModel::FindLink(const std::string& link_name) const {
    for (const auto& l : links) {
        if (l.name == link_name) return &l;
    }
    return nullptr;
}

const UrdfJoint* UrdfModel::FindJoint(const std::string& joint_name) const {
    for (const auto& j : joints) {
        if (j.name == joint_name) return &j;
    }
    return nullptr;
}

const UrdfJoint* UrdfModel::ParentJoint(const std::string& link_name) const {
    for (const auto& j : joints) {
        if (j.child == link_name) return &j;
    }
    return nullptr;
}

UrdfModel ParseUrdf(const std::string& xml, const std::string& source,
                    const UrdfReadParams& params) {
    TiXmlDocument doc;
    doc.Parse(xml.c_str());
    if (doc.Error()) {
        throw FormatError(fmt::format("{}: malformed XML: {} (line {})", source, doc.ErrorDesc(),
                                      doc.ErrorRow()));
    }
    TiXmlElement* robot = doc.FirstChildElement("robot");
    if (robot == nullptr) throw FormatError(fmt::format("{}: no <robot> element", source));
    std::vector<std::string> link_order, joint_order;
    ElementOrder(robot, link_order, joint_order);
    std::string text = xml;
    if (params.complete_limits) {
        CompleteLimits(robot);
        TiXmlPrinter printer;
        doc.Accept(&printer);
        text = printer.CStr();
    }
    urdf::ModelInterfaceSharedPtr parsed;
    std::string reason;
    {
        const std::lock_guard<std::mutex> lock(ParseMutex());
        CollectingHandler handler;
        console_bridge::OutputHandler* previous = console_bridge::getOutputHandler();
        console_bridge::useOutputHandler(&handler);
        try {
            parsed = urdf::parseURDF(text);
        } catch (const std::exception& e) {
            handler.first_error = e.what();
            parsed.reset();
        }
        console_bridge::useOutputHandler(previous);
        reason = handler.first_error;
    }
    if (!parsed) {
        throw FormatError(fmt::format("{}: not a valid URDF model{}{}", source,
                                      reason.empty() ? "" : ": ", reason));
    }
    UrdfModel model;
    model.name = parsed->getName();
    if (auto root = parsed->getRoot()) model.root = root->name;
    for (const auto& name : link_order) {
        const urdf::LinkConstSharedPtr l = parsed->getLink(name);
        if (!l) continue;
        UrdfLink link;
        link.name = l->name;
        auto convert = [](const auto& v) {
            UrdfVisual out;
            out.name = v->name;
            out.origin = ToIsometry(v->origin);
            out.geometry = ToGeometry(v->geometry);
            return out;
        };
        for (const auto& v : l->visual_array) {
            UrdfVisual out = convert(v);
            if (v->material) {
                out.material = v->material->name;
                const auto& c = v->material->color;
                out.rgba = Eigen::Vector4d(c.r, c.g, c.b, c.a);
            }
            link.visuals.push_back(std::move(out));
        }
        for (const auto& c : l->collision_array) link.collisions.push_back(convert(c));
        model.links.push_back(std::move(link));
    }
    for (const auto& name : joint_order) {
        const urdf::JointConstSharedPtr j = parsed->getJoint(name);
        if (!j) continue;
        UrdfJoint joint;
        joint.name = j->name;
        joint.type = ToJointType(j->type);
        joint.parent = j->parent_link_name;
        joint.child = j->child_link_name;
        joint.origin = ToIsometry(j->parent_to_joint_origin_transform);
        joint.axis = Eigen::Vector3d(j->axis.x, j->axis.y, j->axis.z);
        if (j->limits) {
            joint.has_limits = true;
            joint.lower = j->limits->lower;
            joint.upper = j->limits->upper;
        }
        model.joints.push_back(std::move(joint));
    }
    return model;
}

UrdfModel ReadUrdf(const std::filesystem::path& path, const UrdfReadParams& params) {
    return ParseUrdf(ReadFileBytes(path), path.string(), params);
}

std::string UrdfToXml(const UrdfModel& model) {
    CheckTree(model);
    TiXmlDocument doc;
    doc.LinkEndChild(new TiXmlDeclaration("1.0", "utf-8", ""));
    auto* robot = new TiXmlElement("robot");
    robot->SetAttribute("name", model.name.empty() ? "model" : model.name);
    doc.LinkEndChild(robot);
    for (const auto& l : model.links) {
        auto* e = new TiXmlElement("link");
        e->SetAttribute("name", l.name);
        for (const auto& v : l.visuals) e->LinkEndChild(VisualElement("visual", v));
        for (const auto& c : l.collisions) e->LinkEndChild(VisualElement("collision", c));
        robot->LinkEndChild(e);
    }
    for (const auto& j : model.joints) {
        auto* e = new TiXmlElement("joint");
        e->SetAttribute("name", j.name);
        e->SetAttribute("type", UrdfJointTypeName(j.type));
        e->LinkEndChild(OriginElement(j.origin));
        auto* parent = new TiXmlElement("parent");
        parent->SetAttribute("link", j.parent);
        e->LinkEndChild(parent);
        auto* child = new TiXmlElement("child");
        child->SetAttribute("link", j.child);
        e->LinkEndChild(child);
        if (j.type != UrdfJointType::kFixed && j.type != UrdfJointType::kFloating) {
            auto* axis = new TiXmlElement("axis");
            axis->SetAttribute("xyz", Vec(j.axis));
            e->LinkEndChild(axis);
        }
        if (j.type == UrdfJointType::kRevolute || j.type == UrdfJointType::kPrismatic ||
            (j.has_limits && j.type != UrdfJointType::kFixed)) {
            auto* limit = new TiXmlElement("limit");
            limit->SetAttribute("lower", Num(j.lower));
            limit->SetAttribute("upper", Num(j.upper));
            limit->SetAttribute("effort", "0");
            limit->SetAttribute("velocity", "0");
            e->LinkEndChild(limit);
        }
        robot->LinkEndChild(e);
    }
    TiXmlPrinter printer;
    printer.SetIndent("  ");
    doc.Accept(&printer);
    return printer.CStr();
}

void WriteUrdf(const std::filesystem::path& path, const UrdfModel& model) {
    const std::string text = UrdfToXml(model);
    WriteFileAtomically(path, [&](std::ostream& os) { os << text; });
}

}  // namespace multicue::io

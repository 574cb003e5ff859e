// OWL-DL export of kitchen maps in the style of KnowRob's semantic maps (thesis section 4.1.3,
// Figures 4.7 and 4.8), written with TinyXML so that every name and value is escaped.

#include <cmath>

#include <fmt/format.h>
#include <tinyxml.h>

#include "multicue/mapping/map_export.hpp"

namespace multicue::mapping {
namespace {

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

}  // namespace multicue::mapping

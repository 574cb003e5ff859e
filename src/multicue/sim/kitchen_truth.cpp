// Ground truth of simulated kitchens: per-point fields of a scan, the kitchen's URDF, and the
// sensor poses a robot would scan it from.

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numbers>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/sim/kitchen_scene.hpp"
#include "multicue/sim/rng.hpp"

namespace multicue::sim {
namespace {

template <typename T>
ExtraField MakeField(const std::string& name, const std::vector<T>& values) {
    ExtraField f{name, 'U', static_cast<std::uint8_t>(sizeof(T)), 1, {}};
    f.data.resize(values.size() * sizeof(T));
    if (!values.empty()) std::memcpy(f.data.data(), values.data(), f.data.size());
    return f;
}

void SetField(PointCloud& cloud, ExtraField field) {
    for (auto& f : cloud.extra_fields) {
        if (f.name == field.name) {
            f = std::move(field);
            return;
        }
    }
    cloud.extra_fields.push_back(std::move(field));
}

std::vector<std::uint16_t> ReadU16(const PointCloud& cloud, const std::string& name) {
    const ExtraField* f = cloud.FindExtraField(name);
    std::vector<std::uint16_t> out(cloud.size(), 0);
    if (f == nullptr || f->size != 2 || f->count != 1 || f->data.size() != 2 * cloud.size()) {
        return out;
    }
    std::memcpy(out.data(), f->data.data(), f->data.size());
    return out;
}

io::UrdfVisual BoxVisual(const SceneObject& o, const std::string& name) {
    io::UrdfVisual v;
    v.name = name;
    const Eigen::AlignedBox3f b = o.mesh->Bounds();
    v.geometry.kind = io::UrdfGeometry::Kind::kBox;
    v.geometry.size = b.sizes().cast<double>();
    v.origin = Eigen::Isometry3d::Identity();
    v.origin.translation() = b.center().cast<double>();
    v.rgba = Eigen::Vector4d(o.color.r / 255.0, o.color.g / 255.0, o.color.b / 255.0, 1.0);
    return v;
}

Eigen::Isometry3d ToDouble(const Eigen::Isometry3f& T) {
    Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
    out.linear() = T.linear().cast<double>();
    out.translation() = T.translation().cast<double>();
    return out;
}

}  // namespace

void AddKitchenTruth(const KitchenScene& kitchen, PointCloud& scan) {
    const std::size_t n = scan.size();
    if (scan.labels.size() != n) {
        throw DataError(fmt::format("kitchen truth: the scan has {} labels for {} points",
                                    scan.labels.size(), n));
    }
    const std::vector<std::uint16_t> part = ReadU16(scan, "part");
    // The kitchen joint that moves each (instance, link).
    std::vector<std::vector<int>> link_joint(kitchen.instances.size());
    for (std::size_t i = 0; i < kitchen.instances.size(); ++i) {
        link_joint[i].assign(kitchen.instances[i].model->links.size(), -1);
    }
    for (std::size_t j = 0; j < kitchen.joints.size(); ++j) {
        const KitchenJoint& kj = kitchen.joints[j];
        const auto& aj = kitchen.instances[static_cast<std::size_t>(kj.instance)]
                             .model->joints[static_cast<std::size_t>(kj.joint)];
        link_joint[static_cast<std::size_t>(kj.instance)][static_cast<std::size_t>(aj.child)] =
            static_cast<int>(j);
    }
    std::vector<std::uint8_t> semantic(n, 0);
    std::vector<std::uint16_t> model(n, 0), link(n, 0), joint(n, 0);
    for (std::size_t i = 0; i < n; ++i) {
        const std::uint32_t label = scan.labels[i];
        if (label == 0 || label > kitchen.truth.size()) continue;
        const KitchenObjectTruth& t = kitchen.truth[label - 1];
        KitchenClass c = t.base;
        if (t.instance >= 0) {
            const SceneObject& o = kitchen.scene.objects[label - 1];
            if (part[i] > 0 && part[i] <= o.mesh->part_names.size()) {
                const std::string& pn = o.mesh->part_names[part[i] - 1u];
                if (pn.find("handle") != std::string::npos) c = KitchenClass::kHandle;
                if (pn.find("knob") != std::string::npos) c = KitchenClass::kKnob;
            }
            model[i] = static_cast<std::uint16_t>(t.instance + 1);
            link[i] = static_cast<std::uint16_t>(t.link + 1);
            const int j =
                link_joint[static_cast<std::size_t>(t.instance)][static_cast<std::size_t>(t.link)];
            // A link without a joint of its own moves with its parent's (a handle link, say).
            int parent = j;
            if (parent < 0) {
                const auto& m = *kitchen.instances[static_cast<std::size_t>(t.instance)].model;
                int l = t.link;
                while (parent < 0 && l >= 0) {
                    const int pj = m.links[static_cast<std::size_t>(l)].parent_joint;
                    if (pj < 0) break;
                    l = m.joints[static_cast<std::size_t>(pj)].parent;
                    parent = link_joint[static_cast<std::size_t>(t.instance)]
                                       [static_cast<std::size_t>(l)];
                }
            }
            joint[i] = static_cast<std::uint16_t>(parent + 1);
        }
        semantic[i] = static_cast<std::uint8_t>(c);
    }
    SetField(scan, MakeField("semantic", semantic));
    SetField(scan, MakeField("model", model));
    SetField(scan, MakeField("link", link));
    SetField(scan, MakeField("joint", joint));
}

void ScanToWorld(PointCloud& scan, const Eigen::Isometry3f& T_world_sensor) {
    for (auto& p : scan.points) {
        if (p.allFinite()) p = T_world_sensor * p;
    }
    for (auto& n : scan.normals) {
        if (n.allFinite()) n = T_world_sensor.linear() * n;
    }
    scan.sensor_origin = T_world_sensor.translation();
    scan.sensor_orientation = Eigen::Quaternionf(T_world_sensor.linear()).normalized();
}

io::UrdfModel KitchenGroundTruthUrdf(const KitchenScene& kitchen) {
    io::UrdfModel urdf;
    urdf.name = "kitchen";
    urdf.root = "kitchen";
    urdf.links.push_back(io::UrdfLink{"kitchen", {}, {}});
    int structure = 0;
    for (std::size_t o = 0; o < kitchen.scene.objects.size(); ++o) {
        const KitchenObjectTruth& t = kitchen.truth[o];
        if (t.instance >= 0 || t.base == KitchenClass::kObject) continue;
        const std::string name = fmt::format(
            "{}_{}", KitchenClassNames()[static_cast<std::size_t>(t.base)], structure++);
        const SceneObject& so = kitchen.scene.objects[o];
        io::UrdfLink link{name, {BoxVisual(so, name)}, {BoxVisual(so, name)}};
        urdf.links.push_back(std::move(link));
        io::UrdfJoint j;
        j.name = name + "_joint";
        j.parent = "kitchen";
        j.child = name;
        j.origin = ToDouble(so.T_world_object);
        urdf.joints.push_back(std::move(j));
    }
    for (const KitchenInstance& inst : kitchen.instances) {
        const ArticulatedModel& m = *inst.model;
        const std::string pre = inst.name + "__";
        for (const ArticulatedLink& l : m.links) {
            io::UrdfLink link;
            link.name = pre + l.name;
            if (l.mesh) {
                // The link's geometry as one box around its mesh (the mesh files are in the
                // library, in file units; the box keeps the URDF self-contained).
                SceneObject so;
                so.mesh = l.mesh;
                link.visuals.push_back(BoxVisual(so, l.semantic));
                link.collisions = link.visuals;
            }
            urdf.links.push_back(std::move(link));
        }
        io::UrdfJoint base;
        base.name = pre + "base_joint";
        base.parent = "kitchen";
        base.child = pre + m.links[static_cast<std::size_t>(m.root)].name;
        base.origin = ToDouble(inst.T_world_model * m.T_model_root);
        urdf.joints.push_back(std::move(base));
        for (const ArticulatedJoint& aj : m.joints) {
            io::UrdfJoint j;
            j.name = pre + aj.name;
            j.type = aj.type;
            j.parent = pre + m.links[static_cast<std::size_t>(aj.parent)].name;
            j.child = pre + m.links[static_cast<std::size_t>(aj.child)].name;
            j.origin = ToDouble(aj.T_parent_joint);
            j.axis = aj.axis.cast<double>();
            j.has_limits =
                aj.type == io::UrdfJointType::kRevolute || aj.type == io::UrdfJointType::kPrismatic;
            j.lower = aj.lower;
            j.upper = aj.upper;
            urdf.joints.push_back(std::move(j));
        }
    }
    return urdf;
}

std::vector<Eigen::Isometry3f> KitchenLaserPoses(const KitchenScene& kitchen, int count,
                                                 std::uint64_t seed) {
    if (count < 0)
        throw InvalidArgument(fmt::format("laser poses: count must be >= 0, got {}", count));
    std::vector<Eigen::Isometry3f> out;
    StreamRng rng(seed, 11);
    const Eigen::Vector3f s = kitchen.size;
    for (int i = 0; i < count; ++i) {
        Eigen::Vector3f p(s.x() / 2, s.y() / 2 - 0.2f, 1.4f);
        float yaw = static_cast<float>(std::numbers::pi / 2);  // facing the back wall (+y)
        if (i > 0) {
            p.x() += static_cast<float>(rng.Uniform(-0.25, 0.25)) * s.x();
            p.y() += static_cast<float>(rng.Uniform(-0.2, 0.1)) * s.y();
            yaw += static_cast<float>(rng.Uniform(-0.5, 0.5));
        }
        for (const KitchenScene::Run& run : kitchen.runs) {
            const float clear = std::max(run.depth, 0.85f) + 0.3f;
            const float d = run.normal.dot(p - run.origin);
            if (d < clear) p += run.normal * (clear - d);
        }
        Eigen::Isometry3f T = Eigen::Isometry3f::Identity();
        T.linear() = Eigen::AngleAxisf(yaw, Eigen::Vector3f::UnitZ()).toRotationMatrix();
        T.translation() = p;
        out.push_back(T);
    }
    return out;
}

std::vector<Eigen::Isometry3f> KitchenCameraPoses(const KitchenScene& kitchen, int count,
                                                  std::uint64_t seed) {
    if (count < 0)
        throw InvalidArgument(fmt::format("camera poses: count must be >= 0, got {}", count));
    std::vector<Eigen::Isometry3f> out;
    if (kitchen.runs.empty()) return out;
    StreamRng rng(seed, 13);
    const Eigen::Vector3f s = kitchen.size;
    const int runs = static_cast<int>(kitchen.runs.size());
    for (int i = 0; i < count; ++i) {
        const KitchenScene::Run& run = kitchen.runs[static_cast<std::size_t>(i % runs)];
        const int per_run = (count + runs - 1 - i % runs) / runs;
        const int k = i / runs;
        const float len = std::max(0.0f, run.end - run.begin);
        float along = run.begin + len * (static_cast<float>(k) + 0.5f) /
                                      static_cast<float>(std::max(1, per_run));
        along += static_cast<float>(rng.Uniform(-0.1, 0.1)) * len;
        along = std::clamp(along, run.begin + 0.3f, std::max(run.begin + 0.3f, run.end - 0.3f));
        const Eigen::Vector3f& n = run.normal;
        const Eigen::Vector3f on_wall = run.origin + run.tangent * along;
        const float depth = std::abs(n.x()) > 0.5f ? s.x() : s.y();
        // Stand clear of a run on the opposite wall (units up to about 0.8 m deep).
        const float dist =
            std::min(2.8f, depth - 0.95f) + static_cast<float>(rng.Uniform(-0.15, 0.0));
        Eigen::Vector3f eye = on_wall + n * dist;
        // Out of every run's units (tall ones up to about 0.85 m deep) and the walls.
        for (const KitchenScene::Run& other : kitchen.runs) {
            const float clear = std::max(other.depth, 0.85f) + 0.3f;
            const float d = other.normal.dot(eye - other.origin);
            if (d < clear) eye += other.normal * (clear - d);
        }
        eye.x() = std::clamp(eye.x(), 0.3f, s.x() - 0.3f);
        eye.y() = std::clamp(eye.y(), 0.3f, s.y() - 0.3f);
        eye.z() = 1.5f + static_cast<float>(rng.Uniform(-0.1, 0.1));
        Eigen::Vector3f target = on_wall + n * 0.5f;
        target.z() = 0.95f;
        out.push_back(LookAt(eye, target));
    }
    return out;
}

}  // namespace multicue::sim

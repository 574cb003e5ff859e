
// Articulated models and simulated kitchens: a PartNet-Mobility-like folder written by the test
// (URDF, semantics.txt, OBJ parts with a material), forward kinematics, the front direction, the
// kitchen library split; with the shared kitchen models: kitchens, ground truth, the simulate
// kitchens and map kitchen commands.

#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>
#include <fstream>
#include <functional>
#include <limits>
#include <memory>
#include <numbers>

#include <nlohmann/json.hpp>

#include "cli_runner.hpp"
#include "multicue/core/exceptions.hpp"
#include "multicue/io/point_cloud_io.hpp"
#include "multicue/io/urdf.hpp"
#include "multicue/sim/kitchen_procedural.hpp"
#include "multicue/sim/kitchen_scene.hpp"
#include "multicue/sim/procedural.hpp"
#include "multicue/sim/sensors.hpp"
#include "reduced_kinect.hpp"
#include "test_util.hpp"

namespace multicue {
namespace {

/// The kitchen's ground-truth URDF parses with urdfdom and holds every joint.
void ExpectUrdfHoldsEveryJoint(const sim::KitchenScene& k) {
    const io::UrdfModel urdf =
        io::ParseUrdf(io::UrdfToXml(sim::KitchenGroundTruthUrdf(k)), "kitchen.urdf");
    for (const auto& j : k.joints) EXPECT_NE(urdf.FindJoint(j.name), nullptr) << j.name;
}

/// An axis-aligned box as an OBJ file with one material of diffuse colour `kd`.
void WriteBoxObj(const std::filesystem::path& path, const Eigen::Vector3f& lo,
                 const Eigen::Vector3f& hi, const std::string& kd) {
    const std::string mtl = path.stem().string() + ".mtl";
    std::ofstream(path.parent_path() / mtl) << "newmtl m\nKd " << kd << "\n";
    std::ofstream o(path);
    o << "mtllib " << mtl << "\nusemtl m\n";
    for (int k = 0; k < 8; ++k) {
        o << "v " << ((k & 1) ? hi.x() : lo.x()) << ' ' << ((k & 2) ? hi.y() : lo.y()) << ' '
          << ((k & 4) ? hi.z() : lo.z()) << "\n";
    }
    o << "f 1 3 4 2\nf 5 6 8 7\nf 1 2 6 5\nf 3 7 8 4\nf 1 5 7 3\nf 2 4 8 6\n";
}

/// A cupboard in PartNet-Mobility's conventions (y up, front towards +z, a door hinged about
/// the y axis at x = -0.4, a drawer sliding along +z, limits without effort), 0.8 x 1.6 x 1.
void WriteCupboard(const std::filesystem::path& dir) {
    std::filesystem::create_directories(dir / "textured_objs");
    WriteBoxObj(dir / "textured_objs/body.obj", {-0.4f, -0.8f, -0.5f}, {0.4f, 0.8f, 0.45f},
                "0.9 0.9 0.9");
    // The door in its link frame (the joint at the hinge: the door extends along +x).
    WriteBoxObj(dir / "textured_objs/door.obj", {0.0f, -0.8f, 0.45f}, {0.8f, 0.2f, 0.5f},
                "0.4 0.2 0.1");
    WriteBoxObj(dir / "textured_objs/handle.obj", {0.7f, -0.4f, 0.5f}, {0.72f, -0.1f, 0.55f},
                "0.7 0.7 0.7");
    WriteBoxObj(dir / "textured_objs/drawer.obj", {-0.4f, 0.25f, 0.45f}, {0.4f, 0.8f, 0.5f},
                "0.2 0.3 0.6");
    std::ofstream(dir / "semantics.txt")
        << "link_0 hinge rotation_door\nlink_1 slider drawer\nlink_2 heavy furniture_body\n";
    std::ofstream(dir / "mobility.urdf") << R"(<?xml version="1.0"?>
<robot name="cupboard">
  <link name="base"/>
  <link name="link_0">
    <visual name="cabinet_door_surface-1"><origin xyz="0 0 0"/><geometry><mesh filename="textured_objs/door.obj"/></geometry></visual>
    <visual name="handle-2"><origin xyz="0 0 0"/><geometry><mesh filename="textured_objs/handle.obj"/></geometry></visual>
  </link>
  <joint name="joint_0" type="revolute"><origin xyz="-0.4 0 0"/><axis xyz="0 -1 0"/>
    <child link="link_0"/><parent link="link_2"/><limit lower="0" upper="1.57"/></joint>
  <link name="link_1">
    <visual name="drawer_front-3"><origin xyz="0 0 0"/><geometry><mesh filename="textured_objs/drawer.obj"/></geometry></visual>
  </link>
  <joint name="joint_1" type="prismatic"><origin xyz="0 0 0"/><axis xyz="0 0 0.5"/>
    <child link="link_1"/><parent link="link_2"/><limit lower="0" upper="0.4"/></joint>
  <link name="link_2">
    <visual name="body-4"><origin xyz="0 0 0"/><geometry><mesh filename="textured_objs/body.obj"/></geometry></visual>
  </link>
  <joint name="joint_2" type="fixed"><origin rpy="1.570796326794897 0 -1.570796326794897" xyz="0 0 0"/>
    <child link="link_2"/><parent link="base"/></joint>
</robot>)";
}

TEST(Articulated, LoadsThroughTheUrdfWithKinematicsAndFront) {
    test::TempDir dir;
    const auto folder = dir / "Cupboard" / "1";
    WriteCupboard(folder);
    const sim::ArticulatedModel m = sim::LoadArticulatedModel(folder, {.scale = 0.5f});
    EXPECT_EQ(m.id, "Cupboard/1");
    ASSERT_EQ(m.links.size(), 4u);
    ASSERT_EQ(m.joints.size(), 3u);
    // Model frame: z up, 0.8 m high after the scale, bottom at 0, front +x.
    EXPECT_NEAR(m.bounds.sizes().z(), 0.8f, 1e-3f);
    EXPECT_NEAR(m.bounds.min().z(), 0.0f, 1e-4f);
    EXPECT_NEAR(m.bounds.sizes().y(), 0.4f, 1e-3f);  // width
    const sim::ArticulatedLink& door = m.links[static_cast<std::size_t>(m.FindLink("link_0"))];
    EXPECT_EQ(door.semantic, "rotation_door");
    ASSERT_TRUE(door.mesh);
    EXPECT_NE(std::find(door.mesh->part_names.begin(), door.mesh->part_names.end(), "handle"),
              door.mesh->part_names.end());
    // Colours from the material: the door is brown (Kd 0.4 0.2 0.1).
    ASSERT_TRUE(door.mesh->mesh.HasVertexColors());
    EXPECT_NEAR(door.mesh->mesh.vertex_colors[0].r, 102, 2);
    EXPECT_NEAR(door.mesh->mesh.vertex_colors[0].b, 26, 2);
    EXPECT_EQ(door.mesh->vertex_reflectance.size(), door.mesh->mesh.vertices.size());
    // Prismatic axis normalised, limits scaled; revolute limits kept.
    EXPECT_NEAR(m.joints[1].axis.norm(), 1.0f, 1e-6f);
    EXPECT_NEAR(m.joints[1].upper, 0.2f, 1e-6f);
    EXPECT_NEAR(m.joints[0].upper, 1.57f, 1e-6f);
    // Opening: the drawer moves along +x (the front), by its travel.
    auto q = m.ClosedState();
    const auto closed = m.LinkPoses(q);
    q[1] = m.joints[1].Opened(1.0f);
    const auto open = m.LinkPoses(q);
    const auto drawer = static_cast<std::size_t>(m.FindLink("link_1"));
    const auto door_link = static_cast<std::size_t>(m.FindLink("link_0"));
    const Eigen::Vector3f d = open[drawer].translation() - closed[drawer].translation();
    EXPECT_NEAR(d.x(), 0.2f, 1e-4f);
    EXPECT_NEAR(d.head<2>().tail<1>().norm() + std::abs(d.z()), 0.0f, 1e-4f);
    // The door's free edge swings out of the front when opened a little.
    q = m.ClosedState();
    q[0] = 0.3f;
    const Eigen::Vector3f edge(0.8f * 0.5f, 0.0f, 0.5f * 0.5f);  // link frame, scaled
    const Eigen::Vector3f moved = m.LinkPoses(q)[door_link] * edge - closed[door_link] * edge;
    EXPECT_GT(moved.x(), 0.02f);
    EXPECT_THROW(m.LinkPoses({0.0f}), InvalidArgument);
    EXPECT_THROW(sim::LoadArticulatedModel(folder, {.scale = -1.0f}), InvalidArgument);
    EXPECT_THROW(sim::LoadArticulatedModel(dir / "none"), IoError);
}

TEST(Articulated, MissingPartMeshesAreSkippedOrRefused) {
    test::TempDir dir;
    const auto folder = dir / "Cupboard" / "2";
    WriteCupboard(folder);
    std::filesystem::remove(folder / "textured_objs/handle.obj");
    EXPECT_THROW(sim::LoadArticulatedModel(folder, {.strict = true}), IoError);
    const sim::ArticulatedModel m = sim::LoadArticulatedModel(folder);
    const auto& parts = m.links[static_cast<std::size_t>(m.FindLink("link_0"))].mesh->part_names;
    EXPECT_EQ(std::find(parts.begin(), parts.end(), "handle"), parts.end());
    // An unreadable URDF is a clear error naming the file.
    std::ofstream(folder / "mobility.urdf") << "<robot name=";
    try {
        sim::LoadArticulatedModel(folder);
        FAIL() << "no exception";
    } catch (const FormatError& e) {
        EXPECT_NE(std::string(e.what()).find("mobility.urdf"), std::string::npos);
    }
}

/// A kitchen of one drawer front (0.6 m wide along y) whose handle is a bar 0.2 m long along y,
/// 4.5 cm in front of it, on two mounts at y = +-0.08.
sim::KitchenScene OneHandleKitchen() {
    auto moved = [](sim::PartMesh m, const Eigen::Vector3f& offset) {
        for (auto& v : m.mesh.vertices) v += offset;
        return m;
    };
    sim::PartMesh mesh = sim::MakeBoxMesh({0.02f, 0.6f, 0.3f}, "drawer_front");
    mesh.AppendParts(moved(sim::MakeBoxMesh({0.015f, 0.2f, 0.015f}, "handle"), {0.045f, 0, 0.19f}));
    for (const float y : {-0.08f, 0.08f}) {
        mesh.AppendParts(
            moved(sim::MakeBoxMesh({0.03f, 0.015f, 0.015f}, "handle"), {0.025f, y, 0.19f}));
    }
    sim::KitchenScene k;
    sim::SceneObject o;
    o.mesh = std::make_shared<const sim::PartMesh>(std::move(mesh));
    k.scene.objects.push_back(o);
    k.truth.push_back({0, 0, sim::KitchenClass::kDrawer});
    return k;
}

/// Bounds of the vertices of `m` with index in [first, last).
Eigen::AlignedBox3f VertexBounds(const sim::PartMesh& m, std::size_t first, std::size_t last) {
    Eigen::AlignedBox3f b;
    for (std::size_t i = first; i < last; ++i) b.extend(m.mesh.vertices[i]);
    return b;
}

TEST(KitchenScene, VaryHandlesStretchesTheBarAndMovesItsMountsRigidly) {
    const sim::KitchenScene original = OneHandleKitchen();
    const sim::PartMesh& before = *original.scene.objects[0].mesh;
    const std::size_t box = 8;  // vertices of a box: front [0, 8), bar [8, 16), mounts
    ASSERT_EQ(before.mesh.vertices.size(), 4 * box);
    sim::HandleVariation v;
    v.chance = 1.0f;
    int longer = 0, shorter = 0;
    for (std::uint64_t seed = 1; seed <= 20; ++seed) {
        sim::KitchenScene k = original;
        ASSERT_EQ(sim::VaryHandles(k, v, seed), 1);
        const sim::PartMesh& after = *k.scene.objects[0].mesh;
        ASSERT_NE(&after, &before);  // a mesh of its own; the shared one is unchanged
        EXPECT_TRUE(VertexBounds(before, box, 2 * box)
                        .isApprox(Eigen::AlignedBox3f(Eigen::Vector3f(0.0375f, -0.1f, 0.19f),
                                                      Eigen::Vector3f(0.0525f, 0.1f, 0.205f))));
        // The front stays; the bar keeps its cross-section and centre, its length lies between
        // half its own and the front's width less the margins.
        EXPECT_TRUE(VertexBounds(after, 0, box).isApprox(VertexBounds(before, 0, box)));
        const Eigen::AlignedBox3f bar = VertexBounds(after, box, 2 * box);
        const float length = bar.sizes().y();
        EXPECT_GE(length, 0.1f - 1e-5f);
        EXPECT_LE(length, 0.6f - 2 * v.front_margin + 1e-5f);
        EXPECT_NEAR(bar.center().y(), 0.0f, 1e-5f);
        EXPECT_NEAR(bar.sizes().x(), 0.015f, 1e-5f);
        EXPECT_NEAR(bar.sizes().z(), 0.015f, 1e-5f);
        // The mounts keep their width and move with the bar's ends.
        for (std::size_t m = 2; m < 4; ++m) {
            const Eigen::AlignedBox3f mount = VertexBounds(after, m * box, (m + 1) * box);
            EXPECT_NEAR(mount.sizes().y(), 0.015f, 1e-5f);
            EXPECT_NEAR(std::abs(mount.center().y()), 0.08f + (length - 0.2f) / 2, 1e-5f);
        }
        longer += length > 0.2f;
        shorter += length < 0.2f;
        // Deterministic for a seed.
        sim::KitchenScene again = original;
        sim::VaryHandles(again, v, seed);
        EXPECT_EQ(again.scene.objects[0].mesh->mesh.vertices, after.mesh.vertices);
    }
    EXPECT_GT(longer, 0);
    EXPECT_GT(shorter, 0);
}

TEST(KitchenScene, VaryHandlesScalesTheReachFromTheFrontAndTheThickness) {
    const sim::KitchenScene original = OneHandleKitchen();
    const std::size_t box = 8;
    sim::HandleVariation v;
    v.chance = 1.0f;
    v.min_reach_scale = v.max_reach_scale = 0.5f;
    v.min_thickness_scale = v.max_thickness_scale = 2.0f;
    sim::KitchenScene k = original;
    ASSERT_EQ(sim::VaryHandles(k, v, 3), 1);
    const sim::PartMesh& after = *k.scene.objects[0].mesh;
    const sim::PartMesh& before = *original.scene.objects[0].mesh;
    EXPECT_TRUE(VertexBounds(after, 0, box).isApprox(VertexBounds(before, 0, box)));
    // The front's surface is at x = 0.01: the bar (0.0375-0.0525) comes half as far out of it,
    // twice as thick along z about the handle's centre, as long as a variation of the length
    // alone makes it.
    const Eigen::AlignedBox3f bar = VertexBounds(after, box, 2 * box);
    EXPECT_NEAR(bar.min().x(), 0.01f + 0.0275f * 0.5f, 1e-5f);
    EXPECT_NEAR(bar.max().x(), 0.01f + 0.0425f * 0.5f, 1e-5f);
    EXPECT_NEAR(bar.sizes().z(), 0.03f, 1e-5f);
    EXPECT_NEAR(bar.center().z(), 0.1975f, 1e-5f);
    sim::HandleVariation length_only;
    length_only.chance = 1.0f;
    sim::KitchenScene lk = original;
    sim::VaryHandles(lk, length_only, 3);
    EXPECT_NEAR(bar.sizes().y(), VertexBounds(*lk.scene.objects[0].mesh, box, 2 * box).sizes().y(),
                1e-5f);
    // The mounts start at the front and reach half as far.
    const Eigen::AlignedBox3f mount = VertexBounds(after, 2 * box, 3 * box);
    EXPECT_NEAR(mount.min().x(), 0.01f, 1e-5f);
    EXPECT_NEAR(mount.max().x(), 0.025f, 1e-5f);
    // Ranges give scales within them; deterministic for a seed.
    v.min_reach_scale = 0.5f;
    v.max_reach_scale = 1.5f;
    v.min_thickness_scale = 0.5f;
    v.max_thickness_scale = 2.0f;
    for (std::uint64_t seed = 1; seed <= 10; ++seed) {
        sim::KitchenScene a = original, b = original;
        sim::VaryHandles(a, v, seed);
        sim::VaryHandles(b, v, seed);
        EXPECT_EQ(a.scene.objects[0].mesh->mesh.vertices, b.scene.objects[0].mesh->mesh.vertices);
        const Eigen::AlignedBox3f varied = VertexBounds(*a.scene.objects[0].mesh, box, 2 * box);
        EXPECT_GE(varied.max().x(), 0.01f + 0.0425f * 0.5f - 1e-5f);
        EXPECT_LE(varied.max().x(), 0.01f + 0.0425f * 1.5f + 1e-5f);
        EXPECT_GE(varied.sizes().z(), 0.0075f - 1e-5f);
        EXPECT_LE(varied.sizes().z(), 0.03f + 1e-5f);
    }
}

TEST(KitchenScene, VaryHandlesLeavesKnobsAndRefusesBadParameters) {
    sim::KitchenScene k = OneHandleKitchen();
    const auto* mesh = k.scene.objects[0].mesh.get();
    sim::HandleVariation v;
    v.chance = 0.0f;
    EXPECT_EQ(sim::VaryHandles(k, v, 1), 0);
    EXPECT_EQ(k.scene.objects[0].mesh.get(), mesh);
    // A round handle (a knob shaped like one) is not stretched.
    v.chance = 1.0f;
    v.min_elongation = 20.0f;
    EXPECT_EQ(sim::VaryHandles(k, v, 1), 0);
    // Room structure (no model instance) is never touched.
    k.truth[0].instance = -1;
    v.min_elongation = 2.0f;
    EXPECT_EQ(sim::VaryHandles(k, v, 1), 0);
    for (auto change : std::vector<std::function<void(sim::HandleVariation&)>>{
             [](auto& h) { h.chance = 1.5f; }, [](auto& h) { h.min_length = 0.0f; },
             [](auto& h) { h.max_length = 0.01f; },
             [](auto& h) { h.min_shrink = std::numeric_limits<float>::quiet_NaN(); },
             [](auto& h) { h.min_elongation = 0.5f; }, [](auto& h) { h.min_reach_scale = 0.0f; },
             [](auto& h) { h.max_thickness_scale = 0.5f; }}) {
        sim::HandleVariation bad;
        change(bad);
        EXPECT_THROW(sim::VaryHandles(k, bad, 1), InvalidArgument);
    }
}

TEST(KitchenLibrary, SplitIsStableAndKeepsDuplicatesInTraining) {
    std::vector<sim::KitchenModelEntry> lib;
    for (int i = 0; i < 6; ++i)
        lib.push_back({"", "CabinetLower/" + std::to_string(100 + i), "cupboard", 1.0f});
    lib.push_back({"", "CabinetUpper/103", "wall_cupboard", 1.0f});
    lib.push_back({"", "CabinetUpper/999", "wall_cupboard", 1.0f});
    const auto a = sim::KitchenSplitOf(lib);
    std::vector<sim::KitchenModelEntry> reversed(lib.rbegin(), lib.rend());
    auto b = sim::KitchenSplitOf(reversed);
    std::reverse(b.begin(), b.end());
    EXPECT_EQ(a, b);  // independent of the order of labels.csv
    int test_count = 0;
    for (std::size_t i = 0; i < 6; ++i) test_count += a[i] == sim::MeshSplit::kTest;
    EXPECT_GE(test_count, 2);
    EXPECT_LE(test_count, 3);
    // Model 103 is listed twice: never a test model.
    EXPECT_EQ(a[3], sim::MeshSplit::kTune);
    EXPECT_EQ(a[6], sim::MeshSplit::kTune);
    EXPECT_EQ(sim::ContainerTypeOfKind("sink_cupboard"), "cupboard");
    // A cupboard of drawers only is a drawer unit; one with a door stays a cupboard, and other
    // kinds keep their type.
    sim::ArticulatedModel drawers = sim::MakeProceduralUnit("drawer_unit", 3);
    EXPECT_EQ(sim::ContainerTypeOfModel(drawers), "drawer_unit");
    drawers.kind = "cupboard";
    EXPECT_EQ(sim::ContainerTypeOfModel(drawers), "drawer_unit");
    drawers.kind = "table";
    EXPECT_EQ(sim::ContainerTypeOfModel(drawers), "table");
    sim::ArticulatedModel doors = sim::MakeProceduralUnit("wall_cupboard", 3);
    EXPECT_EQ(sim::ContainerTypeOfModel(doors), "cupboard");
    doors.joints.clear();
    EXPECT_EQ(sim::ContainerTypeOfModel(doors), "cupboard");
    test::TempDir dir;
    EXPECT_THROW(sim::ReadKitchenLibrary(dir.path()), IoError);
}

std::filesystem::path KitchenModels() { return test::SharedData("meshes/kitchen"); }

TEST(KitchenScene, GroundTruthAndUrdfWithSharedModels) {
    if (!std::filesystem::is_directory(KitchenModels())) GTEST_SKIP() << "no kitchen models";
    const auto lib =
        sim::SelectKitchenSplit(sim::ReadKitchenLibrary(KitchenModels()), sim::MeshSplit::kTune);
    sim::KitchenModelCache cache;
    sim::KitchenScene k = sim::MakeKitchenScene(lib, cache, {}, 3);
    const sim::KitchenScene again = sim::MakeKitchenScene(lib, cache, {}, 3);
    ASSERT_EQ(k.instances.size(), again.instances.size());
    EXPECT_TRUE(k.instances[0].T_world_model.isApprox(again.instances[0].T_world_model));
    EXPECT_GE(k.runs.size(), 2u);
    ASSERT_FALSE(k.joints.empty());
    // The URDF parses with urdfdom and holds every joint.
    ExpectUrdfHoldsEveryJoint(k);
    // A Kinect view: its points carry the kitchen's classes, and fronts have joints.
    const sim::KinectParams kp = test::ReducedKinect(2);
    const auto pose = sim::KitchenCameraPoses(k, 1, 3).at(0);
    PointCloud scan = sim::ScanKinect(sim::RayCaster(k.scene), pose, kp, 1);
    sim::AddKitchenTruth(k, scan);
    const ExtraField* sem = scan.FindExtraField("semantic");
    const ExtraField* joint = scan.FindExtraField("joint");
    ASSERT_NE(sem, nullptr);
    ASSERT_NE(joint, nullptr);
    std::size_t fronts = 0, fronts_with_joint = 0;
    for (std::size_t i = 0; i < scan.size(); ++i) {
        const auto c = static_cast<sim::KitchenClass>(sem->data[i]);
        if (c == sim::KitchenClass::kDoor || c == sim::KitchenClass::kDrawer) {
            ++fronts;
            std::uint16_t j = 0;
            std::memcpy(&j, joint->data.data() + 2 * i, 2);
            fronts_with_joint += j > 0;
        }
    }
    EXPECT_GT(fronts, 1000u);
    EXPECT_GT(fronts_with_joint, fronts * 9 / 10);
    // Opening a joint moves its link.
    const std::size_t j = 0;
    const auto& inst = k.instances[static_cast<std::size_t>(k.joints[j].instance)];
    const int child = inst.model->joints[static_cast<std::size_t>(k.joints[j].joint)].child;
    const int object = inst.link_object[static_cast<std::size_t>(child)];
    ASSERT_GE(object, 0);
    const Eigen::Isometry3f before =
        k.scene.objects[static_cast<std::size_t>(object)].T_world_object;
    k.SetJoint(j, inst.model->joints[static_cast<std::size_t>(k.joints[j].joint)].Opened(0.5f));
    EXPECT_FALSE(k.scene.objects[static_cast<std::size_t>(object)].T_world_object.isApprox(before));
}

TEST(ProceduralUnits, FollowTheModelFrameAndOpenTowardsTheFront) {
    int handles = 0, fronts = 0;
    std::vector<std::string> kinds = sim::ProceduralUnitKinds();
    for (const auto& kind : sim::ProceduralApplianceKinds()) kinds.push_back(kind);
    for (const std::string& kind : kinds) {
        int prismatic = 0;
        for (std::uint64_t seed = 1; seed <= 12; ++seed) {
            const sim::ArticulatedModel m = sim::MakeProceduralUnit(kind, seed);
            SCOPED_TRACE(m.id);
            EXPECT_EQ(m.kind, kind);
            // The closed model's box is centred on x = y = 0, its bottom on the floor, and its
            // size is a unit's.
            EXPECT_NEAR(m.bounds.center().x(), 0.0f, 1e-4f);
            EXPECT_NEAR(m.bounds.center().y(), 0.0f, 1e-4f);
            EXPECT_NEAR(m.bounds.min().z(), 0.0f, 1e-4f);
            EXPECT_GT(m.bounds.sizes().y(), 0.25f);
            EXPECT_LT(m.bounds.sizes().y(), 1.3f);
            EXPECT_LT(m.bounds.sizes().z(),
                      kind == "tall_cupboard" || kind == "fridge" ? 2.3f : 1.0f);
            ASSERT_FALSE(m.joints.empty());
            const auto closed = m.LinkPoses(m.ClosedState());
            for (std::size_t j = 0; j < m.joints.size(); ++j) {
                const sim::ArticulatedJoint& jt = m.joints[j];
                ASSERT_TRUE(jt.Movable());
                const sim::ArticulatedLink& link = m.links[static_cast<std::size_t>(jt.child)];
                ASSERT_TRUE(link.mesh);
                // Colours and laser reflectances on every vertex.
                EXPECT_EQ(link.mesh->mesh.vertex_colors.size(), link.mesh->mesh.vertices.size());
                EXPECT_EQ(link.mesh->vertex_reflectance.size(), link.mesh->mesh.vertices.size());
                EXPECT_NO_THROW(link.mesh->Validate());
                const bool drawer = jt.type == io::UrdfJointType::kPrismatic;
                prismatic += drawer;
                EXPECT_EQ(link.semantic, drawer ? "drawer" : "rotation_door");
                ++fronts;
                bool has_handle = false;
                for (const auto& p : link.mesh->part_names) {
                    has_handle = has_handle || p == "handle" || p == "knob";
                }
                handles += has_handle;
                // Opening moves the front towards +x (out of the unit), never behind its face.
                std::vector<float> q = m.ClosedState();
                q[j] = jt.Opened(0.5f);
                const auto open = m.LinkPoses(q);
                const Eigen::Vector3f c = link.mesh->Bounds().center();
                const std::size_t l = static_cast<std::size_t>(jt.child);
                EXPECT_GT((open[l] * c).x(), (closed[l] * c).x() + 0.05f);
                if (drawer) {
                    EXPECT_NEAR((open[l] * c - closed[l] * c).norm(), jt.Opened(0.5f), 1e-4f);
                    continue;
                }
                // A hinge lies on an edge of its closed front.
                Eigen::AlignedBox3f front;
                for (const auto& v : link.mesh->mesh.vertices) front.extend(closed[l] * v);
                const Eigen::Vector3f hinge = closed[l].translation();
                const Eigen::Vector3f axis = closed[l].linear() * jt.axis;
                const int a = std::abs(axis.z()) > 0.99f ? 1 : 2;  // across the axis
                EXPECT_GT(std::abs(axis.z()) + std::abs(axis.y()), 0.99f);
                EXPECT_LT(std::min(std::abs(hinge[a] - front.min()[a]),
                                   std::abs(hinge[a] - front.max()[a])),
                          1e-4f);
            }
        }
        if (kind == "drawer_unit") {
            EXPECT_GE(prismatic, 24);  // at least two drawers each
        }
    }
    EXPECT_GT(handles, fronts * 9 / 10);
    // Deterministic for a seed, different for another.
    const auto a = sim::MakeProceduralUnit("drawer_unit", 5);
    const auto b = sim::MakeProceduralUnit("drawer_unit", 5);
    const auto c = sim::MakeProceduralUnit("drawer_unit", 6);
    EXPECT_EQ(a.links[1].mesh->mesh.vertices, b.links[1].mesh->mesh.vertices);
    EXPECT_FALSE(a.bounds.isApprox(c.bounds));
    EXPECT_THROW(sim::MakeProceduralUnit("microwave", 1), InvalidArgument);
    EXPECT_THROW(sim::ProceduralKitchenEntries(-1, 1), InvalidArgument);
    EXPECT_THROW(sim::ProceduralKitchenEntries(sim::kMaxProceduralPerKind + 1, 1), InvalidArgument);
}

/// The box of every jointed link (door, drawer) of `m`, closed, in the model frame.
std::vector<Eigen::AlignedBox3f> MovingLinkBoxes(const sim::ArticulatedModel& m) {
    const auto closed = m.LinkPoses(m.ClosedState());
    std::vector<Eigen::AlignedBox3f> boxes;
    for (const sim::ArticulatedJoint& jt : m.joints) {
        const std::size_t l = static_cast<std::size_t>(jt.child);
        Eigen::AlignedBox3f box;
        for (const auto& v : m.links[l].mesh->mesh.vertices) box.extend(closed[l] * v);
        boxes.push_back(box);
    }
    return boxes;
}

TEST(ProceduralUnits, AppliancesOpenAsTheirKindDoes) {
    int knobs_on_ovens = 0, split_fridges = 0, tall_fridges = 0;
    for (std::uint64_t seed = 1; seed <= 20; ++seed) {
        for (const std::string& kind : sim::ProceduralApplianceKinds()) {
            const sim::ArticulatedModel m = sim::MakeProceduralUnit(kind, seed);
            SCOPED_TRACE(m.id);
            EXPECT_EQ(sim::ContainerTypeOfKind(kind), kind);
            int flaps = 0, doors = 0, drawers = 0;
            for (const sim::ArticulatedJoint& jt : m.joints) {
                if (jt.type == io::UrdfJointType::kPrismatic) {
                    ++drawers;
                } else if (std::abs(jt.axis.z()) > 0.99f) {
                    ++doors;
                } else {
                    // Hinged at its bottom edge: it opens downwards, to level at most.
                    EXPECT_GT(jt.axis.y(), 0.99f);
                    EXPECT_LE(jt.upper, 1.56f);
                    ++flaps;
                }
            }
            if (kind == "fridge") {
                EXPECT_EQ(flaps + drawers, 0);
                ASSERT_GE(doors, 1);
                ASSERT_LE(doors, 2);
                // Two doors turn about one side.
                if (doors == 2) {
                    EXPECT_EQ(m.joints[0].axis.z(), m.joints[1].axis.z());
                }
                split_fridges += doors == 2;
                tall_fridges += m.bounds.sizes().z() > 1.5f;
            } else {
                EXPECT_EQ(flaps, 1);
                EXPECT_EQ(doors, 0);
                EXPECT_LE(drawers, kind == "oven" ? 1 : 0);
            }
            if (kind == "oven") {
                int knobs = 0;
                for (const auto& p : m.links[0].mesh->part_names) knobs += p == "knob";
                knobs_on_ovens += knobs > 0;
            }
        }
    }
    EXPECT_EQ(knobs_on_ovens, 20);
    EXPECT_GE(split_fridges, 3);
    EXPECT_GE(tall_fridges, 6);
    EXPECT_LE(tall_fridges, 18);
    // Appliances come after the cupboard kinds, whose entries stay the same.
    const auto cupboards = sim::ProceduralKitchenEntries(2, 11);
    const auto all = sim::ProceduralKitchenEntries(2, 11, true);
    ASSERT_EQ(all.size(), cupboards.size() + 2 * sim::ProceduralApplianceKinds().size());
    for (std::size_t i = 0; i < cupboards.size(); ++i) EXPECT_EQ(all[i].id, cupboards[i].id);
    EXPECT_EQ(all.back().kind, "fridge");
}

TEST(ProceduralUnits, SomeDrawerUnitsHoldAPanDrawer) {
    // A fifth of the drawer units end in a pan drawer as tall as a low door (over 45 cm); no
    // drawer is taller than 60 cm.
    int pans = 0;
    for (std::uint64_t seed = 1; seed <= 40; ++seed) {
        const sim::ArticulatedModel m = sim::MakeProceduralUnit("drawer_unit", seed);
        bool pan = false;
        for (const Eigen::AlignedBox3f& box : MovingLinkBoxes(m)) {
            EXPECT_LT(box.sizes().z(), 0.6f) << m.id;
            pan = pan || box.sizes().z() > 0.45f;
        }
        pans += pan;
    }
    EXPECT_GE(pans, 2);
    EXPECT_LE(pans, 16);
}

TEST(ProceduralUnits, SomeDrawerUnitsAreDeep) {
    // A quarter of the drawer units are 0.8-1.0 m deep, with drawer boxes to match; the rest,
    // and every cupboard, no deeper than 0.62 m (carcasses; the fronts and handles add some).
    int deep = 0;
    for (std::uint64_t seed = 1; seed <= 40; ++seed) {
        const sim::ArticulatedModel m = sim::MakeProceduralUnit("drawer_unit", seed);
        const float d = m.bounds.sizes().x();
        // The carcass, the fronts and the handles standing out of them.
        EXPECT_LE(d, 1.1f) << m.id;
        EXPECT_TRUE(d < 0.75f || d > 0.8f) << m.id << " " << d;
        if (d < 0.8f) continue;
        ++deep;
        for (const Eigen::AlignedBox3f& box : MovingLinkBoxes(m)) {
            EXPECT_GT(box.sizes().x(), 0.6f) << m.id;
        }
        // Identical to the unit drawn again.
        EXPECT_EQ(sim::MakeProceduralUnit("drawer_unit", seed).bounds.sizes().x(), d);
    }
    EXPECT_GE(deep, 3);
    EXPECT_LE(deep, 18);
    for (std::uint64_t seed = 1; seed <= 20; ++seed) {
        EXPECT_LT(sim::MakeProceduralUnit("cupboard", seed).bounds.sizes().x(), 0.75f);
    }
}

TEST(ProceduralUnits, MakeKitchensWithGroundTruth) {
    const auto entries = sim::ProceduralKitchenEntries(3, 11);
    ASSERT_EQ(entries.size(), 3 * sim::ProceduralUnitKinds().size());
    EXPECT_NE(entries[0].id, sim::ProceduralKitchenEntries(3, 12)[0].id);
    sim::KitchenModelCache cache;
    const sim::KitchenScene k = sim::MakeKitchenScene(entries, cache, {}, 2);
    ASSERT_GE(k.instances.size(), 3u);
    ASSERT_FALSE(k.joints.empty());
    // The cache builds each unit once.
    EXPECT_EQ(cache.Get(entries[4]), cache.Get(entries[4]));
    EXPECT_EQ(cache.Get(entries[4])->id, entries[4].id);
    ExpectUrdfHoldsEveryJoint(k);
    const sim::KinectParams kp = test::ReducedKinect(2);
    PointCloud scan =
        sim::ScanKinect(sim::RayCaster(k.scene), sim::KitchenCameraPoses(k, 1, 2).at(0), kp, 1);
    sim::AddKitchenTruth(k, scan);
    const ExtraField* sem = scan.FindExtraField("semantic");
    ASSERT_NE(sem, nullptr);
    std::size_t fronts = 0, handles = 0;
    for (std::size_t i = 0; i < scan.size(); ++i) {
        const auto c = static_cast<sim::KitchenClass>(sem->data[i]);
        fronts += c == sim::KitchenClass::kDoor || c == sim::KitchenClass::kDrawer;
        handles += c == sim::KitchenClass::kHandle || c == sim::KitchenClass::kKnob;
    }
    EXPECT_GT(fronts, 1000u);
    EXPECT_GT(handles, 20u);
}

TEST(KitchenCli, SimulateThenMapWithSharedModels) {
    if (!std::filesystem::is_directory(KitchenModels())) GTEST_SKIP() << "no kitchen models";
    test::TempDir dir;
    const auto sim_dir = dir / "sim";
    auto r = test::RunCli(
        "simulate kitchens --kitchens 1 --views 1 --laser-views 0 --open-doors "
        "--open-count 1 -q --out " +
        sim_dir.string() + " --models " + KitchenModels().string());
    ASSERT_EQ(r.code, 0) << r.output;
    const auto manifest = nlohmann::json::parse(test::ReadTextFile(sim_dir / "manifest.json"));
    EXPECT_TRUE(manifest["complete"].get<bool>());
    const auto& kitchen = manifest["kitchens"][0];
    EXPECT_NO_THROW(io::ReadUrdf(sim_dir / kitchen["urdf"].get<std::string>()));
    const std::string frame = kitchen["frames"][0]["file"].get<std::string>();
    const PointCloud scan = io::ReadPointCloud(sim_dir / frame);
    EXPECT_TRUE(scan.HasSensorPosition());
    EXPECT_NE(scan.FindExtraField("semantic"), nullptr);
    const auto map_dir = dir / "map";
    std::string opened;
    if (!kitchen["opened"].empty()) {
        opened =
            " --opened " + (sim_dir / kitchen["opened"][0]["file"].get<std::string>()).string();
    }
    // The fixture classifier of `train fixtures` (one small kitchen) serves `map kitchen`.
    const auto fixtures = dir / "fixtures.mcm";
    const auto rows = dir / "rows.csv";
    r = test::RunCli(
        "train fixtures --kitchens 1 --views 1 -q --vary-handles --procedural 2 --out " +
        fixtures.string() + " --rows " + rows.string() + " --kitchen " + KitchenModels().string());
    ASSERT_EQ(r.code, 0) << r.output;
    // The candidate rows: a header of the fixture features and one labelled row per candidate.
    const std::string csv = test::ReadTextFile(rows);
    EXPECT_NE(csv.find("local_protrusion"), std::string::npos);
    EXPECT_NE(csv.find("handle"), std::string::npos);
    r = test::RunCli("map kitchen " + (sim_dir / frame).string() + opened + " -q --fixtures " +
                     fixtures.string() + " --out " + map_dir.string());
    ASSERT_EQ(r.code, 0) << r.output;
    for (const char* f : {"map.json", "map.urdf", "map.owl", "labels.pcd", "report.html"}) {
        EXPECT_TRUE(std::filesystem::is_regular_file(map_dir / f)) << f;
    }
    const io::UrdfModel urdf = io::ReadUrdf(map_dir / "map.urdf");
    EXPECT_FALSE(urdf.joints.empty());
    if (std::system("command -v check_urdf > /dev/null 2>&1") == 0) {
        const int code = std::system(
            ("check_urdf " + (map_dir / "map.urdf").string() + " > /dev/null 2>&1").c_str());
        EXPECT_EQ(code, 0);
    }
    const PointCloud labels = io::ReadPointCloud(map_dir / "labels.pcd");
    EXPECT_EQ(labels.size(), scan.size());
    EXPECT_NE(labels.FindExtraField("semantic"), nullptr);
}

TEST(KitchenCli, ProceduralKitchensWithoutTheLibrary) {
    // Kitchens of procedural units need no model files: simulate, train and map end to end.
    test::TempDir dir;
    const auto sim_dir = dir / "sim";
    auto r = test::RunCli(
        "simulate kitchens --models none --procedural 3 --procedural-appliances --kitchens 1 "
        "--views 1 --laser-views 0 --open-doors --open-count 1 -q --out " +
        sim_dir.string());
    ASSERT_EQ(r.code, 0) << r.output;
    const auto manifest = nlohmann::json::parse(test::ReadTextFile(sim_dir / "manifest.json"));
    EXPECT_TRUE(manifest["complete"].get<bool>());
    EXPECT_TRUE(manifest["procedural_appliances"].get<bool>());
    const auto& kitchen = manifest["kitchens"][0];
    for (const auto& m : kitchen["models"]) {
        EXPECT_EQ(m["model"].get<std::string>().rfind("procedural/", 0), 0u) << m["model"];
    }
    EXPECT_NO_THROW(io::ReadUrdf(sim_dir / kitchen["urdf"].get<std::string>()));
    const auto fixtures = dir / "fixtures.mcm";
    r = test::RunCli(
        "train fixtures --kitchen none --procedural 3 --kitchens 2 --views 2 -q --out " +
        fixtures.string());
    ASSERT_EQ(r.code, 0) << r.output;
    const auto map_dir = dir / "map";
    std::string opened;
    if (!kitchen["opened"].empty()) {
        opened =
            " --opened " + (sim_dir / kitchen["opened"][0]["file"].get<std::string>()).string();
    }
    // The container classifier, on maps made with that fixture classifier.
    const auto containers = dir / "containers.mcm";
    const auto rows = dir / "pieces.csv";
    r = test::RunCli(
        "train containers --kitchen none --procedural 2 --kitchens 1 --views 1 --laser-views 0 "
        "-q --kinect-fixtures " +
        fixtures.string() + " --rows " + rows.string() + " --out " + containers.string());
    ASSERT_EQ(r.code, 0) << r.output;
    const std::string csv = test::ReadTextFile(rows);
    EXPECT_NE(csv.find("container:drawers"), std::string::npos);
    EXPECT_NE(csv.find("cupboard"), std::string::npos);
    // The joint classifier, on the same kind of maps.
    const auto joints = dir / "joints.mcm";
    const auto front_rows = dir / "fronts.csv";
    r = test::RunCli(
        "train joints --kitchen none --procedural 2 --kitchens 1 --views 1 --laser-views 0 -q "
        "--kinect-fixtures " +
        fixtures.string() + " --rows " + front_rows.string() + " --out " + joints.string());
    ASSERT_EQ(r.code, 0) << r.output;
    EXPECT_NE(test::ReadTextFile(front_rows).find("joint:length_share"), std::string::npos);
    r = test::RunCli(
        "map kitchen " + (sim_dir / kitchen["frames"][0]["file"].get<std::string>()).string() +
        opened + " -q --fixtures " + fixtures.string() + " --containers " + containers.string() +
        " --joints " + joints.string() + " --out " + map_dir.string());
    ASSERT_EQ(r.code, 0) << r.output;
    EXPECT_FALSE(io::ReadUrdf(map_dir / "map.urdf").links.empty());
    const auto map_json = nlohmann::json::parse(test::ReadTextFile(map_dir / "map.json"));
    ASSERT_FALSE(map_json["furniture"].empty());
    // A fixture classifier where the container one belongs is refused before any work, and
    // the other way round.
    r = test::RunCli("map kitchen " +
                     (sim_dir / kitchen["frames"][0]["file"].get<std::string>()).string() +
                     " -q --containers " + fixtures.string() + " --out " + (dir / "z").string());
    EXPECT_EQ(r.code, 2) << r.output;
    EXPECT_NE(r.output.find("container features"), std::string::npos) << r.output;
    EXPECT_FALSE(std::filesystem::exists(dir / "z"));
    r = test::RunCli("map kitchen " +
                     (sim_dir / kitchen["frames"][0]["file"].get<std::string>()).string() +
                     " -q --joints " + containers.string() + " --out " + (dir / "z").string());
    EXPECT_EQ(r.code, 2) << r.output;
    EXPECT_NE(r.output.find("joint features"), std::string::npos) << r.output;
    EXPECT_FALSE(std::filesystem::exists(dir / "z"));
    r = test::RunCli("train containers --kitchen none --procedural 2 --kinect-fixtures " +
                     containers.string() + " --out " + (dir / "y.mcm").string());
    EXPECT_EQ(r.code, 2) << r.output;
    EXPECT_EQ(r.output.find("kitchens:"), std::string::npos) << r.output;
    EXPECT_FALSE(std::filesystem::exists(dir / "y.mcm"));
    // Without procedural units there is nothing to build kitchens from.
    EXPECT_EQ(test::RunCli("simulate kitchens --models none --out " + (dir / "x").string()).code,
              2);
    EXPECT_EQ(test::RunCli("train fixtures --kitchen none --out " + (dir / "x.mcm").string()).code,
              2);
    EXPECT_FALSE(std::filesystem::exists(dir / "x"));
    EXPECT_FALSE(std::filesystem::exists(dir / "x.mcm"));
}

TEST(KitchenCli, BadInputWritesNothing) {
    test::TempDir dir;
    // An empty cloud.
    {
        std::ofstream(dir / "empty.pcd") << "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\n"
                                            "TYPE F F F\nCOUNT 1 1 1\nWIDTH 0\nHEIGHT 1\nPOINTS 0\n"
                                            "DATA ascii\n";
    }
    auto r = test::RunCli("map kitchen " + (dir / "empty.pcd").string() + " --out " +
                          (dir / "a").string());
    EXPECT_EQ(r.code, 1) << r.output;
    EXPECT_FALSE(std::filesystem::exists(dir / "a"));
    // A floor and nothing else: no vertical planes.
    {
        std::ofstream o(dir / "floor.pcd");
        o << "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
             "WIDTH 2601\nHEIGHT 1\nVIEWPOINT 1 1 1.4 1 0 0 0\nPOINTS 2601\nDATA ascii\n";
        for (int i = 0; i <= 50; ++i) {
            for (int j = 0; j <= 50; ++j) o << i * 0.04 << ' ' << j * 0.04 << " 0\n";
        }
    }
    r = test::RunCli("map kitchen " + (dir / "floor.pcd").string() + " --out " +
                     (dir / "b").string());
    EXPECT_EQ(r.code, 1) << r.output;
    EXPECT_NE(r.output.find("vertical"), std::string::npos) << r.output;
    EXPECT_FALSE(std::filesystem::exists(dir / "b"));
    // Scans that look like different sensors (a coloured one: a Kinect's; one of points alone,
    // unorganized: a laser's) are refused, unless --sensor names the parameters.
    {
        std::ofstream o(dir / "floor_rgb.pcd");
        o << "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z rgb\nSIZE 4 4 4 4\nTYPE F F F U\n"
             "COUNT 1 1 1 1\nWIDTH 441\nHEIGHT 1\nVIEWPOINT 1 1 1.4 1 0 0 0\nPOINTS 441\n"
             "DATA ascii\n";
        for (int i = 0; i <= 20; ++i) {
            for (int j = 0; j <= 20; ++j) o << i * 0.04 << ' ' << j * 0.04 << " 0 8421504\n";
        }
    }
    const std::string mixed =
        "map kitchen " + (dir / "floor.pcd").string() + ' ' + (dir / "floor_rgb.pcd").string();
    r = test::RunCli(mixed + " --out " + (dir / "b").string());
    EXPECT_EQ(r.code, 2) << r.output;
    EXPECT_NE(r.output.find("--sensor"), std::string::npos) << r.output;
    EXPECT_FALSE(std::filesystem::exists(dir / "b"));
    r = test::RunCli(mixed + " --sensor laser --out " + (dir / "b").string());
    EXPECT_EQ(r.code, 1) << r.output;
    EXPECT_NE(r.output.find("vertical"), std::string::npos) << r.output;
    EXPECT_FALSE(std::filesystem::exists(dir / "b"));
    // Bad options: usage errors.
    EXPECT_EQ(test::RunCli("map kitchen " + (dir / "floor.pcd").string() +
                           " --sensor sonar --out " + (dir / "c").string())
                  .code,
              2);
    EXPECT_EQ(test::RunCli("simulate kitchens --kitchens -1 --out " + (dir / "d").string()).code,
              2);
    EXPECT_EQ(test::RunCli("simulate kitchens --procedural -1 --out " + (dir / "d").string()).code,
              2);
    EXPECT_EQ(
        test::RunCli("simulate kitchens --procedural-appliances --out " + (dir / "d").string())
            .code,
        2);
    EXPECT_FALSE(std::filesystem::exists(dir / "d"));
    EXPECT_EQ(test::RunCli("map kitchen --out " + (dir / "e").string()).code, 2);
    EXPECT_FALSE(std::filesystem::exists(dir / "c"));
    for (const std::string bad :
         {"--sensor sonar", "--kitchens 0", "--classifier bogus", "--split half", "--views -1",
          "--vary-handles --handle-lengths 0.5,0.1", "--handle-lengths 0.1",
          "--vary-handles --handle-reach 1.5,0.5", "--handle-thickness 0,2", "--handle-reach 2",
          "--procedural -1", "--procedural 100000", "--procedural-share 1.5", "--fold 2"}) {
        r = test::RunCli("train fixtures " + bad + " --out " + (dir / "f.mcm").string());
        EXPECT_EQ(r.code, 2) << bad << ": " << r.output;
    }
    EXPECT_EQ(test::RunCli("train fixtures --out " + (dir / "none" / "f.mcm").string()).code, 2);
    EXPECT_EQ(test::RunCli("train fixtures --out " + (dir / "f.mcm").string() + " --rows " +
                           (dir / "none" / "rows.mcd").string())
                  .code,
              2);
    EXPECT_FALSE(std::filesystem::exists(dir / "f.mcm"));
    for (const std::string& bad : std::vector<std::string>{
             "--sensor sonar", "--kitchens 0", "--views -1", "--sensor kinect --views 0",
             "--fold 2", "--split half", "--procedural -1", "--procedural 100000",
             "--procedural-share 1.5", "--classifier bogus", "--kitchen none --procedural 0",
             "--rows " + (dir / "none" / "rows.csv").string()}) {
        for (const char* job : {"containers", "joints"}) {
            r = test::RunCli(std::string("train ") + job + ' ' + bad + " --out " +
                             (dir / "g.mcm").string());
            EXPECT_EQ(r.code, 2) << job << ' ' << bad << ": " << r.output;
        }
    }
    EXPECT_EQ(test::RunCli("train containers --out " + (dir / "none" / "g.mcm").string()).code, 2);
    r = test::RunCli("train containers --kinect-fixtures " + (dir / "missing.mcm").string() +
                     " --out " + (dir / "g.mcm").string());
    EXPECT_EQ(r.code, 1) << r.output;
    EXPECT_FALSE(std::filesystem::exists(dir / "g.mcm"));
}

}  // namespace
}  // namespace multicue

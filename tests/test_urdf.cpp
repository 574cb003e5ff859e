// URDF reading (urdfdom) and writing: round trips, PartNet-Mobility limits, bad files.

#include <gtest/gtest.h>

#include <fstream>

#include "cli_runner.hpp"
#include "multicue/core/exceptions.hpp"
#include "multicue/io/urdf.hpp"
#include "test_util.hpp"

namespace multicue {
namespace {

io::UrdfModel TwoJointModel() {
    io::UrdfModel m;
    m.name = "cabinet";
    m.root = "base";
    io::UrdfVisual box;
    box.name = "body";
    box.geometry.kind = io::UrdfGeometry::Kind::kBox;
    box.geometry.size = {0.6, 0.5, 0.8};
    box.rgba = Eigen::Vector4d(0.5, 0.5, 0.5, 1.0);
    io::UrdfVisual mesh;
    mesh.name = "handle";
    mesh.geometry.kind = io::UrdfGeometry::Kind::kMesh;
    mesh.geometry.filename = "parts/handle.obj";
    mesh.geometry.scale = {0.5, 0.5, 0.5};
    mesh.origin.translation() = Eigen::Vector3d(0.1, 0.2, 0.3);
    m.links = {{"base", {box}, {box}}, {"door", {mesh}, {}}, {"drawer", {}, {}}};
    io::UrdfJoint hinge;
    hinge.name = "hinge";
    hinge.type = io::UrdfJointType::kRevolute;
    hinge.parent = "base";
    hinge.child = "door";
    hinge.origin.linear() =
        Eigen::AngleAxisd(0.7, Eigen::Vector3d(0.2, 0.3, 1.0).normalized()).toRotationMatrix();
    hinge.origin.translation() = Eigen::Vector3d(-0.3, 0.25, 0.1);
    hinge.axis = Eigen::Vector3d(0, 0, 1);
    hinge.has_limits = true;
    hinge.lower = 0.0;
    hinge.upper = 1.5;
    io::UrdfJoint slide = hinge;
    slide.name = "slide";
    slide.type = io::UrdfJointType::kPrismatic;
    slide.child = "drawer";
    slide.axis = Eigen::Vector3d(1, 0, 0);
    slide.upper = 0.4;
    m.joints = {hinge, slide};
    return m;
}

TEST(Urdf, WriteThenReadRoundTrips) {
    const io::UrdfModel m = TwoJointModel();
    const io::UrdfModel r = io::ParseUrdf(io::UrdfToXml(m), "round trip");
    EXPECT_EQ(r.name, "cabinet");
    EXPECT_EQ(r.root, "base");
    ASSERT_EQ(r.links.size(), 3u);
    ASSERT_EQ(r.joints.size(), 2u);
    for (std::size_t j = 0; j < 2; ++j) {
        EXPECT_EQ(r.joints[j].name, m.joints[j].name);
        EXPECT_EQ(r.joints[j].type, m.joints[j].type);
        EXPECT_EQ(r.joints[j].parent, m.joints[j].parent);
        EXPECT_EQ(r.joints[j].child, m.joints[j].child);
        EXPECT_TRUE(r.joints[j].origin.isApprox(m.joints[j].origin, 1e-6));
        EXPECT_TRUE(r.joints[j].axis.isApprox(m.joints[j].axis, 1e-9));
        EXPECT_NEAR(r.joints[j].upper, m.joints[j].upper, 1e-9);
    }
    const io::UrdfLink* door = r.FindLink("door");
    ASSERT_NE(door, nullptr);
    ASSERT_EQ(door->visuals.size(), 1u);
    EXPECT_EQ(door->visuals[0].geometry.filename, "parts/handle.obj");
    EXPECT_TRUE(door->visuals[0].geometry.scale.isApprox(Eigen::Vector3d(0.5, 0.5, 0.5)));
    EXPECT_TRUE(door->visuals[0].origin.translation().isApprox(Eigen::Vector3d(0.1, 0.2, 0.3)));
    const io::UrdfLink* base = r.FindLink("base");
    ASSERT_NE(base, nullptr);
    EXPECT_TRUE(base->visuals[0].geometry.size.isApprox(Eigen::Vector3d(0.6, 0.5, 0.8)));
    EXPECT_EQ(r.ParentJoint("drawer")->name, "slide");
}

TEST(Urdf, LimitsWithoutEffortAreCompletedForPartNetFiles) {
    const std::string xml = R"(<?xml version="1.0"?>
<robot name="partnet">
  <link name="base"/>
  <link name="link_0"><visual name="handle-3"><origin xyz="0 0 0"/>
    <geometry><mesh filename="textured_objs/a.obj"/></geometry></visual></link>
  <joint name="joint_0" type="prismatic"><origin xyz="0 0 0.5"/><axis xyz="0 0 0.1"/>
    <child link="link_0"/><parent link="base"/><limit lower="0" upper="0.88"/></joint>
</robot>)";
    EXPECT_THROW(io::ParseUrdf(xml, "strict", {.complete_limits = false}), FormatError);
    const io::UrdfModel m = io::ParseUrdf(xml, "partnet");
    ASSERT_EQ(m.joints.size(), 1u);
    EXPECT_EQ(m.joints[0].type, io::UrdfJointType::kPrismatic);
    EXPECT_NEAR(m.joints[0].upper, 0.88, 1e-12);
    EXPECT_TRUE(m.joints[0].axis.isApprox(Eigen::Vector3d(0, 0, 0.1)));  // kept as written
    EXPECT_EQ(m.links[1].visuals[0].name, "handle-3");
}

TEST(Urdf, BadFilesThrowNamingTheFile) {
    test::TempDir dir;
    EXPECT_THROW(io::ReadUrdf(dir / "missing.urdf"), IoError);
    { std::ofstream(dir / "broken.urdf") << "<robot name=\"x\"><link name=\"a\">"; }
    try {
        io::ReadUrdf(dir / "broken.urdf");
        FAIL() << "no exception";
    } catch (const FormatError& e) {
        EXPECT_NE(std::string(e.what()).find("broken.urdf"), std::string::npos);
    }
    // Well-formed XML, but a joint naming a link that does not exist.
    const std::string dangling =
        "<robot name=\"x\"><link name=\"a\"/><joint name=\"j\" type=\"fixed\"><parent "
        "link=\"a\"/><child link=\"nope\"/></joint></robot>";
    EXPECT_THROW(io::ParseUrdf(dangling, "dangling"), FormatError);
    EXPECT_THROW(io::ParseUrdf("", "empty"), FormatError);
}

TEST(Urdf, WriterRefusesModelsThatAreNoTree) {
    io::UrdfModel m = TwoJointModel();
    m.joints[1].child = "door";  // two parents
    EXPECT_THROW(io::UrdfToXml(m), InvalidArgument);
    m = TwoJointModel();
    m.joints[0].parent = "ghost";
    EXPECT_THROW(io::UrdfToXml(m), InvalidArgument);
    m = TwoJointModel();
    m.links.push_back({"base", {}, {}});
    EXPECT_THROW(io::UrdfToXml(m), InvalidArgument);
}

TEST(Urdf, WriteIsAtomic) {
    test::TempDir dir;
    const auto path = dir / "m.urdf";
    io::WriteUrdf(path, TwoJointModel());
    const std::string before = test::ReadTextFile(path);
    io::UrdfModel bad = TwoJointModel();
    bad.joints[0].parent = "ghost";
    EXPECT_THROW(io::WriteUrdf(path, bad), InvalidArgument);
    EXPECT_EQ(test::ReadTextFile(path), before);
    EXPECT_NO_THROW(io::ReadUrdf(path));
}

}  // namespace
}  // namespace multicue

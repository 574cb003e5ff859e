// Models of perceived objects: verification against free space, mesh fallback, attached outlier
// surfaces, rotational models and the grasp summary in result.json.

#include <cmath>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "multicue/core/exceptions.hpp"
#include "multicue/sim/tabletop_scene.hpp"
#include "multicue/system/perceive.hpp"
#include "multicue/system/perceive_output.hpp"

namespace multicue {
namespace {

// Camera frame: sensor at the origin looking along +z, up = -y; the table is y = 0.3.
const Eigen::Vector4f kPlane(0.0f, -1.0f, 0.0f, 0.3f);

void Add(PointCloud& cloud, const Eigen::Vector3f& p, const Eigen::Vector3f& n) {
    cloud.points.push_back(p);
    cloud.normals.push_back(n.normalized());
}

void Finish(PointCloud& cloud) {
    cloud.width = static_cast<std::uint32_t>(cloud.points.size());
    cloud.height = 1;
}

// A vertical plate facing the camera at depth z, x in [x0, x1], from the table up to y = 0.15.
Indices AddPlate(PointCloud& cloud, float x0, float x1, float z) {
    Indices idx;
    for (float x = x0; x <= x1 + 1e-6f; x += 0.004f) {
        for (float y = 0.15f; y <= 0.3f + 1e-6f; y += 0.004f) {
            idx.push_back(static_cast<Index>(cloud.points.size()));
            Add(cloud, {x, y, z}, {0, 0, -1});
        }
    }
    return idx;
}

// A wall behind everything, seen through any gap.
void AddWall(PointCloud& cloud) {
    for (float x = -0.3f; x <= 0.3f; x += 0.005f) {
        for (float y = 0.0f; y <= 0.3f; y += 0.005f) Add(cloud, {x, y, 1.5f}, {0, 0, -1});
    }
}

PerceiveParams Params() {
    PerceiveParams p;
    p.num_threads = 1;
    return p;
}

ModelParams Models() {
    ModelParams p;
    p.num_threads = 1;
    return p;
}

TEST(PerceiveModels, ModelInFreeSpaceIsRejectedAndReplacedByAMesh) {
    // Two plates 24 cm apart, one object categorised as a box: the box closes the gap, where the
    // sensor sees the wall behind.
    PointCloud cloud;
    PerceivedObject object;
    object.indices = AddPlate(cloud, -0.16f, -0.12f, 1.0f);
    const Indices right = AddPlate(cloud, 0.12f, 0.16f, 1.0f);
    object.indices.insert(object.indices.end(), right.begin(), right.end());
    AddWall(cloud);
    Finish(cloud);
    object.category.category = Category::kBox;
    const ObjectModel m = ModelObject(cloud, object, kPlane, Models());
    ASSERT_TRUE(m.verification.has_value());
    EXPECT_GT(m.verification->invalid, 0.25f);
    EXPECT_FALSE(m.verification->accepted);
    EXPECT_FALSE(m.accepted);
    EXPECT_EQ(m.replaced, "box");
    EXPECT_EQ(m.replace_reason, "verification");
    EXPECT_FALSE(m.box.has_value());
    EXPECT_FALSE(m.mesh.triangles.empty());
    // The mesh is the object's surface: its vertices lie on the plates, none in the gap.
    for (const auto& v : m.mesh.vertices) {
        EXPECT_NEAR(v.z(), 1.0f, 1e-4f);
        EXPECT_GT(std::abs(v.x()), 0.115f);
    }

    // Without the fallback the box stays, marked as not accepted.
    ModelParams p = Models();
    p.mesh_fallback = false;
    const ObjectModel kept = ModelObject(cloud, object, kPlane, p);
    EXPECT_TRUE(kept.box.has_value());
    EXPECT_FALSE(kept.accepted);
}

TEST(PerceiveModels, ModelMatchingTheScanIsAccepted) {
    PointCloud cloud;
    PerceivedObject object;
    object.indices = AddPlate(cloud, -0.12f, 0.12f, 1.0f);
    AddWall(cloud);
    Finish(cloud);
    object.category.category = Category::kBox;
    const ObjectModel m = ModelObject(cloud, object, kPlane, Models());
    ASSERT_TRUE(m.box.has_value());
    ASSERT_TRUE(m.verification.has_value());
    EXPECT_TRUE(m.accepted);
    EXPECT_LT(m.verification->invalid, 0.1f);
    EXPECT_GT(m.verification->verified, 0.2f);
    EXPECT_TRUE(m.replaced.empty());
    // Grasp summary: a 24 cm wide, 15 cm high plate.
    ASSERT_EQ(m.grasp.dimensions.size(), 3u);
    EXPECT_NEAR(m.grasp.dimensions[0].second, 0.24f, 0.01f);
    EXPECT_NEAR(m.grasp.dimensions[2].second, 0.15f, 0.01f);
    EXPECT_LT(m.grasp.graspable_width, 0.03f);
}

TEST(PerceiveModels, ModelInsideTheTableIsRejected) {
    // A plate reaching 10 cm below the table's top: hidden from the sensor, but impossible.
    PointCloud cloud;
    PerceivedObject object;
    object.indices = AddPlate(cloud, -0.12f, 0.12f, 1.0f);
    AddWall(cloud);
    Finish(cloud);
    object.category.category = Category::kOther;
    const Eigen::Vector4f high_table(0.0f, -1.0f, 0.0f, 0.2f);
    const ObjectModel m = ModelObject(cloud, object, high_table, Models());
    ASSERT_TRUE(m.verification.has_value());
    EXPECT_GT(m.verification->invalid, 0.4f);
    EXPECT_FALSE(m.accepted);
    EXPECT_EQ(m.replaced, "box");
    // The same plate on the real table is fine.
    EXPECT_TRUE(ModelObject(cloud, object, kPlane, Models()).accepted);
    // A model too large for the grid is not verified (no error).
    ModelParams p = Models();
    p.verification.max_cells = 1000;
    const ObjectModel unverified = ModelObject(cloud, object, high_table, p);
    EXPECT_FALSE(unverified.verification.has_value());
    EXPECT_TRUE(unverified.accepted);
}

// The visible half of an upright mug (radius 4 cm, 10 cm high) at depth 1 m with a handle on
// its right side (a tube of radius 6 mm bent in a half circle of radius 3 cm).
PointCloud Mug(Indices& body, Indices& handle) {
    PointCloud cloud;
    const Eigen::Vector3f c(0.0f, 0.25f, 1.0f);
    const float r = 0.04f;
    for (float a = 0.0f; a < static_cast<float>(M_PI); a += 0.003f / r) {
        // a = 0: right (+x), a = pi/2: facing the camera (-z).
        const Eigen::Vector3f n(std::cos(a), 0.0f, -std::sin(a));
        for (float y = 0.2f; y <= 0.3f + 1e-6f; y += 0.003f) {
            body.push_back(static_cast<Index>(cloud.points.size()));
            Add(cloud, Eigen::Vector3f(c.x(), y, c.z()) + r * n, n);
        }
    }
    const float R = 0.03f, t = 0.006f;
    const Eigen::Vector3f hc(r, 0.25f, 1.0f);  // centre of the handle's half circle
    for (float s = -static_cast<float>(M_PI) / 2; s <= static_cast<float>(M_PI) / 2;
         s += 0.002f / R) {
        const Eigen::Vector3f radial(std::cos(s), std::sin(s), 0.0f);
        const Eigen::Vector3f centre = hc + R * radial;
        for (float b = 0.0f; b < 2.0f * static_cast<float>(M_PI); b += 0.5f) {
            const Eigen::Vector3f n = std::cos(b) * radial + std::sin(b) * Eigen::Vector3f::UnitZ();
            if (n.z() > 0.2f) continue;  // the back of the tube is unseen
            const Eigen::Vector3f p = centre + t * n;
            if (p.x() < r + 0.004f) continue;  // inside the mug wall
            handle.push_back(static_cast<Index>(cloud.points.size()));
            Add(cloud, p, n);
        }
    }
    Finish(cloud);
    return cloud;
}

TEST(PerceiveModels, HandleOfAGoodCylinderIsAttached) {
    Indices body, handle;
    const PointCloud cloud = Mug(body, handle);
    ASSERT_GT(handle.size(), 100u);
    PerceivedObject object;
    object.indices = body;
    object.indices.insert(object.indices.end(), handle.begin(), handle.end());
    object.category.category = Category::kCylinder;
    const ObjectModel m = ModelObject(cloud, object, kPlane, Models());
    ASSERT_TRUE(m.cylinder.has_value());
    EXPECT_NEAR(m.cylinder->radius, 0.04f, 0.004f);
    EXPECT_TRUE(m.accepted);
    EXPECT_GT(m.attached_points, handle.size() / 2);
    EXPECT_GT(m.attached_triangles, 20u);
    const TriangleMesh plain = CylinderMesh(*m.cylinder);
    EXPECT_EQ(m.mesh.triangles.size(), plain.triangles.size() + m.attached_triangles);
    // The attached vertices are the handle's: right of the mug wall.
    for (std::size_t v = plain.vertices.size(); v < m.mesh.vertices.size(); ++v) {
        EXPECT_GT(m.mesh.vertices[v].x(), 0.04f);
    }
    // Grasp: the diameter, the axis up, and the handle does not widen the narrowest direction.
    ASSERT_TRUE(m.grasp.axis.has_value());
    EXPECT_GT(m.grasp.axis->dot(Eigen::Vector3f(0, -1, 0)), 0.99f);
    EXPECT_EQ(m.grasp.dimensions[0].first, "diameter");
    EXPECT_NEAR(m.grasp.graspable_width, 0.08f, 0.01f);

    // Without the handle nothing is attached.
    PerceivedObject plain_object;
    plain_object.indices = body;
    plain_object.category.category = Category::kCylinder;
    EXPECT_EQ(ModelObject(cloud, plain_object, kPlane, Models()).attached_triangles, 0u);
}

// A 10 cm wide, 4 cm high strip of a 25 cm radius cylinder standing on the table: a cylinder
// fits it well, but is 50 cm wide, far larger than its points.
TEST(PerceiveModels, ModelLargerThanItsPointsIsRejected) {
    PointCloud cloud;
    PerceivedObject object;
    const Eigen::Vector3f axis_point(0.0f, 0.3f, 1.25f);
    for (float a = -0.2f; a <= 0.2f; a += 0.012f) {
        for (float y = 0.26f; y <= 0.3f + 1e-6f; y += 0.003f) {
            const Eigen::Vector3f radial(std::sin(a), 0.0f, -std::cos(a));
            object.indices.push_back(static_cast<Index>(cloud.points.size()));
            Add(cloud, Eigen::Vector3f(axis_point.x(), y, axis_point.z()) + 0.25f * radial, radial);
        }
    }
    AddWall(cloud);
    Finish(cloud);
    object.category.category = Category::kPlate;
    ModelParams lenient = Models();
    lenient.max_size_ratio = 100.0f;
    const ObjectModel fitted = ModelObject(cloud, object, kPlane, lenient);
    ASSERT_TRUE(fitted.cylinder.has_value()) << "the strip must fit a cylinder";
    EXPECT_GT(fitted.cylinder->radius, 0.15f);
    const ObjectModel m = ModelObject(cloud, object, kPlane, Models());
    EXPECT_FALSE(m.accepted);
    EXPECT_EQ(m.replaced, "cylinder");
    EXPECT_EQ(m.replace_reason, "size");
    EXPECT_FALSE(m.verification.has_value());
    for (const auto& v : m.mesh.vertices) EXPECT_NEAR((v - axis_point).norm(), 0.25f, 0.05f);
    // A model of its points' size is kept: the mug's body.
    Indices body, handle;
    const PointCloud mug = Mug(body, handle);
    PerceivedObject cup;
    cup.indices = body;
    cup.category.category = Category::kCylinder;
    EXPECT_TRUE(ModelObject(mug, cup, kPlane, Models()).accepted);
}

TEST(PerceiveModels, BadParameters) {
    Indices body, handle;
    const PointCloud cloud = Mug(body, handle);
    PerceivedObject object;
    object.indices = body;
    object.category.category = Category::kCylinder;
    ModelParams p = Models();
    p.min_inlier_ratio = 1.5f;
    EXPECT_THROW(ModelObject(cloud, object, kPlane, p), InvalidArgument);
    p = Models();
    p.mesh.search_radius = 0.0f;
    EXPECT_THROW(ModelObject(cloud, object, kPlane, p), InvalidArgument);
    p = Models();
    p.verification.voxel_size = -1.0f;
    EXPECT_THROW(ModelObject(cloud, object, kPlane, p), InvalidArgument);
    p = Models();
    p.max_size_ratio = 0.5f;
    EXPECT_THROW(ModelObject(cloud, object, kPlane, p), InvalidArgument);
    p = Models();
    p.size_margin = -0.01f;
    EXPECT_THROW(ModelObject(cloud, object, kPlane, p), InvalidArgument);
}

TEST(PerceiveModels, VerificationOfOrganizedFramesMatchesAllRays) {
    // Organized frames cast only the rays through the model's projected bounds, spaced at most
    // half a cell apart; the shares agree with casting every point of the unorganized cloud.
    const sim::TableTopScene scene = sim::MakeDemoScene();
    sim::ScanParams sp;
    sp.T_world_camera = sim::DefaultCameraPose(scene);
    const PointCloud organized = sim::ScanTableTopScene(scene, sp);
    ASSERT_TRUE(organized.IsOrganized());
    const PerceiveResult r = Perceive(organized, Params());
    ASSERT_FALSE(r.objects.empty());
    PointCloud flat = organized;
    flat.width = static_cast<std::uint32_t>(flat.size());
    flat.height = 1;
    ModelParams p = Models();
    p.mesh_fallback = false;
    p.min_attached_points = 0;
    for (const auto& o : r.objects) {
        PerceivedObject object = o;
        object.category.category = Category::kBox;  // no normals needed
        const ObjectModel a = ModelObject(organized, object, r.support.plane, p);
        const ObjectModel b = ModelObject(flat, object, r.support.plane, p);
        ASSERT_TRUE(a.verification && b.verification);
        EXPECT_NEAR(a.verification->verified, b.verification->verified, 0.05f) << o.id;
        EXPECT_NEAR(a.verification->invalid, b.verification->invalid, 0.03f) << o.id;
        EXPECT_GT(a.verification->verified, 0.2f) << o.id;
    }
}

TEST(PerceiveModels, ResultJsonHasVerificationGraspAndRotationalModels) {
    const sim::TableTopScene scene = sim::MakeDemoScene();
    sim::ScanParams sp;
    sp.T_world_camera = sim::DefaultCameraPose(scene);
    const PointCloud cloud = sim::ScanTableTopScene(scene, sp);
    PerceiveResult r = Perceive(cloud, Params());
    ASSERT_EQ(r.objects.size(), 5u);
    std::size_t accepted = 0;
    for (const auto& o : r.objects) accepted += o.model.accepted ? 1 : 0;
    EXPECT_GE(accepted, 4u);  // the demo's boxes and cylinders fit

    // A rotational model as perceive writes it.
    RotationalModel rot;
    rot.found = true;
    rot.axis = Eigen::Vector3f(0, -1, 0);
    rot.origin = Eigen::Vector3f(0, 0.3f, 1.0f);
    rot.heights = {0.0f, 0.05f, 0.1f};
    rot.radii = {0.03f, 0.05f, 0.02f};
    rot.inlier_ratio = 0.9f;
    PerceivedObject extra = r.objects.front();
    extra.id = static_cast<int>(r.objects.size() + 1);
    extra.model = ObjectModel{};
    extra.model.rotational = rot;
    extra.model.mesh = RotationalMesh(rot);
    extra.model.grasp.dimensions = {{"max_diameter", 0.1f}, {"height", 0.1f}};
    extra.model.grasp.axis = rot.axis;
    extra.model.grasp.graspable_width = 0.1f;
    r.objects.push_back(extra);

    const auto j = nlohmann::json::parse(PerceiveResultJson("scene.pcd", r).dump());
    for (const auto& o : j["objects"]) {
        ASSERT_TRUE(o.contains("accepted"));
        ASSERT_TRUE(o.contains("verification"));
        ASSERT_TRUE(o.contains("grasp"));
        EXPECT_GT(o["grasp"]["graspable_width"].get<double>(), 0.0);
        EXPECT_FALSE(o["grasp"]["dimensions"].empty());
        const std::string type = o["model"]["type"];
        if (type == "box" || type == "cylinder") {
            ASSERT_TRUE(o["verification"].is_object());
            const double sum = o["verification"]["verified"].get<double>() +
                               o["verification"]["occluded"].get<double>() +
                               o["verification"]["invalid"].get<double>();
            EXPECT_NEAR(sum, 1.0, 1e-3);
        }
        if (type == "cylinder") {
            EXPECT_EQ(o["grasp"]["axis"].size(), 3u);
        }
    }
    const auto& last = j["objects"].back();
    EXPECT_EQ(last["model"]["type"], "rotational");
    EXPECT_EQ(last["model"]["axis"].size(), 3u);
    EXPECT_EQ(last["model"]["axis_point"].size(), 3u);
    ASSERT_EQ(last["model"]["profile"].size(), 3u);
    EXPECT_NEAR(last["model"]["profile"][1][1].get<double>(), 0.05, 1e-6);
    EXPECT_TRUE(last["verification"].is_null());
    EXPECT_NEAR(last["grasp"]["dimensions"]["max_diameter"].get<double>(), 0.1, 1e-6);
}

}  // namespace
}  // namespace multicue

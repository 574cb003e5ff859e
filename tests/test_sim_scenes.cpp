// Meshes, mesh libraries, procedural objects and scene generators of the simulator.

#include <fstream>
#include <set>

#include <gtest/gtest.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/core/logging.hpp"
#include "multicue/sim/procedural.hpp"
#include "multicue/sim/scene_gen.hpp"
#include "multicue/sim/sensors.hpp"
#include "reduced_kinect.hpp"
#include "test_util.hpp"

namespace multicue::sim {
namespace {

void WriteText(const std::filesystem::path& p, const std::string& text) {
    std::ofstream(p) << text;
}

/// A 10 cm cube in millimetres with two groups.
const char* kCubeObj = R"(v -50 -50 0
v 50 -50 0
v 50 50 0
v -50 50 0
v -50 -50 100
v 50 -50 100
v 50 50 100
v -50 50 100
g bottom
f 1 3 2
f 1 4 3
g top
f 5 6 7
f 5 7 8
g sides
f 1 2 6 5
f 2 3 7 6
f 3 4 8 7
f 4 1 5 8
)";

TEST(SimMesh, LoadsObjWithPartsAndScale) {
    test::TempDir dir;
    WriteText(dir / "cube.obj", kCubeObj);
    const PartMesh m = LoadMesh(dir / "cube.obj", {.scale = 0.001f});
    EXPECT_EQ(m.mesh.triangles.size(), 12u);
    EXPECT_NEAR(m.Bounds().sizes().maxCoeff(), 0.1f, 1e-6f);
    const std::set<std::string> parts(m.part_names.begin(), m.part_names.end());
    EXPECT_TRUE(parts.count("bottom") && parts.count("top") && parts.count("sides"))
        << fmt::format("{}", fmt::join(m.part_names, ","));
    EXPECT_NO_THROW(m.Validate());
}

TEST(SimMesh, LoadsPlyWithVertexColours) {
    test::TempDir dir;
    WriteText(dir / "tri.ply",
              "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
              "property float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n"
              "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
              "0 0 0 255 0 0\n0.1 0 0 255 0 0\n0 0.1 0 255 0 0\n3 0 1 2\n");
    const PartMesh m = LoadMesh(dir / "tri.ply");
    ASSERT_TRUE(m.mesh.HasVertexColors());
    EXPECT_EQ(m.mesh.vertex_colors[0].r, 255);
    EXPECT_EQ(m.mesh.vertex_colors[0].g, 0);
}

TEST(SimMesh, LoadsStl) {
    test::TempDir dir;
    WriteText(dir / "tri.stl",
              "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 100 0 0\n"
              "vertex 0 50 0\nendloop\nendfacet\nendsolid t\n");
    const PartMesh m = LoadMesh(dir / "tri.stl", {.scale = 0.001f});
    EXPECT_EQ(m.mesh.triangles.size(), 1u);
    EXPECT_NEAR(m.Bounds().sizes().x(), 0.1f, 1e-6f);
}

TEST(SimMesh, BadMeshesAreRefusedOrSkipped) {
    test::TempDir dir;
    WriteText(dir / "cube.obj", kCubeObj);
    WriteText(dir / "empty.obj", "v 0 0 0\nv 1 0 0\n");
    WriteText(dir / "garbage.ply", "ply\nthis is not a ply file\n");
    EXPECT_THROW(LoadMesh(dir / "missing.obj"), IoError);
    EXPECT_THROW(LoadMesh(dir / "empty.obj"), Error);
    EXPECT_THROW(LoadMesh(dir / "garbage.ply"), Error);
    EXPECT_THROW(LoadMesh(dir / "cube.obj"), DataError);  // 100 m: millimetres read as metres
    EXPECT_THROW(LoadMesh(dir / "cube.obj", {.scale = 1e-6f}), DataError);  // 0.1 mm
    EXPECT_THROW(LoadMesh(dir / "cube.obj", {.scale = -1.0f}), InvalidArgument);
    try {
        LoadMesh(dir / "cube.obj");
    } catch (const DataError& e) {
        EXPECT_NE(std::string(e.what()).find("cube.obj"), std::string::npos);
    }
    std::vector<std::string> warnings;
    SetLogSink([&](LogLevel, std::string_view m) { warnings.emplace_back(m); });
    EXPECT_FALSE(TryLoadMesh(dir / "empty.obj", {}, false).has_value());
    SetLogSink({});
    ASSERT_EQ(warnings.size(), 1u);
    EXPECT_NE(warnings[0].find("empty.obj"), std::string::npos);
    EXPECT_THROW(TryLoadMesh(dir / "empty.obj", {}, true), Error);
}

// PLY meshes are read by multicue's PLY reader, not by Assimp (whose PLY importer crashed or
// asserted on damaged files): a face without indices is skipped, polygons are triangulated.
TEST(SimMesh, PlyMeshesAreReadWithoutAssimp) {
    test::TempDir dir;
    const std::string head =
        "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
        "property float z\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n"
        "0 0 0\n0.1 0 0\n0 0.1 0\n0.1 0.1 0\n3 0 1 2\n";
    WriteText(dir / "empty_face.ply", head + "0\n");
    WriteText(dir / "quad.ply", head + "4 0 1 3 2\n");
    WriteText(dir / "short.ply", head);  // the second face is missing
    SetLogSink([](LogLevel, std::string_view) {});
    const PartMesh one = LoadMesh(dir / "empty_face.ply");
    SetLogSink({});
    EXPECT_EQ(one.mesh.triangles.size(), 1u);
    EXPECT_EQ(one.part_names, std::vector<std::string>{"part0"});
    const PartMesh quad = LoadMesh(dir / "quad.ply", {.scale = 2.0f});
    EXPECT_EQ(quad.mesh.triangles.size(), 3u);
    EXPECT_FLOAT_EQ(quad.mesh.vertices[3].x(), 0.2f);
    EXPECT_FALSE(quad.mesh.HasVertexColors());
    EXPECT_THROW(LoadMesh(dir / "short.ply"), FormatError);
    // A .ply name with a damaged first line is refused by multicue's reader (Assimp's looped).
    WriteText(dir / "damaged.ply", "plx\n" + head.substr(4));
    EXPECT_THROW(LoadMesh(dir / "damaged.ply"), FormatError);
    // PLY content behind another name is still read as PLY.
    WriteText(dir / "quad.mesh", head + "4 0 1 3 2\n");
    EXPECT_EQ(LoadMesh(dir / "quad.mesh").mesh.triangles.size(), 3u);
}

TEST(SimMesh, LibraryLabelsAreChecked) {
    test::TempDir dir;
    WriteText(dir / "kit__cube.obj", kCubeObj);
    WriteText(dir / "labels.csv",
              "file,category,source,object,notes,scale_to_m\n"
              "kit__cube.obj,box,kit,cube,\"a note, with a comma\",0.001\n");
    const auto lib = ReadMeshLibrary(dir.path());
    ASSERT_EQ(lib.size(), 1u);
    EXPECT_EQ(lib[0].category, "box");
    EXPECT_FLOAT_EQ(lib[0].scale_to_m, 0.001f);
    EXPECT_TRUE(lib[0].rescale);

    WriteText(dir / "labels.csv",
              "file,category,scale_to_m\nkit__cube.obj,box,0.001\nmissing.obj,box,1\n");
    try {
        ReadMeshLibrary(dir.path());
        FAIL() << "missing mesh accepted";
    } catch (const FormatError& e) {
        EXPECT_NE(std::string(e.what()).find("labels.csv:3"), std::string::npos) << e.what();
    }
    WriteText(dir / "labels.csv", "file,category,scale_to_m\nkit__cube.obj,teapot,1\n");
    try {
        ReadMeshLibrary(dir.path());
        FAIL() << "unknown category accepted";
    } catch (const FormatError& e) {
        EXPECT_NE(std::string(e.what()).find("labels.csv:2"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("teapot"), std::string::npos);
    }
    WriteText(dir / "labels.csv", "file,category,scale_to_m\nkit__cube.obj,box,-2\n");
    EXPECT_THROW(ReadMeshLibrary(dir.path()), FormatError);
    EXPECT_THROW(ReadMeshLibrary(dir / "nope"), IoError);
}

TEST(SimMesh, ShrunkLibraryMeshesGetARealisticSize) {
    test::TempDir dir;
    WriteText(dir / "kit__cube.obj", kCubeObj);
    WriteText(dir / "labels.csv", "file,category,scale_to_m\nkit__cube.obj,flat,0.0001\n");
    ObjectSource source(ReadMeshLibrary(dir.path()), true);
    const auto [lo, hi] = RealisticExtentRange("flat");
    for (int i = 0; i < 10; ++i) {
        StreamRng rng(1, static_cast<std::uint64_t>(i));
        const ObjectModel m = source.Random(rng);
        const float e = m.mesh->Bounds().sizes().maxCoeff();
        EXPECT_GE(e, lo - 1e-4f);
        EXPECT_LE(e, hi + 1e-4f);
    }
}

TEST(SimProcedural, EveryKindIsValidWithPartsAndRealisticSize) {
    for (const auto& [kind, category] : ProceduralKinds()) {
        for (std::uint64_t s = 0; s < 5; ++s) {
            StreamRng rng(s, 9);
            const ProceduralObject o = MakeProceduralKind(kind, rng);
            EXPECT_EQ(o.category, category);
            EXPECT_NO_THROW(o.mesh.Validate()) << kind;
            const Eigen::AlignedBox3f b = o.mesh.Bounds();
            EXPECT_NEAR(b.min().z(), 0.0f, 1e-5f) << kind;  // rests on z = 0
            const auto [lo, hi] = RealisticExtentRange(category);
            EXPECT_GE(b.sizes().maxCoeff(), lo * 0.9f) << kind;
            EXPECT_LE(b.sizes().maxCoeff(), hi * 1.1f) << kind;
        }
    }
    StreamRng rng(1);
    const auto mug = MakeProceduralKind("mug", rng);
    EXPECT_EQ(mug.mesh.part_names, (std::vector<std::string>{"body", "handle"}));
    EXPECT_THROW(MakeProceduralObject("teapot", rng), InvalidArgument);
}

TEST(SimProcedural, BoxesRestOnAnyFaceBottlesOnlyUpright) {
    const auto box = StableRotations(MakeBoxMesh({0.2f, 0.1f, 0.05f}));
    EXPECT_EQ(box.size(), 6u);
    EXPECT_TRUE(box.front().isApprox(Eigen::Matrix3f::Identity()));
    StreamRng rng(3);
    const auto bottle = StableRotations(MakeProceduralKind("bottle", rng).mesh);
    EXPECT_TRUE(bottle.front().isApprox(Eigen::Matrix3f::Identity()));
    EXPECT_EQ(bottle.size(), 1u);  // neither on its side (rolls) nor on its cap (topples)
}

TEST(SimScenes, TableSceneObjectsRestOnTheTableApart) {
    TableSceneParams p;
    p.min_objects = 4;
    p.max_objects = 6;
    p.clutter = 0.0f;
    for (std::uint64_t seed = 1; seed <= 5; ++seed) {
        const Scene s = MakeTableScene(p, seed);
        const float h = s.support_center.z();
        EXPECT_GE(s.NumObjects(), 3u);
        EXPECT_LE(s.NumObjects(), 6u);
        std::vector<std::vector<Eigen::Vector2f>> footprints;
        for (const auto& o : s.objects) {
            if (o.label < ObjectLabel(1)) continue;
            float zmin = 1e9f;
            std::vector<Eigen::Vector2f> pts;
            for (const auto& v : o.mesh->mesh.vertices) {
                const Eigen::Vector3f w = o.T_world_object * v;
                zmin = std::min(zmin, w.z());
                pts.emplace_back(w.x(), w.y());
                EXPECT_LE(std::abs(w.x()), s.support_size.x() / 2);
                EXPECT_LE(std::abs(w.y()), s.support_size.y() / 2);
            }
            EXPECT_NEAR(zmin, h, 1e-4f);
            EXPECT_GE(o.category, 1u);
            EXPECT_LE(o.category, 6u);
            footprints.push_back(ConvexHull2D(pts));
        }
        for (std::size_t a = 0; a < footprints.size(); ++a) {
            for (std::size_t b = a + 1; b < footprints.size(); ++b) {
                EXPECT_GE(PolygonSeparation(footprints[a], footprints[b]), p.min_gap - 1e-4f);
            }
        }
    }
}

TEST(SimScenes, ClutterMakesObjectsTouch) {
    TableSceneParams p;
    p.min_objects = p.max_objects = 6;
    p.clutter = 1.0f;
    int touching = 0;
    for (std::uint64_t seed = 1; seed <= 3; ++seed) {
        const Scene s = MakeTableScene(p, seed);
        std::vector<std::vector<Eigen::Vector2f>> fp;
        for (const auto& o : s.objects) {
            if (o.label < ObjectLabel(1)) continue;
            std::vector<Eigen::Vector2f> pts;
            for (const auto& v : o.mesh->mesh.vertices)
                pts.push_back((o.T_world_object * v).head<2>());
            fp.push_back(ConvexHull2D(pts));
        }
        for (std::size_t a = 0; a < fp.size(); ++a) {
            for (std::size_t b = a + 1; b < fp.size(); ++b) {
                const float sep = PolygonSeparation(fp[a], fp[b]);
                EXPECT_GT(sep, -1e-4f);  // never intersecting
                touching += sep < 0.005f ? 1 : 0;
            }
        }
    }
    EXPECT_GE(touching, 6);
}

TEST(SimScenes, GenerationIsDeterministic) {
    const Scene a = MakeTableScene({}, 21), b = MakeTableScene({}, 21), c = MakeTableScene({}, 22);
    ASSERT_EQ(a.objects.size(), b.objects.size());
    for (std::size_t i = 0; i < a.objects.size(); ++i) {
        EXPECT_TRUE(a.objects[i].T_world_object.isApprox(b.objects[i].T_world_object, 0.0f));
        EXPECT_EQ(a.objects[i].mesh->mesh.vertices, b.objects[i].mesh->mesh.vertices);
    }
    EXPECT_FALSE(a.objects.back().T_world_object.isApprox(c.objects.back().T_world_object));
}

TEST(SimScenes, ViewpointsAtHeadHeightLookAtTheTable) {
    const Scene s = MakeTableScene({}, 4);
    const auto poses = TableViewpoints(s, 6, {}, 4);
    ASSERT_EQ(poses.size(), 6u);
    for (const auto& T : poses) {
        EXPECT_GE(T.translation().z(), 1.3f);
        EXPECT_LE(T.translation().z(), 1.6f);
        const float d = (T.translation() - s.support_center).head<2>().norm();
        EXPECT_GE(d, 0.8f - 1e-4f);
        const Eigen::Vector3f to = (s.support_center - T.translation()).normalized();
        EXPECT_GT(to.dot(T.linear().col(2)), 0.99f);
    }
    EXPECT_THROW(TableViewpoints(s, -1, {}, 1), InvalidArgument);
    TableSceneParams bad;
    bad.clutter = 2.0f;
    EXPECT_THROW(MakeTableScene(bad, 1), InvalidArgument);
}

TEST(SimScenes, TurntableViewsAllSeeTheObject) {
    StreamRng rng(5);
    const auto obj = MakeProceduralKind("mug", rng);
    const ObjectModel model{std::make_shared<const PartMesh>(obj.mesh), "cylinder", "mug", 1.0f};
    const Scene s = MakeTurntableScene(model, {}, 5);
    const auto views = TurntableViews(s, 16, {});
    ASSERT_EQ(views.size(), 16u);
    const RayCaster caster(s);
    const KinectParams p = test::ReducedKinect(4);
    std::set<int> handle_seen;
    for (std::size_t v = 0; v < views.size(); ++v) {
        const PointCloud c = ScanKinect(caster, views[v], p, v);
        const auto* part = c.FindExtraField("part");
        std::size_t n = 0;
        for (std::size_t i = 0; i < c.size(); ++i) {
            if (c.labels[i] != ObjectLabel(1)) continue;
            ++n;
            if (part->data[2 * i] == 2) handle_seen.insert(static_cast<int>(v));  // 1 + "handle"
        }
        EXPECT_GT(n, 30u) << "view " << v;
    }
    EXPECT_GE(handle_seen.size(), 4u);
    EXPECT_LT(handle_seen.size(), 16u);
}

TEST(SimScenes, SharedTabletopMeshesAllRender) {
    if (!test::HasSharedData()) GTEST_SKIP() << "no shared data";
    const auto folder = test::SharedData("meshes/tabletop");
    if (!std::filesystem::exists(folder / "labels.csv")) GTEST_SKIP() << "no tabletop meshes";
    ObjectSource source(ReadMeshLibrary(folder, TabletopCategories()), false);
    const KinectParams p = test::ReducedKinect(8);
    std::size_t rendered = 0;
    for (std::size_t i = 0; i < source.library().size(); ++i) {
        StreamRng rng(1, i);
        const auto model = source.FromEntry(i, rng);
        ASSERT_TRUE(model.has_value()) << source.library()[i].file;
        const Scene s = MakeTurntableScene(*model, {.distance = 0.6f}, i);
        const PointCloud c = ScanKinect(s, TurntableViews(s, 1, {.distance = 0.6f})[0], p, i);
        std::size_t n = 0;
        for (auto l : c.labels) n += l == ObjectLabel(1) ? 1 : 0;
        EXPECT_GT(n, 0u) << source.library()[i].file;
        ++rendered;
    }
    EXPECT_GT(rendered, 150u);
}

}  // namespace
}  // namespace multicue::sim

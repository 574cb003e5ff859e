// The mOSD-like table scene modes (boxes, stacked, occluded, cylindric, mixed, complex) and the
// held-out mesh split: counts, physical plausibility, ground truth, determinism.

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <map>
#include <set>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/sim/mesh_split.hpp"
#include "multicue/sim/procedural.hpp"
#include "multicue/sim/scene_gen.hpp"
#include "multicue/sim/sensors.hpp"
#include "test_util.hpp"

namespace multicue::sim {
namespace {

constexpr std::array<TableSceneMode, 6> kModes = {
    TableSceneMode::kBoxes,     TableSceneMode::kStacked, TableSceneMode::kOccluded,
    TableSceneMode::kCylindric, TableSceneMode::kMixed,   TableSceneMode::kComplex};

/// An object's mesh in world coordinates.
struct WorldMesh {
    std::vector<Eigen::Vector3f> v;
    std::vector<Eigen::Matrix<std::uint32_t, 3, 1>> t;
    Eigen::AlignedBox3f box;
};

WorldMesh World(const SceneObject& o) {
    WorldMesh w;
    for (const auto& p : o.mesh->mesh.vertices) {
        w.v.push_back(o.T_world_object * p);
        w.box.extend(w.v.back());
    }
    for (const auto& t : o.mesh->mesh.triangles) w.t.emplace_back(t[0], t[1], t[2]);
    return w;
}

std::vector<const SceneObject*> Objects(const Scene& s) {
    std::vector<const SceneObject*> out;
    for (const auto& o : s.objects) {
        if (o.label >= ObjectLabel(1)) out.push_back(&o);
    }
    return out;
}

const SceneObject& ByLabel(const Scene& s, std::uint32_t label) {
    const int i = FindObject(s, label);
    EXPECT_GE(i, 0) << label;
    return s.objects.at(static_cast<std::size_t>(std::max(i, 0)));
}

/// Closest point on triangle abc to p (Ericson, Real-Time Collision Detection, 5.1.5).
Eigen::Vector3f ClosestOnTriangle(const Eigen::Vector3f& p, const Eigen::Vector3f& a,
                                  const Eigen::Vector3f& b, const Eigen::Vector3f& c) {
    const Eigen::Vector3f ab = b - a, ac = c - a, ap = p - a;
    const float d1 = ab.dot(ap), d2 = ac.dot(ap);
    if (d1 <= 0 && d2 <= 0) return a;
    const Eigen::Vector3f bp = p - b;
    const float d3 = ab.dot(bp), d4 = ac.dot(bp);
    if (d3 >= 0 && d4 <= d3) return b;
    const float vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + d1 / (d1 - d3) * ab;
    const Eigen::Vector3f cp = p - c;
    const float d5 = ab.dot(cp), d6 = ac.dot(cp);
    if (d6 >= 0 && d5 <= d6) return c;
    const float vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + d2 / (d2 - d6) * ac;
    const float va = d3 * d6 - d5 * d4;
    if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
        return b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b);
    }
    const float denom = 1.0f / (va + vb + vc);
    return a + ab * (vb * denom) + ac * (vc * denom);
}

float Distance(const WorldMesh& m, const Eigen::Vector3f& p) {
    float best = std::numeric_limits<float>::infinity();
    for (const auto& t : m.t) {
        best = std::min(best, (p - ClosestOnTriangle(p, m.v[t[0]], m.v[t[1]], m.v[t[2]])).norm());
    }
    return best;
}

/// Inside a closed mesh by the parity of ray crossings, the majority of three directions.
bool InsideMesh(const WorldMesh& m, const Eigen::Vector3f& p) {
    static const std::array<Eigen::Vector3f, 3> dirs = {
        Eigen::Vector3f(0.31f, 0.52f, 0.79f).normalized(),
        Eigen::Vector3f(-0.67f, 0.23f, 0.70f).normalized(),
        Eigen::Vector3f(0.12f, -0.81f, -0.57f).normalized()};
    int votes = 0;
    for (const auto& d : dirs) {
        int crossings = 0;
        for (const auto& t : m.t) {
            // Moeller-Trumbore.
            const Eigen::Vector3f e1 = m.v[t[1]] - m.v[t[0]], e2 = m.v[t[2]] - m.v[t[0]];
            const Eigen::Vector3f q = d.cross(e2);
            const float det = e1.dot(q);
            if (std::abs(det) < 1e-12f) continue;
            const Eigen::Vector3f s = p - m.v[t[0]];
            const float u = s.dot(q) / det;
            if (u < 0 || u > 1) continue;
            const Eigen::Vector3f r = s.cross(e1);
            const float v = d.dot(r) / det;
            if (v < 0 || u + v > 1) continue;
            if (e2.dot(r) / det > 0) ++crossings;
        }
        votes += crossings % 2;
    }
    return votes >= 2;
}

/// Points on the surface: vertices and a barycentric grid on every triangle.
std::vector<Eigen::Vector3f> SurfaceSamples(const WorldMesh& m) {
    std::vector<Eigen::Vector3f> out = m.v;
    const int n = m.t.size() > 400 ? 1 : 5;
    for (const auto& t : m.t) {
        for (int i = 0; i <= n; ++i) {
            for (int j = 0; i + j <= n; ++j) {
                const float a = static_cast<float>(i) / n, b = static_cast<float>(j) / n;
                out.push_back(m.v[t[0]] + a * (m.v[t[1]] - m.v[t[0]]) +
                              b * (m.v[t[2]] - m.v[t[0]]));
            }
        }
    }
    return out;
}

/// Deepest penetration of a surface sample of one object into the other [m] (0: none).
float Penetration(const WorldMesh& a, const WorldMesh& b) {
    float worst = 0.0f;
    for (const auto& pair : {std::array{&a, &b}, std::array{&b, &a}}) {
        const WorldMesh& from = *pair[0];
        const WorldMesh& into = *pair[1];
        for (const auto& p : SurfaceSamples(from)) {
            if (!into.box.contains(p) || !InsideMesh(into, p)) continue;
            worst = std::max(worst, Distance(into, p));
        }
    }
    return worst;
}

/// Smallest distance between two meshes [m], from points every millimetre along the edges of
/// each to the triangles of the other (within 0.5 mm of the true distance).
float Gap(const WorldMesh& a, const WorldMesh& b) {
    float best = std::numeric_limits<float>::infinity();
    for (const auto& pair : {std::array{&a, &b}, std::array{&b, &a}}) {
        const WorldMesh& from = *pair[0];
        for (const auto& t : from.t) {
            for (int e = 0; e < 3; ++e) {
                const Eigen::Vector3f p = from.v[t[e]], q = from.v[t[(e + 1) % 3]];
                const int n = 1 + static_cast<int>((q - p).norm() / 1e-3f);
                for (int i = 0; i <= n; ++i) {
                    const Eigen::Vector3f x = p + (q - p) * (static_cast<float>(i) / n);
                    if (pair[1]->box.exteriorDistance(x) < best) {
                        best = std::min(best, Distance(*pair[1], x));
                    }
                }
            }
        }
    }
    return best;
}

KinectParams SmallKinect(int scale_down) {
    KinectParams k;
    k.width = 640 / scale_down;
    k.height = 480 / scale_down;
    k.fx = k.fy = 525.0f / static_cast<float>(scale_down);
    k.cx = (static_cast<float>(k.width) - 1) / 2;
    k.cy = (static_cast<float>(k.height) - 1) / 2;
    k.num_threads = 1;
    return k;
}

TEST(SimModes, NamesRoundTripAndBadModesAreRefused) {
    for (const auto m : kModes) EXPECT_EQ(ParseTableSceneMode(TableSceneModeName(m)), m);
    EXPECT_EQ(ParseTableSceneMode("default"), TableSceneMode::kDefault);
    try {
        ParseTableSceneMode("jumbled");
        FAIL() << "bad mode accepted";
    } catch (const InvalidArgument& e) {
        EXPECT_NE(std::string(e.what()).find("'jumbled'"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("complex"), std::string::npos) << e.what();
    }
    TableSceneParams bad = TableSceneParamsFor(TableSceneMode::kComplex);
    bad.min_objects = 30;
    EXPECT_THROW(MakeTableScene(bad, 1), InvalidArgument);  // min > max
    bad = TableSceneParamsFor(TableSceneMode::kStacked);
    bad.upright_probability = 2.0f;
    EXPECT_THROW(MakeTableScene(bad, 1), InvalidArgument);
}

TEST(SimModes, DefaultParamsAreTheOriginalOnes) {
    const TableSceneParams a = TableSceneParamsFor(TableSceneMode::kDefault), b;
    EXPECT_EQ(a.mode, TableSceneMode::kDefault);
    EXPECT_EQ(a.min_objects, b.min_objects);
    EXPECT_EQ(a.max_objects, b.max_objects);
    EXPECT_EQ(a.clutter, b.clutter);
    EXPECT_EQ(a.edge_margin, b.edge_margin);
    EXPECT_EQ(TableViewpointParamsFor(TableSceneMode::kDefault).max_distance,
              ViewpointParams{}.max_distance);
}

// Pinned: the default mode's scenes are those the generator made before the modes existed (the
// demo and the published simulated data sets depend on them).
TEST(SimModes, DefaultModeSceneIsUnchanged) {
    struct Pinned {
        std::uint64_t stream;
        std::vector<std::string> sources;
        Eigen::Vector3f first, last;  // translations of the first and last object
    };
    const std::vector<Pinned> pinned = {
        {0,
         {"flat_box", "irregular", "mug"},
         {-0.127377093f, 0.0478798896f, 0.747413576f},
         {-0.207509995f, 0.212344855f, 0.723685384f}},
        {1,
         {"pitcher", "plate", "plate"},
         {0.414508402f, -0.0432196446f, 0.725091457f},
         {-0.12090157f, 0.0667384416f, 0.740911484f}},
        {2,
         {"plate", "can", "plate", "plate", "pitcher", "flat_box", "can"},
         {0.0580617227f, -0.229479417f, 0.748807967f},
         {-0.0680473372f, 0.232208148f, 0.748807967f}},
    };
    for (const auto& p : pinned) {
        const Scene s = MakeTableScene({}, SubSeed(9, p.stream));
        const auto objects = Objects(s);
        ASSERT_EQ(objects.size(), p.sources.size()) << p.stream;
        for (std::size_t i = 0; i < objects.size(); ++i) {
            EXPECT_EQ(objects[i]->source, p.sources[i]) << p.stream << " " << i;
        }
        EXPECT_TRUE(objects.front()->T_world_object.translation().isApprox(p.first, 1e-5f));
        EXPECT_TRUE(objects.back()->T_world_object.translation().isApprox(p.last, 1e-5f));
        EXPECT_FALSE(std::isfinite(s.view_azimuth));
    }
}

TEST(SimModes, EveryModeYieldsItsObjectCountAndKinds) {
    const std::set<std::string> boxes{"box", "flat_box"};
    const std::set<std::string> cylindric{"can", "cup", "mug", "tin", "bottle", "plate", "bowl"};
    for (const auto mode : kModes) {
        const TableSceneParams p = TableSceneParamsFor(mode);
        for (std::uint64_t seed = 1; seed <= 4; ++seed) {
            const Scene s = MakeTableScene(p, seed);
            const std::string what = fmt::format("{} seed {}", TableSceneModeName(mode), seed);
            EXPECT_GE(s.NumObjects(), static_cast<std::size_t>(p.min_objects)) << what;
            EXPECT_LE(s.NumObjects(), static_cast<std::size_t>(p.max_objects)) << what;
            EXPECT_TRUE(std::isfinite(s.view_azimuth)) << what;
            for (const auto* o : Objects(s)) {
                if (mode == TableSceneMode::kBoxes || mode == TableSceneMode::kStacked) {
                    EXPECT_TRUE(boxes.count(o->source)) << what << ": " << o->source;
                }
                if (mode == TableSceneMode::kCylindric) {
                    EXPECT_TRUE(cylindric.count(o->source)) << what << ": " << o->source;
                }
                if (mode == TableSceneMode::kMixed) {
                    EXPECT_TRUE(boxes.count(o->source) || cylindric.count(o->source)) << what;
                }
                if (mode == TableSceneMode::kBoxes) {
                    EXPECT_EQ(o->placement, ObjectPlacement::kStanding) << what;  // apart
                }
            }
        }
    }
    // --objects overrides the mode's range.
    TableSceneParams p = TableSceneParamsFor(TableSceneMode::kMixed);
    p.min_objects = p.max_objects = 2;
    EXPECT_EQ(MakeTableScene(p, 3).NumObjects(), 2u);
}

TEST(SimModes, PenetrationAndGapOracles) {
    // Two 10 cm cubes: 2 cm into each other, then 3 mm apart.
    SceneObject a, b;
    a.mesh = b.mesh = std::make_shared<const PartMesh>(MakeBoxMesh({0.1f, 0.1f, 0.1f}));
    b.T_world_object.translation() = Eigen::Vector3f(0.08f, 0.01f, 0.0f);
    EXPECT_NEAR(Penetration(World(a), World(b)), 0.02f, 1e-3f);
    b.T_world_object.translation() = Eigen::Vector3f(0.103f, 0.01f, 0.0f);
    EXPECT_EQ(Penetration(World(a), World(b)), 0.0f);
    EXPECT_NEAR(Gap(World(a), World(b)), 0.003f, 1e-4f);
}

TEST(SimModes, ObjectsNeverInterpenetrateAndRestOnSomething) {
    for (const auto mode : kModes) {
        for (std::uint64_t seed = 1; seed <= 3; ++seed) {
            const Scene s = MakeTableScene(TableSceneParamsFor(mode), seed);
            const std::string what = fmt::format("{} seed {}", TableSceneModeName(mode), seed);
            const float h = s.support_center.z();
            std::vector<WorldMesh> meshes;
            for (const auto* o : Objects(s)) {
                meshes.push_back(World(*o));
                const auto& b = meshes.back().box;
                EXPECT_LE(std::abs(b.min().x()), s.support_size.x() / 2 + 1e-4f) << what;
                EXPECT_LE(std::abs(b.min().y()), s.support_size.y() / 2 + 1e-4f) << what;
                EXPECT_LE(std::abs(b.max().x()), s.support_size.x() / 2 + 1e-4f) << what;
                EXPECT_LE(std::abs(b.max().y()), s.support_size.y() / 2 + 1e-4f) << what;
                // Everything stands on the table or on (in) another object.
                if (o->placement == ObjectPlacement::kStanding ||
                    o->placement == ObjectPlacement::kTouching ||
                    o->placement == ObjectPlacement::kLeaning) {
                    EXPECT_NEAR(b.min().z(), h, 1e-4f) << what << " " << o->label;
                } else {
                    EXPECT_GT(b.min().z(), h + 1e-3f) << what << " " << o->label;
                }
            }
            for (std::size_t a = 0; a < meshes.size(); ++a) {
                for (std::size_t b = a + 1; b < meshes.size(); ++b) {
                    if (!meshes[a].box.intersects(meshes[b].box)) continue;
                    EXPECT_LT(Penetration(meshes[a], meshes[b]), 1e-3f)
                        << what << ": objects " << a << " and " << b;
                }
            }
        }
    }
}

TEST(SimModes, StackedObjectsRestOnTheTopFaceBelow) {
    int three_high = 0;
    for (std::uint64_t seed = 1; seed <= 8; ++seed) {
        const Scene s = MakeTableScene(TableSceneParamsFor(TableSceneMode::kStacked), seed);
        int stacked = 0;
        for (const auto* o : Objects(s)) {
            if (o->placement != ObjectPlacement::kStacked) continue;
            ++stacked;
            const SceneObject& below = ByLabel(s, o->support);
            const WorldMesh up = World(*o), down = World(below);
            // Its lowest point is on the top of the one below, its centre above that top.
            EXPECT_NEAR(up.box.min().z(), down.box.max().z(), 1e-4f) << seed;
            std::vector<Eigen::Vector2f> top;
            for (const auto& v : down.v) {
                if (v.z() > down.box.max().z() - 1e-3f) top.push_back(v.head<2>());
            }
            const auto hull = ConvexHull2D(top);
            const Eigen::Vector2f c = up.box.center().head<2>();
            EXPECT_LT(PolygonSeparation(hull, {c}), -0.005f) << seed << ": centre off the top";
            if (below.placement == ObjectPlacement::kStacked) {
                ++three_high;
                EXPECT_NE(ByLabel(s, below.support).placement, ObjectPlacement::kStacked);
            }
        }
        EXPECT_GE(stacked, 1) << "seed " << seed;
    }
    EXPECT_GE(three_high, 1);
}

TEST(SimModes, PointLabelsOfAStackedSceneNameTheRightObject) {
    const Scene s = MakeTableScene(TableSceneParamsFor(TableSceneMode::kStacked), 2);
    KinectParams k = SmallKinect(2);
    k.axial_noise = 0.0f;  // exact surfaces, so each point can be traced to its mesh
    k.disparity_step = 1e-5f;
    k.lateral_noise_px = 0.0f;
    std::map<std::uint32_t, WorldMesh> meshes;
    for (const auto* o : Objects(s)) meshes.emplace(o->label, World(*o));
    std::map<std::uint32_t, int> seen;
    for (const auto& T : TableViewpoints(s, 3, {}, 2)) {
        const PointCloud c = ScanKinect(s, T, k, 5);
        for (std::size_t i = 0; i < c.size(); ++i) {
            if (c.labels[i] < ObjectLabel(1) || !c.points[i].allFinite()) continue;
            const Eigen::Vector3f p = T * c.points[i];
            ASSERT_TRUE(meshes.count(c.labels[i])) << c.labels[i];
            const float own = Distance(meshes.at(c.labels[i]), p);
            EXPECT_LT(own, 1e-3f) << "label " << c.labels[i];
            for (const auto& [label, m] : meshes) {
                if (label != c.labels[i] && m.box.exteriorDistance(p) < own) {
                    EXPECT_GE(Distance(m, p) + 1e-4f, own) << "closer to " << label;
                }
            }
            ++seen[c.labels[i]];
        }
    }
    int stacked_seen = 0;
    for (const auto* o : Objects(s)) {
        if (o->placement == ObjectPlacement::kStacked && seen[o->label] > 20) ++stacked_seen;
    }
    EXPECT_GE(stacked_seen, 1);
}

TEST(SimModes, ComplexScenesAreDenseStackedNestedAndLeaning) {
    std::map<ObjectPlacement, int> placements;
    int cut_by_the_view = 0;
    const int seeds = 6;
    for (std::uint64_t seed = 1; seed <= seeds; ++seed) {
        const Scene s = MakeTableScene(TableSceneParamsFor(TableSceneMode::kComplex), seed);
        EXPECT_GE(s.NumObjects(), 10u) << seed;
        EXPECT_LE(s.NumObjects(), 20u) << seed;
        for (const auto* o : Objects(s)) ++placements[o->placement];
        // Objects partly outside the first view's image.
        const auto T =
            TableViewpoints(s, 1, TableViewpointParamsFor(TableSceneMode::kComplex), seed)[0];
        const KinectParams k;
        bool cut = false;
        const Eigen::Isometry3f T_camera_world = T.inverse();
        for (const auto* o : Objects(s)) {
            int in = 0, out = 0;
            for (const auto& v : World(*o).v) {
                const Eigen::Vector3f c = T_camera_world * v;
                const float u = k.fx * c.x() / c.z() + k.cx, w = k.fy * c.y() / c.z() + k.cy;
                const bool inside = c.z() > 0 && u >= 0 && u < k.width && w >= 0 && w < k.height;
                (inside ? in : out) += 1;
            }
            cut = cut || (in > 0 && out > 0);
        }
        cut_by_the_view += cut ? 1 : 0;
    }
    EXPECT_GE(placements[ObjectPlacement::kStacked], seeds);
    EXPECT_GE(placements[ObjectPlacement::kNested], seeds / 2);
    EXPECT_GE(placements[ObjectPlacement::kLeaning], 2);
    EXPECT_GE(placements[ObjectPlacement::kTouching], seeds);
    EXPECT_GE(cut_by_the_view, seeds / 2);
}

TEST(SimModes, LeaningObjectsTouchTheirSupportAndNestedOnesSitInside) {
    int leaning = 0, nested = 0;
    for (std::uint64_t seed = 1; seed <= 8; ++seed) {
        const Scene s = MakeTableScene(TableSceneParamsFor(TableSceneMode::kComplex), seed);
        for (const auto* o : Objects(s)) {
            if (o->placement == ObjectPlacement::kLeaning) {
                ++leaning;
                const SceneObject& support = ByLabel(s, o->support);
                EXPECT_LT(Gap(World(*o), World(support)), 1e-3f) << seed << " " << o->label;
                // Tilted: no axis of the object is vertical.
                const Eigen::Matrix3f R = o->T_world_object.linear();
                EXPECT_LT(R.row(2).cwiseAbs().maxCoeff(), std::cos(5.0f * 3.14159f / 180)) << seed;
            }
            if (o->placement == ObjectPlacement::kNested) {
                ++nested;
                const SceneObject& bowl = ByLabel(s, o->support);
                EXPECT_TRUE(bowl.source == "bowl" || bowl.source == "plate") << bowl.source;
                const WorldMesh item = World(*o), container = World(bowl);
                const Eigen::Vector2f axis = bowl.T_world_object.translation().head<2>();
                const float rim = (container.box.sizes().x() + container.box.sizes().y()) / 4;
                for (const auto& v : item.v) EXPECT_LT((v.head<2>() - axis).norm(), rim);
                EXPECT_GT(item.box.min().z(), container.box.min().z());
            }
        }
    }
    EXPECT_GE(leaning, 2);
    EXPECT_GE(nested, 4);
}

TEST(SimModes, OccludedScenesHidePartOfAnObjectFromTheFirstView) {
    const KinectParams k = SmallKinect(4);
    for (std::uint64_t seed = 1; seed <= 8; ++seed) {
        const Scene s = MakeTableScene(TableSceneParamsFor(TableSceneMode::kOccluded), seed);
        const auto T =
            TableViewpoints(s, 1, TableViewpointParamsFor(TableSceneMode::kOccluded), seed)[0];
        const PointCloud all = ScanKinect(s, T, k, 1);
        bool partly_hidden = false;
        for (const auto* o : Objects(s)) {
            Scene alone;
            alone.objects = {s.objects[0], *o};
            const PointCloud one = ScanKinect(alone, T, k, 1);
            const auto count = [&](const PointCloud& c) {
                return std::count(c.labels.begin(), c.labels.end(), o->label);
            };
            const auto visible = count(all), total = count(one);
            if (total > 20 && visible > 0.05 * total && visible < 0.85 * total) {
                partly_hidden = true;
            }
        }
        EXPECT_TRUE(partly_hidden) << "seed " << seed;
    }
}

TEST(SimModes, SameSeedSameScene) {
    for (const auto mode : kModes) {
        const TableSceneParams p = TableSceneParamsFor(mode);
        const Scene a = MakeTableScene(p, 31), b = MakeTableScene(p, 31), c = MakeTableScene(p, 32);
        ASSERT_EQ(a.objects.size(), b.objects.size());
        for (std::size_t i = 0; i < a.objects.size(); ++i) {
            EXPECT_TRUE(a.objects[i].T_world_object.isApprox(b.objects[i].T_world_object, 0.0f));
            EXPECT_EQ(a.objects[i].mesh->mesh.vertices, b.objects[i].mesh->mesh.vertices);
            EXPECT_EQ(a.objects[i].placement, b.objects[i].placement);
            EXPECT_EQ(a.objects[i].color, b.objects[i].color);
        }
        EXPECT_EQ(a.view_azimuth, b.view_azimuth);
        EXPECT_FALSE(a.objects.back().T_world_object.isApprox(c.objects.back().T_world_object));
    }
}

TEST(SimModes, TheFirstViewLooksFromTheSceneSide) {
    const Scene s = MakeTableScene(TableSceneParamsFor(TableSceneMode::kOccluded), 5);
    const auto T = TableViewpoints(s, 2, {}, 5);
    const Eigen::Vector2f d = (T[0].translation() - s.support_center).head<2>().normalized();
    EXPECT_NEAR(std::atan2(d.y(), d.x()), std::remainder(s.view_azimuth, 2 * 3.14159265f), 1e-4f);
}

std::vector<MeshEntry> FakeLibrary() {
    std::vector<MeshEntry> lib;
    const std::map<std::string, int> counts = {{"box", 7},   {"flat", 2},   {"cylinder", 12},
                                               {"plate", 3}, {"sphere", 1}, {"other", 6}};
    for (const auto& [category, n] : counts) {
        for (int i = 0; i < n; ++i) {
            MeshEntry e;
            e.file = fmt::format("/somewhere/meshes/{}_{}.obj", category, i);
            e.category = category;
            lib.push_back(e);
        }
    }
    return lib;
}

TEST(SimMeshSplit, HalvesAreBalancedPerCategoryAndDeterministic) {
    const auto lib = FakeLibrary();
    const auto halves = MeshSplitOf(lib);
    ASSERT_EQ(halves.size(), lib.size());
    std::map<std::string, std::array<int, 2>> per;
    for (std::size_t i = 0; i < lib.size(); ++i) {
        ASSERT_NE(halves[i], MeshSplit::kAll);
        ++per[lib[i].category][halves[i] == MeshSplit::kTune ? 0 : 1];
    }
    for (const auto& [category, n] : per) {
        EXPECT_LE(std::abs(n[0] - n[1]), 1) << category;
        if (n[0] + n[1] >= 2) {
            EXPECT_GE(n[0], 1) << category;
            EXPECT_GE(n[1], 1) << category;
        }
    }
    // Neither the order of labels.csv nor the folder changes a mesh's half.
    auto moved = lib;
    std::reverse(moved.begin(), moved.end());
    for (auto& e : moved) e.file = "/elsewhere" / e.file.filename();
    const auto again = MeshSplitOf(moved);
    for (std::size_t i = 0; i < lib.size(); ++i) EXPECT_EQ(again[lib.size() - 1 - i], halves[i]);
    // Selection keeps the order and partitions the library.
    const auto tune = SelectMeshSplit(lib, MeshSplit::kTune);
    const auto test = SelectMeshSplit(lib, MeshSplit::kTest);
    EXPECT_EQ(tune.size() + test.size(), lib.size());
    EXPECT_EQ(SelectMeshSplit(lib, MeshSplit::kAll).size(), lib.size());
    std::set<std::string> names;
    for (const auto& e : tune) names.insert(e.file.string());
    for (const auto& e : test) EXPECT_FALSE(names.count(e.file.string())) << e.file;
    EXPECT_EQ(MeshNameHash("a"), 0xaf63dc4c8601ec8cull);  // FNV-1a 64 reference value
    EXPECT_EQ(ParseMeshSplit("tune"), MeshSplit::kTune);
    EXPECT_EQ(ParseMeshSplit("test"), MeshSplit::kTest);
    EXPECT_EQ(ParseMeshSplit("all"), MeshSplit::kAll);
    EXPECT_THROW(ParseMeshSplit("train"), InvalidArgument);
    EXPECT_TRUE(MeshSplitOf({}).empty());
}

TEST(SimMeshSplit, SharedTabletopLibraryHalvesHoldEveryCategory) {
    if (!test::HasSharedData()) GTEST_SKIP() << "no shared data";
    const auto folder = test::SharedData("meshes/tabletop");
    if (!std::filesystem::exists(folder / "labels.csv")) GTEST_SKIP() << "no tabletop meshes";
    const auto lib = ReadMeshLibrary(folder, TabletopCategories());
    std::map<std::string, std::array<int, 2>> per;
    const auto halves = MeshSplitOf(lib);
    for (std::size_t i = 0; i < lib.size(); ++i) {
        ++per[lib[i].category][halves[i] == MeshSplit::kTune ? 0 : 1];
    }
    for (const auto& [category, n] : per) {
        EXPECT_LE(std::abs(n[0] - n[1]), 1) << category;
        if (n[0] + n[1] >= 2) {
            EXPECT_GE(std::min(n[0], n[1]), 1) << category;
        }
    }
    // Scenes of one half only hold meshes of that half.
    ObjectSource source(SelectMeshSplit(lib, MeshSplit::kTest), false);
    std::set<std::string> test_names;
    for (const auto& e : source.library()) test_names.insert(e.file.filename().string());
    const Scene s = MakeTableScene(TableSceneParamsFor(TableSceneMode::kMixed), source, 4);
    for (const auto* o : Objects(s)) EXPECT_TRUE(test_names.count(o->source)) << o->source;
}

}  // namespace
}  // namespace multicue::sim

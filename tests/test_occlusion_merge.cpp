// Joining fragments of occluded objects on synthetic table-top scans with exact labels.

#include <algorithm>
#include <cmath>
#include <deque>
#include <limits>
#include <vector>

#include <gtest/gtest.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/segmentation/occlusion_merge.hpp"
#include "multicue/sim/tabletop_scene.hpp"
#include "multicue/surface/normals.hpp"

namespace multicue {
namespace {

struct Scan {
    PointCloud cloud;
    Eigen::Vector4f plane = Eigen::Vector4f::Zero();  ///< table plane in the camera frame, up
    Eigen::Vector3f up = Eigen::Vector3f::Zero();     ///< world up in the camera frame
};

Scan ScanScene(const sim::TableTopScene& scene) {
    sim::ScanParams p;
    p.T_world_camera = sim::DefaultCameraPose(scene);
    Scan s;
    s.cloud = sim::ScanTableTopScene(scene, p);
    SetNormals(s.cloud, EstimateNormalsOrganized(s.cloud, OrganizedNormalParams{.half_window = 5}));
    const Eigen::Isometry3f T_camera_world = p.T_world_camera.inverse();
    s.up = T_camera_world.linear() * Eigen::Vector3f::UnitZ();
    const Eigen::Vector3f on_table = T_camera_world * Eigen::Vector3f(0, 0, scene.table_height);
    s.plane << s.up, -s.up.dot(on_table);
    return s;
}

// The image-connected pieces (4-neighbourhood) of the pixels labelled `label`, largest first.
std::vector<Indices> Fragments(const PointCloud& cloud, std::uint32_t label) {
    std::vector<std::uint8_t> seen(cloud.size(), 0);
    std::vector<Indices> out;
    const auto w = static_cast<long>(cloud.width), h = static_cast<long>(cloud.height);
    for (std::size_t s = 0; s < cloud.size(); ++s) {
        if (seen[s] || cloud.labels[s] != label || !cloud.IsFinite(s)) continue;
        Indices piece;
        std::deque<long> queue{static_cast<long>(s)};
        seen[s] = 1;
        while (!queue.empty()) {
            const long i = queue.front();
            queue.pop_front();
            piece.push_back(static_cast<Index>(i));
            const long r = i / w, c = i % w;
            const long next[4][2] = {{r - 1, c}, {r + 1, c}, {r, c - 1}, {r, c + 1}};
            for (const auto& [nr, nc] : next) {
                if (nr < 0 || nr >= h || nc < 0 || nc >= w) continue;
                const long j = nr * w + nc;
                if (seen[j] || cloud.labels[j] != label || !cloud.IsFinite(j)) continue;
                seen[j] = 1;
                queue.push_back(j);
            }
        }
        std::sort(piece.begin(), piece.end());
        if (piece.size() >= 50) out.push_back(std::move(piece));
    }
    std::sort(out.begin(), out.end(), [](auto& a, auto& b) { return a.size() > b.size(); });
    return out;
}

// Surface parts of a box fragment: the top (normal along up) and the rest (the front face).
std::vector<Indices> BoxParts(const Scan& s, const Indices& object) {
    std::vector<Indices> parts(2);
    for (Index i : object) parts[s.cloud.normals[i].dot(s.up) > 0.8f ? 0 : 1].push_back(i);
    return parts;
}

// Three objects: a wide box behind a tall thin box that splits it in two in the image, and a
// third, separate box.
sim::TableTopScene OccludedBoxScene() {
    sim::TableTopScene scene;
    scene.boxes = {
        {{0.00f, 0.15f}, 0.0f, {0.30f, 0.08f, 0.12f}, {200, 60, 40, 255}},   // back, occluded
        {{0.00f, -0.05f}, 0.0f, {0.05f, 0.05f, 0.26f}, {60, 170, 80, 255}},  // thin occluder
    };
    return scene;
}

TEST(OcclusionMerge, JoinsBoxFragmentsBehindThinBox) {
    const Scan s = ScanScene(OccludedBoxScene());
    const auto back = Fragments(s.cloud, sim::ObjectLabel(1));
    const auto front = Fragments(s.cloud, sim::ObjectLabel(2));
    ASSERT_EQ(back.size(), 2u) << "the occluder must split the back box";
    ASSERT_EQ(front.size(), 1u);
    const std::vector<Indices> objects{front[0], back[0], back[1]};
    const std::vector<std::vector<Indices>> parts{BoxParts(s, front[0]), BoxParts(s, back[0]),
                                                  BoxParts(s, back[1])};
    const OcclusionMergeResult r = MergeOccludedFragments(s.cloud, objects, parts, s.plane);
    EXPECT_EQ(r.merges, 1u);
    ASSERT_EQ(r.groups.size(), 2u);
    EXPECT_EQ(r.groups[0], (std::vector<std::size_t>{0}));
    EXPECT_EQ(r.groups[1], (std::vector<std::size_t>{1, 2}));

    // Without the surface evidence (a stricter plane test and no cylinder) nothing is joined:
    // the image test alone does not merge.
    OcclusionMergeParams strict;
    strict.min_explained_share = 1.0f;
    EXPECT_EQ(MergeOccludedFragments(s.cloud, objects, parts, s.plane, strict).merges, 0u);
    // Nor across a gap wider than max_gap.
    OcclusionMergeParams near;
    near.max_gap = 0.02f;
    EXPECT_EQ(MergeOccludedFragments(s.cloud, objects, parts, s.plane, near).merges, 0u);
}

TEST(OcclusionMerge, JoinsCylinderFragmentsBehindThinBox) {
    sim::TableTopScene scene;
    scene.boxes = {{{0.00f, -0.05f}, 0.0f, {0.04f, 0.04f, 0.30f}, {60, 170, 80, 255}}};
    scene.cylinders = {{{0.00f, 0.20f}, 0.10f, 0.16f, {40, 90, 200, 255}}};
    const Scan s = ScanScene(scene);
    const auto back = Fragments(s.cloud, sim::ObjectLabel(2));
    const auto front = Fragments(s.cloud, sim::ObjectLabel(1));
    ASSERT_EQ(back.size(), 2u) << "the occluder must split the cylinder";
    ASSERT_EQ(front.size(), 1u);
    // Each fragment as one part: a curved part has no plane, so the cylinder test decides.
    const std::vector<Indices> objects{back[0], front[0], back[1]};
    const std::vector<std::vector<Indices>> parts{{back[0]}, {front[0]}, {back[1]}};
    const OcclusionMergeResult r = MergeOccludedFragments(s.cloud, objects, parts, s.plane);
    EXPECT_EQ(r.merges, 1u);
    ASSERT_EQ(r.groups.size(), 2u);
    EXPECT_EQ(r.groups[0], (std::vector<std::size_t>{0, 2}));
    EXPECT_EQ(r.groups[1], (std::vector<std::size_t>{1}));
    // A cylinder of 10 cm radius outside the accepted radii: no surface continues, no merge.
    OcclusionMergeParams small;
    small.max_cylinder_radius = 0.05f;
    EXPECT_EQ(MergeOccludedFragments(s.cloud, objects, parts, s.plane, small).merges, 0u);
}

TEST(OcclusionMerge, KeepsSideBySideObjectsApart) {
    // Two equal boxes in one row with a 6 cm gap: their faces continue each other, but the table
    // shows between them, so nothing hides a connection.
    sim::TableTopScene scene;
    scene.boxes = {
        {{-0.10f, 0.10f}, 0.0f, {0.14f, 0.08f, 0.12f}, {200, 60, 40, 255}},
        {{0.10f, 0.10f}, 0.0f, {0.14f, 0.08f, 0.12f}, {60, 170, 80, 255}},
    };
    const Scan s = ScanScene(scene);
    const auto left = Fragments(s.cloud, sim::ObjectLabel(1));
    const auto right = Fragments(s.cloud, sim::ObjectLabel(2));
    ASSERT_EQ(left.size(), 1u);
    ASSERT_EQ(right.size(), 1u);
    const std::vector<Indices> objects{left[0], right[0]};
    const std::vector<std::vector<Indices>> parts{BoxParts(s, left[0]), BoxParts(s, right[0])};
    const OcclusionMergeResult r = MergeOccludedFragments(s.cloud, objects, parts, s.plane);
    EXPECT_EQ(r.candidate_pairs, 0u);
    EXPECT_EQ(r.merges, 0u);
    EXPECT_EQ(r.groups.size(), 2u);
}

TEST(OcclusionMerge, KeepsDifferentObjectsBehindOneOccluderApart) {
    // A low box left and a tall can right of a thin occluder, both partly hidden by it: the image
    // test passes, but heights and surfaces do not continue.
    sim::TableTopScene scene;
    scene.boxes = {
        {{-0.09f, 0.15f}, 0.0f, {0.14f, 0.08f, 0.06f}, {200, 60, 40, 255}},
        {{0.00f, -0.05f}, 0.0f, {0.05f, 0.05f, 0.30f}, {60, 170, 80, 255}},
    };
    scene.cylinders = {{{0.06f, 0.18f}, 0.05f, 0.20f, {40, 90, 200, 255}}};
    const Scan s = ScanScene(scene);
    const auto box = Fragments(s.cloud, sim::ObjectLabel(1));
    const auto can = Fragments(s.cloud, sim::ObjectLabel(3));
    ASSERT_EQ(box.size(), 1u);
    ASSERT_EQ(can.size(), 1u);
    const std::vector<Indices> objects{box[0], can[0]};
    const std::vector<std::vector<Indices>> parts{BoxParts(s, box[0]), {can[0]}};
    const OcclusionMergeResult r = MergeOccludedFragments(s.cloud, objects, parts, s.plane);
    EXPECT_EQ(r.candidate_pairs, 1u);
    EXPECT_EQ(r.merges, 0u);
    EXPECT_EQ(r.groups.size(), 2u);
}

TEST(OcclusionMerge, DeterministicAndOrderIndependentGroups) {
    const Scan s = ScanScene(OccludedBoxScene());
    const auto back = Fragments(s.cloud, sim::ObjectLabel(1));
    const auto front = Fragments(s.cloud, sim::ObjectLabel(2));
    ASSERT_EQ(back.size(), 2u);
    const std::vector<Indices> objects{back[1], front[0], back[0]};
    const std::vector<std::vector<Indices>> parts{BoxParts(s, back[1]), BoxParts(s, front[0]),
                                                  BoxParts(s, back[0])};
    const auto a = MergeOccludedFragments(s.cloud, objects, parts, s.plane);
    const auto b = MergeOccludedFragments(s.cloud, objects, parts, s.plane);
    EXPECT_EQ(a.groups, b.groups);
    EXPECT_EQ(a.groups, (std::vector<std::vector<std::size_t>>{{0, 2}, {1}}));
    // The pairs are tested in parallel; the result is that of one thread.
    for (int threads : {2, 3, 0}) {
        const auto c = MergeOccludedFragments(s.cloud, objects, parts, s.plane,
                                              OcclusionMergeParams{.num_threads = threads});
        EXPECT_EQ(c.groups, a.groups) << threads;
        EXPECT_EQ(c.candidate_pairs, a.candidate_pairs) << threads;
        EXPECT_EQ(c.merges, a.merges) << threads;
    }
}

TEST(OcclusionMerge, EmptyAndTrivialInputs) {
    const Scan s = ScanScene(OccludedBoxScene());
    const OcclusionMergeResult none = MergeOccludedFragments(s.cloud, {}, {}, s.plane);
    EXPECT_TRUE(none.groups.empty());
    EXPECT_EQ(none.merges, 0u);
    const auto back = Fragments(s.cloud, sim::ObjectLabel(1));
    ASSERT_FALSE(back.empty());
    const OcclusionMergeResult one = MergeOccludedFragments(s.cloud, {back[0]}, {{}}, s.plane);
    EXPECT_EQ(one.groups, (std::vector<std::vector<std::size_t>>{{0}}));
    // An empty hypothesis stays alone.
    const auto with_empty =
        MergeOccludedFragments(s.cloud, {Indices{}, back[0]}, {{}, {}}, s.plane);
    EXPECT_EQ(with_empty.groups, (std::vector<std::vector<std::size_t>>{{0}, {1}}));
    // An unorganized cloud has no image: every hypothesis stays alone.
    PointCloud flat = s.cloud;
    flat.SetUnorganized();
    const auto unorganized = MergeOccludedFragments(flat, back, {{}, {}}, s.plane);
    EXPECT_EQ(unorganized.groups, (std::vector<std::vector<std::size_t>>{{0}, {1}}));
    // Without a plane the height test is skipped; the fragments still join.
    const auto front = Fragments(s.cloud, sim::ObjectLabel(2));
    const auto no_plane =
        MergeOccludedFragments(s.cloud, {back[0], back[1], front[0]},
                               {BoxParts(s, back[0]), BoxParts(s, back[1]), BoxParts(s, front[0])},
                               Eigen::Vector4f::Zero());
    EXPECT_EQ(no_plane.groups, (std::vector<std::vector<std::size_t>>{{0, 1}, {2}}));
}

TEST(OcclusionMerge, Contract) {
    const Scan s = ScanScene(OccludedBoxScene());
    const auto back = Fragments(s.cloud, sim::ObjectLabel(1));
    ASSERT_EQ(back.size(), 2u);
    const std::vector<std::vector<Indices>> parts{{}, {}};
    const auto call = [&](OcclusionMergeParams p) {
        return MergeOccludedFragments(s.cloud, back, parts, s.plane, p);
    };
    EXPECT_THROW(call({.depth_margin = -0.01f}), InvalidArgument);
    EXPECT_THROW(call({.min_near_share = 0.0f}), InvalidArgument);
    EXPECT_THROW(call({.min_occluded_share = 1.5f}), InvalidArgument);
    EXPECT_THROW(call({.min_rows = 0}), InvalidArgument);
    EXPECT_THROW(call({.max_gap = 0.0f}), InvalidArgument);
    EXPECT_THROW(call({.max_gap = std::numeric_limits<float>::infinity()}), InvalidArgument);
    EXPECT_THROW(call({.min_height_overlap = -0.1f}), InvalidArgument);
    EXPECT_THROW(call({.surface_distance = 0.0f}), InvalidArgument);
    EXPECT_THROW(call({.surface_angle_deg = 95.0f}), InvalidArgument);
    EXPECT_THROW(call({.min_explained_share = 0.0f}), InvalidArgument);
    EXPECT_THROW(call({.min_cylinder_radius = 0.3f, .max_cylinder_radius = 0.2f}), InvalidArgument);
    EXPECT_THROW(call({.cylinder_iterations = 0}), InvalidArgument);
    EXPECT_THROW(call({.num_threads = -1}), InvalidArgument);
    // One parts list per hypothesis.
    EXPECT_THROW(MergeOccludedFragments(s.cloud, back, {{}}, s.plane), InvalidArgument);
    // Indices inside the cloud.
    const std::vector<Indices> bad{back[0], {static_cast<Index>(s.cloud.size())}};
    EXPECT_THROW(MergeOccludedFragments(s.cloud, bad, parts, s.plane), InvalidArgument);
    // A finite plane.
    EXPECT_THROW(
        MergeOccludedFragments(s.cloud, back, parts,
                               Eigen::Vector4f::Constant(std::numeric_limits<float>::quiet_NaN())),
        InvalidArgument);
    // Normals are needed to compare surfaces.
    PointCloud bare = s.cloud;
    bare.normals.clear();
    bare.curvature.clear();
    EXPECT_THROW(MergeOccludedFragments(bare, back, parts, s.plane), DataError);
}

}  // namespace
}  // namespace multicue

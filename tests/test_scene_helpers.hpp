#pragma once
// Simulated Kinect frames of boxes and cylinders on a table, for the stages of perceive: exact
// ground truth per object, the table plane in the camera frame, and objects built the way
// segmentation would build them (several ground-truth objects kept together as one).

#include <algorithm>
#include <map>
#include <vector>

#include <Eigen/Geometry>

#include "multicue/core/point_cloud.hpp"
#include "multicue/recognition/category_distribution.hpp"
#include "multicue/reconstruction/object_model.hpp"
#include "multicue/search/kdtree.hpp"
#include "multicue/segmentation/part_segmentation.hpp"
#include "multicue/sim/procedural.hpp"
#include "multicue/sim/scene.hpp"
#include "multicue/sim/sensors.hpp"
#include "multicue/surface/normals.hpp"

namespace multicue::test {

/// An upright box (extents x, y, z), cylinder (radius, height) or dish (radius, height: a plate
/// whose floor, 4 mm thick, spans 0.6 of its radius) whose base centre is `base` (x, y on the
/// table, z above the table top) [m].
struct Shape {
    enum Kind { kBox, kCylinder, kDish } kind = kBox;
    Eigen::Vector3f size = Eigen::Vector3f::Constant(0.1f);  ///< box extents or (r, r, h)
    Eigen::Vector3f base = Eigen::Vector3f::Zero();
};

struct SimulatedFrame {
    PointCloud cloud;                                 ///< organized, camera frame, with normals
    Eigen::Vector4f plane = Eigen::Vector4f::Zero();  ///< the table top, normal up, camera frame
    std::vector<Indices> truth;                       ///< per shape, its points (ascending)
};

inline constexpr float kTableTop = 0.75f;

/// One Kinect view (0.9 m in front of the table, 0.6 m above it) of `shapes` on a table.
inline SimulatedFrame ScanShapes(const std::vector<Shape>& shapes, std::uint64_t seed = 1) {
    sim::Scene scene;
    sim::SceneObject table;
    table.mesh = std::make_shared<const sim::PartMesh>(
        sim::MakeBoxMesh(Eigen::Vector3f(1.2f, 0.9f, kTableTop)));
    table.label = sim::kTableLabel;
    scene.objects.push_back(table);
    for (std::size_t k = 0; k < shapes.size(); ++k) {
        const Shape& s = shapes[k];
        sim::SceneObject o;
        if (s.kind == Shape::kBox) {
            o.mesh = std::make_shared<const sim::PartMesh>(sim::MakeBoxMesh(s.size));
        } else if (s.kind == Shape::kCylinder) {
            const float r = s.size.x(), h = s.size.z();
            o.mesh = std::make_shared<const sim::PartMesh>(sim::MakeRevolutionMesh(
                {{0.0f, 0.0f, 0}, {r, 0.0f, 0}, {r, h, 0}, {0.0f, h, 0}}, {"body"}, 96));
        } else {
            const float r = s.size.x(), h = s.size.z(), t = 0.004f;
            o.mesh = std::make_shared<const sim::PartMesh>(
                sim::MakeRevolutionMesh({{0.0f, 0.0f, 0},
                                         {0.6f * r, 0.0f, 0},
                                         {r, h, 0},
                                         {r - 0.006f, h, 0},
                                         {0.6f * r - 0.004f, t, 0},
                                         {0.0f, t, 0}},
                                        {"dish"}, 96));
        }
        o.T_world_object.translation() = s.base + Eigen::Vector3f(0.0f, 0.0f, kTableTop);
        o.label = sim::ObjectLabel(static_cast<std::uint32_t>(k + 1));
        o.category = 1;
        scene.objects.push_back(o);
    }
    scene.support_center = Eigen::Vector3f(0.0f, 0.0f, kTableTop);
    scene.support_size = Eigen::Vector2f(1.2f, 0.9f);
    const Eigen::Isometry3f T_world_camera = sim::LookAt(
        Eigen::Vector3f(0.0f, -0.9f, kTableTop + 0.6f), Eigen::Vector3f(0.0f, 0.0f, kTableTop));
    SimulatedFrame f;
    f.cloud = sim::ScanKinect(scene, T_world_camera, sim::KinectParams{}, seed);
    const Eigen::Vector3f up = T_world_camera.linear().transpose() * Eigen::Vector3f::UnitZ();
    const Eigen::Vector3f on_table =
        T_world_camera.inverse() * Eigen::Vector3f(0.0f, 0.0f, kTableTop);
    f.plane = Eigen::Vector4f(up.x(), up.y(), up.z(), -up.dot(on_table));
    f.truth.resize(shapes.size());
    Indices finite;
    for (std::size_t i = 0; i < f.cloud.size(); ++i) {
        if (!f.cloud.IsFinite(i)) continue;
        finite.push_back(static_cast<Index>(i));
        const std::uint32_t label = f.cloud.labels[i];  // 10 * (k + 2) for shape k
        if (label >= 20 && label / 10 - 2 < shapes.size()) {
            f.truth[label / 10 - 2].push_back(static_cast<Index>(i));
        }
    }
    EnsureFrameNormals(f.cloud, finite, FrameNormalParams{});
    return f;
}

/// The shapes `which` kept together as one object, with the parts perceive would find and
/// category `c` (probability 1).
inline PerceivedObject MergedObject(const SimulatedFrame& f, const std::vector<std::size_t>& which,
                                    Category c) {
    PerceivedObject o;
    for (std::size_t k : which)
        o.indices.insert(o.indices.end(), f.truth[k].begin(), f.truth[k].end());
    std::sort(o.indices.begin(), o.indices.end());
    const KdTree tree(f.cloud, o.indices);
    RegionGrowingParams rg = PartSegmentationParams{}.region_growing;
    rg.subset = o.indices;
    o.parts = RegionGrowing(f.cloud, tree, rg).parts;
    o.category.category = c;
    o.category.probabilities[static_cast<std::size_t>(c)] = 1.0f;
    o.category.confidence = 1.0f;
    return o;
}

/// Share of `object`'s points that belong to its most represented shape, and that shape.
inline std::pair<double, std::size_t> Purity(const SimulatedFrame& f, const Indices& object) {
    std::map<std::size_t, std::size_t> votes;
    for (Index i : object) {
        for (std::size_t k = 0; k < f.truth.size(); ++k) {
            if (std::binary_search(f.truth[k].begin(), f.truth[k].end(), i)) ++votes[k];
        }
    }
    std::size_t best = 0, count = 0;
    for (const auto& [k, n] : votes) {
        if (n > count) {
            best = k;
            count = n;
        }
    }
    return {object.empty() ? 0.0 : static_cast<double>(count) / object.size(), best};
}

}  // namespace multicue::test

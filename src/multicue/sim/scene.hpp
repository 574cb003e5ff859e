#pragma once
/// \file Simulated scenes: mesh instances with pose, ground-truth label, category and colour.
/// World frame: z up, metres, the floor at z = 0.
///
/// Ground-truth labels follow the mOSD scheme (as tabletop_scene.hpp): 0 no return, 1 table
/// (support), 2 floor, 3 wall, 10*(k+1) for object k = 1, 2, ... (ObjectLabel).

#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "multicue/core/types.hpp"
#include "multicue/sim/mesh.hpp"
#include "multicue/sim/tabletop_scene.hpp"

namespace multicue::sim {

constexpr std::uint32_t kWallLabel = 3;

/// How an object came to rest where it is (ground truth of the scene generators).
enum class ObjectPlacement {
    kFixed,     ///< table, floor, walls
    kStanding,  ///< stands on the table (or the floor) apart from the other objects
    kTouching,  ///< stands on the table touching another object's side
    kStacked,   ///< rests on the flat top face of SceneObject::support
    kNested,    ///< rests inside the container SceneObject::support (a bowl, a plate)
    kLeaning,   ///< stands on the table, tilted, leaning against SceneObject::support
};

/// "fixed", "standing", "touching", "stacked", "nested" or "leaning".
const char* ObjectPlacementName(ObjectPlacement placement);

/// One mesh instance in a scene.
struct SceneObject {
    std::shared_ptr<const PartMesh> mesh;  ///< geometry in the object frame [m] (shared)
    Eigen::Isometry3f T_world_object = Eigen::Isometry3f::Identity();
    std::uint32_t label = 0;     ///< mOSD label (kTableLabel, kFloorLabel, kWallLabel, ObjectLabel)
    std::uint32_t category = 0;  ///< index into CategoryNames() (0 for table, floor, walls)
    Color color{200, 200, 200, 255};  ///< used where the mesh has no vertex colours
    bool use_vertex_colors = false;   ///< take colours from the mesh's vertex colours
    std::string source;               ///< mesh file or procedural generator ("mug", "box", ...)
    float scale = 1.0f;               ///< scale applied to the source mesh (file units -> m)
    ObjectPlacement placement = ObjectPlacement::kFixed;  ///< how it rests
    /// Label of what it rests on (kStanding, kTouching: the table or floor), sits in (kNested)
    /// or leans against (kLeaning); 0 for kFixed.
    std::uint32_t support = 0;
};

/// A scene: every instance plus the support surface it was built around.
struct Scene {
    std::vector<SceneObject> objects;
    /// Centre of the table top (or turntable) in the world [m]; the point cameras look at.
    Eigen::Vector3f support_center = Eigen::Vector3f::Zero();
    Eigen::Vector2f support_size = Eigen::Vector2f::Zero();  ///< table top x/y size [m]
    /// Azimuth [rad] around support_center of the side the scene was composed to be seen from
    /// (objects hidden behind others from there); NaN: any side. TableViewpoints puts the first
    /// view there.
    float view_azimuth = std::numeric_limits<float>::quiet_NaN();

    /// Number of objects with an object label (>= 20).
    std::size_t NumObjects() const;
};

/// An object of the scene's object labels: index into Scene::objects of label 10*(k+1), or -1.
int FindObject(const Scene& scene, std::uint32_t label);

/// A camera looking from `eye` at `target` with the image's "up" towards world +z. Optical frame:
/// x right, y down, z forward. Throws InvalidArgument when eye == target or looking straight down.
Eigen::Isometry3f LookAt(const Eigen::Vector3f& eye, const Eigen::Vector3f& target);

}  // namespace multicue::sim

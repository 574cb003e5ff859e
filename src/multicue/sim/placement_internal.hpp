#pragma once
/// \file Helpers shared by the scene generators: resting poses and footprints of objects on a
/// horizontal support, 2D polygon tests, the table and floor meshes, object instances. Internal
/// to the sim module, not part of its API.

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "multicue/sim/objects.hpp"
#include "multicue/sim/scene.hpp"

namespace multicue::sim {
struct TableSceneParams;
}

namespace multicue::sim::placement_internal {

using Polygon = std::vector<Eigen::Vector2f>;

/// An object's pose on a support at height `h`: rotation (stable pose and yaw) and the footprint
/// relative to the footprint's centre.
struct Pose {
    Eigen::Matrix3f R = Eigen::Matrix3f::Identity();
    float z = 0.0f;          ///< translation z that rests the object on the support
    Eigen::Vector2f offset;  ///< object origin relative to the footprint centre
    Polygon footprint;       ///< hull around the footprint centre
};

/// The pose of `mesh` rotated by R resting on a horizontal support at height `h`: its lowest
/// vertex at h and its footprint (convex hull of the rotated vertices in x-y) centred on the
/// centre of the footprint's bounding box.
Pose RestingPose(const PartMesh& mesh, const Eigen::Matrix3f& R, float h);

/// A random stable pose (StableRotations; the upright one with `upright_probability` when it is
/// stable and `allow_tilted`) with uniform yaw, resting at height `h`.
Pose ChoosePose(const PartMesh& mesh, float h, float upright_probability, StreamRng& rng,
                bool allow_tilted = true);

/// `p` moved by `t`.
Polygon Translated(const Polygon& p, const Eigen::Vector2f& t);

/// True when every vertex of `p` lies in the box [lo, hi].
bool Inside(const Polygon& p, const Eigen::Vector2f& lo, const Eigen::Vector2f& hi);

/// Smallest PolygonSeparation of `p` from any of `others` (infinity when there are none).
float MinSeparation(const Polygon& p, const std::vector<Polygon>& others);

/// An instance of `model` in `pose` with its footprint centre at `at`.
SceneObject MakeInstance(const ObjectModel& model, const Pose& pose, const Eigen::Vector2f& at,
                         std::uint32_t label, Color color);

/// Table top (a slab whose top is at `h`) and four legs, one mesh with parts "top" and "leg".
std::shared_ptr<const PartMesh> TableMesh(const Eigen::Vector2f& size, float h);

/// A fixed instance (identity pose) of `mesh`: table, floor, walls.
SceneObject Fixed(std::shared_ptr<const PartMesh> mesh, std::uint32_t label, Color color,
                  const std::string& source);

/// A floor slab of 2*half x 2*half m with its top at z = 0 (label kFloorLabel).
SceneObject Floor(float half);

/// The floor and four walls (0.1 m thick, `wall_height` high, label kWallLabel) of a room of
/// size_x x size_y m centred on the origin, appended to `scene`.
void AddFloorAndWalls(float size_x, float size_y, float wall_height, Scene& scene);

/// The table of `params` (size and height drawn from `rng` in this order, then its wood colour)
/// and the floor, appended to `scene`, which gets the support centre and size. Returns the
/// table's height [m].
float AddTableAndFloor(const TableSceneParams& params, StreamRng& rng, Scene& scene);

/// The table-top scenes of the modes other than kDefault (scene_modes.cpp); `params` are
/// checked by the caller.
Scene MakeModeTableScene(const TableSceneParams& params, ObjectSource& source, std::uint64_t seed);

}  // namespace multicue::sim::placement_internal

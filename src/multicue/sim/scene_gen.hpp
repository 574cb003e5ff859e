#pragma once
/// \file Scene generators: a table with objects in stable, non-intersecting poses (optionally
/// touching), viewpoints around it at robot-head height (section 5.3, Figure 5.15), a turntable
/// for single objects (16+ views, sections 4.2.2 and 4.2.5) and a room with furniture for the
/// tilting laser (section 4.2.5).

#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "multicue/sim/objects.hpp"
#include "multicue/sim/scene.hpp"

namespace multicue::sim {

struct TableSceneParams {
    int min_objects = 3;  ///< objects per scene, drawn uniformly in [min, max]
    int max_objects = 8;
    /// Probability that an object is placed touching an object already on the table [0, 1]
    /// (0: every object stands apart by at least min_gap).
    float clutter = 0.3f;
    float min_gap = 0.02f;      ///< clearance between objects that do not touch [m]
    float edge_margin = 0.05f;  ///< clearance from the table edge [m]
    Eigen::Vector2f table_min_size{0.9f, 0.6f};  ///< table top x/y size range [m]
    Eigen::Vector2f table_max_size{1.6f, 1.0f};
    float table_min_height = 0.70f;  ///< table top above the floor [m]
    float table_max_height = 0.78f;
    float upright_probability = 0.75f;  ///< chance of the upright pose when it is stable
};

/// A table (label 1) on the floor (label 2) with objects from `source` (labels 10*(k+1)), random
/// yaw, stable poses and random colours. The world origin is below the table centre.
/// Objects that find no free place are left out (the scene may hold fewer than min_objects).
Scene MakeTableScene(const TableSceneParams& params, ObjectSource& source, std::uint64_t seed);
/// Procedural objects of every category.
Scene MakeTableScene(const TableSceneParams& params, std::uint64_t seed);

struct ViewpointParams {
    float min_height = 1.3f;  ///< camera height above the floor [m]
    float max_height = 1.6f;
    float min_distance = 0.8f;  ///< horizontal distance from the table centre [m]
    float max_distance = 1.5f;
    float target_jitter = 0.05f;  ///< random offset of the look-at point on the table [m]
};

/// `n` camera poses (optical frames) on a circle around the support centre, evenly spaced in
/// azimuth from a random start, at a random height and distance (kept outside the table top),
/// looking at the table.
std::vector<Eigen::Isometry3f> TableViewpoints(const Scene& scene, int n,
                                               const ViewpointParams& params, std::uint64_t seed);

struct TurntableParams {
    float table_height = 0.75f;  ///< turntable top above the floor [m]
    float camera_height = 1.5f;  ///< above the floor [m]
    float distance = 1.0f;       ///< horizontal distance camera - turntable axis [m]
};

/// One object (label 20) in its upright (or first stable) pose on a 0.6 m x 0.6 m table.
Scene MakeTurntableScene(const ObjectModel& object, const TurntableParams& params,
                         std::uint64_t seed);
/// `n` views all around the object, azimuth 360*k/n degrees: the same as turning the object on a
/// turntable in front of a fixed sensor.
std::vector<Eigen::Isometry3f> TurntableViews(const Scene& scene, int n,
                                              const TurntableParams& params);

struct RoomParams {
    float min_size = 4.0f;  ///< room side length range [m]
    float max_size = 7.0f;
    float wall_height = 2.5f;  ///< [m]
    int min_furniture = 3;
    int max_furniture = 6;
    float min_gap = 0.3f;  ///< clearance between pieces of furniture [m]
};

/// A room: floor (2), four walls (3) and furniture pieces from `source` (a furniture library;
/// objects 10*(k+1)) standing upright with random yaw, without overlap.
Scene MakeRoomScene(const RoomParams& params, ObjectSource& source, std::uint64_t seed);

/// Pose of the tilting laser's head at `height` above the floor at a random free spot of a room,
/// looking towards the room centre (x forward, z up).
Eigen::Isometry3f RoomLaserPose(const Scene& room, float height, std::uint64_t seed);

/// Pose of a tilting laser head at `height` above the floor, `distance` from the table centre,
/// facing it (azimuth in radians).
Eigen::Isometry3f TableLaserPose(const Scene& scene, float azimuth, float distance,
                                 float height = 1.5f);

}  // namespace multicue::sim

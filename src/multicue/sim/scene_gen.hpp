#pragma once
/// \file Scene generators: a table with objects in stable, non-intersecting poses (optionally
/// touching), viewpoints around it at robot-head height (section 5.3, Figure 5.15), a turntable
/// for single objects (16+ views, sections 4.2.2 and 4.2.5) and a room with furniture for the
/// tilting laser (section 4.2.5).

#include <cstdint>
#include <string_view>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "multicue/sim/objects.hpp"
#include "multicue/sim/scene.hpp"

namespace multicue::sim {

/// What kind of table-top scene MakeTableScene composes. kDefault is the generator's original
/// scene (same seed, same scene); the others follow the scene types of the Object Segmentation
/// Database (mOSD; thesis section 5.3): their object kinds, counts and arrangements.
enum class TableSceneMode {
    kDefault,    ///< objects of every category standing apart or, with `clutter`, touching
    kBoxes,      ///< boxes and flat boxes standing apart
    kStacked,    ///< boxes stacked on boxes, 2-3 high, beside boxes on the table
    kOccluded,   ///< pairs: an object partly hidden behind another from the view side
    kCylindric,  ///< cans, cups, mugs, tins, bottles, plates and bowls
    kMixed,      ///< boxes and cylindric objects, touching, now and then stacked
    kComplex,    ///< stacked, touching, leaning, nested (an object in a bowl or on a plate),
                 ///< some at the edge of the view
};

/// "default", "boxes", "stacked", "occluded", "cylindric", "mixed", "complex".
const char* TableSceneModeName(TableSceneMode mode);
/// Inverse of TableSceneModeName. Throws InvalidArgument naming the value and the choices.
TableSceneMode ParseTableSceneMode(std::string_view name);

struct TableSceneParams {
    TableSceneMode mode = TableSceneMode::kDefault;  ///< scene type (TableSceneParamsFor)
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

/// The parameters of a scene type: its mode, object count range, clutter and, for kComplex, a
/// larger table used up to 1 cm from its edge (docs/simulation.md lists them). The other fields
/// keep their defaults; TableSceneParamsFor(kDefault) equals TableSceneParams{}.
TableSceneParams TableSceneParamsFor(TableSceneMode mode);

/// A table (label 1) on the floor (label 2) with objects from `source` (labels 10*(k+1)), random
/// yaw, stable poses and random colours, arranged as `params.mode` says. The world origin is below
/// the table centre. Objects never interpenetrate; each records how it rests
/// (SceneObject::placement, SceneObject::support). kDefault: objects that find no free place are
/// left out (the scene may hold fewer than min_objects); the other modes draw further objects
/// until the count is reached or the table is full. Throws InvalidArgument for bad params.
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

/// Viewpoints for a scene type: the defaults, but closer to the table for kComplex (0.8-1.0 m,
/// 1.3-1.45 m high), so that objects near the table's ends leave the field of view.
ViewpointParams TableViewpointParamsFor(TableSceneMode mode);

/// `n` camera poses (optical frames) on a circle around the support centre, evenly spaced in
/// azimuth from a random start (from Scene::view_azimuth when that is set), at a random height
/// and distance (kept outside the table top), looking at the table.
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

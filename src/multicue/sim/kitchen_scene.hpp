#pragma once
/// \file Simulated kitchens as a robot sees them (thesis section 4.1, Figure 4.1): a room with
/// floor, ceiling and walls; rows of cupboards, drawer units and appliances (PartNet-Mobility
/// models) against two or three walls, a worktop on the lower units, wall cupboards above,
/// now and then a microwave on the worktop and a table with objects in the room. Every door and
/// drawer has a joint state (closed, or opened by an angle or distance).
///
/// World frame: z up, metres, the floor at z = 0, the room spanning [0, size.x] x [0, size.y].
/// Scene objects are the room's boxes and one object per model link (posed by the joint state),
/// each with a label 1 + its index, so a scan's `labels` field says which object every point hit;
/// AddKitchenTruth turns that into the kitchen's ground-truth fields.

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "multicue/core/point_cloud.hpp"
#include "multicue/io/urdf.hpp"
#include "multicue/sim/kitchen_library.hpp"
#include "multicue/sim/scene.hpp"

namespace multicue::sim {

/// Ground-truth semantic class of a kitchen point (the extra field `semantic`).
enum class KitchenClass : std::uint8_t {
    kNone = 0,
    kWall,
    kFloor,
    kCeiling,
    kWorktop,
    kBody,    ///< furniture and appliance bodies, shelves, buttons
    kDoor,    ///< revolute fronts
    kDrawer,  ///< prismatic fronts
    kHandle,
    kKnob,
    kTable,   ///< the body of a table
    kObject,  ///< objects standing on a table or the worktop
};

/// "none", "wall", "floor", "ceiling", "worktop", "body", "door", "drawer", "handle", "knob",
/// "table", "object" (index = KitchenClass value).
const std::vector<std::string>& KitchenClassNames();

struct KitchenSceneParams {
    float room_min = 3.4f;               ///< smallest side of the room [m]
    float room_max = 4.6f;               ///< largest side of the room [m]
    float height_min = 2.4f;             ///< lowest ceiling [m]
    float height_max = 2.7f;             ///< highest ceiling [m]
    int min_runs = 2;                    ///< walls with a row of units, 2 or 3
    int max_runs = 3;                    ///< [walls]
    float worktop_thickness = 0.03f;     ///< [m]
    float worktop_overhang = 0.02f;      ///< beyond the deepest unit below [m]
    float wall_cupboard_bottom = 1.45f;  ///< height of the wall cupboards' bottom [m]
    float wall_cupboard_chance = 0.7f;   ///< chance of a wall cupboard above a lower unit
    float microwave_chance = 0.5f;       ///< chance of a microwave on a run's worktop
    float table_chance = 0.5f;           ///< chance of a table with objects in the room
    int max_table_objects = 4;           ///< objects on the table [objects]
    float max_model_width = 2.3f;        ///< models wider than this are not used [m]
    float max_model_depth = 1.1f;        ///< models deeper than this are not used [m]
    /// Where the models of a kind include procedural units (KitchenModelEntry::procedural) and
    /// library models, the chance that a unit is a procedural one
    float procedural_share = 0.5f;
    /// Throws InvalidArgument naming the first out-of-range field.
    void Validate() const;
};

/// One model placed in the kitchen.
struct KitchenInstance {
    std::string name;  ///< "m00", "m01", ...: prefix of its links and joints in the URDF
    std::shared_ptr<const ArticulatedModel> model;
    Eigen::Isometry3f T_world_model = Eigen::Isometry3f::Identity();
    std::vector<float> q;          ///< joint state, one value per model joint
    std::vector<int> link_object;  ///< per model link: its index in Scene::objects, -1 if none
    int run = -1;                  ///< wall run it stands in (-1: free-standing)
};

/// Ground truth of one scene object.
struct KitchenObjectTruth {
    int instance = -1;  ///< index into KitchenScene::instances; -1 for room structure, objects
    int link = -1;      ///< link of that instance's model
    KitchenClass base = KitchenClass::kNone;  ///< class of its points (handles and knobs aside)
};

/// A movable joint of the kitchen (revolute, prismatic or continuous).
struct KitchenJoint {
    std::string name;  ///< "<instance>__<joint>" as in the ground-truth URDF
    int instance = -1;
    int joint = -1;      ///< index into the model's joints
    bool front = false;  ///< the child is a door or drawer
    io::UrdfJointType type = io::UrdfJointType::kFixed;
    /// Axis in the world for the current state of the other joints: a point on it [m] and the
    /// unit direction.
    Eigen::Vector3f axis_point = Eigen::Vector3f::Zero();
    Eigen::Vector3f axis_direction = Eigen::Vector3f::UnitZ();
    float lower = 0.0f, upper = 0.0f;  ///< limits [rad] or [m]
};

struct KitchenScene {
    Scene scene;
    Eigen::Vector3f size = Eigen::Vector3f::Zero();  ///< room extents [m]
    std::vector<KitchenInstance> instances;
    std::vector<KitchenObjectTruth> truth;  ///< one per Scene::objects entry
    std::vector<KitchenJoint> joints;       ///< every movable joint
    /// A row of units along a wall: the units stand at origin + tangent * s, s in [begin, end],
    /// their fronts facing `normal` (the wall's inward normal); origin lies on the wall face.
    struct Run {
        Eigen::Vector3f origin = Eigen::Vector3f::Zero();
        Eigen::Vector3f tangent = Eigen::Vector3f::UnitX();
        Eigen::Vector3f normal = Eigen::Vector3f::UnitY();
        float begin = 0.0f;  ///< [m]
        float end = 0.0f;    ///< [m]
        float depth = 0.0f;  ///< of the deepest lower unit [m]
    };
    std::vector<Run> runs;

    /// Sets joint `k` (index into `joints`) to `value` and moves the links it carries.
    void SetJoint(std::size_t k, float value);
    /// Index into `joints` of a joint by name; -1 if absent.
    int FindJoint(const std::string& name) const;
};

/// A random kitchen of models from `library` (loaded through `cache`), all closed. Deterministic
/// for a seed and a library. Throws InvalidArgument for bad parameters, DataError when the library
/// lacks lower units (cupboards, sink cupboards, drawer units, dishwashers or fridges).
KitchenScene MakeKitchenScene(const std::vector<KitchenModelEntry>& library,
                              KitchenModelCache& cache, const KitchenSceneParams& params,
                              std::uint64_t seed);

/// Adds the ground-truth fields of a scan of `kitchen` (made by the sim sensors, whose `labels`
/// are 1 + scene object index and `part` 1 + mesh part): extra fields `semantic` (uint8,
/// KitchenClass), `model` (uint16, 1 + instance, 0 for room structure and objects), `link`
/// (uint16, 1 + link index in the model) and `joint` (uint16, 1 + index into kitchen.joints of
/// the joint that moves the point's link, 0 for none).
void AddKitchenTruth(const KitchenScene& kitchen, PointCloud& scan);

/// Moves a scan from its sensor frame into the world (points and normals; NaN points stay NaN,
/// the layout is kept) and records the sensor pose as the cloud's sensor_origin and
/// sensor_orientation, as kitchen scans are stored.
void ScanToWorld(PointCloud& scan, const Eigen::Isometry3f& T_world_sensor);

/// The whole kitchen as URDF: a root link "kitchen" (the world frame), the room's boxes as fixed
/// links, and every model's links and joints (names prefixed "<instance>__") with mesh visuals
/// naming the library files (`scale` = the model's scale), its base fixed at its pose.
io::UrdfModel KitchenGroundTruthUrdf(const KitchenScene& kitchen);

/// Sensor poses of a kitchen: the laser head in the room, 1.4 m high, facing the back run;
/// `count` head positions spread over the free floor (the first in the room's centre), always at
/// least 0.3 m clear of the units (taken as 0.85 m deep or deeper).
std::vector<Eigen::Isometry3f> KitchenLaserPoses(const KitchenScene& kitchen, int count,
                                                 std::uint64_t seed);
/// Kinect poses (optical frames, LookAt) looking at the runs from 2.0-2.8 m, 1.4-1.6 m high,
/// `count` views spread over the runs in turn, clear of the units like the laser's.
std::vector<Eigen::Isometry3f> KitchenCameraPoses(const KitchenScene& kitchen, int count,
                                                  std::uint64_t seed);

/// Handle variety for training: PartNet-Mobility holds few handle designs per kind, so a
/// classifier trained on one half of the models meets handles of lengths it never saw on the
/// other. VaryHandles stretches or shrinks handles along their length (the middle is scaled, the
/// ends with their mounts move rigidly), keeping their cross-section, mounts and position.
struct HandleVariation {
    float chance = 0.7f;          ///< chance that a handle is varied (the others keep their length)
    float min_length = 0.04f;     ///< shortest varied handle [m]
    float max_length = 1.0f;      ///< longest varied handle [m]
    float min_shrink = 0.5f;      ///< a handle keeps at least this share of its length
    float front_margin = 0.03f;   ///< a varied handle ends this far inside its front's edges [m]
    float min_elongation = 2.0f;  ///< handles less elongated than this (length / width) are kept
    /// Cross-section: a varied handle's reach out of its front (along the front's normal, from
    /// the front's surface) is scaled by a factor drawn from [min, max]; [1, 1] keeps it
    float min_reach_scale = 1.0f;
    float max_reach_scale = 1.0f;
    /// ... and its thickness (the third axis, about its centre) by one from [min, max]
    float min_thickness_scale = 1.0f;
    float max_thickness_scale = 1.0f;
    /// Throws InvalidArgument naming the first out-of-range field.
    void Validate() const;
};

/// Varies the handles of every model link in `kitchen` (the mesh parts named "handle", split into
/// connected pieces) as `variation` says (length, then reach and thickness); a varied link gets a
/// mesh of its own, the library's meshes are not changed. Deterministic for a seed. Returns the
/// number of handles varied.
int VaryHandles(KitchenScene& kitchen, const HandleVariation& variation, std::uint64_t seed);

}  // namespace multicue::sim

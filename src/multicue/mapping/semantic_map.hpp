#pragma once
/// \file The semantic map of a kitchen (thesis section 4.1.3, Figures 4.1 and 4.8): the room's
/// axes, structure (floor, ceiling, walls, worktops and tables, furniture faces), the fixtures
/// (handles and knobs) on the faces, the door and drawer fronts they open with their articulation,
/// and the furniture pieces typed as containers, in the hierarchy kitchenette -> furniture ->
/// fronts -> fixtures. Every stage of MapKitchen (kitchen_map.hpp) fills one part of it.

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "multicue/core/types.hpp"

namespace multicue::mapping {

/// Semantic class of a map point (labels.pcd field `semantic`, the report's colours).
enum class MapClass : std::uint8_t {
    kNone = 0,  ///< unexplained or invalid
    kWall = 1,
    kFloor = 2,
    kCeiling = 3,
    kWorktop = 4,
    kTable = 5,  ///< a free-standing horizontal surface
    kFace = 6,   ///< a furniture face outside every front (bodies, frames, side panels)
    kFront = 7,  ///< a door or drawer front
    kHandle = 8,
    kKnob = 9,
};
inline constexpr std::size_t kNumMapClasses = 10;

/// "none", "wall", "floor", "ceiling", "worktop", "table", "face", "front", "handle", "knob".
const std::vector<std::string>& MapClassNames();

/// The room's main axes: columns x and y horizontal, z up; right-handed.
struct RoomFrame {
    Eigen::Matrix3f axes = Eigen::Matrix3f::Identity();
    Eigen::Vector3f Up() const { return axes.col(2); }
};

/// A connected planar component aligned with one of the room axes.
struct PlanarComponent {
    int axis = 0;  ///< 0, 1 (vertical planes, normal along a horizontal axis) or 2 (horizontal)
    /// (a, b, c, d) with unit normal facing the sensors (up for horizontal planes).
    Eigen::Vector4f plane = Eigen::Vector4f::Zero();
    Indices indices;  ///< its points
    /// Extent in plane coordinates: u along the in-plane horizontal axis (for horizontal planes
    /// the room x axis), v along up (for horizontal planes the room y axis) [m].
    Eigen::Vector2f min = Eigen::Vector2f::Zero();
    Eigen::Vector2f max = Eigen::Vector2f::Zero();
    float area = 0.0f;  ///< occupied area [m^2]
    MapClass label = MapClass::kNone;
};

enum class FixtureType : std::uint8_t { kHandle, kKnob };

/// A handle or knob found in front of a furniture face (section 4.1.2).
struct Fixture {
    FixtureType type = FixtureType::kHandle;
    int face = -1;                                         ///< index into KitchenMap::components
    Eigen::Vector3f center = Eigen::Vector3f::Zero();      ///< centroid of its points [m]
    Eigen::Vector3f direction = Eigen::Vector3f::UnitZ();  ///< handle's long axis (unit)
    float length = 0.0f;                                   ///< extent along `direction` [m]
    float width = 0.0f;                ///< extent across it, in the face plane [m]
    float protrusion = 0.0f;           ///< largest distance from the face [m]
    float depth_extent = 0.0f;         ///< extent of its points along the face normal [m]
    float line_inlier_ratio = 0.0f;    ///< share of points on the RANSAC line
    float circle_inlier_ratio = 0.0f;  ///< share of points on the RANSAC circle
    Indices indices;
};

enum class JointType : std::uint8_t { kUnknown, kRevolute, kPrismatic };

/// "unknown", "revolute" or "prismatic".
const char* JointTypeName(JointType type);

/// How a front moves: a revolute joint about `axis` through `origin`, or a prismatic joint along
/// `axis`; positive values open it. Limits in radians or metres.
struct Articulation {
    JointType type = JointType::kUnknown;
    Eigen::Vector3f origin = Eigen::Vector3f::Zero();  ///< a point on the axis [m]
    Eigen::Vector3f axis = Eigen::Vector3f::UnitZ();   ///< unit
    float lower = 0.0f;
    float upper = 0.0f;
    /// "fixture" (from the handle's orientation and place), "classifier" (a joint classifier's
    /// answer from the same, ClassifyJoints), "motion" (from two scans), "none".
    std::string source = "none";
    /// Whether the scans saw the edge a revolute front's hinge lies on. False when that edge
    /// lay at the border of the view, out of it or hidden: the front may run on beyond what was
    /// seen, so the hinge's place is a guess, not a measurement.
    bool hinge_seen = true;
};

/// A door or drawer front: the region grown from a fixture's footprint (section 4.1.2) and its
/// rectangular approximation on the face plane.
struct Front {
    int face = -1;                                  ///< index into KitchenMap::components
    std::vector<int> fixtures;                      ///< indices into KitchenMap::fixtures
    Indices indices;                                ///< its points
    Eigen::Vector2f min = Eigen::Vector2f::Zero();  ///< rectangle in face coordinates [m]
    Eigen::Vector2f max = Eigen::Vector2f::Zero();
    Eigen::Vector3f center = Eigen::Vector3f::Zero();   ///< rectangle centre in the world [m]
    Eigen::Vector3f u_axis = Eigen::Vector3f::UnitX();  ///< world direction of face u
    Eigen::Vector3f v_axis = Eigen::Vector3f::UnitZ();  ///< world direction of face v (up)
    Eigen::Vector3f normal = Eigen::Vector3f::UnitY();  ///< facing out of the furniture
    float appearance_median = 0.0f;  ///< final median of the colour/intensity model
    float appearance_mad = 0.0f;     ///< final MAD of the model
    int model_iterations = 0;        ///< rounds until the model was stable
    bool overlapping = false;  ///< its region overlapped another fixture's (marked, then split)
    Articulation articulation;
    int furniture = -1;  ///< index into KitchenMap::furniture
};

/// A furniture piece or appliance: fronts grouped by their arrangement, typed as a container.
struct Furniture {
    std::vector<int> fronts;  ///< indices into KitchenMap::fronts
    int face = -1;
    Eigen::Vector3f center = Eigen::Vector3f::Zero();    ///< box centre [m]
    Eigen::Matrix3f axes = Eigen::Matrix3f::Identity();  ///< columns: width, depth (out), up
    Eigen::Vector3f extents = Eigen::Vector3f::Zero();   ///< width, depth, height [m]
    std::string type = "cupboard";                       ///< ContainerTypes() of containers.hpp
    float confidence = 0.0f;
    int kitchenette = -1;
};

/// Furniture along one wall (or all furniture when no wall is known).
struct Kitchenette {
    std::vector<int> furniture;
    int wall = -1;  ///< index into KitchenMap::components, -1 for none
};

struct KitchenMap {
    RoomFrame frame;
    float floor_height = 0.0f;    ///< along up [m]; NaN when no floor was seen
    float ceiling_height = 0.0f;  ///< NaN when no ceiling was seen
    std::vector<PlanarComponent> components;
    std::vector<Fixture> fixtures;
    std::vector<Front> fronts;
    std::vector<Furniture> furniture;
    std::vector<Kitchenette> kitchenettes;
    /// Per point of the mapped cloud: class, and 1 + front index (0 for none).
    std::vector<MapClass> point_class;
    std::vector<std::uint32_t> point_front;
};

}  // namespace multicue::mapping

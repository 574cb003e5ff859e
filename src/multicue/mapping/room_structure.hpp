#pragma once
/// \file Room structure from axis-aligned planes (thesis section 4.1.2): the points whose normal
/// lies along one of the room's axes are histogrammed by their coordinate along it; each peak is
/// a plane, split into connected components. Horizontal planes are the floor (lowest, large), the
/// ceiling (highest, seen from below) and worktops or tables (at counter height; a worktop runs
/// along a wall); vertical planes are walls when they reach the ceiling, or, with no ceiling in
/// view, when nothing lies behind them; the remaining vertical components are the candidates for
/// furniture faces.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "multicue/core/point_cloud.hpp"
#include "multicue/mapping/semantic_map.hpp"

namespace multicue::mapping {

struct RoomStructureParams {
    float normal_angle_deg = 25.0f;    ///< a point's normal within this of an axis [deg]
    float distance_threshold = 0.02f;  ///< plane half-thickness near the sensor [m]
    /// The half-thickness grows with the range r of a point as range_noise * r^2 (a Kinect's
    /// disparity noise and quantisation); 0 = constant [1/m]
    float range_noise = 0.0f;
    float max_distance_threshold = 0.06f;   ///< the half-thickness never exceeds this [m]
    float bin_size = 0.005f;                ///< histogram bin along an axis [m]
    std::size_t min_plane_points = 60;      ///< smaller peaks are no planes [points]
    float component_tolerance = 0.05f;      ///< points of one plane closer than this connect [m]
    std::size_t min_component_points = 40;  ///< smaller components are dropped [points]
    float cell_size = 0.03f;                ///< occupancy cell for component areas [m]
    /// The floor (the lowest plane facing up, min_floor_depth below the sensor) needs this much
    /// area [m^2]: a Kinect looking at a counter from 1-2 m sees a strip of floor in front of it,
    /// often under 0.3 m^2.
    float min_floor_area = 0.1f;
    /// The ceiling needs this much [m^2]: a smaller plane seen from below is the underside of a
    /// wall cupboard or a shelf.
    float min_ceiling_area = 0.3f;
    /// With a sensor position: the floor lies at least this far below the sensor [m]
    float min_floor_depth = 0.8f;
    /// A plane with more than this share of the finite points at least floor_below_margin below
    /// it is no floor: a table top taken for it where little floor is in view has the furniture
    /// under it, while range noise and stray returns put few points below a real floor. 1: off
    /// [-]
    float max_below_floor_share = 0.02f;
    float floor_below_margin = 0.1f;      ///< [m]
    float min_room_height = 1.8f;         ///< the ceiling lies at least this above the floor [m]
    float wall_ceiling_gap = 0.15f;       ///< a wall reaches this close to the ceiling [m]
    float min_wall_area = 0.4f;           ///< a wall plane has this much area [m^2]
    float max_behind_share = 0.003f;      ///< with no ceiling: share of points behind a wall [-]
    float behind_margin = 0.06f;          ///< points this far behind a plane are behind it [m]
    float min_counter_height = 0.3f;      ///< worktops and tables above the floor [m]
    float max_counter_height = 1.3f;      ///< [m]
    float min_counter_area = 0.04f;       ///< [m^2]
    float worktop_wall_distance = 0.25f;  ///< a worktop's edge lies this close to a wall [m]
    /// A counter away from every wall found is still a worktop when a solid vertical face at
    /// least this tall (and 15 cm wide) stands under it, its top just below the counter (the
    /// front of the cupboards it rests on; a table's apron or drawer is shorter, its legs
    /// narrower). Walls are often hidden behind wall cupboards or out of a close view; 0: off [m]
    float worktop_face_height = 0.4f;
    float min_face_area = 0.015f;  ///< furniture face candidates [m^2]
    /// The three axes' planes, and each plane's components, in parallel (0 = all cores); the
    /// result does not depend on it.
    int num_threads = 1;
    /// Throws InvalidArgument naming the first out-of-range field.
    void Validate() const;
};

struct RoomStructure {
    std::vector<PlanarComponent> components;  ///< every kept component, labelled
    float floor_height = 0.0f;                ///< along up [m]; NaN without a floor
    float ceiling_height = 0.0f;              ///< NaN without a ceiling
    /// Per point: index into `components`, -1 for points on no kept component.
    std::vector<std::int32_t> point_component;
    /// Per point: the axis (0, 1, 2) of the axis-aligned plane it lies on (kept component or
    /// not), -1 for none.
    std::vector<std::int8_t> plane_axis;
};

/// Planes, components and their classes. The cloud needs normals (one per point). `ranges` holds
/// each point's distance to the sensor that saw it (empty: the distance to cloud.sensor_origin).
/// Throws InvalidArgument for bad parameters or ranges of the wrong size, DataError for a cloud
/// without normals. An empty cloud gives an empty structure (NaN heights).
RoomStructure SegmentRoomStructure(const PointCloud& cloud, const RoomFrame& frame,
                                   const RoomStructureParams& params = {},
                                   const std::vector<float>& ranges = {});

/// Coordinates (u, v) of a point in a component's plane (see PlanarComponent).
Eigen::Vector2f PlaneCoordinates(const PlanarComponent& c, const RoomFrame& frame,
                                 const Eigen::Vector3f& p);
/// World directions of a component's u and v axes.
Eigen::Vector3f PlaneU(const PlanarComponent& c, const RoomFrame& frame);
Eigen::Vector3f PlaneV(const PlanarComponent& c, const RoomFrame& frame);

}  // namespace multicue::mapping

#pragma once
/// \file The parts of a furniture scan and their features (thesis sections 4.2.1 and 4.2.3.1):
/// the scan is moved into the world frame (z up, the floor at z = 0), the floor and what is above
/// furniture height are cut away, the rest is thinned to an even density, given normals
/// (optionally after robust MLS smoothing, section 2.3.1) and over-segmented by normal-angle
/// region growing (delta = 5 cm, alpha = 40 degrees, parts under 10 points merged or dropped).
/// Each part gets the 24 statistical features of features/part_stats.hpp, its centre of mass l
/// and the bearing under which the sensor saw it; training views and scenes go through this one
/// function, so the vocabulary and the scenes see the same parts.

#include <cstddef>
#include <string_view>
#include <vector>

#include <Eigen/Geometry>

#include "multicue/core/params.hpp"
#include "multicue/core/point_cloud.hpp"
#include "multicue/core/types.hpp"
#include "multicue/features/feature_common.hpp"
#include "multicue/features/part_stats.hpp"
#include "multicue/segmentation/region_growing.hpp"

namespace multicue {

/// The frame a part's shape vectors are kept in (its x axis on the floor).
enum class FurniturePartFrame {
    kBearing,  ///< x along the sensor's line of sight to the part
    /// x along the part's own axes where they are clear: the inward normal of an upright planar
    /// part (a chair back, a cabinet door), the long axis of a lying elongated part (a table top,
    /// a seat), turned away from the sensor; the line of sight otherwise (legs, blobs)
    kPart,
};
/// "bearing", "part"; and back (InvalidArgument naming the choices).
const char* FurniturePartFrameName(FurniturePartFrame frame);
FurniturePartFrame ParseFurniturePartFrame(std::string_view name);

struct FurniturePartParams {
    float voxel_size = 0.02f;     ///< thinning before everything else [m]; 0 = none
    float floor_margin = 0.03f;   ///< points below this height are floor [m], >= 0
    float max_height = 2.3f;      ///< points above this height are cut away [m], > floor_margin
    bool estimate_floor = false;  ///< find the floor (lowest large horizontal layer) instead of
                                  ///< taking z = 0 of the world frame
    float normal_radius = 0.06f;  ///< PCA neighbourhood of the normals [m], > 0
    int normal_k = 30;            ///< at most this many neighbours [points], >= 3
    /// Robust MLS smoothing before the normals (thesis: RMLS, Eq. 2.4); its radius [m]. 0 = off.
    float smoothing_radius = 0.0f;
    RegionGrowingParams region_growing{.radius = 0.05f, .k = 30, .max_angle_deg = 40.0f};
    std::size_t min_part_points = 10;  ///< smaller parts are left out [points], >= 3
    FurniturePartFrame frame = FurniturePartFrame::kPart;  ///< frame of the shape vectors
    PartStatsParams stats{.radius = 0.06f, .voxel_size = 0.02f, .num_threads = 1};
    int num_threads = 0;  ///< 0 = all cores; never changes the result
    /// Throws InvalidArgument naming the first out-of-range field.
    void Validate() const;
};

/// One part of a scan.
struct FurniturePart {
    Indices indices;                                     ///< into FurnitureParts::cloud
    Eigen::Vector3f centroid = Eigen::Vector3f::Zero();  ///< l of Eq. (4.2), world frame [m]
    /// Yaw of the horizontal direction from the sensor to the centroid [rad].
    float bearing = 0.0f;
    /// Yaw of the part's frame (FurniturePartFrame) [rad]: its shape vectors are kept in it.
    float frame_yaw = 0.0f;
    float top = 0.0f;        ///< highest point [m]
    float extent = 0.0f;     ///< longest extent (feature L_3) [m]
    FeatureVector features;  ///< the 24 values of part_stats.hpp
};

struct FurnitureParts {
    /// The usable points in the world frame (floor and ceiling cut away, thinned), with normals
    /// and curvature.
    PointCloud cloud;
    Eigen::Vector3f sensor_origin = Eigen::Vector3f::Zero();  ///< world frame [m]
    /// Height of the floor in the world frame given (0 unless estimate_floor) [m]; the cloud
    /// is shifted by -floor_height so that the floor lies at z = 0.
    float floor_height = 0.0f;
    std::vector<FurniturePart> parts;
    double preprocess_ms = 0.0;  ///< cut, thinning, smoothing and normals [ms]
    double segment_ms = 0.0;     ///< region growing [ms]
    double features_ms = 0.0;    ///< part features [ms]
};

/// Parts of `scan` (in its sensor frame; T_world_sensor places it in a z-up world frame).
/// Non-finite points are skipped; a scan without usable points gives no parts. Throws
/// InvalidArgument for bad parameters or a non-finite pose.
FurnitureParts ExtractFurnitureParts(const PointCloud& scan,
                                     const Eigen::Isometry3f& T_world_sensor,
                                     const FurniturePartParams& params);

/// Height of the floor: the lowest horizontal layer (1 cm bins) holding at least a quarter as
/// many points as the fullest layer, refined to the mean height of the points within 3 cm.
/// NaN when the cloud has fewer than 100 finite points.
float EstimateFloorHeight(const PointCloud& world_cloud);

}  // namespace multicue

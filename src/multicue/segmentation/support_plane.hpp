#pragma once
/// \file The support plane of a table-top scene (thesis section 2.4): among the near-horizontal
/// planes, the one that supports the objects (the most points stand on it, inside its hull and
/// below the prism's top), its convex hull, and the prism above it as the region of interest.
/// Where no plane supports anything, the largest plane nearest the viewpoint.

#include <cstdint>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "multicue/core/point_cloud.hpp"
#include "multicue/core/types.hpp"
#include "multicue/segmentation/polygonal_prism.hpp"

namespace multicue {

/// Where "up" came from.
enum class UpSource {
    kGiven,      ///< SupportPlaneParams::up
    kViewpoint,  ///< the sensor is away from the origin, so the cloud is in a world frame, z up
    /// The sensor is at the origin (any VIEWPOINT rotation: OpenNI's and PCL's samples store
    /// 0 1 0 0 for the optical frame): optical convention, up is roughly -y.
    kCamera,
    kDominant,  ///< no hint: the dominant plane's normal, oriented towards the viewpoint
};

struct SupportPlaneParams {
    std::optional<Eigen::Vector3f> up = std::nullopt;  ///< up in the cloud's frame; none = derive
    float max_tilt_deg = 15.0f;     ///< table normal within this angle of a given or world up [deg]
    float camera_tilt_deg = 70.0f;  ///< in the sensor frame: normal within this angle of -y [deg]
    float distance_threshold = 0.012f;  ///< plane inlier distance [m]
    int max_candidates = 4;             ///< planes extracted one after another before choosing
    float min_inlier_fraction = 0.05f;  ///< a candidate holds at least this share of the points
    /// The table is the candidate with the most points standing on it (inside the hull of its
    /// largest patch, up to the prism's height), if that is at least this share of the sampled
    /// points; the top of a box supports little, a table every object. Below it, no candidate
    /// supports anything and the choice is by view (the next three fields).
    float min_supported_fraction = 0.01f;
    /// Choice by view: candidates with at least this share of the largest one's inliers compete
    /// on distance to the viewpoint; the nearest wins ("largest plane nearest the viewpoint").
    float size_ratio_to_compete = 0.5f;
    /// A smaller candidate at least raised_gap nearer to the viewpoint than that choice, holding
    /// raised_ratio of the largest one's inliers, is a table standing on the chosen floor: the
    /// largest such candidate wins (a robot sees the floor around a small table; box tops on the
    /// table are smaller than the table). In the choice by support, a supporting candidate
    /// raised_gap above the winner is the table standing on the floor (the floor may hold more:
    /// the table's legs, chairs). raised_gap <= 0 turns this off.
    float raised_gap = 0.3f;     ///< [m]
    float raised_ratio = 0.08f;  ///< [-]
    /// Points used for the robust fit and the support counts (a strided subsample); 10000 scored
    /// as 20000 did on the validation splits, with a sixth less work in this stage.
    std::size_t max_samples = 10000;
    /// The table is the largest set of its plane's inliers connected within this distance: the
    /// objects on it cut its visible top into pieces up to about their size apart [m].
    float cluster_tolerance = 0.2f;
    std::uint64_t seed = 1;  ///< sample consensus seed
    int num_threads = 0;     ///< 0 = all cores
    /// Throws InvalidArgument naming the first out-of-range field.
    void Validate() const;
    /// Its parameters once each: configuration key (the field's name), field, meaning. A
    /// visitor reads or records them (io::ConfigSection::operator(); ReadPerceiveParams).
    template <typename V>
    void VisitParams(V& v) {
        v("up", up,
          "up in the cloud's frame, null = from VIEWPOINT, the camera convention or the "
          "dominant plane");
        v("max_tilt_deg", max_tilt_deg,
          "table normal within this angle of a given or world up [deg]");
        v("camera_tilt_deg", camera_tilt_deg,
          "in the sensor frame: table normal within this angle of -y [deg]");
        v("distance_threshold", distance_threshold, "plane inlier distance [m]");
        v("max_candidates", max_candidates, "planes extracted before choosing");
        v("min_inlier_fraction", min_inlier_fraction,
          "a candidate plane holds at least this share of the points");
        v("min_supported_fraction", min_supported_fraction,
          "the plane with the most points standing on it is the table, if they are at least "
          "this share of the sampled points; else the choice is by view [-]");
        v("size_ratio_to_compete", size_ratio_to_compete,
          "planes this large relative to the largest compete on nearness to the viewpoint");
        v("raised_gap", raised_gap,
          "a smaller plane this much nearer to the viewpoint than the largest is a table on "
          "the floor and wins (0 = off) [m]");
        v("raised_ratio", raised_ratio,
          "... if it holds this share of the largest plane's inliers [-]");
        v("max_samples", max_samples, "points used by the robust fit");
        v("cluster_tolerance", cluster_tolerance,
          "the table is the largest set of plane inliers connected within this distance [m]");
        v("seed", seed, "sample consensus seed");
    }
};

struct SupportPlane {
    bool found = false;
    Eigen::Vector4f plane = Eigen::Vector4f::Zero();  ///< unit normal pointing up, a x+b y+c z+d=0
    Indices inliers;                                  ///< the table's points, ascending
    std::vector<Eigen::Vector3f> hull;  ///< convex hull of the inliers on the plane, CCW from up
    Eigen::Vector3f up = Eigen::Vector3f::UnitZ();  ///< up used for the search (unit)
    UpSource up_source = UpSource::kDominant;
    int candidates = 0;  ///< planes extracted before choosing
    /// Sampled points standing on the chosen plane; 0 when nothing stands on it or the sensor
    /// sees points through it.
    std::size_t supported = 0;
};

/// Finds the support plane; `prism` bounds the height at which points count as standing on a
/// candidate. A cloud without a suitable plane gives found = false (not an error). Throws
/// InvalidArgument for bad parameters (non-positive threshold, zero up vector, ...).
SupportPlane FindSupportPlane(const PointCloud& cloud, const SupportPlaneParams& params,
                              const PrismParams& prism = {});

/// The support plane and the points that may belong to objects on it.
struct TableRegion {
    SupportPlane support;  ///< found = false: no table (or one that supports nothing)
    Indices points;        ///< the points above the table (its prism), else every finite point
};

/// The table and the points standing on it (thesis section 2.4): FindSupportPlane, then the
/// polygonal prism (`prism`) over the plane's hull. Without a plane, or with a plane that
/// supports nothing (SupportPlane::supported = 0: the top of a box in a cloud of objects), every
/// finite point may belong to an object and `support` is reset to "none". Throws InvalidArgument
/// for bad parameters.
TableRegion FindTableRegion(const PointCloud& cloud, const SupportPlaneParams& support,
                            const PrismParams& prism);

}  // namespace multicue

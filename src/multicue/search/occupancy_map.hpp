#pragma once
/// \file Probabilistic occupancy map over an octree (OctoMap, Hornung et al. 2013): every scan
/// inserted with its sensor origin marks the voxels its rays cross as free and the voxels its
/// points fall in as occupied (thesis section 2.2: "store ... if it was explored (and found to be
/// free or occupied by an object's surface) or not"). Voxels no ray reached stay unknown, which is
/// what a next-best-view planner looks for.
///
/// Each voxel holds the log-odds of being occupied, clamped to [clamp_min, clamp_max] so that the
/// map keeps adapting; a voxel is occupied when its probability exceeds occupied_threshold. The
/// octree and its on-disk format (.bt, OctoMap's binary tree: free / occupied per leaf, readable
/// by octovis and ROS's octomap_server) stay inside this class: callers see Eigen types only.

#include <cstddef>
#include <istream>
#include <memory>
#include <ostream>

#include <Eigen/Core>

#include "multicue/core/point_cloud.hpp"

namespace multicue {

/// State of a point of space in an occupancy map.
enum class Occupancy {
    kUnknown,   ///< no ray has reached it
    kFree,      ///< rays crossed it more often than they ended in it
    kOccupied,  ///< rays ended in it (a surface)
};

/// "unknown", "free" or "occupied".
const char* OccupancyName(Occupancy state);

struct OccupancyMapParams {
    double resolution = 0.02;  ///< edge of the smallest voxel [m]; > 0
    /// Rays are cut at this length: a point further away only frees space up to it [m];
    /// 0 = no limit.
    double max_range = 0.0;
    double prob_hit = 0.7;            ///< occupancy probability after one hit, in (0.5, 1) [-]
    double prob_miss = 0.4;           ///< occupancy probability after one miss, in (0, 0.5) [-]
    double clamp_min = 0.12;          ///< lower clamp of the probability, in (0, prob_miss] [-]
    double clamp_max = 0.97;          ///< upper clamp of the probability, in [prob_hit, 1) [-]
    double occupied_threshold = 0.5;  ///< occupied above this probability, in (0, 1) [-]
    /// Throws InvalidArgument naming the first out-of-range field.
    void Validate() const;
};

/// Leaf statistics of a map.
struct OccupancyCounts {
    std::size_t free_leaves = 0;      ///< leaves classified free
    std::size_t occupied_leaves = 0;  ///< leaves classified occupied
    double free_volume = 0.0;         ///< volume of the free leaves [m^3]
    double occupied_volume = 0.0;     ///< volume of the occupied leaves [m^3]
};

/// An occupancy octree. Not thread-safe for insertion; const queries may run concurrently.
class OccupancyMap {
  public:
    /// An empty map. Throws InvalidArgument for bad parameters.
    explicit OccupancyMap(const OccupancyMapParams& params = {});
    ~OccupancyMap();
    OccupancyMap(OccupancyMap&&) noexcept;
    OccupancyMap& operator=(OccupancyMap&&) noexcept;
    OccupancyMap(const OccupancyMap&) = delete;
    OccupancyMap& operator=(const OccupancyMap&) = delete;

    /// Inserts the finite points of `points` (in the map's frame) as seen from `sensor_origin`
    /// (map frame): each voxel a ray crosses gets one miss, each voxel a point falls in one hit
    /// (a voxel is updated once per scan, hits winning over misses). Non-finite points are
    /// skipped; an empty cloud changes nothing. Throws InvalidArgument for a non-finite origin.
    void InsertScan(const PointCloud& points, const Eigen::Vector3f& sensor_origin);

    /// State of the voxel containing `point` (kUnknown outside the mapped space).
    Occupancy Query(const Eigen::Vector3f& point) const;
    /// Occupancy probability of the voxel containing `point`; 0.5 where unknown.
    double Probability(const Eigen::Vector3f& point) const;

    /// Counts and volumes of the free and occupied leaves.
    OccupancyCounts Counts() const;
    /// Centres of the occupied leaves (at their own resolution), in the octree's order.
    std::vector<Eigen::Vector3f> OccupiedCenters() const;
    /// Axis-aligned bounds of the known space; false (outputs untouched) when the map is empty.
    bool Bounds(Eigen::Vector3f& min, Eigen::Vector3f& max) const;

    double resolution() const;
    bool empty() const;
    const OccupancyMapParams& params() const;

    /// Writes the map as an OctoMap binary tree (.bt: the maximum-likelihood free / occupied
    /// state of every leaf). Throws IoError when the stream fails.
    void WriteBinary(std::ostream& out) const;
    /// Reads a .bt stream. The thresholds and clamps are those of `params`; the resolution is
    /// the stream's. Throws FormatError (naming `source`) for a stream that is not an OctoMap
    /// binary tree.
    static OccupancyMap ReadBinary(std::istream& in, const char* source = "stream",
                                   const OccupancyMapParams& params = {});

  private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace multicue

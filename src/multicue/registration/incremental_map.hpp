#pragma once
/// \file Multi-view maps (thesis sections 2.2, 4.1.1 and 5.3): frames taken from rough poses
/// (odometry, a calibrated kinematic chain) are aligned one by one to the map built from the
/// frames before them, and each aligned frame
///   - joins the map cloud (a voxel grid of every aligned frame, the target of the next one);
///   - updates an occupancy map (free / occupied / unknown space, what a next-best-view planner
///     explores);
///   - is triangulated into the existing mesh (incremental greedy projection, section 4.1.1):
///     its points in the overlap with the mesh are first re-sampled by MLS on a coarser,
///     curvature-adaptive grid (section 2.3.1), so that repeated views do not pile up vertices,
///     and points on the existing surface are dropped by the triangulation itself.
///
/// The initial guess of frame k is the aligned pose of frame k-1 moved by the odometry between
/// the two (or the pose of frame k-1 when there is no odometry). A frame whose alignment fails
/// (not converged, degenerate, too little overlap) is retried by global registration against the
/// previous frame; if that fails too, it is reported and left out of the map, so one bad frame
/// never corrupts the frames after it.

#include <cstddef>
#include <memory>
#include <optional>
#include <vector>

#include <Eigen/Geometry>

#include "multicue/core/params.hpp"
#include "multicue/core/point_cloud.hpp"
#include "multicue/core/triangle_mesh.hpp"
#include "multicue/registration/register.hpp"
#include "multicue/search/occupancy_map.hpp"
#include "multicue/surface/greedy_triangulation.hpp"

namespace multicue {

/// The mesh of a map: triangulation and the re-sampling of overlaps.
struct MapMeshParams {
    /// Triangulation of each new frame into the mesh (search_radius 0 = 3 vertex spacings).
    GreedyTriangulationParams triangulation{};
    float vertex_spacing = 0.005f;  ///< frames are voxel-downsampled to this first [m]; > 0
    /// New points within this distance of a mesh vertex are in the overlap [m]; 0 = 3 spacings
    float overlap_radius = 0.0f;
    /// MLS re-sampling step in the overlap (Eq. 2.1) [m]; 0 = 2 spacings
    float overlap_step = 0.0f;
    /// Denser re-sampling where the surface curves (MlsParams::curvature_slope) [-]
    float curvature_slope = 1.0f;
    /// Throws InvalidArgument naming the first out-of-range field.
    void Validate() const;
};

struct MapParams {
    /// Frame-to-map alignment; kAuto uses points and planes from the guess.
    RegistrationParams registration = RegistrationParams::ForResolution(0.01f);
    float map_voxel = 0.01f;      ///< voxel of the map cloud [m]; > 0
    bool register_frames = true;  ///< false: take the given poses as they are
    bool global_fallback = true;  ///< retry failed frames globally against the previous frame
    Switchable<OccupancyMapParams> occupancy{};  ///< the occupancy map
    Switchable<MapMeshParams> mesh{};            ///< the incremental mesh
    int num_threads = 0;  ///< 0 = all cores (overrides the stages'); never changes results
    /// Throws InvalidArgument naming the first out-of-range field ("node.field: ...").
    void Validate() const;
};

/// What happened to one frame.
struct MapFrameResult {
    Eigen::Isometry3d T_world_sensor = Eigen::Isometry3d::Identity();        ///< the pose used
    Eigen::Isometry3d T_world_sensor_guess = Eigen::Isometry3d::Identity();  ///< its start
    /// True when the frame was aligned (or is the first frame, or register_frames is off) and
    /// joined the map; false when its alignment failed and it was left out.
    bool in_map = false;
    bool global_fallback_used = false;         ///< the global retry gave the pose
    RegistrationResult registration;           ///< the alignment (default for the first frame)
    std::size_t map_points = 0;                ///< map cloud size after the frame
    IncrementalTriangulation::AddResult mesh;  ///< mesh update (zeros without a mesh)
    std::size_t resampled_overlap = 0;         ///< overlap points replaced by MLS re-sampling
};

/// A map grown frame by frame. Not thread-safe; the work inside AddFrame is parallel.
class IncrementalMap {
  public:
    /// Throws InvalidArgument for bad parameters.
    explicit IncrementalMap(const MapParams& params);
    ~IncrementalMap();
    IncrementalMap(IncrementalMap&&) noexcept;
    IncrementalMap& operator=(IncrementalMap&&) noexcept;

    /// Adds a frame (in its own coordinates; its sensor_origin is the sensor there) given the
    /// odometry pose of those coordinates in the world, if any. The first frame fixes the world:
    /// its pose is its odometry (identity without). An empty or NaN-only frame is reported
    /// (in_map false) and skipped. Throws DataError for an inconsistent cloud.
    MapFrameResult AddFrame(const PointCloud& frame,
                            const std::optional<Eigen::Isometry3d>& T_world_sensor_odometry);

    const std::vector<MapFrameResult>& frames() const;
    /// The map cloud: every frame in the map, voxel-downsampled, with normals, world frame.
    const PointCloud& cloud() const;
    /// The occupancy map, or null when it is switched off.
    const OccupancyMap* occupancy() const;
    /// The mesh (empty when it is switched off).
    const TriangleMesh& mesh() const;

  private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

/// Poses of a sequence of frames, aligned as an IncrementalMap would (occupancy and mesh
/// switched off): for `perceive --manifest` with missing or noisy poses. `odometry` has one
/// entry per frame (nothing where unknown). Throws InvalidArgument for mismatched sizes.
std::vector<MapFrameResult> AlignFrameSequence(
    const std::vector<const PointCloud*>& frames,
    const std::vector<std::optional<Eigen::Isometry3d>>& odometry, MapParams params);

}  // namespace multicue

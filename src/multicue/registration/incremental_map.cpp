#include "multicue/registration/incremental_map.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/core/logging.hpp"
#include "multicue/filters/voxel_grid.hpp"
#include "multicue/search/kdtree.hpp"
#include "multicue/surface/mls.hpp"

namespace multicue {
namespace {

// The cloud's points and normals moved by T, its sensor origin too; other fields kept.
PointCloud TransformCloud(const PointCloud& cloud, const Eigen::Isometry3d& T) {
    PointCloud out = cloud;
    const Eigen::Isometry3f Tf = T.cast<float>();
    for (auto& p : out.points) p = Tf * p;
    for (auto& n : out.normals) n = Tf.linear() * n;
    out.sensor_origin = Tf * cloud.sensor_origin;
    out.sensor_orientation = Eigen::Quaternionf(Tf.linear()) * cloud.sensor_orientation;
    return out;
}

// The map points within `margin` of the frame's bounding box moved by T.
PointCloud CropAround(const PointCloud& map, const PointCloud& frame, const Eigen::Isometry3d& T,
                      float margin) {
    Eigen::Vector3f lo, hi;
    const PointCloud moved = TransformCloud(frame, T);
    if (!ComputeBounds(moved, lo, hi)) return {};
    lo.array() -= margin;
    hi.array() += margin;
    Indices keep;
    for (std::size_t i = 0; i < map.size(); ++i) {
        const auto& p = map.points[i];
        if ((p.array() >= lo.array()).all() && (p.array() <= hi.array()).all()) {
            keep.push_back(static_cast<Index>(i));
        }
    }
    PointCloud out = SelectByIndex(map, keep);
    out.sensor_origin = moved.sensor_origin;
    return out;
}

}  // namespace

void MapMeshParams::Validate() const {
    if (!(vertex_spacing > 0.0f) || !std::isfinite(vertex_spacing)) {
        throw InvalidArgument(
            fmt::format("mesh vertex_spacing must be > 0, got {}", vertex_spacing));
    }
    for (const auto& [name, v] :
         {std::pair{"overlap_radius", overlap_radius}, std::pair{"overlap_step", overlap_step},
          std::pair{"curvature_slope", curvature_slope}}) {
        if (!(v >= 0.0f) || !std::isfinite(v)) {
            throw InvalidArgument(fmt::format("mesh {} must be >= 0, got {}", name, v));
        }
    }
    GreedyTriangulationParams t = triangulation;
    if (t.search_radius == 0.0f) t.search_radius = 3.0f * vertex_spacing;
    ValidateNode("triangulation", [&] { t.Validate(); });
}

void MapParams::Validate() const {
    ValidateNode("registration", [&] { registration.Validate(); });
    if (!(map_voxel > 0.0f) || !std::isfinite(map_voxel)) {
        throw InvalidArgument(fmt::format("map_voxel must be > 0, got {}", map_voxel));
    }
    if (occupancy.enabled) ValidateNode("occupancy", [&] { occupancy.Validate(); });
    if (mesh.enabled) ValidateNode("mesh", [&] { mesh.Validate(); });
    if (num_threads < 0) {
        throw InvalidArgument(fmt::format("num_threads must be >= 0, got {}", num_threads));
    }
}

struct IncrementalMap::Impl {
    MapParams params;
    RegistrationParams registration;
    PointCloud map;
    std::optional<OccupancyMap> occupancy;
    std::optional<IncrementalTriangulation> triangulation;
    TriangleMesh no_mesh;
    std::vector<MapFrameResult> frames;
    // The last frame that joined the map: its pose, odometry and preprocessed points.
    bool has_last = false;
    Eigen::Isometry3d last_pose = Eigen::Isometry3d::Identity();
    std::optional<Eigen::Isometry3d> last_odometry;
    PointCloud last_prepared;
    PointCloud last_frame;  // raw, for the free-space check

    // The free-space check of an alignment of `frame` against the last frame of the map.
    void CheckVisibility(const PointCloud& frame, const PointCloud& prepared,
                         RegistrationResult& r) const {
        if (!registration.free_space.enabled || !r.converged) return;
        RegistrationResult relative = r;
        relative.T_target_source = last_pose.inverse() * r.T_target_source;
        CheckAgainstFreeSpace(prepared, last_prepared, &frame, &last_frame, registration.free_space,
                              relative);
        r.free_space_violation = relative.free_space_violation;
        r.converged = relative.converged;
        r.status = relative.status;
        r.reason = relative.reason;
    }

    RegistrationResult Align(const PointCloud& prepared, const KdTree& prepared_tree,
                             const Eigen::Isometry3d& guess) const {
        const float margin = 2.0f * std::max(registration.icp.initial_max_distance,
                                             registration.icp.correspondences.max_distance);
        const PointCloud local = CropAround(map, prepared, guess, margin);
        if (local.empty()) {
            RegistrationResult r;
            r.T_target_source = guess;
            r.status = RegistrationStatus::kLowOverlap;
            r.reason = "no map point near the frame's guessed pose";
            return r;
        }
        const KdTree local_tree(local);
        RegistrationParams p = registration;
        // From the guess only: the map has its own fallback (global against the last frame).
        if (p.method == RegistrationMethod::kGlobal || p.method == RegistrationMethod::kAuto) {
            p.method = RegistrationMethod::kPlane;
        }
        return RegisterPrepared(prepared, &prepared_tree, local, local_tree, p, guess);
    }

    void Integrate(const PointCloud& frame, const PointCloud& prepared,
                   const Eigen::Isometry3d& pose, MapFrameResult& out) {
        const int threads = params.num_threads;
        PointCloud world = TransformCloud(prepared, pose);
        map.points.insert(map.points.end(), world.points.begin(), world.points.end());
        map.normals.insert(map.normals.end(), world.normals.begin(), world.normals.end());
        map.curvature.insert(map.curvature.end(), world.curvature.begin(), world.curvature.end());
        map.SetUnorganized();
        map = VoxelGrid(map, {.leaf_size = params.map_voxel, .num_threads = threads});
        out.map_points = map.size();
        const PointCloud raw_world = TransformCloud(frame, pose);
        if (occupancy) {
            const PointCloud thin = VoxelGrid(
                raw_world,
                {.leaf_size = static_cast<float>(occupancy->resolution()), .num_threads = threads});
            occupancy->InsertScan(thin, raw_world.sensor_origin);
        }
        if (triangulation) AddToMesh(raw_world, out);
    }

    // Section 4.1.1: the frame's points near the mesh are re-sampled on a coarser, curvature-
    // adaptive grid (section 2.3.1); then the frame is triangulated into the mesh.
    void AddToMesh(const PointCloud& raw_world, MapFrameResult& out) {
        const MapMeshParams& mp = params.mesh;
        PreprocessParams pre;
        pre.voxel_size = mp.vertex_spacing;
        pre.num_threads = params.num_threads;
        PointCloud points = PreprocessForRegistration(raw_world, pre);
        if (points.empty()) return;
        const TriangleMesh& mesh = triangulation->mesh();
        if (!mesh.vertices.empty()) {
            const float radius =
                mp.overlap_radius > 0.0f ? mp.overlap_radius : 3.0f * mp.vertex_spacing;
            const float step = mp.overlap_step > 0.0f ? mp.overlap_step : 2.0f * mp.vertex_spacing;
            const PointCloud vertices(mesh.vertices);
            const KdTree vertex_tree(vertices);
            Indices overlap, fresh;
            Index j = 0;
            float d2 = 0.0f;
            for (std::size_t i = 0; i < points.size(); ++i) {
                const bool near =
                    vertex_tree.SearchNearest(points.points[i], j, d2) && d2 <= radius * radius;
                (near ? overlap : fresh).push_back(static_cast<Index>(i));
            }
            if (overlap.size() >= 10) {
                const PointCloud near_points = SelectByIndex(points, overlap);
                const KdTree near_tree(near_points);
                MlsParams mls;
                mls.radius = 2.0f * step;
                mls.resample_step = step;
                mls.curvature_slope = mp.curvature_slope;
                mls.plane_fit = MlsPlaneFit::kWeightedLeastSquares;
                mls.viewpoint = raw_world.sensor_origin;
                mls.num_threads = params.num_threads;
                MlsResult resampled = MovingLeastSquares(near_points, near_tree, mls);
                // Fresh points as they are, the overlap re-sampled: points, normals and (when
                // both have them) colours.
                const PointCloud kept = SelectByIndex(points, fresh);
                const PointCloud& re = resampled.cloud;
                PointCloud merged;
                merged.points = kept.points;
                merged.points.insert(merged.points.end(), re.points.begin(), re.points.end());
                merged.normals = kept.normals;
                merged.normals.insert(merged.normals.end(), re.normals.begin(), re.normals.end());
                if (kept.HasColors() && re.HasColors()) {
                    merged.colors = kept.colors;
                    merged.colors.insert(merged.colors.end(), re.colors.begin(), re.colors.end());
                }
                merged.SetUnorganized();
                merged.sensor_origin = raw_world.sensor_origin;
                out.resampled_overlap = overlap.size();
                points = std::move(merged);
            }
        }
        out.mesh = triangulation->Add(points);
    }
};

IncrementalMap::IncrementalMap(const MapParams& params) : impl_(std::make_unique<Impl>()) {
    params.Validate();
    impl_->params = params;
    impl_->registration = params.registration;
    impl_->registration.num_threads = params.num_threads;
    if (params.occupancy.enabled) impl_->occupancy.emplace(params.occupancy);
    if (params.mesh.enabled) {
        GreedyTriangulationParams t = params.mesh.triangulation;
        if (t.search_radius == 0.0f) t.search_radius = 3.0f * params.mesh.vertex_spacing;
        t.num_threads = params.num_threads;
        impl_->triangulation.emplace(t);
    }
}
IncrementalMap::~IncrementalMap() = default;
IncrementalMap::IncrementalMap(IncrementalMap&&) noexcept = default;
IncrementalMap& IncrementalMap::operator=(IncrementalMap&&) noexcept = default;

MapFrameResult IncrementalMap::AddFrame(
    const PointCloud& frame, const std::optional<Eigen::Isometry3d>& T_world_sensor_odometry) {
    Impl& m = *impl_;
    frame.Validate();
    if (T_world_sensor_odometry && !T_world_sensor_odometry->matrix().allFinite()) {
        throw InvalidArgument(
            fmt::format("frame {}: odometry pose is not finite", m.frames.size()));
    }
    MapFrameResult out;
    PreprocessParams pre = m.registration.preprocess;
    pre.num_threads = m.params.num_threads;
    PointCloud prepared = PreprocessForRegistration(frame, pre);
    // The guess: the last aligned pose moved by the odometry since then.
    Eigen::Isometry3d guess = T_world_sensor_odometry.value_or(Eigen::Isometry3d::Identity());
    if (m.has_last) {
        guess = m.last_pose;
        if (m.last_odometry && T_world_sensor_odometry) {
            guess = m.last_pose * (m.last_odometry->inverse() * *T_world_sensor_odometry);
        }
    }
    out.T_world_sensor_guess = guess;
    out.T_world_sensor = guess;
    out.registration.T_target_source = guess;
    if (prepared.empty()) {
        out.registration.status = RegistrationStatus::kEmptyInput;
        out.registration.reason = "the frame has no finite point";
        m.frames.push_back(out);
        return out;
    }
    if (!m.has_last || !m.params.register_frames) {
        if (!m.params.register_frames && T_world_sensor_odometry) guess = *T_world_sensor_odometry;
        out.T_world_sensor = guess;
        out.in_map = true;
        out.registration.converged = true;
        out.registration.status = RegistrationStatus::kConverged;
        out.registration.reason =
            m.has_last ? "pose taken as given" : "first frame: fixes the map's frame";
    } else {
        const KdTree prepared_tree(prepared);
        out.registration = m.Align(prepared, prepared_tree, guess);
        m.CheckVisibility(frame, prepared, out.registration);
        if (!out.registration.converged && m.params.global_fallback) {
            RegistrationParams global = m.registration;
            global.method = RegistrationMethod::kGlobal;
            const KdTree last_tree(m.last_prepared);
            const RegistrationResult g =
                RegisterPrepared(prepared, &prepared_tree, m.last_prepared, last_tree, global,
                                 std::nullopt, &frame, &m.last_frame);
            if (g.converged) {
                RegistrationResult r =
                    m.Align(prepared, prepared_tree, m.last_pose * g.T_target_source);
                m.CheckVisibility(frame, prepared, r);
                if (r.converged) {
                    r.reason = fmt::format("global fallback ({}), then {}", g.reason.substr(0, 200),
                                           r.reason);
                    out.registration = std::move(r);
                    out.global_fallback_used = true;
                }
            }
        }
        out.in_map = out.registration.converged;
        out.T_world_sensor = out.in_map ? out.registration.T_target_source : guess;
        if (!out.in_map) {
            LogWarning("map: frame {} not aligned ({}); left out of the map", m.frames.size(),
                       out.registration.reason);
        }
    }
    if (out.in_map) {
        m.Integrate(frame, prepared, out.T_world_sensor, out);
        m.has_last = true;
        m.last_pose = out.T_world_sensor;
        m.last_odometry = T_world_sensor_odometry;
        m.last_prepared = std::move(prepared);
        m.last_frame = frame;
    } else {
        out.map_points = m.map.size();
    }
    m.frames.push_back(out);
    return out;
}

const std::vector<MapFrameResult>& IncrementalMap::frames() const { return impl_->frames; }
const PointCloud& IncrementalMap::cloud() const { return impl_->map; }
const OccupancyMap* IncrementalMap::occupancy() const {
    return impl_->occupancy ? &*impl_->occupancy : nullptr;
}
const TriangleMesh& IncrementalMap::mesh() const {
    return impl_->triangulation ? impl_->triangulation->mesh() : impl_->no_mesh;
}

std::vector<MapFrameResult> AlignFrameSequence(
    const std::vector<const PointCloud*>& frames,
    const std::vector<std::optional<Eigen::Isometry3d>>& odometry, MapParams params) {
    if (frames.size() != odometry.size()) {
        throw InvalidArgument(
            fmt::format("{} frames but {} odometry poses", frames.size(), odometry.size()));
    }
    params.occupancy.enabled = false;
    params.mesh.enabled = false;
    IncrementalMap map(params);
    for (std::size_t k = 0; k < frames.size(); ++k) {
        if (frames[k] == nullptr) throw InvalidArgument(fmt::format("frame {} is null", k));
        map.AddFrame(*frames[k], odometry[k]);
    }
    return map.frames();
}

}  // namespace multicue

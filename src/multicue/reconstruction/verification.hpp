#pragma once
/// \file Verification of a model against what the sensor saw (thesis sections 4.2.4.3 and 5.4.1,
/// Figure 5.18). A model's surface is sampled and every sample is labelled by an occupancy grid
/// built from the scan by casting the ray of each measured point from the sensor:
/// - verified: next to a measured point (an occupied voxel within `tolerance_voxels`);
/// - invalid: in space the sensor saw through (a free voxel, no occupied one near): the model
///   claims a surface where the sensor measured something farther away;
/// - occluded: never observed (behind what the sensor saw, or outside its view) — the hidden back
///   side of a completed model, for example.
/// A model with a large invalid share (max_invalid_ratio) is rejected.
///
/// Only rays through the model's bounding box (grown by `margin`) are traversed (3D DDA of
/// Amanatides and Woo, clipped to the box), so the cost is proportional to the scan's points and
/// the box's size, not the room's.

#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "multicue/core/point_cloud.hpp"
#include "multicue/core/triangle_mesh.hpp"

namespace multicue {

enum class SurfaceState : std::uint8_t { kVerified = 0, kOccluded = 1, kInvalid = 2 };

struct VerificationParams {
    float voxel_size = 0.01f;           ///< occupancy grid cell [m]; > 0
    float margin = 0.05f;               ///< the grid covers the model's bounds grown by this [m]
    float sample_spacing = 0.005f;      ///< distance between surface samples [m]; > 0
    int tolerance_voxels = 1;           ///< occupied cells this close verify a sample [cells]; >= 0
    float max_invalid_ratio = 0.1f;     ///< larger invalid shares reject the model, [0, 1]
    std::size_t max_cells = 16u << 20;  ///< refuse grids larger than this [cells]
    int num_threads = 1;  ///< rays cast in parallel (0 = all cores); never changes the result
    /// Throws InvalidArgument naming the first out-of-range field.
    void Validate() const;
    /// Its parameters once each: configuration key (the field's name), field, meaning. A
    /// visitor reads or records them (io::ConfigSection::operator(); ReadPerceiveParams).
    template <typename V>
    void VisitParams(V& v) {
        v("voxel_size", voxel_size, "occupancy cell [m]");
        v("margin", margin, "grid margin around the model [m]");
        v("sample_spacing", sample_spacing, "surface sample spacing [m]");
        v("tolerance_voxels", tolerance_voxels,
          "occupied cells this close verify a sample [cells]");
        v("max_invalid_ratio", max_invalid_ratio,
          "models with a larger share of surface in free space are rejected");
    }
};

struct VerificationResult {
    std::vector<Eigen::Vector3f> samples;  ///< points on the model's surface
    std::vector<SurfaceState> states;      ///< one per sample
    float verified_ratio = 0.0f;
    float occluded_ratio = 0.0f;
    float invalid_ratio = 0.0f;
    bool accepted = true;  ///< invalid_ratio <= max_invalid_ratio
};

/// Verifies `model` against `scan` (in the same frame) seen from `sensor_origin`. Non-finite scan
/// points are skipped. An empty model gives an empty, accepted result. Throws InvalidArgument for
/// bad parameters, a non-finite origin, or a grid above max_cells.
VerificationResult VerifyModel(const TriangleMesh& model, const PointCloud& scan,
                               const Eigen::Vector3f& sensor_origin,
                               const VerificationParams& params = {});

/// Points on the mesh's triangles, at most `spacing` apart: rows parallel to each triangle's
/// longest edge, `spacing` apart, each sampled at most `spacing` apart (about area / spacing^2
/// points per triangle, thin triangles included), deterministic.
std::vector<Eigen::Vector3f> SampleMeshSurface(const TriangleMesh& mesh, float spacing);

}  // namespace multicue

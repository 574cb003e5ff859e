#pragma once
/// \file Fitting and verifying CAD models of detected furniture (thesis section 4.2.4.3).
///
/// Upright RANSAC over (x, y, yaw): a random scan point of the hypothesis's parts is paired with
/// model points at a similar height (a share of them, checked_share), each pair giving a pose:
/// the yaw that turns the model point's normal onto the scan point's (a random yaw where the
/// normals are nearly parallel to up: table tops, seats) and the translation that brings the two
/// points together. A pose scores the scan points it covers (a model point within
/// inlier_distance), counted on a share of the scan points and abandoned as soon as it cannot
/// beat the best pose of any model so far. The iteration count adapts by Eq. (4.6) with
/// p_good = covered / all scan points, over all models of the class together. The best pose (with
/// FitFurnitureModels, each of the best few models' best poses) is refined by ICP (registration
/// module, point-to-plane) and projected back to upright, then optionally stretched to the
/// piece's size (max_scale), and turned to face the room when it faces a wall it stands against
/// (back_to_wall).
///
/// Verification rejects a fit that covers less than min_coverage of the scan points, and one
/// whose model lies in space a scan saw as free: a model point counts as in free space when its
/// voxel and the voxel one step further along its ray are free in a view's occupancy map (one
/// OctoMap per scan, search/occupancy_map.hpp; the second voxel keeps model points just in front
/// of the measured surface from counting).

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "multicue/core/point_cloud.hpp"
#include "multicue/recognition/furniture_model.hpp"
#include "multicue/registration/icp.hpp"
#include "multicue/search/occupancy_map.hpp"

namespace multicue {

/// A wall seen in a view: an upright plane reaching above every piece of furniture, long
/// enough. Furniture stands on the room's side of it (the 2D floor map that section 4.2.5.2 asks
/// for against detections inside walls).
struct FurnitureWall {
    Eigen::Vector2f point = Eigen::Vector2f::Zero();    ///< on the wall [m]
    Eigen::Vector2f normal = Eigen::Vector2f::UnitX();  ///< towards the room (the sensor)
    float lo = 0.0f, hi = 0.0f;  ///< extent along the wall (normal turned by +90 degrees) [m]
    /// Signed distance of `x` from the wall, positive on the room's side, when `x` lies within
    /// the wall's extent (+-0.3 m); NaN beside it.
    float Distance(const Eigen::Vector2f& x) const;
    /// True when `x` lies behind the wall by more than `margin`, within its extent (+-0.3 m).
    bool Behind(const Eigen::Vector2f& x, float margin) const { return Distance(x) < -margin; }
};

/// True when `x` lies behind any of `walls` by more than `margin`.
bool BehindWalls(const std::vector<const FurnitureWall*>& walls, const Eigen::Vector2f& x,
                 float margin);

struct FurnitureFitParams {
    float inlier_distance = 0.03f;      ///< a scan point is covered within this of the model [m]
    double success_probability = 0.99;  ///< p_success of Eq. (4.6), in (0, 1)
    float height_tolerance = 0.02f;     ///< pairs of points at similar height: |dz| below [m]
    /// Share of the candidate pairs and of the scan points checked per pose (thesis: about
    /// half), in (0, 1]
    float checked_share = 0.5f;
    std::size_t max_scan_points = 1500;  ///< the parts' points thinned evenly to at most this
    std::size_t max_candidates = 48;     ///< model points paired with one scan point at most
    int max_iterations = 200;            ///< per model at most; Eq. (4.6) usually stops earlier
    /// Normals whose horizontal component is below this are parallel to up: random yaw [-]
    float min_horizontal_normal = 0.5f;
    /// The model's centre stays this far from the hypothesis at most, in class widths [-], > 0
    float max_offset = 1.0f;
    bool refine = true;  ///< ICP refinement after the search
    /// Back to the wall: a fit whose front (the model's +x) faces a wall it stands within
    /// wall_gap of (beyond half its depth) is turned by a half turn about its centre when the
    /// turned pose scores (coverage minus the free and wall shares) at most flip_tolerance below
    /// it. Cabinets and sideboards differ front to back only in handles and doors, so the scan
    /// alone often cannot tell; furniture against a wall faces the room. Only the reported pose
    /// turns: coverage and the free and wall shares stay those of the pose the search found.
    bool back_to_wall = true;
    float wall_gap = 0.3f;        ///< [m], >= 0
    float flip_tolerance = 0.6f;  ///< [-], >= 0 (chosen on validation rooms)
    /// Size adaptation: after the search and refinement the fitted model is stretched along its
    /// own axes, each by a factor within [1 - max_scale, 1 + max_scale] (scale_steps factors on
    /// either side of 1), axis by axis in two rounds. A horizontal stretch keeps the model's near
    /// face, far face or the plane through the scan points' centroid in place, the height keeps
    /// the floor. A stretch is kept when it scores (coverage minus the free and wall shares) more
    /// than min_scale_gain above the best so far. A library model of another size then fits a
    /// piece it has the shape of. 0: the models keep their size (the default: on validation rooms
    /// stretching made wrong fits look as good as right ones, eval/README.md) [-], in [0, 0.5)
    float max_scale = 0.0f;
    int scale_steps = 2;           ///< >= 1
    float min_scale_gain = 0.02f;  ///< [-], >= 0
    IcpParams icp{.correspondences = {.max_distance = 0.06f},
                  .max_iterations = 30,
                  .min_fitness = 0.1,
                  .min_condition = 0.0,
                  .num_threads = 1};
    /// A point of a fitted model counts as behind a wall beyond this (CAD models are deeper or
    /// shallower than the piece they explain) [m]
    float wall_margin = 0.15f;
    float max_behind_share = 0.1f;  ///< reject with more of the model behind a wall
    float min_coverage = 0.5f;      ///< reject below this share of covered scan points
    /// Reject above this share of model points in free space (0.4 chosen on validation rooms: a
    /// CAD model of another piece of the class sticks out of the scanned one)
    float max_free_share = 0.4f;
    double occupancy_resolution = 0.05;   ///< voxel of the per-scan occupancy maps [m]
    std::size_t max_model_checks = 3000;  ///< model points tested against free space at most
    std::size_t max_search_checks = 300;  ///< the same while searching poses
    std::uint64_t seed = 1;
    /// Throws InvalidArgument naming the first out-of-range field.
    void Validate() const;
};

/// Per-model data built once for many fits: the models' points sorted by height, a grid of the
/// voxels within inlier_distance of each model, k-d trees for ICP.
class FurnitureFitContext {
  public:
    /// Throws InvalidArgument for bad parameters or a model without CAD models.
    FurnitureFitContext(const FurnitureModel& model, const FurnitureFitParams& params);
    ~FurnitureFitContext();
    FurnitureFitContext(const FurnitureFitContext&) = delete;
    FurnitureFitContext& operator=(const FurnitureFitContext&) = delete;

    const FurnitureModel& model() const { return model_; }
    const FurnitureFitParams& params() const { return params_; }
    struct Cad;
    const Cad& cad(std::size_t i) const { return *cads_[i]; }

  private:
    const FurnitureModel& model_;
    FurnitureFitParams params_;
    std::vector<std::unique_ptr<Cad>> cads_;
};

/// Occupancy maps of the views, for the free-space test.
class FurnitureFreeSpace {
  public:
    explicit FurnitureFreeSpace(double resolution = 0.05);
    /// Adds one view's map: its points (world frame; the floor included: rays to the floor free
    /// the space above it) seen from `origin`.
    void AddView(const PointCloud& world_points, const Eigen::Vector3f& origin);
    std::size_t views() const { return maps_.size(); }
    /// Share of `points` (world frame) in free space of any view; 0 without views.
    float FreeShare(const std::vector<Eigen::Vector3f>& points) const;
    /// Whether `p` (world frame) lies in free space of any view, as FreeShare counts it.
    bool IsFree(const Eigen::Vector3f& p) const;

  private:
    double resolution_;
    std::vector<OccupancyMap> maps_;
    std::vector<Eigen::Vector3f> origins_;
};

/// What the scans say about the space around a fit: the views' free space and their walls.
struct FurnitureSpace {
    std::vector<const FurnitureFreeSpace*> free;
    std::vector<const FurnitureWall*> walls;
};

struct FurnitureFit {
    int cad = -1;  ///< index into FurnitureModel::cads(); -1 when nothing was found
    /// Upright; the model is stretched by `scale` before it (ModelToWorld)
    Eigen::Isometry3f T_world_model = Eigen::Isometry3f::Identity();
    Eigen::Vector3f scale = Eigen::Vector3f::Ones();  ///< along the model's axes (max_scale)
    float yaw = 0.0f;                                 ///< [rad]
    std::size_t scan_points = 0;                      ///< the parts' points used
    std::size_t covered = 0;                          ///< of those, covered by the fitted model
    float coverage = 0.0f;                            ///< covered / scan_points
    int iterations = 0;                               ///< RANSAC iterations over all models
    int models_tried = 0;
    bool refined = false;       ///< ICP converged and was kept
    bool turned = false;        ///< turned by a half turn to face away from a wall (back_to_wall)
    float free_share = 0.0f;    ///< share of model points in observed free space
    float behind_share = 0.0f;  ///< share of model points behind a wall
    bool accepted = false;      ///< passed both checks
    std::string rejection;      ///< "", "coverage", "free_space", "behind_wall" or "no_fit"
    double ms = 0.0;            ///< wall time [ms]
    /// The fitted model's points to the world: T_world_model after the stretch by `scale`.
    Eigen::Affine3f ModelToWorld() const { return T_world_model * Eigen::Scaling(scale); }
    /// The same before the half turn of back_to_wall: the pose the tests and the verifier judge.
    Eigen::Affine3f FittedModelToWorld() const {
        const Eigen::Affine3f A = ModelToWorld();
        return turned ? A * Eigen::Scaling(Eigen::Vector3f(-1.0f, -1.0f, 1.0f)) : A;
    }
};

/// Fits the CAD models of class `cls` to `points` (world frame, floor at z = 0, with normals
/// facing the sensor) near `centre`. A pose scores its coverage of the points minus the shares
/// of the model in free space and behind walls (`space`; empty: coverage alone), so that the
/// pose and the model chosen explain the scan without claiming space the scans saw empty or
/// space outside the room; the penalties are computed for the poses that come within 5 % of the
/// best coverage of their model. Every model gets its best pose, the iteration count of Eq. (4.6)
/// computed from the best coverage of all models so far. The best is refined and verified.
/// Fewer than 10 points give no fit. Throws InvalidArgument for an unknown class or points
/// without normals.
FurnitureFit FitFurniture(const PointCloud& points, int cls, const Eigen::Vector2f& centre,
                          const FurnitureFitContext& context, const FurnitureSpace& space = {});

/// The same, finishing (refining, testing) the best pose of each of the `count` models that
/// scored best in the search, best first: a shorter model placed on the piece may explain it
/// better to the verifier than a longer one that also covers a neighbour. At least one fit (with
/// `cad` -1 when nothing was found), at most `count` (>= 1, else InvalidArgument), of distinct
/// models. The first is FitFurniture's.
std::vector<FurnitureFit> FitFurnitureModels(const PointCloud& points, int cls,
                                             const Eigen::Vector2f& centre,
                                             const FurnitureFitContext& context,
                                             const FurnitureSpace& space, int count);

}  // namespace multicue

#pragma once
/// \file Training of the kitchen map's classifiers on simulated kitchens: kitchens built from
/// one half of the kitchen models (the tune half by default, never the held-out test half),
/// scanned as `multicue simulate kitchens` scans them and mapped by MapKitchen.
/// - The fixture classifier (thesis section 4.1.2): every fixture candidate in front of a
///   furniture face labelled by the simulator's ground truth, "handle" or "knob" when it lies
///   within match_distance of a true handle's or knob's points, else "none"; rows of
///   FixtureFeatureNames columns (`multicue train fixtures`, `map kitchen --fixtures`).
/// - The container classifier (section 4.1.3): every furniture piece labelled with its model's
///   container type; rows of ContainerFeatureNames columns (`multicue train containers`, `map
///   kitchen --containers`).
/// The rows train any multicue classifier.

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "multicue/core/point_cloud.hpp"
#include "multicue/core/progress.hpp"
#include "multicue/mapping/kitchen_map.hpp"
#include "multicue/ml/classifier.hpp"
#include "multicue/ml/dataset.hpp"
#include "multicue/sim/kitchen_library.hpp"
#include "multicue/sim/kitchen_scene.hpp"
#include "multicue/sim/sensors.hpp"

namespace multicue::training {

/// The simulated Kinect of kitchen scans (30 % shading) as `simulate kitchens` uses it.
sim::KinectParams KitchenKinectParams();
/// The simulated tilting laser of kitchen scans (tilt -40 .. 60 deg).
sim::LaserParams KitchenLaserParams();

/// One scan of a simulated kitchen in the world frame with its ground-truth fields
/// (sim::AddKitchenTruth) and the sensor pose.
struct KitchenFrame {
    PointCloud cloud;
    bool laser = false;
    Eigen::Isometry3f T_world_sensor = Eigen::Isometry3f::Identity();
};

/// The scans of a kitchen as `simulate kitchens` makes them with seed `seed`: `laser_views`
/// laser sweeps, then `views` Kinect frames (either may be 0).
std::vector<KitchenFrame> ScanKitchen(const sim::KitchenScene& kitchen, int views, int laser_views,
                                      std::uint64_t seed);

/// One of two folds of `entries` (one half of the library, for validation on models the
/// classifiers never saw while still never touching the other half): within each kind the
/// models, ordered by the hash of their annotation id, alternate between fold 0 and fold 1; a
/// model listed under two kinds is in fold 0. Throws InvalidArgument for a fold other than 0, 1.
std::vector<sim::KitchenModelEntry> SelectKitchenFold(
    const std::vector<sim::KitchenModelEntry>& entries, int fold);

struct FixtureTrainingOptions {
    int kitchens = 24;  ///< kitchens simulated
    int views = 3;      ///< scans per kitchen of the chosen sensor
    mapping::KitchenSensor sensor = mapping::KitchenSensor::kKinect;
    sim::MeshSplit split = sim::MeshSplit::kTune;  ///< the models the kitchens are built from
    int fold = -1;           ///< -1: the whole half; 0 or 1: that fold of it (SelectKitchenFold)
    std::uint64_t seed = 7;  ///< kitchen i uses sim::SubSeed(seed, i)
    /// A candidate whose centre lies within this of a true fixture's points is that fixture [m]
    float match_distance = 0.03f;
    int num_threads = 0;  ///< 0 = all cores (per scan)
    /// Vary the training kitchens' handles (sim::VaryHandles): lengths, how far they stand out
    /// of their fronts and their thickness, so that the classifier meets handle designs beyond
    /// the few of the training models (docs/kitchens.md has the validation).
    bool vary_handles = true;
    sim::HandleVariation handle_variation{.min_reach_scale = 0.5f,
                                          .max_reach_scale = 1.5f,
                                          .min_thickness_scale = 0.5f,
                                          .max_thickness_scale = 2.0f};
    /// Procedural units (sim::ProceduralKitchenEntries, seeds from `seed`) of every cupboard
    /// kind added to the training kitchens' models, this many per kind; 0: library models only.
    /// They bring unit designs (drawer stacks, framed fronts, handle placements) the library's
    /// half lacks.
    int procedural = 0;
    /// The chance that a unit of a kind with procedural and library models is procedural
    float procedural_share = 0.5f;
    /// The candidates' parameters; unset: those of mapping::KitchenParamsFor(sensor)
    std::optional<mapping::FixtureParams> fixture_params;
    /// Throws InvalidArgument naming the first out-of-range field.
    void Validate() const;
};

/// Class per candidate (index into mapping::FixtureClassNames: 0 none, 1 handle, 2 knob) from the
/// `semantic` ground-truth field of `scan` (the cloud the candidates were found in). Throws
/// DataError when the scan has no `semantic` field.
std::vector<int> LabelFixtureCandidates(const PointCloud& scan,
                                        const std::vector<mapping::FixtureCandidate>& candidates,
                                        float match_distance);

/// An empty dataset with the fixture columns (block "fixture") and classes none, handle, knob.
ml::Dataset EmptyFixtureDataset();

/// Appends one row per candidate of a mapped scan (its labels from LabelFixtureCandidates);
/// `source` names the scan in Dataset::sources.
void AppendFixtureRows(const PointCloud& scan,
                       const std::vector<mapping::FixtureCandidate>& candidates,
                       float match_distance, const std::string& source, ml::Dataset& data);

/// Rows of every fixture candidate of simulated kitchens of `library`'s `options.split` half.
/// Stops early (rows so far) when an interruption is requested. Throws InvalidArgument for bad
/// options, DataError when the half lacks the models a kitchen needs.
ml::Dataset CollectFixtureRows(const std::vector<sim::KitchenModelEntry>& library,
                               sim::KitchenModelCache& cache, const FixtureTrainingOptions& options,
                               Progress* progress = nullptr);

/// A classifier of spec `spec` (ml::CreateClassifier) trained on fixture rows. Throws
/// DataError when the rows hold fewer than two classes.
std::unique_ptr<ml::Classifier> TrainFixtureClassifier(const ml::Dataset& rows,
                                                       const std::string& spec,
                                                       std::uint32_t seed = 1);

/// Training of the container classifier of `map kitchen --containers` (thesis section 4.1.3):
/// simulated kitchens mapped scan by scan, every furniture piece labelled with the true type
/// (sim::ContainerTypeOfModel) of the model holding most of its matched fronts.
struct ContainerTrainingOptions {
    int kitchens = 48;        ///< kitchens simulated
    int views = 3;            ///< Kinect frames per kitchen
    int laser_views = 1;      ///< laser sweeps per kitchen
    std::uint64_t seed = 11;  ///< kitchen i uses sim::SubSeed(seed, i)
    /// The chance that a unit of a kind with procedural and library models is procedural
    float procedural_share = 0.5f;
    /// The maps' parameters per sensor; unset: mapping::KitchenParamsFor(sensor)
    std::optional<mapping::MapKitchenParams> kinect_params, laser_params;
    /// The fixture classifiers the maps use (`map kitchen --fixtures`); null: fixtures by rules
    const ml::Classifier* kinect_fixtures = nullptr;
    const ml::Classifier* laser_fixtures = nullptr;
    int num_threads = 0;  ///< 0 = all cores (per scan); overrides the params' own
    /// Throws InvalidArgument naming the first out-of-range field.
    void Validate() const;
};

/// An empty dataset with the container columns (block "container", mapping::
/// ContainerFeatureNames) and no classes yet (they are added as rows name them).
ml::Dataset EmptyContainerDataset();

/// Appends one row per furniture piece of `map` (a map of `scan`, a scan of `kitchen` with its
/// ground-truth fields) that holds fronts matched to a true model's (FurnitureInstances); the
/// label is that model's container type. `source` names the scan in Dataset::sources.
void AppendContainerRows(const sim::KitchenScene& kitchen, const PointCloud& scan,
                         const mapping::KitchenMap& map, const std::string& source,
                         ml::Dataset& data);

/// Rows of the furniture of `options.kitchens` kitchens built from `models` (already the chosen
/// half, fold and procedural units). A scan the map refuses is skipped. Stops early (rows so
/// far) when an interruption is requested. Throws InvalidArgument for bad options, DataError
/// when `models` lack what a kitchen needs.
ml::Dataset CollectContainerRows(const std::vector<sim::KitchenModelEntry>& models,
                                 sim::KitchenModelCache& cache,
                                 const ContainerTrainingOptions& options,
                                 Progress* progress = nullptr);

/// A classifier of spec `spec` trained on container rows. Throws DataError when the rows hold
/// fewer than two types (classes with rows).
std::unique_ptr<ml::Classifier> TrainContainerClassifier(const ml::Dataset& rows,
                                                         const std::string& spec,
                                                         std::uint32_t seed = 1);

/// Training of the joint classifier of `map kitchen --joints` (mapping::ClassifyJoints): the
/// same maps as the container training's (ContainerTrainingOptions; joints by the fixture rules),
/// every front with a fixture matched to a true front (IoU >= 0.5) labelled with its true joint
/// and hinge edge (mapping::JointClassOf).
ml::Dataset EmptyJointDataset();

/// Appends one row per front of `map` (a map of `scan`, a scan of `kitchen` with its ground-truth
/// fields) that has a fixture and a joint from it and is matched to a true front with a joint.
void AppendJointRows(const sim::KitchenScene& kitchen, const PointCloud& scan,
                     const mapping::KitchenMap& map, const std::string& source, ml::Dataset& data,
                     const mapping::ArticulationParams& params = {});

/// Rows of the fronts of `options.kitchens` kitchens built from `models`, as CollectContainerRows
/// makes its maps. Throws as CollectContainerRows.
ml::Dataset CollectJointRows(const std::vector<sim::KitchenModelEntry>& models,
                             sim::KitchenModelCache& cache, const ContainerTrainingOptions& options,
                             Progress* progress = nullptr);

/// A classifier of spec `spec` trained on joint rows. Throws DataError when the rows hold fewer
/// than two classes.
std::unique_ptr<ml::Classifier> TrainJointClassifier(const ml::Dataset& rows,
                                                     const std::string& spec,
                                                     std::uint32_t seed = 1);

}  // namespace multicue::training

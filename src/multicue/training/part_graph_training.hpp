#pragma once
/// \file Training of the part-graph categoriser (thesis sections 4.2.2 and 5.1) on simulated
/// data: procedural objects of every table-top category and optionally a mesh library, each
/// scanned from `views` turntable directions by the simulated Kinect and decomposed as perceive
/// decomposes objects (organized normals, normal-angle region growing), plus the objects perceive
/// finds in simulated table scenes; optionally a stacker over the experts. Also the default model
/// (procedural objects only), trained once and cached, and the models perceive's categorisers
/// need (LoadPerceiveModels).

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "multicue/core/point_cloud.hpp"
#include "multicue/core/progress.hpp"
#include "multicue/recognition/part_graph_model.hpp"
#include "multicue/recognition/part_vocabulary.hpp"
#include "multicue/sim/scene_gen.hpp"
#include "multicue/sim/sensors.hpp"
#include "multicue/system/perceive.hpp"

namespace multicue::training {

/// One labelled training object as the model saw it (for baselines trained on the same data).
struct TrainingObject {
    FeatureMatrix part_descriptors;  ///< raw part descriptors (ComputePartDescriptors)
    FeatureMatrix part_statistics;   ///< the 24 features of every part (with part_statistics)
    FeatureVector cluster;           ///< ComputeClusterDescriptor (always computed)
    Category category = Category::kNone;
    PartGraph graph;  ///< adjacency of its parts (to train further models on the same rows)
    std::uint64_t train_seed = 0;  ///< PartGraphTrainParams::seed it was added with
};

/// Table scenes of a model trained on a mesh library: more varied objects gain from more scenes.
inline constexpr int kLibraryTableScenes = 80;

struct PartGraphTrainingOptions {
    int objects_per_category = 8;              ///< procedural objects per category (0: none)
    std::vector<std::string> categories = {};  ///< procedural categories (empty: all six)
    int views = 8;                             ///< turntable views per object
    std::filesystem::path meshes;  ///< mesh library folder with labels.csv (empty: none)
    std::filesystem::path labels;  ///< another labels file for `meshes` (empty: its labels.csv)
    /// Library entries used: those whose index i satisfies i % mesh_modulo == mesh_remainder (a
    /// simple split of a library into training and test meshes).
    int mesh_modulo = 1;
    int mesh_remainder = 0;
    int max_meshes = 0;          ///< at most this many library meshes (0 = all selected)
    bool mesh_turntable = true;  ///< scan the selected library meshes on the turntable
    std::uint64_t seed = 1;
    int num_threads = 0;
    float camera_distance = 1.0f;  ///< turntable camera distance [m]
    sim::KinectParams kinect{};    ///< the simulated sensor of every training scan
    /// Cluttered table scenes (objects drawn from the selected library meshes, else procedural
    /// objects) scanned from `table_views` robot-head viewpoints each (sim::TableViewpoints) and
    /// segmented by perceive itself; every perceived object whose points are mostly (>= 60 %) of
    /// one category adds its parts as one labelled object. Closer to real frames than the
    /// turntable. 0: none. `multicue train` and part_graph_eval take kLibraryTableScenes when they
    /// train on a mesh library (more varied objects gain from more scenes; docs/training.md).
    int table_scenes = 40;
    int table_views = 4;
    sim::ViewpointParams table_viewpoints{};  ///< camera placement around the table scenes
    /// Further table scenes of the same objects (other seeds), perceived after the model is
    /// built, whose objects train the model's stacker (CategoryStacker: the rules, part-graph
    /// and whole-object experts as perceive computes them, and the rules' geometric evidence).
    /// 0: no stacker.
    int stacker_scenes = 0;
    int stacker_views = 6;
    CategoryStackerParams stacker{};
    PartGraphTrainParams train{};
    /// When set, receives every labelled object added to the model, in a fixed order (turntable
    /// scans, then table-scene objects).
    std::vector<TrainingObject>* objects_out = nullptr;
    ClusterDescriptorParams cluster_params{};
    bool part_statistics = false;  ///< fill TrainingObject::part_statistics (up = world z)
};

/// The 24 statistical features (features/part_stats.hpp) of every part, `up` given in the frame
/// of `scan` (which needs normals); one row per part.
FeatureMatrix ComputePartStatisticsRows(const PointCloud& scan, const std::vector<Indices>& parts,
                                        const Eigen::Vector3f& up);

/// Perceive's decomposition of one scanned object: organized normals on the object's pixels and
/// region-growing parts (PerceiveParams::parts) of `object` (indices into `scan`). Sets normals on
/// `scan`.
std::vector<Indices> DecomposeObject(PointCloud& scan, const Indices& object,
                                     const PerceiveParams& perceive = {});

/// Trains a model (the graph and descriptor settings of `model` are kept) and builds it.
/// Interruptible: stops between objects once InterruptRequested() and returns false (the model
/// then holds what was added so far); true when complete.
bool TrainPartGraphModel(PartGraphModel& model, const PartGraphTrainingOptions& options,
                         Progress* progress = nullptr);

/// The default model: procedural objects only, `multicue train` defaults.
PartGraphModel TrainDefaultPartGraphModel(Progress* progress = nullptr);

/// Revision of the default model's training settings (2: 40 table scenes); part of the cache
/// name, so that a cached model of older defaults is not read.
inline constexpr int kDefaultTrainingRevision = 2;

/// Where the default model is cached: $XDG_CACHE_HOME/multicue (else ~/.cache/multicue, else the
/// system temp folder) / part-graph-default-v<model format version>.<training revision>.mcpg.
std::filesystem::path DefaultPartGraphModelPath();

/// Loads the cached default model, training and caching it first when it is missing.
PartGraphModel LoadOrTrainDefaultPartGraphModel();

/// The models perceive needs for `params`: none for the rules categoriser; otherwise the model
/// file category.part_graph_model, or without one the default model (LoadOrTrainDefault-
/// PartGraphModel; the stacked categoriser needs a file of a model with a stacker). Throws
/// IoError / FormatError for an unreadable model file, InvalidArgument for "stacked" without one.
PerceiveModels LoadPerceiveModels(const PerceiveParams& params);

}  // namespace multicue::training

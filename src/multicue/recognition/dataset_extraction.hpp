#pragma once
/// \file The feature extraction tool of section 3.1.4: point clouds in, one dataset row per object
/// (or file) out, one named feature block per feature type (features/registry.hpp).
///
/// Inputs come from a simulator manifest (`multicue simulate`, every object of every frame by its
/// `label` field) or from a directory tree of PCD/PLY files whose folders are the label path
/// (root/cylinder/mug/scan_001.pcd -> "cylinder/mug"). Each cluster is downsampled, gets normals
/// and then every requested feature. The output dataset is saved atomically every few files, and a
/// resumed run skips every file already present in the output's sources, so an interrupted
/// extraction continues where it stopped and ends with the same rows as an uninterrupted one.

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "multicue/core/point_cloud.hpp"
#include "multicue/core/progress.hpp"
#include "multicue/features/registry.hpp"
#include "multicue/ml/dataset.hpp"

namespace multicue {

/// One object of a frame: its label value and where its rows go.
struct ExtractionObject {
    std::uint32_t label = 0;  ///< value of the cloud's label field
    std::string class_path;   ///< label path of the rows ("cylinder/mug")
    std::int64_t group = -1;  ///< object instance
};

/// One input file and how to label its rows.
struct ExtractionInput {
    std::filesystem::path file;
    std::string source;      ///< key recorded in the dataset (relative path); rows: source#label
    std::int64_t view = -1;  ///< view id of the rows
    /// Up direction in the cloud's frame for the part statistics; nullopt: the params' up.
    std::optional<Eigen::Vector3f> up = std::nullopt;
    /// Manifest mode: the objects to extract (other label values are ignored).
    std::vector<ExtractionObject> objects;
    /// Tree mode: the label path and group of the whole file.
    std::string class_path;
    std::int64_t group = -1;
    /// Tree mode: one row per label value (0 = no object, skipped) instead of one per file.
    bool per_cluster = false;
};

struct DatasetExtractionParams {
    std::vector<std::string> features;    ///< registry names, one block each, in this order
    ClusterFeatureParams feature_params;  ///< viewpoint = each cloud's sensor origin if unset
    /// Voxel grid applied to every cluster before normals and features [m]; 0 = none. The
    /// pair histograms cost O(points x neighbours^2), so full-resolution clusters are slow.
    float voxel_size = 0.005f;
    float normal_radius = 0.015f;  ///< normal estimation radius [m]
    std::size_t min_points = 30;   ///< clusters with fewer points (after downsampling) are skipped
    std::size_t save_every = 20;   ///< files between atomic saves of the partial output
    bool resume = false;           ///< keep the rows of an existing output and skip their files
};

struct DatasetExtractionSummary {
    std::size_t files = 0;           ///< inputs
    std::size_t files_resumed = 0;   ///< skipped because present in the output
    std::size_t files_done = 0;      ///< read in this run
    std::size_t rows_added = 0;      ///< rows appended in this run
    std::size_t rows = 0;            ///< rows in the output
    std::size_t small_clusters = 0;  ///< skipped: fewer than min_points
    std::size_t bad_features = 0;    ///< skipped: a feature was not finite
    bool interrupted = false;        ///< stopped by InterruptRequested(); the output is partial
};

/// Inputs of a `multicue simulate` manifest: every frame, every object (labels >= 20). Class path
/// "category/kind" (kind = the procedural kind or the mesh file name without extension), group =
/// a stable 63-bit hash of the mesh file name for library meshes (the same mesh is one instance in
/// every scene and every manifest) and of (scene seed, label) for procedural objects, view = the
/// frame's index in its scene, up = world z in the sensor frame. Throws IoError/FormatError for a
/// missing or malformed manifest.
std::vector<ExtractionInput> ManifestInputs(const std::filesystem::path& manifest);

/// Inputs of a directory tree: every .pcd and .ply file below `root` in sorted order, class path
/// from the folders (ml::LabelPathFromFile), group = hash of the class path (its folder is the
/// instance), view = index of the file in its folder. Throws IoError when `root` is not a folder
/// and DataError when it holds no point cloud or a file lies directly in `root` (no label).
std::vector<ExtractionInput> TreeInputs(const std::filesystem::path& root, bool per_cluster);

/// An empty dataset with one block per feature ("vfh" with columns vfh0..vfh307, ...).
/// Throws InvalidArgument for an unknown or repeated feature name or an empty list.
ml::Dataset EmptyFeatureDataset(const std::vector<std::string>& features);

/// Features of one cluster (points of one object, any frame): voxel grid, normals towards
/// `viewpoint`, then every feature concatenated in order. nullopt when fewer than min_points
/// remain.
std::optional<std::vector<float>> ExtractClusterFeatures(const PointCloud& cluster,
                                                         const Eigen::Vector3f& viewpoint,
                                                         const DatasetExtractionParams& params);

/// Runs the extraction into `out` (.mcd or .csv, written atomically every save_every files and at
/// the end, also when interrupted). With params.resume and an existing `out`, its rows are kept
/// and files already among its sources skipped; its blocks must equal the requested features
/// (InvalidArgument otherwise). Advances `progress` once per input. A file that cannot be read
/// stops the run with its error after saving the rows so far.
DatasetExtractionSummary ExtractDataset(const std::vector<ExtractionInput>& inputs,
                                        const std::filesystem::path& out,
                                        const DatasetExtractionParams& params, Progress& progress);

}  // namespace multicue

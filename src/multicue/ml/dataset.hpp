#pragma once
/// \file Dataset: a float feature matrix with hierarchical labels, object-instance groups, view ids
/// and named feature blocks (section 3.1.4). Geometry-free: any feature file can be one.
///
/// Rows are samples (one per scan, view or cluster), columns are feature values. Columns are named,
/// and contiguous runs of columns form *blocks*, one per feature type ("vfh", "grsd", "surf_bow"),
/// so a classifier can be trained on a subset of feature types (section 3.3). Labels are paths in
/// a class hierarchy ("cylinder/mug"), as read from a directory tree; `FlattenLabels` cuts them to
/// a depth. Storage is row-major in one std::vector so that rows can be appended cheaply by a tool
/// extracting features file by file; `sources` records where each row came from, so such a tool
/// can resume by skipping sources already present.

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>
#include <unordered_set>
#include <vector>

#include <Eigen/Core>

namespace multicue::ml {

/// Row-major float matrix: one row per sample.
using FeatureMatrix = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
/// A read-only view of any row-major float matrix (a FeatureMatrix, a Dataset's values).
using FeaturesRef = Eigen::Ref<const FeatureMatrix>;

/// A contiguous run of columns holding one feature type.
struct FeatureBlock {
    std::string name;       ///< feature type, e.g. "vfh"
    std::size_t begin = 0;  ///< first column
    std::size_t count = 0;  ///< number of columns
};

/// Label value of a row without a class.
inline constexpr int kNoLabel = -1;

struct Dataset {
    std::size_t num_cols = 0;
    std::vector<float> values;  ///< rows x num_cols, row-major

    std::vector<std::string> feature_names;  ///< one per column
    std::vector<FeatureBlock> blocks;        ///< cover all columns in order, no gaps

    std::vector<std::string> class_names;  ///< label paths, index = class id
    std::vector<int> labels;               ///< per row: class id or kNoLabel
    std::vector<std::int64_t> groups;      ///< per row: object instance id (-1 = none)
    std::vector<std::int64_t> views;       ///< per row: view id within the instance (-1 = none)
    std::vector<std::int64_t> row_ids;     ///< per row: unique id, key of column-wise concatenation
    std::vector<std::string> sources;      ///< per row: originating file/cluster ("" = unknown)

    std::size_t rows() const { return labels.size(); }
    std::size_t cols() const { return num_cols; }
    std::size_t num_classes() const { return class_names.size(); }
    /// Labelled rows per class (index = class id); unlabelled rows are not counted.
    std::vector<std::size_t> ClassCounts() const;
    bool empty() const { return rows() == 0; }

    /// The feature matrix as an Eigen view (no copy).
    Eigen::Map<const FeatureMatrix> features() const {
        return {values.data(), static_cast<Eigen::Index>(rows()),
                static_cast<Eigen::Index>(num_cols)};
    }
    Eigen::Map<FeatureMatrix> features() {
        return {values.data(), static_cast<Eigen::Index>(rows()),
                static_cast<Eigen::Index>(num_cols)};
    }
    std::span<const float> row(std::size_t i) const {
        return {values.data() + i * num_cols, num_cols};
    }

    /// Creates an empty dataset with the given blocks (name, column names) in order.
    static Dataset WithBlocks(
        const std::vector<std::pair<std::string, std::vector<std::string>>>& blocks);
    /// Creates an empty dataset with `cols` columns in one block named `block` ("f0", "f1", ...).
    static Dataset WithColumns(std::size_t cols, const std::string& block = "features");

    /// Class id of `path`, adding it to class_names if new.
    int ClassId(const std::string& path);
    /// Class id of `path` or kNoLabel if absent.
    int FindClass(const std::string& path) const;
    /// Appends one row. `label` is a class path ("" = unlabelled); `row_id` < 0 takes the last row
    /// id + 1. Throws InvalidArgument when the feature count differs from cols() and DataError on a
    /// non-finite value.
    void AppendRow(std::span<const float> features, const std::string& label,
                   std::int64_t group = -1, std::int64_t view = -1, std::string source = {},
                   std::int64_t row_id = -1);
    /// Every source present (for resuming an extraction).
    std::unordered_set<std::string> Sources() const;
    /// Index of the block named `name`; throws InvalidArgument listing the blocks when absent.
    std::size_t BlockIndex(const std::string& name) const;
    /// Block names in order.
    std::vector<std::string> BlockNames() const;

    /// Checks internal consistency (sizes, blocks covering the columns, label range, unique row
    /// ids); throws FormatError prefixed with `what`.
    void Validate(const std::string& what = "dataset") const;
    /// Throws DataError naming the first row and column holding NaN or infinity.
    void CheckFinite(const std::string& what = "dataset") const;
};

/// The label path of a file below `root`: its parent folders joined by '/'
/// (root/cylinder/mug/scan_001.pcd -> "cylinder/mug"). Throws InvalidArgument if `file` is not
/// below `root`.
std::string LabelPathFromFile(const std::filesystem::path& root, const std::filesystem::path& file);

/// `prefix` followed by the decimal `index` ("w" and 3 -> "w3"), for generated column names.
std::string IndexedName(std::string_view prefix, std::size_t index);

/// First `depth` components of a label path ("cylinder/mug", 1 -> "cylinder"); depth 0 = all.
std::string TruncateLabelPath(const std::string& path, std::size_t depth);

// --- files -------------------------------------------------------------------------------------

/// Current version of the binary dataset format (docs/ml.md).
inline constexpr std::uint32_t kDatasetFormatVersion = 1;

/// Writes the binary format (.mcd) atomically.
void SaveDataset(const Dataset& data, const std::filesystem::path& path);
/// Reads the binary format; FormatError for another version, a corrupt or truncated file.
Dataset LoadDataset(const std::filesystem::path& path);

/// CSV with a header: meta columns row_id, group, view, label, source (any order, all optional)
/// and feature columns named "block:feature" (no ':' -> block "features").
void SaveCsv(const Dataset& data, const std::filesystem::path& path);
Dataset LoadCsv(const std::filesystem::path& path);

/// Loads by extension: .csv -> CSV, anything else -> binary.
Dataset ReadDatasetFile(const std::filesystem::path& path);
/// Saves by extension: .csv -> CSV, anything else -> binary.
void WriteDatasetFile(const Dataset& data, const std::filesystem::path& path);

}  // namespace multicue::ml

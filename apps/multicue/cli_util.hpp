#pragma once
// Small helpers shared by the subcommands.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>

#include <CLI/CLI.hpp>
#include <Eigen/Core>

#include "multicue/core/point_cloud.hpp"
#include "multicue/core/progress.hpp"
#include "multicue/io/point_cloud_io.hpp"
#include "multicue/ml/classifier.hpp"
#include "multicue/ml/dataset.hpp"

namespace multicue::cli {

/// Reads a cloud and refuses clouds without a single finite point (data error naming the file).
PointCloud ReadNonEmptyCloud(const std::filesystem::path& path);

/// Adds `--format ascii|binary|compressed` to a subcommand.
CLI::Option* AddFormatOption(CLI::App& cmd, std::string& format);

/// Refuses to write the output over the input, which would lose the input on a failed run.
void CheckDistinctPaths(const std::filesystem::path& in, const std::filesystem::path& out);

/// Refuses an output file (given by `option`; empty: none) whose folder does not exist, before
/// any work is done.
void CheckOutputFolder(const std::string& option, const std::filesystem::path& file);

/// The end of a training command on simulated kitchens: collects the rows with progress over
/// `kitchens` kitchens and the interrupt handler installed, trains the classifier on them and
/// saves it to `out` (atomically) and, when `rows_file` is set, the rows. Nothing is written when
/// the job is interrupted (an Error naming `job`). Returns the rows.
ml::Dataset CollectTrainAndSave(
    const std::string& job, int kitchens, const std::function<ml::Dataset(Progress*)>& collect,
    const std::function<std::unique_ptr<ml::Classifier>(const ml::Dataset&)>& train,
    const std::string& out, const std::string& rows_file);

/// The options every training on simulated kitchens takes, bound to the command's fields.
struct KitchenTrainingOptions {
    std::string& out;         ///< --out: the model file
    std::string& library;     ///< --kitchen: the kitchen model library, or none
    std::string& split;       ///< --split: the library half
    int& fold;                ///< --fold: -1, or one fold of the half
    int& kitchens;            ///< --kitchens
    float& procedural_share;  ///< --procedural-share
    std::string& spec;        ///< --classifier
    std::string& rows;        ///< --rows: the labelled rows too (`what` names them in the help)
    std::uint64_t& seed;      ///< --seed
    bool& quiet;              ///< -q
};

/// Adds the options of `o` to `cmd`; `what` names the rows ("candidate rows", "pieces").
void AddKitchenTrainingOptions(CLI::App* cmd, const KitchenTrainingOptions& o,
                               const std::string& what);

/// Parses "x,y,z" into a vector; throws InvalidArgument naming the option otherwise.
Eigen::Vector3f ParseVector3(const std::string& text, const std::string& option);

}  // namespace multicue::cli

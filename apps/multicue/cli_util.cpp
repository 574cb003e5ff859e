#include "cli_util.hpp"

#include <cmath>
#include <sstream>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"

namespace multicue::cli {

PointCloud ReadNonEmptyCloud(const std::filesystem::path& path) {
    PointCloud cloud = io::ReadPointCloud(path);
    if (cloud.empty()) throw DataError(fmt::format("{}: cloud has no points", path.string()));
    if (!cloud.HasFinite()) {
        throw DataError(fmt::format("{}: all {} points are NaN", path.string(), cloud.size()));
    }
    return cloud;
}

CLI::Option* AddFormatOption(CLI::App& cmd, std::string& format) {
    return cmd
        .add_option("--format", format,
                    "ascii, binary or compressed (PCD binary_compressed; PLY has no compression "
                    "and writes binary)")
        ->check(CLI::IsMember({"ascii", "binary", "compressed"}))
        ->capture_default_str();
}

void CheckDistinctPaths(const std::filesystem::path& in, const std::filesystem::path& out) {
    std::error_code ec;
    if (std::filesystem::exists(out, ec) && std::filesystem::equivalent(in, out, ec)) {
        throw InvalidArgument(
            fmt::format("output '{}' is the input file; choose another path", out.string()));
    }
}

void CheckOutputFolder(const std::string& option, const std::filesystem::path& file) {
    const std::filesystem::path folder = file.parent_path();
    if (!folder.empty() && !std::filesystem::is_directory(folder)) {
        throw InvalidArgument(fmt::format("{}: no such folder '{}'", option, folder.string()));
    }
}

void AddKitchenTrainingOptions(CLI::App* cmd, const KitchenTrainingOptions& o,
                               const std::string& what) {
    cmd->add_option("--out", o.out, "classifier file to write (.mcm)")->required();
    cmd->add_option("--kitchen", o.library,
                    "kitchen library (PartNet-Mobility models); none: procedural units only "
                    "(--procedural)")
        ->capture_default_str();
    cmd->add_option("--split", o.split,
                    "library half trained on: tune (the other half stays held out), test, all")
        ->capture_default_str();
    cmd->add_option("--fold", o.fold,
                    "-1: the whole --split half; 0 or 1: one fold of it (validation inside it)")
        ->capture_default_str();
    cmd->add_option("--kitchens", o.kitchens, "simulated kitchens")->capture_default_str();
    cmd->add_option("--procedural-share", o.procedural_share,
                    "chance that a unit of a kind with procedural and library models is "
                    "procedural")
        ->capture_default_str();
    cmd->add_option("--classifier", o.spec, "classifier spec (`multicue classifier train`)")
        ->capture_default_str();
    cmd->add_option("--rows", o.rows,
                    "also write the labelled " + what +
                        " as a dataset (.mcd, or .csv by extension) for `multicue classifier`");
    cmd->add_option("--seed", o.seed, "kitchen i uses a sub-seed of this")->capture_default_str();
    cmd->add_flag("-q,--quiet", o.quiet, "no summary");
}

ml::Dataset CollectTrainAndSave(
    const std::string& job, int kitchens, const std::function<ml::Dataset(Progress*)>& collect,
    const std::function<std::unique_ptr<ml::Classifier>(const ml::Dataset&)>& train,
    const std::string& out, const std::string& rows_file) {
    InstallInterruptHandler();
    Progress progress("kitchens", static_cast<std::size_t>(kitchens));
    ml::Dataset rows = collect(&progress);
    if (InterruptRequested()) throw Error(job + ": interrupted, no model written");
    progress.Finish();
    train(rows)->Save(out);
    if (!rows_file.empty()) ml::WriteDatasetFile(rows, rows_file);
    return rows;
}

Eigen::Vector3f ParseVector3(const std::string& text, const std::string& option) {
    std::istringstream in(text);
    Eigen::Vector3f v;
    char sep1 = 0, sep2 = 0;
    if (!(in >> v.x() >> sep1 >> v.y() >> sep2 >> v.z()) || sep1 != ',' || sep2 != ',' ||
        !(in >> std::ws).eof() || !v.allFinite()) {
        throw InvalidArgument(
            fmt::format("{} must be three numbers x,y,z; got '{}'", option, text));
    }
    return v;
}

}  // namespace multicue::cli

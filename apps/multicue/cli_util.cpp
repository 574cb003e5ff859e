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

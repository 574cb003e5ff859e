#pragma once
// The task file of `multicue run` (YAML or JSON; docs/executive.md): what to do, the database, the
// frames with their poses and where the result goes.

#include <filesystem>
#include <string_view>
#include <vector>

#include "multicue/system/executive.hpp"

namespace multicue::cli {

struct TaskFile {
    Task task;
    std::filesystem::path database;  ///< "" = none
    std::filesystem::path output;    ///< "" = standard output
    std::filesystem::path params;    ///< "" = default parameters
    std::vector<Frame> frames;       ///< names, poses and times; the clouds are read later
    std::vector<std::filesystem::path> files;  ///< the cloud of frames[i]
};

/// Reads a task file; relative paths in it are relative to its folder. Throws IoError,
/// FormatError (malformed YAML) or InvalidArgument (unknown keys, wrong values), naming the file.
TaskFile ReadTaskFile(const std::filesystem::path& path);

/// Same for text already in memory; `path` names it and is the base of relative paths.
TaskFile ParseTaskFile(std::string_view text, const std::filesystem::path& path);

}  // namespace multicue::cli

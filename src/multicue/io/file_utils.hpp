#pragma once
/// \file File helpers shared by the readers and writers: whole-file reads with clear errors and
/// atomic writes (temporary file in the target's folder, renamed on success), so a failed run never
/// leaves a half-written file and never destroys an existing one.

#include <filesystem>
#include <functional>
#include <ostream>
#include <string>

#include "multicue/core/atomic_file.hpp"

namespace multicue::io {

/// Reads a whole file into memory. Throws IoError naming the file if it is missing, a directory
/// or unreadable.
std::string ReadFileBytes(const std::filesystem::path& path);

/// Atomic writes (core/atomic_file.hpp), also under io's name.
using multicue::WriteFileAtomically;

/// Lower-case extension of `path` without the dot ("pcd", "ply", "obj"), or "" if none.
std::string LowerExtension(const std::filesystem::path& path);

}  // namespace multicue::io

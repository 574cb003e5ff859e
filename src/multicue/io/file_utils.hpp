#pragma once
/// \file File helpers shared by the readers and writers: whole-file reads with clear errors and
/// atomic writes (temporary file in the target's folder, renamed on success), so a failed run never
/// leaves a half-written file and never destroys an existing one.

#include <filesystem>
#include <functional>
#include <ostream>
#include <string>

namespace multicue::io {

/// Reads a whole file into memory. Throws IoError naming the file if it is missing, a directory
/// or unreadable.
std::string ReadFileBytes(const std::filesystem::path& path);

/// Calls `write` with a binary stream on a temporary file next to `path`, then renames it over
/// `path`. If `write` throws or the stream fails, the temporary file is removed, `path` is left as
/// it was and the exception propagates (stream failures become IoError).
void WriteFileAtomically(const std::filesystem::path& path,
                         const std::function<void(std::ostream&)>& write);

/// Lower-case extension of `path` without the dot ("pcd", "ply", "obj"), or "" if none.
std::string LowerExtension(const std::filesystem::path& path);

}  // namespace multicue::io

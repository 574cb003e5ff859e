#pragma once
/// \file Atomic file writes: the bytes go to a temporary file in the target's folder
/// (".NAME.tmp-PID-N"), which is renamed over the target on success, so a failed or killed writer
/// never leaves a half-written file and never destroys an existing one. Temporaries of killed
/// writers are removed by the next write of the same file.

#include <filesystem>
#include <functional>
#include <ostream>

namespace multicue {

/// Calls `write` with a binary stream on a temporary file next to `path`, then renames it over
/// `path`. If `write` throws or the stream fails, the temporary file is removed, `path` is left as
/// it was and the exception propagates (stream failures become IoError naming the file and the
/// system's reason). Throws IoError if the folder of `path` does not exist.
void WriteFileAtomically(const std::filesystem::path& path,
                         const std::function<void(std::ostream&)>& write);

}  // namespace multicue

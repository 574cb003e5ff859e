#pragma once
/// \file Reading a mesh file with Assimp so that a damaged file is refused with an error instead
/// of reaching an assertion or a bad read inside Assimp's post-processing. Internal to the sim
/// module, not part of its API.

#include <filesystem>

struct aiScene;
namespace Assimp {
class Importer;
}

namespace multicue::sim::assimp_read {

/// Reads `path` with `importer` and validates the scene (indices within the vertices, counts
/// matching arrays), refuses faces without indices, sets each mesh's primitive types from its
/// faces and only then applies `post_steps` (aiPostProcessSteps flags, e.g. triangulation).
/// Debian's Assimp takes the primitive types its importers declare as they are, and its
/// triangulation asserts (aborting the process) when a mesh declares polygons it does not have.
/// The scene belongs to `importer`. Throws FormatError on an unreadable or damaged file.
const aiScene* ReadScene(Assimp::Importer& importer, const std::filesystem::path& path,
                         unsigned post_steps);

}  // namespace multicue::sim::assimp_read

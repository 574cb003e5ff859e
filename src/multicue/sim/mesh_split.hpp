#pragma once
/// \file A held-out split of a mesh library into a "tune" and a "test" half, so that parameters
/// are tuned on scenes of one half and results are reported on scenes of the other, never on
/// meshes seen while tuning. The split is a pure function of the file names and categories:
/// deterministic, independent of the folder the library lives in and of the order of labels.csv.

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "multicue/sim/mesh.hpp"

namespace multicue::sim {

enum class MeshSplit {
    kAll,   ///< every mesh
    kTune,  ///< the half used for tuning and training
    kTest,  ///< the held-out half used for testing
};

/// "all", "tune" or "test".
std::string_view MeshSplitName(MeshSplit split);
/// Inverse of MeshSplitName. Throws InvalidArgument naming the value for anything else.
MeshSplit ParseMeshSplit(std::string_view name);

/// 64-bit FNV-1a hash of a mesh file name (the name only, not its folder): the stable key that
/// orders the meshes of a category.
std::uint64_t MeshNameHash(std::string_view file_name);

/// The half (kTune or kTest) of every entry of `library`, in the order of `library`. Within each
/// category the entries are ordered by MeshNameHash of their file name (ties by name) and
/// alternate tune, test, tune, ...: each category is split 50/50 (the tune half takes the odd
/// one out), and both halves hold every category with at least two meshes. Entries whose file
/// name appears twice in a category (the same mesh listed twice) share one half.
std::vector<MeshSplit> MeshSplitOf(const std::vector<MeshEntry>& library);

/// The entries of `library` in `split` (all of them for kAll), in their original order.
std::vector<MeshEntry> SelectMeshSplit(const std::vector<MeshEntry>& library, MeshSplit split);

}  // namespace multicue::sim

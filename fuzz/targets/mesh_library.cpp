// The labels.csv of a mesh library (`multicue simulate --meshes`, `multicue train --meshes`). The
// folder holds labels.csv itself, so a line naming it passes the check that the mesh exists.

#include "fuzz_target.hpp"
#include "multicue/sim/mesh.hpp"

MULTICUE_FUZZ_TARGET(mesh_library) {
    using namespace multicue;
    const auto path = fuzz::WriteInput(fuzz::Bytes(data, size), "labels.csv");
    fuzz::AllowTypedErrors([&] { sim::ReadMeshLibrary(path.parent_path()); });
}

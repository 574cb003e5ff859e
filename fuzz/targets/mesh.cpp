// Meshes read through Assimp (sim::LoadMesh: the mesh libraries of simulate and train). The first
// byte picks the format (by the file name's extension), the rest is the file. Assimp itself is
// Debian's build, without coverage instrumentation: this target mostly checks what multicue does
// with the scenes Assimp returns.

#include <array>

#include "fuzz_target.hpp"
#include "multicue/sim/mesh.hpp"

MULTICUE_FUZZ_TARGET(mesh) {
    using namespace multicue;
    if (size == 0) return;
    static constexpr std::array<const char*, 6> kNames = {"input.obj", "input.ply", "input.stl",
                                                          "input.off", "input.dae", "input.gltf"};
    const auto path =
        fuzz::WriteInput(fuzz::Bytes(data + 1, size - 1), kNames[data[0] % kNames.size()]);
    fuzz::AllowTypedErrors([&] { sim::LoadMesh(path).Validate(); });
}

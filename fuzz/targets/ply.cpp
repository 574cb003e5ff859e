// PLY files (ascii, binary little and big endian) as point clouds and as meshes.

#include "multicue/io/ply.hpp"
#include "fuzz_target.hpp"

MULTICUE_FUZZ_TARGET(ply) {
    using namespace multicue;
    const auto path = fuzz::WriteInput(fuzz::Bytes(data, size), "input.ply");
    fuzz::AllowTypedErrors([&] {
        const PointCloud cloud = io::ReadPly(path);
        cloud.Validate();
    });
    fuzz::AllowTypedErrors([&] {
        const TriangleMesh mesh = io::ReadPlyMesh(path);
        mesh.Validate();
    });
}

// Wavefront OBJ meshes.

#include "multicue/io/obj.hpp"
#include "fuzz_target.hpp"

MULTICUE_FUZZ_TARGET(obj) {
    using namespace multicue;
    const auto path = fuzz::WriteInput(fuzz::Bytes(data, size), "input.obj");
    fuzz::AllowTypedErrors([&] {
        const io::ObjMesh obj = io::ReadObj(path);
        obj.mesh.Validate();
        if (obj.triangle_groups.size() != obj.mesh.triangles.size() &&
            !obj.triangle_groups.empty()) {
            throw std::logic_error("OBJ: one group per triangle expected");
        }
        for (const auto g : obj.triangle_groups) {
            if (g >= obj.group_names.size())
                throw std::logic_error("OBJ: group index out of range");
        }
    });
}

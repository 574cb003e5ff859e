// URDF robot descriptions (`multicue simulate kitchens`, the articulated kitchen models): the
// XML, its links, joints, visuals and limits as io::ReadUrdf checks them.

#include "multicue/io/urdf.hpp"
#include "fuzz_target.hpp"

MULTICUE_FUZZ_TARGET(urdf) {
    using namespace multicue;
    const auto path = fuzz::WriteInput(fuzz::Bytes(data, size), "input.urdf");
    fuzz::AllowTypedErrors([&] { io::ReadUrdf(path); });
}

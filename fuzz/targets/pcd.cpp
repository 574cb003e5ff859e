// PCD files (DATA ascii, binary and binary_compressed): read, and what was read written and read
// back.

#include "multicue/io/pcd.hpp"
#include "fuzz_target.hpp"

MULTICUE_FUZZ_TARGET(pcd) {
    using namespace multicue;
    const auto path = fuzz::WriteInput(fuzz::Bytes(data, size), "input.pcd");
    fuzz::AllowTypedErrors([&] {
        const PointCloud cloud = io::ReadPcd(path);
        const auto copy = path.parent_path() / "copy.pcd";
        io::WritePcd(copy, cloud, {.encoding = io::PcdEncoding::kBinaryCompressed});
        const PointCloud again = io::ReadPcd(copy);
        if (again.size() != cloud.size() || again.width != cloud.width ||
            again.height != cloud.height) {
            throw std::logic_error("a PCD file written from a read cloud reads back differently");
        }
    });
}

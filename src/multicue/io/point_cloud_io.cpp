#include "multicue/io/point_cloud_io.hpp"

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/io/file_utils.hpp"
#include "multicue/io/obj.hpp"
#include "multicue/io/pcd.hpp"
#include "multicue/io/ply.hpp"

namespace multicue::io {

Encoding ParseEncoding(const std::string& name) {
    if (name == "ascii") return Encoding::kAscii;
    if (name == "binary") return Encoding::kBinary;
    if (name == "compressed") return Encoding::kCompressed;
    throw InvalidArgument(
        fmt::format("format must be one of ascii, binary, compressed; got '{}'", name));
}

PointCloud ReadPointCloud(const std::filesystem::path& path) {
    const std::string ext = LowerExtension(path);
    if (ext == "pcd") return ReadPcd(path);
    if (ext == "ply") return ReadPly(path);
    throw IoError(fmt::format("{}: unknown point cloud format '.{}' (expected .pcd or .ply)",
                              path.string(), ext));
}

void WritePointCloud(const std::filesystem::path& path, const PointCloud& cloud,
                     Encoding encoding) {
    const std::string ext = LowerExtension(path);
    if (ext == "pcd") {
        const PcdEncoding e = encoding == Encoding::kAscii    ? PcdEncoding::kAscii
                              : encoding == Encoding::kBinary ? PcdEncoding::kBinary
                                                              : PcdEncoding::kBinaryCompressed;
        WritePcd(path, cloud, {.encoding = e});
        return;
    }
    if (ext == "ply") {
        const PlyEncoding e =
            encoding == Encoding::kAscii ? PlyEncoding::kAscii : PlyEncoding::kBinaryLittleEndian;
        WritePly(path, cloud, {.encoding = e});
        return;
    }
    throw IoError(fmt::format("{}: unknown point cloud format '.{}' (expected .pcd or .ply)",
                              path.string(), ext));
}

TriangleMesh ReadTriangleMesh(const std::filesystem::path& path) {
    const std::string ext = LowerExtension(path);
    if (ext == "ply") return ReadPlyMesh(path);
    if (ext == "obj") return ReadObj(path).mesh;
    throw IoError(
        fmt::format("{}: unknown mesh format '.{}' (expected .ply or .obj)", path.string(), ext));
}

}  // namespace multicue::io

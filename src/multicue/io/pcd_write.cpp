#include "multicue/io/pcd.hpp"

#include <lzf.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/io/file_utils.hpp"
#include "multicue/io/pcd_internal.hpp"

namespace multicue::io {
namespace {

using detail::Byte;
using detail::CopyStrided;
using detail::ScalarOf;
using detail::VisitScalar;

// ------------------------------------------------------------------------------------- writing

/// One field as written: its header entry and where its values are in the cloud.
struct OutField {
    std::string name;
    char type = 'F';
    std::uint8_t size = 4;
    std::uint32_t count = 1;
    const Byte* src = nullptr;
    std::size_t stride = 0;
    std::size_t Bytes() const { return std::size_t{size} * count; }
};

std::vector<OutField> OutFields(const PointCloud& c,
                                const std::vector<std::uint32_t>& packed_colors, bool opaque,
                                PcdEncoding encoding) {
    std::vector<OutField> out;
    const auto bytes = [](const auto* p) { return reinterpret_cast<const Byte*>(p); };
    const auto floats = [&](const std::vector<float>& v, const char* name) {
        if (!v.empty()) out.push_back({name, 'F', 4, 1, bytes(v.data()), sizeof(float)});
    };
    const auto vec3 = [&](const std::vector<Eigen::Vector3f>& v, const char* nx, const char* ny,
                          const char* nz) {
        const char* names[3] = {nx, ny, nz};
        for (int k = 0; k < 3; ++k) {
            const Byte* base = v.empty() ? nullptr : bytes(v.data()) + k * sizeof(float);
            out.push_back({names[k], 'F', 4, 1, base, sizeof(Eigen::Vector3f)});
        }
    };
    vec3(c.points, "x", "y", "z");
    if (c.HasNormals()) vec3(c.normals, "normal_x", "normal_y", "normal_z");
    floats(c.curvature, "curvature");
    // PCL declares rgb as F 4, but in ascii as U 4 with the packed colour as an integer: printed
    // as a float, every opaque colour would be nan. PCL's ascii reader relies on that TYPE.
    const char rgb_type = opaque && encoding != PcdEncoding::kAscii ? 'F' : 'U';
    if (c.HasColors()) {
        out.push_back({opaque ? "rgb" : "rgba", rgb_type, 4, 1, bytes(packed_colors.data()), 4});
    }
    if (c.HasLabels()) out.push_back({"label", 'U', 4, 1, bytes(c.labels.data()), 4});
    floats(c.intensity, "intensity");
    floats(c.confidence, "confidence");
    for (const auto& e : c.extra_fields) {
        if (e.name.empty() || e.name == "_" ||
            e.name.find_first_of(" \t\r\n#") != std::string::npos) {
            throw DataError(fmt::format("extra field name '{}' cannot be written to PCD", e.name));
        }
        if (!ScalarOf(e.type, e.size)) {
            throw DataError(
                fmt::format("extra field '{}' has unsupported type {} {}", e.name, e.type, e.size));
        }
        out.push_back({e.name, e.type, e.size, e.count, e.data.data(), e.BytesPerPoint()});
    }
    return out;
}

std::string MakeHeader(const PointCloud& c, const std::vector<OutField>& fields, PcdEncoding enc) {
    const std::size_t n = c.size();
    const std::uint32_t width = c.IsOrganized() ? c.width : static_cast<std::uint32_t>(n);
    const std::uint32_t height = c.IsOrganized() ? c.height : 1;
    fmt::memory_buffer out;
    auto it = std::back_inserter(out);
    fmt::format_to(it, "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS");
    for (const auto& f : fields) fmt::format_to(it, " {}", f.name);
    fmt::format_to(it, "\nSIZE");
    for (const auto& f : fields) fmt::format_to(it, " {}", f.size);
    fmt::format_to(it, "\nTYPE");
    for (const auto& f : fields) fmt::format_to(it, " {}", f.type);
    fmt::format_to(it, "\nCOUNT");
    for (const auto& f : fields) fmt::format_to(it, " {}", f.count);
    const auto& o = c.sensor_origin;
    const auto& q = c.sensor_orientation;
    fmt::format_to(it,
                   "\nWIDTH {}\nHEIGHT {}\nVIEWPOINT {} {} {} {} {} {} {}\nPOINTS {}\nDATA {}\n",
                   width, height, o.x(), o.y(), o.z(), q.w(), q.x(), q.y(), q.z(), n,
                   enc == PcdEncoding::kAscii    ? "ascii"
                   : enc == PcdEncoding::kBinary ? "binary"
                                                 : "binary_compressed");
    return fmt::to_string(out);
}

std::string AsciiBody(const std::vector<OutField>& fields, std::size_t n) {
    fmt::memory_buffer out;
    auto it = std::back_inserter(out);
    for (std::size_t i = 0; i < n; ++i) {
        bool first = true;
        for (const auto& f : fields) {
            const Byte* p = f.src + i * f.stride;
            const auto scalar = *ScalarOf(f.type, f.size);
            for (std::uint32_t e = 0; e < f.count; ++e, p += f.size) {
                if (!first) out.push_back(' ');
                first = false;
                VisitScalar(scalar, [&](auto tag) {
                    using T = decltype(tag);
                    T v;
                    std::memcpy(&v, p, sizeof(T));
                    if constexpr (std::is_floating_point_v<T>) {
                        if (std::isnan(v)) {
                            fmt::format_to(it, "nan");
                        } else {
                            fmt::format_to(it, "{}", v);  // shortest round-trip representation
                        }
                    } else if constexpr (sizeof(T) == 1) {
                        fmt::format_to(it, "{}", static_cast<int>(v));
                    } else {
                        fmt::format_to(it, "{}", v);
                    }
                });
            }
        }
        out.push_back('\n');
    }
    return fmt::to_string(out);
}

}  // namespace

void WritePcd(const std::filesystem::path& path, const PointCloud& cloud,
              const PcdWriteOptions& options) {
    cloud.Validate();
    const std::size_t n = cloud.size();
    bool opaque = true;
    std::vector<std::uint32_t> packed_colors(cloud.colors.size());
    for (std::size_t i = 0; i < cloud.colors.size(); ++i) {
        opaque = opaque && cloud.colors[i].a == 255;
        packed_colors[i] = PackRgba(cloud.colors[i]);
    }
    const std::vector<OutField> fields = OutFields(cloud, packed_colors, opaque, options.encoding);
    const std::string header = MakeHeader(cloud, fields, options.encoding);
    std::size_t point_size = 0;
    for (const auto& f : fields) point_size += f.Bytes();

    std::string body;
    if (options.encoding == PcdEncoding::kAscii) {
        body = AsciiBody(fields, n);
    } else if (options.encoding == PcdEncoding::kBinary) {
        // Records are written in blocks, not assembled whole: a file of 10 million points would
        // otherwise hold its size in memory a second time beside the cloud.
        WriteFileAtomically(path, [&](std::ostream& out) {
            out.write(header.data(), static_cast<std::streamsize>(header.size()));
            constexpr std::size_t kBlock = 1 << 16;  // points per block
            std::vector<Byte> block(std::min(n, kBlock) * point_size);
            for (std::size_t first = 0; first < n && out; first += kBlock) {
                const std::size_t count = std::min(kBlock, n - first);
                std::size_t offset = 0;
                for (const auto& f : fields) {
                    CopyStrided(f.src + first * f.stride, f.stride, block.data() + offset,
                                point_size, f.Bytes(), count);
                    offset += f.Bytes();
                }
                out.write(reinterpret_cast<const char*>(block.data()),
                          static_cast<std::streamsize>(count * point_size));
            }
        });
        return;
    } else {
        // Field by field (all x, then all y, ...) compresses far better than whole records.
        const std::size_t size = n * point_size;
        if (size > std::numeric_limits<std::uint32_t>::max() / 2) {
            throw DataError(fmt::format("{}: {} bytes are too many for binary_compressed PCD",
                                        path.string(), size));
        }
        std::vector<Byte> planes(size);
        std::size_t offset = 0;
        for (const auto& f : fields) {
            CopyStrided(f.src, f.stride, planes.data() + offset, f.Bytes(), f.Bytes(), n);
            offset += f.Bytes() * n;
        }
        // LZF grows incompressible data by at most 1/32 plus a byte; PCL still stores it
        // compressed (its reader expects nothing else), so leave room for that growth.
        const std::size_t capacity = size + size / 16 + 64;
        body.resize(8 + capacity);
        std::uint32_t compressed = 0;
        if (size > 0) {
            compressed = lzf_compress(planes.data(), static_cast<unsigned>(size), body.data() + 8,
                                      static_cast<unsigned>(capacity));
            if (compressed == 0) {
                throw IoError(fmt::format("{}: LZF compression failed", path.string()));
            }
        }
        const auto uncompressed = static_cast<std::uint32_t>(size);
        std::memcpy(body.data(), &compressed, 4);
        std::memcpy(body.data() + 4, &uncompressed, 4);
        body.resize(8 + compressed);
    }
    WriteFileAtomically(path, [&](std::ostream& out) {
        out.write(header.data(), static_cast<std::streamsize>(header.size()));
        out.write(body.data(), static_cast<std::streamsize>(body.size()));
    });
}

}  // namespace multicue::io

#include "multicue/io/ply.hpp"

#include <algorithm>
#include <bit>
#include <cstdint>
#include <cstring>
#include <limits>
#include <optional>
#include <ostream>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <fmt/compile.h>
#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/core/logging.hpp"
#include "multicue/io/file_utils.hpp"
#include "multicue/io/ply_internal.hpp"

namespace multicue::io {
namespace {

using detail::IsSpace;
using detail::MakeExtraField;
using detail::ScalarType;
using detail::TypeName;
using detail::WithType;

// ---------------------------------------------------------------------------------------------
// Writer

/// Buffers the data section and hands it to the stream in large blocks.
class BodyWriter {
  public:
    BodyWriter(std::ostream& out, PlyEncoding encoding) : out_(out), encoding_(encoding) {}
    ~BodyWriter() = default;
    BodyWriter(const BodyWriter&) = delete;
    BodyWriter& operator=(const BodyWriter&) = delete;

    template <typename T>
    void Put(T v) {
        if (encoding_ == PlyEncoding::kAscii) {
            if (!row_start_) buf_.push_back(' ');
            row_start_ = false;
            char text[40];  // longest: a double's shortest repr, 24 characters
            char* end = nullptr;
            if constexpr (sizeof(T) == 1) {
                end = fmt::format_to(text, FMT_COMPILE("{}"), static_cast<int>(v));
            } else {
                end = fmt::format_to(text, FMT_COMPILE("{}"), v);
            }
            buf_.insert(buf_.end(), text, end);
            return;
        }
        char tmp[sizeof(T)];
        std::memcpy(tmp, &v, sizeof(T));
        const bool big = encoding_ == PlyEncoding::kBinaryBigEndian;
        if (big != (std::endian::native == std::endian::big)) std::reverse(tmp, tmp + sizeof(T));
        buf_.insert(buf_.end(), tmp, tmp + sizeof(T));
    }

    void EndRow() {
        if (encoding_ == PlyEncoding::kAscii) buf_.push_back('\n');
        row_start_ = true;
        if (buf_.size() >= (1u << 20)) Flush();
    }

    void Flush() {
        out_.write(buf_.data(), static_cast<std::streamsize>(buf_.size()));
        buf_.clear();
    }

  private:
    std::ostream& out_;
    PlyEncoding encoding_;
    std::vector<char> buf_;
    bool row_start_ = true;
};

const char* EncodingName(PlyEncoding e) {
    switch (e) {
        case PlyEncoding::kAscii:
            return "ascii";
        case PlyEncoding::kBinaryLittleEndian:
            return "binary_little_endian";
        case PlyEncoding::kBinaryBigEndian:
            return "binary_big_endian";
    }
    return "ascii";
}

/// The PLY type of a one-element extra field (the inverse of MakeExtraField); none for 8-byte
/// integers, which PLY lacks.
std::optional<ScalarType> ExtraScalarType(const ExtraField& f) {
    for (int i = 0; i <= static_cast<int>(ScalarType::kFloat64); ++i) {
        const auto t = static_cast<ScalarType>(i);
        const ExtraField g = MakeExtraField(f.name, t);
        if (g.type == f.type && g.size == f.size) return t;
    }
    return std::nullopt;
}

/// Names the reader maps to PointCloud vectors; an extra field with such a name would not
/// round-trip as an extra field.
bool IsReservedVertexName(const std::string& n) {
    static constexpr std::string_view kNames =
        " x y z nx ny nz normal_x normal_y normal_z red green blue alpha r g b a rgb rgba "
        "diffuse_red diffuse_green diffuse_blue diffuse_alpha label intensity confidence "
        "curvature ";
    return kNames.find(" " + n + " ") != std::string_view::npos;
}

/// The per-vertex columns written by both writers.
struct VertexColumns {
    const std::vector<Eigen::Vector3f>* points = nullptr;
    const std::vector<Eigen::Vector3f>* normals = nullptr;
    const std::vector<Color>* colors = nullptr;
    bool alpha = false;
    const std::vector<std::uint32_t>* labels = nullptr;
    const std::vector<float>* intensity = nullptr;
    const std::vector<float>* confidence = nullptr;
    const std::vector<float>* curvature = nullptr;
    std::vector<std::pair<const ExtraField*, ScalarType>> extras;
};

template <typename T>
const std::vector<T>* IfPresent(const std::vector<T>& v) {
    return v.empty() ? nullptr : &v;
}

std::string VertexHeader(const VertexColumns& c, PlyEncoding encoding) {
    std::string h = fmt::format("ply\nformat {} 1.0\ncomment multicue\nelement vertex {}\n",
                                EncodingName(encoding), c.points->size());
    h += "property float x\nproperty float y\nproperty float z\n";
    if (c.normals) h += "property float nx\nproperty float ny\nproperty float nz\n";
    if (c.colors) h += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
    if (c.colors && c.alpha) h += "property uchar alpha\n";
    if (c.labels) h += "property uint label\n";
    if (c.intensity) h += "property float intensity\n";
    if (c.confidence) h += "property float confidence\n";
    if (c.curvature) h += "property float curvature\n";
    for (const auto& [f, t] : c.extras) h += fmt::format("property {} {}\n", TypeName(t), f->name);
    return h;
}

void PutExtra(BodyWriter& w, const std::uint8_t* p, ScalarType t) {
    WithType(t, [&](auto x) {
        std::memcpy(&x, p, sizeof(x));
        w.Put(x);
    });
}

void WriteVertexRows(BodyWriter& w, const VertexColumns& c) {
    const std::size_t n = c.points->size();
    for (std::size_t i = 0; i < n; ++i) {
        const auto& p = (*c.points)[i];
        w.Put(p.x());
        w.Put(p.y());
        w.Put(p.z());
        if (c.normals) {
            const auto& nv = (*c.normals)[i];
            w.Put(nv.x());
            w.Put(nv.y());
            w.Put(nv.z());
        }
        if (c.colors) {
            const Color& col = (*c.colors)[i];
            w.Put(col.r);
            w.Put(col.g);
            w.Put(col.b);
            if (c.alpha) w.Put(col.a);
        }
        if (c.labels) w.Put((*c.labels)[i]);
        if (c.intensity) w.Put((*c.intensity)[i]);
        if (c.confidence) w.Put((*c.confidence)[i]);
        if (c.curvature) w.Put((*c.curvature)[i]);
        for (const auto& [f, t] : c.extras) PutExtra(w, f->data.data() + i * f->size, t);
        w.EndRow();
    }
}

bool AnyTranslucent(const std::vector<Color>& colors) {
    return std::any_of(colors.begin(), colors.end(), [](const Color& c) { return c.a != 255; });
}

}  // namespace

void WritePly(const std::filesystem::path& path, const PointCloud& cloud,
              const PlyWriteOptions& options) {
    cloud.Validate();
    VertexColumns c;
    c.points = &cloud.points;
    c.normals = IfPresent(cloud.normals);
    c.colors = IfPresent(cloud.colors);
    c.alpha = AnyTranslucent(cloud.colors);
    c.labels = IfPresent(cloud.labels);
    c.intensity = IfPresent(cloud.intensity);
    c.confidence = IfPresent(cloud.confidence);
    c.curvature = IfPresent(cloud.curvature);
    for (const auto& f : cloud.extra_fields) {
        const auto t = ExtraScalarType(f);
        const bool bad_name = f.name.empty() || IsReservedVertexName(f.name) ||
                              std::any_of(f.name.begin(), f.name.end(), IsSpace);
        if (f.count != 1 || !t || bad_name) {
            LogWarning(
                "{}: extra field '{}' ({}{} x {}) cannot be written as a PLY property; "
                "skipped",
                path.string(), f.name, f.type, f.size, f.count);
            continue;
        }
        c.extras.emplace_back(&f, *t);
    }
    const std::string header = VertexHeader(c, options.encoding) + "end_header\n";
    WriteFileAtomically(path, [&](std::ostream& out) {
        out.write(header.data(), static_cast<std::streamsize>(header.size()));
        BodyWriter w(out, options.encoding);
        WriteVertexRows(w, c);
        w.Flush();
    });
}

void WritePlyMesh(const std::filesystem::path& path, const TriangleMesh& mesh,
                  const PlyWriteOptions& options) {
    mesh.Validate();
    if (mesh.vertices.size() > static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max())) {
        throw DataError(fmt::format("{}: {} vertices do not fit PLY int vertex indices",
                                    path.string(), mesh.vertices.size()));
    }
    VertexColumns c;
    c.points = &mesh.vertices;
    c.normals = IfPresent(mesh.vertex_normals);
    c.colors = IfPresent(mesh.vertex_colors);
    c.alpha = AnyTranslucent(mesh.vertex_colors);
    c.labels = IfPresent(mesh.vertex_labels);
    const std::string header =
        VertexHeader(c, options.encoding) +
        fmt::format("element face {}\nproperty list uchar int vertex_indices\nend_header\n",
                    mesh.triangles.size());
    WriteFileAtomically(path, [&](std::ostream& out) {
        out.write(header.data(), static_cast<std::streamsize>(header.size()));
        BodyWriter w(out, options.encoding);
        WriteVertexRows(w, c);
        for (const Triangle& t : mesh.triangles) {
            w.Put(std::uint8_t{3});
            for (int k = 0; k < 3; ++k) w.Put(static_cast<std::int32_t>(t[k]));
            w.EndRow();
        }
        w.Flush();
    });
}

}  // namespace multicue::io

#include "multicue/io/point_cloud2.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <set>
#include <type_traits>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"

namespace multicue::io {
namespace {

using Byte = std::uint8_t;

/// Reverses the bytes of an unsigned integer (std::byteswap is C++23).
template <typename T>
T ByteSwap(T v) {
    T r = 0;
    for (std::size_t k = 0; k < sizeof(T); ++k)
        r = static_cast<T>((r << 8) | ((v >> (8 * k)) & 0xffu));
    return r;
}

/// Reads one element of `datatype` at `p` (message byte order `swap`) as T.
template <typename T>
T ReadElement(const Byte* p, std::uint8_t datatype, bool swap) {
    Byte b[8];
    const std::size_t size = PointFieldTypeSize(datatype);
    if (swap) {
        for (std::size_t k = 0; k < size; ++k) b[k] = p[size - 1 - k];
    } else {
        std::memcpy(b, p, size);
    }
    const auto as = [&](auto v) {
        std::memcpy(&v, b, sizeof(v));
        return static_cast<T>(v);
    };
    switch (static_cast<PointFieldType>(datatype)) {
        case PointFieldType::kInt8:
            return as(std::int8_t{});
        case PointFieldType::kUInt8:
            return as(std::uint8_t{});
        case PointFieldType::kInt16:
            return as(std::int16_t{});
        case PointFieldType::kUInt16:
            return as(std::uint16_t{});
        case PointFieldType::kInt32:
            return as(std::int32_t{});
        case PointFieldType::kUInt32:
            return as(std::uint32_t{});
        case PointFieldType::kFloat32:
            return as(float{});
        case PointFieldType::kFloat64:
            return as(double{});
    }
    return T{};
}

/// The raw 4 bytes of a packed colour as a uint32 in machine order.
std::uint32_t ReadPacked(const Byte* p, bool swap) {
    std::uint32_t v;
    std::memcpy(&v, p, 4);
    return swap ? ByteSwap(v) : v;
}

/// PCD-style type letter of an extra field.
char TypeLetter(std::uint8_t datatype) {
    switch (static_cast<PointFieldType>(datatype)) {
        case PointFieldType::kFloat32:
        case PointFieldType::kFloat64:
            return 'F';
        case PointFieldType::kInt8:
        case PointFieldType::kInt16:
        case PointFieldType::kInt32:
            return 'I';
        default:
            return 'U';
    }
}

std::uint8_t DatatypeOf(char type, std::uint8_t size) {
    using T = PointFieldType;
    T t = T::kFloat32;
    if (type == 'F') {
        t = size == 8 ? T::kFloat64 : T::kFloat32;
    } else if (type == 'I') {
        t = size == 1 ? T::kInt8 : size == 2 ? T::kInt16 : T::kInt32;
    } else {
        t = size == 1 ? T::kUInt8 : size == 2 ? T::kUInt16 : T::kUInt32;
    }
    return static_cast<std::uint8_t>(t);
}

/// Checks the layout against the data; throws FormatError naming `source`.
void CheckLayout(const PointCloud2Message& m, const std::string& source) {
    std::set<std::string> names;
    for (const auto& f : m.fields) {
        const std::size_t size = PointFieldTypeSize(f.datatype);
        if (size == 0) {
            throw FormatError(
                fmt::format("{}: field '{}' has unknown datatype {}", source, f.name, f.datatype));
        }
        const std::size_t end = f.offset + size * std::max<std::uint32_t>(f.count, 1);
        if (end > m.point_step) {
            throw FormatError(fmt::format(
                "{}: field '{}' (offset {}, {} x {} bytes) ends beyond point_step {}", source,
                f.name, f.offset, std::max<std::uint32_t>(f.count, 1), size, m.point_step));
        }
        if (!f.name.empty() && !names.insert(f.name).second) {
            throw FormatError(fmt::format("{}: field '{}' appears twice", source, f.name));
        }
    }
    const std::uint64_t row_bytes = std::uint64_t{m.point_step} * m.width;
    if (m.height > 0 && m.width > 0 && row_bytes > m.row_step) {
        throw FormatError(fmt::format("{}: row_step {} is less than width {} x point_step {}",
                                      source, m.row_step, m.width, m.point_step));
    }
    // The last row needs only its points, not the padding after them.
    const std::uint64_t needed =
        m.height == 0 || m.width == 0 ? 0 : std::uint64_t{m.row_step} * (m.height - 1) + row_bytes;
    if (m.data.size() < needed) {
        throw FormatError(fmt::format(
            "{}: data truncated: {} bytes, the layout ({} x {} points, row_step {}) needs {}",
            source, m.data.size(), m.width, m.height, m.row_step, needed));
    }
}

}  // namespace

std::size_t PointFieldTypeSize(std::uint8_t datatype) {
    switch (datatype) {
        case 1:
        case 2:
            return 1;
        case 3:
        case 4:
            return 2;
        case 5:
        case 6:
        case 7:
            return 4;
        case 8:
            return 8;
        default:
            return 0;
    }
}

MessageStamp MessageStamp::FromNanoseconds(std::int64_t ns) {
    std::int64_t sec = ns / 1000000000LL;
    std::int64_t rest = ns % 1000000000LL;
    if (rest < 0) {
        rest += 1000000000LL;
        --sec;
    }
    return MessageStamp{sec, static_cast<std::uint32_t>(rest)};
}

std::string MessageStamp::ToString() const { return fmt::format("{}.{:09d}", sec, nanosec); }

const PointField* PointCloud2Message::FindField(const std::string& name) const {
    for (const auto& f : fields) {
        if (f.name == name) return &f;
    }
    return nullptr;
}

namespace {

/// Reads the points of a checked message field by field; remembers the fields it used.
struct MessageReader {
    const PointCloud2Message& m;
    const std::string& source;
    bool swap = false;
    std::size_t n = 0;
    std::set<const PointField*> used;

    MessageReader(const PointCloud2Message& message, const std::string& source_name)
        : m(message),
          source(source_name),
          swap(message.is_bigendian != (std::endian::native == std::endian::big)),
          n(std::size_t{message.width} * message.height) {}

    const Byte* Point(std::size_t i) const {
        return m.data.data() + (i / m.width) * std::size_t{m.row_step} +
               (i % m.width) * std::size_t{m.point_step};
    }
    /// The field `name` holding one element per point, nullptr otherwise.
    const PointField* Single(const char* name) const {
        const PointField* f = m.FindField(name);
        return f != nullptr && f->count <= 1 ? f : nullptr;
    }
    bool Vec3(std::vector<Eigen::Vector3f>& out, const char* a, const char* b, const char* c) {
        const PointField* fa = Single(a);
        const PointField* fb = Single(b);
        const PointField* fc = Single(c);
        if (fa == nullptr || fb == nullptr || fc == nullptr) return false;
        out.resize(n);
        for (std::size_t i = 0; i < n; ++i) {
            const Byte* p = Point(i);
            out[i] = {ReadElement<float>(p + fa->offset, fa->datatype, swap),
                      ReadElement<float>(p + fb->offset, fb->datatype, swap),
                      ReadElement<float>(p + fc->offset, fc->datatype, swap)};
        }
        used.insert({fa, fb, fc});
        return true;
    }
    template <typename T>
    void Scalar(const char* name, std::vector<T>& out) {
        const PointField* f = Single(name);
        if (f == nullptr) return;
        out.resize(n);
        const auto type = static_cast<PointFieldType>(f->datatype);
        if (std::is_integral_v<T> &&
            (type == PointFieldType::kFloat32 || type == PointFieldType::kFloat64)) {
            // A floating-point field read as integers: each value must fit the integer type.
            const double lo = static_cast<double>(std::numeric_limits<T>::lowest()) - 1.0;
            const double hi = static_cast<double>(std::numeric_limits<T>::max()) + 1.0;
            for (std::size_t i = 0; i < n; ++i) {
                const double v = ReadElement<double>(Point(i) + f->offset, f->datatype, swap);
                if (!(v > lo && v < hi)) {
                    throw FormatError(fmt::format(
                        "{}: field '{}' of point {} holds {}, which is no {}-bit integer value",
                        source, name, i, v, 8 * sizeof(T)));
                }
                out[i] = static_cast<T>(v);
            }
        } else {
            for (std::size_t i = 0; i < n; ++i)
                out[i] = ReadElement<T>(Point(i) + f->offset, f->datatype, swap);
        }
        used.insert(f);
    }
    /// Packed rgb/rgba (4 bytes whatever the datatype says: PCL declares rgb float32, rgba
    /// uint32), else separate r, g, b channels (0..255 for integers, 0..1 for floats).
    void Colours(std::vector<Color>& out) {
        const PointField* rgb = Single("rgb");
        const PointField* rgba = Single("rgba");
        const PointField* packed = nullptr;
        if (rgb != nullptr && PointFieldTypeSize(rgb->datatype) == 4) {
            packed = rgb;
        } else if (rgba != nullptr && PointFieldTypeSize(rgba->datatype) == 4) {
            packed = rgba;
        }
        if (packed != nullptr) {
            out.resize(n);
            for (std::size_t i = 0; i < n; ++i) {
                Color c = UnpackRgba(ReadPacked(Point(i) + packed->offset, swap));
                if (packed == rgb && c.a == 0) c.a = 255;  // older writers leave rgb's alpha 0
                out[i] = c;
            }
            used.insert(packed);
            return;
        }
        const PointField* r = Single("r");
        const PointField* g = Single("g");
        const PointField* b = Single("b");
        if (r == nullptr || g == nullptr || b == nullptr) return;
        const auto channel = [&](const PointField* f, const Byte* p) {
            const double v = ReadElement<double>(p + f->offset, f->datatype, swap);
            const bool unit = f->datatype == static_cast<std::uint8_t>(PointFieldType::kFloat32) ||
                              f->datatype == static_cast<std::uint8_t>(PointFieldType::kFloat64);
            const double scaled = unit ? v * 255.0 : v;
            return static_cast<std::uint8_t>(
                std::clamp(std::isfinite(scaled) ? scaled : 0.0, 0.0, 255.0));
        };
        out.resize(n);
        for (std::size_t i = 0; i < n; ++i) {
            const Byte* p = Point(i);
            out[i] = Color{channel(r, p), channel(g, p), channel(b, p), 255};
        }
        used.insert({r, g, b});
    }
    /// Every field not used so far, byte-swapped to the machine's order.
    void Extras(std::vector<ExtraField>& out) const {
        for (const auto& f : m.fields) {
            if (used.count(&f) != 0 || f.name.empty() || f.name == "_") continue;
            const std::size_t size = PointFieldTypeSize(f.datatype);
            ExtraField e{f.name,
                         TypeLetter(f.datatype),
                         static_cast<std::uint8_t>(size),
                         std::max<std::uint32_t>(f.count, 1),
                         {}};
            e.data.resize(n * e.BytesPerPoint());
            for (std::size_t i = 0; i < n; ++i) {
                const Byte* src = Point(i) + f.offset;
                Byte* dst = e.data.data() + i * e.BytesPerPoint();
                for (std::uint32_t k = 0; k < e.count; ++k) {
                    for (std::size_t b = 0; b < size; ++b)
                        dst[k * size + b] = swap ? src[k * size + size - 1 - b] : src[k * size + b];
                }
            }
            out.push_back(std::move(e));
        }
    }
};

}  // namespace

PointCloud FromPointCloud2(const PointCloud2Message& m, const std::string& source) {
    CheckLayout(m, source);
    MessageReader reader(m, source);
    PointCloud cloud;
    if (!reader.Vec3(cloud.points, "x", "y", "z")) {
        std::string names;
        for (const auto& f : m.fields) names += (names.empty() ? "" : " ") + f.name;
        throw FormatError(fmt::format("{}: no x/y/z fields (fields: {})", source,
                                      names.empty() ? "none" : names));
    }
    reader.Vec3(cloud.normals, "normal_x", "normal_y", "normal_z");
    reader.Scalar("curvature", cloud.curvature);
    reader.Scalar("intensity", cloud.intensity);
    reader.Scalar("confidence", cloud.confidence);
    reader.Scalar("label", cloud.labels);
    reader.Colours(cloud.colors);
    reader.Extras(cloud.extra_fields);
    cloud.width = m.width;
    cloud.height = m.height;
    if (m.height <= 1 || reader.n == 0) cloud.SetUnorganized();
    return cloud;
}

void PointCloud2Params::Validate() const {
    if (point_alignment == 0 || point_alignment > 64) {
        throw InvalidArgument(
            fmt::format("point_alignment must be in [1, 64] bytes, got {}", point_alignment));
    }
}

PointCloud2Message ToPointCloud2(const PointCloud& cloud, const PointCloud2Params& params) {
    params.Validate();
    cloud.Validate();
    PointCloud2Message m;
    m.is_bigendian = params.big_endian;
    const auto add = [&](const std::string& name, PointFieldType type, std::uint32_t count = 1) {
        const std::uint32_t size =
            static_cast<std::uint32_t>(PointFieldTypeSize(static_cast<std::uint8_t>(type)));
        // Elements aligned to their size inside the point, as C structs (and PCL) lay them out.
        m.point_step = (m.point_step + size - 1) / size * size;
        m.fields.push_back({name, m.point_step, static_cast<std::uint8_t>(type), count});
        m.point_step += size * count;
    };
    using T = PointFieldType;
    for (const char* name : {"x", "y", "z"}) add(name, T::kFloat32);
    if (cloud.HasNormals()) {
        for (const char* name : {"normal_x", "normal_y", "normal_z"}) add(name, T::kFloat32);
    }
    if (cloud.HasCurvature()) add("curvature", T::kFloat32);
    if (cloud.HasColors())
        add(params.rgba ? "rgba" : "rgb", params.rgba ? T::kUInt32 : T::kFloat32);
    if (cloud.HasIntensity()) add("intensity", T::kFloat32);
    if (cloud.HasConfidence()) add("confidence", T::kFloat32);
    if (cloud.HasLabels()) add("label", T::kUInt32);
    for (const auto& e : cloud.extra_fields) {
        const std::uint8_t type = DatatypeOf(e.type, e.size);
        if (PointFieldTypeSize(type) != e.size) {
            throw InvalidArgument(
                fmt::format("extra field '{}': {} {}-byte elements have no PointField datatype",
                            e.name, e.type, e.size));
        }
        add(e.name, static_cast<T>(type), e.count);
    }
    const std::uint32_t align = params.point_alignment;
    m.point_step = (m.point_step + align - 1) / align * align;

    const std::size_t n = cloud.size();
    m.height = cloud.IsOrganized() ? cloud.height : 1;
    m.width = cloud.IsOrganized() ? cloud.width : static_cast<std::uint32_t>(n);
    m.row_step = m.point_step * m.width;
    m.data.assign(n * m.point_step, 0);
    const bool swap = params.big_endian != (std::endian::native == std::endian::big);
    const auto put = [&](std::size_t i, std::size_t field, const void* value, std::size_t size) {
        Byte* dst = m.data.data() + i * m.point_step + m.fields[field].offset;
        const Byte* src = static_cast<const Byte*>(value);
        for (std::size_t b = 0; b < size; ++b) dst[b] = swap ? src[size - 1 - b] : src[b];
    };
    bool dense = true;
    for (std::size_t i = 0; i < n; ++i) {
        std::size_t f = 0;
        for (int k = 0; k < 3; ++k) put(i, f++, &cloud.points[i][k], 4);
        dense = dense && cloud.points[i].allFinite();
        if (cloud.HasNormals()) {
            for (int k = 0; k < 3; ++k) put(i, f++, &cloud.normals[i][k], 4);
        }
        if (cloud.HasCurvature()) put(i, f++, &cloud.curvature[i], 4);
        if (cloud.HasColors()) {
            const std::uint32_t packed = PackRgba(cloud.colors[i]);
            put(i, f++, &packed, 4);
        }
        if (cloud.HasIntensity()) put(i, f++, &cloud.intensity[i], 4);
        if (cloud.HasConfidence()) put(i, f++, &cloud.confidence[i], 4);
        if (cloud.HasLabels()) put(i, f++, &cloud.labels[i], 4);
        for (const auto& e : cloud.extra_fields) {
            const Byte* src = e.data.data() + i * e.BytesPerPoint();
            for (std::uint32_t k = 0; k < e.count; ++k) {
                Byte* dst = m.data.data() + i * m.point_step + m.fields[f].offset + k * e.size;
                for (std::size_t b = 0; b < e.size; ++b)
                    dst[b] = swap ? src[k * e.size + e.size - 1 - b] : src[k * e.size + b];
            }
            ++f;
        }
    }
    m.is_dense = dense;
    return m;
}

}  // namespace multicue::io

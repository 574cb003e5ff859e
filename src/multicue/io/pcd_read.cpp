#include "multicue/io/pcd.hpp"

#include <lzf.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/core/logging.hpp"
#include "multicue/io/file_utils.hpp"
#include "multicue/io/pcd_internal.hpp"

namespace multicue::io {
namespace {

using detail::Byte;
using detail::CopyStrided;
using detail::Scalar;
using detail::ScalarOf;
using detail::VisitScalar;

/// Where a PCD field goes in a PointCloud (kX ... kConfidence are float vectors).
enum class Target : std::uint8_t {
    kX,
    kY,
    kZ,
    kNormalX,
    kNormalY,
    kNormalZ,
    kCurvature,
    kIntensity,
    kConfidence,
    kRgb,
    kRgba,
    kLabel,
    kExtra,
    kPadding
};

struct PcdField {
    std::string name;
    char type = 'F';
    std::uint8_t size = 4;
    std::uint32_t count = 1;
    Scalar scalar = Scalar::kF32;
    Target target = Target::kExtra;
    std::size_t Bytes() const { return std::size_t{size} * count; }
};

struct PcdHeader {
    std::vector<PcdField> fields;
    std::size_t point_size = 0;   ///< bytes per binary record, '_' padding included
    std::size_t packed_size = 0;  ///< bytes per point without padding (compressed layout)
    std::uint32_t width = 0;
    std::uint32_t height = 1;
    std::size_t points = 0;
    Eigen::Vector3f origin = Eigen::Vector3f::Zero();
    Eigen::Quaternionf orientation = Eigen::Quaternionf::Identity();
    PcdEncoding encoding = PcdEncoding::kAscii;
    std::size_t data_offset = 0;  ///< first byte after the DATA line
    std::size_t data_line = 0;    ///< line number of the DATA line
};

bool IsBlank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

/// Splits at blanks into `out` (reused between calls to avoid allocations).
void Tokenize(std::string_view line, std::vector<std::string_view>& out) {
    out.clear();
    std::size_t i = 0;
    while (i < line.size()) {
        while (i < line.size() && IsBlank(line[i])) ++i;
        const std::size_t start = i;
        while (i < line.size() && !IsBlank(line[i])) ++i;
        if (i > start) out.push_back(line.substr(start, i - start));
    }
}

bool EqualsNoCase(std::string_view a, std::string_view b) {
    if (a.size() != b.size()) return false;
    for (std::size_t i = 0; i < a.size(); ++i) {
        const auto lower = [](char c) { return c >= 'A' && c <= 'Z' ? char(c - 'A' + 'a') : c; };
        if (lower(a[i]) != lower(b[i])) return false;
    }
    return true;
}

template <typename T>
bool ParseNumber(std::string_view s, T& value) {
    if (!s.empty() && s.front() == '+') s.remove_prefix(1);
    const char* end = s.data() + s.size();
    auto [ptr, ec] = std::from_chars(s.data(), end, value);
    if constexpr (std::is_floating_point_v<T>) {
        if (ec == std::errc::result_out_of_range && ptr == end) {
            // Beyond the type's range: round to 0 or infinity by the exponent's sign, as strtod
            // does.
            const std::size_t e = s.find_first_of("eE");
            const bool tiny = e != std::string_view::npos && e + 1 < s.size() && s[e + 1] == '-';
            const T magnitude = tiny ? T{0} : std::numeric_limits<T>::infinity();
            value = s.front() == '-' ? -magnitude : magnitude;
            return true;
        }
    } else if (ec != std::errc() || ptr != end) {
        // Integers written with a fraction ("3.0") by some tools.
        double d = 0;
        auto [p2, ec2] = std::from_chars(s.data(), end, d);
        if (ec2 != std::errc() || p2 != end || d != std::floor(d) ||
            d < static_cast<double>(std::numeric_limits<T>::lowest()) ||
            d > static_cast<double>(std::numeric_limits<T>::max())) {
            return false;
        }
        value = static_cast<T>(d);
        return true;
    }
    return ec == std::errc() && ptr == end;
}

/// Converts a stored value to the destination type; out-of-range floats become 0 for integers.
template <typename Dst, typename Src>
Dst CastValue(Src v) {
    if constexpr (std::is_integral_v<Dst> && std::is_floating_point_v<Src>) {
        const double limit = static_cast<double>(std::numeric_limits<Dst>::max()) + 1.0;
        return v >= 0 && static_cast<double>(v) < limit ? static_cast<Dst>(v) : Dst{0};
    } else {
        return static_cast<Dst>(v);
    }
}

/// dst[i*dst_stride] = Dst(src[i*src_stride]) for n values of the field's scalar type.
template <typename Dst>
void ConvertField(Scalar scalar, const Byte* src, std::size_t src_stride, Byte* dst,
                  std::size_t dst_stride, std::size_t n) {
    VisitScalar(scalar, [&](auto tag) {
        using Src = decltype(tag);
        for (std::size_t i = 0; i < n; ++i) {
            Src v;
            std::memcpy(&v, src + i * src_stride, sizeof(Src));
            const Dst d = CastValue<Dst>(v);
            std::memcpy(dst + i * dst_stride, &d, sizeof(Dst));
        }
    });
}

// ------------------------------------------------------------------------------------- header

template <typename T>
T HeaderNumber(std::string_view token, std::string_view keyword, std::size_t line,
               const std::string& file) {
    T value{};
    if (!ParseNumber(token, value)) {
        throw FormatError(
            fmt::format("{}: line {}: bad {} value '{}'", file, line, keyword, token));
    }
    return value;
}

/// Assigns each field its destination; fields that do not fit a PointCloud vector become extras.
void AssignTargets(std::vector<PcdField>& fields, const std::string& file) {
    const auto find = [&](std::string_view name) -> PcdField* {
        for (auto& f : fields) {
            if (f.name == name && f.target == Target::kExtra) return &f;
        }
        return nullptr;
    };
    for (auto& f : fields) {
        if (f.name == "_") f.target = Target::kPadding;
    }
    const auto claim = [&](std::string_view name, Target target) {
        PcdField* f = find(name);
        if (f != nullptr && f->count == 1) f->target = target;
        return f != nullptr && f->count == 1;
    };
    if (!claim("x", Target::kX) || !claim("y", Target::kY) || !claim("z", Target::kZ)) {
        std::string names;
        for (const auto& f : fields) names += (names.empty() ? "" : " ") + f.name;
        throw FormatError(fmt::format("{}: no x/y/z fields (FIELDS {})", file, names));
    }
    PcdField* nx = find("normal_x");
    PcdField* ny = find("normal_y");
    PcdField* nz = find("normal_z");
    if (nx && ny && nz && nx->count == 1 && ny->count == 1 && nz->count == 1) {
        nx->target = Target::kNormalX;
        ny->target = Target::kNormalY;
        nz->target = Target::kNormalZ;
    }
    claim("curvature", Target::kCurvature);
    claim("intensity", Target::kIntensity);
    claim("confidence", Target::kConfidence);
    claim("label", Target::kLabel);
    // Colours are packed in 4 bytes, whatever TYPE says (PCL declares rgb as F 4, rgba as U 4).
    PcdField* rgb = find("rgb");
    PcdField* rgba = find("rgba");
    if (rgb && rgb->count == 1 && rgb->size == 4) {
        rgb->target = Target::kRgb;
    } else if (rgba && rgba->count == 1 && rgba->size == 4) {
        rgba->target = Target::kRgba;
    }
}

/// The header's lines as read, before they are checked against each other: PCD allows the
/// keywords in any order, so the field lists can only be matched once DATA is reached.
struct HeaderLines {
    std::vector<std::string_view> names, sizes, types, counts;
    bool have_fields = false, have_size = false, have_type = false, have_count = false;
    std::optional<std::uint32_t> width, height;
    std::optional<std::uint64_t> points;
    bool have_data = false;
};

/// Control bytes in a header line mean a binary file, not a PCD header.
void CheckHeaderBytes(std::string_view line, std::size_t line_no, const std::string& file) {
    for (char c : line) {
        if ((static_cast<unsigned char>(c) < 0x20 && !IsBlank(c)) || c == 0x7f) {
            throw FormatError(fmt::format(
                "{}: line {}: binary bytes in the header (not a PCD file?)", file, line_no));
        }
    }
}

/// VIEWPOINT: the sensor origin (3 values) and orientation (a quaternion w x y z).
void ReadViewpoint(const std::vector<std::string_view>& values, std::string_view key,
                   std::size_t line_no, const std::string& file, PcdHeader& h) {
    if (values.size() != 7) {
        throw FormatError(fmt::format("{}: line {}: VIEWPOINT needs 7 values, got {}", file,
                                      line_no, values.size()));
    }
    float v[7];
    for (int i = 0; i < 7; ++i) v[i] = HeaderNumber<float>(values[i], key, line_no, file);
    h.origin = {v[0], v[1], v[2]};
    h.orientation = Eigen::Quaternionf(v[3], v[4], v[5], v[6]);
}

/// DATA's encoding, by name in any case.
PcdEncoding ParseEncoding(std::string_view enc, std::size_t line_no, const std::string& file) {
    if (EqualsNoCase(enc, "ascii")) return PcdEncoding::kAscii;
    if (EqualsNoCase(enc, "binary")) return PcdEncoding::kBinary;
    if (EqualsNoCase(enc, "binary_compressed")) return PcdEncoding::kBinaryCompressed;
    throw FormatError(
        fmt::format("{}: line {}: unknown DATA encoding '{}' (expected ascii, binary or "
                    "binary_compressed)",
                    file, line_no, enc));
}

/// One header line's keyword and values. `pos` is the offset after the line (where DATA's
/// records begin); an unknown keyword is an error on the first line (not a PCD file) and where a
/// number stands for it (point data after a missing DATA line), else a warning.
void ReadKeyword(std::string_view key, const std::vector<std::string_view>& values,
                 std::size_t line_no, std::size_t pos, bool seen_keyword, const std::string& file,
                 HeaderLines& lines, PcdHeader& h) {
    const auto single = [&]() {
        if (values.size() != 1) {
            throw FormatError(fmt::format("{}: line {}: {} needs one value, got {}", file, line_no,
                                          key, values.size()));
        }
        return values.front();
    };
    if (EqualsNoCase(key, "VERSION")) {
        // .5, .6, 0.7 and others are read alike; the layout rules below cover them all.
    } else if (EqualsNoCase(key, "FIELDS") || EqualsNoCase(key, "COLUMNS")) {
        lines.names = values;
        lines.have_fields = true;
    } else if (EqualsNoCase(key, "SIZE")) {
        lines.sizes = values;
        lines.have_size = true;
    } else if (EqualsNoCase(key, "TYPE")) {
        lines.types = values;
        lines.have_type = true;
    } else if (EqualsNoCase(key, "COUNT")) {
        lines.counts = values;
        lines.have_count = true;
    } else if (EqualsNoCase(key, "WIDTH")) {
        lines.width = HeaderNumber<std::uint32_t>(single(), key, line_no, file);
    } else if (EqualsNoCase(key, "HEIGHT")) {
        lines.height = HeaderNumber<std::uint32_t>(single(), key, line_no, file);
    } else if (EqualsNoCase(key, "POINTS")) {
        lines.points = HeaderNumber<std::uint64_t>(single(), key, line_no, file);
    } else if (EqualsNoCase(key, "VIEWPOINT")) {
        ReadViewpoint(values, key, line_no, file, h);
    } else if (EqualsNoCase(key, "DATA")) {
        h.encoding = ParseEncoding(single(), line_no, file);
        lines.have_data = true;
        h.data_offset = pos;
        h.data_line = line_no;
    } else if (!seen_keyword) {
        throw FormatError(fmt::format("{}: line {}: unknown header keyword '{}' (not a PCD file?)",
                                      file, line_no, key));
    } else if (!std::isalpha(static_cast<unsigned char>(key.front()))) {
        // Numbers where a keyword belongs: point data follows a missing or mangled DATA line.
        throw FormatError(fmt::format("{}: line {}: '{}' in the header (no DATA line before it?)",
                                      file, line_no, key));
    } else {
        LogWarning("{}: line {}: ignoring unknown header keyword '{}'", file, line_no, key);
    }
}

/// The header's lines up to and including DATA (comments after '#' and blank lines skipped);
/// sets the viewpoint, the encoding and where the data begin in `h`.
HeaderLines ReadHeaderLines(std::string_view bytes, const std::string& file, PcdHeader& h) {
    HeaderLines lines;
    std::vector<std::string_view> tokens;
    bool seen_keyword = false;
    std::size_t pos = 0, line_no = 0;
    while (pos < bytes.size() && !lines.have_data) {
        const std::size_t eol = bytes.find('\n', pos);
        const std::size_t end = eol == std::string_view::npos ? bytes.size() : eol;
        std::string_view line = bytes.substr(pos, end - pos);
        pos = eol == std::string_view::npos ? bytes.size() : eol + 1;
        ++line_no;
        CheckHeaderBytes(line, line_no, file);
        if (const std::size_t hash = line.find('#'); hash != std::string_view::npos) {
            line = line.substr(0, hash);
        }
        Tokenize(line, tokens);
        if (tokens.empty()) continue;
        const std::string_view key = tokens.front();
        const auto values = std::vector<std::string_view>(tokens.begin() + 1, tokens.end());
        ReadKeyword(key, values, line_no, pos, seen_keyword, file, lines, h);
        seen_keyword = true;
    }
    return lines;
}

/// DATA, FIELDS, SIZE and TYPE must be there, and every field list as long as FIELDS.
void CheckFieldLists(const HeaderLines& lines, const std::string& file) {
    if (!lines.have_data) {
        throw FormatError(fmt::format("{}: header has no DATA line (not a PCD file?)", file));
    }
    if (!lines.have_fields || lines.names.empty())
        throw FormatError(fmt::format("{}: header has no FIELDS", file));
    if (!lines.have_size) throw FormatError(fmt::format("{}: header has no SIZE line", file));
    if (!lines.have_type) throw FormatError(fmt::format("{}: header has no TYPE line", file));
    const auto check_count = [&](const std::vector<std::string_view>& v, const char* key) {
        if (v.size() != lines.names.size()) {
            throw FormatError(
                fmt::format("{}: header field count mismatch: FIELDS has {} entries, {} has {}",
                            file, lines.names.size(), key, v.size()));
        }
    };
    check_count(lines.sizes, "SIZE");
    check_count(lines.types, "TYPE");
    if (lines.have_count) check_count(lines.counts, "COUNT");
}

/// Field i of the lists: its name, scalar type (TYPE letters of either case) and count.
PcdField ParseField(const HeaderLines& lines, std::size_t i, const std::string& file) {
    PcdField f;
    f.name = std::string(lines.names[i]);
    const auto field_number = [&](std::string_view token, const char* key) {
        std::uint32_t v = 0;
        if (!ParseNumber(token, v)) {
            throw FormatError(
                fmt::format("{}: field '{}' has bad {} '{}'", file, f.name, key, token));
        }
        return v;
    };
    const std::uint32_t size = field_number(lines.sizes[i], "SIZE");
    if (lines.types[i].size() != 1) {
        throw FormatError(
            fmt::format("{}: field '{}' has bad TYPE '{}'", file, f.name, lines.types[i]));
    }
    f.type = lines.types[i].front();
    if (f.type >= 'a' && f.type <= 'z') f.type = static_cast<char>(f.type - 'a' + 'A');
    const auto scalar = ScalarOf(f.type, size);
    if (!scalar) {
        throw FormatError(fmt::format("{}: field '{}' has unsupported TYPE/SIZE combination {} {}",
                                      file, f.name, lines.types[i], lines.sizes[i]));
    }
    f.scalar = *scalar;
    f.size = static_cast<std::uint8_t>(size);
    f.count = lines.have_count ? field_number(lines.counts[i], "COUNT") : 1;
    if (f.count == 0) throw FormatError(fmt::format("{}: field '{}' has COUNT 0", file, f.name));
    return f;
}

/// The cloud's size from WIDTH, HEIGHT and POINTS. PCD v0.6 files may lack POINTS; very old ones
/// WIDTH/HEIGHT (PCL then takes POINTS as width).
void SetDimensions(const HeaderLines& lines, const std::string& file, PcdHeader& h) {
    const auto& width = lines.width;
    const auto& points = lines.points;
    if (!width && !points) {
        throw FormatError(fmt::format("{}: header has neither WIDTH nor POINTS", file));
    }
    if (!width && *points > std::numeric_limits<std::uint32_t>::max()) {
        throw FormatError(fmt::format("{}: POINTS {} without WIDTH is too large", file, *points));
    }
    h.height = lines.height.value_or(1);
    h.width = width ? *width : static_cast<std::uint32_t>(*points);
    const std::uint64_t wh = std::uint64_t{h.width} * h.height;
    if (points && *points != wh) {
        throw FormatError(fmt::format("{}: POINTS {} does not match WIDTH*HEIGHT = {}x{} = {}",
                                      file, *points, h.width, h.height, wh));
    }
    if (wh > std::numeric_limits<std::size_t>::max() / std::max<std::size_t>(h.point_size, 1)) {
        throw FormatError(fmt::format("{}: {} points are too many", file, wh));
    }
    h.points = static_cast<std::size_t>(wh);
    if (h.points == 0) {
        // PCL writes empty clouds as WIDTH 0 HEIGHT 0; an empty PointCloud is 0x1.
        h.width = 0;
        h.height = 1;
    }
}

PcdHeader ParseHeader(std::string_view bytes, const std::string& file) {
    PcdHeader h;
    const HeaderLines lines = ReadHeaderLines(bytes, file, h);
    CheckFieldLists(lines, file);
    for (std::size_t i = 0; i < lines.names.size(); ++i) {
        PcdField f = ParseField(lines, i, file);
        h.point_size += f.Bytes();
        if (f.name != "_") h.packed_size += f.Bytes();
        h.fields.push_back(std::move(f));
    }
    AssignTargets(h.fields, file);
    SetDimensions(lines, file, h);
    return h;
}

// ------------------------------------------------------------------------------------- reading

/// Parses ascii DATA into binary records of the header's layout without '_' padding, so that one
/// decoder serves all encodings.
std::vector<Byte> ParseAscii(std::string_view data, const PcdHeader& h, const std::string& file) {
    const std::size_t n = h.points;
    std::size_t values = 0, values_with_padding = 0;
    for (const auto& f : h.fields) {
        values_with_padding += f.count;
        if (f.target != Target::kPadding) values += f.count;
    }
    // A point takes at least two bytes (a value and a line end): a header that claims more points
    // than the data could ever hold is refused before anything is read. A count that is merely
    // too large is found line by line below, with the line where the data end.
    if (const std::size_t most = (data.size() + 1) / 2; n > most) {
        throw FormatError(fmt::format(
            "{}: DATA section truncated: {} points claimed, {} bytes of data hold at most {}", file,
            n, data.size(), most));
    }
    std::vector<Byte> records;
    records.reserve(std::min(n, data.size() / (2 * values) + 1) * h.packed_size);
    std::vector<std::string_view> tokens;
    std::size_t pos = 0, line_no = h.data_line, point = 0;
    while (point < n && pos < data.size()) {
        const std::size_t eol = data.find('\n', pos);
        const std::size_t end = eol == std::string_view::npos ? data.size() : eol;
        const std::string_view line = data.substr(pos, end - pos);
        pos = eol == std::string_view::npos ? data.size() : eol + 1;
        ++line_no;
        Tokenize(line, tokens);
        if (tokens.empty()) continue;
        const bool with_padding = tokens.size() == values_with_padding;
        if (tokens.size() != values && !with_padding) {
            throw FormatError(fmt::format("{}: line {}: expected {} values, got {}", file, line_no,
                                          values, tokens.size()));
        }
        records.resize((point + 1) * h.packed_size);
        Byte* record = records.data() + point * h.packed_size;
        std::size_t t = 0;
        for (const auto& f : h.fields) {
            if (f.target == Target::kPadding) {
                if (with_padding) t += f.count;
                continue;
            }
            for (std::uint32_t e = 0; e < f.count; ++e, ++t) {
                const std::string_view tok = tokens[t];
                Byte* dst = record + std::size_t{e} * f.size;
                bool ok = true;
                if ((f.target == Target::kRgb || f.target == Target::kRgba) && f.type == 'F' &&
                    tok.find_first_not_of("0123456789") == std::string_view::npos) {
                    // PCL writes the packed colour of an F 4 rgb field as an unsigned integer
                    // (as a float, opaque colours would print as nan).
                    std::uint32_t packed = 0;
                    ok = ParseNumber(tok, packed);
                    std::memcpy(dst, &packed, 4);
                } else {
                    VisitScalar(f.scalar, [&](auto tag) {
                        decltype(tag) v{};
                        ok = ParseNumber(tok, v);
                        std::memcpy(dst, &v, sizeof(v));
                    });
                }
                if (!ok) {
                    throw FormatError(
                        fmt::format("{}: line {}: cannot parse '{}' as {} {} (field '{}')", file,
                                    line_no, tok, f.type, f.size, f.name));
                }
            }
            record += f.Bytes();
        }
        ++point;
    }
    if (point < n) {
        throw FormatError(
            fmt::format("{}: DATA section truncated: expected {} points, got {}", file, n, point));
    }
    return records;
}

/// Base pointer and stride of each field's values: records (one point after the other) or
/// planes (all values of one field, then the next field); '_' padding included only if `padded`.
struct FieldSource {
    const Byte* base = nullptr;
    std::size_t stride = 0;
};

std::vector<FieldSource> RecordSources(const PcdHeader& h, const Byte* data, bool padded) {
    std::vector<FieldSource> s;
    std::size_t offset = 0;
    for (const auto& f : h.fields) {
        s.push_back(
            {h.points > 0 ? data + offset : nullptr, padded ? h.point_size : h.packed_size});
        if (padded || f.target != Target::kPadding) offset += f.Bytes();
    }
    return s;
}

std::vector<FieldSource> PlaneSources(const PcdHeader& h, const Byte* data, bool padded) {
    std::vector<FieldSource> s;
    std::size_t offset = 0;
    for (const auto& f : h.fields) {
        s.push_back({h.points > 0 ? data + offset : nullptr, f.Bytes()});
        if (padded || f.target != Target::kPadding) offset += f.Bytes() * h.points;
    }
    return s;
}

PointCloud Decode(const PcdHeader& h, const std::vector<FieldSource>& sources,
                  const std::string& file) {
    const std::size_t n = h.points;
    PointCloud cloud;
    cloud.width = h.width;
    cloud.height = h.height;
    cloud.sensor_origin = h.origin;
    cloud.sensor_orientation = h.orientation;
    cloud.points.resize(n);
    std::string extra_names;
    for (std::size_t j = 0; j < h.fields.size(); ++j) {
        const PcdField& f = h.fields[j];
        const FieldSource& src = sources[j];
        const auto to_floats = [&](Byte* dst, std::size_t dst_stride) {
            ConvertField<float>(f.scalar, src.base, src.stride, dst, dst_stride, n);
        };
        const auto float_vector = [&](std::vector<float>& v) {
            v.resize(n);
            to_floats(reinterpret_cast<Byte*>(v.data()), sizeof(float));
        };
        const auto coordinate = [&](std::vector<Eigen::Vector3f>& v, int k) {
            v.resize(n);
            if (n == 0) return;  // data() may be null: no offset from it
            to_floats(reinterpret_cast<Byte*>(v.data()) + k * sizeof(float),
                      sizeof(Eigen::Vector3f));
        };
        switch (f.target) {
            case Target::kX:
                coordinate(cloud.points, 0);
                break;
            case Target::kY:
                coordinate(cloud.points, 1);
                break;
            case Target::kZ:
                coordinate(cloud.points, 2);
                break;
            case Target::kNormalX:
                coordinate(cloud.normals, 0);
                break;
            case Target::kNormalY:
                coordinate(cloud.normals, 1);
                break;
            case Target::kNormalZ:
                coordinate(cloud.normals, 2);
                break;
            case Target::kCurvature:
                float_vector(cloud.curvature);
                break;
            case Target::kIntensity:
                float_vector(cloud.intensity);
                break;
            case Target::kConfidence:
                float_vector(cloud.confidence);
                break;
            case Target::kLabel:
                cloud.labels.resize(n);
                ConvertField<std::uint32_t>(f.scalar, src.base, src.stride,
                                            reinterpret_cast<Byte*>(cloud.labels.data()),
                                            sizeof(std::uint32_t), n);
                break;
            case Target::kRgb:
            case Target::kRgba: {
                cloud.colors.resize(n);
                // PCL packs a<<24|r<<16|g<<8|b. Files from older PCL versions and other tools
                // leave the alpha byte of "rgb" at 0 and mean an opaque colour, so alpha 0 reads
                // as 255 there; "rgba" keeps its alpha.
                const bool opaque_if_zero = f.target == Target::kRgb;
                for (std::size_t i = 0; i < n; ++i) {
                    std::uint32_t packed;
                    std::memcpy(&packed, src.base + i * src.stride, 4);
                    Color c = UnpackRgba(packed);
                    if (opaque_if_zero && c.a == 0) c.a = 255;
                    cloud.colors[i] = c;
                }
                break;
            }
            case Target::kExtra: {
                ExtraField e{f.name, f.type, f.size, f.count, {}};
                e.data.resize(n * f.Bytes());
                CopyStrided(src.base, src.stride, e.data.data(), f.Bytes(), f.Bytes(), n);
                cloud.extra_fields.push_back(std::move(e));
                extra_names += (extra_names.empty() ? "'" : ", '") + f.name + "'";
                break;
            }
            case Target::kPadding:
                break;
        }
    }
    if (!extra_names.empty()) LogDebug("{}: keeping fields {} as extra fields", file, extra_names);
    return cloud;
}

PointCloud DecodeCompressed(const PcdHeader& h, std::string_view data, const std::string& file) {
    const std::size_t n = h.points;
    if (data.size() < 8) {
        if (n == 0 && data.empty()) return Decode(h, PlaneSources(h, nullptr, false), file);
        throw FormatError(
            fmt::format("{}: DATA section truncated: expected 8 bytes of compressed sizes, got {}",
                        file, data.size()));
    }
    std::uint32_t compressed = 0, uncompressed = 0;
    std::memcpy(&compressed, data.data(), 4);
    std::memcpy(&uncompressed, data.data() + 4, 4);
    // PCL leaves '_' padding out of compressed data; accept it included as well.
    const std::size_t packed = n * h.packed_size, padded = n * h.point_size;
    if (uncompressed != packed && uncompressed != padded) {
        throw FormatError(fmt::format(
            "{}: corrupt compressed header: uncompressed size {} != {} points x {} bytes = {}",
            file, uncompressed, n, h.packed_size, packed));
    }
    if (compressed > data.size() - 8) {
        throw FormatError(
            fmt::format("{}: DATA section truncated: expected {} bytes of compressed data, got {}",
                        file, compressed, data.size() - 8));
    }
    if (uncompressed == 0) return Decode(h, PlaneSources(h, nullptr, false), file);
    // An LZF back reference of 3 bytes expands to at most 264 bytes: anything beyond that ratio
    // is corrupt, and is rejected before allocating.
    if (compressed == 0 || uncompressed / 88 > compressed) {
        throw FormatError(
            fmt::format("{}: corrupt compressed header: {} compressed bytes cannot hold {} bytes",
                        file, compressed, uncompressed));
    }
    // The decompressed planes live only until they are scattered into the cloud. Reusing one
    // buffer per thread matters: faulting in fresh pages for a 640x480 scan costs about as much
    // CPU time as decompressing it. Buffers beyond kMaxKeptScratch are not kept.
    constexpr std::size_t kMaxKeptScratch = std::size_t{64} << 20;
    thread_local std::vector<Byte> scratch;
    std::vector<Byte> large;
    std::vector<Byte>& planes = uncompressed <= kMaxKeptScratch ? scratch : large;
    planes.resize(uncompressed);
    const unsigned got = lzf_decompress(data.data() + 8, compressed, planes.data(), uncompressed);
    if (got != uncompressed) {
        throw FormatError(
            fmt::format("{}: corrupt compressed data: decompressed {} bytes, expected {}", file,
                        got, uncompressed));
    }
    return Decode(h, PlaneSources(h, planes.data(), uncompressed != packed), file);
}

}  // namespace

PointCloud ReadPcd(const std::filesystem::path& path) {
    const std::string file = path.string();
    const std::string bytes = ReadFileBytes(path);
    const PcdHeader h = ParseHeader(bytes, file);
    const std::string_view data = std::string_view(bytes).substr(h.data_offset);
    const std::size_t n = h.points;
    PointCloud cloud;
    switch (h.encoding) {
        case PcdEncoding::kAscii: {
            const std::vector<Byte> records = ParseAscii(data, h, file);
            cloud = Decode(h, RecordSources(h, records.data(), false), file);
            break;
        }
        case PcdEncoding::kBinary: {
            if (data.size() < n * h.point_size) {
                throw FormatError(
                    fmt::format("{}: DATA section truncated: expected {} bytes, got {}", file,
                                n * h.point_size, data.size()));
            }
            const auto* records = reinterpret_cast<const Byte*>(data.data());
            cloud = Decode(h, RecordSources(h, records, true), file);
            break;
        }
        case PcdEncoding::kBinaryCompressed:
            cloud = DecodeCompressed(h, data, file);
            break;
    }
    cloud.Validate();
    return cloud;
}

}  // namespace multicue::io

#include "multicue/io/ply.hpp"

#include <algorithm>
#include <bit>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/core/logging.hpp"
#include "multicue/io/file_utils.hpp"
#include "multicue/io/ply_internal.hpp"

namespace multicue::io {
namespace {

using detail::IsFloat;
using detail::IsSpace;
using detail::MakeExtraField;
using detail::ScalarType;
using detail::SizeOf;
using detail::TypeName;
using detail::WithType;

// ---------------------------------------------------------------------------------------------
// Types and header

/// Both the classic names (char, uchar, ...) and the sized ones (int8, uint8, ...) are in use.
std::optional<ScalarType> ParseTypeName(std::string_view s) {
    static constexpr std::pair<std::string_view, ScalarType> kNames[] = {
        {"char", ScalarType::kInt8},      {"int8", ScalarType::kInt8},
        {"uchar", ScalarType::kUint8},    {"uint8", ScalarType::kUint8},
        {"short", ScalarType::kInt16},    {"int16", ScalarType::kInt16},
        {"ushort", ScalarType::kUint16},  {"uint16", ScalarType::kUint16},
        {"int", ScalarType::kInt32},      {"int32", ScalarType::kInt32},
        {"uint", ScalarType::kUint32},    {"uint32", ScalarType::kUint32},
        {"float", ScalarType::kFloat32},  {"float32", ScalarType::kFloat32},
        {"double", ScalarType::kFloat64}, {"float64", ScalarType::kFloat64},
    };
    for (const auto& [name, type] : kNames) {
        if (name == s) return type;
    }
    return std::nullopt;
}

enum class PlyFormat { kAscii, kBinaryLittleEndian, kBinaryBigEndian };

struct PlyProperty {
    std::string name;
    ScalarType type = ScalarType::kFloat32;  ///< item type for lists
    bool is_list = false;
    ScalarType count_type = ScalarType::kUint8;
};

struct PlyElement {
    std::string name;
    std::size_t count = 0;
    std::vector<PlyProperty> properties;

    int Find(std::string_view property) const {
        for (std::size_t i = 0; i < properties.size(); ++i) {
            if (properties[i].name == property) return static_cast<int>(i);
        }
        return -1;
    }
    /// Smallest number of data bytes one row can take (lists empty; ascii: "0 " per value).
    std::size_t MinRowBytes(PlyFormat format) const {
        std::size_t bytes = 0;
        for (const auto& p : properties) {
            if (format == PlyFormat::kAscii) {
                bytes += 2;
            } else {
                bytes += SizeOf(p.is_list ? p.count_type : p.type);
            }
        }
        return bytes;
    }
};

struct PlyHeader {
    PlyFormat format = PlyFormat::kAscii;
    std::vector<PlyElement> elements;
    std::size_t data_offset = 0;  ///< first byte after the end_header line
    std::size_t lines = 0;        ///< number of header lines (ascii data starts on lines + 1)
};

std::vector<std::string_view> SplitWords(std::string_view line) {
    std::vector<std::string_view> words;
    std::size_t i = 0;
    while (i < line.size()) {
        while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
        const std::size_t start = i;
        while (i < line.size() && line[i] != ' ' && line[i] != '\t') ++i;
        if (i > start) words.push_back(line.substr(start, i - start));
    }
    return words;
}

PlyProperty ParsePropertyLine(const std::vector<std::string_view>& w, const std::string& where) {
    PlyProperty p;
    std::size_t used = 0;
    if (w.size() >= 2 && w[1] == "list") {
        if (w.size() < 5) throw FormatError(where + "incomplete list property");
        const auto count_type = ParseTypeName(w[2]);
        const auto item_type = ParseTypeName(w[3]);
        if (!count_type) throw FormatError(fmt::format("{}unknown type '{}'", where, w[2]));
        if (!item_type) throw FormatError(fmt::format("{}unknown type '{}'", where, w[3]));
        if (IsFloat(*count_type)) {
            throw FormatError(
                fmt::format("{}list count type '{}' is not an integer type", where, w[2]));
        }
        p = PlyProperty{std::string(w[4]), *item_type, true, *count_type};
        used = 5;
    } else {
        if (w.size() < 3) throw FormatError(where + "incomplete property");
        if (const auto t = ParseTypeName(w[1])) {
            p = PlyProperty{std::string(w[2]), *t, false, ScalarType::kUint8};
        } else if (const auto t2 = ParseTypeName(w[2])) {
            // "property <name> <type>": the order used by some old Stanford files (the material
            // element of bun_zipper.ply).
            p = PlyProperty{std::string(w[1]), *t2, false, ScalarType::kUint8};
        } else {
            throw FormatError(fmt::format("{}unknown type '{}'", where, w[1]));
        }
        used = 3;
    }
    // Old files annotate properties with "{ comment }" after the name; nothing else may follow.
    if (w.size() > used && w[used].front() != '{') {
        throw FormatError(
            fmt::format("{}unexpected '{}' after property '{}'", where, w[used], p.name));
    }
    return p;
}

PlyHeader ParseHeader(std::string_view bytes, const std::string& file) {
    PlyHeader h;
    std::size_t pos = 0;
    std::size_t line_no = 0;
    bool have_format = false;
    bool ended = false;
    while (pos < bytes.size()) {
        const std::size_t nl = bytes.find('\n', pos);
        const std::size_t end = nl == std::string_view::npos ? bytes.size() : nl;
        std::string_view line = bytes.substr(pos, end - pos);
        pos = nl == std::string_view::npos ? bytes.size() : nl + 1;
        ++line_no;
        if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
        if (line_no == 1) {
            if (SplitWords(line) != std::vector<std::string_view>{"ply"}) {
                throw FormatError(file + ": not a PLY file (first line is not 'ply')");
            }
            continue;
        }
        const auto w = SplitWords(line);
        if (w.empty()) continue;
        const std::string where = fmt::format("{}: line {}: ", file, line_no);
        if (w[0] == "comment" || w[0] == "obj_info") continue;
        if (w[0] == "end_header") {
            ended = true;
            break;
        }
        if (w[0] == "format") {
            if (w.size() != 3) throw FormatError(where + "expected 'format <encoding> 1.0'");
            if (w[1] == "ascii") {
                h.format = PlyFormat::kAscii;
            } else if (w[1] == "binary_little_endian") {
                h.format = PlyFormat::kBinaryLittleEndian;
            } else if (w[1] == "binary_big_endian") {
                h.format = PlyFormat::kBinaryBigEndian;
            } else {
                throw FormatError(fmt::format("{}unknown format '{}'", where, w[1]));
            }
            if (w[2] != "1.0") {
                throw FormatError(fmt::format("{}unsupported PLY version '{}'", where, w[2]));
            }
            have_format = true;
        } else if (w[0] == "element") {
            if (w.size() != 3) throw FormatError(where + "expected 'element <name> <count>'");
            std::uint64_t count = 0;
            const auto r = std::from_chars(w[2].data(), w[2].data() + w[2].size(), count);
            if (r.ec != std::errc() || r.ptr != w[2].data() + w[2].size()) {
                throw FormatError(fmt::format("{}bad element count '{}'", where, w[2]));
            }
            h.elements.push_back(
                PlyElement{std::string(w[1]), static_cast<std::size_t>(count), {}});
        } else if (w[0] == "property") {
            if (h.elements.empty()) throw FormatError(where + "property before any element");
            h.elements.back().properties.push_back(ParsePropertyLine(w, where));
        } else {
            const bool data = !std::isalpha(static_cast<unsigned char>(w[0].front()));
            throw FormatError(
                fmt::format("{}{} '{}'", where,
                            data ? "data before end_header" : "unknown header keyword", w[0]));
        }
    }
    if (!ended) throw FormatError(file + ": header has no end_header line");
    if (!have_format) throw FormatError(file + ": header has no format line");
    h.data_offset = pos;
    h.lines = line_no;

    // Reject absurd counts before anything is allocated for them.
    const std::size_t available = bytes.size() - pos;
    std::size_t needed = 0;
    for (const auto& e : h.elements) {
        const std::size_t row = e.MinRowBytes(h.format);
        if (row != 0 && e.count > (available + 1) / row) {
            throw FormatError(fmt::format(
                "{}: data is truncated: element '{}' announces {} rows but only {} bytes of data "
                "follow the header",
                file, e.name, e.count, available));
        }
        needed += row * e.count;
    }
    if (needed > available + 1) {
        throw FormatError(fmt::format(
            "{}: data is truncated: the header announces at least {} bytes but only {} follow",
            file, needed, available));
    }
    return h;
}

// ---------------------------------------------------------------------------------------------
// Data readers. Both expose Scalar (any value as double, exact for every PLY type), Count (a list
// length), Skip and Where (a prefix locating the last value in error messages).

class BinaryReader {
  public:
    BinaryReader(std::string_view data, bool swap, const std::string& file)
        : data_(data), swap_(swap), file_(file) {}

    void SetContext(const PlyElement* element, std::size_t row) {
        element_ = element;
        row_ = row;
    }

    double Scalar(ScalarType t) {
        const char* p = Take(SizeOf(t));
        return WithType(t, [&](auto v) { return static_cast<double>(Load<decltype(v)>(p)); });
    }

    std::int64_t Count(ScalarType t) { return static_cast<std::int64_t>(Scalar(t)); }

    void Skip(ScalarType t, std::size_t n) {
        if (n > (data_.size() - pos_) / SizeOf(t)) Truncated();
        pos_ += n * SizeOf(t);
    }

    /// Skips `rows` rows of fixed size `row_bytes`.
    void SkipRows(std::size_t rows, std::size_t row_bytes) {
        if (row_bytes != 0 && rows > (data_.size() - pos_) / row_bytes) Truncated();
        pos_ += rows * row_bytes;
    }

    std::string Where() const { return {}; }

  private:
    template <typename T>
    T Load(const char* p) const {
        T v;
        if (swap_) {
            char tmp[sizeof(T)];
            for (std::size_t i = 0; i < sizeof(T); ++i) tmp[i] = p[sizeof(T) - 1 - i];
            std::memcpy(&v, tmp, sizeof(T));
        } else {
            std::memcpy(&v, p, sizeof(T));
        }
        return v;
    }

    const char* Take(std::size_t n) {
        if (data_.size() - pos_ < n) Truncated();
        const char* p = data_.data() + pos_;
        pos_ += n;
        return p;
    }

    [[noreturn]] void Truncated() const {
        throw FormatError(fmt::format("{}: data is truncated in element '{}' (row {} of {})", file_,
                                      element_ ? element_->name : "", row_,
                                      element_ ? element_->count : 0));
    }

    std::string_view data_;
    std::size_t pos_ = 0;
    bool swap_ = false;
    const std::string& file_;
    const PlyElement* element_ = nullptr;
    std::size_t row_ = 0;
};

/// Parses a whole token as T with std::from_chars; a leading '+' is allowed.
template <typename T>
bool ParseWhole(std::string_view tok, T& value) {
    if (!tok.empty() && tok.front() == '+') tok.remove_prefix(1);
    const char* end = tok.data() + tok.size();
    const auto r = std::from_chars(tok.data(), end, value);
    if (r.ptr != end || tok.empty()) return false;
    if (r.ec == std::errc()) return true;
    if constexpr (std::is_floating_point_v<T>) {
        if (r.ec == std::errc::result_out_of_range) {
            // Underflow to zero or overflow to infinity, as strtod does.
            const std::string copy(tok);
            value = static_cast<T>(std::strtod(copy.c_str(), nullptr));
            return true;
        }
    }
    return false;
}

class AsciiReader {
  public:
    AsciiReader(std::string_view data, std::size_t first_line, const std::string& file)
        : data_(data), line_(first_line), file_(file) {}

    /// Called before each row. Rows are lines: a value left on the previous row's line means the
    /// row had more values than its element has properties.
    void SetContext(const PlyElement* element, std::size_t row) {
        if (pos_ > 0) {
            while (pos_ < data_.size() &&
                   (data_[pos_] == ' ' || data_[pos_] == '\t' || data_[pos_] == '\r')) {
                ++pos_;
            }
            if (pos_ < data_.size() && data_[pos_] != '\n') {
                throw FormatError(
                    fmt::format("{}: line {}: more values than element '{}' has properties", file_,
                                line_, element_ ? element_->name : ""));
            }
        }
        element_ = element;
        row_ = row;
    }

    double Scalar(ScalarType t) {
        const std::string_view tok = Token();
        if (t == ScalarType::kFloat32) {
            float f = 0.0f;  // parsed as float directly: no double rounding
            if (!ParseWhole(tok, f)) Bad(tok, t);
            return f;
        }
        if (t == ScalarType::kFloat64) {
            double d = 0.0;
            if (!ParseWhole(tok, d)) Bad(tok, t);
            return d;
        }
        std::int64_t i = 0;
        if (!ParseWhole(tok, i)) {
            // Some writers print integers as "3.0".
            double d = 0.0;
            if (!ParseWhole(tok, d) || d != std::floor(d) || std::abs(d) > 1e18) Bad(tok, t);
            i = static_cast<std::int64_t>(d);
        }
        const auto [lo, hi] = IntegerRange(t);
        if (i < lo || i > hi) Bad(tok, t);
        return static_cast<double>(i);
    }

    std::int64_t Count(ScalarType t) { return static_cast<std::int64_t>(Scalar(t)); }

    void Skip(ScalarType /*t*/, std::size_t n) {
        for (std::size_t i = 0; i < n; ++i) Token();
    }

    std::string Where() const { return fmt::format("line {}: ", token_line_); }

  private:
    static std::pair<std::int64_t, std::int64_t> IntegerRange(ScalarType t) {
        return WithType(t, [](auto v) {
            using T = decltype(v);
            if constexpr (std::is_floating_point_v<T>)
                return std::pair<std::int64_t, std::int64_t>{};
            return std::pair<std::int64_t, std::int64_t>{
                static_cast<std::int64_t>(std::numeric_limits<T>::lowest()),
                static_cast<std::int64_t>(std::numeric_limits<T>::max())};
        });
    }

    std::string_view Token() {
        while (pos_ < data_.size() && IsSpace(data_[pos_])) {
            if (data_[pos_] == '\n') ++line_;
            ++pos_;
        }
        if (pos_ >= data_.size()) {
            throw FormatError(fmt::format("{}: data is truncated in element '{}' (row {} of {})",
                                          file_, element_ ? element_->name : "", row_,
                                          element_ ? element_->count : 0));
        }
        const std::size_t start = pos_;
        while (pos_ < data_.size() && !IsSpace(data_[pos_])) ++pos_;
        token_line_ = line_;
        return data_.substr(start, pos_ - start);
    }

    [[noreturn]] void Bad(std::string_view tok, ScalarType t) const {
        throw FormatError(fmt::format("{}: line {}: bad {} value '{}' in element '{}'", file_,
                                      token_line_, TypeName(t), tok,
                                      element_ ? element_->name : ""));
    }

    std::string_view data_;
    std::size_t pos_ = 0;
    std::size_t line_ = 1;
    std::size_t token_line_ = 1;
    const std::string& file_;
    const PlyElement* element_ = nullptr;
    std::size_t row_ = 0;
};

/// Skips one property value (a scalar, or a list with its count).
template <typename Reader>
void SkipValue(Reader& r, bool is_list, ScalarType count_type, ScalarType type) {
    if (is_list) {
        const std::int64_t n = r.Count(count_type);
        r.Skip(type, n > 0 ? static_cast<std::size_t>(n) : 0);
    } else {
        r.Skip(type, 1);
    }
}

template <typename Reader>
void SkipElement(Reader& r, const PlyElement& e) {
    if constexpr (std::is_same_v<Reader, BinaryReader>) {
        const bool fixed = std::none_of(e.properties.begin(), e.properties.end(),
                                        [](const PlyProperty& p) { return p.is_list; });
        if (fixed) {
            r.SetContext(&e, 0);
            r.SkipRows(e.count, e.MinRowBytes(PlyFormat::kBinaryLittleEndian));
            return;
        }
    }
    for (std::size_t row = 0; row < e.count; ++row) {
        r.SetContext(&e, row);
        for (const auto& p : e.properties) SkipValue(r, p.is_list, p.count_type, p.type);
    }
}

// ---------------------------------------------------------------------------------------------
// Reader plan for the vertex element: one step per property, saying where its value goes.

enum class Target : std::uint8_t {
    kSkip,
    kPoint,
    kNormal,
    kColor,
    kPackedRgb,
    kPackedRgba,
    kLabel,
    kFloat,
    kExtra,
};

struct Step {
    Target target = Target::kSkip;
    ScalarType type = ScalarType::kFloat32;
    bool is_list = false;
    ScalarType count_type = ScalarType::kUint8;
    int axis = 0;                                      ///< kPoint, kNormal: coordinate
    std::uint8_t Color::*channel = &Color::r;          ///< kColor
    std::vector<float> PointCloud::*floats = nullptr;  ///< kFloat
    std::uint32_t extra = 0;                           ///< kExtra: index into extras
};

struct VertexPlan {
    std::vector<Step> steps;
    std::vector<ExtraField> extras;  ///< one per kExtra step, data not yet allocated
    std::vector<std::string> skipped_lists;
};

VertexPlan MakeVertexPlan(const PlyElement& e, bool keep_extras, const std::string& file) {
    VertexPlan plan;
    for (const auto& p : e.properties) {
        plan.steps.push_back(
            Step{.type = p.type, .is_list = p.is_list, .count_type = p.count_type});
    }
    // The step of scalar property `name` if it is present and not yet assigned.
    auto find = [&](std::string_view name) -> Step* {
        const int i = e.Find(name);
        if (i < 0) return nullptr;
        Step& s = plan.steps[static_cast<std::size_t>(i)];
        return s.is_list || s.target != Target::kSkip ? nullptr : &s;
    };
    // Assigns three properties as one vector, only if all three are there.
    auto assign_vector = [&](std::string_view a, std::string_view b, std::string_view c,
                             Target target) {
        Step* s[3] = {find(a), find(b), find(c)};
        if (!s[0] || !s[1] || !s[2]) return false;
        for (int k = 0; k < 3; ++k) {
            s[k]->target = target;
            s[k]->axis = k;
        }
        return true;
    };

    for (const char* axis : {"x", "y", "z"}) {
        const int i = e.Find(axis);
        if (i < 0) {
            throw FormatError(fmt::format("{}: vertex element has no '{}' property", file, axis));
        }
        if (e.properties[static_cast<std::size_t>(i)].is_list) {
            throw FormatError(fmt::format("{}: vertex property '{}' is a list", file, axis));
        }
    }
    assign_vector("x", "y", "z", Target::kPoint);
    if (!assign_vector("nx", "ny", "nz", Target::kNormal)) {
        assign_vector("normal_x", "normal_y", "normal_z", Target::kNormal);
    }

    struct ColourNames {
        std::string_view r, g, b, a;
    };
    static constexpr ColourNames kColourSets[] = {
        {"red", "green", "blue", "alpha"},
        {"r", "g", "b", "a"},
        {"diffuse_red", "diffuse_green", "diffuse_blue", "diffuse_alpha"},
    };
    bool colors = false;
    for (const auto& set : kColourSets) {
        Step* s[4] = {find(set.r), find(set.g), find(set.b), find(set.a)};
        if (!s[0] || !s[1] || !s[2]) continue;
        std::uint8_t Color::*const channels[4] = {&Color::r, &Color::g, &Color::b, &Color::a};
        for (int k = 0; k < 4; ++k) {
            if (!s[k]) continue;
            s[k]->target = Target::kColor;
            s[k]->channel = channels[k];
        }
        colors = true;
        break;
    }
    // Otherwise a colour packed as PCL does in its `rgb` / `rgba` fields (a<<24 | r<<16 | g<<8 |
    // b).
    for (const auto& [name, target] :
         {std::pair{"rgba", Target::kPackedRgba}, std::pair{"rgb", Target::kPackedRgb}}) {
        Step* s = colors ? nullptr : find(name);
        if (s && (s->type == ScalarType::kFloat32 || s->type == ScalarType::kUint32 ||
                  s->type == ScalarType::kInt32)) {
            s->target = target;
            colors = true;
        }
    }

    if (Step* s = find("label")) s->target = Target::kLabel;
    for (const auto& [name, member] : {std::pair{"intensity", &PointCloud::intensity},
                                       std::pair{"confidence", &PointCloud::confidence},
                                       std::pair{"curvature", &PointCloud::curvature}}) {
        if (Step* s = find(name)) {
            s->target = Target::kFloat;
            s->floats = member;
        }
    }

    if (!keep_extras) return plan;
    for (std::size_t i = 0; i < e.properties.size(); ++i) {
        Step& s = plan.steps[i];
        if (s.target != Target::kSkip) continue;
        if (s.is_list) {
            plan.skipped_lists.push_back(e.properties[i].name);
            continue;
        }
        s.target = Target::kExtra;
        s.extra = static_cast<std::uint32_t>(plan.extras.size());
        plan.extras.push_back(MakeExtraField(e.properties[i].name, s.type));
    }
    return plan;
}

std::uint8_t ToColorChannel(double v, ScalarType t) {
    if (IsFloat(t)) v *= 255.0;                // float colours are 0..1
    if (t == ScalarType::kUint16) v /= 257.0;  // 16-bit colours are 0..65535
    if (!(v > 0.0)) return 0;                  // also NaN
    if (v >= 255.0) return 255;
    return static_cast<std::uint8_t>(std::lround(v));
}

std::uint32_t PackedBits(double v, ScalarType t) {
    if (t == ScalarType::kFloat32) return std::bit_cast<std::uint32_t>(static_cast<float>(v));
    return static_cast<std::uint32_t>(static_cast<std::int64_t>(v));
}

/// Stores `v` (exactly representable in `t`, as every value read is) in the bytes of type `t`.
void StoreScalar(std::uint8_t* dst, ScalarType t, double v) {
    WithType(t, [&](auto tag) {
        const auto x = static_cast<decltype(tag)>(v);
        std::memcpy(dst, &x, sizeof(x));
    });
}

std::uint32_t ToLabel(double v) {
    if (!std::isfinite(v)) return 0;
    return static_cast<std::uint32_t>(static_cast<std::int64_t>(v));
}

template <typename Reader>
void ReadVertices(Reader& r, const PlyElement& e, VertexPlan& plan, PointCloud& cloud) {
    const std::size_t n = e.count;
    auto allocate = [n](auto& field, auto value) {
        if (field.size() != n) field.assign(n, value);
    };
    allocate(cloud.points, Eigen::Vector3f::Zero().eval());
    for (const Step& s : plan.steps) {
        if (s.target == Target::kNormal) allocate(cloud.normals, Eigen::Vector3f::Zero().eval());
        if (s.target == Target::kColor || s.target == Target::kPackedRgb ||
            s.target == Target::kPackedRgba) {
            allocate(cloud.colors, Color{});  // opaque unless there is an alpha
        }
        if (s.target == Target::kLabel) allocate(cloud.labels, std::uint32_t{0});
        if (s.target == Target::kFloat) allocate(cloud.*s.floats, 0.0f);
    }
    for (auto& f : plan.extras) f.data.assign(n * f.BytesPerPoint(), 0);

    for (std::size_t i = 0; i < n; ++i) {
        r.SetContext(&e, i);
        for (const Step& s : plan.steps) {
            if (s.is_list || s.target == Target::kSkip) {
                SkipValue(r, s.is_list, s.count_type, s.type);
                continue;
            }
            const double v = r.Scalar(s.type);
            switch (s.target) {
                case Target::kPoint:
                    cloud.points[i][s.axis] = static_cast<float>(v);
                    break;
                case Target::kNormal:
                    cloud.normals[i][s.axis] = static_cast<float>(v);
                    break;
                case Target::kColor:
                    cloud.colors[i].*s.channel = ToColorChannel(v, s.type);
                    break;
                case Target::kPackedRgb:
                case Target::kPackedRgba:
                    cloud.colors[i] = UnpackRgba(PackedBits(v, s.type));
                    if (s.target == Target::kPackedRgb) cloud.colors[i].a = 255;
                    break;
                case Target::kLabel:
                    cloud.labels[i] = ToLabel(v);
                    break;
                case Target::kFloat:
                    (cloud.*s.floats)[i] = static_cast<float>(v);
                    break;
                case Target::kExtra: {
                    ExtraField& f = plan.extras[s.extra];
                    StoreScalar(f.data.data() + i * f.size, s.type, v);
                    break;
                }
                case Target::kSkip:
                    break;
            }
        }
    }
    cloud.extra_fields = std::move(plan.extras);
    cloud.SetUnorganized();
}

template <typename Reader>
void ReadFaces(Reader& r, const PlyElement& e, std::size_t num_vertices,
               std::vector<Triangle>& triangles, const std::string& file) {
    int index_property = e.Find("vertex_indices");
    if (index_property < 0) index_property = e.Find("vertex_index");
    if (index_property < 0) {
        if (e.count == 0) return;
        throw FormatError(file + ": face element has no vertex_indices list");
    }
    if (!e.properties[static_cast<std::size_t>(index_property)].is_list) {
        throw FormatError(file + ": face property vertex_indices is not a list");
    }
    triangles.reserve(triangles.size() + e.count);
    std::vector<std::uint32_t> corners;
    std::size_t degenerate = 0;
    for (std::size_t row = 0; row < e.count; ++row) {
        r.SetContext(&e, row);
        for (std::size_t pi = 0; pi < e.properties.size(); ++pi) {
            const PlyProperty& p = e.properties[pi];
            if (static_cast<int>(pi) != index_property) {
                SkipValue(r, p.is_list, p.count_type, p.type);
                continue;
            }
            const std::int64_t k = r.Count(p.count_type);
            if (k < 0) {
                throw FormatError(fmt::format("{}: {}face {} has a negative vertex count {}", file,
                                              r.Where(), row, k));
            }
            corners.clear();
            for (std::int64_t j = 0; j < k; ++j) {
                const double v = r.Scalar(p.type);
                if (!(v >= 0.0) || v >= static_cast<double>(num_vertices) || v != std::floor(v)) {
                    throw FormatError(fmt::format("{}: {}face {} refers to vertex {} of {}", file,
                                                  r.Where(), row, v, num_vertices));
                }
                corners.push_back(static_cast<std::uint32_t>(v));
            }
            if (corners.size() < 3) {
                ++degenerate;
                continue;
            }
            for (std::size_t j = 1; j + 1 < corners.size(); ++j) {
                triangles.emplace_back(corners[0], corners[j], corners[j + 1]);
            }
        }
    }
    if (degenerate > 0) {
        LogWarning("{}: skipped {} faces with fewer than 3 vertices", file, degenerate);
    }
}

struct PlyContent {
    PointCloud cloud;
    std::vector<Triangle> triangles;
};

template <typename Reader>
PlyContent ReadBody(Reader& r, const PlyHeader& h, bool mesh, const std::string& file) {
    PlyContent out;
    const PlyElement* vertex = nullptr;
    const PlyElement* face = nullptr;
    for (const auto& e : h.elements) {
        if (e.name == "vertex" && !vertex) vertex = &e;
        if (e.name == "face" && !face) face = &e;
    }
    if (!vertex) throw FormatError(file + ": no vertex element");
    VertexPlan plan = MakeVertexPlan(*vertex, !mesh, file);
    for (const auto& name : plan.skipped_lists) {
        LogWarning("{}: vertex list property '{}' is not kept", file, name);
    }
    bool vertices_done = false;
    bool faces_done = !mesh || !face;
    for (const auto& e : h.elements) {
        if (vertices_done && faces_done) break;  // the rest of the file is not needed
        if (&e == vertex) {
            ReadVertices(r, e, plan, out.cloud);
            vertices_done = true;
        } else if (&e == face && mesh) {
            ReadFaces(r, e, vertex->count, out.triangles, file);
            faces_done = true;
        } else {
            SkipElement(r, e);
        }
    }
    return out;
}

PlyContent ReadPlyFile(const std::filesystem::path& path, bool mesh) {
    const std::string file = path.string();
    const std::string bytes = ReadFileBytes(path);
    const PlyHeader h = ParseHeader(bytes, file);
    const std::string_view data = std::string_view(bytes).substr(h.data_offset);
    if (h.format == PlyFormat::kAscii) {
        AsciiReader r(data, h.lines + 1, file);
        return ReadBody(r, h, mesh, file);
    }
    const bool big = h.format == PlyFormat::kBinaryBigEndian;
    BinaryReader r(data, big != (std::endian::native == std::endian::big), file);
    return ReadBody(r, h, mesh, file);
}

}  // namespace

PointCloud ReadPly(const std::filesystem::path& path) { return ReadPlyFile(path, false).cloud; }

TriangleMesh ReadPlyMesh(const std::filesystem::path& path) {
    PlyContent content = ReadPlyFile(path, true);
    TriangleMesh mesh;
    mesh.vertices = std::move(content.cloud.points);
    mesh.vertex_normals = std::move(content.cloud.normals);
    mesh.vertex_colors = std::move(content.cloud.colors);
    mesh.vertex_labels = std::move(content.cloud.labels);
    mesh.triangles = std::move(content.triangles);
    return mesh;
}

}  // namespace multicue::io

#include "multicue/io/obj.hpp"

#include <array>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <string>
#include <string_view>
#include <unordered_map>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/core/logging.hpp"
#include "multicue/io/file_utils.hpp"

namespace multicue::io {
namespace {

void SplitWords(std::string_view line, std::vector<std::string_view>& words) {
    words.clear();
    std::size_t i = 0;
    while (i < line.size()) {
        while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
        const std::size_t start = i;
        while (i < line.size() && line[i] != ' ' && line[i] != '\t') ++i;
        if (i > start) words.push_back(line.substr(start, i - start));
    }
}

/// One face corner as written: 1-based or negative (relative) indices, 0 where absent.
struct RawCorner {
    std::int64_t v = 0;
    std::int64_t vn = 0;
};

class ObjParser {
  public:
    explicit ObjParser(std::string file) : file_(std::move(file)) {}

    ObjMesh Parse(std::string_view text) {
        std::size_t pos = 0;
        std::vector<std::string_view> words;
        while (pos < text.size()) {
            const std::size_t nl = text.find('\n', pos);
            const std::size_t end = nl == std::string_view::npos ? text.size() : nl;
            std::string_view line = text.substr(pos, end - pos);
            pos = end + 1;
            ++line_;
            if (const std::size_t hash = line.find('#'); hash != std::string_view::npos) {
                line = line.substr(0, hash);
            }
            if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
            SplitWords(line, words);
            if (!words.empty()) ParseLine(line, words);
        }
        return Finish();
    }

  private:
    [[noreturn]] void Fail(const std::string& problem) const {
        throw FormatError(fmt::format("{}: line {}: {}", file_, line_, problem));
    }

    float Number(std::string_view tok) const {
        std::string_view t = tok;
        if (!t.empty() && t.front() == '+') t.remove_prefix(1);
        float value = 0.0f;
        const char* end = t.data() + t.size();
        const auto r = std::from_chars(t.data(), end, value);
        if (t.empty() || r.ptr != end) Fail(fmt::format("bad number '{}'", tok));
        if (r.ec == std::errc::result_out_of_range) {
            value = std::strtof(std::string(t).c_str(), nullptr);
        } else if (r.ec != std::errc()) {
            Fail(fmt::format("bad number '{}'", tok));
        }
        return value;
    }

    std::int64_t Index(std::string_view tok, std::string_view corner) const {
        std::int64_t value = 0;
        const char* end = tok.data() + tok.size();
        const auto r = std::from_chars(tok.data(), end, value);
        if (tok.empty() || r.ptr != end || r.ec != std::errc()) {
            Fail(fmt::format("bad face corner '{}'", corner));
        }
        if (value == 0)
            Fail(fmt::format("index 0 in face corner '{}' (indices start at 1)", corner));
        return value;
    }

    void ParseLine(std::string_view line, const std::vector<std::string_view>& w) {
        const std::string_view key = w[0];
        if (key == "v") {
            ParseVertex(w);
        } else if (key == "vn") {
            if (w.size() != 4) Fail(fmt::format("vn needs 3 numbers, got {}", w.size() - 1));
            normals_.emplace_back(Number(w[1]), Number(w[2]), Number(w[3]));
        } else if (key == "f") {
            ParseFace(w);
        } else if (key == "o" || key == "g") {
            // The name is the rest of the line (g may list several names).
            std::string_view name = line.substr(line.find(key) + key.size());
            const std::size_t first = name.find_first_not_of(" \t");
            name = first == std::string_view::npos ? std::string_view{} : name.substr(first);
            name = name.substr(0, name.find_last_not_of(" \t") + 1);
            current_group_ = static_cast<std::int64_t>(GroupIndex(std::string(name)));
        } else if (key == "vt" || key == "vp" || key == "usemtl" || key == "mtllib" || key == "s" ||
                   key == "l" || key == "p") {
            // Texture coordinates, materials, smoothing groups, lines and points are not kept.
        } else {
            if (unknown_lines_ == 0) first_unknown_ = std::string(key);
            ++unknown_lines_;
        }
    }

    void ParseVertex(const std::vector<std::string_view>& w) {
        const std::size_t n = w.size() - 1;
        if (n != 3 && n != 4 && n != 6 && n != 7) {
            Fail(fmt::format("v needs 3, 4 (x y z w) or 6 (x y z r g b) numbers, got {}", n));
        }
        vertices_.emplace_back(Number(w[1]), Number(w[2]), Number(w[3]));
        if (n >= 6 && all_colored_) {
            colors_.push_back(
                {Number(w[4]), Number(w[5]), Number(w[6]), n == 7 ? Number(w[7]) : -1.0f});
        } else if (n < 6) {
            all_colored_ = false;
            colors_.clear();
        }
    }

    void ParseFace(const std::vector<std::string_view>& w) {
        if (w.size() < 4) Fail(fmt::format("face needs at least 3 vertices, got {}", w.size() - 1));
        corners_.clear();
        for (std::size_t k = 1; k < w.size(); ++k) {
            const std::string_view c = w[k];
            const std::size_t s1 = c.find('/');
            RawCorner rc;
            rc.v = Index(c.substr(0, s1), c);
            if (s1 != std::string_view::npos) {
                const std::size_t s2 = c.find('/', s1 + 1);
                const std::string_view vt = c.substr(
                    s1 + 1, s2 == std::string_view::npos ? std::string_view::npos : s2 - s1 - 1);
                if (!vt.empty()) Index(vt, c);  // validated, not kept
                if (s2 != std::string_view::npos) rc.vn = Index(c.substr(s2 + 1), c);
            }
            corners_.push_back(Resolve(rc));
        }
        if (current_group_ < 0) current_group_ = static_cast<std::int64_t>(GroupIndex(""));
        for (std::size_t k = 1; k + 1 < corners_.size(); ++k) {
            triangles_.emplace_back(corners_[0].first, corners_[k].first, corners_[k + 1].first);
            triangle_groups_.push_back(static_cast<std::uint32_t>(current_group_));
        }
        for (const auto& c : corners_) {
            if (c.second < 0) {
                all_corners_have_normals_ = false;
            } else if (all_corners_have_normals_) {
                corner_normals_.push_back(c);
            }
        }
    }

    /// Turns file indices into 0-based ones. Relative indices count back from the elements
    /// defined so far; positive ones may refer ahead and are checked at the end of the file.
    std::pair<std::uint32_t, std::int64_t> Resolve(const RawCorner& rc) {
        const auto one = [&](std::int64_t idx, std::size_t defined, const char* what,
                             std::int64_t& max_index, std::size_t& max_line) -> std::int64_t {
            if (idx < 0) {
                const std::int64_t r = static_cast<std::int64_t>(defined) + idx;
                if (r < 0) {
                    Fail(fmt::format("relative {} index {} with only {} defined so far", what, idx,
                                     defined));
                }
                return r;
            }
            if (idx > max_index) {
                max_index = idx;
                max_line = line_;
            }
            return idx - 1;
        };
        const std::int64_t v = one(rc.v, vertices_.size(), "vertex", max_v_, max_v_line_);
        if (v > std::numeric_limits<std::uint32_t>::max()) Fail("vertex index too large");
        std::int64_t vn = -1;
        if (rc.vn != 0) vn = one(rc.vn, normals_.size(), "normal", max_vn_, max_vn_line_);
        return {static_cast<std::uint32_t>(v), vn};
    }

    std::uint32_t GroupIndex(const std::string& name) {
        const auto [it, inserted] =
            group_index_.try_emplace(name, static_cast<std::uint32_t>(group_names_.size()));
        if (inserted) group_names_.push_back(name);
        return it->second;
    }

    ObjMesh Finish() {
        const std::size_t nv = vertices_.size();
        if (max_v_ > static_cast<std::int64_t>(nv)) {
            throw FormatError(fmt::format("{}: line {}: face refers to vertex {} of {}", file_,
                                          max_v_line_, max_v_, nv));
        }
        if (max_vn_ > static_cast<std::int64_t>(normals_.size())) {
            throw FormatError(fmt::format("{}: line {}: face refers to normal {} of {}", file_,
                                          max_vn_line_, max_vn_, normals_.size()));
        }
        if (unknown_lines_ > 0) {
            LogWarning("{}: ignored {} lines with unsupported keywords (first: '{}')", file_,
                       unknown_lines_, first_unknown_);
        }
        ObjMesh out;
        out.mesh.vertices = std::move(vertices_);
        out.mesh.triangles = std::move(triangles_);
        out.mesh.vertex_colors = ConvertColors();
        out.mesh.vertex_normals = AssignNormals(nv);
        out.group_names = std::move(group_names_);
        out.triangle_groups = std::move(triangle_groups_);
        return out;
    }

    /// Colours only when every v line has them; 0..1 floats, or 0..255 if any value exceeds 1.
    std::vector<Color> ConvertColors() const {
        std::vector<Color> out;
        if (!all_colored_ || colors_.empty()) return out;
        float max_value = 0.0f;
        for (const auto& c : colors_) {
            for (float x : c) max_value = std::max(max_value, x);
        }
        const float scale = max_value > 1.0f ? 1.0f : 255.0f;
        auto channel = [scale](float x) {
            const float s = x * scale;
            if (!(s > 0.0f)) return std::uint8_t{0};
            if (s >= 255.0f) return std::uint8_t{255};
            return static_cast<std::uint8_t>(std::lround(s));
        };
        out.reserve(colors_.size());
        for (const auto& c : colors_) {
            out.push_back(Color{channel(c[0]), channel(c[1]), channel(c[2]),
                                c[3] < 0.0f ? std::uint8_t{255} : channel(c[3])});
        }
        return out;
    }

    /// Vertex normals only when every face corner names a normal and each vertex gets one normal
    /// (the same vn index, or vn lines with equal values, at all its corners). Vertices used by no
    /// face get NaN. Anything else (normals per face corner, missing vn) gives no normals.
    std::vector<Eigen::Vector3f> AssignNormals(std::size_t nv) const {
        std::vector<Eigen::Vector3f> out;
        if (normals_.empty() || !all_corners_have_normals_ || corner_normals_.empty()) return out;
        std::vector<std::int64_t> chosen(nv, -1);
        for (const auto& [v, vn] : corner_normals_) {
            std::int64_t& c = chosen[v];
            if (c < 0) {
                c = vn;
            } else if (c != vn && normals_[static_cast<std::size_t>(c)] !=
                                      normals_[static_cast<std::size_t>(vn)]) {
                return out;
            }
        }
        const float nan = std::numeric_limits<float>::quiet_NaN();
        out.resize(nv, Eigen::Vector3f::Constant(nan));
        for (std::size_t i = 0; i < nv; ++i) {
            if (chosen[i] >= 0) out[i] = normals_[static_cast<std::size_t>(chosen[i])];
        }
        return out;
    }

    std::string file_;
    std::size_t line_ = 0;
    std::vector<Eigen::Vector3f> vertices_;
    std::vector<std::array<float, 4>> colors_;  ///< alpha < 0 when not given
    bool all_colored_ = true;
    std::vector<Eigen::Vector3f> normals_;
    std::vector<Triangle> triangles_;
    std::vector<std::pair<std::uint32_t, std::int64_t>> corners_;
    std::vector<std::pair<std::uint32_t, std::int64_t>> corner_normals_;
    bool all_corners_have_normals_ = true;
    std::int64_t max_v_ = 0;
    std::size_t max_v_line_ = 0;
    std::int64_t max_vn_ = 0;
    std::size_t max_vn_line_ = 0;
    std::vector<std::string> group_names_;
    std::unordered_map<std::string, std::uint32_t> group_index_;
    std::vector<std::uint32_t> triangle_groups_;
    std::int64_t current_group_ = -1;
    std::size_t unknown_lines_ = 0;
    std::string first_unknown_;
};

}  // namespace

ObjMesh ReadObj(const std::filesystem::path& path) {
    const std::string bytes = ReadFileBytes(path);
    return ObjParser(path.string()).Parse(bytes);
}

}  // namespace multicue::io

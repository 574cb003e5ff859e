#include "multicue/system/kitchen_report.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <string_view>
#include <vector>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/mapping/containers.hpp"

namespace multicue {
namespace {

using mapping::MapClass;

// Colours of the map classes (index = MapClass): walls and floor dark red/purple and fronts green
// as in the thesis' Figure 4.1.
constexpr std::array<std::string_view, mapping::kNumMapClasses> kClassColors = {
    "#8c9096", "#8e3b46", "#6a4c93", "#d9d9d9", "#e0c341",
    "#d9534f", "#7fb3d5", "#3fb950", "#e8504a", "#f5a623"};

// Container type colours (thesis Figure 4.1): cupboard blue, drawer unit green, oven yellow,
// dishwasher purple, fridge cyan, microwave orange, table red.
std::string_view TypeColor(const std::string& type) {
    const auto& names = mapping::ContainerTypeNames();
    constexpr std::array<std::string_view, 7> colors = {"#3b6fd8", "#2ea043", "#e3c12b", "#9b59b6",
                                                        "#2bc4d8", "#f08c2b", "#d9534f"};
    const auto it = std::find(names.begin(), names.end(), type);
    return it == names.end() ? "#8c9096" : colors[static_cast<std::size_t>(it - names.begin())];
}

/// A thin box over a front's rectangle, as a triangle list.
nlohmann::json FrontMesh(const mapping::Front& f) {
    const Eigen::Vector3f u = f.u_axis * ((f.max.x() - f.min.x()) / 2);
    const Eigen::Vector3f v = f.v_axis * ((f.max.y() - f.min.y()) / 2);
    const Eigen::Vector3f n = f.normal * 0.01f;
    std::vector<float> vert;
    for (int k = 0; k < 8; ++k) {
        const Eigen::Vector3f p = f.center + ((k & 1) ? u : -u) + ((k & 2) ? v : -v) +
                                  ((k & 4) ? n : Eigen::Vector3f(-n));
        vert.insert(vert.end(), {p.x(), p.y(), p.z()});
    }
    const std::vector<std::uint32_t> tri = {0, 1, 3, 0, 3, 2, 4, 7, 5, 4, 6, 7, 0, 4, 5, 0, 5, 1,
                                            2, 3, 7, 2, 7, 6, 0, 2, 6, 0, 6, 4, 1, 5, 7, 1, 7, 3};
    return {{"vertices", Base64Encode(vert)}, {"triangles", Base64Encode(tri)}};
}

std::string Panel(const mapping::KitchenMap& map) {
    std::string html = fmt::format("<h2>Fronts ({})</h2>\n", map.fronts.size());
    if (map.fronts.empty()) return html + "<p class=\"mc-empty\">No fronts were found.</p>\n";
    html += "<ul class=\"mc-objects\">\n";
    for (std::size_t i = 0; i < map.fronts.size(); ++i) {
        const auto& f = map.fronts[i];
        const std::string type =
            f.furniture >= 0 ? map.furniture[static_cast<std::size_t>(f.furniture)].type : "-";
        html += fmt::format(
            "<li class=\"mc-object\" data-object=\"{}\"><div class=\"mc-title\"><span "
            "class=\"mc-swatch\" style=\"background:{}\"></span>#{} {} of {}</div>",
            i + 1, TypeColor(type), i + 1, JointTypeName(f.articulation.type), HtmlEscape(type));
        html += fmt::format("<div class=\"mc-dims\">{:.0f} × {:.0f} cm · {} fixture(s){}</div>",
                            100 * (f.max.x() - f.min.x()), 100 * (f.max.y() - f.min.y()),
                            f.fixtures.size(), f.overlapping ? " · overlapping" : "");
        html += fmt::format(
            "<div class=\"mc-meta\">{} points · centre ({:.2f}, {:.2f}, {:.2f}) m</div></li>\n",
            f.indices.size(), f.center.x(), f.center.y(), f.center.z());
    }
    return html + "</ul>\n";
}

std::string Legend() {
    std::string html = "<div class=\"mc-legend\" data-legend=\"category\" hidden>";
    const auto& names = mapping::MapClassNames();
    for (std::size_t c = 1; c < names.size(); ++c) {
        html +=
            fmt::format("<span><span class=\"mc-swatch\" style=\"background:{}\"></span>{}</span>",
                        kClassColors[c], names[c]);
    }
    html += "</div><div class=\"mc-legend\" data-legend=\"object\" hidden>";
    for (const auto& t : mapping::ContainerTypeNames()) {
        html +=
            fmt::format("<span><span class=\"mc-swatch\" style=\"background:{}\"></span>{}</span>",
                        TypeColor(t), t);
    }
    return html + "</div>";
}

}  // namespace

ReportPage KitchenReportPage(const PointCloud& cloud, const mapping::KitchenMap& map,
                             const std::string& title, const KitchenReportParams& params) {
    if (map.point_class.size() != cloud.size() || map.point_front.size() != cloud.size()) {
        throw InvalidArgument(
            fmt::format("kitchen report: the map labels {} points, the cloud has {}",
                        map.point_class.size(), cloud.size()));
    }
    std::vector<std::size_t> finite;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        if (cloud.IsFinite(i)) finite.push_back(i);
    }
    std::vector<std::size_t> shown = finite;
    if (params.max_points > 0 && finite.size() > params.max_points) {
        shown.clear();
        const double step =
            static_cast<double>(finite.size()) / static_cast<double>(params.max_points);
        for (std::size_t k = 0; k < params.max_points; ++k) {
            shown.push_back(
                finite[std::min(finite.size() - 1, static_cast<std::size_t>(k * step))]);
        }
    }
    Eigen::Vector3f lo = Eigen::Vector3f::Zero(), hi = Eigen::Vector3f::Zero();
    if (!shown.empty()) {
        lo = hi = cloud.points[shown.front()];
        for (const std::size_t i : shown) {
            lo = lo.cwiseMin(cloud.points[i]);
            hi = hi.cwiseMax(cloud.points[i]);
        }
    }
    Eigen::Vector3f scale = (hi - lo) / 65535.0f;
    for (int k = 0; k < 3; ++k) scale[k] = scale[k] > 0.0f ? scale[k] : 1e-6f;
    const bool wide = map.fronts.size() > 255;
    std::vector<std::uint16_t> q;
    std::vector<std::uint8_t> rgb, classes, objects8;
    std::vector<std::uint16_t> objects16, parts;
    for (const std::size_t i : shown) {
        for (int k = 0; k < 3; ++k) {
            q.push_back(static_cast<std::uint16_t>(
                std::clamp(std::round((cloud.points[i][k] - lo[k]) / scale[k]), 0.0f, 65535.0f)));
        }
        if (cloud.HasColors()) {
            rgb.insert(rgb.end(), {cloud.colors[i].r, cloud.colors[i].g, cloud.colors[i].b});
        }
        classes.push_back(static_cast<std::uint8_t>(map.point_class[i]));
        const std::uint32_t fr = map.point_front[i];
        if (wide) {
            objects16.push_back(static_cast<std::uint16_t>(std::min<std::uint32_t>(fr, 65535)));
        } else {
            objects8.push_back(static_cast<std::uint8_t>(fr));
        }
        const int furn = fr > 0 ? map.fronts[fr - 1].furniture : -1;
        parts.push_back(static_cast<std::uint16_t>(furn + 1));
    }
    nlohmann::json cj;
    cj["count"] = shown.size();
    cj["finite"] = finite.size();
    cj["origin"] = {lo.x(), lo.y(), lo.z()};
    cj["scale"] = {scale.x(), scale.y(), scale.z()};
    cj["positions"] = Base64Encode(q);
    cj["colors"] = rgb.empty() ? nlohmann::json(nullptr) : nlohmann::json(Base64Encode(rgb));
    cj["object_bytes"] = wide ? 2 : 1;
    cj["objects"] = wide ? Base64Encode(objects16) : Base64Encode(objects8);
    cj["categories"] = Base64Encode(classes);
    cj["parts"] = Base64Encode(parts);
    const Eigen::Vector3f ext = hi - lo;
    cj["point_size"] = std::max(
        0.004f, 1.5f * std::sqrt(std::max(1e-6f, ext.x() * ext.y()) /
                                 static_cast<float>(std::max<std::size_t>(shown.size(), 1))));
    nlohmann::json scene;
    scene["format"] = "multicue.report-scene/1";
    scene["subtitle"] = fmt::format(
        "{} · {} points ({} shown) · {} fronts · {} fixtures · {} pieces", title, finite.size(),
        shown.size(), map.fronts.size(), map.fixtures.size(), map.furniture.size());
    scene["legend_html"] = Legend();
    std::vector<std::string> class_colors(kClassColors.begin(), kClassColors.end());
    scene["categories"] = mapping::MapClassNames();
    scene["category_colors"] = class_colors;
    const auto& o = cloud.sensor_origin;
    scene["sensor_origin"] = {o.x(), o.y(), o.z()};
    const Eigen::Vector3f up = map.frame.Up();
    scene["up"] = {up.x(), up.y(), up.z()};
    scene["support"] = nullptr;
    scene["cloud"] = cj;
    scene["objects"] = nlohmann::json::array();
    for (std::size_t i = 0; i < map.fronts.size(); ++i) {
        const auto& f = map.fronts[i];
        const std::string type =
            f.furniture >= 0 ? map.furniture[static_cast<std::size_t>(f.furniture)].type : "front";
        scene["objects"].push_back({{"id", i + 1},
                                    {"category", type},
                                    {"confidence", 1.0},
                                    {"color", std::string(TypeColor(type))},
                                    {"centroid", {f.center.x(), f.center.y(), f.center.z()}},
                                    {"mesh", FrontMesh(f)}});
    }
    ReportPage page("multicue kitchen map");
    page.SetScene(std::move(scene), Panel(map));
    page.AddHeading("Fronts");
    std::vector<std::vector<std::string>> rows;
    for (std::size_t i = 0; i < map.fronts.size(); ++i) {
        const auto& f = map.fronts[i];
        const auto& a = f.articulation;
        rows.push_back(
            {std::to_string(i + 1), std::to_string(f.furniture),
             fmt::format("{:.2f} × {:.2f}", f.max.x() - f.min.x(), f.max.y() - f.min.y()),
             JointTypeName(a.type),
             fmt::format("({:.2f}, {:.2f}, {:.2f})", a.axis.x(), a.axis.y(), a.axis.z()),
             fmt::format("({:.2f}, {:.2f}, {:.2f})", a.origin.x(), a.origin.y(), a.origin.z()),
             fmt::format("{:.2f} .. {:.2f}", a.lower, a.upper), a.source,
             std::to_string(f.indices.size())});
    }
    page.AddTable({"front", "piece", "size [m]", "joint", "axis", "axis point [m]", "limits",
                   "from", "points"},
                  rows);
    page.AddHeading("Furniture");
    rows.clear();
    for (std::size_t k = 0; k < map.furniture.size(); ++k) {
        const auto& f = map.furniture[k];
        rows.push_back(
            {std::to_string(k), f.type, fmt::format("{:.2f}", f.confidence),
             std::to_string(f.fronts.size()),
             fmt::format("{:.2f} × {:.2f} × {:.2f}", f.extents.x(), f.extents.y(), f.extents.z()),
             std::to_string(f.kitchenette)});
    }
    page.AddTable({"piece", "type", "confidence", "fronts", "w × d × h [m]", "kitchenette"}, rows);
    return page;
}

}  // namespace multicue

#include "multicue/system/perceive_report.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string_view>
#include <vector>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/recognition/geometric_category.hpp"
#include "multicue/system/perceive_output.hpp"

namespace multicue {
namespace {

// One colour per category, index as in kCategoryNames (none, sphere, box, flat, cylinder, plate,
// other).
constexpr std::array<std::string_view, kNumCategories> kCategoryColors = {
    "#8c9096", "#f5a623", "#e8504a", "#b36ae2", "#3fb950", "#2bc4d8", "#d4c84a"};

std::string Hex(const Color& c) { return fmt::format("#{:02x}{:02x}{:02x}", c.r, c.g, c.b); }

// The points shown: every finite point up to the budget; beyond it object points are kept (thinned
// only if they alone exceed it) and the rest is thinned evenly. Input order is kept.
std::vector<std::size_t> SelectPoints(const PointCloud& cloud, const PerceiveResult& result,
                                      std::size_t max_points) {
    std::vector<std::size_t> objects;
    std::vector<std::size_t> rest;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        if (!cloud.IsFinite(i)) continue;
        (result.point_objects[i] != 0 ? objects : rest).push_back(i);
    }
    if (max_points == 0 || objects.size() + rest.size() <= max_points) {
        std::vector<std::size_t> all;
        all.reserve(objects.size() + rest.size());
        std::merge(objects.begin(), objects.end(), rest.begin(), rest.end(),
                   std::back_inserter(all));
        return all;
    }
    auto thin = [](const std::vector<std::size_t>& in, std::size_t keep) {
        std::vector<std::size_t> out;
        if (keep == 0 || in.empty()) return out;
        out.reserve(keep);
        const double step = static_cast<double>(in.size()) / static_cast<double>(keep);
        for (std::size_t k = 0; k < keep; ++k) {
            out.push_back(in[std::min(in.size() - 1, static_cast<std::size_t>(k * step))]);
        }
        return out;
    };
    const std::size_t keep_objects = std::min(objects.size(), max_points);
    const auto a = keep_objects < objects.size() ? thin(objects, keep_objects) : objects;
    const auto b = thin(rest, max_points - keep_objects);
    std::vector<std::size_t> all;
    all.reserve(a.size() + b.size());
    std::merge(a.begin(), a.end(), b.begin(), b.end(), std::back_inserter(all));
    return all;
}

// A point size in metres about 1.5 times the spacing of the shown points: the median distance of
// neighbouring pixels in organized frames (scaled by the thinning), else from the bounding box.
float PointSize(const PointCloud& cloud, std::size_t finite, std::size_t shown,
                const Eigen::Vector3f& extent) {
    const double thinning =
        shown > 0 ? std::sqrt(static_cast<double>(finite) / static_cast<double>(shown)) : 1.0;
    if (cloud.IsOrganized()) {
        std::vector<float> d;
        const std::size_t stride = std::max<std::size_t>(1, cloud.size() / 4000);
        for (std::size_t i = 0; i + 1 < cloud.size(); i += stride) {
            if ((i + 1) % cloud.width == 0) continue;
            if (!cloud.IsFinite(i) || !cloud.IsFinite(i + 1)) continue;
            d.push_back((cloud.points[i + 1] - cloud.points[i]).norm());
        }
        if (d.size() >= 10) {
            std::nth_element(d.begin(), d.begin() + d.size() / 2, d.end());
            return static_cast<float>(1.5 * d[d.size() / 2] * thinning);
        }
    }
    std::array<float, 3> e = {extent.x(), extent.y(), extent.z()};
    std::sort(e.begin(), e.end());
    const double area = std::max(1e-6, static_cast<double>(e[1]) * e[2]);
    return static_cast<float>(1.5 * std::sqrt(area / std::max<std::size_t>(shown, 1)));
}

std::string Cm(float metres) { return fmt::format("{:.1f}", 100.0f * metres); }

std::string ModelText(const PerceivedObject& o) {
    if (o.model.cylinder) {
        const auto& c = *o.model.cylinder;
        return fmt::format("cylinder model: radius {} cm, height {} cm", Cm(c.radius),
                           Cm(c.height));
    }
    if (o.model.box) {
        const auto& e = o.model.box->extents;
        return fmt::format("box model: {} × {} × {} cm", Cm(e.x()), Cm(e.y()), Cm(e.z()));
    }
    if (o.model.rotational && !o.model.rotational->radii.empty()) {
        const auto& r = *o.model.rotational;
        return fmt::format("rotational model: largest diameter {} cm, height {} cm",
                           Cm(2.0f * *std::max_element(r.radii.begin(), r.radii.end())),
                           Cm(r.heights.back() - r.heights.front()));
    }
    if (!o.model.replaced.empty()) {
        return fmt::format("mesh model ({} rejected: {})", o.model.replaced,
                           o.model.replace_reason == "verification" ? "surface in free space"
                           : o.model.replace_reason == "size"       ? "larger than its points"
                                                                    : "too few points explained");
    }
    const auto& e = o.category.extents;
    if (e.maxCoeff() > 0) {
        return fmt::format("extent {} × {} × {} cm", Cm(e.x()), Cm(e.y()), Cm(e.z()));
    }
    return "no model";
}

std::string Dimensions(const PerceivedObject& o) {
    std::string text = ModelText(o);
    if (o.model.grasp.graspable_width > 0.0f) {
        text += fmt::format(", grasp width {} cm", Cm(o.model.grasp.graspable_width));
    }
    return text;
}

std::string ObjectPanel(const PerceiveResult& result) {
    std::string html = fmt::format("<h2>Objects ({})</h2>\n", result.objects.size());
    if (result.objects.empty()) {
        return html + "<p class=\"mc-empty\">No objects were found.</p>\n";
    }
    html += "<ul class=\"mc-objects\">\n";
    for (const auto& o : result.objects) {
        const std::string_view category = CategoryName(o.category.category);
        html += fmt::format(
            "<li class=\"mc-object\" data-object=\"{}\" data-category=\"{}\">"
            "<div class=\"mc-title\"><span class=\"mc-swatch\" style=\"background:{}\"></span>"
            "#{} {} <span class=\"mc-conf\">{:.2f}</span></div>",
            o.id, category, Hex(ObjectColor(o.id)), o.id, category, o.category.confidence);
        html += "<div class=\"mc-dims\">" + HtmlEscape(Dimensions(o)) + "</div>";
        html += fmt::format(
            "<div class=\"mc-meta\">{} points · {} parts · centroid ({:.3f}, {:.3f}, {:.3f}) m"
            "</div>",
            o.indices.size(), o.parts.size(), o.centroid.x(), o.centroid.y(), o.centroid.z());
        html += "<div class=\"mc-probs\">";
        for (std::size_t c = 1; c < kNumCategories; ++c) {
            const float p = o.category.probabilities[c];
            html += fmt::format(
                "<span>{}</span><div class=\"mc-bar\"><div style=\"width:{:.1f}%;background:{}\">"
                "</div></div><span class=\"mc-num\">{:.2f}</span>",
                kCategoryNames[c], 100.0f * std::clamp(p, 0.0f, 1.0f), kCategoryColors[c], p);
        }
        html += "</div></li>\n";
    }
    return html + "</ul>\n";
}

std::string Legends(const PerceiveResult& result) {
    std::string html = "<div class=\"mc-legend\" data-legend=\"category\" hidden>";
    for (std::size_t c = 1; c < kNumCategories; ++c) {
        html += fmt::format(
            "<span><span class=\"mc-swatch\" style=\"background:{}\"></span>{}"
            "</span>",
            kCategoryColors[c], kCategoryNames[c]);
    }
    html += "</div>";
    if (!result.objects.empty()) {
        html += "<div class=\"mc-legend\" data-legend=\"object\" hidden>";
        for (const auto& o : result.objects) {
            html += fmt::format(
                "<span><span class=\"mc-swatch\" style=\"background:{}\"></span>#{}</span>",
                Hex(ObjectColor(o.id)), o.id);
        }
        html += "</div>";
    }
    return html;
}

nlohmann::json CloudJson(const PointCloud& cloud, const PerceiveResult& result,
                         const std::vector<std::size_t>& shown, std::size_t finite) {
    Eigen::Vector3f lo = Eigen::Vector3f::Constant(0.0f);
    Eigen::Vector3f hi = Eigen::Vector3f::Constant(0.0f);
    if (!shown.empty()) {
        lo = hi = cloud.points[shown.front()];
        for (const std::size_t i : shown) {
            lo = lo.cwiseMin(cloud.points[i]);
            hi = hi.cwiseMax(cloud.points[i]);
        }
    }
    // 16 bits per coordinate over the bounding box: 0.05 mm steps over 3 m.
    Eigen::Vector3f scale = (hi - lo) / 65535.0f;
    for (int k = 0; k < 3; ++k) {
        if (!(scale[k] > 0.0f)) scale[k] = 1e-6f;
    }
    std::vector<std::uint16_t> q(shown.size() * 3);
    for (std::size_t j = 0; j < shown.size(); ++j) {
        const Eigen::Vector3f p = cloud.points[shown[j]];
        for (int k = 0; k < 3; ++k) {
            const float v = std::round((p[k] - lo[k]) / scale[k]);
            q[3 * j + k] = static_cast<std::uint16_t>(std::clamp(v, 0.0f, 65535.0f));
        }
    }
    // Global part number of every point (1-based over all objects, 0 = none).
    std::vector<std::uint16_t> part_of(cloud.size(), 0);
    std::uint32_t part = 0;
    for (const auto& o : result.objects) {
        for (const auto& indices : o.parts) {
            part = part % 65535 + 1;
            for (const auto i : indices) {
                if (i < part_of.size()) part_of[i] = static_cast<std::uint16_t>(part);
            }
        }
    }
    int max_id = 0;
    for (const auto& o : result.objects) max_id = std::max(max_id, o.id);
    const int object_bytes = max_id > 255 ? 2 : 1;

    std::vector<std::uint8_t> rgb;
    std::vector<std::uint8_t> categories(shown.size());
    std::vector<std::uint16_t> parts(shown.size());
    std::vector<std::uint8_t> objects8;
    std::vector<std::uint16_t> objects16;
    if (cloud.HasColors()) rgb.reserve(shown.size() * 3);
    for (std::size_t j = 0; j < shown.size(); ++j) {
        const std::size_t i = shown[j];
        if (cloud.HasColors()) {
            rgb.push_back(cloud.colors[i].r);
            rgb.push_back(cloud.colors[i].g);
            rgb.push_back(cloud.colors[i].b);
        }
        categories[j] = result.point_categories[i];
        parts[j] = part_of[i];
        if (object_bytes == 1) {
            objects8.push_back(static_cast<std::uint8_t>(result.point_objects[i]));
        } else {
            objects16.push_back(static_cast<std::uint16_t>(
                std::min<std::uint32_t>(result.point_objects[i], 65535)));
        }
    }
    nlohmann::json j;
    j["count"] = shown.size();
    j["finite"] = finite;
    j["origin"] = {lo.x(), lo.y(), lo.z()};
    j["scale"] = {scale.x(), scale.y(), scale.z()};
    j["positions"] = Base64Encode(q);
    j["colors"] = rgb.empty() ? nlohmann::json(nullptr) : nlohmann::json(Base64Encode(rgb));
    j["object_bytes"] = object_bytes;
    j["objects"] = object_bytes == 1 ? Base64Encode(objects8) : Base64Encode(objects16);
    j["categories"] = Base64Encode(categories);
    j["parts"] = Base64Encode(parts);
    j["point_size"] = PointSize(cloud, finite, shown.size(), hi - lo);
    return j;
}

nlohmann::json MeshJson(const TriangleMesh& mesh) {
    static_assert(sizeof(Eigen::Vector3f) == 12 && sizeof(Triangle) == 12);
    std::vector<float> v(mesh.vertices.size() * 3);
    std::memcpy(v.data(), mesh.vertices.data(), v.size() * sizeof(float));
    std::vector<std::uint32_t> t(mesh.triangles.size() * 3);
    std::memcpy(t.data(), mesh.triangles.data(), t.size() * sizeof(std::uint32_t));
    return {{"vertices", Base64Encode(v)}, {"triangles", Base64Encode(t)}};
}

std::string Subtitle(const nlohmann::ordered_json& rj, const PerceiveResult& result,
                     std::size_t finite, std::size_t shown) {
    std::string s;
    if (rj.contains("input") && rj["input"].is_string())
        s += rj["input"].get<std::string>() + " · ";
    s += fmt::format("{} points ({} finite", result.points, finite);
    if (shown < finite) s += fmt::format(", {} shown", shown);
    s += fmt::format(") · {} objects · support plane {}", result.objects.size(),
                     result.support.found ? "found" : "not found");
    if (rj.contains("timings_ms") && rj["timings_ms"].contains("total")) {
        s += fmt::format(" · {:.1f} ms", rj["timings_ms"]["total"].get<double>());
    }
    return s;
}

}  // namespace

void ReadReportParams(io::ConfigSection& config, ReportParams& p) {
    auto report = config.Section("report");
    report.Get("enabled", p.enabled, "write report.html (3D view and tables) next to result.json");
    report.Get("max_points", p.max_points,
               "points embedded in report.html; background points are thinned first, 0 = all");
    report.Get("models", p.models, "embed the reconstructed models in report.html");
}

ReportPage PerceiveReportPage(const PointCloud& cloud, const PerceiveResult& result,
                              const nlohmann::ordered_json& result_json,
                              const ReportParams& params) {
    if (result.point_objects.size() != cloud.size() ||
        result.point_categories.size() != cloud.size()) {
        throw InvalidArgument(
            fmt::format("report: the result has labels for {} points, the cloud has {}",
                        result.point_objects.size(), cloud.size()));
    }
    const std::size_t finite = cloud.CountFinite();
    const auto shown = SelectPoints(cloud, result, params.max_points);

    ReportPage page("multicue perceive report");
    nlohmann::json scene;
    scene["format"] = "multicue.report-scene/1";
    scene["subtitle"] = Subtitle(result_json, result, finite, shown.size());
    scene["legend_html"] = Legends(result);
    scene["categories"] = kCategoryNames;
    scene["category_colors"] = kCategoryColors;
    const auto& o = cloud.sensor_origin;
    scene["sensor_origin"] = {o.x(), o.y(), o.z()};
    Eigen::Vector3f up =
        result.support.found
            ? Eigen::Vector3f(result.support.plane.head<3>())
            : Eigen::Vector3f(cloud.sensor_orientation * -Eigen::Vector3f::UnitY());
    scene["up"] = {up.x(), up.y(), up.z()};
    if (result.support.found) {
        nlohmann::json hull = nlohmann::json::array();
        for (const auto& h : result.support.hull) hull.push_back({h.x(), h.y(), h.z()});
        const auto& pl = result.support.plane;
        scene["support"] = {{"plane", {pl.x(), pl.y(), pl.z(), pl.w()}}, {"hull", hull}};
    } else {
        scene["support"] = nullptr;
    }
    scene["cloud"] = CloudJson(cloud, result, shown, finite);
    scene["objects"] = nlohmann::json::array();
    for (const auto& obj : result.objects) {
        nlohmann::json oj;
        oj["id"] = obj.id;
        oj["category"] = CategoryName(obj.category.category);
        oj["confidence"] = obj.category.confidence;
        oj["color"] = Hex(ObjectColor(obj.id));
        oj["centroid"] = {obj.centroid.x(), obj.centroid.y(), obj.centroid.z()};
        if (params.models && !obj.model.mesh.triangles.empty()) {
            oj["mesh"] = MeshJson(obj.model.mesh);
        }
        scene["objects"].push_back(oj);
    }
    page.SetScene(std::move(scene), ObjectPanel(result));

    // Below the view: the numbers of result.json as tables.
    page.AddHeading("Objects");
    std::vector<std::vector<std::string>> rows;
    for (const auto& obj : result.objects) {
        rows.push_back({std::to_string(obj.id), std::string(CategoryName(obj.category.category)),
                        fmt::format("{:.2f}", obj.category.confidence),
                        std::to_string(obj.indices.size()), std::to_string(obj.parts.size()),
                        Dimensions(obj),
                        fmt::format("{:.3f}, {:.3f}, {:.3f}", obj.centroid.x(), obj.centroid.y(),
                                    obj.centroid.z())});
    }
    page.AddTable({"id", "category", "confidence", "points", "parts", "dimensions", "centroid [m]"},
                  rows);
    if (result.support.found) {
        const auto& pl = result.support.plane;
        page.AddParagraph(fmt::format(
            "Support plane {:.4f} x + {:.4f} y + {:.4f} z + {:.4f} = 0 with {} inliers, hull of {} "
            "corners.",
            pl.x(), pl.y(), pl.z(), pl.w(), result.support.inliers.size(),
            result.support.hull.size()));
    } else {
        page.AddParagraph("No support plane was found; objects were sought in the whole cloud.");
    }
    if (result_json.contains("timings_ms") && result_json["timings_ms"].is_object()) {
        std::vector<std::vector<std::string>> timing_rows;
        for (const auto& [stage, ms] : result_json["timings_ms"].items()) {
            timing_rows.push_back({stage, fmt::format("{:.2f}", ms.get<double>())});
        }
        page.AddHeading("Timings");
        page.AddTable({"stage", "ms"}, timing_rows);
    }
    return page;
}

void WritePerceiveReport(const std::filesystem::path& path, const PointCloud& cloud,
                         const PerceiveResult& result, const std::string& input_name,
                         const ReportParams& params) {
    PerceiveReportPage(cloud, result, PerceiveResultJson(input_name, result), params).Write(path);
}

}  // namespace multicue

#include "furniture_report.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>

#include <fmt/format.h>

#include "multicue/system/report_page.hpp"

namespace multicue::cli {
namespace {

const char* ClassColour(const std::string& name) {
    if (name == "table") return "#1f77b4";
    if (name == "chair") return "#d62728";
    if (name == "cabinet") return "#2ca02c";
    if (name == "sideboard") return "#9467bd";
    return "#7f7f7f";
}

// The corners of an oriented box's footprint: centre (x, y), size (sx, sy), yaw [deg].
std::string Footprint(const nlohmann::json& box) {
    const float cx = box["centre"][0], cy = box["centre"][1];
    const float sx = box["size"][0], sy = box["size"][1];
    const float yaw = static_cast<float>(box["yaw_deg"]) * static_cast<float>(M_PI) / 180.0f;
    const float c = std::cos(yaw), s = std::sin(yaw);
    std::string points;
    for (const auto& [u, v] :
         {std::pair{-0.5f, -0.5f}, {0.5f, -0.5f}, {0.5f, 0.5f}, {-0.5f, 0.5f}}) {
        const float x = cx + c * u * sx - s * v * sy, y = cy + s * u * sx + c * v * sy;
        points += fmt::format("{:.3f},{:.3f} ", x, -y);  // SVG's y points down
    }
    return points;
}

}  // namespace

std::string FurnitureReportPage(const nlohmann::json& doc,
                                const std::vector<FurnitureView>& views) {
    // World points between 5 cm and 2 m above the floor, thinned to about 20 000.
    std::size_t total = 0;
    for (const auto& v : views) total += v.scan->size();
    const std::size_t stride = std::max<std::size_t>(1, total / 20000);
    std::string dots;
    float lo_x = 1e30f, lo_y = 1e30f, hi_x = -1e30f, hi_y = -1e30f;
    const auto extend = [&](float x, float y) {
        lo_x = std::min(lo_x, x), hi_x = std::max(hi_x, x);
        lo_y = std::min(lo_y, y), hi_y = std::max(hi_y, y);
    };
    std::size_t k = 0;
    for (const auto& v : views) {
        for (const auto& p : v.scan->points) {
            if (k++ % stride != 0 || !p.allFinite()) continue;
            const Eigen::Vector3f w = v.T_world_sensor * p;
            if (w.z() < 0.05f || w.z() > 2.0f) continue;
            extend(w.x(), w.y());
            dots += fmt::format("M{:.3f} {:.3f}h0.01", w.x(), -w.y());
        }
        extend(v.T_world_sensor.translation().x(), v.T_world_sensor.translation().y());
    }
    if (lo_x > hi_x) lo_x = lo_y = -1.0f, hi_x = hi_y = 1.0f;
    const float margin = 0.3f;
    std::string svg = fmt::format(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" viewBox=\"{:.3f} {:.3f} {:.3f} {:.3f}\" "
        "width=\"900\">\n<path d=\"{}\" stroke=\"#999\" stroke-width=\"0.02\" "
        "stroke-linecap=\"round\"/>\n",
        lo_x - margin, -hi_y - margin, hi_x - lo_x + 2 * margin, hi_y - lo_y + 2 * margin, dots);
    for (const auto& v : views) {
        svg += fmt::format("<circle cx=\"{:.3f}\" cy=\"{:.3f}\" r=\"0.08\" fill=\"#000\"/>\n",
                           v.T_world_sensor.translation().x(), -v.T_world_sensor.translation().y());
    }
    std::string rows;
    const auto draw = [&](const nlohmann::json& d, bool rejected) {
        const std::string cls = d.value("class", "");
        if (d.contains("box")) {
            svg += fmt::format(
                "<polygon points=\"{}\" fill=\"{}\" fill-opacity=\"{}\" stroke=\"{}\" "
                "stroke-width=\"0.03\"{}><title>{}</title></polygon>\n",
                Footprint(d["box"]), ClassColour(cls), rejected ? 0.0 : 0.3, ClassColour(cls),
                rejected ? " stroke-dasharray=\"0.1 0.06\"" : "", HtmlEscape(cls));
        }
        const float x = d["centre"][0], y = d["centre"][1];
        svg += fmt::format(
            "<text x=\"{:.3f}\" y=\"{:.3f}\" font-size=\"{}\" fill=\"{}\"{}>{}</text>\n", x, -y,
            rejected ? 0.1 : 0.18, ClassColour(cls), rejected ? " fill-opacity=\"0.6\"" : "",
            HtmlEscape(cls));
        rows += fmt::format(
            "<tr{}><td>{}</td><td>{:.2f}, "
            "{:.2f}</td><td>{}</td><td>{:.2f}</td><td>{}</td><td>{}</td>"
            "</tr>\n",
            rejected ? " class=\"rejected\"" : "", HtmlEscape(cls), x, y,
            d.contains("yaw_deg") ? fmt::format("{:.0f}", static_cast<float>(d["yaw_deg"])) : "-",
            static_cast<float>(d.value("score", 0.0f)),
            d.contains("coverage") ? fmt::format("{:.2f}", static_cast<float>(d["coverage"])) : "-",
            HtmlEscape(d.value("rejection", std::string())));
    };
    for (const auto& d : doc["detections"]) draw(d, false);
    for (const auto& d : doc["rejected"]) draw(d, true);
    svg += "</svg>\n";
    return fmt::format(
        "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>multicue: furniture"
        "</title>\n<style>body{{font-family:sans-serif;margin:2em}}table{{border-collapse:"
        "collapse}}td,th{{border:1px solid #ccc;padding:2px 8px;text-align:left}}"
        "tr.rejected{{color:#888}}</style></head><body>\n<h1>Furniture</h1>\n<p>{} scans, {} "
        "detections, {} rejected hypotheses; model {}. Top view of the world frame (x to the "
        "right, y up, metres): scan points 5 cm to 2 m above the floor in grey, sensor positions "
        "black, fitted models filled, rejected hypotheses dashed.</p>\n{}<table><tr><th>class"
        "</th><th>centre [m]</th><th>yaw [deg]</th><th>score</th><th>coverage</th><th>rejected "
        "because</th></tr>\n{}</table>\n</body></html>\n",
        views.size(), doc["detections"].size(), doc["rejected"].size(),
        HtmlEscape(doc.value("model", std::string())), svg, rows);
}

}  // namespace multicue::cli

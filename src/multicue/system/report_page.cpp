#include "multicue/system/report_page.hpp"

#include <algorithm>
#include <utility>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/io/file_utils.hpp"
#include "multicue/system/report_assets.hpp"

namespace multicue {
namespace {

void CheckSquare(const std::vector<std::vector<std::size_t>>& counts) {
    for (std::size_t r = 0; r < counts.size(); ++r) {
        if (counts[r].size() != counts.size()) {
            throw InvalidArgument(
                fmt::format("confusion matrix must be square: row {} has {} entries, expected {}",
                            r, counts[r].size(), counts.size()));
        }
    }
}

// JSON inside <script>: "</" would end the element early; "<\/" is the same JSON string.
std::string ScriptSafeJson(const nlohmann::json& data) {
    std::string text = data.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
    std::string out;
    out.reserve(text.size() + 16);
    for (std::size_t i = 0; i < text.size(); ++i) {
        out += text[i];
        if (text[i] == '<' && i + 1 < text.size() && text[i + 1] == '/') out += '\\';
    }
    return out;
}

std::string Percent(double v) { return fmt::format("{:.1f} %", 100.0 * v); }

}  // namespace

std::string HtmlEscape(std::string_view text) {
    std::string out;
    out.reserve(text.size());
    for (const char c : text) {
        switch (c) {
            case '&':
                out += "&amp;";
                break;
            case '<':
                out += "&lt;";
                break;
            case '>':
                out += "&gt;";
                break;
            case '"':
                out += "&quot;";
                break;
            case '\'':
                out += "&#39;";
                break;
            default:
                out += c;
        }
    }
    return out;
}

std::string Base64Encode(const void* data, std::size_t size) {
    static constexpr char kAlphabet[] =
        "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    const auto* bytes = static_cast<const unsigned char*>(data);
    std::string out;
    out.reserve((size + 2) / 3 * 4);
    std::size_t i = 0;
    for (; i + 3 <= size; i += 3) {
        const unsigned v = (bytes[i] << 16) | (bytes[i + 1] << 8) | bytes[i + 2];
        out += kAlphabet[(v >> 18) & 63];
        out += kAlphabet[(v >> 12) & 63];
        out += kAlphabet[(v >> 6) & 63];
        out += kAlphabet[v & 63];
    }
    if (i < size) {
        const unsigned v = (bytes[i] << 16) | (i + 1 < size ? bytes[i + 1] << 8 : 0);
        out += kAlphabet[(v >> 18) & 63];
        out += kAlphabet[(v >> 12) & 63];
        out += i + 1 < size ? kAlphabet[(v >> 6) & 63] : '=';
        out += '=';
    }
    return out;
}

bool ReportViewerAvailable() { return report_assets::HasViewer(); }

std::vector<ClassFigures> ConfusionFigures(const std::vector<std::vector<std::size_t>>& counts) {
    CheckSquare(counts);
    const std::size_t n = counts.size();
    std::vector<ClassFigures> figures(n);
    for (std::size_t r = 0; r < n; ++r) {
        for (std::size_t c = 0; c < n; ++c) {
            figures[r].support += counts[r][c];
            figures[c].predicted += counts[r][c];
        }
    }
    for (std::size_t k = 0; k < n; ++k) {
        auto& f = figures[k];
        const double correct = static_cast<double>(counts[k][k]);
        f.precision = f.predicted > 0 ? correct / static_cast<double>(f.predicted) : 0.0;
        f.recall = f.support > 0 ? correct / static_cast<double>(f.support) : 0.0;
        f.f1 = f.precision + f.recall > 0 ? 2.0 * f.precision * f.recall / (f.precision + f.recall)
                                          : 0.0;
    }
    return figures;
}

std::string ConfusionMatrixHtml(std::string_view title, const std::vector<std::string>& class_names,
                                const std::vector<std::vector<std::size_t>>& counts) {
    CheckSquare(counts);
    if (class_names.size() != counts.size()) {
        throw InvalidArgument(fmt::format("confusion matrix: {} class names for {} rows",
                                          class_names.size(), counts.size()));
    }
    const auto figures = ConfusionFigures(counts);
    std::size_t total = 0;
    std::size_t correct = 0;
    for (std::size_t k = 0; k < counts.size(); ++k) {
        total += figures[k].support;
        correct += counts[k][k];
    }
    std::string html =
        fmt::format("<section class=\"mc-confusion-section\"><h2>{}</h2>\n", HtmlEscape(title));
    html += fmt::format("<p>Accuracy {} ({} of {}).</p>\n",
                        total > 0 ? Percent(static_cast<double>(correct) / total) : "n/a", correct,
                        total);
    html +=
        "<table class=\"mc-confusion\"><caption>rows: true class, columns: predicted class"
        "</caption>\n<tr><th></th>";
    for (const auto& name : class_names) html += "<th>" + HtmlEscape(name) + "</th>";
    html += "</tr>\n";
    for (std::size_t r = 0; r < counts.size(); ++r) {
        html += "<tr><th>" + HtmlEscape(class_names[r]) + "</th>";
        for (std::size_t c = 0; c < counts.size(); ++c) {
            const double share =
                figures[r].support > 0
                    ? static_cast<double>(counts[r][c]) / static_cast<double>(figures[r].support)
                    : 0.0;
            // Correct cells in blue, confusions in red, stronger with the row share.
            const char* rgb = r == c ? "47,129,247" : "207,34,46";
            html += fmt::format("<td style=\"background:rgba({},{:.2f})\" title=\"{}\">{}</td>",
                                rgb, 0.08 + 0.6 * share, Percent(share), counts[r][c]);
        }
        html += "</tr>\n";
    }
    html += "</table>\n";
    std::vector<std::vector<std::string>> rows;
    for (std::size_t k = 0; k < counts.size(); ++k) {
        const auto& f = figures[k];
        rows.push_back({class_names[k], std::to_string(f.support), std::to_string(f.predicted),
                        Percent(f.precision), Percent(f.recall), fmt::format("{:.3f}", f.f1)});
    }
    html += TableHtml({"class", "support", "predicted", "precision", "recall", "F1"}, rows,
                      "per class");
    html += "</section>\n";
    return html;
}

std::string TableHtml(const std::vector<std::string>& header,
                      const std::vector<std::vector<std::string>>& rows, std::string_view caption) {
    std::string html = "<table>";
    if (!caption.empty()) html += "<caption>" + HtmlEscape(caption) + "</caption>";
    html += "\n<tr>";
    for (const auto& h : header) html += "<th>" + HtmlEscape(h) + "</th>";
    html += "</tr>\n";
    for (const auto& row : rows) {
        html += "<tr>";
        const std::size_t n = std::max(row.size(), header.size());
        for (std::size_t i = 0; i < n; ++i) {
            html += "<td>" + (i < row.size() ? HtmlEscape(row[i]) : std::string()) + "</td>";
        }
        html += "</tr>\n";
    }
    html += "</table>\n";
    return html;
}

ReportPage::ReportPage(std::string title) : title_(std::move(title)) {}

void ReportPage::AddHeading(std::string_view text) {
    sections_.push_back("<h2>" + HtmlEscape(text) + "</h2>\n");
}

void ReportPage::AddParagraph(std::string_view text) {
    sections_.push_back("<p>" + HtmlEscape(text) + "</p>\n");
}

void ReportPage::AddTable(const std::vector<std::string>& header,
                          const std::vector<std::vector<std::string>>& rows,
                          std::string_view caption) {
    sections_.push_back(TableHtml(header, rows, caption));
}

void ReportPage::AddConfusionMatrix(std::string_view title,
                                    const std::vector<std::string>& class_names,
                                    const std::vector<std::vector<std::size_t>>& counts) {
    sections_.push_back(ConfusionMatrixHtml(title, class_names, counts));
}

void ReportPage::AddHtml(std::string html) { sections_.push_back(std::move(html)); }

void ReportPage::SetScene(nlohmann::json data, std::string side_panel) {
    scene_ = std::move(data);
    side_panel_ = std::move(side_panel);
    has_scene_ = true;
}

std::string ReportPage::Render() const {
    const bool viewer = has_scene_ && report_assets::HasViewer();
    std::string html = "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n";
    html += "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n";
    html += "<meta name=\"generator\" content=\"multicue\">\n";
    html += "<title>" + HtmlEscape(title_) + "</title>\n<style>\n";
    html += report_assets::PageStyle();
    html += "</style>\n</head>\n<body>\n";
    html += "<header><h1>" + HtmlEscape(title_) + "</h1>";
    if (has_scene_ && scene_.contains("subtitle")) {
        html += "<p>" + HtmlEscape(scene_["subtitle"].get<std::string>()) + "</p>";
    }
    html += "</header>\n";
    if (has_scene_) {
        html += "<div class=\"mc-scene\">\n<div id=\"mc-view\">";
        if (viewer) {
            html +=
                "<div class=\"mc-toolbar\">"
                "<div class=\"mc-group\">colour "
                "<button data-color-mode=\"rgb\">RGB</button>"
                "<button data-color-mode=\"object\">object</button>"
                "<button data-color-mode=\"category\">category</button>"
                "<button data-color-mode=\"part\">part</button></div>"
                "<div class=\"mc-group\">"
                "<label><input type=\"checkbox\" data-toggle=\"cloud\" checked> cloud</label>"
                "<label><input type=\"checkbox\" data-toggle=\"models\" checked> models</label>"
                "<label><input type=\"checkbox\" data-toggle=\"support\" checked> support "
                "plane</label></div>"
                "<div class=\"mc-group\"><label>point size <input id=\"mc-point-size\" "
                "type=\"range\" min=\"0.3\" max=\"4\" step=\"0.1\" value=\"1\"></label>"
                "<button id=\"mc-reset-view\">reset view</button></div></div>";
            if (scene_.contains("legend_html")) {
                html += scene_["legend_html"].get<std::string>();
            }
            html +=
                "<div class=\"mc-hint\">drag: rotate · right-drag: pan · wheel: zoom · "
                "click: select</div>";
        } else {
            html +=
                "<p class=\"mc-note\">This multicue build has no 3D viewer: web/node_modules was "
                "missing when it was configured (run scripts/setup.sh, then reconfigure).</p>";
        }
        html += "</div>\n<aside>" + side_panel_ + "</aside>\n</div>\n";
    }
    if (!sections_.empty()) {
        html += "<section>\n";
        for (const auto& s : sections_) html += s;
        html += "</section>\n";
    }
    html += "<footer>Written by multicue";
    if (viewer) {
        html += fmt::format(" · 3D view: three.js {} (MIT licence)", report_assets::ThreeVersion());
    }
    html += "</footer>\n";
    if (viewer) {
        nlohmann::json data = scene_;
        data.erase("legend_html");
        data.erase("subtitle");
        html += "<script type=\"application/json\" id=\"mc-data\">";
        html += ScriptSafeJson(data);
        html += "</script>\n<script>\n";
        html += report_assets::ViewerScript();
        html += "\n</script>\n";
    }
    html += "</body>\n</html>\n";
    return html;
}

void ReportPage::Write(const std::filesystem::path& path) const {
    const std::string html = Render();
    io::WriteFileAtomically(path, [&](std::ostream& out) { out << html; });
}

}  // namespace multicue

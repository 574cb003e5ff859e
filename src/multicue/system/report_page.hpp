#pragma once
/// \file Self-contained HTML report pages: one file with its style, data and (when this build has
/// it) the WebGL viewer inlined, so it opens from disk without a network. `multicue perceive`
/// writes one per scene; evaluation commands add confusion matrices and per-class tables.

#include <cstddef>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

namespace multicue {

/// Escapes & < > " ' for HTML text and attribute values.
std::string HtmlEscape(std::string_view text);

/// Standard base64 (RFC 4648, with padding) of `size` bytes; the page's typed arrays use it.
std::string Base64Encode(const void* data, std::size_t size);

/// The bytes of a vector's elements in base64.
template <typename T>
std::string Base64Encode(const std::vector<T>& v) {
    return Base64Encode(v.data(), v.size() * sizeof(T));
}

/// True when this build embeds the WebGL viewer (three.js bundled from web/ at build time).
bool ReportViewerAvailable();

/// Per-class figures of a confusion matrix (rows = true class, columns = predicted class).
struct ClassFigures {
    std::size_t support = 0;    ///< samples of the class (row sum)
    std::size_t predicted = 0;  ///< samples predicted as the class (column sum)
    double precision = 0.0;     ///< correct / predicted, 0 when nothing was predicted
    double recall = 0.0;        ///< correct / support, 0 for an empty class
    double f1 = 0.0;            ///< harmonic mean of precision and recall
};

/// Figures of every class, in the matrix's order. Throws InvalidArgument unless `counts` is square.
std::vector<ClassFigures> ConfusionFigures(const std::vector<std::vector<std::size_t>>& counts);

/// An HTML section with the confusion matrix (cells shaded by the row share), the overall accuracy
/// and a per-class table (support, precision, recall, F1). Throws InvalidArgument unless `counts`
/// is square with one row per name.
std::string ConfusionMatrixHtml(std::string_view title, const std::vector<std::string>& class_names,
                                const std::vector<std::vector<std::size_t>>& counts);

/// An HTML table; cells are escaped. Rows shorter than the header are padded.
std::string TableHtml(const std::vector<std::string>& header,
                      const std::vector<std::vector<std::string>>& rows,
                      std::string_view caption = {});

/// A report page built from sections. Sections are HTML fragments shown in order below the 3D
/// scene (if any); Add* functions escape text, AddHtml takes trusted markup as it is.
class ReportPage {
  public:
    explicit ReportPage(std::string title);

    void AddHeading(std::string_view text);
    void AddParagraph(std::string_view text);
    void AddTable(const std::vector<std::string>& header,
                  const std::vector<std::vector<std::string>>& rows, std::string_view caption = {});
    void AddConfusionMatrix(std::string_view title, const std::vector<std::string>& class_names,
                            const std::vector<std::vector<std::size_t>>& counts);
    void AddHtml(std::string html);

    /// Shows a 3D scene: `data` is the viewer's JSON (format "multicue.report-scene/1", see
    /// docs/report.md) and `side_panel` the HTML beside the view (elements with a data-object
    /// attribute select that object). Without the viewer in this build, the panel is shown with a
    /// note instead of the view.
    void SetScene(nlohmann::json data, std::string side_panel);

    /// The whole document.
    std::string Render() const;
    /// Writes Render() to `path` atomically; throws IoError naming the path.
    void Write(const std::filesystem::path& path) const;

  private:
    std::string title_;
    std::vector<std::string> sections_;
    nlohmann::json scene_;
    std::string side_panel_;
    bool has_scene_ = false;
};

}  // namespace multicue

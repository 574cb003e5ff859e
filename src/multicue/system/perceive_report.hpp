#pragma once
/// \file report.html of `multicue perceive`: the cloud coloured by RGB, object, category or part,
/// the reconstructed models and the support plane in a WebGL view, and every object's category,
/// probabilities and dimensions beside it (docs/report.md).

#include <cstddef>
#include <filesystem>
#include <string>

#include <nlohmann/json.hpp>

#include "multicue/core/point_cloud.hpp"
#include "multicue/io/config.hpp"
#include "multicue/system/perceive.hpp"
#include "multicue/system/report_page.hpp"

namespace multicue {

struct ReportParams {
    bool enabled = true;  ///< write report.html next to result.json
    /// Points embedded in the page; beyond it, background points are thinned first (object points
    /// are kept). 200,000 keeps a 640x480 frame's page near 4 MB. 0 = every finite point [points]
    std::size_t max_points = 200000;
    bool models = true;  ///< embed the model meshes
};

/// Reads (or, with a dump section, records) the "report" section of a parameter file.
void ReadReportParams(io::ConfigSection& config, ReportParams& params);

/// The page for one perceived scene. `result_json` is PerceiveResultJson() of the same result
/// (the page shows its numbers). `cloud` is the cloud given to Perceive. Throws InvalidArgument
/// when the result does not belong to the cloud (different point count).
ReportPage PerceiveReportPage(const PointCloud& cloud, const PerceiveResult& result,
                              const nlohmann::ordered_json& result_json,
                              const ReportParams& params = {});

/// Writes the page of PerceiveReportPage() to `path` atomically; throws IoError naming the path.
void WritePerceiveReport(const std::filesystem::path& path, const PointCloud& cloud,
                         const PerceiveResult& result, const std::string& input_name = {},
                         const ReportParams& params = {});

}  // namespace multicue

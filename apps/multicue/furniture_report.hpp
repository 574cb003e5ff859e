#pragma once
// report.html of `multicue detect furniture`: a top view of the scans with the detections.

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "multicue/mapping/furniture_detection.hpp"

namespace multicue::cli {

/// A self-contained HTML page (no scripts, no downloads): the scans' points seen from above in
/// the world frame (at most about 20 000, floor and ceiling left out), every sensor position, the
/// fitted models' boxes with class, score and yaw, the rejected hypotheses dashed with their
/// reason, and the table of detections. `doc` is the result.json document.
std::string FurnitureReportPage(const nlohmann::json& doc, const std::vector<FurnitureView>& views);

}  // namespace multicue::cli

#pragma once
/// \file report.html of `multicue map kitchen`: the mapped points in the report viewer coloured by
/// semantic class (wall, floor, ceiling, worktop, table, face, front, handle, knob), by front
/// (each door or drawer in the colour of its container type, as in the thesis' Figure 4.1) or by
/// sensor colour, every front as a translucent box, and tables of the fronts, their joints and the
/// furniture (docs/kitchens.md).

#include <cstddef>
#include <filesystem>
#include <string>

#include <nlohmann/json.hpp>

#include "multicue/core/point_cloud.hpp"
#include "multicue/mapping/semantic_map.hpp"
#include "multicue/system/report_page.hpp"

namespace multicue {

struct KitchenReportParams {
    /// Points embedded in the page, evenly thinned beyond it; 0 = every finite point [points]
    std::size_t max_points = 250000;
};

/// The page for a map of `cloud` (the cloud the map's indices refer to). `title` names the input.
/// Throws InvalidArgument when the map's point labels do not belong to the cloud.
ReportPage KitchenReportPage(const PointCloud& cloud, const mapping::KitchenMap& map,
                             const std::string& title, const KitchenReportParams& params = {});

}  // namespace multicue

#pragma once
/// \file Outputs of `multicue perceive` (docs/file-formats.md):
/// result.json, labels.pcd (per-point object and category, input order and layout) and
/// models.ply (all models as one mesh, coloured per object).

#include <filesystem>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "multicue/core/point_cloud.hpp"
#include "multicue/core/triangle_mesh.hpp"
#include "multicue/system/perceive.hpp"

namespace multicue {

/// Version of the perceive outputs, "multicue.result/<version>" in result.json. 2: labels.pcd
/// also has PCL's `label` field (uint32, the object id).
inline constexpr int kPerceiveOutputFormatVersion = 2;

/// The result.json object. `timings_ms` are appended after the pipeline's own stage timings.
nlohmann::ordered_json PerceiveResultJson(
    const std::string& input_name, const PerceiveResult& result,
    const std::vector<std::pair<std::string, double>>& timings_ms = {});

/// The labels cloud: the input's points and layout with the object id as `labels` (PCD field
/// `label`, uint32) and extra fields object (uint32, the same id) and category (uint8).
PointCloud PerceiveLabelsCloud(const PointCloud& input, const PerceiveResult& result);
/// The same, taking the input's points instead of copying them: `input` is left empty (its
/// normals and other fields released too), so a large frame is not held twice while it is written.
PointCloud PerceiveLabelsCloud(PointCloud&& input, const PerceiveResult& result);

/// All object models as one mesh, each coloured with the object's colour.
TriangleMesh PerceiveModelsMesh(const PerceiveResult& result);

/// A distinct colour per object id (1-based).
Color ObjectColor(int id);

/// Writes result.json, labels.pcd, models.ply and, when `report_html` is not empty, report.html
/// into `dir` (created if missing). All are written to a staging folder first and moved into place
/// only when every one succeeded, so a failed run leaves an existing folder's files as they were.
/// Throws IoError naming the path.
void WritePerceiveOutputs(const std::filesystem::path& dir, const nlohmann::ordered_json& result,
                          const PointCloud& labels, const TriangleMesh& models,
                          std::string_view report_html = {});

}  // namespace multicue

// `multicue info` and `multicue convert`.

#include <cstdio>
#include <memory>
#include <string>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>

#include "cli_util.hpp"
#include "commands.hpp"
#include "multicue/core/exceptions.hpp"
#include "multicue/core/logging.hpp"
#include "multicue/io/point_cloud_io.hpp"

namespace multicue::cli {
namespace {

std::vector<std::string> FieldNames(const PointCloud& c) {
    std::vector<std::string> f{"x", "y", "z"};
    if (c.HasNormals()) f.insert(f.end(), {"normal_x", "normal_y", "normal_z"});
    if (c.HasCurvature()) f.push_back("curvature");
    if (c.HasColors()) f.push_back("rgba");
    if (c.HasLabels()) f.push_back("label");
    if (c.HasIntensity()) f.push_back("intensity");
    if (c.HasConfidence()) f.push_back("confidence");
    for (const auto& e : c.extra_fields) {
        f.push_back(e.count == 1 ? e.name : fmt::format("{}[{}]", e.name, e.count));
    }
    return f;
}

void PrintInfo(const std::string& path, const PointCloud& c, bool json) {
    const std::size_t finite = c.CountFinite();
    Eigen::Vector3f lo = Eigen::Vector3f::Zero(), hi = Eigen::Vector3f::Zero();
    const bool has_bounds = ComputeBounds(c, lo, hi);
    const auto fields = FieldNames(c);
    const auto& q = c.sensor_orientation;
    const auto& o = c.sensor_origin;
    if (json) {
        nlohmann::ordered_json j;
        j["file"] = path;
        j["points"] = c.size();
        j["width"] = c.width;
        j["height"] = c.height;
        j["organized"] = c.IsOrganized();
        j["finite"] = finite;
        j["nan"] = c.size() - finite;
        j["fields"] = fields;
        j["bounds"] = nullptr;
        if (has_bounds) {
            j["bounds"] = {{"min", {lo.x(), lo.y(), lo.z()}}, {"max", {hi.x(), hi.y(), hi.z()}}};
        }
        j["viewpoint"] = {o.x(), o.y(), o.z(), q.w(), q.x(), q.y(), q.z()};
        std::printf("%s\n", j.dump().c_str());
        return;
    }
    std::string text;
    text += fmt::format("file:       {}\n", path);
    text += fmt::format("points:     {}\n", c.size());
    text += fmt::format("organized:  {}", c.IsOrganized() ? "yes" : "no");
    text += c.IsOrganized() ? fmt::format(" ({} x {})\n", c.width, c.height) : "\n";
    text += fmt::format("finite:     {}\n", finite);
    text += fmt::format("nan:        {}\n", c.size() - finite);
    text += fmt::format("fields:     {}\n", fmt::join(fields, " "));
    if (has_bounds) {
        text += fmt::format("bounds min: {:.4f} {:.4f} {:.4f}\n", lo.x(), lo.y(), lo.z());
        text += fmt::format("bounds max: {:.4f} {:.4f} {:.4f}\n", hi.x(), hi.y(), hi.z());
    } else {
        text += "bounds:     none (no finite points)\n";
    }
    text += fmt::format("viewpoint:  {} {} {}  {} {} {} {}\n", o.x(), o.y(), o.z(), q.w(), q.x(),
                        q.y(), q.z());
    std::fputs(text.c_str(), stdout);
}

}  // namespace

void AddInfoCommand(CLI::App& app, const GlobalOptions& /*global*/) {
    auto* cmd = app.add_subcommand(
        "info", "Print fields, size, organization, bounds and NaN count of a PCD or PLY file");
    auto path = std::make_shared<std::string>();
    auto json = std::make_shared<bool>(false);
    cmd->add_option("FILE", *path, "point cloud (.pcd or .ply)")->required();
    cmd->add_flag("--json", *json, "print one JSON object instead of text");
    cmd->callback([path, json] { PrintInfo(*path, io::ReadPointCloud(*path), *json); });
}

void AddConvertCommand(CLI::App& app, const GlobalOptions& /*global*/) {
    auto* cmd = app.add_subcommand(
        "convert", "Convert between PCD and PLY, or change the encoding; every field is kept");
    auto in = std::make_shared<std::string>();
    auto out = std::make_shared<std::string>();
    auto format = std::make_shared<std::string>("binary");
    cmd->add_option("IN", *in, "input cloud (.pcd or .ply)")->required();
    cmd->add_option("OUT", *out, "output cloud (.pcd or .ply)")->required();
    AddFormatOption(*cmd, *format);
    cmd->callback([in, out, format] {
        const auto encoding = io::ParseEncoding(*format);
        CheckDistinctPaths(*in, *out);
        const PointCloud cloud = io::ReadPointCloud(*in);
        io::WritePointCloud(*out, cloud, encoding);
        LogInfo("wrote {} points to {}", cloud.size(), *out);
    });
}

}  // namespace multicue::cli

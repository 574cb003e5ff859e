// `multicue downsample`, `multicue normals` and `multicue outliers`.

#include <limits>
#include <memory>
#include <optional>
#include <string>

#include <fmt/format.h>

#include "cli_util.hpp"
#include "commands.hpp"
#include "multicue/core/exceptions.hpp"
#include "multicue/core/logging.hpp"
#include "multicue/filters/outlier_removal.hpp"
#include "multicue/filters/voxel_grid.hpp"
#include "multicue/io/point_cloud_io.hpp"
#include "multicue/search/kdtree.hpp"
#include "multicue/surface/normals.hpp"

namespace multicue::cli {
namespace {

/// Keeps the selected points. Organized clouds stay organized when asked: dropped points become
/// NaN.
PointCloud KeepPoints(const PointCloud& cloud, const Indices& keep, bool keep_organized) {
    if (!keep_organized || !cloud.IsOrganized()) return SelectByIndex(cloud, keep);
    PointCloud out = cloud;
    std::vector<bool> kept(cloud.size(), false);
    for (Index i : keep) kept[i] = true;
    const float nan = std::numeric_limits<float>::quiet_NaN();
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        if (kept[i]) continue;
        out.points[i] = Eigen::Vector3f::Constant(nan);
        if (out.HasNormals()) out.normals[i] = Eigen::Vector3f::Constant(nan);
        if (out.HasCurvature()) out.curvature[i] = nan;
    }
    return out;
}

}  // namespace

void AddDownsampleCommand(CLI::App& app, const GlobalOptions& global) {
    auto* cmd = app.add_subcommand(
        "downsample", "Voxel-grid downsampling: one point per voxel at the centroid of its points");
    auto in = std::make_shared<std::string>();
    auto out = std::make_shared<std::string>();
    auto format = std::make_shared<std::string>("binary");
    auto params = std::make_shared<VoxelGridParams>();
    cmd->add_option("IN", *in, "input cloud (.pcd or .ply)")->required();
    cmd->add_option("OUT", *out, "output cloud (.pcd or .ply)")->required();
    cmd->add_option("--leaf", params->leaf_size, "voxel edge length [m]")->capture_default_str();
    cmd->add_option("--min-points", params->min_points_per_voxel,
                    "voxels with fewer points are dropped")
        ->capture_default_str();
    AddFormatOption(*cmd, *format);
    cmd->callback([in, out, format, params, &global] {
        const auto encoding = io::ParseEncoding(*format);
        CheckDistinctPaths(*in, *out);
        params->num_threads = global.threads;
        const PointCloud cloud = ReadNonEmptyCloud(*in);
        const PointCloud down = VoxelGrid(cloud, *params);
        io::WritePointCloud(*out, down, encoding);
        LogInfo("{} -> {} points", cloud.CountFinite(), down.size());
    });
}

void AddNormalsCommand(CLI::App& app, const GlobalOptions& global) {
    auto* cmd = app.add_subcommand(
        "normals",
        "PCA normals and curvature, oriented towards the viewpoint (k-d tree or, for organized "
        "RGB-D frames, image-space neighbourhoods)");
    auto in = std::make_shared<std::string>();
    auto out = std::make_shared<std::string>();
    auto format = std::make_shared<std::string>("binary");
    auto k = std::make_shared<int>(0);
    auto radius = std::make_shared<float>(0.0f);
    auto organized = std::make_shared<bool>(false);
    auto viewpoint = std::make_shared<std::string>();
    cmd->add_option("IN", *in, "input cloud (.pcd or .ply)")->required();
    cmd->add_option("OUT", *out, "output cloud with normal_x/y/z and curvature")->required();
    cmd->add_option("--k", *k, "number of neighbours (default 20 when no radius is given)");
    cmd->add_option("--radius", *radius, "neighbourhood radius [m]; with --k, caps the count");
    cmd->add_flag("--organized", *organized,
                  "use the image-space fast path (input must be an organized cloud)");
    cmd->add_option("--viewpoint", *viewpoint,
                    "x,y,z to orient normals towards (default: the file's VIEWPOINT)");
    AddFormatOption(*cmd, *format);
    cmd->callback([=, &global] {
        const auto encoding = io::ParseEncoding(*format);
        CheckDistinctPaths(*in, *out);
        if (*k < 0) throw InvalidArgument(fmt::format("--k must be > 0, got {}", *k));
        if (*radius < 0.0f) {
            throw InvalidArgument(fmt::format("--radius must be > 0, got {}", *radius));
        }
        std::optional<Eigen::Vector3f> vp;
        if (!viewpoint->empty()) vp = ParseVector3(*viewpoint, "--viewpoint");
        PointCloud cloud = ReadNonEmptyCloud(*in);
        NormalsResult result;
        if (*organized) {
            if (!cloud.IsOrganized()) {
                throw InvalidArgument(
                    fmt::format("--organized needs an organized cloud; {} is {}x{}", *in,
                                cloud.width, cloud.height));
            }
            OrganizedNormalParams p;
            p.viewpoint = vp;
            p.num_threads = global.threads;
            result = EstimateNormalsOrganized(cloud, p);
        } else {
            NormalParams p;
            p.k = (*k == 0 && *radius == 0.0f) ? 20 : *k;
            p.radius = *radius;
            p.viewpoint = vp;
            p.num_threads = global.threads;
            const KdTree tree(cloud);
            result = EstimateNormals(cloud, tree, p);
        }
        const std::size_t undefined = result.undefined;
        SetNormals(cloud, std::move(result));
        io::WritePointCloud(*out, cloud, encoding);
        LogInfo("normals for {} points ({} undefined)", cloud.size(), undefined);
    });
}

void AddOutliersCommand(CLI::App& app, const GlobalOptions& global) {
    auto* cmd = app.add_subcommand("outliers",
                                   "Statistical or radius outlier removal (drops NaN points too)");
    auto in = std::make_shared<std::string>();
    auto out = std::make_shared<std::string>();
    auto format = std::make_shared<std::string>("binary");
    auto method = std::make_shared<std::string>("statistical");
    auto stat = std::make_shared<StatisticalOutlierParams>();
    auto rad = std::make_shared<RadiusOutlierParams>();
    auto keep_organized = std::make_shared<bool>(false);
    cmd->add_option("IN", *in, "input cloud (.pcd or .ply)")->required();
    cmd->add_option("OUT", *out, "output cloud without the outliers")->required();
    cmd->add_option("--method", *method, "statistical or radius")
        ->check(CLI::IsMember({"statistical", "radius"}))
        ->capture_default_str();
    cmd->add_option("--k", stat->k, "statistical: neighbours for the mean distance")
        ->capture_default_str();
    cmd->add_option("--std", stat->std_ratio, "statistical: keep points within mean + std * stddev")
        ->capture_default_str();
    cmd->add_option("--radius", rad->radius, "radius: neighbourhood radius [m]")
        ->capture_default_str();
    cmd->add_option("--min-neighbors", rad->min_neighbors,
                    "radius: neighbours (besides the point) needed to keep it")
        ->capture_default_str();
    cmd->add_flag("--keep-organized", *keep_organized,
                  "organized input stays organized; removed points become NaN");
    AddFormatOption(*cmd, *format);
    cmd->callback([=, &global] {
        const auto encoding = io::ParseEncoding(*format);
        CheckDistinctPaths(*in, *out);
        const PointCloud cloud = ReadNonEmptyCloud(*in);
        const KdTree tree(cloud);
        Indices keep;
        if (*method == "statistical") {
            stat->num_threads = global.threads;
            keep = StatisticalOutlierRemoval(cloud, tree, *stat);
        } else {
            rad->num_threads = global.threads;
            keep = RadiusOutlierRemoval(cloud, tree, *rad);
        }
        io::WritePointCloud(*out, KeepPoints(cloud, keep, *keep_organized), encoding);
        LogInfo("kept {} of {} finite points", keep.size(), cloud.CountFinite());
    });
}

}  // namespace multicue::cli

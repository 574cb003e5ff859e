// `multicue features`: RSD, surface types, GRSD, GRSD-, VFH, PFH, FPFH, PFHRGB and part
// statistics per point or per cluster/part (thesis sections 2.5 and 4.2.3.1).

#include <cmath>
#include <cstring>
#include <map>
#include <memory>
#include <ostream>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "cli_util.hpp"
#include "commands.hpp"
#include "multicue/core/exceptions.hpp"
#include "multicue/core/logging.hpp"
#include "multicue/features/features.hpp"
#include "multicue/io/file_utils.hpp"
#include "multicue/io/point_cloud_io.hpp"
#include "multicue/search/kdtree.hpp"
#include "multicue/surface/normals.hpp"

namespace multicue::cli {
namespace {

// Registry name of each --type.
std::string RegistryName(const std::string& type) {
    return type == "surface-types" ? std::string() : type;
}

bool IsClusterOnly(const std::string& type) {
    return type == "grsd" || type == "grsd-minus" || type == "vfh" || type == "part-stats";
}

FeatureMatrix PerPoint(const std::string& type, const PointCloud& cloud, float radius,
                       int threads) {
    const KdTree tree(cloud);
    if (type == "rsd") return ComputeRsd(cloud, tree, {.radius = radius, .num_threads = threads});
    if (type == "surface-types") {
        const FeatureMatrix rsd =
            ComputeRsd(cloud, tree, {.radius = radius, .num_threads = threads});
        const auto types = LabelSurfaceTypes(rsd);
        FeatureMatrix out(static_cast<Eigen::Index>(types.size()), 1);
        for (std::size_t i = 0; i < types.size(); ++i) {
            out(static_cast<Eigen::Index>(i), 0) = static_cast<float>(types[i]);
        }
        return out;
    }
    const PairFeatureParams p{.radius = radius, .num_threads = threads};
    if (type == "fpfh") return ComputeFpfh(cloud, tree, p);
    if (type == "pfh") return ComputePfh(cloud, tree, p);
    return ComputePfhRgb(cloud, tree, p);
}

// Writes per-point features as CSV (index, values) or as a cloud with the feature as fields.
void WritePerPoint(const std::string& out, const std::string& type, PointCloud cloud,
                   const FeatureMatrix& f) {
    const std::string ext = io::LowerExtension(out);
    if (ext == "pcd" || ext == "ply") {
        ExtraField field;
        if (type == "surface-types") {
            field = {"surface_type", 'U', 1, 1, {}};
            field.data.resize(cloud.size());
            for (std::size_t i = 0; i < cloud.size(); ++i) {
                field.data[i] = static_cast<std::uint8_t>(f(static_cast<Eigen::Index>(i), 0));
            }
            cloud.extra_fields.push_back(std::move(field));
        } else if (type == "rsd") {
            for (int c = 0; c < 2; ++c) {
                ExtraField e{c == 0 ? "r_min" : "r_max", 'F', 4, 1, {}};
                e.data.resize(cloud.size() * 4);
                for (std::size_t i = 0; i < cloud.size(); ++i) {
                    const float v = f(static_cast<Eigen::Index>(i), c);
                    std::memcpy(e.data.data() + 4 * i, &v, 4);
                }
                cloud.extra_fields.push_back(std::move(e));
            }
        } else {
            if (ext == "ply") {
                throw InvalidArgument(
                    fmt::format("--type {} per point has {} values: write .pcd or .csv, not .ply",
                                type, f.cols()));
            }
            ExtraField e{type, 'F', 4, static_cast<std::uint32_t>(f.cols()), {}};
            e.data.resize(cloud.size() * 4 * static_cast<std::size_t>(f.cols()));
            std::memcpy(e.data.data(), f.data(), e.data.size());
            cloud.extra_fields.push_back(std::move(e));
        }
        io::WritePointCloud(out, cloud, io::Encoding::kBinary);
        return;
    }
    io::WriteFileAtomically(out, [&](std::ostream& os) {
        os << "index";
        for (Eigen::Index c = 0; c < f.cols(); ++c) {
            os << ","
               << (type == "rsd"             ? (c == 0 ? "r_min" : "r_max")
                   : type == "surface-types" ? "surface_type"
                                             : fmt::format("{}{}", type, c));
        }
        os << "\n";
        for (Eigen::Index i = 0; i < f.rows(); ++i) {
            os << i;
            for (Eigen::Index c = 0; c < f.cols(); ++c) {
                if (type == "surface-types") {
                    os << "," << SurfaceTypeName(static_cast<SurfaceType>(f(i, c)));
                } else {
                    os << "," << fmt::format("{:.7g}", f(i, c));
                }
            }
            os << "\n";
        }
    });
}

void WritePerCluster(const std::string& out, const std::string& type,
                     const std::map<std::uint32_t, FeatureVector>& values,
                     const std::map<std::uint32_t, std::size_t>& sizes) {
    const bool json = io::LowerExtension(out) == "json";
    io::WriteFileAtomically(out, [&](std::ostream& os) {
        if (json) {
            nlohmann::json j;
            j["feature"] = type;
            j["dimension"] = values.empty() ? 0 : values.begin()->second.size();
            j["clusters"] = nlohmann::json::array();
            for (const auto& [label, v] : values) {
                j["clusters"].push_back(
                    {{"label", label},
                     {"points", sizes.at(label)},
                     {"values", std::vector<float>(v.data(), v.data() + v.size())}});
            }
            os << j.dump(1) << "\n";
            return;
        }
        os << "label,points";
        const Eigen::Index dim = values.empty() ? 0 : values.begin()->second.size();
        for (Eigen::Index c = 0; c < dim; ++c) os << "," << type << c;
        os << "\n";
        for (const auto& [label, v] : values) {
            os << label << "," << sizes.at(label);
            for (Eigen::Index c = 0; c < v.size(); ++c) os << "," << fmt::format("{:.7g}", v[c]);
            os << "\n";
        }
    });
}

}  // namespace

void AddFeaturesCommand(CLI::App& app, const GlobalOptions& global) {
    auto* cmd = app.add_subcommand(
        "features",
        "Point and cluster features: RSD, surface types, GRSD, GRSD-, VFH, PFH, FPFH, PFHRGB, "
        "part statistics");
    auto in = std::make_shared<std::string>();
    auto out = std::make_shared<std::string>();
    auto type = std::make_shared<std::string>();
    auto per = std::make_shared<std::string>();
    auto radius = std::make_shared<float>(0.0f);
    auto normal_radius = std::make_shared<float>(0.015f);
    cmd->add_option("IN", *in, "input cloud (.pcd or .ply)")->required();
    cmd->add_option("--type", *type, "feature")
        ->required()
        ->check(CLI::IsMember({"rsd", "surface-types", "grsd", "grsd-minus", "vfh", "pfh", "fpfh",
                               "pfhrgb", "part-stats"}));
    cmd->add_option("--out", *out,
                    "output: per point .csv, .pcd (feature as fields) or .ply (rsd, "
                    "surface-types); per cluster .csv or .json")
        ->required();
    cmd->add_option("--radius", *radius,
                    "neighbourhood radius [m] (default 0.02 for rsd/surface-types/part-stats, "
                    "0.03 for pfh/fpfh/pfhrgb)");
    cmd->add_option("--per", *per,
                    "point, cluster or part (clusters/parts = the input's label field; default: "
                    "point for local features, cluster for global ones)")
        ->check(CLI::IsMember({"point", "cluster", "part"}));
    cmd->add_option("--normal-radius", *normal_radius,
                    "radius of the normals computed when the input has none [m]")
        ->capture_default_str();
    cmd->callback([=, &global] {
        CheckDistinctPaths(*in, *out);
        if (*radius < 0.0f || !std::isfinite(*radius) ||
            (*radius == 0.0f && cmd->count("--radius") > 0)) {
            throw InvalidArgument(fmt::format("--radius must be > 0, got {}", *radius));
        }
        if (!(*normal_radius > 0.0f)) {
            throw InvalidArgument(
                fmt::format("--normal-radius must be > 0, got {}", *normal_radius));
        }
        std::string mode = per->empty() ? (IsClusterOnly(*type) ? "cluster" : "point") : *per;
        if (mode == "part") mode = "cluster";
        if (mode == "point" && IsClusterOnly(*type)) {
            throw InvalidArgument(fmt::format("--type {} is computed per cluster or part", *type));
        }
        if (mode == "cluster" && *type == "surface-types") {
            throw InvalidArgument("--type surface-types is computed per point");
        }
        const bool local_pairs = *type == "pfh" || *type == "fpfh" || *type == "pfhrgb";
        const float r = *radius > 0.0f ? *radius : (local_pairs ? 0.03f : 0.02f);

        PointCloud cloud = ReadNonEmptyCloud(*in);
        if (*type == "pfhrgb" && !cloud.HasColors()) {
            throw DataError(fmt::format("{} has no colours: pfhrgb needs rgb or rgba", *in));
        }
        if (!cloud.HasNormals()) {
            const KdTree tree(cloud);
            SetNormals(cloud,
                       EstimateNormals(cloud, tree,
                                       {.radius = *normal_radius, .num_threads = global.threads}));
            LogInfo("normals computed with radius {}", *normal_radius);
        }
        if (mode == "point") {
            const FeatureMatrix f = PerPoint(*type, cloud, r, global.threads);
            WritePerPoint(*out, *type, cloud, f);
            LogInfo("{}: {} of {} points defined", *type, CountDefinedRows(f), cloud.size());
            return;
        }
        // One cluster per label value; without labels the whole cloud is one cluster (label 0).
        std::map<std::uint32_t, Indices> clusters;
        for (std::size_t i = 0; i < cloud.size(); ++i) {
            clusters[cloud.HasLabels() ? cloud.labels[i] : 0].push_back(static_cast<Index>(i));
        }
        ClusterFeatureParams params;
        params.radius = r;
        params.rsd_radius = *radius > 0.0f && !local_pairs ? *radius : 0.02f;
        params.num_threads = global.threads;
        std::map<std::uint32_t, FeatureVector> values;
        std::map<std::uint32_t, std::size_t> sizes;
        for (const auto& [label, indices] : clusters) {
            const PointCloud cluster = SelectByIndex(cloud, indices);
            values[label] = ComputeClusterFeature(RegistryName(*type), cluster, params);
            sizes[label] = indices.size();
        }
        WritePerCluster(*out, *type, values, sizes);
        LogInfo("{}: {} clusters", *type, values.size());
    });
}

}  // namespace multicue::cli

#include "multicue/features/registry.hpp"

#include <array>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/features/colour.hpp"
#include "multicue/features/grsd.hpp"
#include "multicue/features/part_stats.hpp"
#include "multicue/features/pfh.hpp"
#include "multicue/features/rsd.hpp"
#include "multicue/features/vfh.hpp"

namespace multicue {
namespace {

template <FeatureMatrix (*Local)(const PointCloud&, const KdTree&, const PairFeatureParams&)>
FeatureVector MeanLocal(const PointCloud& cluster, const ClusterFeatureParams& p) {
    const KdTree tree(cluster);
    return MeanOfDefinedRows(
        Local(cluster, tree, {.radius = p.radius, .num_threads = p.num_threads}));
}

FeatureVector Rsd(const PointCloud& cluster, const ClusterFeatureParams& p) {
    const KdTree tree(cluster);
    return MeanOfDefinedRows(
        ComputeRsd(cluster, tree, {.radius = p.rsd_radius, .num_threads = p.num_threads}));
}

GrsdParams ToGrsd(const ClusterFeatureParams& p) {
    GrsdParams g;
    g.voxels.voxel_size = p.voxel_size;
    g.voxels.rsd.radius = p.rsd_radius;
    g.voxels.rsd.num_threads = p.num_threads;
    g.viewpoint = p.viewpoint;
    return g;
}

FeatureVector Grsd(const PointCloud& c, const ClusterFeatureParams& p) {
    return ComputeGrsd(c, ToGrsd(p));
}
FeatureVector GrsdMinus(const PointCloud& c, const ClusterFeatureParams& p) {
    return ComputeGrsdMinus(c, ToGrsd(p));
}
FeatureVector Vfh(const PointCloud& c, const ClusterFeatureParams& p) {
    return ComputeVfh(c, {.viewpoint = p.viewpoint});
}
FeatureVector PartStats(const PointCloud& c, const ClusterFeatureParams& p) {
    return ComputePartStatistics(c, {.radius = p.rsd_radius,
                                     .voxel_size = p.part_voxel_size,
                                     .up = p.up,
                                     .num_threads = p.num_threads});
}

FeatureVector Colour(const PointCloud& c, const ClusterFeatureParams&) {
    return ComputeColourHistogram(c);
}

const std::array<ClusterFeature, 9> kFeatures = {{
    {"rsd", 2, "mean RSD radii (r_min, r_max) [m], section 2.5.1", Rsd},
    {"grsd", kGrsdSize, "GRSD with ray-cast free space, section 2.5.2", Grsd},
    {"grsd-minus", kGrsdSize, "additive GRSD-, section 2.5.2", GrsdMinus},
    {"vfh", kVfhSize, "Viewpoint Feature Histogram", Vfh},
    {"pfh", kPfhSize, "mean PFH", MeanLocal<ComputePfh>},
    {"fpfh", kFpfhSize, "mean FPFH", MeanLocal<ComputeFpfh>},
    {"pfhrgb", kPfhRgbSize, "mean PFHRGB (needs colours)", MeanLocal<ComputePfhRgb>},
    {"part-stats", kPartStatsSize, "24 part statistics, section 4.2.3.1", PartStats},
    {"colour", kColourHistogramSize, "HSV colour histogram (needs colours)", Colour},
}};

}  // namespace

std::span<const ClusterFeature> ClusterFeatures() { return kFeatures; }

const ClusterFeature& FindClusterFeature(std::string_view name) {
    for (const auto& f : kFeatures) {
        if (f.name == name) return f;
    }
    std::string known;
    for (const auto& f : kFeatures) known += (known.empty() ? "" : ", ") + std::string(f.name);
    throw InvalidArgument(fmt::format("unknown feature '{}' (known: {})", name, known));
}

FeatureVector ComputeClusterFeature(std::string_view name, const PointCloud& cluster,
                                    const ClusterFeatureParams& params) {
    const ClusterFeature& feature = FindClusterFeature(name);
    if (cluster.empty()) return FeatureVector::Zero(feature.dimension);
    return feature.compute(cluster, params);
}

}  // namespace multicue

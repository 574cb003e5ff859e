#include "multicue/segmentation/part_segmentation.hpp"

#include <algorithm>
#include <optional>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/core/parallel.hpp"
#include "multicue/search/kdtree.hpp"
#include "multicue/search/organized.hpp"

namespace multicue {
namespace {

// The parts of `parts` that belong to `object` (judged by their first point: the concave split
// keeps parts whole).
std::vector<Indices> PartsOf(const Indices& object, const std::vector<Indices>& parts) {
    std::vector<Indices> out;
    for (const auto& part : parts) {
        if (!part.empty() && std::binary_search(object.begin(), object.end(), part.front())) {
            out.push_back(part);
        }
    }
    return out;
}

}  // namespace

void PartSegmentationParams::Validate() const {
    ValidateNode("region_growing", [&] { region_growing.Validate(); });
    ValidateNode("convexity", [&] { convexity.Validate(); });
    if (organized_half_window < 0) {
        throw InvalidArgument(fmt::format("organized_half_window must be >= 0 [pixels], got {}",
                                          organized_half_window));
    }
    ResolveThreadCount(num_threads);
}

PartSegmentationResult SegmentParts(const PointCloud& cloud, const std::vector<Indices>& clusters,
                                    const Eigen::Vector4f& plane,
                                    const PartSegmentationParams& params,
                                    std::size_t min_object_points) {
    params.Validate();
    if (!clusters.empty() && !cloud.HasNormals())
        throw DataError("part segmentation needs normals");
    // Neighbours among the points of every hypothesis: on organized frames searched once for all
    // of them in pixel windows (in parallel), else from one k-d tree over all of them.
    const bool organized = cloud.IsOrganized() && params.organized_half_window > 0;
    Indices all;
    for (const auto& c : clusters) all.insert(all.end(), c.begin(), c.end());
    std::sort(all.begin(), all.end());
    std::optional<KdTree> tree;
    NeighbourTable table;
    if (organized) {
        std::vector<std::uint8_t> mask(cloud.size(), 0);
        for (Index i : all) mask.at(i) = 1;
        table = OrganizedNeighbourTable(cloud, all, params.region_growing,
                                        {.half_window = params.organized_half_window, .mask = mask},
                                        params.num_threads);
    } else {
        tree.emplace(cloud, all);
    }
    std::vector<std::vector<ObjectSegment>> split(clusters.size());
    ParallelFor(
        clusters.size(), params.num_threads,
        [&](std::size_t k) {
            RegionGrowingParams rg = params.region_growing;
            rg.subset = clusters[k];
            const std::vector<Indices> parts = organized ? RegionGrowing(cloud, table, rg).parts
                                                         : RegionGrowing(cloud, *tree, rg).parts;
            if (params.convexity.enabled) {
                ConvexitySplitParams cp = params.convexity;
                cp.min_object_points = min_object_points;
                ConvexitySplitResult r = SplitByConvexity(cloud, clusters[k], parts, cp, plane);
                for (std::size_t g = 0; g < r.objects.size(); ++g) {
                    split[k].push_back({std::move(r.objects[g]), std::move(r.parts[g])});
                }
            } else {
                split[k].push_back({clusters[k], PartsOf(clusters[k], parts)});
            }
        },
        1);
    PartSegmentationResult result;
    for (auto& pieces : split) {
        if (pieces.size() > 1) ++result.split_hypotheses;
        for (auto& o : pieces) {
            if (o.indices.size() < min_object_points) {
                ++result.dropped_pieces;
                continue;
            }
            result.objects.push_back(std::move(o));
        }
    }
    return result;
}

}  // namespace multicue

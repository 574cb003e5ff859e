#include "multicue/system/perceive.hpp"

#include <algorithm>
#include <chrono>
#include <iterator>
#include <limits>
#include <optional>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/core/logging.hpp"
#include "multicue/core/parallel.hpp"
#include "multicue/search/organized.hpp"

namespace multicue {
namespace {

class StageTimer {
  public:
    explicit StageTimer(std::vector<std::pair<std::string, double>>& out) : out_(out) {}
    void Done(const char* stage) {
        const auto now = std::chrono::steady_clock::now();
        out_.emplace_back(stage, std::chrono::duration<double, std::milli>(now - start_).count());
        start_ = now;
    }

  private:
    std::vector<std::pair<std::string, double>>& out_;
    std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
};

// Every parameter and the categoriser's model, before any work; then the cloud.
void CheckInputs(const PointCloud& cloud, const PerceiveParams& params,
                 const PerceiveModels& models) {
    params.Validate();
    CheckCategorizationModel(params.category, models.part_graph.get());
    cloud.Validate();
    if (!cloud.HasFinite()) {
        throw DataError(fmt::format("no valid points: all {} points are NaN or the cloud is empty",
                                    cloud.size()));
    }
}

std::vector<PerceivedObject> ToObjects(std::vector<ObjectSegment> segments) {
    std::vector<PerceivedObject> objects(segments.size());
    for (std::size_t k = 0; k < segments.size(); ++k) {
        objects[k].id = static_cast<int>(k + 1);
        objects[k].indices = std::move(segments[k].indices);
        objects[k].parts = std::move(segments[k].parts);
    }
    return objects;
}

// The objects a grouping stage merged or split, categorised and modelled again (within the
// categories its model allows).
void Refit(const PointCloud& cloud, std::vector<PerceivedObject>& objects, const GroupingResult& g,
           const Eigen::Vector4f& plane, const PerceiveParams& params,
           const PerceiveModels& models) {
    if (g.changed.empty()) return;
    CategorizeObjects(cloud, objects, plane, params.category, models.part_graph.get(), g.changed,
                      g.allowed);
    ModelObjects(cloud, objects, plane, params.models, g.changed);
}

}  // namespace

void PerceiveParams::Validate() const {
    ValidateNode("threads", [&] { ResolveThreadCount(num_threads); });
    ValidateNode("normals", [&] { normals.Validate(); });
    ValidateNode("support", [&] { support.Validate(); });
    ValidateNode("prism", [&] { prism.Validate(); });
    ValidateNode("clustering", [&] { clustering.Validate(); });
    ValidateNode("parts", [&] { parts.Validate(); });
    ValidateNode("occlusion", [&] { occlusion.Validate(); });
    ValidateNode("category", [&] { category.Validate(); });
    ValidateNode("models", [&] { models.Validate(); });
    ValidateNode("floors", [&] { floors.Validate(); });
}

PerceiveParams ApplyThreadCount(PerceiveParams p) {
    p.normals.organized.num_threads = p.normals.unorganized.num_threads = p.num_threads;
    p.support.num_threads = p.num_threads;
    p.clustering.num_threads = p.num_threads;
    p.parts.num_threads = p.num_threads;
    p.category.num_threads = p.num_threads;
    p.models.num_threads = p.num_threads;
    p.occlusion.num_threads = p.num_threads;
    return p;
}

void LabelPoints(const PointCloud& cloud, PerceiveResult& result) {
    result.point_objects.assign(cloud.size(), 0);
    result.point_categories.assign(cloud.size(), 0);
    for (std::size_t k = 0; k < result.objects.size(); ++k) {
        PerceivedObject& o = result.objects[k];
        o.id = static_cast<int>(k + 1);
        Eigen::Vector3d sum = Eigen::Vector3d::Zero();
        for (Index i : o.indices) {
            if (i >= cloud.size()) {
                throw InvalidArgument(
                    fmt::format("object {} has point {} of a cloud of {}", o.id, i, cloud.size()));
            }
            sum += cloud.points[i].cast<double>();
            result.point_objects[i] = static_cast<std::uint32_t>(o.id);
            result.point_categories[i] = static_cast<std::uint8_t>(o.category.category);
        }
        o.centroid = (sum / std::max<std::size_t>(1, o.indices.size())).cast<float>();
    }
}

namespace {

// The table-band points that a low object's own points enclose join the object as one more part
// (its floor) and leave the table's inliers. Categories and models stay those of the object
// without them.
void AddEnclosedFloors(const PointCloud& cloud, const Eigen::Vector4f& plane,
                       const PerceiveParams& params, std::vector<PerceivedObject>& objects,
                       Indices& table_inliers) {
    std::vector<Indices> points;
    points.reserve(objects.size());
    for (const PerceivedObject& o : objects) points.push_back(o.indices);
    const std::vector<Indices> floors =
        EnclosedFloors(cloud, plane, points, params.prism.min_height, params.floors);
    Indices all;
    for (std::size_t k = 0; k < objects.size(); ++k) {
        if (floors[k].empty()) continue;
        Indices joined;
        joined.reserve(objects[k].indices.size() + floors[k].size());
        std::merge(objects[k].indices.begin(), objects[k].indices.end(), floors[k].begin(),
                   floors[k].end(), std::back_inserter(joined));
        objects[k].indices = std::move(joined);
        all.insert(all.end(), floors[k].begin(), floors[k].end());
        // The floor is a part of its own, named as its object.
        objects[k].parts.push_back(floors[k]);
        if (!objects[k].part_probabilities.empty())
            objects[k].part_probabilities.push_back(objects[k].category.probabilities);
    }
    if (all.empty()) return;
    std::sort(all.begin(), all.end());
    Indices kept;
    kept.reserve(table_inliers.size());
    std::set_difference(table_inliers.begin(), table_inliers.end(), all.begin(), all.end(),
                        std::back_inserter(kept));
    table_inliers = std::move(kept);
}

// The stages on one frame (parameters checked already), in `cloud` itself: the normals stage
// adds normals and curvature to it when it has none.
PerceiveResult PerceiveFrame(PointCloud& cloud, const PerceiveParams& params,
                             const PerceiveModels& models) {
    PerceiveResult result;
    result.points = cloud.size();
    StageTimer timer(result.timings_ms);
    const std::size_t min_points = params.clustering.min_points;

    // The table and the points above it (section 2.4), their normals, object hypotheses.
    TableRegion table = FindTableRegion(cloud, params.support, params.prism);
    result.support = std::move(table.support);
    const Eigen::Vector4f plane =
        result.support.found ? result.support.plane : Eigen::Vector4f::Zero();
    timer.Done("support_plane");
    EnsureFrameNormals(cloud, table.points, params.normals);
    timer.Done("normals");
    const ClusteringResult clusters = ClusterObjects(cloud, table.points, params.clustering);
    timer.Done("clustering");

    // Parts, hypotheses split at concave creases (section 4.2.1), occluded fragments joined.
    auto segments = SegmentParts(cloud, clusters.clusters, plane, params.parts, min_points).objects;
    timer.Done("parts");
    segments = MergeOccludedObjects(cloud, std::move(segments), plane, params.occlusion);
    timer.Done("occlusion");

    // Categories (sections 3.3, 5.1).
    std::vector<PerceivedObject> objects = ToObjects(std::move(segments));
    CategorizeObjects(cloud, objects, plane, params.category, models.part_graph.get());
    timer.Done("categories");

    // Models (section 5.4) and grouping by models (section 5.4.1): what a stage merges or splits
    // is categorised and modelled again before the next stage looks.
    ModelObjects(cloud, objects, plane, params.models);
    const auto refit = [&](const GroupingResult& g) {
        Refit(cloud, objects, g, plane, params, models);
    };
    refit(MergeConcentricObjects(objects, params.models.concentric));
    refit(MergeContainedObjects(cloud, objects, params.models.contained));
    refit(SplitStackedBoxes(cloud, objects, plane, params.models, min_points));
    refit(SplitTouchingBoxes(cloud, objects, plane, params.models, min_points));
    refit(SplitTouchingRound(cloud, objects, plane, params.models, min_points));
    CategorizeByModels(objects, params.category);
    timer.Done("models");
    if (params.floors.enabled && result.support.found) {
        AddEnclosedFloors(cloud, plane, params, objects, result.support.inliers);
        timer.Done("floors");
    }

    result.objects = std::move(objects);
    LabelPoints(cloud, result);
    return result;
}

// Makes the points farther than kMaxPerceiveRange from the sensor frame's origin invalid (NaN).
// Such points are no measurement of a table top (a corrupt pixel, a value in the wrong units);
// beyond about 1e18 m squared distances would not even be finite, and the voxel grids of the
// stages would leave the 32-bit range much sooner.
void MakeFarPointsInvalid(PointCloud& cloud) {
    const auto far = [](const Eigen::Vector3f& p) {
        return p.allFinite() && p.cwiseAbs().maxCoeff() > kMaxPerceiveRange;
    };
    const std::size_t n =
        static_cast<std::size_t>(std::count_if(cloud.points.begin(), cloud.points.end(), far));
    if (n == 0) return;
    const std::size_t finite = cloud.CountFinite();
    if (n == finite) {
        throw DataError(fmt::format(
            "no valid points: all {} finite points lie farther than {:.0e} m from the sensor "
            "(wrong units?)",
            finite, kMaxPerceiveRange));
    }
    LogWarning(
        "perceive: {} of {} points lie farther than {:.0e} m from the sensor and are left "
        "out as invalid",
        n, finite, kMaxPerceiveRange);
    for (auto& p : cloud.points) {
        if (far(p)) p = Eigen::Vector3f::Constant(std::numeric_limits<float>::quiet_NaN());
    }
}

// Point indices of the recovered grid mapped to the input's, ascending.
void ToInput(Indices& indices, const ImageGrid& grid) {
    for (Index& i : indices) i = grid.input_of[i];
    std::sort(indices.begin(), indices.end());
}

}  // namespace

PerceiveResult Perceive(const PointCloud& cloud, const PerceiveParams& params,
                        const PerceiveModels& models) {
    PointCloud frame = cloud;
    return PerceiveInPlace(frame, params, models);
}

PerceiveResult PerceiveInPlace(PointCloud& input, const PerceiveParams& given,
                               const PerceiveModels& models) {
    const PerceiveParams params = ApplyThreadCount(given);
    CheckInputs(input, params, models);
    MakeFarPointsInvalid(input);
    PerceiveResult result;
    const auto start = std::chrono::steady_clock::now();
    std::optional<ImageGrid> grid;
    if (params.image_grid && !input.IsOrganized())
        grid = RecoverImageGrid(input, params.num_threads);
    if (!grid) {
        result = PerceiveFrame(input, params, models);
    } else {
        const double ms =
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
                .count();
        result = PerceiveFrame(grid->organized, params, models);
        result.timings_ms.insert(result.timings_ms.begin(), {"image_grid", ms});
        result.points = input.size();
        ToInput(result.support.inliers, *grid);
        for (PerceivedObject& o : result.objects) {
            ToInput(o.indices, *grid);
            for (Indices& part : o.parts) ToInput(part, *grid);
        }
        LabelPoints(input, result);
        LogDebug("perceive: the unorganized cloud was perceived on its {}x{} pixel grid",
                 grid->organized.width, grid->organized.height);
    }
    LogInfo("perceive: support {}, {} objects", result.support.found ? "found" : "none",
            result.objects.size());
    return result;
}

}  // namespace multicue

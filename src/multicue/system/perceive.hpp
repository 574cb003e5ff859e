#pragma once
/// \file The table-top perception pipeline behind `multicue perceive` (thesis sections 2.4,
/// 3.2.1, 4.2.1, 5.1 and 5.4): support plane, normals, object hypotheses, parts, categories, and
/// models with grouping by models. Each stage is a public function of the module that owns it;
/// Perceive() runs them in order. PerceiveParams is the tree of their parameters, shaped like the
/// configuration file (ReadPerceiveParams, `multicue config --dump`).

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "multicue/core/params.hpp"
#include "multicue/core/point_cloud.hpp"
#include "multicue/io/config.hpp"
#include "multicue/recognition/part_graph_model.hpp"
#include "multicue/reconstruction/model_grouping.hpp"
#include "multicue/reconstruction/object_model.hpp"
#include "multicue/segmentation/enclosed_floors.hpp"
#include "multicue/segmentation/euclidean_clustering.hpp"
#include "multicue/segmentation/occlusion_merge.hpp"
#include "multicue/segmentation/part_segmentation.hpp"
#include "multicue/segmentation/polygonal_prism.hpp"
#include "multicue/segmentation/support_plane.hpp"
#include "multicue/surface/normals.hpp"
#include "multicue/system/object_categories.hpp"

namespace multicue {

/// Points farther than this from the sensor frame's origin in any coordinate are left out of
/// perceive as invalid, like NaN points (a warning names how many) [m].
inline constexpr float kMaxPerceiveRange = 1e5f;

/// Every parameter of the pipeline, one node per configuration section.
struct PerceiveParams {
    int num_threads = 0;  ///< "threads": 0 = all cores; set in every stage (ApplyThreadCount)
    /// An unorganized cloud that is a depth image saved without its invalid pixels is put back
    /// on its pixel grid (RecoverImageGrid) and perceived as the frame it was; the result refers
    /// to the input's points.
    bool image_grid = true;
    FrameNormalParams normals{};  ///< normals of the region above the table
    SupportPlaneParams support{};
    PrismParams prism{.min_height = 0.008f, .max_height = 0.5f};  ///< the region above the table
    ObjectClusteringParams clustering{};  ///< object hypotheses; min_points also bounds every piece
    PartSegmentationParams parts{};       ///< parts and the concave split (section 4.2.1)
    /// Joining fragments of objects split by a nearer occluder.
    Switchable<OcclusionMergeParams> occlusion{};
    CategorizationParams category{};
    ModelParams models{};  ///< models and grouping by models (sections 5.4, 5.4.1)
    /// The floor of a low object (a plate's bottom), cut away with the table, given back to it.
    Switchable<EnclosedFloorParams> floors{};
    /// Throws ParameterError naming the node and field of the first out-of-range value.
    void Validate() const;
    /// Its parameters once each: configuration key (the field's name), field, meaning. A
    /// visitor reads or records them (io::ConfigSection::operator(); ReadPerceiveParams).
    template <typename V>
    void VisitParams(V& v) {
        v("threads", num_threads, "worker threads, 0 = all cores");
        v("image_grid", image_grid,
          "perceive an unorganized depth frame (invalid pixels dropped) on its recovered pixel "
          "grid");
        v.Node("normals", normals);
        v.Node("support", support);
        v.Node("prism", prism);
        v.Node("clustering", clustering);
        v.Node("parts", parts);
        v.Switch("occlusion", occlusion,
                 "join fragments of an object that a nearer object cuts in two");
        v.Node("category", category);
        v.Node("models", models);
        v.Switch("floors", floors,
                 "give a low object the table-band points its own points enclose (a plate's "
                 "floor)");
    }
};

/// `params` with its num_threads set in every stage that runs in parallel (the one place the
/// pipeline's thread count reaches the stages).
PerceiveParams ApplyThreadCount(PerceiveParams params);

/// Reads every parameter from a configuration (or, in dump mode, records the defaults with their
/// meaning). Keys of earlier releases are read under their current names with a warning.
void ReadPerceiveParams(io::ConfigSection& config, PerceiveParams& params);

/// The keys of earlier releases that ReadPerceiveParams still reads: (former key, current key);
/// a section moves with all its keys.
std::vector<std::pair<std::string, std::string>> PerceiveRenamedKeys();

/// The learned models the categorisers use: loaded once by the caller, shared by every frame.
struct PerceiveModels {
    std::shared_ptr<const PartGraphModel> part_graph;  ///< every categoriser but "rules"
};

struct PerceiveResult {
    std::size_t points = 0;  ///< points of the input (NaN included)
    SupportPlane support;    ///< support.found = false: no table, objects from the whole cloud
    std::vector<PerceivedObject> objects;
    std::vector<std::uint32_t> point_objects;    ///< per input point: object id or 0
    std::vector<std::uint8_t> point_categories;  ///< per input point: category index or 0
    std::vector<std::pair<std::string, double>> timings_ms;  ///< stage -> wall time, in order
};

/// The last stage: numbers result.objects 1..n in order, sets their centroids, and labels every
/// point of `cloud` with its object's id and category (0 outside every object).
void LabelPoints(const PointCloud& cloud, PerceiveResult& result);

/// Runs the pipeline. Parameters (and that the categoriser has its model) are checked before any
/// work: InvalidArgument. The cloud must hold at least one finite point within
/// kMaxPerceiveRange (DataError otherwise; points beyond it are left out as invalid); normals are
/// computed unless it has them.
PerceiveResult Perceive(const PointCloud& cloud, const PerceiveParams& params,
                        const PerceiveModels& models = {});

/// Perceive without a working copy of the cloud (for large clouds: the copy is the size of the
/// input): normals and curvature are added to `cloud` when it has none, and points beyond
/// kMaxPerceiveRange become NaN. Same result as Perceive.
PerceiveResult PerceiveInPlace(PointCloud& cloud, const PerceiveParams& params,
                               const PerceiveModels& models = {});

}  // namespace multicue

#pragma once
/// \file The table-top perception pipeline behind `multicue perceive`: normals, support plane,
/// object hypotheses above it, parts, first categories and primitive models (thesis sections 2.4,
/// 3.2.1, 4.2.1). Every parameter lives in PerceiveParams; ReadPerceiveParams maps it to a
/// parameter file.

#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "multicue/core/point_cloud.hpp"
#include "multicue/core/triangle_mesh.hpp"
#include "multicue/io/config.hpp"
#include "multicue/recognition/geometric_category.hpp"
#include "multicue/recognition/part_graph_model.hpp"
#include "multicue/reconstruction/primitive_models.hpp"
#include "multicue/segmentation/convexity_split.hpp"
#include "multicue/segmentation/euclidean_clustering.hpp"
#include "multicue/segmentation/occlusion_merge.hpp"
#include "multicue/segmentation/polygonal_prism.hpp"
#include "multicue/segmentation/region_growing.hpp"
#include "multicue/segmentation/support_plane.hpp"
#include "multicue/surface/normals.hpp"

namespace multicue {

struct PerceiveParams {
    /// Normals of organized frames (image-space fast path).
    /// A 15x15 window read every 3rd pixel (about 2.7 cm at 1 m): wide enough to smooth Kinect
    /// noise, narrow enough to keep the faces of a 9 cm box apart.
    OrganizedNormalParams organized_normals{.half_window = 7};
    /// Normals of unorganized clouds (k-d tree).
    NormalParams normals{.k = 20, .radius = 0.0f, .viewpoint = std::nullopt, .num_threads = 0};
    SupportPlaneParams support{};
    PrismParams prism{.min_height = 0.008f, .max_height = 0.5f};
    float cluster_tolerance = 0.015f;        ///< object hypotheses: Euclidean tolerance [m]
    std::size_t min_object_points = 150;     ///< smaller clusters are not objects [points]
    std::size_t max_object_points = 200000;  ///< larger clusters are not objects [points]
    int organized_half_window = 2;  ///< organized clustering reach; bridges 1-pixel gaps [px]
    /// Over-segmentation into parts (section 4.2.1). The k cap keeps dense RGB-D objects cheap:
    /// with thousands of points within 5 cm, the nearest ones already decide connectivity.
    RegionGrowingParams parts{.k = 16};
    bool split_concave = true;  ///< split hypotheses along concave part borders (stacked objects)
    ConvexitySplitParams convexity{};
    bool merge_occluded = true;  ///< join fragments of objects split by a nearer occluder
    OcclusionMergeParams occlusion{};
    /// First, rule-based categories; fewer samples than the defaults of a one-off call, which
    /// keeps a frame within budget at the same accuracy on mOSD.
    CategoryParams category{.max_points = 1500, .max_iterations = 400};
    /// "rules" (CategorizeObject) or "part-graph" (part-graph hashing, docs/part-graph.md: the
    /// categories, probabilities and per-point labels then come from the parts' votes; the rule
    /// result stays the input of the model fits' "upright" details only), or "part-graph+rules"
    /// (both: per category rules^(1 - w) * part-graph^w, w = part_graph_weight, each
    /// distribution floored at 0.01 first, then normalised).
    std::string categoriser = "rules";
    /// Part-graph model file; empty = `part_graph` must be set (the CLI then uses the default
    /// model, trained once and cached).
    std::string part_graph_model;
    std::shared_ptr<const PartGraphModel> part_graph;  ///< loaded model (wins over the file)
    PartGraphRecognitionParams part_graph_recognition{};
    float part_graph_weight = 0.5f;      ///< weight w of the part-graph votes in "part-graph+rules"
    BoxFitParams box{};                  ///< box models of box and flat objects
    CylinderModelParams cylinder = [] {  ///< cylinder models of cylindrical objects
        CylinderModelParams p;
        p.sac.max_iterations = 800;
        return p;
    }();
    int num_threads = 0;  ///< 0 = all cores; overrides the stages' own thread counts
};

/// Reads (or, with a dump section, records) every parameter.
void ReadPerceiveParams(io::ConfigSection& config, PerceiveParams& params);

/// The model of one object: exactly one of box / cylinder is set.
struct ObjectModel {
    std::optional<BoxModel> box;
    std::optional<CylinderModel> cylinder;
    TriangleMesh mesh;
};

struct PerceivedObject {
    int id = 0;       ///< 1-based, as in labels.pcd's `object` field
    Indices indices;  ///< the object's points, ascending
    std::vector<Indices> parts;
    CategoryResult category;
    Eigen::Vector3f centroid = Eigen::Vector3f::Zero();
    ObjectModel model;
};

struct PerceiveResult {
    std::size_t points = 0;  ///< points of the input (NaN included)
    SupportPlane support;    ///< support.found = false: no table, objects from the whole cloud
    std::vector<PerceivedObject> objects;
    std::vector<std::uint32_t> point_objects;    ///< per input point: object id or 0
    std::vector<std::uint8_t> point_categories;  ///< per input point: category index or 0
    std::vector<std::pair<std::string, double>> timings_ms;  ///< stage -> wall time, in order
};

/// Runs the pipeline. The cloud must hold at least one finite point (DataError otherwise); normals
/// are computed unless the cloud has them. Throws InvalidArgument for bad parameters.
PerceiveResult Perceive(const PointCloud& cloud, const PerceiveParams& params);

}  // namespace multicue
